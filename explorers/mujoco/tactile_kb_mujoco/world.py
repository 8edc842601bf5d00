"""The MuJoCo world: :class:`tactile_kb.touch.world.World` on top of a physics simulation.

The finger is driven by its three motors (position actuators on slide joints x, y, z) and
MuJoCo steps the dynamics; the tactile sensors are MuJoCo ``<touch>`` sensors (a sensor is ON
when the normal force inside its site exceeds :attr:`MujocoWorld.threshold`). A motion is
carried out in two stages:

1. **drive**: the motors' set-points advance along the commanded line at ``speed`` and the
   simulation steps; after every step the world reads the touch sensors of the moving finger
   (the physical detection). When the finger feels a change, or touches something, or at
   least every ``check_every`` steps, the commanded line is *probed* there (the finger placed
   on the line, ``mj_forward``, sensors read) to confirm;
2. **refine**: the first confirmed sample is found among the samples since the last clean
   probe, and the event is located between two samples by bisection on probes to
   :attr:`MujocoWorld.resolution`; the finger is then set there at rest.

A *slide* (compliant motion) follows the surface the sensor touches: the surface normal comes
from MuJoCo's contact, the motion runs along the horizontal tangent, and the set-points are
offset by :attr:`MujocoWorld.press` into the surface, so the motors press the frictionless tip
on it with a small force while it slides. The commanded line runs just inside the contact band
(``depth`` below ρ + margin), parallel to the surface's plane; that is where probes are taken,
as the analytic world keeps the tip at distance ρ.

With an indexing head (``finger.wrist``), the world's value includes the head's pose
(:class:`~tactile_kb.touch.world.OrientableWorld`): :meth:`MujocoWorld.oriented` returns the
same world (the same simulation) with the head turned. The turn is simulated: with the tip
held where the head turns, the two hinge motors' set-points ramp to the new angles and the
simulation steps (contacts off: the turn is checked at its end, as in the analytic world)
until the head settles; the head then locks at its index (an indexing head's detent), and the
finger frame reached in the simulation must be the pose's rotation. A pose whose shaft enters
the object or the table there is refused with a one-line
:class:`~tactile_kb.errors.ExplorationError`. During motions the head's motors hold the pose,
and a motion the shaft would make enter the object or the table stops ``"blocked"``: the
shaft's contacts count as penetrations, and the touch sensors never feel them (they read the
contacts of the tip's own body).

Contacts are read from MuJoCo's contact list: the tip is *in contact* with a surface when its
distance is below the tip's margin (:class:`~tactile_kb_mujoco.scene.SceneOptions`), which is
:data:`tactile_kb.touch.world.CONTACT_TOL`. A motion is *blocked* where the tip would penetrate
the object by more than :data:`tactile_kb.touch.world.BLOCK_TOL` without a change of the fired set
(a blind contact), as in the analytic world.

Examples
--------
>>> from tactile_kb import solids
>>> from tactile_kb.touch.finger import builtin_finger
>>> world = MujocoWorld(solids.box(0.04, 0.04, 0.04), builtin_finger("4"))
>>> m = world.move((-0.05, 0.0, 0.02), (1.0, 0.0, 0.0), 0.1)
>>> m.event, m.closed, round(m.end[0], 6)
('touch', (0,), -0.025)
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
import trimesh
from numpy.typing import NDArray

from tactile_kb.errors import ExplorationError, ObjectError, UsageError
from tactile_kb.settings import current
from tactile_kb.touch.finger import VERTICAL, Finger, Orientation
from tactile_kb.touch.world import (
    Box,
    Event,
    Motion,
    MotionKind,
    Vec3,
    Workspace,
    default_workspace,
)
from tactile_kb_mujoco.parts import CONCAVITY_RHO, MAX_HULL_VERTICES, ConvexPart, convex_parts
from tactile_kb_mujoco.scene import HEAD_JOINTS, SceneOptions, scene_xml

__all__ = ["MujocoWorld"]

FloatArray = NDArray[np.float64]

_SNAP_COS = math.cos(2e-3)  # a contact normal this close to a hull face's normal is that face's


@dataclass(frozen=True)
class _Contact:
    geom: int
    dist: float
    normal: FloatArray  # unit, from the object towards the tip centre


@dataclass(frozen=True)
class _Probe:
    fired: tuple[int, ...]
    penetration: float  # deepest penetration of the tip or shaft into anything (≤ 0: none), m


@dataclass
class _Stats:
    """Counters shared by a world and the worlds :meth:`MujocoWorld.oriented` makes of it."""

    steps: int = 0
    probes: int = 0
    sim_time: float = 0.0
    physical_events: int = 0
    index_steps: int = 0
    index_time: float = 0.0
    indexes: int = 0


HEAD_TOL_RAD = 1e-4
"""Radians: a simulated turn of the head has settled when both hinges are this close to their
set-points (and slower than this per second); the frame then reached must match the pose's
rotation to this angle."""


def _angles(orientation: Orientation) -> FloatArray:
    """The head's hinge angles ``(turn, tilt)``, radians, for ``orientation``."""
    return np.radians([orientation.turn_deg, orientation.tilt_deg]).astype(float)


