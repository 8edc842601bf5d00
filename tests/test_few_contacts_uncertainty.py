"""A face touched only four times on a rough scan: its normal is as uncertain as the scatter its
other faces show, no more (ground truth: a frustum built here, its true faces, and the
roughness added to their contacts)."""

from __future__ import annotations

import numpy as np
from scanlike import roughened

from tactile_kb import solids
from tactile_kb.features.builtin import _uncertainty, face_angles, parallelism_table
from tactile_kb.geometry.model import build_model
from tactile_kb.pipeline import classify_record
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

ROUGH = 0.0006  # the scan's relief about its faces' planes (m), exact touches


def _record() -> tuple[ExplorationRecord, np.ndarray]:
    """Exact touches of a triangular frustum whose faces are rough (each centre moved along
    its face's normal by up to ``ROUGH``), except one side touched only four times, whose
    four centres happen to lie on its plane; and that side's outward normal."""
    mesh = solids.frustum(3, 0.07, 0.035, 0.12)
    rec = sample_record(mesh, builtin_finger("33"), per_face=10, quantise=False, noise=0.0, seed=11)
    rng = np.random.default_rng(4)
    normals = [tuple(np.round(c.direction, 6)) for c in rec.contacts]
    sides = sorted({n for n in normals if abs(n[2]) < 0.9})
    few = sides[0]  # the side touched four times, exactly
    kept, seen = [], 0
    for c, n in zip(rec.contacts, normals, strict=True):
        if n == few:
            seen += 1
            if seen > 4:
                continue
            kept.append(c)
            continue
        kept.append(roughened(c, rng, ROUGH))
    return rec.model_copy(update={"contacts": kept}), -np.asarray(few)


def test_four_exact_touches_are_no_face_parallel_to_all() -> None:
    rec, n = _record()
    model = build_model(rec)
    poly = model.polyhedron
    assert poly is not None
    assert len(poly.faces) == 5
    k = int(np.argmax(poly.normals @ n))
    assert float(poly.normals[k] @ n) > 0.999  # the four touches fit their side's plane
    unc = _uncertainty(model)
    # no more uncertain than a few times the roughness over the frustum's size allows
    assert unc[k] < 10.0
    # so it is parallel to no face: the nearest to antiparallel is the opposite edge's
    par = parallelism_table(model)
    assert not par[k].any()
    assert float((180.0 - face_angles(model)[k]).min()) > 40.0
    assert classify_record(rec, rules="polyhedra").decision.label == "frustum"
