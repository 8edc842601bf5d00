"""Probes of undercut faces near the table reach where they were aimed (issue 11). Ground
truth: solids built here, their true faces (never the code under test)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from probing import OneProbe

from tactile_kb import solids
from tactile_kb.pipeline import classify
from tactile_kb.touch.servo import Probe
from tactile_kb.touch.stepper import StepperExplorer

RHO = 0.005  # the 33-sensor finger's tip radius


def _lying_pyramid() -> tuple[trimesh.Trimesh, np.ndarray, np.ndarray]:
    """A hexagonal pyramid lying on a lateral face, one of the two lateral faces beside the
    table (overhanging: its normal points 41° down) and that face's corners."""
    pyramid = solids.pyramid(6, 0.0315, 0.0405)
    side = pyramid.face_normals[int(np.argmin(np.abs(pyramid.face_normals[:, 2])))]
    lying = solids.rest_on_face(pyramid, side)
    k = int(np.argmin(np.abs(lying.face_normals[:, 2] + 0.656)))
    normal = np.asarray(lying.face_normals[k], dtype=float)
    assert normal[2] == pytest.approx(-0.656, abs=0.001)
    return lying, normal, np.asarray(lying.vertices[lying.faces[k]], dtype=float)


@pytest.mark.parametrize("centre_z", [1.5 * RHO, 1.8 * RHO, 2.2 * RHO])
def test_a_probe_of_an_undercut_face_near_the_table_touches_where_it_was_aimed(
    centre_z: float,
) -> None:
    # Along the face's normal, the approach would start under the table: it starts on the
    # workspace's floor and runs from there at the target. (It used to run parallel to the
    # normal from the lifted start, and met the face's upper edge 14-16 mm from the target.)
    mesh, n, ring = _lying_pyramid()
    up = np.array([0.0, 0.0, 1.0]) - n[2] * n  # up the face, in its plane
    up /= np.linalg.norm(up)
    middle = ring.mean(axis=0)
    surface = middle + (centre_z - RHO * n[2] - middle[2]) / up[2] * up
    target = surface + RHO * n
    assert target[2] == pytest.approx(centre_z)
    explorer = StepperExplorer()
    probe = Probe(tuple(float(x) for x in target), tuple(float(x) for x in n), 4 * RHO, "test")
    explorer.completer = lambda: OneProbe(probe)
    record = explorer.explore(mesh, finger="33", seed=0)
    touch = [c for c in record.contacts if c.kind == "touch"][-1]
    assert np.linalg.norm(np.asarray(touch.centre) - target) < 1e-4
    assert float(np.asarray(touch.direction) @ -n) > np.cos(np.radians(15.0))  # the face's sensor


@pytest.mark.parametrize(
    ("mesh", "pose", "turn", "label"),
    [
        # a stable-pose benchmark instance (bench_poses --turns 1 before round 6): a hexagonal
        # pyramid on a side, noisy contacts; an undercut face probed at its other height was
        # touched at its upper edge, and fitted through that edge's touches. (The small
        # hexagonal frustum fixed the same way, frustum(6, 0.0201, 0.0121, 0.02) pose 3, is
        # answered other_polyhedron again since planes._fit keeps the sensors' normal for a
        # line that runs along it: a known loss of round 6, see docs/benchmarks.md.)
        (solids.pyramid(6, 0.0315, 0.0405), 3, 81.11823907523944, "pyramid"),
    ],
)
def test_lying_solids_with_undercut_faces_near_the_table(
    mesh: trimesh.Trimesh, pose: int, turn: float, label: str
) -> None:
    turned = solids.rotate_about_z(mesh, 357.8)  # the instance's own turn in that benchmark
    r = classify(solids.resting(turned, pose, turn), rules="polyhedra", noise=0.0005, seed=1)
    assert r.decision.label == label
