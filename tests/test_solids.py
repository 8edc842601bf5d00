"""Solids: watertight, in metres, resting on z = 0, with the intended shape."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.errors import UsageError

BUILDERS = [
    solids.box(0.1, 0.06, 0.04),
    solids.parallelepiped(0.1, 0.07, 0.05, angle_deg=60, shear_deg=10, shear_azimuth_deg=30),
    solids.rhombohedron(0.08),
    solids.tetrahedron(0.1),
    solids.octahedron(0.1),
    solids.prism(5, 0.05, 0.1),
    solids.pyramid(4, 0.05, 0.08),
    solids.frustum(6, 0.06, 0.03, 0.05),
    solids.cylinder(0.04, 0.1),
    solids.sphere(0.05),
    solids.l_shape(0.1, 0.08, 0.03, 0.04),
    solids.t_shape(0.12, 0.1, 0.03, 0.05),
    solids.u_shape(0.12, 0.1, 0.03, 0.04),
]


@pytest.mark.parametrize("mesh", BUILDERS)
def test_watertight_and_resting_on_the_table(mesh: trimesh.Trimesh) -> None:
    assert mesh.is_watertight
    assert mesh.volume > 0
    assert abs(mesh.bounds[0][2]) < 1e-12
    lo, hi = mesh.bounds
    assert np.allclose((lo[:2] + hi[:2]) / 2, 0.0, atol=1e-12)


def test_volumes_match_the_formulas() -> None:
    assert math.isclose(solids.box(0.1, 0.06, 0.04).volume, 0.1 * 0.06 * 0.04, rel_tol=1e-9)
    e = 0.1
    assert math.isclose(solids.tetrahedron(e).volume, e**3 / (6 * math.sqrt(2)), rel_tol=1e-9)
    assert math.isclose(solids.octahedron(e).volume, math.sqrt(2) / 3 * e**3, rel_tol=1e-9)
    # sheared parallelepiped: base area × height
    m = solids.parallelepiped(0.1, 0.07, 0.05, angle_deg=60, shear_deg=10)
    assert math.isclose(m.volume, 0.1 * 0.07 * math.sin(math.radians(60)) * 0.05, rel_tol=1e-9)
    assert math.isclose(
        solids.l_shape(0.1, 0.08, 0.03, 0.04).volume,
        (0.1 * 0.03 + 0.03 * 0.05) * 0.04,
        rel_tol=1e-9,
    )
    u = solids.u_shape(0.12, 0.1, 0.03, 0.04)
    assert math.isclose(u.volume, (0.12 * 0.03 + 2 * 0.03 * 0.07) * 0.04, rel_tol=1e-9)


def test_rhombohedron_has_equal_edges_and_equal_angles() -> None:
    m = solids.rhombohedron(0.08, angle_deg=75)
    edges = m.face_adjacency_edges[m.face_adjacency_angles > 1e-6]
    lengths = np.linalg.norm(m.vertices[edges[:, 0]] - m.vertices[edges[:, 1]], axis=1)
    assert np.allclose(lengths, 0.08)


def test_octahedron_and_tetrahedron_rest_on_a_face() -> None:
    for m in (solids.octahedron(0.1), solids.tetrahedron(0.1)):
        on_table = np.abs(m.vertices[:, 2]) < 1e-12
        assert on_table.sum() == 3


def test_the_sheared_parallelepiped_overhangs_by_at_most_its_shear() -> None:
    m = solids.parallelepiped(0.1, 0.07, 0.05, angle_deg=70, shear_deg=10)
    below = m.face_normals[:, 2]
    assert np.degrees(np.arcsin(-below[below > -0.99].min())) <= 10.0 + 1e-9


def test_rotate_place_and_rest_on_face() -> None:
    m = solids.box(0.1, 0.02, 0.03)
    r = solids.rotate_about_z(m, 90.0)
    assert np.allclose(r.extents, [0.02, 0.1, 0.03])
    p = solids.place(r, (0.2, -0.1))
    lo, hi = p.bounds
    assert np.allclose((lo[:2] + hi[:2]) / 2, [0.2, -0.1])
    side = solids.rest_on_face(m, (1.0, 0.0, 0.0))
    assert np.allclose(side.extents, [0.03, 0.02, 0.1]) or np.allclose(
        side.extents, [0.02, 0.03, 0.1]
    )
    assert abs(side.bounds[0][2]) < 1e-12


def test_fig5_objects_in_the_papers_order() -> None:
    objs = solids.fig5_objects()
    assert [n for n, _, _ in objs] == [
        "OCTA",
        "CUBE1",
        "CUBE2",
        "TETRA",
        "PRAPAR",
        "KOPAR",
        "TETRA1",
        "TETRA2",
        "CUBE11",
        "CUBE22",
        "PRAPA1",
        "KOPAR1",
    ]
    assert {lab for _, _, lab in objs} == {
        "not_hexahedron",
        "cube",
        "rectangular_parallelepiped",
        "nonrectangular_parallelepiped",
    }
    for _, mesh, _ in objs:
        assert mesh.is_watertight
        edges = mesh.face_adjacency_edges[mesh.face_adjacency_angles > 1e-6]
        lengths = np.linalg.norm(mesh.vertices[edges[:, 0]] - mesh.vertices[edges[:, 1]], axis=1)
        assert lengths.min() >= 0.02
        assert lengths.max() <= 0.30 + 1e-9
        assert abs(mesh.bounds[0][2]) < 1e-12


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: solids.box(0.1, -1, 0.1), "b must be a positive"),
        (lambda: solids.prism(2, 0.1, 0.1), "n .* must be an integer ≥ 3"),
        (lambda: solids.frustum(4, 0.05, 0.06, 0.1), "r_top"),
        (lambda: solids.u_shape(0.05, 0.1, 0.03, 0.1), "twice the width"),
        (lambda: solids.box_union([(0, 0, 1, 1), (2, 2, 3, 3)], 0.1), "one polygon"),
        (lambda: solids.parallelepiped(0.1, 0.1, 0.1, angle_deg=5), "angle_deg"),
    ],
)
def test_bad_arguments_are_usage_errors(call: object, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        call()  # type: ignore[operator]


def test_stable_poses_rest_on_a_face_most_probable_first() -> None:
    block = solids.box(0.06, 0.04, 0.02)
    poses = solids.stable_poses(block)
    probs = [p for _, p in poses]
    assert len(poses) == 6  # each face of a box is a resting face
    assert probs == sorted(probs, reverse=True)
    assert sum(probs) == pytest.approx(1.0, abs=1e-6)
    heights = []
    for posed, _ in poses:
        lo, hi = posed.bounds
        assert lo[2] == pytest.approx(0.0, abs=1e-12)
        assert (lo[:2] + hi[:2]) == pytest.approx((0.0, 0.0), abs=1e-12)
        down = posed.face_normals[:, 2] < -0.999999
        assert np.allclose(posed.triangles_center[down][:, 2], 0.0, atol=1e-12)  # on a face
        heights.append(round(float(hi[2]), 6))
    # lying flat is the most probable, standing on the smallest face the least
    assert heights[:2] == [0.02, 0.02]
    assert heights[-2:] == [0.06, 0.06]
    # a sphere has no pose of 2 %: its most probable one alone
    assert len(solids.stable_poses(solids.sphere(0.03))) == 1
    with pytest.raises(UsageError, match="min_probability"):
        solids.stable_poses(block, min_probability=1.5)


@pytest.mark.parametrize("turn", [0.0, 37.5, 290.0])
def test_resting_is_a_stable_pose_turned_about_the_vertical(turn: float) -> None:
    block = solids.box(0.06, 0.04, 0.02)
    a = np.radians(turn)
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    for k in (0, 2, 5):
        mesh = solids.resting(block, k, turn)
        assert mesh.bounds[:, 2] == pytest.approx([0.0, [0.02, 0.04, 0.06][k // 2]], abs=1e-9)
        # the same corners as the plain pose, each turned about the vertical through the centre
        plain = solids.stable_poses(block)[k][0].vertices @ rot.T
        gap = np.linalg.norm(mesh.vertices[:, None, :] - plain[None, :, :], axis=2)
        assert gap.min(axis=1).max() < 1e-9
        assert gap.min(axis=0).max() < 1e-9


def test_resting_names_the_poses_a_mesh_has() -> None:
    with pytest.raises(UsageError, match=r"pose must be 0 to 5 \(the mesh has 6\), got 6"):
        solids.resting(solids.box(0.06, 0.04, 0.02), 6)
