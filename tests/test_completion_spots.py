"""Faces known from one spot get a second one; table corners that jut out are checked level
(issues 11 and 10). Ground truth: solids built here or by the benchmark's constructions, and
their true faces (never the code under test)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.completion import second_spot_probes
from tactile_kb.geometry.model import build_model
from tactile_kb.pipeline import classify
from tactile_kb.record import ExplorationRecord
from tactile_kb.settings import override
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

RHO = 0.005  # the 33-sensor finger's tip radius
A, B, C = 0.06, 0.05, 0.04  # the box: x from −A/2 to A/2, y from −B/2 to B/2, z from 0 to C
SPOT = np.array([A / 2, -0.012, 0.012])  # where the +x face is touched once


def _box_record(noise: float) -> ExplorationRecord:
    return sample_record(
        solids.box(A, B, C), builtin_finger("33"), per_face=6, quantise=False, noise=noise, seed=3
    )


def _touched_once(rec: ExplorationRecord) -> ExplorationRecord:
    """``rec`` with the +x face's contacts replaced by six at one spot (a probe and its
    short slide: within 8 mm, across the face), with the record's noise."""
    plus_x = [c for c in rec.contacts if c.direction[0] < -0.99]
    assert len(plus_x) >= 6  # the sampled record touched it
    kept = [c for c in rec.contacts if c.direction[0] >= -0.99]
    rng = np.random.default_rng(5)
    offsets = [(0.0, 0.0), (0.003, 0.001), (-0.001, 0.003), (0.002, -0.0025), (-0.003, -0.001)]
    spot = []
    for k, (dy, dz) in enumerate([*offsets, (0.001, 0.002)]):
        centre = SPOT + np.array([RHO, dy, dz]) + rng.normal(0.0, rec.noise, 3)
        spot.append(
            plus_x[k].model_copy(
                update={
                    "point": tuple(float(x) for x in centre - np.array([RHO, 0.0, 0.0])),
                    "centre": tuple(float(x) for x in centre),
                    "direction": (-1.0, 0.0, 0.0),
                }
            )
        )
    return rec.model_copy(update={"contacts": kept + spot})


def test_a_face_touched_at_one_spot_is_probed_far_from_it_on_the_face() -> None:
    model = build_model(_touched_once(_box_record(0.0005)))
    assert model.polyhedron is not None
    probes = second_spot_probes(model)
    assert len(probes) == 1
    p = probes[0]
    assert p.reason.startswith("a face touched at one spot")
    # along the +x face's normal (as fitted through one noisy spot), aimed at its plane
    assert float(np.asarray(p.normal) @ (1.0, 0.0, 0.0)) > math.cos(math.radians(15.0))
    surface = np.asarray(p.target) - RHO * np.asarray(p.normal)
    assert surface[0] == pytest.approx(A / 2, abs=0.003)
    # on the true face, inside its rectangle, and away from the spot touched
    assert abs(surface[1]) < B / 2
    assert 0.0 < surface[2] < C
    assert float(np.linalg.norm(surface - SPOT)) >= 2.0 * RHO
    # the tip stays clear of the table
    assert p.target[2] >= 1.5 * RHO


def test_exact_touches_at_one_spot_fix_the_plane_already() -> None:
    model = build_model(_touched_once(_box_record(0.0)))
    face = next(f for f in model.faces if f.normal[0] > 0.99)
    assert face.refined
    assert second_spot_probes(model) == []


def test_faces_touched_at_spots_apart_get_no_second_spot_probe() -> None:
    model = build_model(_box_record(0.0005))
    assert model.polyhedron is not None
    assert second_spot_probes(model) == []


def test_the_spot_thresholds_are_settings() -> None:
    # a spot as wide as the box: every side counts as touched at one spot (tops are left to
    # their own probes); no least uncertainty: the exact spot is probed too
    with override(explore={"spot_rho": 20.0, "spot_deg": 0.0}):
        assert len(second_spot_probes(build_model(_box_record(0.0005)))) == 4
    with override(explore={"spot_deg": 0.0}):
        assert len(second_spot_probes(build_model(_touched_once(_box_record(0.0))))) == 1


def _true_normals(mesh: trimesh.Trimesh) -> np.ndarray:
    hull = trimesh.convex.convex_hull(mesh.vertices)
    return np.unique(np.round(hull.face_normals, 6), axis=0)


def _worst_face_deg(model_normals: list[np.ndarray], truth: np.ndarray) -> float:
    return max(math.degrees(math.acos(min(1.0, float((truth @ n).max())))) for n in model_normals)


@pytest.mark.parametrize(("pose", "turn"), [(0, 303.7646024527416), (2, 352.68793506347635)])
def test_a_lying_frustums_overhanging_end_is_found_at_its_table_corner(
    pose: int, turn: float
) -> None:
    # A triangular frustum lying on a side, noisy contacts: its small end overhangs and no
    # layer touches it, so its sides' planes close as a tetrahedron whose corner on the table
    # juts out far beyond every touch. No side of that model overhangs, so the corner is
    # probed level; the end face is found and the model is the frustum's five faces.
    mesh = solids.resting(
        solids.rotate_about_z(solids.frustum(3, 0.0194, 0.0096, 0.02), 268.0), pose, turn
    )
    truth = _true_normals(mesh)
    assert len(truth) == 5
    r = classify(mesh, rules="polyhedra", noise=0.0005, seed=1)
    assert r.decision.label == "frustum"
    normals = [f.normal_array for f in r.model.faces]
    assert len(normals) == 5
    assert _worst_face_deg(normals, truth) < 10.0


@pytest.mark.parametrize(
    ("pose", "turn", "noise"),
    [
        (1, 174.7926499606516, 0.0),
        (2, 152.14622271292123, 0.0),
        (6, 284.0956645338526, 0.0),
    ],
)
def test_a_lying_hexagonal_pyramid_keeps_its_undercut_faces(
    pose: int, turn: float, noise: float
) -> None:
    # Lying on a side, the pyramid has sides that overhang: its model's table corners are
    # not probed level (such a probe meets an undercut's edge, whose touches fit a wrong
    # plane), and an undercut side touched once is touched again elsewhere. The faces found
    # lie near true planes, and the lateral edges meet at the apex.
    mesh = solids.resting(
        solids.rotate_about_z(solids.pyramid(6, 0.0315, 0.0405), 357.8), pose, turn
    )
    truth = _true_normals(mesh)
    r = classify(mesh, rules="polyhedra", noise=noise, seed=1)
    assert r.decision.label == "pyramid"
    assert len(truth) == 7
    # every modelled face is one of the pyramid's, near its true plane (none is fitted
    # through an edge's touches)
    assert _worst_face_deg([f.normal_array for f in r.model.faces], truth) < 8.0
