"""The generated MJCF: the finger's joints, motors, tip and sensors mirror the Finger layout."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from tactile_kb_mujoco.parts import convex_parts
from tactile_kb_mujoco.scene import SceneOptions, scene_xml, site_radius
from tactile_kb_mujoco.world import MujocoWorld

from tactile_kb import solids
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.world import CONTACT_TOL


@pytest.mark.parametrize("layout", ["4", "33"])
def test_model_mirrors_the_finger(layout):
    finger = builtin_finger(layout)
    parts = convex_parts(solids.l_shape(0.1, 0.08, 0.03, 0.04))
    model = mujoco.MjModel.from_xml_string(scene_xml(finger, parts))
    n = len(finger.directions)
    assert model.nsensor == n
    assert all(model.sensor_type[i] == mujoco.mjtSensor.mjSENS_TOUCH for i in range(n))
    head = finger.wrist is not None  # "33" indexes, "4" stays vertical
    assert model.njnt == (5 if head else 3)
    assert all(model.jnt_type[i] == mujoco.mjtJoint.mjJNT_SLIDE for i in range(3))
    np.testing.assert_array_equal(model.jnt_axis[:3], np.eye(3))
    names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(model.nu)]
    assert names == ["Mx", "My", "Mz", *(["Mturn", "Mtilt"] if head else [])]
    if head:  # turn about z, then tilt about the turned y, both through the tip centre
        assert all(model.jnt_type[i] == mujoco.mjtJoint.mjJNT_HINGE for i in (3, 4))
        np.testing.assert_array_equal(model.jnt_axis[3:], [[0, 0, 1], [0, 1, 0]])
        np.testing.assert_array_equal(model.jnt_pos[3:], np.zeros((2, 3)))
    tip = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "tip")
    assert model.geom_type[tip] == mujoco.mjtGeom.mjGEOM_SPHERE
    assert model.geom_size[tip][0] == pytest.approx(finger.radius)
    assert model.geom_margin[tip] == pytest.approx(CONTACT_TOL)
    finger_body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "finger")
    assert model.body_gravcomp[finger_body] == 1.0
    for i, d in enumerate(finger.directions):
        site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"s{i}")
        np.testing.assert_allclose(model.site_pos[site], np.asarray(d) * finger.radius, atol=1e-15)
        assert model.site_size[site][0] == pytest.approx(
            2 * finger.radius * math.sin(math.radians(finger.cone_deg) / 2)
        )
    # two box geoms for the L, one plane for the table (which never collides)
    kinds = [int(model.geom_type[g]) for g in range(model.ngeom) if g != tip]
    plane, box = int(mujoco.mjtGeom.mjGEOM_PLANE), int(mujoco.mjtGeom.mjGEOM_BOX)
    assert sorted(kinds) == sorted([plane, box, box])
    table = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "table")
    assert model.geom_contype[table] == 0
    assert model.geom_conaffinity[table] == 0


def test_convex_object_is_one_mesh_geom():
    xml = scene_xml(builtin_finger("33"), convex_parts(solids.octahedron(0.06)))
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.nmesh == 1
    assert (
        sum(int(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH) for g in range(model.ngeom)) == 1
    )


def test_motor_gains():
    opt = SceneOptions(finger_mass=0.1, omega=100.0)
    assert opt.kp == pytest.approx(1000.0)
    assert opt.kv == pytest.approx(20.0)


def test_site_radius_is_the_cone_chord():
    finger = builtin_finger("4")
    r = site_radius(finger)
    # a point on the tip at exactly the cone's half-angle from the sensor lies on the site sphere
    a = math.radians(finger.cone_deg)
    on_tip = finger.radius * np.array([math.cos(a), math.sin(a), 0.0])
    assert np.linalg.norm(on_tip - finger.radius * np.array([1.0, 0.0, 0.0])) == pytest.approx(r)


def _face_towards(direction: np.ndarray) -> trimesh.Trimesh:
    """A 0.4 m cube whose face has outward normal −direction and passes through the origin."""
    box = trimesh.creation.box((0.4, 0.4, 0.4))
    box.apply_translation((0.2, 0.0, 0.0))  # face x = 0, outward normal −x
    rot = trimesh.geometry.align_vectors((1.0, 0.0, 0.0), direction)
    box.apply_transform(rot)
    return box


FINGER_33 = builtin_finger("33")


def _away_from_cone_boundaries(u: np.ndarray, margin_deg: float = 0.05) -> bool:
    angles = np.degrees(np.arccos(np.clip(FINGER_33.matrix @ u, -1.0, 1.0)))
    return bool(np.abs(angles - FINGER_33.cone_deg).min() > margin_deg)


@settings(max_examples=25, deadline=None)
@given(
    st.floats(-math.pi, math.pi),
    st.floats(-math.pi / 2 + 0.01, 0.3),
)
def test_touch_sensors_fire_inside_their_cones(azimuth, elevation):
    """Ground truth: a plane touched in direction u fires exactly the sensors whose cone holds u."""
    u = np.array(
        [
            math.cos(elevation) * math.cos(azimuth),
            math.cos(elevation) * math.sin(azimuth),
            math.sin(elevation),
        ]
    )
    if not _away_from_cone_boundaries(u):
        return
    world = MujocoWorld(_face_towards(u), FINGER_33, workspace=None)
    centre = -u * (FINGER_33.radius + 0.5 * CONTACT_TOL)  # inside the contact band
    expected = tuple(
        i
        for i, d in enumerate(FINGER_33.directions)
        if math.degrees(math.acos(max(-1.0, min(1.0, float(np.dot(d, u)))))) <= FINGER_33.cone_deg
    )
    assert world.sense(tuple(centre)) == expected
    # just outside the band: nothing fires
    assert world.sense(tuple(-u * (FINGER_33.radius + 2 * CONTACT_TOL))) == ()
