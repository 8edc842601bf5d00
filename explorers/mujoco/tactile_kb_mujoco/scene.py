"""The MuJoCo scene (MJCF) generated from a finger layout and an object's convex parts.

The scene mirrors the analytic stepper's world:

* the **finger** is a body on three slide joints ``x``, ``y``, ``z`` driven by three
  position actuators ``Mx``, ``My``, ``Mz`` (the paper's motors), its weight compensated
  (``gravcomp="1"``); its tip is a frictionless sphere geom of radius ρ (``finger.radius``)
  with a contact margin of :data:`tactile_kb.touch.world.CONTACT_TOL`, so a tip whose centre is
  within ρ + margin of the object is in contact and pressed, as the protocol defines contact
  (a soft contact makes force only once the margin is crossed);
* each **tactile sensor** ``i`` is a sphere site ``s{i}`` centred on the tip surface at
  ``ρ·dᵢ`` whose radius ``2ρ·sin(θ/2)`` is the chord of the acceptance cone θ: a contact
  point on the tip lies in the site exactly when its direction from the tip centre lies
  in the cone. A ``<touch>`` sensor ``t{i}`` reads the normal force inside the site; the
  sensor fires when that force exceeds a threshold;
* the **object** is fixed to the world: one geom per convex part (a ``box`` geom for each box
  of an orthogonal object, a ``mesh`` geom (its convex hull) otherwise). Contacts are
  frictionless (``condim="1"`` on the tip and the parts): the sensors feel normal pressure
  only, and with friction MuJoCo's pyramidal cones kick a tip that slides pressed on a face
  off it;
* the **table** is the plane z = 0, drawn but not colliding with the tip: the workspace
  floor keeps the tip above it, as in the analytic world;
* a finger with an indexing head (``finger.wrist``) gets two **hinge joints** after the slides,
  both through the tip centre: ``turn`` about +z, then ``tilt`` about the turned +y. MuJoCo
  composes a body's joints in their order, so the finger frame is ``Rz(turn) · Ry(tilt)``:
  :attr:`tactile_kb.touch.finger.Orientation.rotation` (tilted by θ, then turned about the
  vertical). Each hinge has a position actuator (``Mturn``, ``Mtilt``). The sites are placed in
  the finger frame, so the sensors turn with the head;
* a finger with a ``shaft_radius`` gets a **shaft**: a capsule of that radius on the finger's
  axis (+z in the finger frame) from ``max(ρ − r, 0)`` to ``shaft_length`` above the tip centre,
  as the analytic world's chain of balls. It is a child body of the finger (so the touch sensors,
  which read the contacts of their own body, never feel it) and collides with the object and
  the table (a block under z = 0).

Examples
--------
>>> import trimesh
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb_mujoco.parts import convex_parts
>>> xml = scene_xml(builtin_finger("4"), convex_parts(trimesh.creation.box((0.04, 0.04, 0.04))))
>>> xml.count("<touch "), xml.count('type="slide"'), xml.count("<position ")
(4, 3, 3)
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from tactile_kb.settings import current
from tactile_kb.touch.finger import Finger
from tactile_kb_mujoco.parts import ConvexPart

__all__ = ["HEAD_JOINTS", "SceneOptions", "scene_xml", "site_radius"]

HEAD_JOINTS = ("turn", "tilt")
"""The head's hinge joints in chain order (after the slides ``x``, ``y``, ``z``)."""


@dataclass(frozen=True)
class SceneOptions:
    """Physical parameters of the generated scene.

    Attributes
    ----------
    timestep
        Simulation step, seconds.
    finger_mass
        Mass of the moving finger, kg (its weight is compensated).
    omega
        Natural frequency of each motor's position loop, rad/s; the actuators get
        ``kp = m·ω²`` and critical damping ``kv = 2·m·ω``.
    margin
        Contact margin of the tip, metres: the tip is in contact (and pressed) within
        ρ + margin of the object; by default the settings' ``world.contact_tol`` when the
        options are made.
    head_inertia
        Rotor inertia (``armature``) of each head hinge, kg·m²; it dominates the tip's and the
        shaft's own inertia, so the head's loop behaves the same in every pose.
    head_omega
        Natural frequency of each head motor's position loop, rad/s (``kp = I·ω²``, critical
        damping ``kv = 2·I·ω``).
    shaft_mass
        Mass of the shaft, kg (its weight is compensated).
    """

    timestep: float = 0.001
    finger_mass: float = 0.05
    omega: float = 150.0
    margin: float = field(default_factory=lambda: current().world.contact_tol)
    head_inertia: float = 0.01
    head_omega: float = 60.0
    shaft_mass: float = 0.01

    @property
    def kp(self) -> float:
        """Position gain of each motor, N/m."""
        return self.finger_mass * self.omega**2

    @property
    def kv(self) -> float:
        """Velocity gain of each motor, N·s/m (critical damping)."""
        return 2.0 * self.finger_mass * self.omega

    @property
    def head_kp(self) -> float:
        """Position gain of each head motor, N·m/rad."""
        return self.head_inertia * self.head_omega**2

    @property
    def head_kv(self) -> float:
        """Velocity gain of each head motor, N·m·s/rad (critical damping)."""
        return 2.0 * self.head_inertia * self.head_omega


def site_radius(finger: Finger) -> float:
    """Radius of a sensor site: the chord 2ρ·sin(θ/2) of the acceptance cone θ."""
    return 2.0 * finger.radius * math.sin(math.radians(finger.cone_deg) / 2.0)


def _f(values: Sequence[float] | np.ndarray) -> str:
    return " ".join(repr(float(v)) for v in np.asarray(values, dtype=float).ravel())


