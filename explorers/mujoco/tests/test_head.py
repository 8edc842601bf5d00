"""The indexing head in MuJoCo: hinge joints turned by their motors, sensors that turn with the
head, a colliding shaft, and objects whose faces only a tilted head reaches.

Ground truth comes from the construction: rotations built independently with scipy (a tilt
about y, then a turn about z), distances from plane geometry, and face normals of the solids.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation
from tactile_kb_mujoco.compare import compare_object
from tactile_kb_mujoco.explorer import MujocoExplorer
from tactile_kb_mujoco.world import MujocoWorld

from tactile_kb import solids
from tactile_kb.errors import ExplorationError
from tactile_kb.pipeline import classify
from tactile_kb.touch.finger import VERTICAL, Orientation, Wrist, builtin_finger
from tactile_kb.touch.sensors import FaultySensors
from tactile_kb.touch.stepper import StepperWorld
from tactile_kb.touch.world import OrientableWorld

RHO = 0.005
RS = 0.0025  # the stem's radius in these tests


def _stem(length: float = 0.1, **wrist: float) -> object:
    return builtin_finger("33").model_copy(
        update={"shaft_radius": RS, "shaft_length": length, "wrist": Wrist(**wrist)}
    )


def _cube() -> trimesh.Trimesh:
    return solids.box(0.04, 0.04, 0.04)  # x, y in [-0.02, 0.02], z in [0, 0.04]


def _truth(o: Orientation) -> np.ndarray:
    """The head's rotation by its definition: tilt about the horizontal y, then turn about z
    (scipy's extrinsic "yz" sequence)."""
    return Rotation.from_euler("yz", [o.tilt_deg, o.turn_deg], degrees=True).as_matrix()


POSES = [
    Orientation(15.0, 0.0),
    Orientation(90.0, 180.0),
    Orientation(45.0, 345.0),  # the turn from 180° goes the short way round
    Orientation(60.0, 90.0),
    Orientation(30.0, 210.0),
    VERTICAL,
]


def test_the_head_turned_by_its_motors_reaches_the_requested_pose() -> None:
    world = MujocoWorld(_cube(), builtin_finger("33"))
    assert isinstance(world, OrientableWorld)
    at = (0.0, 0.0, 0.15)
    for o in POSES:
        turned = world.oriented(o, at)
        assert turned.orientation == o
        assert turned.reached is not None
        # the motors brought the finger frame to the pose (before the detent locks it)
        assert np.abs(turned.reached - _truth(o)).max() < 2e-4
        # locked: MuJoCo's frame of the finger body and its sensor sites, placed at `at`
        np.testing.assert_allclose(turned.head_rotation(), _truth(o), atol=1e-12)
        sites = np.asarray(turned.data.site_xpos[: len(turned.finger.directions)])
        expected = np.asarray(at) + RHO * (turned.finger.matrix @ _truth(o).T)
        np.testing.assert_allclose(sites, expected, atol=1e-12)
        world = turned
    assert world.indexes == len(POSES)
    assert 0.0 < world.index_time < 5.0  # simulated seconds the head spent turning


def test_the_turned_head_senses_with_the_sensor_facing_the_face() -> None:
    world = MujocoWorld(_cube(), builtin_finger("33"))
    turned = world.oriented(Orientation(90.0, 270.0), (0.0, -0.08, 0.02))  # the pole faces +y
    m = turned.move((0.0, -0.08, 0.02), (0.0, 1.0, 0.0), 0.1)
    assert (m.event, m.closed) == ("touch", (0,))
    assert m.end[1] == pytest.approx(-0.02 - RHO, abs=1e-6)
    # the same motion with the vertical finger closes an equator sensor instead
    m = world.move((0.0, -0.08, 0.02), (0.0, 1.0, 0.0), 0.1)
    assert m.event == "touch"
    assert m.closed != (0,)
    assert world.orientation == VERTICAL  # oriented() made another world


def _overhang() -> tuple[trimesh.Trimesh, np.ndarray]:
    """A prism whose left face overhangs by 45°: its cross-section in the xz-plane is
    (0, 0), (0.04, 0), (0.04, 0.04), (-0.04, 0.04), extruded 4 cm along y."""
    xz = np.array([(0.0, 0.0), (0.04, 0.0), (0.04, 0.04), (-0.04, 0.04)])
    verts = [(x, y, z) for y in (-0.02, 0.02) for x, z in xz]
    mesh = trimesh.convex.convex_hull(np.array(verts))
    normal = np.array([-1.0, 0.0, -1.0]) / math.sqrt(2.0)
    return mesh, normal


def test_an_overhanging_face_is_felt_only_by_a_tilted_head() -> None:
    mesh, n = _overhang()
    assert np.isclose(mesh.face_normals @ n, 1.0).sum() == 2  # the face, two triangles
    finger = builtin_finger("33")
    # approach the face's point (-0.03, 0, 0.03) along −n from 2 cm out
    on = np.array([-0.03, 0.0, 0.03]) + RHO * n
    start = tuple(on + 0.02 * n)
    world = MujocoWorld(mesh, finger)
    m = world.move(start, tuple(-n), 0.05)
    assert m.event == "blocked"  # the vertical finger: no sensor faces the face (blind)
    assert m.fired == ()
    pose = finger.index_for(tuple(n))
    assert pose is not None
    assert pose.tilt_deg > 0
    tilted = world.oriented(pose, start)
    m = tilted.move(start, tuple(-n), 0.05)
    assert m.event == "touch"
    assert np.linalg.norm(np.asarray(m.end) - on) < 1e-6
    # the sensors that closed face the face (their turned directions within the cone of −n)
    dirs = finger.directions_at(pose)
    assert all(float(dirs[i] @ -n) >= finger.cos_cone - 1e-9 for i in m.closed)
    # and the analytic world agrees on the event and the sensors
    s = StepperWorld(mesh, finger).oriented(pose, start).move(start, tuple(-n), 0.05)
    assert (s.event, s.closed) == (m.event, m.closed)


def test_the_shaft_blocks_a_motion_where_it_meets_the_object() -> None:
    world = MujocoWorld(_cube(), _stem())
    # tilted 45° (turn 0): the pole points down −x, the shaft up +x; moving +x at z = 0.02
    # the shaft meets the cube's top-left edge (x = -0.02, z = 0.04) before the tip meets
    # the side: the axis through (x, 0.02) along (1, 1)/√2 passes RS from the edge when
    # (−0.04 − x)/√2 = RS
    o = Orientation(45.0, 0.0)
    start = (-0.1, 0.0, 0.02)
    m = world.oriented(o, start).move(start, (1.0, 0.0, 0.0), 0.1)
    assert m.event == "blocked"
    assert m.fired == ()
    assert m.end[0] == pytest.approx(-0.04 - RS * math.sqrt(2.0), abs=1e-6)
    # the analytic world's chain of balls stops within its ball spacing of the same place
    s = StepperWorld(_cube(), _stem()).oriented(o, start).move(start, (1.0, 0.0, 0.0), 0.1)
    assert s.event == "blocked"
    assert s.end[0] == pytest.approx(m.end[0], abs=0.75 * RS)
    # the vertical finger on the same line: the tip meets the side, the shaft stays clear
    m = world.move(start, (1.0, 0.0, 0.0), 0.1)
    assert m.event == "touch"
    assert m.end[0] == pytest.approx(-0.02 - RHO, abs=1e-6)


def test_the_shaft_blocks_the_vertical_finger_under_a_slab() -> None:
    slab = trimesh.creation.box((0.1, 0.1, 0.02))
    slab.apply_translation((0.06, 0.0, 0.05))  # x in [0.01, 0.11], z in [0.04, 0.06]
    m = MujocoWorld(slab, _stem()).move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.25)
    assert m.event == "blocked"
    assert m.end[0] == pytest.approx(0.01 - RS, abs=1e-6)
    m = MujocoWorld(slab, builtin_finger("33")).move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.25)
    assert m.event in ("none", "limit")  # without a stem the tip passes under


