"""The world a finger explores: the protocol every explorer's physics implements.

The servo logic (:mod:`tactile_kb.touch.servo`) never knows which world it drives. A world answers
two questions only: *what do the sensors read here?* (:meth:`World.sense`) and *where along
this straight move does that change?* (:meth:`World.move`, :meth:`World.slide`). The built-in
analytic world is :class:`tactile_kb.touch.stepper.StepperWorld`; the MuJoCo plugin implements the
same protocol on top of a physics engine.

Conventions (every world follows them; the contract suite in :mod:`tactile_kb.testing` and
the controller rely on them):

* Units are metres; the table is the plane z = 0 and the object rests on it (z ≥ 0).
* A *position* is the centre of the finger's spherical tip of radius ``finger.radius``.
* Sensor ``i`` fires when the direction from the tip centre to a contact point lies inside
  its acceptance cone (:meth:`tactile_kb.touch.finger.Finger.fired`); a contact is a point of the
  object at distance ρ (within :data:`CONTACT_TOL`) from the tip centre.
* Worlds are stateless with respect to the finger's position: every motion names its
  ``start``. The controller always passes either the ``end`` of the previous motion or a
  position in free space (a physical world may teleport the finger there, or refuse with
  :class:`~tactile_kb.errors.ExplorationError`). Randomness (noise, drop-outs) comes from the
  world's own seeded generator, so a world built with the same seed answers the same
  sequence of calls identically.
* A motion never penetrates the object: a straight :meth:`~World.move` stops where the tip
  first meets it, and a :meth:`~World.slide` stays pressed on the surface it follows.

A motion ends at the *first* of these, reported as :attr:`Motion.event`:

``"touch"``
    at least one sensor closed (OFF→ON) relative to the fired set at ``start``
    (:attr:`Motion.closed` lists them; some may have opened at the same point too);
``"release"``
    sensors opened (ON→OFF) and none closed (:attr:`Motion.opened` lists them);
``"blocked"``
    the tip met the object (or, in a slide, a second surface) but the fired set did not
    change: a *blind* contact, in a direction no sensor covers, or where the same sensors
    stay ON; the finger stops there;
``"limit"``
    the next step would leave the :attr:`World.workspace` box (whose floor keeps the tip
    above the table);
``"none"``
    the whole ``length`` was travelled without any change.

Examples
--------
>>> ws = Workspace(lo=(-0.2, -0.2, 0.005), hi=(0.2, 0.2, 0.4))
>>> ws.contains((0.0, 0.0, 0.1))
True
>>> round(ws.room((0.0, 0.0, 0.1), (1.0, 0.0, 0.0)), 6)
0.2
>>> round(ws.room((0.0, 0.0, 0.1), (0.0, 0.0, -1.0)), 6)
0.095
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol, runtime_checkable

import numpy as np

from tactile_kb.settings import DEFAULTS
from tactile_kb.touch.finger import Finger, Orientation
from tactile_kb.types import FloatArray, Vec3

__all__ = [
    "BLOCK_TOL",
    "CONTACT_TOL",
    "Box",
    "Event",
    "Motion",
    "MotionKind",
    "OrientableWorld",
    "Vec3",
    "Workspace",
    "World",
    "default_workspace",
]


Event = Literal["touch", "release", "blocked", "limit", "none"]
"""How a motion ended (see the module docstring)."""

MotionKind = Literal["move", "slide"]

CONTACT_TOL = DEFAULTS.world.contact_tol
"""Metres: the tip touches the object when its centre is within ρ + CONTACT_TOL of it."""

BLOCK_TOL = DEFAULTS.world.block_tol
"""Metres: a world blocks the tip where its distance to the object would drop below
ρ − BLOCK_TOL."""


@dataclass(frozen=True)
class Box:
    """An axis-aligned box ``lo ≤ x ≤ hi`` (metres)."""

    lo: Vec3
    hi: Vec3

    @property
    def centre(self) -> Vec3:
        """The middle of the box."""
        return (
            0.5 * (self.lo[0] + self.hi[0]),
            0.5 * (self.lo[1] + self.hi[1]),
            0.5 * (self.lo[2] + self.hi[2]),
        )

    @property
    def size(self) -> Vec3:
        """Edge lengths along x, y, z."""
        return (self.hi[0] - self.lo[0], self.hi[1] - self.lo[1], self.hi[2] - self.lo[2])

    def contains(self, point: Sequence[float], margin: float = 0.0) -> bool:
        """Whether ``point`` lies inside the box shrunk by ``margin`` on every side."""
        return all(
            self.lo[k] + margin - 1e-12 <= point[k] <= self.hi[k] - margin + 1e-12 for k in range(3)
        )

    def room(self, start: Sequence[float], direction: Sequence[float]) -> float:
        """How far one can go from ``start`` along unit ``direction`` and stay inside the box.

        0 when ``start`` is outside (or on the boundary heading out).
        """
        if not self.contains(start):
            return 0.0
        t = math.inf
        for k in range(3):
            d = direction[k]
            if d > 1e-15:
                t = min(t, (self.hi[k] - start[k]) / d)
            elif d < -1e-15:
                t = min(t, (self.lo[k] - start[k]) / d)
        return max(0.0, t)


class Workspace(Box):
    """Where the tip centre may go. Its floor (``lo[2]``) is at least ρ: the tip never
    enters the table."""


@dataclass(frozen=True)
class Motion:
    """The result of one straight motion (a :meth:`World.move` or a :meth:`World.slide`).

    Attributes
    ----------
    kind
        ``"move"`` (rigid straight line) or ``"slide"`` (compliant, pressed on a surface).
    start, end
        Tip-centre positions where the motion started and where it stopped (true positions:
        the next motion starts from ``end``).
    direction
        The unit direction actually travelled. For a move it is the commanded one; for a
        slide, the horizontal tangent of the followed surface in the commanded sense.
    distance
        Length travelled, ``|end − start|``.
    event
        Why the motion stopped (``"touch"``, ``"release"``, ``"blocked"``, ``"limit"`` or
        ``"none"``; see the module docstring).
    fired_start, fired
        Sensors ON (as reported) at ``start`` and at ``end``, sorted.
    closed, opened
        Sensors that went OFF→ON and ON→OFF between ``start`` and ``end``, sorted.
    measured
        ``end`` as the position encoders report it (the world's contact-position noise added);
        this is what an exploration record stores.
    """

    kind: MotionKind
    start: Vec3
    end: Vec3
    direction: Vec3
    distance: float
    event: Event
    fired_start: tuple[int, ...]
    fired: tuple[int, ...]
    closed: tuple[int, ...]
    opened: tuple[int, ...]
    measured: Vec3

    @property
    def touched(self) -> bool:
        """Whether a sensor closed during the motion."""
        return self.event == "touch"


@runtime_checkable
class World(Protocol):
    """What an exploration controller needs from the world the finger moves in.

    Attributes
    ----------
    finger
        The finger layout (tip radius, sensor directions, cones) the world senses with.
    workspace
        Where the tip centre may go (the motors' range); its floor keeps the tip above the
        table.
    hint
        A rough box around the object: the visual estimate the paper assumes before the
        first touch ("before direct contact ... decision is based only on the optical
        information"). Controllers aim their first approach and bound their sweeps with it;
        it need not be tight.
    """

    @property
    def finger(self) -> Finger: ...

    @property
    def workspace(self) -> Workspace: ...

    @property
    def hint(self) -> Box: ...

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        """Sensors ON (sorted indices) with the tip centre at ``centre``.

        ``centre`` must not be inside the object by more than :data:`CONTACT_TOL`.
        """
        ...

    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        """Move the tip rigidly from ``start`` along unit ``direction`` for up to ``length``.

        Stops at the first change of the fired set (``"touch"``/``"release"``), where the tip
        meets the object without a change (``"blocked"``), at the workspace boundary
        (``"limit"``), or after ``length`` (``"none"``). Starting in contact and heading
        into the surface gives ``"blocked"`` at distance 0; heading away gives ``"release"``
        at the point where the contact is lost.
        """
        ...

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        """Follow the surface touched by ``sensor``, pressed on it (compliant motion).

        The tip must be in contact at ``start`` with a surface whose contact direction lies in
        ``sensor``'s cone. It moves along the horizontal line tangent to that surface (z
        constant) in the sense of the commanded horizontal ``direction`` (for a horizontal
        surface, along ``direction`` itself), for up to ``length``, staying at distance ρ
        from the surface's plane. It stops at the first change of the fired set: a
        ``"release"`` where the surface ends at a convex edge, a ``"touch"`` where another
        surface is met (a concave corner), ``"blocked"`` when another surface stops it
        without a change, ``"limit"`` or ``"none"``. Not in contact at ``start`` → a
        ``"release"`` of ``sensor`` at distance 0.

        A world may be compliant, as a finger under force control is: the analytic world rides
        over irregularities smaller than the tip (:meth:`StepperWorld._comply
        <tactile_kb.touch.stepper.StepperWorld._comply>`, the setting ``world.comply_deg``);
        its ``distance`` is then the length of the path and its ``direction`` the last one
        travelled.
        """
        ...


@runtime_checkable
class OrientableWorld(World, Protocol):
    """A world whose finger has an indexing head (:class:`~tactile_kb.touch.finger.Wrist`).

    The head's pose is part of the world's value, like its finger: :meth:`oriented` returns the
    same world with the head at another pose (sharing the object and, for a physical world,
    the simulation), so the motions keep their signatures. In every pose the sensors answer in
    the world frame (a sensor's direction is ``orientation.rotation @ d`` for its direction ``d``
    in the finger frame), and the finger's shaft collides with the object: a motion the shaft
    would make enter the object stops ``"blocked"``.
    """

    @property
    def orientation(self) -> Orientation: ...

    def oriented(self, orientation: Orientation, at: Vec3 | None = None) -> OrientableWorld:
        """This world with the head at ``orientation``. With ``at`` (the tip centre where the
        head turns), a pose that collides there raises
        :class:`~tactile_kb.errors.ExplorationError` with a one-line message."""
        ...


def default_workspace(bounds: FloatArray, radius: float) -> Workspace:
    """A workspace around an object's ``bounds`` (2, 3): its size plus 0.15 m each side, floor ρ."""
    lo, hi = np.asarray(bounds[0], float), np.asarray(bounds[1], float)
    pad = 0.15
    return Workspace(
        lo=(float(lo[0] - pad), float(lo[1] - pad), float(radius)),
        hi=(float(hi[0] + pad), float(hi[1] + pad), float(hi[2] + pad)),
    )