def scene_xml(
    finger: Finger,
    parts: Sequence[ConvexPart],
    *,
    options: SceneOptions | None = None,
    start: Sequence[float] = (0.0, 0.0, 0.5),
    table_size: float = 1.0,
    head: Sequence[float] | np.ndarray = (0.0, 0.0),
) -> str:
    """The MJCF text of the scene: ``finger`` exploring the object made of ``parts``.

    Parameters
    ----------
    finger
        The finger layout (tip radius, sensor directions, cone half-angle).
    parts
        The object's convex parts in world coordinates (:func:`convex_parts`).
    options
        Physical parameters (:class:`SceneOptions`).
    start
        Initial tip-centre position (the joints' zero is the world origin).
    head
        Initial head angles ``(turn, tilt)``, radians (used when the finger has a wrist).
    table_size
        Half-size of the drawn table plane, metres.
    """
    opt = options or SceneOptions()
    root = ET.Element("mujoco", model="tactile_kb")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(
        root,
        "option",
        timestep=repr(opt.timestep),
        gravity="0 0 -9.81",
        integrator="implicitfast",
    )
    asset = ET.SubElement(root, "asset")
    world = ET.SubElement(root, "worldbody")
    ET.SubElement(
        world,
        "geom",
        name="table",
        type="plane",
        size=_f((table_size, table_size, 0.01)),
        contype="0",
        conaffinity="0",
        rgba="0.8 0.8 0.75 1",
    )
    if finger.shaft_radius is not None:
        # the table as the shaft meets it: a block under z = 0, deeper than the shaft is long
        # (MuJoCo 4.0 misses a capsule passing right through a thin box, and a colliding
        # plane in the world body makes it drop the tip's contacts with box geoms)
        depth = max(table_size, finger.shaft_length)
        ET.SubElement(
            world,
            "geom",
            name="slab",
            type="box",
            size=_f((table_size, table_size, depth)),
            pos=_f((0.0, 0.0, -depth)),
            contype="0",
            conaffinity="4",  # the shaft's contype: the tip never meets it (workspace floor)
            rgba="0.8 0.8 0.75 0",
        )
    for k, part in enumerate(parts):
        attrs = {
            "name": f"part{k}",
            "contype": "2",
            "conaffinity": "1",
            "condim": "1",
            "rgba": "0.3 0.5 0.8 1",
        }
        if part.kind == "box":
            attrs |= {
                "type": "box",
                "size": _f(part.size),
                "pos": _f(part.centre),
                "xyaxes": _f(np.concatenate([part.rotation[:, 0], part.rotation[:, 1]])),
            }
        else:
            ET.SubElement(asset, "mesh", name=f"hull{k}", vertex=_f(part.vertices))
            attrs |= {"type": "mesh", "mesh": f"hull{k}"}
        ET.SubElement(world, "geom", attrs)
    body = ET.SubElement(world, "body", name="finger", gravcomp="1")
    for axis, vec in (("x", "1 0 0"), ("y", "0 1 0"), ("z", "0 0 1")):
        ET.SubElement(body, "joint", name=axis, type="slide", axis=vec, ref="0")
    wrist = finger.wrist is not None
    if wrist:  # after the slides, through the tip centre: the frame is Rz(turn) · Ry(tilt)
        for name, vec in zip(HEAD_JOINTS, ("0 0 1", "0 1 0"), strict=True):
            ET.SubElement(
                body,
                "joint",
                name=name,
                type="hinge",
                axis=vec,
                pos="0 0 0",
                ref="0",
                armature=repr(opt.head_inertia),
            )
    ET.SubElement(
        body,
        "geom",
        name="tip",
        type="sphere",
        size=repr(finger.radius),
        mass=repr(opt.finger_mass),
        condim="1",
        margin=repr(opt.margin),
        contype="1",
        conaffinity="2",
        rgba="0.9 0.6 0.4 1",
    )
    r_site = site_radius(finger)
    for i, d in enumerate(finger.directions):
        ET.SubElement(
            body,
            "site",
            name=f"s{i}",
            type="sphere",
            size=repr(r_site),
            pos=_f(np.asarray(d) * finger.radius),
            rgba="1 0 0 0.3",
        )
    if finger.shaft_radius is not None:
        rs = float(finger.shaft_radius)
        shaft = ET.SubElement(body, "body", name="shaft", gravcomp="1")
        ET.SubElement(
            shaft,
            "geom",
            name="shaft",
            type="capsule",
            size=repr(rs),
            fromto=_f((0.0, 0.0, max(finger.radius - rs, 0.0), 0.0, 0.0, finger.shaft_length)),
            mass=repr(opt.shaft_mass),
            condim="1",
            margin="0",
            contype="4",  # the table's conaffinity
            conaffinity="2",  # the object's contype
            rgba="0.5 0.5 0.5 1",
        )
    actuators = ET.SubElement(root, "actuator")
    for axis in ("x", "y", "z"):
        ET.SubElement(
            actuators,
            "position",
            name=f"M{axis}",
            joint=axis,
            kp=repr(opt.kp),
            kv=repr(opt.kv),
        )
    if wrist:
        for name in HEAD_JOINTS:
            ET.SubElement(
                actuators,
                "position",
                name=f"M{name}",
                joint=name,
                kp=repr(opt.head_kp),
                kv=repr(opt.head_kv),
            )
    sensors = ET.SubElement(root, "sensor")
    for i in range(len(finger.directions)):
        ET.SubElement(sensors, "touch", name=f"t{i}", site=f"s{i}")
    keyframe = ET.SubElement(root, "keyframe")
    q0 = [*start, *head] if wrist else list(start)
    ET.SubElement(keyframe, "key", name="start", qpos=_f(q0), ctrl=_f(q0))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")
