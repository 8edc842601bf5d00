"""A face's uncertainty counts the places its tip centres lie at, not its contacts: touches of
one patch of a rough surface share its bumps (ground truth: a box built here, its contacts
sampled, roughened and repeated in place)."""

from __future__ import annotations

import numpy as np
from scanlike import roughened

from tactile_kb import solids
from tactile_kb.geometry.model import build_model
from tactile_kb.geometry.planes import PLACE_RHO, places
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

RHO = 0.005
ROUGH = 0.0006  # the scan's relief about its faces' planes (m)


def test_places_counts_patches_a_tip_radius_apart() -> None:
    pts = np.array(
        [
            [0.0, 0.0, 0.0],
            [0.4 * RHO, 0.0, 0.0],  # the same patch as the first
            [0.0, 0.9 * RHO, 0.0],  # still within ρ of the first
            [3.0 * RHO, 0.0, 0.0],
            [3.0 * RHO, 0.2 * RHO, 0.1 * RHO],
            [0.0, 5.0 * RHO, 0.0],
        ]
    )
    assert PLACE_RHO == 1.0
    assert places(pts, RHO) == 3
    assert places(pts[:1], RHO) == 1
    assert places(np.zeros((0, 3)), RHO) == 0
    # each point its own place when they lie further apart than ρ
    assert places(np.arange(5)[:, None] * np.array([[1.5 * RHO, 0.0, 0.0]]), RHO) == 5


def _rough_box() -> ExplorationRecord:
    """Exact touches of a box whose faces are rough: each centre moved along its face's normal
    by up to ``ROUGH``."""
    mesh = solids.box(0.09, 0.07, 0.05)
    rec = sample_record(mesh, builtin_finger("33"), per_face=9, quantise=False, noise=0.0, seed=3)
    rng = np.random.default_rng(8)
    rough = [roughened(c, rng, ROUGH) for c in rec.contacts]
    return rec.model_copy(update={"contacts": rough})


def _twice(rec: ExplorationRecord) -> ExplorationRecord:
    """Every contact recorded again 0.2 mm along its face, as a touch and the slide that
    starts where it was recorded (the same patch, the same bumps)."""
    out: list[Contact] = []
    for c in rec.contacts:
        n = np.asarray(c.direction)
        along = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
        along *= 0.0002 / np.linalg.norm(along)
        out.append(c)
        out.append(
            c.model_copy(
                update={
                    "centre": tuple(np.asarray(c.centre) + along),
                    "point": tuple(np.asarray(c.point) + along),
                    "kind": "slide",
                }
            )
        )
    return rec.model_copy(update={"contacts": out})


def _by_normal(rec: ExplorationRecord) -> dict[tuple[int, int, int], tuple[float, float, int]]:
    """Per contact face of ``rec``'s model, keyed by its rounded normal: its normal's and its
    offset's uncertainty, and its places."""
    model = build_model(rec)
    out = {}
    for f in model.faces:
        if f.source == "contacts":
            key = tuple(round(v) for v in f.normal)
            out[key] = (f.normal_uncertainty_deg, f.offset_uncertainty, f.places)
    return out


def test_a_touch_repeated_in_place_makes_no_face_more_certain() -> None:
    rec = _rough_box()
    once = _by_normal(rec)
    twice = _by_normal(_twice(rec))
    assert len(once) == 5
    assert set(once) == set(twice)
    for key, (unc, off, spots) in once.items():
        unc2, off2, spots2 = twice[key]
        assert spots2 == spots  # the repeats lie at the places already counted
        assert unc > 0.0
        assert off > 0.0
        # counted by contacts, twice as many would claim √2 less uncertainty
        assert abs(unc2 - unc) <= 0.05 * unc
        assert abs(off2 - off) <= 0.05 * off


def test_places_of_a_face_are_its_distinct_patches() -> None:
    rec = _rough_box()
    model = build_model(rec)
    centres = np.asarray([c.centre for c in rec.contacts])
    for f in model.faces:
        if f.source != "contacts":
            assert f.places == 0
            continue
        starts: list[np.ndarray] = []  # each centre further than ρ from all before starts one
        for p in centres[list(f.contacts)]:
            if all(float(np.linalg.norm(p - q)) > RHO for q in starts):
                starts.append(p)
        assert f.places == len(starts)
        assert 3 <= f.places <= f.n_contacts
