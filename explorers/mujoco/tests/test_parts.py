"""Convex parts: exact boxes for orthogonal meshes, one hull for convex ones, CoACD otherwise."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh
from tactile_kb_mujoco.parts import convex_parts, felt_concavity, orthogonal_frame, winding_number

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


def _fine_box() -> trimesh.Trimesh:
    box = solids.box(0.08, 0.06, 0.04)
    v, f = trimesh.remesh.subdivide_to_size(box.vertices, box.faces, max_edge=0.002)
    return trimesh.Trimesh(v, f)


def _dented(depth: float) -> trimesh.Trimesh:
    """The fine box with a spherical dent (radius 5 cm, wider than the tip) ``depth`` deep in
    its top face."""
    ball = trimesh.creation.icosphere(subdivisions=5, radius=0.05)
    ball.apply_translation((0.0, 0.0, 0.04 + 0.05 - depth))
    out: trimesh.Trimesh = trimesh.boolean.difference([_fine_box(), ball])
    return out


def _grooved(radius: float) -> trimesh.Trimesh:
    """The fine box with a half-round groove of ``radius`` across its top face."""
    rod = trimesh.creation.cylinder(radius=radius, height=0.1, sections=64)
    rod.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (0, 1, 0)))
    rod.apply_translation((0.0, 0.0, 0.04))
    out: trimesh.Trimesh = trimesh.boolean.difference([_fine_box(), rod])
    return out


def test_felt_concavity_of_a_wide_dent_is_its_depth():
    c = felt_concavity(_dented(0.003), 0.005)
    assert c.depth == pytest.approx(0.003, abs=2e-5)  # the 5 cm ball's cap is wider than the tip
    assert c.roughness == pytest.approx(0.0, abs=1e-6)


def test_felt_concavity_of_a_narrow_groove_is_how_far_the_tip_sinks_into_it():
    rho, a = 0.005, 0.002
    c = felt_concavity(_grooved(a), rho)
    sag = rho - np.sqrt(rho**2 - a**2)  # the tip resting on both rims, 2 mm from the axis
    assert sag < c.depth < sag + 0.2e-3  # the rim is sampled at the mesh's 2 mm spacing
    assert c.depth < a  # the groove is 2 mm deep; the 5 mm tip never reaches its bottom


def test_felt_concavity_of_an_l_shape_is_its_notch():
    ell = solids.l_shape(0.06, 0.05, 0.02, 0.03)  # the short arm's end is 1 cm under the hull
    c = felt_concavity(ell, 0.005)
    assert c.depth == pytest.approx(0.01, abs=1e-9)
    assert c.roughness == 0.0


def test_a_scan_of_a_convex_solid_is_one_hull():
    from tactile_kb.perturb import perturb

    ideal = solids.box(0.08, 0.06, 0.04)
    scan = perturb(ideal, 2, seed=1)
    assert not scan.is_convex
    assert orthogonal_frame(scan) is None
    (part,) = convex_parts(scan, tip_radius=0.005, concavity_tol=0.005)
    assert part.kind == "mesh"
    hull = trimesh.convex.convex_hull(scan.vertices)
    assert part.volume == pytest.approx(hull.volume, rel=1e-9)
    assert len(part.vertices) == len(hull.vertices)  # only the hull's vertices are kept
    # A tolerance below the 3 mm dent sends the dented box to the decomposition instead.
    dented = _dented(0.003)
    assert felt_concavity(dented, 0.005).depth > 0.002
    (one,) = convex_parts(dented, tip_radius=0.005, concavity_tol=0.005)
    assert one.volume == pytest.approx(trimesh.convex.convex_hull(dented.vertices).volume)
    fast = {"mcts_iterations": 20, "mcts_max_depth": 2, "resolution": 500}
    assert len(convex_parts(dented, tip_radius=0.005, concavity_tol=0.002, coacd_options=fast)) > 1
