"""A face's measured turn makes the surface curved only beyond three standard errors.

Every face whose interior sensors spread is tested for a turn, so at two standard errors the
false alarms of a model's flat faces add up (one model in eight with six such faces). These
are saved scans of flat-faced prisms (``bench_real.py``, draw 0, 0.5 mm declared noise)
whose model had one side measured as turning by 43° or 82° on 8 or 15 touches, just two
standard errors beyond ``features.spread_deg``: the prisms' faces are flat, and they are no
longer curved.
"""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

from tactile_kb import settings
from tactile_kb.features.builtin import _bend, _face_spreads, surface_curved
from tactile_kb.pipeline import classify_record
from tactile_kb.record import ExplorationRecord

RECORDS = Path(__file__).parent / "data" / "records"


def _record(name: str) -> ExplorationRecord:
    return ExplorationRecord.model_validate_json(gzip.decompress((RECORDS / name).read_bytes()))


@pytest.mark.parametrize(
    ("name", "label"),
    [
        # prism(6, 0.0205, 0.102), a level-2 scan: vertex noise, bumps, edges rounded by 6 %
        ("prism6-level2-draw0.json.gz", "prism"),
        # prism(4, 0.0818, 0.0738), a level-3 scan: a box 8.2 cm square and 7.4 cm high
        ("prism4-level3-draw0.json.gz", "rectangular_parallelepiped"),
    ],
)
def test_a_flat_face_whose_turn_is_two_errors_beyond_the_spread_is_not_curved(
    name: str, label: str
) -> None:
    record = _record(name)
    result = classify_record(record, rules="polyhedra")
    model = result.model
    spread = settings.current().features.spread_deg
    # the one face that two standard errors found turning: its estimate is far beyond the
    # spread, its error large (the jackknife's: a few centres carry the bend)
    found = []
    for fi, s in enumerate(_face_spreads(model)):
        if s.angle <= spread:
            continue
        bend = _bend(model, fi, False)
        if bend is not None and bend[0] - 2.0 * bend[2] > spread:
            found.append(bend)
    assert len(found) == 1
    turn, _, error = found[0]
    assert turn > 40.0
    assert error > 10.0
    assert turn - 3.0 * error <= spread
    assert settings.current().features.bend_sigmas == 3.0
    assert not surface_curved(model)
    assert result.decision.label == label
    with settings.override(features={"bend_sigmas": 2.0}):
        assert classify_record(record, rules="polyhedra").decision.label == "curved"


def test_bend_sigmas_must_be_positive() -> None:
    with pytest.raises(ValueError, match="bend_sigmas"):
        settings.Settings.model_validate({"features": {"bend_sigmas": 0.0}})