def _turn_between(rot_a: FloatArray, rot_b: FloatArray) -> float:
    """The angle of the rotation taking ``rot_a`` to ``rot_b``, radians."""
    c = (float(np.trace(rot_a.T @ rot_b)) - 1.0) / 2.0
    return math.acos(max(-1.0, min(1.0, c)))


def _normals(part: ConvexPart) -> FloatArray:
    """Unit outward normals of the faces of a part's convex hull."""
    if part.kind == "box":
        return np.vstack([part.rotation.T, -part.rotation.T])
    hull = trimesh.convex.convex_hull(part.vertices)
    return np.asarray(hull.face_normals, dtype=float)


def _vec(v: Sequence[float] | FloatArray) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


class MujocoWorld:
    """A finger exploring ``mesh`` in a MuJoCo simulation (implements ``World``).

    Parameters
    ----------
    mesh
        The object, resting on the table z = 0 (not modified).
    finger
        The finger layout; the scene's sites and sensors are generated from it.
    name
        What error messages call the object.
    workspace
        The motors' range (default: the analytic world's,
        :func:`tactile_kb.touch.world.default_workspace`).
    hint_margin
        How much the :attr:`hint` box exceeds the object's bounds, metres (as the analytic
        world).
    speed
        Motor speed along a motion, m/s.
    press
        Set-point offset into the surface during a slide, metres (force = kp · press).
    threshold
        Touch-sensor force above which a sensor is ON, newtons.
    resolution
        Bisection tolerance of an event's position, metres.
    settle
        A motion without event ends when the finger is this close to its end point, metres
        (the servo loop's last micrometres are not simulated).
    check_every
        While the finger touches nothing and feels no change, the commanded line is probed
        every this many physics steps (always when it touches or feels a change).
    depth
        How far inside the contact band (ρ + margin) a slide's commanded line runs, metres.
    options
        The scene's physical parameters (:class:`SceneOptions`).
    parts
        The object's convex parts, if already computed (:func:`convex_parts`).
    max_hull_vertices
        A convex part with more hull vertices is refused (:class:`ObjectError`).
    concavity_tol
        A mesh that is neither convex nor orthogonal is collided as its convex hull when the
        tip reaches no deeper than this under the hull beyond the surface's roughness
        (:func:`~tactile_kb_mujoco.parts.convex_parts`), metres; default
        :data:`~tactile_kb_mujoco.parts.CONCAVITY_RHO` tip radii; 0 always decomposes it.
    orientation
        The head's pose (:class:`~tactile_kb.touch.finger.Orientation`); only the vertical for a
        finger without a wrist. :meth:`oriented` gives the same world with the head turned.
    head_speed
        How fast the head's motors turn it when it indexes, rad/s.
    """

    def __init__(
        self,
        mesh: trimesh.Trimesh,
        finger: Finger,
        *,
        name: str = "object",
        workspace: Workspace | None = None,
        hint_margin: float = 0.005,
        speed: float = 0.25,
        press: float = 1e-4,
        threshold: float = 0.0,
        resolution: float = 1e-9,
        settle: float = 1e-6,
        depth: float = 1e-8,
        check_every: int = 4,
        options: SceneOptions | None = None,
        parts: Sequence[ConvexPart] | None = None,
        max_hull_vertices: int = MAX_HULL_VERTICES,
        concavity_tol: float | None = None,
        orientation: Orientation = VERTICAL,
        head_speed: float = 2.0 * math.pi,
    ) -> None:
        if speed <= 0 or press < 0 or resolution <= 0 or head_speed <= 0:
            raise UsageError("press must be ≥ 0, speed, head_speed and resolution > 0")
        self._head = finger.wrist is not None
        if not self._head and orientation != VERTICAL:
            raise UsageError(f"finger {finger.name!r} has no wrist: its head stays vertical")
        self._finger = finger
        self._orientation = orientation
        self._q_head = _angles(orientation) if self._head else np.zeros(0)
        self.head_speed = float(head_speed)
        self.name = name
        self.speed = float(speed)
        self.press = float(press)
        self.threshold = float(threshold)
        self.resolution = float(resolution)
        self.settle = float(settle)
        self.depth = float(depth)
        self.check_every = max(1, int(check_every))
        self.options = options or SceneOptions()
        self.parts = (
            tuple(parts)
            if parts is not None
            else convex_parts(
                mesh,
                name=name,
                max_hull_vertices=max_hull_vertices,
                tip_radius=finger.radius,
                concavity_tol=(
                    CONCAVITY_RHO * finger.radius if concavity_tol is None else concavity_tol
                ),
            )
        )
        b = np.asarray(mesh.bounds, dtype=float)
        self._workspace = workspace or default_workspace(b, finger.radius)
        self._hint = Box(lo=_vec(b[0] - hint_margin), hi=_vec(b[1] + hint_margin))
        start = self._workspace.hi
        self.xml = scene_xml(
            finger, self.parts, options=self.options, start=start, head=self._q_head
        )
        try:
            self.model: Any = mujoco.MjModel.from_xml_string(self.xml)
        except ValueError as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else "unknown error"
            raise ObjectError(f"{name}: MuJoCo cannot take this mesh: {first}") from None
        self.data: Any = mujoco.MjData(self.model)
        self._probe_data: Any = mujoco.MjData(self.model)
        mujoco.mj_resetDataKeyframe(self.model, self.data, 0)
        self._tip = int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "tip"))
        self._shaft = int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "shaft"))
        self._body = int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "finger"))
        joints = [
            int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, j))
            for j in (HEAD_JOINTS if self._head else ())
        ]
        self._hinges = [int(self.model.jnt_qposadr[j]) for j in joints]
        self._hinge_dofs = [int(self.model.jnt_dofadr[j]) for j in joints]
        self._margin = float(self.model.geom_margin[self._tip])
        self._dirs = finger.directions_at(orientation)
        self._face_normals = {
            int(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"part{k}")): _normals(part)
            for k, part in enumerate(self.parts)
        }
        self._stats = _Stats()
        self.reached: FloatArray | None = None
        """The finger frame (3×3) the head's motors reached in the simulated turn that made
        this world (:meth:`oriented` with ``at``), before the head locked at its index."""

    # counters (shared with the worlds oriented() makes) ----------------------------------
    @property
    def steps(self) -> int:
        """Physics steps taken so far in motions."""
        return self._stats.steps

    @property
    def probes(self) -> int:
        """Probes (``mj_forward`` at a placed position) taken so far."""
        return self._stats.probes

    @property
    def sim_time(self) -> float:
        """Simulated seconds of motion so far."""
        return self._stats.sim_time

    @property
    def physical_events(self) -> int:
        """Steps at which the moving finger's own sensors differed from the motion's start."""
        return self._stats.physical_events

    @property
    def indexes(self) -> int:
        """How many times the head was turned (simulated) so far."""
        return self._stats.indexes

    @property
    def index_time(self) -> float:
        """Simulated seconds spent turning the head so far."""
        return self._stats.index_time

    # World protocol -----------------------------------------------------------------------
    @property
    def finger(self) -> Finger:
        """The finger layout."""
        return self._finger

    @property
    def workspace(self) -> Workspace:
        """Where the tip centre may go."""
        return self._workspace

    @property
    def hint(self) -> Box:
        """A rough box around the object."""
        return self._hint

    @property
    def orientation(self) -> Orientation:
        """The head's pose."""
        return self._orientation

    def oriented(self, orientation: Orientation, at: Vec3 | None = None) -> MujocoWorld:
        """This world (the same simulation) with the head indexed to ``orientation``.

        With ``at`` (the tip centre where the head turns), the turn is simulated there by the
        head's motors, and a pose whose shaft enters the object or the table there raises
        :class:`~tactile_kb.errors.ExplorationError` (one line).
        """
        if not self._head:
            if orientation == VERTICAL:
                return self
            raise ExplorationError(
                f"finger {self._finger.name!r} has no wrist: its head cannot index to tilt "
                f"{orientation.tilt_deg:g}°, turn {orientation.turn_deg:g}°"
            )
        out = copy.copy(self)
        out._orientation = orientation
        out._q_head = _angles(orientation)
        out._dirs = self._finger.directions_at(orientation)
        out.reached = None
        if at is None:
            return out
        p = np.asarray(at, dtype=float)
        reached = out._turn_head(p, self._q_head)
        out.reached = reached
        error = _turn_between(reached, orientation.rotation)
        if error > 10.0 * HEAD_TOL_RAD:
            raise ExplorationError(
                f"the head settled {math.degrees(error):.3g}° away from tilt "
                f"{orientation.tilt_deg:g}°, turn {orientation.turn_deg:g}°"
            )
        if out._shaft_penetration(p) > current().world.block_tol:
            raise ExplorationError(
                f"the head at tilt {orientation.tilt_deg:g}°, turn {orientation.turn_deg:g}° "
                f"collides with the object or the table at {tuple(round(c, 4) for c in at)}: "
                "index the head elsewhere"
            )
        return out

    def head_rotation(self) -> FloatArray:
        """The finger frame's rotation in the simulation where the finger was last placed
        (the head's pose as MuJoCo has it), 3×3."""
        out: FloatArray = np.asarray(self.data.xmat[self._body], dtype=float).reshape(3, 3).copy()
        return out

    def shaft_collides(self, centre: Vec3) -> bool:
        """Whether the shaft enters the object or the table with the tip centre at ``centre``."""
        return self._shaft_penetration(np.asarray(centre, dtype=float)) > current().world.block_tol

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        """Sensors ON with the tip centre placed at ``centre``."""
        return self._probe(np.asarray(centre, dtype=float)).fired

    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        """Drive the tip from ``start`` along ``direction`` up to the first event."""
        p0 = np.asarray(start, dtype=float)
        u = self._unit(direction)
        ref = self._probe(p0)
        return self._run("move", p0, u, float(length), ref, press=np.zeros(3))

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        """Slide pressed on the surface ``sensor`` touches, horizontally, up to an event."""
        p0 = np.asarray(start, dtype=float)
        if not 0 <= sensor < len(self._dirs):
            raise UsageError(f"slide: no sensor {sensor} on finger {self._finger.name!r}")
        ref = self._probe(p0)
        surface = self._surface_of(sensor)
        if surface is None:  # not in contact: the sensor is released where it stands
            return Motion(
                kind="slide",
                start=_vec(p0),
                end=_vec(p0),
                direction=_vec(direction),
                distance=0.0,
                event="release",
                fired_start=ref.fired,
                fired=ref.fired,
                closed=(),
                opened=(sensor,),
                measured=_vec(p0),
            )
        n = self._snap(surface)
        # Pressed on the surface: the commanded line runs just inside the contact band.
        p0 = p0 - (surface.dist - (self._margin - self.depth)) * n
        ref = self._probe(p0)
        cmd = np.asarray(direction, dtype=float)
        if math.hypot(n[0], n[1]) < 1e-6:  # a horizontal surface: any horizontal is tangent
            t = np.array([cmd[0], cmd[1], 0.0])
        else:
            t = np.array([-n[1], n[0], 0.0])  # ẑ × n; a command into the face keeps this sense
            if float(t @ cmd) < -1e-12 * float(np.linalg.norm(cmd)):
                t = -t
        norm = float(np.linalg.norm(t))
        if norm < 1e-12:
            raise UsageError("slide: the commanded direction has no horizontal component")
        return self._run("slide", p0, t / norm, float(length), ref, press=-self.press * n)

    # internals ------------------------------------------------------------------------------
    @staticmethod
    def _unit(direction: Sequence[float]) -> FloatArray:
        u = np.asarray(direction, dtype=float)
        n = float(np.linalg.norm(u))
        if not math.isfinite(n) or n < 1e-12:
            raise UsageError(f"motion direction {tuple(direction)} is not a direction")
        return u / n

    def _read(self, data: Any) -> _Probe:
        fired = tuple(np.flatnonzero(data.sensordata > self.threshold).tolist())
        # Only the tip and the shaft collide (the object's parts are all fixed to the world).
        depth = -float(data.contact.dist.min()) if data.ncon else -math.inf
        return _Probe(fired=fired, penetration=depth)

    def _contacts(self, data: Any) -> list[_Contact]:
        """The tip's contacts within its margin, normals from the object towards the tip."""
        contacts = []
        for k in range(int(data.ncon)):
            c = data.contact[k]
            if c.geom1 == self._tip:
                other, sign = int(c.geom2), -1.0
            elif c.geom2 == self._tip:
                other, sign = int(c.geom1), 1.0
            else:
                continue
            if c.dist >= self._margin:
                continue
            n = sign * np.array(c.frame[:3], dtype=float)
            contacts.append(_Contact(geom=other, dist=float(c.dist), normal=n))
        return contacts

    def _q(self, p: FloatArray) -> FloatArray:
        """The joint vector with the tip centre at ``p`` and the head at its pose."""
        return np.concatenate([p, self._q_head]) if self._head else p

    def _probe(self, p: FloatArray) -> _Probe:
        d = self._probe_data
        q = self._q(p)
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.ctrl[:] = q
        mujoco.mj_forward(self.model, d)
        self._stats.probes += 1
        return self._read(d)

    def _shaft_penetration(self, p: FloatArray) -> float:
        """How deep the shaft is in the object or the table with the tip centre at ``p``
        (≤ 0 or ``-inf``: not at all), metres."""
        if self._shaft < 0:
            return -math.inf
        self._probe(p)
        d = self._probe_data
        depth = -math.inf
        for k in range(int(d.ncon)):
            c = d.contact[k]
            if self._shaft in (int(c.geom1), int(c.geom2)):
                depth = max(depth, -float(c.dist))
        return depth

    def _turn_head(self, p: FloatArray, q_from: FloatArray) -> FloatArray:
        """Simulate the head's motors turning it from angles ``q_from`` to this world's pose,
        the tip held at ``p`` and contacts off; the finger frame reached, 3×3."""
        goal = self._q_head.copy()
        start = q_from.copy()
        # the turn goes the short way round (the hinge is unlimited)
        goal[0] = start[0] + math.remainder(float(goal[0] - start[0]), 2.0 * math.pi)
        d = self.data
        q = np.concatenate([p, start])
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        d.ctrl[:] = q
        dt = float(self.model.opt.timestep)
        span = float(np.abs(goal - start).max())
        ramp = max(1, math.ceil(span / (self.head_speed * dt)))
        flags = int(self.model.opt.disableflags)
        self.model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        try:
            for step in range(ramp + 2000):
                f = min(1.0, (step + 1) / ramp)
                d.ctrl[3:] = start + f * (goal - start)  # Mturn, Mtilt follow Mx, My, Mz
                mujoco.mj_step(self.model, d)
                self._stats.index_steps += 1
                self._stats.index_time += dt
                qh = np.asarray(d.qpos[self._hinges], dtype=float)
                vh = np.asarray(d.qvel[self._hinge_dofs], dtype=float)
                if f >= 1.0 and (
                    float(np.abs(qh - goal).max()) < HEAD_TOL_RAD
                    and float(np.abs(vh).max()) < HEAD_TOL_RAD
                ):
                    break
            mujoco.mj_kinematics(self.model, d)
        finally:
            self.model.opt.disableflags = flags
        self._stats.indexes += 1
        reached = self.head_rotation()
        self._place(p)  # the head locks at its index
        mujoco.mj_kinematics(self.model, d)
        return reached

    def _surface_of(self, sensor: int) -> _Contact | None:
        """The contact (at the last probe) whose direction lies in ``sensor``'s cone."""
        best: _Contact | None = None
        best_cos = -2.0
        cos_cone = self._finger.cos_cone
        for c in self._contacts(self._probe_data):
            cos = float(-c.normal @ self._dirs[sensor])
            if cos >= cos_cone - 1e-12 and cos > best_cos:
                best, best_cos = c, cos
        return best

    def _snap(self, contact: _Contact) -> FloatArray:
        """The contact's normal, snapped to the exact normal of the part's face it lies on.

        MuJoCo's normals of mesh contacts carry errors up to ~1e-4 rad inside the margin; the
        hull's face normals are exact, and a slide must run parallel to the face.
        """
        normals = self._face_normals.get(contact.geom)
        if normals is None or len(normals) == 0:
            return contact.normal
        cos = normals @ contact.normal
        j = int(np.argmax(cos))
        return normals[j] if cos[j] >= _SNAP_COS else contact.normal

    def _event(self, ref: _Probe, probe: _Probe, *, physical: bool = False) -> bool:
        """Whether a motion must stop at ``probe``: the fired set differs from ``ref``'s, or
        (on the commanded line) the tip would penetrate the object by more than
        :data:`tactile_kb.touch.world.BLOCK_TOL`, as in the analytic world.

        ``physical`` samples (the finger where the dynamics put it) are pressed into the
        surface on purpose during a slide: only a change of the fired set counts for them.
        """
        if probe.fired != ref.fired:
            return True
        if physical:
            return False
        return probe.penetration > current().world.block_tol

    def _place(self, p: FloatArray) -> None:
        d = self.data
        q = self._q(p)
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        d.ctrl[:] = q

    def _run(
        self,
        kind: MotionKind,
        p0: FloatArray,
        u: FloatArray,
        length: float,
        ref: _Probe,
        *,
        press: FloatArray,
    ) -> Motion:
        if not math.isfinite(length) or length < 0:
            raise UsageError(f"{kind}: length {length} must be a finite number ≥ 0")
        room = self._workspace.room(_vec(p0), _vec(u))
        travel = max(0.0, min(length, room))
        self._place(p0)
        d = self.data
        dt = float(self.model.opt.timestep)
        ds = self.speed * dt
        lag = self.options.kv / self.options.kp * self.speed  # the ramp-following error
        # samples[i]: distance along the line of the finger's actual position before step i+1;
        # samples[known] is the last one where the commanded line shows no event.
        samples = [0.0]
        known = 0
        found = -1
        s_cmd = 0.0
        for step in range(int(travel / ds * 4) + 2000):
            if travel - samples[-1] <= self.settle:
                break
            s_cmd = min(travel, s_cmd + ds)
            d.ctrl[:3] = p0 + min(s_cmd + lag, travel) * u + press
            mujoco.mj_step(self.model, d)
            self._stats.steps += 1
            self._stats.sim_time += dt
            # After mj_step, sensordata and contacts describe the state before the step: the
            # sensors as the moving finger feels them at samples[-1].
            felt = self._read(d)
            samples.append(min(travel, max(samples[-1], float((np.asarray(d.qpos[:3]) - p0) @ u))))
            if self._event(ref, felt, physical=True):
                self._stats.physical_events += 1
                check = len(samples) - 2  # the finger felt a change: confirm on the line
            elif d.ncon or (step + 1) % self.check_every == 0:
                check = len(samples) - 1  # touching something, or a routine check
            else:
                continue
            if samples[check] <= samples[known]:
                continue
            if self._event(ref, self._probe(p0 + samples[check] * u)):
                found = check
                break
            known = check
        if found < 0:
            if samples[-1] < travel:
                samples.append(travel)  # the servo's last micrometres onto the end point
            if self._event(ref, self._probe(p0 + travel * u)):
                found = len(samples) - 1
            else:
                end = p0 + travel * u
                self._place(end)
                event: Event = "limit" if room < length else "none"
                return self._motion(kind, p0, u, end, event, ref, ref.fired)
        # The first sample after `known` showing the event on the line, then bisection.
        lo_i, hi_i = known, found
        while hi_i - lo_i > 1:
            k = (lo_i + hi_i) // 2
            if self._event(ref, self._probe(p0 + samples[k] * u)):
                hi_i = k
            else:
                lo_i = k
        lo, hi = samples[lo_i], samples[hi_i]
        while hi - lo > self.resolution:
            mid = 0.5 * (lo + hi)
            if self._event(ref, self._probe(p0 + mid * u)):
                hi = mid
            else:
                lo = mid
        end = p0 + hi * u
        final = self._probe(end)
        closed = set(final.fired) - set(ref.fired)
        opened = set(ref.fired) - set(final.fired)
        event = "touch" if closed else "release" if opened else "blocked"
        if event == "blocked" and hi <= 2.0 * self._margin:
            end = p0.copy()  # heading into a surface it already touches
        self._place(end)
        return self._motion(kind, p0, u, end, event, ref, final.fired)

    def _motion(
        self,
        kind: MotionKind,
        p0: FloatArray,
        u: FloatArray,
        end: FloatArray,
        event: Event,
        ref: _Probe,
        fired: tuple[int, ...],
    ) -> Motion:
        fired_start = ref.fired
        return Motion(
            kind=kind,
            start=_vec(p0),
            end=_vec(end),
            direction=_vec(u),
            distance=float(np.linalg.norm(end - p0)),
            event=event,
            fired_start=fired_start,
            fired=fired,
            closed=tuple(sorted(set(fired) - set(fired_start))),
            opened=tuple(sorted(set(fired_start) - set(fired))),
            measured=_vec(end),
        )