def test_the_touch_sensors_never_feel_the_shaft() -> None:
    # a stem a little thicker than the tip (5.5 mm against 5): moving +x, its lower end meets
    # the face 0.5 mm before the tip, at a point inside the equator sensor's site (2.2 mm
    # around the tip point facing +x); the stem is its own body, so no sensor fires
    finger = builtin_finger("33").model_copy(update={"shaft_radius": 0.0055, "shaft_length": 0.1})
    world = MujocoWorld(_cube(), finger)
    m = world.move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.3)
    assert m.event == "blocked"
    assert m.fired == ()
    assert m.end[0] == pytest.approx(-0.02 - 0.0055, abs=1e-6)
    contact = np.array([-0.02, 0.0, 0.02])
    site = np.asarray(m.end) + RHO * np.array([1.0, 0.0, 0.0])
    assert np.linalg.norm(contact - site) < 0.0021


def test_a_colliding_start_pose_is_one_line_and_changes_nothing() -> None:
    world = MujocoWorld(_cube(), _stem())
    # beside the cube, tilted 90° towards −x: the stem points +x into the cube
    with pytest.raises(ExplorationError) as exc:
        world.oriented(Orientation(90.0, 0.0), (-0.03, 0.0, 0.02))
    text = str(exc.value)
    assert "\n" not in text
    assert text.startswith("the head at tilt 90°, turn 0° collides with the object or the table")
    assert world.orientation == VERTICAL
    assert world.move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.1).event == "touch"
    # the same pose where the stem clears the cube is fine
    assert world.oriented(Orientation(90.0, 0.0), (-0.2, 0.0, 0.02)).orientation.tilt_deg == 90
    # a head tilted past the horizontal points its stem down: into the table at z = 1 cm
    # (its end at 0.01 + 0.1·cos 120° < 0), clear of it at 10 cm
    low = MujocoWorld(_cube(), _stem(max_tilt_deg=135.0))
    with pytest.raises(ExplorationError, match=r"^the head at tilt 120°, turn 0° collides"):
        low.oriented(Orientation(120.0, 0.0), (-0.1, 0.0, 0.01))
    assert (
        low.oriented(Orientation(120.0, 0.0), (-0.1, 0.0, 0.1)).shaft_collides((-0.1, 0.0, 0.1))
        is False
    )
    # through the explorer's faulty-sensor wrapper too
    wrapped = FaultySensors(MujocoWorld(_cube(), _stem()), seed=0)
    with pytest.raises(ExplorationError, match="collides"):
        wrapped.oriented(Orientation(90.0, 0.0), (-0.03, 0.0, 0.02))


