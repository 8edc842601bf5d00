"""Convex parts: exact boxes for orthogonal meshes, one hull for convex ones, CoACD otherwise."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh
from tactile_kb_mujoco.parts import convex_parts, orthogonal_frame, winding_number

from tactile_kb import solids
from tactile_kb.errors import ObjectError


def _in_box(part, points):
    local = (points - part.centre) @ part.rotation
    return (np.abs(local) <= part.size + 1e-12).all(axis=1)


@pytest.mark.parametrize(
    "mesh",
    [solids.box(0.1, 0.06, 0.04), solids.tetrahedron(0.08), solids.octahedron(0.06)],
    ids=["box", "tetrahedron", "octahedron"],
)
def test_convex_mesh_is_one_hull(mesh):
    (part,) = convex_parts(mesh)
    assert part.kind == "mesh"
    assert part.volume == pytest.approx(mesh.volume, rel=1e-9)


UNIONS = {
    "L": solids.l_shape(0.1, 0.08, 0.03, 0.04),
    "T": solids.t_shape(0.12, 0.08, 0.03, 0.05),
    "U": solids.u_shape(0.1, 0.08, 0.025, 0.03),
    "L rotated 30°": solids.rotate_about_z(solids.l_shape(0.1, 0.08, 0.03, 0.04), 30.0),
}


@pytest.mark.parametrize("name", list(UNIONS))
def test_box_unions_split_exactly_into_disjoint_boxes(name):
    mesh = UNIONS[name]
    parts = convex_parts(mesh)
    assert all(p.kind == "box" for p in parts)
    assert 2 <= len(parts) <= 3
    assert sum(p.volume for p in parts) == pytest.approx(mesh.volume, rel=1e-9)
    # Ground truth membership from trimesh's ray test on random points.
    rng = np.random.default_rng(1)
    lo, hi = mesh.bounds
    pts = rng.uniform(lo - 0.01, hi + 0.01, size=(3000, 3))
    inside_boxes = np.column_stack([_in_box(p, pts) for p in parts])
    assert (inside_boxes.sum(axis=1) <= 1).all()  # disjoint (measure-zero shared faces aside)
    np.testing.assert_array_equal(inside_boxes.any(axis=1), mesh.contains(pts))


def test_orthogonal_frame():
    assert orthogonal_frame(solids.tetrahedron(0.05)) is None
    frame = orthogonal_frame(UNIONS["L rotated 30°"])
    assert frame is not None
    np.testing.assert_allclose(frame.T @ frame, np.eye(3), atol=1e-12)
    assert np.linalg.det(frame) == pytest.approx(1.0)
    angles = sorted(
        abs(float(np.degrees(np.arctan2(c[1], c[0])))) % 90 for c in frame.T if abs(c[2]) < 0.5
    )
    assert angles == pytest.approx([30.0, 30.0]) or angles == pytest.approx([30.0, 60.0])


def test_winding_number_of_a_cube():
    cube = trimesh.creation.box((1.0, 1.0, 1.0))
    corners = np.array(list(itertools.product((-0.4, 0.4), repeat=3)))
    np.testing.assert_allclose(winding_number(cube, corners), 1.0, atol=1e-12)
    np.testing.assert_allclose(winding_number(cube, corners * 2.0), 0.0, atol=1e-12)


def test_other_nonconvex_meshes_go_through_coacd():
    ring = trimesh.creation.annulus(0.01, 0.03, 0.02, sections=12)
    fast = {"mcts_iterations": 40, "mcts_max_depth": 2, "resolution": 1000}
    parts = convex_parts(ring, seed=3, coacd_options=fast)
    assert len(parts) >= 3
    assert all(p.kind == "mesh" for p in parts)
    total = sum(p.volume for p in parts)
    assert total == pytest.approx(ring.volume, rel=0.15)
    again = convex_parts(ring, seed=3, coacd_options=fast)
    assert [p.vertices.tolist() for p in parts] == [p.vertices.tolist() for p in again]


def _flat():
    return trimesh.Trimesh(
        vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], faces=[[0, 1, 2], [1, 3, 2]]
    )


@pytest.mark.parametrize(
    ("mesh", "message"),
    [
        (trimesh.Trimesh(), "empty"),
        (_flat(), "degenerate"),
        (
            trimesh.Trimesh(vertices=np.full((4, 3), np.nan), faces=[[0, 1, 2]], process=False),
            "non-finite",
        ),
        (
            trimesh.Trimesh(vertices=np.zeros((4, 3)), faces=[[0, 1, 2]], process=False),
            "degenerate",
        ),
    ],
    ids=["empty", "flat", "nan", "point"],
)
def test_meshes_mujoco_cannot_take(mesh, message):
    with pytest.raises(ObjectError, match=message) as err:
        convex_parts(mesh, name="thing.stl")
    assert str(err.value).startswith("thing.stl: ")
    assert "\n" not in str(err.value)


def test_too_many_hull_vertices():
    ball = solids.sphere(0.05, subdivisions=2)
    with pytest.raises(ObjectError, match=r"ball: a convex part has 162 hull vertices, more than"):
        convex_parts(ball, name="ball", max_hull_vertices=100)
