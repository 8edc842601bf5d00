"""Records written by tactile_kb 0.1 (format version 1) still load and classify the same.

The two files in ``tests/data/records`` were written by 0.1's stepper (commit fa11780) and
classified there with the polyhedra rules; the labels below are what 0.1 answered. Version 1
records carry the layer contours the explorer traced; the model now computes them from the
contacts, and the two agree.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely.geometry

from tactile_kb import ExplorationRecord, RecordError, classify_record
from tactile_kb.geometry.model import build_model
from tactile_kb.record import READABLE_VERSIONS, RECORD_VERSION

DATA = Path(__file__).parent / "data" / "records"

ANSWERED_BY_0_1 = {
    "v1-box-33": ("nonrectangular_parallelepiped", 10),
    "v1-lshape-4": ("composed_of_boxes", 12),
}


@pytest.mark.parametrize("name", sorted(ANSWERED_BY_0_1))
def test_version_1_records_load_and_classify_as_0_1_did(name: str) -> None:
    rec = ExplorationRecord.load(DATA / f"{name}.json")
    assert rec.version == 1
    label, touches = ANSWERED_BY_0_1[name]
    assert rec.touches == touches
    assert classify_record(rec, rules="polyhedra").decision.label == label


def test_the_model_computes_the_contours_version_1_stored() -> None:
    rec = ExplorationRecord.load(DATA / "v1-lshape-4.json")
    stored = [layer.contour for layer in rec.layers]
    computed = [layer.contour for layer in build_model(rec).layers]
    assert len(stored) == len(computed) > 0
    for a, b in zip(stored, computed, strict=True):
        pa, pb = shapely.geometry.Polygon(a), shapely.geometry.Polygon(b)
        assert pa.symmetric_difference(pb).area < 1e-3 * pa.area


def test_new_records_are_version_2_and_unknown_versions_are_refused() -> None:
    rec = ExplorationRecord.load(DATA / "v1-box-33.json")
    again = ExplorationRecord.from_json(
        rec.model_copy(update={"version": RECORD_VERSION}).to_json()
    )
    assert again.version == 2
    assert RECORD_VERSION in READABLE_VERSIONS
    future = rec.model_copy(update={"version": 99}).to_json()
    with pytest.raises(RecordError, match="version 99 is not supported"):
        ExplorationRecord.from_json(future, file="future.json")
    assert np.isfinite(rec.path_length)


def test_the_noise_sigma_is_a_field_and_version_1_params_migrate() -> None:
    v1 = ExplorationRecord.load(DATA / "v1-box-33.json")
    assert v1.noise == 0.0
    assert "noise" not in v1.params
    text = (DATA / "v1-box-33.json").read_text(encoding="utf-8")
    noisy = text.replace('"noise": 0.0', '"noise": 0.0005', 1)
    assert noisy != text
    rec = ExplorationRecord.from_json(noisy)
    assert rec.noise == 0.0005
    assert "noise" not in rec.params