def test_the_4_sensor_finger_has_no_head() -> None:
    world = MujocoWorld(_cube(), builtin_finger("4"))
    assert world.model.njnt == 3
    assert world.model.nu == 3
    assert world.oriented(VERTICAL, (0.0, 0.0, 0.1)) is world
    with pytest.raises(ExplorationError, match="has no wrist") as exc:
        world.oriented(Orientation(30.0, 0.0), (0.0, 0.0, 0.1))
    assert "\n" not in str(exc.value)
    assert mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, "shaft") == -1


def _lying_hexagonal_prism() -> trimesh.Trimesh:
    return solids.stable_poses(solids.prism(6, 0.03, 0.1))[0][0]  # its most probable pose


def test_a_lying_hexagonal_prism_is_a_prism_with_mujoco() -> None:
    m = _lying_hexagonal_prism()
    normals = np.unique(np.round(m.face_normals, 6), axis=0)
    assert sum(1 for n in normals if -0.6 < n[2] < -0.4) == 2  # two faces overhang by 30°
    r = classify(m, rules="polyhedra", explorer=MujocoExplorer())
    assert r.decision.label == "prism"
    assert r.record.ending == "closed", r.record.unreachable
    under = [f for f in r.model.contact_faces if f.normal[2] < -0.4]
    assert len(under) == 2  # touched by the indexed head
    tilted = [c for c in r.record.contacts if c.orientation != (0.0, 0.0)]
    assert tilted
    for f in under:
        assert math.degrees(math.acos(min(1.0, -f.normal[2]))) == pytest.approx(60.0, abs=3.0)


def test_an_oblique_parallelepiped_in_every_stable_pose_with_mujoco() -> None:
    block = solids.parallelepiped(
        0.09, 0.07, 0.05, angle_deg=65.0, shear_deg=12.0, shear_azimuth_deg=30.0
    )
    poses = solids.stable_poses(block)
    assert len(poses) == 6
    leaning = 0
    for k, (posed, _) in enumerate(poses):
        m = solids.rotate_about_z(posed, 47.0 * k)
        truth = np.unique(np.round(m.face_normals, 6), axis=0)
        leaning += int((truth[:, 2] < -0.2).any())
        r = classify(m, rules="polyhedra", explorer=MujocoExplorer())
        assert r.decision.label == "nonrectangular_parallelepiped", k
        assert r.record.ending in ("closed", "unreachable"), (k, r.record.unreachable)
        poly = r.model.polyhedron
        assert poly is not None
        for n in truth:
            assert float(np.max(poly.normals @ n)) >= math.cos(math.radians(3.0)), (k, n)
    assert leaning >= 2


@pytest.mark.parametrize("name", ["OCTA", "PRAPAR", "KOPAR"])
def test_with_a_stem_both_explorers_agree_on_fig5(name: str) -> None:
    # the stem collides in both worlds (a capsule here, a chain of balls in the stepper): the
    # explorations take the same touches and contacts and give the same answer and planes
    # (OCTA's answer changes with a stem in both, as docs/exploration.md says)
    mesh = {n: m for n, m, _ in solids.fig5_objects()}[name]
    stem = builtin_finger("33").model_copy(update={"shaft_radius": 0.5 * RHO})
    row = compare_object(name, mesh, finger=stem, seed=0)
    stepper, sim = row.runs
    assert (sim.label, sim.answer) == (stepper.label, stepper.answer)
    assert sim.record.touches == stepper.record.touches
    assert len(sim.record.contacts) == len(stepper.record.contacts)
    assert row.planes[0] == row.planes[1]
    assert row.agreement.unmatched == 0
    assert row.max_angle_deg < 0.01
    assert row.max_offset < 1e-5
