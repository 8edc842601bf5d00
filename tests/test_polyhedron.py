"""The polyhedron from planes: topology, measures and open models against trimesh truth."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import trimesh
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from tactile_kb import solids
from tactile_kb.errors import GeometryError, OpenModelError, UsageError
from tactile_kb.polyhedron import open_directions, polyhedron_from_planes


def _planes(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    n = mesh.face_normals
    return n, np.einsum("ij,ij->i", n, mesh.triangles_center)


@pytest.mark.parametrize(
    ("mesh", "counts", "dihedral"),
    [
        (solids.box(0.1, 0.06, 0.04), (8, 12, 6), [90.0]),
        (solids.tetrahedron(0.1), (4, 6, 4), [70.53]),
        (solids.octahedron(0.1), (6, 12, 8), [109.47]),
        (solids.pyramid(4, 0.05, 0.08), (5, 8, 5), None),
        (solids.prism(7, 0.05, 0.1), (14, 21, 9), None),
        (solids.frustum(5, 0.06, 0.03, 0.04), (10, 15, 7), None),
    ],
)
def test_topology_and_measures_equal_trimesh(
    mesh: trimesh.Trimesh, counts: tuple[int, int, int], dihedral: list[float] | None
) -> None:
    p = polyhedron_from_planes(*_planes(mesh))
    assert (len(p.vertices), len(p.edges), len(p.faces)) == counts
    assert math.isclose(p.volume, mesh.volume, rel_tol=1e-9)
    assert np.allclose(p.centroid, mesh.center_mass, atol=1e-9)
    assert math.isclose(p.face_areas.sum(), mesh.area, rel_tol=1e-9)
    if dihedral is not None:
        assert sorted({round(float(a), 2) for a in p.dihedral_deg}) == dihedral
    # every face counter-clockwise seen from outside: its polygon normal is the outward normal
    for f, poly in enumerate(p.faces):
        v = p.vertices[list(poly)]
        cross = sum(np.cross(v[i], v[(i + 1) % len(v)]) for i in range(len(v)))
        assert float(cross @ p.normals[f]) > 0
    for (a, b), (f, g) in zip(p.edges, p.edge_faces, strict=True):
        assert a in p.faces[f]
        assert b in p.faces[f]
        assert a in p.faces[g]
        assert b in p.faces[g]


# Points on a 1 mm grid in a 2 m cube: exact coplanarity happens, a point 1e-12 off a plane
# (a hull folded by 1e-12 rad, no ground truth at any tolerance) does not.
_MM = st.integers(-1000, 1000).map(lambda k: k / 1000.0)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(_MM, _MM, _MM), min_size=4, max_size=30))
def test_hull_of_random_points_satisfies_euler(points: list[tuple[float, float, float]]) -> None:
    pts = np.asarray(points)
    # The ground truth must itself be well-formed: skip hulls with sliver triangles, which
    # trimesh cannot give normals for (it warns of a division by zero).
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            hull = trimesh.convex.convex_hull(pts)
        except Exception:
            hull = None
        ok = (
            hull is not None
            and hull.is_volume
            and hull.volume >= 1e-3
            and float(hull.area_faces.min()) > 1e-6
        )
        if ok:  # adjacent hull triangles are coplanar or clearly folded, nothing between
            folds = hull.face_adjacency_angles
            ok = bool(np.all((folds < 1e-12) | (folds > 1e-4)))
        planes = _planes(hull) if ok else None
    assume(ok)
    assert planes is not None
    p = polyhedron_from_planes(*planes, merge_fraction=1e-9)
    assert len(p.vertices) - len(p.edges) + len(p.faces) == 2
    assert math.isclose(p.volume, hull.volume, rel_tol=1e-6)


def test_redundant_planes_are_dropped() -> None:
    n = np.vstack([np.eye(3), -np.eye(3), [[1, 1, 0]]]) / np.c_[[1] * 6 + [math.sqrt(2)]]
    d = np.array([1, 1, 1, 1, 1, 1, 5.0])
    p = polyhedron_from_planes(n, d)
    assert len(p.faces) == 6
    assert 6 not in p.plane_index


def test_open_sets_name_the_open_direction() -> None:
    box_without_top = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, -1.0]])
    with pytest.raises(OpenModelError, match=r"open towards \(\+0\.00, \+0\.00, \+1\.00\)") as info:
        polyhedron_from_planes(box_without_top, [1, 1, 1, 1, 0])
    assert info.value.open_directions == [(0.0, 0.0, 1.0)]
    tet_missing_one = solids.tetrahedron(0.1)
    n, d = _planes(tet_missing_one)
    keep = n[:, 2] > -0.5  # drop the base: open downwards
    with pytest.raises(OpenModelError) as info:
        polyhedron_from_planes(n[keep], d[keep])
    assert all(z < 0 for _, _, z in info.value.open_directions)
    assert open_directions(np.vstack([np.eye(3), -np.eye(3)])) == []


def test_empty_and_bad_inputs() -> None:
    n = np.vstack([np.eye(3), -np.eye(3)])
    with pytest.raises(GeometryError, match="enclose no region"):
        polyhedron_from_planes(n, [1, 1, 1, -2, 1, 1])
    with pytest.raises(UsageError, match="normals must be"):
        polyhedron_from_planes(np.eye(3)[:, :2], [1, 1, 1])
    with pytest.raises(UsageError, match="zero normal"):
        polyhedron_from_planes(np.vstack([n, [[0, 0, 0]]]), [1] * 7)


def test_far_vertex_outside_the_bound_is_open() -> None:
    tilt = math.radians(1.0)
    n = np.array(
        [
            [math.cos(tilt), 0, math.sin(tilt)],
            [-math.cos(tilt), 0, math.sin(tilt)],
            [0, math.cos(tilt), math.sin(tilt)],
            [0, -math.cos(tilt), math.sin(tilt)],
            [0, 0, -1],
        ]
    )
    d = np.array([0.05, 0.05, 0.05, 0.05, 0.0])
    p = polyhedron_from_planes(n, d)  # closes, but ~3 m up
    assert p.vertices[:, 2].max() > 2.0
    with pytest.raises(OpenModelError, match="close only far") as info:
        polyhedron_from_planes(n, d, bound=((0, 0, 0.05), 0.3))
    assert info.value.open_directions[0][2] > 0.99
