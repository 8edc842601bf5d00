"""The analytic stepper world against constructed geometry, and whole explorations."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from tactile_kb import solids
from tactile_kb.errors import UsageError
from tactile_kb.geometry.model import build_model
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.stepper import StepperExplorer, StepperWorld
from tactile_kb.touch.synthetic import mesh_planes
from tactile_kb.touch.world import CONTACT_TOL, World

RHO = 0.005


def cube(size: float = 0.1) -> trimesh.Trimesh:
    m: trimesh.Trimesh = trimesh.creation.box((size, size, size))
    m.apply_translation((0.0, 0.0, size / 2))
    return m


def test_is_a_world() -> None:
    assert isinstance(StepperWorld(cube(), builtin_finger("4")), World)


@given(
    y=st.floats(-0.04, 0.04),
    z=st.floats(0.01, 0.09),
    x0=st.floats(-0.19, -0.06),
)
@settings(max_examples=30, deadline=None)
def test_touch_at_the_exact_distance_from_a_face(y: float, z: float, x0: float) -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    m = world.move((x0, y, z), (1.0, 0.0, 0.0), 0.5)
    assert m.event == "touch"
    assert m.closed == (0,)  # the sensor pointing +x
    # the face is x = -0.05: the tip centre stops at x = -0.05 - rho (within the contact shell)
    assert -0.05 - RHO - CONTACT_TOL <= m.end[0] <= -0.05 - RHO + 1e-12
    assert math.isclose(m.distance, m.end[0] - x0, rel_tol=0, abs_tol=1e-12)
    assert world.sense(m.end) == (0,)


def test_touch_on_a_vertical_edge_at_distance_rho_from_the_edge_line() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    # moving along +x on the line y = -0.05 - 0.003: the edge x = y = -0.05 is met first
    y = -0.053
    m = world.move((-0.2, y, 0.05), (1.0, 0.0, 0.0), 0.3)
    assert m.event == "touch"
    # ground truth: (x + 0.05)^2 + (y + 0.05)^2 = rho^2
    x = -0.05 - math.sqrt(RHO**2 - (y + 0.05) ** 2)
    assert abs(m.end[0] - x) < 1e-6
    assert set(m.closed) <= {0, 3}


def test_touch_on_a_vertex_at_distance_rho() -> None:
    world = StepperWorld(cube(), builtin_finger("33"))
    # descending next to the top corner (0.05, 0.05, 0.1), offset 3 mm outward in x and y
    cx, cy = 0.053, 0.053
    m = world.move((cx, cy, 0.2), (0.0, 0.0, -1.0), 0.2)
    assert m.event == "touch"
    z = 0.1 + math.sqrt(RHO**2 - 2 * 0.003**2)
    assert abs(m.end[2] - z) < 1e-6


def test_blind_contact_blocks_the_finger() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))  # no sensor points down
    m = world.move((0.0, 0.0, 0.2), (0.0, 0.0, -1.0), 0.2)
    assert m.event == "blocked"
    assert m.fired == ()
    assert abs(m.end[2] - (0.1 + RHO)) < 1e-8


def test_workspace_limit_and_free_motion() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    ws = world.workspace
    m = world.move((0.0, 0.0, 0.2), (1.0, 0.0, 0.0), 10.0)
    assert m.event == "limit"
    assert math.isclose(m.end[0], ws.hi[0])
    free = world.move((0.0, 0.0, 0.2), (1.0, 0.0, 0.0), 0.05)
    assert free.event == "none"
    assert free.distance == pytest.approx(0.05)


def test_moving_into_a_touched_face_is_blocked_at_once() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    m = world.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    again = world.move(m.end, (1.0, 0.0, 0.0), 0.1)
    assert again.event == "blocked"
    assert again.distance < 1e-7


def test_moving_away_releases() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    m = world.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    away = world.move(m.end, (-1.0, 0.0, 0.0), 0.1)
    assert away.event == "release"
    assert away.opened == (0,)
    assert away.distance < 1e-6


def test_slide_releases_where_the_face_ends() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    m = world.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    s = world.slide(m.end, (0.0, -1.0, 0.0), 1.0, 0)
    assert s.event == "release"
    assert s.opened == (0,)
    # the face ends at y = -0.05; the contact is lost within a few hundredths of a mm past it
    assert -0.05 - 1e-4 < s.end[1] <= -0.05
    assert s.end[0] == pytest.approx(m.end[0], abs=1e-12)  # pressed on the face all along


def test_slide_follows_a_sloped_face_horizontally() -> None:
    tet = solids.tetrahedron(0.1)
    world = StepperWorld(tet, builtin_finger("33"))
    lo = tet.bounds[0]
    y = float(tet.vertices[:, 1].mean())
    m = world.move((lo[0] - 0.05, y, 0.02), (1.0, 0.0, 0.0), 0.4)
    assert m.event == "touch"
    d0 = world.distance(m.end)
    s = world.slide(m.end, (0.0, -1.0, 0.0), 0.01, m.closed[0])
    assert s.event == "none"
    assert s.end[2] == m.end[2]
    assert world.distance(s.end) == pytest.approx(d0, abs=1e-12)


def test_concave_corner_closes_the_next_sensor() -> None:
    shape = solids.l_shape(0.08, 0.06, 0.03, 0.04)
    world = StepperWorld(shape, builtin_finger("4"))
    lo, hi = shape.bounds
    # below the inner corner, facing the long leg's inner face (normal +y)
    y_inner = lo[1] + 0.03
    x = lo[0] + 0.05
    m = world.move((x, hi[1] + 0.05, 0.02), (0.0, -1.0, 0.0), 0.2)
    assert m.event == "touch"
    assert m.end[1] == pytest.approx(y_inner + RHO, abs=1e-6)
    # slide towards the inner corner (-x): the leg's inner face (normal +x) closes sensor 2
    s = world.slide(m.end, (-1.0, 0.0, 0.0), 0.2, m.closed[0])
    assert s.event == "touch"
    assert s.closed == (2,)
    assert s.end[0] == pytest.approx(lo[0] + 0.03 + RHO, abs=1e-6)


def test_slide_without_contact_is_a_release_at_once() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    s = world.slide((0.0, 0.0, 0.3), (1.0, 0.0, 0.0), 0.1, 0)
    assert (s.event, s.distance, s.opened) == ("release", 0.0, (0,))


def test_bad_arguments() -> None:
    world = StepperWorld(cube(), builtin_finger("4"))
    with pytest.raises(UsageError, match="direction"):
        world.move((0.0, 0.0, 0.3), (0.0, 0.0, 0.0), 0.1)
    with pytest.raises(UsageError, match="length"):
        world.move((0.0, 0.0, 0.3), (1.0, 0.0, 0.0), -1.0)
    with pytest.raises(UsageError, match="no sensor 9"):
        world.slide((0.0, 0.0, 0.3), (1.0, 0.0, 0.0), 0.1, 9)


def test_the_mesh_is_not_modified() -> None:
    m = cube()
    before = m.vertices.copy()
    StepperWorld(m, builtin_finger("33")).move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    assert np.array_equal(before, m.vertices)


# --- whole explorations ------------------------------------------------------------------------


CONVEX = {
    "box": solids.box(0.08, 0.05, 0.04),
    "parallelepiped": solids.parallelepiped(0.08, 0.05, 0.04, angle_deg=70.0, shear_deg=15.0),
    "tetrahedron": solids.tetrahedron(0.1),
    "prism5": solids.prism(5, 0.04, 0.06),
    "pyramid4": solids.pyramid(4, 0.05, 0.06),
    "frustum6": solids.frustum(6, 0.05, 0.03, 0.05),
    "rotated_box": solids.rotate_about_z(solids.box(0.07, 0.05, 0.03), 0.4),
    "octahedron": solids.octahedron(0.08),
}


@pytest.mark.parametrize("name", sorted(CONVEX))
def test_every_feelable_face_of_a_convex_object_is_touched(name: str) -> None:
    mesh = CONVEX[name]
    finger = builtin_finger("33")
    rec = StepperExplorer().explore(mesh, finger=finger, seed=0)
    centres = np.asarray([c.centre for c in rec.contacts])
    faces = mesh_planes(mesh)
    # a face is felt when its contact direction -n fires a sensor: n_z >= -sin(cone) roughly
    feelable = [(n, d) for n, d in faces if n[2] > -0.3 and not (n[2] < -0.99)]
    missed = []
    for n, d in feelable:
        # some contact's tip centre lies on the face's plane offset by rho, over the face
        on = np.abs(centres @ n - d - finger.radius) < 1e-6
        if not on.any():
            missed.append(np.round(n, 3).tolist())
    overhanging = [n for n, _ in faces if -0.99 < n[2] <= -0.3]
    assert not missed, f"{name}: faces never touched: {missed} (overhanging: {len(overhanging)})"


@pytest.mark.parametrize(
    ("name", "corners"),
    [("l", 6), ("t", 8), ("u", 8)],
)
def test_box_unions_contours_have_the_right_corners(name: str, corners: int) -> None:
    mesh = {
        "l": solids.l_shape(0.08, 0.06, 0.03, 0.04),
        "t": solids.t_shape(0.09, 0.07, 0.03, 0.04),
        "u": solids.u_shape(0.09, 0.07, 0.03, 0.04),
    }[name]
    rec = StepperExplorer().explore(mesh, finger="4", seed=0)
    assert rec.layers
    z = 0.4 * 0.04
    truth = trimesh.intersections.mesh_plane(mesh, (0, 0, 1), (0, 0, z))  # type: ignore[no-untyped-call]
    assert len(truth) > 0
    assert all(layer.closed for layer in rec.layers)
    sections = build_model(rec).layers  # the controller computes no geometry: the model does
    assert len(sections) == len(rec.layers)
    for layer in sections:
        assert len(layer.contour) == corners
        # every traced corner is a corner of the true cross-section (within 1 mm)
        pts = np.asarray(truth).reshape(-1, 3)[:, :2]
        for x, y in layer.contour:
            assert (
                np.min(np.linalg.norm(pts - (x, y), axis=1)) < 1e-3
            )  # fitted to the touched lines


def test_a_hexahedron_is_explored_fast_with_few_touches() -> None:
    rec = StepperExplorer().explore(solids.box(0.06, 0.06, 0.06), finger="33", seed=0)
    assert rec.touches <= 12  # 6 faces: at most 2 touches per face
    assert [layer.closed for layer in rec.layers] == [True, True]
    phases = rec.contacts_per_phase
    assert phases["first-contact"] == 1
    assert phases["top"] >= 1


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=20, deadline=None)
def test_closest_points_are_those_of_trimesh(seed: int) -> None:
    from tactile_kb.touch.stepper import _closest

    rng = np.random.default_rng(seed)
    tri = rng.normal(size=(200, 3, 3))
    pts = rng.normal(size=(200, 3)) * 2.0
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    sides = np.stack([np.cross(n, tri[:, (k + 1) % 3] - tri[:, k]) for k in range(3)], axis=1)
    got, inside = _closest(tri, n, sides, pts)
    want = trimesh.triangles.closest_point(tri, pts)  # type: ignore[no-untyped-call]
    assert np.allclose(got, want, atol=1e-12)
    # inside: the closest point is the projection onto the plane
    proj = pts - np.einsum("ij,ij->i", pts - tri[:, 0], n)[:, None] * n
    assert np.allclose(got[inside], proj[inside], atol=1e-12)


def test_a_face_at_a_cone_edge_does_not_flicker_where_its_triangles_meet() -> None:
    # the face x = 0.05 of a cube turned by -25.08°: its contact direction lies 25.08° from
    # the equator sensor at 180°, just outside that sensor's 25° cone; sliding along it must
    # not close that sensor where the face's two triangles meet
    mesh = solids.rotate_about_z(cube(), -25.08, about=(0.0, 0.0))
    world = StepperWorld(mesh, builtin_finger("33"))
    n = np.array([math.cos(math.radians(-25.08)), math.sin(math.radians(-25.08)), 0.0])
    t = np.array([-n[1], n[0], 0.0])
    start = n * 0.2 + np.array([0.0, 0.0, 0.03]) - t * 0.04
    m = world.move(tuple(start), tuple(-n), 0.3)
    assert m.event == "touch"
    s = world.slide(m.end, tuple(t), 0.2, m.closed[0])
    # no change of sensors before the far end of the face (0.09 m away), where the tip rolls
    # over its edge
    assert s.distance == pytest.approx(0.09, abs=0.003)


def test_every_face_of_an_octahedron_has_tip_centres_at_two_heights() -> None:
    mesh = solids.rotate_about_z(solids.octahedron(0.04), 20.0)
    rec = StepperExplorer().explore(mesh, finger="33", seed=0)
    centres = np.asarray([c.centre for c in rec.contacts])
    for n, d in mesh_planes(mesh):
        if n[2] < -0.99:
            continue  # the table
        on = np.abs(centres @ n - d - RHO) < 1e-6
        heights = np.unique(np.round(centres[on, 2], 4))
        if n[2] > 0.99:
            assert on.sum() >= 3  # the top, from above
        else:
            assert len(heights) >= 2, f"face {np.round(n, 3)} felt at heights {heights}"


@pytest.mark.parametrize("turn", [0.0, 5.0, 90.0, 12.0, 37.0, 200.0])
def test_the_4_sensor_finger_refuses_objects_turned_away_from_its_sensors(turn: float) -> None:
    from tactile_kb.errors import ExplorationError
    from tactile_kb.touch.finger import ALIGN_4_DEG

    # ground truth: the L's faces are turned from the x/y sensors by the turn modulo 90°
    off = min(turn % 90.0, 90.0 - turn % 90.0)
    mesh = solids.rotate_about_z(solids.l_shape(0.1, 0.08, 0.04, 0.05), turn)
    if off <= ALIGN_4_DEG:
        rec = StepperExplorer().explore(mesh, finger="4", seed=0)
        assert all(layer.closed for layer in rec.layers)
        assert all(len(layer.contour) == 6 for layer in build_model(rec).layers)
        assert not any("turned" in n for n in rec.notes)
        return
    with pytest.raises(ExplorationError, match=rf"turned {off:.0f}° from sensor \d of finger '4'"):
        StepperExplorer().explore(mesh, finger="4", seed=0)
    # the 33-sensor finger has no such limit
    rec = StepperExplorer().explore(mesh, finger="33", seed=0)
    assert not any("turned" in n for n in rec.notes)
