"""The servo logic of the exploring finger (the paper's "Tactile Exploration", Fig. 1 and Fig. 2).

:class:`Controller` decides every motion from the sensors alone and drives any
:class:`~tactile_kb.touch.world.World`; it never knows which world it is in. The rules:

* **Contour following.** While a sensor is ON the finger moves along the plane tangential at
  the contact, parallel to x–y, in the sense associated with that sensor (the object on the
  left, i.e. counter-clockwise seen from above: the direction ẑ × n for the outward normal
  n = −r0). The motion is a compliant :meth:`~tactile_kb.touch.world.World.slide`.
* **Block E, gate 1 (block N).** A sensor passing OFF→ON inhibits the commands of every other
  ON sensor: the finger follows the *last sensor that closed*. A sensor of another surface
  opening meanwhile does not interrupt the slide.
* **The search cycle** (monostables M1, M2, M3). On ON→OFF of the followed sensor the finger
  continues ``l1`` in the previous direction, then searches ``l2`` orthogonally towards the
  object, then ``l3`` orthogonally to ``l2`` (back). A contact during the cycle stops it
  (gates 1–3) and is followed. Blocks C and D: the end of ``l2`` or ``l3`` never starts a new
  cycle. If the cycle ends without contact, the object has at least one dimension smaller
  than ``l2``: the layer ends with that note.
* **z increments.** When the first surface of a layer is touched a second time, the finger
  slides on to where the layer began and moves up by ``z_step`` to explore the new plane
  z = const. The increments end when contact is no longer kept after one — unless a short
  horizontal search towards the middle of the layer regains it (a face sloping inwards, as on
  a pyramid, loses contact on every step). A face overhanging the finger stops it going up:
  it steps away from the face, goes up, and searches back. In the last plane (the next one
  would be over the top) the contour is closed without touching the first surface again:
  when the surface before it ends where the layer began. With ``comply``, a touch closes a
  layer only once its tip centres have turned :data:`HALF_DEG` round the object, and a
  contour that no touch closed although it went round once more (:data:`ROUND_DEG`: on a
  cylinder's facets every loss of contact is found again beyond a dent, a slide contact) is
  closed where it passes its first surface's start, before its motion budget runs out.
* **Persistence (``comply``).** A finger under force control rides over a scan's bumps and
  ripples (back off, step on, press back); a slide still blocked without a sensor change
  backs off, steps on and searches back as the cycle does, and re-acquires the surface
  (setting ``servo.persist_tries`` > 0): then it is never the end of the exploration, only
  the layer's motion budget is. A motion blocked where no sensor fires (a bump met above the
  sensors' cones) is tried again higher, within a tip radius of the layer
  (``servo.blind_rise``, :meth:`Controller._over_blind`).
* **Edges are not surfaces.** A touch whose slide rolls off at once (within ``edge_slide``)
  touched an edge or a vertex; its contact is dropped from the record, unless such touches
  come three or more in a row (a curved surface is all edges to a sliding tip). A layer
  narrower than the tip (round an apex) is dropped whole.
* **Other planes.** "Exploration can eventually continue in different planes": a surface
  that only one layer slid along (narrow there, or skipped by a search cycle) is touched once
  more at another height, approached along its normal from outside the object (``probe``),
  so that every face has tip centres at two heights; and tops, which contouring in
  horizontal planes cannot touch, are explored from above: a vertical approach over the
  middle of the last contour, then slides round a diamond on its principal axes. A touch
  from above that cannot slide (an apex or an edge) is noted and not recorded as a plane.
  On a scan's rough top (the contours rode over irregularities, :data:`ROUGH_RIDES`),
  where the sensors that close are turned by the roughness, the tip
  seats itself (lifts, steps on a little, presses down until the sensor pointing down
  closes) and follows that sensor, and seats itself again where a slide ends early.

Contacts: a ``"touch"`` contact on every OFF→ON of the followed sensor and ``"slide"``
contacts every ``spacing`` along each tangential move and at its end (many tip centres per
face without more touches, so that face normals can be fitted through them and the position
noise averages out). ``r0`` is the followed sensor's direction or, when neighbouring sensors
with overlapping cones closed together with it, the normalised mean of their directions.

Examples
--------
>>> p = ServoParams()
>>> p.l1, p.l2, p.l3
(0.008, 0.01, 0.016)
"""

from __future__ import annotations

import itertools
import math
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Literal, Protocol, overload

import numpy as np

from tactile_kb.errors import ExplorationError, UsageError
from tactile_kb.record import Contact, ExplorationRecord, Layer
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.touch.finger import VERTICAL, Orientation
from tactile_kb.touch.watch import current_watcher
from tactile_kb.touch.world import Motion, OrientableWorld, Vec3, World
from tactile_kb.types import FloatArray

__all__ = ["RETRACE_POINTS", "Completer", "Controller", "Ending", "Mark", "Probe", "ServoParams"]

Mark = Literal["contact", "layer", "complete"]
"""What :meth:`Controller.run` yields: the first touch, a finished layer, the end."""


_Z = np.array([0.0, 0.0, 1.0])

CURVED_RUN = DEFAULTS.servo.curved_run
"""Edge touches in a row (each rolling off within ``edge_slide``) that mean a curved surface."""

RIDE_STEP = DEFAULTS.servo.ride_step
"""How far (in tip radii) a ride over an irregularity steps on before pressing back: far enough
that the press, ``bump`` deeper than the surface, misses a real convex edge (√(2ρb − b²) for a
right angle and a bump b ≤ ρ / 4: 0.66 ρ)."""

RIDE_DEG = DEFAULTS.servo.ride_deg
"""Degrees: a touch while riding over an irregularity (:meth:`Controller._ride`) whose sensors
point this close to the surface's normal is the surface followed (a real face turns further at
an edge: 30° and more between the faces of a 12-sided prism)."""


RIPPLE_DEG = DEFAULTS.servo.ripple_deg
"""Degrees: a sensor closing during a slide while the followed one stays ON is a neighbour of
it (the 33-sensor finger's neighbours lie 30° apart) when within this angle."""

PERSIST_TRIES = DEFAULTS.servo.persist_tries
"""How often a blocked slide's re-acquisition (:meth:`Controller._persist`) backs off and steps
on, each time twice as far (0.8, 1.6, 3.2 tip radii), before the contour ends."""


ROUND_DEG = 360.0 + 345.0
"""Degrees: a layer's contour whose tip centres have turned this far round the object
(counter-clockwise, :class:`_Turning`), once round and nearly once more, without a touch on its
first surface closing it, is closed where it passes that surface's start
(:meth:`Controller._gone_round`). On a cylinder's or a sphere's facets every loss of contact is
found again beyond a dent (a slide contact), so the paper's closing touch never comes and the
contour went round until the layer's motion budget ran out (four times round a 64-sided
cylinder). A contour the paper's touch closes within that is left as it was."""

HALF_DEG = 180.0
"""Degrees: a layer's contour is closed by a touch on a surface it already followed
(:meth:`Controller._on_first`, :meth:`Controller._back_on`) only once its tip centres have
turned this far round the object. A simple closed contour turns 360° in all, and by the time
it meets its first surface again at least 360° less its last corner's turn (240° round a
triangle); on a rough side a touch a few millimetres from the layer's start, before the contour
went anywhere, is a bump of the first surface, not the contour come round."""

UNDER_LOOKS = 2
"""How many rims of one side face, per layer, :meth:`Controller._under_edge` looks under (a rough
scan's face rides over dozens of dents)."""

UNDER_DEPTH = 3.0
"""How much deeper than a slide ran (in :attr:`Controller.bump`) the face it followed may lie one
tip radius lower (a dent, or a face sloped by up to 15°) before an opening under the edge is
looked for (:meth:`Controller._under_edge`)."""


def _through_releases(
    move: Callable[[FloatArray, FloatArray, float], Motion],
    pos: FloatArray,
    direction: FloatArray,
    length: float,
) -> tuple[Motion, float]:
    """``move`` ``length`` along ``direction`` from ``pos``, on through losses of contact; the
    last motion and the distance gone."""
    done = 0.0
    while True:
        m = move(pos, direction, length - done)
        done += m.distance
        pos = np.asarray(m.end, dtype=float)
        if m.event != "release" or done >= length - 1e-9 or m.distance <= 0.0:
            return m, done


TOP_UNDER_DEG = 70.0
"""A layer's touch whose followed direction points more than this below the equator met a top
just under the tip's centre, not a side (see :meth:`Controller._top_met`)."""

TOP_NEAR_RHO = 1.5
"""A layer whose tip centre would lie within this many tip radii under the hint's top may run
over the object's top: the top is touched first (:meth:`Controller._under_touched_top`)."""

TOP_CLEAR_RHO = 0.5
"""A layer placed under a top touched first runs this many tip radii under it: below the
top's rounded edge (up to a tenth of a 1.5 cm side) and its bumps (at 0.3 ρ the contour of a
scanned phone's second layer was blocked there)."""

UNDER_TOP_RHO = 0.5
"""A layer lowered under a top it met runs this many tip radii below that top."""

RETRACE_POINTS = 64
"""How many of the tip's last positions the way back from under an overhang may run through
(see :meth:`Controller._retrace_up`)."""


@dataclass(frozen=True)
class ServoParams:
    """Lengths and switches of the servo logic (metres), scaled to objects of 2–30 cm.

    Attributes
    ----------
    l1
        Continue this far past a loss of contact (longer than ρ, so the tip clears the edge).
    l2
        Search this far orthogonally towards the object (longer than ρ and shorter than the
        smallest object dimension: an object thinner than ``l2`` ends the contour).
    l3
        Search this far orthogonally to ``l2``, back (at least ``l1``).
    z_step
        The fixed z increment between layers; ``None``: 0.35 × the height of the world's
        visual hint (two layers on most objects: at 0.35 and 0.7 of it).
    z_first
        Height of the first layer (tip centre); ``None``: 0.35 × the hint's height, at least
        ρ + 1 mm (high enough that a sphere's surface there overhangs by less than the 20°
        the 33-sensor finger can feel).
    spacing
        A ``"slide"`` contact is recorded every ``spacing`` along a slide (more tip centres
        per face without more touches, so that fitted face normals average the position
        noise out); ``None``: a thirtieth of the hint's horizontal diagonal, at least 1.5 mm.
    edge_slide
        A touch whose slide loses the contact (or rolls onto a neighbouring sensor) within
        this distance touched an edge or a vertex, not a surface: it is dropped from the
        record; ``None``: ρ / 2.
    probe
        After the layers, touch again every surface that only one layer slid along (narrow
        there, or skipped by a search cycle), at a height between that layer and the nearest
        other one: one touch each, so that every face has tip centres at two heights and its
        normal can be fitted.
    top
        Explore tops from above after the layers.
    top_spread
        The slides on a top reach this fraction of the last contour's half-widths from its
        middle (a rectangle of slides, so that the top's tip centres span it).
    top_outer
        After that diamond, a second one reaches this fraction of the way from the middle to
        the contour's tip centres less ρ, along the same axes: a box's top is as wide as its
        contour, and tip centres spread over most of it fit its plane several times as
        exactly. Its slides are kept only when it closes without riding over anything: one
        that leaves the top (a frustum's smaller one) or rides where the top turns away
        from the followed sensor (a lying cylinder's ridge) drops them all. ``None``: one
        diamond, as before.
    approach_margin
        Free space kept outside the hint box when approaching.
    comply
        Ride over small irregularities of a surface slid along, as a finger under force
        control does (see :meth:`Controller._ride`): a slide stopped without a sensor change
        backs off, steps over and presses on again; a slide that loses the surface presses
        back onto it. A slide still blocked re-acquires the surface as the search cycle does
        when the setting ``servo.persist_tries`` is > 0 (:meth:`Controller._persist`); a
        neighbouring sensor closing while the followed one stays ON is a ripple of the same
        surface (:meth:`Controller._ripple`). On side faces the finger also looks for
        openings the layers pass by: under the rim a ride over a receding surface came back on
        (:meth:`Controller._under_edge`), and between two layers, rising once along each face
        (:meth:`Controller._rise`). Off: the paper's rules alone (a blocked slide ends the
        contour).
    reapproach
        A contour that a slide blocked without a sensor change ended (something the tip met
        where no sensor faces it: a wall rising from the edge it slid along, or a scan's bump
        too high to ride over) does not end the layers: the plane one ``z_step`` up is found
        by a new approach, as after a contact lost below the top. Off: the paper's rule (an
        open contour ends the layers).
    bump
        The largest irregularity (bump, ripple, relief) ridden over, metres; ``None``:
        ρ / 4 (1.25 mm for the 5 mm tip).
    max_motions
        Hard budget of motions for a whole exploration.
    max_layer_motions
        Budget of motions for one contour.
    max_layers
        At most this many layers.
    """

    l1: float = 0.008
    l2: float = 0.010
    l3: float = 0.016
    z_step: float | None = None
    z_first: float | None = None
    spacing: float | None = None
    edge_slide: float | None = None
    probe: bool = True
    top: bool = True
    top_spread: float = 0.45
    top_outer: float | None = 0.85
    approach_margin: float = 0.01
    comply: bool = True
    reapproach: bool = True
    bump: float | None = None
    max_motions: int = 6000
    max_layer_motions: int = 1000
    max_layers: int = 40

    def __post_init__(self) -> None:
        for name in ("l1", "l2", "l3", "approach_margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise UsageError(f"servo parameter {name} must be > 0 metres, got {v}")
        for name in ("z_step", "z_first", "spacing", "edge_slide", "bump"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise UsageError(f"servo parameter {name} must be > 0 metres or None, got {v}")
        if not (math.isfinite(self.top_spread) and 0.0 < self.top_spread < 1.0):
            raise UsageError(
                f"servo parameter top_spread must lie in (0, 1), got {self.top_spread}"
            )
        if self.top_outer is not None and not (
            math.isfinite(self.top_outer) and self.top_spread < self.top_outer < 1.0
        ):
            raise UsageError(
                f"servo parameter top_outer must lie in (top_spread, 1) or be None, got "
                f"{self.top_outer}"
            )
        for name in ("max_motions", "max_layer_motions", "max_layers"):
            if getattr(self, name) < 1:
                raise UsageError(f"servo parameter {name} must be ≥ 1")


class _Budget(Exception):
    pass


@dataclass(frozen=True)
class Probe:
    """A touch asked for from above the controller (plain values, no geometry in the servo).

    The finger goes round the object (up over the hint box, across, down) to a point
    ``target + normal × (reach + clearance)`` outside it and approaches along ``−normal``
    until a sensor closes, then slides a little along the surface it touched. A ``target``
    so far outside the hint box that this point lies outside the workspace is approached
    from where the line through it along ``normal`` leaves the hint box (plus the clearance):
    the object lies inside the box.

    Attributes
    ----------
    target
        Where the surface is expected (metres; the tip centre's goal, offset by ρ already).
    normal
        Unit outward direction to approach from.
    reach
        How far beyond ``target`` the approach may go looking for the surface (metres).
    reason
        What the probe is for, e.g. ``"open towards +y"`` (for the record's notes).
    """

    target: Vec3
    normal: Vec3
    reach: float
    reason: str
    middle: bool = False
    """Aim at the middle of the hint box (the visual estimate of where the object is) rather
    than at ``target``'s horizontal position: for a side never touched, where the touched
    points say little about where the object's middle is."""
    facing: Vec3 | None = None
    """Where the tip should point during the approach (the head indexed to the pose whose pole
    is nearest, :meth:`~tactile_kb.touch.finger.Finger.index_towards`), for a probe that may
    meet a surface of unknown slope; ``None``: the pose that faces ``normal``."""


@dataclass(frozen=True)
class Ending:
    """How a model-driven completion ended: ``"closed"`` (the envelope is closed and every face
    has tip centres at two heights, or every tip centre lies on one sphere), ``"budget"``
    (touches or path ran out) or ``"unreachable"`` (what stayed open cannot be reached);
    ``message`` says it in one line, ``unreachable`` names what stayed open, and ``budget``
    (with ``"budget"``) says which budget ran out and its size, as a subject: "the
    completion's budget of 24 touches", "the motion budget of 6000 motions"."""

    status: Literal["closed", "budget", "unreachable"]
    message: str
    unreachable: tuple[str, ...] = ()
    budget: str = ""


class Completer(Protocol):
    """What drives the completion after contour following (see :mod:`tactile_kb.completion`):
    given the record so far and the outcome of the previous probe (None at the start), the next
    :class:`Probe`, or the :class:`Ending`.

    A completer may also have ``still_open(record) -> tuple[str, ...]``, what holds it open
    after ``record``: when the motion budget (``ServoParams.max_motions``) ends the exploration
    first, the ending names those items (without it: ``unknown (…)``)."""

    def next_probe(
        self, record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe | Ending: ...


@dataclass
class _Follow:
    """The contact being followed: the sensor, the sensors that closed with it, r0."""

    sensor: int
    group: tuple[int, ...]
    r0: FloatArray = field(default_factory=lambda: np.zeros(3))


def _v3(a: Sequence[float] | FloatArray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def _unit(v: FloatArray) -> FloatArray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-12 else v


class Controller:
    """The exploration controller for one object in one :class:`~tactile_kb.touch.world.World`.

    Parameters
    ----------
    world
        The world to explore (any implementation of the protocol).
    params
        The servo parameters.
    explorer, object_name, seed, noise, extra_params
        Copied into the record (``noise``: σ of the encoder noise of the world's sensors).
    completer
        Drives the completion after the layers, the probes and the tops: probes asked for by
        a model of what was touched (:mod:`tactile_kb.completion`) until it says the model is
        closed or the budget is spent. None: no completion (the paper's exploration alone).
    """

    def __init__(
        self,
        world: World,
        params: ServoParams | None = None,
        *,
        explorer: str = "",
        object_name: str = "",
        seed: int | None = None,
        noise: float = 0.0,
        extra_params: dict[str, float] | None = None,
        completer: Completer | None = None,
    ) -> None:
        self.world = world
        self.completer = completer
        self.ending: Ending | None = None
        self.params = params or ServoParams()
        self.explorer = explorer
        self.object_name = object_name
        self.seed = seed
        self.noise = float(noise)
        self.extra_params = dict(extra_params or {})
        self.finger = world.finger
        self.rho = float(self.finger.radius)
        self.orientation = VERTICAL
        if isinstance(world, OrientableWorld):
            self.orientation = world.orientation
        self._dirs = self.finger.directions_at(self.orientation)
        self.orientations: list[tuple[int, float, float]] = []
        self.blind: list[tuple[Vec3, Vec3]] = []  # (tip centre, motion direction), no sensor
        self.indexes = 0  # head indexings
        hint = world.hint
        height = max(float(hint.hi[2]), 2.0 * self.rho)
        self.z_step = self.params.z_step or max(0.35 * height, 0.5 * self.rho)
        self.z_first = self.params.z_first or max(0.35 * height, self.rho + 0.001)
        size = hint.size
        self.spacing = self.params.spacing or max(0.0015, math.hypot(size[0], size[1]) / 30.0)
        self.edge_slide = self.params.edge_slide or 0.5 * self.rho
        self.bump = self.params.bump or 0.25 * self.rho
        self.reach = float(
            math.hypot(size[0], size[1]) + 2 * (self.rho + self.params.approach_margin)
        )
        self.contacts: list[Contact] = []
        self.path: list[Vec3] = []
        self.layers: list[Layer] = []
        self.notes: list[str] = []
        self.motions = 0
        self.rereads = 0  # touches recovered by reading the sensors again at rest
        self.rides = 0  # irregularities ridden over while sliding
        self.persisted = 0  # blocked slides after which the surface was re-acquired
        self.ripples = 0  # sensors closing during a slide on the same surface, turned a little
        self.dents = 0  # search cycles that found the same face again beyond a dent
        self.openings = 0  # openings found in side faces (under a rim, or between layers)
        self._looking_under = False
        self._risen: list[FloatArray] = []  # followed directions risen along in this layer
        self._looked: list[FloatArray] = []  # faces looked under (their press), this layer
        self._next_z: float | None = None  # the height of the next layer, if one is planned
        self._layer_z: float | None = None  # the height of the layer being contoured
        self._turning: _Turning | None = None  # how far the layer's contour has turned
        self._top_under: float | None = None  # a top met just under the layer (its height)
        self._lowered = False  # a layer was lowered under a top once
        self._top_touched = False  # the top was touched before the last layer
        self._layer_motions = 0
        self._blocked_end = False  # the current contour ended at a blocked slide
        self._phase = "first-contact"
        self._layer: int | None = None
        self._last_pos: Vec3 | None = None
        self._last_move: Motion | None = None
        self._approach = -_Z  # the direction of the last probe's approach
        # where the tip centre truly went (the robot's own way), as far back as a retrace runs
        self._trail: deque[Vec3] = deque(maxlen=RETRACE_POINTS)
        self._surfaces: list[tuple[float, _Segment]] = []  # (layer z, surface slid along)
        self._heights: list[float] = []  # the z of every layer

    # bookkeeping -----------------------------------------------------------------------------
    def _note(self, text: str) -> None:
        if text not in self.notes:
            self.notes.append(text)

    def _track(self, m: Motion) -> Motion:
        if m.event in ("touch", "blocked"):
            m = self._reread(m)
        if (
            m.event == "blocked"
            and m.kind == "move"
            and not m.fired
            and m.distance > 0.0
            and not self._looking_under  # a look into an opening that is not there: no news
        ):
            self.blind.append((m.measured, m.direction))
        self.motions += 1
        self._layer_motions += 1
        if self._last_pos is None or m.start != self._last_pos:
            self.path.append(m.start)
        self.path.append(m.measured)
        for point in (m.start, m.end):
            if not self._trail or point != self._trail[-1]:
                self._trail.append(point)
        self._last_pos = m.end
        self._last_move = m
        watcher = current_watcher()
        if watcher is not None:
            watcher(self._phase, self.touches, self.motions)
        if self.motions >= self.params.max_motions:
            raise _Budget(f"motion budget of {self.params.max_motions} exhausted")
        return m

    def _reread(self, m: Motion) -> Motion:
        """Read the sensors again where a motion stopped at a touch or blocked.

        A sensor's closing signal can be lost at the event (a drop-out): the finger stops
        pressed, blind, or follows only part of the sensors that closed together (a biased r0).
        At rest the sensors are read again and every one that is ON now and was not at the
        start joins the sensors that closed.
        """
        now = set(self.world.sense(m.end))
        closed = now - set(m.fired_start)
        if closed <= set(m.closed):
            return m
        self.rereads += 1
        return replace(
            m,
            event="touch",
            fired=tuple(sorted(now | set(m.fired))),
            closed=tuple(sorted(closed | set(m.closed))),
        )

    def _move(
        self, start: FloatArray | Vec3, direction: FloatArray | Vec3, length: float
    ) -> Motion:
        return self._track(self.world.move(_v3(start), _v3(direction), float(length)))

    def _slide(
        self, start: FloatArray | Vec3, direction: FloatArray, length: float, sensor: int
    ) -> Motion:
        m = self._track(self.world.slide(_v3(start), _v3(direction), float(length), sensor))
        self._check_alignment(direction, m, sensor)
        return m

    def _check_alignment(self, command: FloatArray, m: Motion, sensor: int) -> None:
        """Stop when a surface slid along is turned further from its sensor than the finger's
        ``align_deg``: the slide went along the surface, not where the sensor said it would."""
        limit = self.finger.align_deg
        if limit is None or m.distance < 0.2 * self.rho:  # an edge rolls off at once
            return
        a = np.array([command[0], command[1], 0.0])
        b = np.array([m.direction[0], m.direction[1], 0.0])
        na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
        if na < 1e-9 or nb < 1e-9:
            return
        turn = math.degrees(math.acos(min(1.0, abs(float(a @ b)) / (na * nb))))
        if turn > limit:
            text = (
                f"the surface at {_fmt(m.start)} is turned {turn:.0f}° from sensor {sensor} of "
                f"finger {self.finger.name!r} (at most {limit:g}° expected): this finger explores "
                "objects whose faces face its sensors; turn the object or use finger '33'"
            )
            self._note(text)
            raise ExplorationError(text)

    def _follow(self, closed: Sequence[int]) -> _Follow:
        """The contact to follow among sensors that closed together (overlapping cones)."""
        group = tuple(sorted(closed))
        r0 = _unit(self._dirs[list(group)].sum(axis=0))
        # the followed sensor: the one of the group closest to the group's mean direction
        sensor = group[int(np.argmax(self._dirs[list(group)] @ r0))]
        return _Follow(sensor, group, r0)

    def _record(self, m: Motion, f: _Follow, kind: Literal["touch", "slide"]) -> Contact:
        centre = np.asarray(m.measured, dtype=float)
        sensors = m.fired if kind == "touch" or m.event == "touch" else m.fired_start
        c = Contact(
            step=self.motions,
            centre=_v3(centre),
            sensors=tuple(sensors),
            sensor=f.sensor,
            direction=_v3(f.r0),
            point=_v3(centre + self.rho * f.r0),
            kind=kind,
            phase=self._phase,
            layer=self._layer,
            orientation=(self.orientation.tilt_deg, self.orientation.turn_deg),
        )
        self.contacts.append(c)
        if self._turning is not None and self._phase == "layers":
            self._turning.add(c.centre)
        return c

    def record(self, *, complete: bool) -> ExplorationRecord:
        """The exploration record so far."""
        per_phase: dict[str, int] = {}
        for c in self.contacts:
            per_phase[c.phase] = per_phase.get(c.phase, 0) + 1
        params = {
            k: float(v)
            for k, v in asdict(self.params).items()
            if isinstance(v, int | float) and not isinstance(v, bool)
        }
        params.update(
            z_step=self.z_step,
            z_first=self.z_first,
            spacing=self.spacing,
            edge_slide=self.edge_slide,
            bump=self.bump,
        )
        hint = self.world.hint
        params.update({f"hint_lo_{a}": float(v) for a, v in zip("xyz", hint.lo, strict=True)})
        params.update({f"hint_hi_{a}": float(v) for a, v in zip("xyz", hint.hi, strict=True)})
        params.update(self.extra_params)
        return ExplorationRecord(
            object=self.object_name,
            explorer=self.explorer,
            finger=self.finger.name,
            tip_radius=self.rho,
            sensor_directions=list(self.finger.directions),
            seed=self.seed,
            noise=self.noise,
            params=params,
            contacts=list(self.contacts),
            path=list(self.path),
            layers=list(self.layers),
            contacts_per_phase=per_phase,
            complete=complete,
            notes=list(self.notes)
            + (
                [f"{self.rereads} lost sensor signal(s) recovered by reading the sensors at rest"]
                if self.rereads
                else []
            )
            + ([f"{self.rides} surface irregularities ridden over"] if self.rides else [])
            + (
                [
                    f"{self.ripples} sensor change(s) on a rippled surface followed as the same surface"
                ]
                if self.ripples
                else []
            )
            + (
                [f"{self.dents} search cycle(s) found the same face again beyond a dent"]
                if self.dents
                else []
            )
            + (
                [f"{self.persisted} blocked slide(s) followed by re-acquiring the surface"]
                if self.persisted
                else []
            )
            + (
                [f"{self.openings} opening(s) found in side faces (under a rim, or between layers)"]
                if self.openings
                else []
            ),
            ending=self.ending.status if self.ending else "",
            unreachable=list(self.ending.unreachable) if self.ending else [],
            budget=self.ending.budget if self.ending else "",
            orientations=list(self.orientations),
            blind=list(self.blind),
        )

    # the exploration ---------------------------------------------------------------------------
    def run(self) -> Iterator[Mark]:
        """Explore step by step; yield ``"contact"`` at the first touch, ``"layer"`` after each
        layer, ``"complete"`` at the end (then stop)."""
        try:
            pos, follow = self._first_contact()
            yield "contact"
            self._phase = "layers"
            layer_contacts: list[Contact] = []
            top_contacts: list[Contact] = []
            z = float(pos[2])
            top = float(self.world.hint.hi[2])
            index = 0
            while True:
                self._layer = index
                # the contact that starts the layer belongs to it
                self.contacts[-1] = self.contacts[-1].model_copy(update={"layer": index})
                self._layer_motions = 0
                self._blocked_end = False
                start_path = len(self.path)
                start_contacts = len(self.contacts) - 1
                above = z + self.z_step > top - self.rho  # the next plane would be over the top
                last = above or index + 1 >= self.params.max_layers
                self._risen, self._looked = [], []
                self._next_z = None if last else z + self.z_step
                self._layer_z = z
                self._turning = _Turning(np.asarray(self.contacts[-1].centre[:2]), self.bump)
                closed, pos, follow = self._contour(pos, follow, last=last)
                layer_path = self.path[start_path - 1 if start_path else 0 :]
                self._finish_layer(index, z, layer_path, closed)
                layer_contacts = [c for c in self.contacts[start_contacts:] if c.layer == index]
                self._heights.append(z)
                if index and self._narrow(layer_contacts, top_contacts):
                    # near an apex the faces are narrower than the tip: its touches are edges
                    self._note(
                        f"the layer at z = {z:.4f} m is too narrow for the tip: its contacts "
                        "are dropped and the surfaces are probed lower"
                    )
                    self.contacts = [c for c in self.contacts if c.layer != index]
                    self._surfaces = [(h, g) for h, g in self._surfaces if abs(h - z) > 1e-12]
                    yield "layer"
                    break
                if closed or not top_contacts:
                    top_contacts = layer_contacts  # the top is explored over the last closed layer
                yield "layer"
                lowered = self._lower_under_top(z)
                if lowered is not None:
                    pos, follow = lowered
                    z = float(pos[2])
                    index += 1
                    continue
                # a contour a blocked slide ended is no reason to leave the planes above it
                # unexplored (``reapproach``): the next one is found by a new approach
                blocked = not closed and self.params.reapproach and self._blocked_end
                if not closed and not blocked:
                    break
                if last:
                    if closed and not above:
                        self._note(f"stopped after {self.params.max_layers} layers")
                    break
                step_z = z + self.z_step
                under: float | None = None  # the next layer's height under a top touched first
                if closed or blocked:
                    under = self._under_touched_top(z, top, layer_contacts, whole=closed)
                    if under is not None and under < z + self.bump:
                        self._note(
                            f"the top, touched at {under + TOP_CLEAR_RHO * self.rho:.4f} m, "
                            f"leaves no room for a layer above z = {z:.4f} m"
                        )
                        break
                    if under is not None:
                        step_z = min(step_z, under)
                # from the top just touched, the next layer is found by a new approach
                nxt = (
                    self._z_increment(pos, follow, _centre(layer_contacts))
                    if closed and under is None
                    else None
                )
                if nxt is None and step_z < top - self.rho:
                    # the contact was lost below the top of the visual estimate (a step up the
                    # object, as from an L-block's foot to its leg), or the contour ended at a
                    # blocked slide: a new first contact one z step up
                    nxt = self._first_contact([step_z], quiet=True)
                    if nxt is not None:
                        self._note(self._next_layer_note(z, step_z, under is not None, blocked))
                if nxt is None:
                    break
                pos, follow = nxt
                z = float(pos[2])
                index += 1
            self._layer, self._layer_z, self._turning = None, None, None
            if self.params.probe:
                self._phase = "probe"
                _SideProbes(self).run(_centre(top_contacts))
            if self.params.top:
                self._phase = "top"
                _TopPhase(self).run(top_contacts)
        except _Budget as exc:
            self._note(str(exc))
        if self.completer is not None:
            self._phase = "complete"
            self._complete(self.completer)
        yield "complete"

    # completion driven from above ---------------------------------------------------------------
    def _complete(self, completer: Completer) -> None:
        """Carry out the probes ``completer`` asks for until it returns an :class:`Ending`."""
        last: tuple[Probe, bool] | None = None
        if self.motions >= self.params.max_motions:
            text = f"motion budget of {self.params.max_motions} exhausted before the completion"
            self.ending = Ending(
                "budget", text, self._still_open(completer, text), self._motion_budget
            )
            return
        while True:
            try:
                nxt = completer.next_probe(self.record(complete=False), last)
                if isinstance(nxt, Ending):
                    self.ending = nxt  # the record says it (ending, unreachable, open_ending)
                    return
                last = (nxt, self.probe(nxt))
            except _Budget as exc:
                text = f"{exc} ({self.touches} touches): the model was not completed"
                self._note(text)
                self.ending = Ending(
                    "budget", text, self._still_open(completer, str(exc)), self._motion_budget
                )
                return

    @property
    def _motion_budget(self) -> str:
        """The motion budget as an :class:`Ending` names it."""
        return f"the motion budget of {self.params.max_motions} motions"

    def _still_open(self, completer: Completer, why: str) -> tuple[str, ...]:
        """What ``completer`` says still holds it open (its ``still_open``), or, when it cannot
        say, ``unknown (why)``."""
        ask = getattr(completer, "still_open", None)
        items = tuple(ask(self.record(complete=False))) if callable(ask) else ()
        return items or (f"unknown ({why})",)

    @property
    def touches(self) -> int:
        """Touches so far (sensor OFF→ON events kept in the record)."""
        return sum(1 for c in self.contacts if c.kind == "touch")

    def probe(self, p: Probe) -> bool:
        """Touch the surface asked for by ``p``; whether a sensor facing it closed.

        The way there goes up over the hint box, across to above the start of the approach,
        and down to it (each leg in free space: anything met on the way ends the probe). The
        touch is followed by a short slide each way along the surface (more tip centres on it).
        With the head indexed away from the vertical, the finger then backs out along the
        approach (a tip under an overhang cannot leave upwards).
        """
        start = len(self.path)
        done = self._probe(p)
        if not self.orientation.vertical and self._last_pos is not None and len(self.path) > start:
            here = np.asarray(self._last_pos, dtype=float)
            self._move_on(here, -self._approach, self.reach)
        return done

    def _probe(self, p: Probe) -> bool:
        """Touch the surface asked for by ``p``; whether a sensor facing it closed.

        The way there goes up over the hint box, across to above the start of the approach,
        and down to it (each leg in free space: anything met on the way ends the probe). The
        touch is followed by a short slide each way along the surface (more tip centres on it).

        The approach starts outside the hint box along ``p.normal`` and runs back along it
        through ``p.target``. A normal that points down (an undercut face) leaves the box
        sideways, never through its floor (the table: the start would lie under the object,
        where the way down from above cannot go), and a start that would lie below the
        workspace's floor is lifted onto it: the approach then runs from there straight at
        the target (a parallel line lifted with it would meet the face higher up, or its
        upper edge, instead of where the model asked).
        """
        normal = _unit(np.asarray(p.normal, dtype=float))
        self._approach = -normal
        pose: Orientation | None
        if isinstance(self.world, OrientableWorld) and p.facing is not None:
            pose = self.finger.index_towards(p.facing)
        elif isinstance(self.world, OrientableWorld):
            pose = self.finger.index_for(_v3(normal))
        else:
            pose = VERTICAL if self.finger.nearest(_v3(-normal)) is not None else None
        if pose is None:
            self._note(
                f"no sensor of finger {self.finger.name!r} faces a probe ({p.reason}) "
                "in any pose of its head"
            )
            return False
        target = np.asarray(p.target, dtype=float)
        hint = self.world.hint
        if p.middle:
            target[:2] = np.asarray(hint.centre, dtype=float)[:2]
        lo, hi = np.asarray(hint.lo, dtype=float), np.asarray(hint.hi, dtype=float)
        clear = self.rho + self.params.approach_margin
        # along the normal out of the hint box: the approach starts outside the object
        # (sideways, never through the floor of the box: the table)
        out = min(
            (float(hi[k]) - float(target[k])) / normal[k]
            if normal[k] > 1e-9
            else (float(lo[k]) - float(target[k])) / normal[k]
            if normal[k] < -1e-9 and k < 2
            else math.inf
            for k in range(3)
        )
        out = max(out, 0.0) if math.isfinite(out) else 0.0
        far = target + normal * (out + clear)
        floor = float(self.world.workspace.lo[2])
        if float(far[2]) < floor:  # lifted onto the floor: aimed at the target from there
            far[2] = floor
            if float(np.linalg.norm(target - far)) > 1e-9:
                self._approach = _unit(target - far)
        length = float(np.linalg.norm(far - target)) + p.reach
        if not self.world.workspace.contains(_v3(far)):
            # a target far outside the hint box (a corner of a model that lacks a face): the
            # object lies inside the box, so the approach starts where its line leaves it
            exit_ = _line_exit(target, normal, lo, hi)
            if exit_ is not None and exit_ + clear + p.reach > 0.0:
                start = target + normal * (exit_ + clear)
                if start[2] >= floor and self.world.workspace.contains(_v3(start)):
                    far, length = start, exit_ + clear + p.reach
                    self._approach = -normal
        if not self.world.workspace.contains(_v3(far)):
            self._note(
                f"a probe ({p.reason}) would start outside the workspace at {_fmt(_v3(far))}"
            )
            return False
        if not self._go_round(far, p.reason, pose):
            return False
        here = np.asarray(self._last_pos, dtype=float)
        m = self._move(here, self._approach, length)
        if m.event != "touch":
            self._note(f"a probe ({p.reason}) found nothing ({m.event})")
            return False
        f = self._follow(m.closed)
        self._record(m, f, "touch")
        if float(f.r0 @ -normal) < math.cos(math.radians(60.0)):
            self._note(
                f"a probe ({p.reason}) touched at {_fmt(m.end)} a surface facing "
                f"{_fmt(_v3(-f.r0))}, not the approach"
            )
            return False
        pos = np.asarray(m.end, dtype=float)
        t = self._tangent(f)
        if t is None:  # a top: slide along any horizontal direction
            t = _unit(np.cross(normal, np.array([1.0, 0.0, 0.0])))
            if float(np.linalg.norm(t)) < 0.5:
                t = np.array([0.0, 1.0, 0.0])
            t = _unit(np.array([t[0], t[1], 0.0]))
        for direction in (t, -t):
            sm, travelled = self._slide_sampled(pos, direction, f, 2.0 * self.spacing)
            if travelled > 1e-6 and sm.event in ("none", "release", "blocked"):
                self._record(sm, f, "slide")
            pos = np.asarray(sm.end, dtype=float)
            if sm.event not in ("none", "release", "blocked") or f.sensor not in sm.fired:
                break
        return True

    def _index(self, pose: Orientation, here: FloatArray, why: str) -> bool:
        """Index the head to ``pose`` with the tip centre at ``here`` (in free space)."""
        if pose == self.orientation:
            return True
        if not isinstance(self.world, OrientableWorld):
            self._note(f"the world cannot index the head for a probe ({why})")
            return False
        try:
            world = self.world.oriented(pose, _v3(here))
        except ExplorationError as exc:
            self._note(f"a probe ({why}): {exc}")
            return False
        self.world = world
        self.orientation = pose
        self._dirs = self.finger.directions_at(pose)
        self.indexes += 1
        if self._last_pos is None or _v3(here) != self._last_pos:
            self.path.append(_v3(here))
        self.orientations.append((len(self.path) - 1, pose.tilt_deg, pose.turn_deg))
        return True

    def _go_round(self, goal: FloatArray, why: str, pose: Orientation | None = None) -> bool:
        """Move from where the finger is to ``goal`` over the top of the hint box, indexing the
        head to ``pose`` up there (in free space above the object)."""
        hint = self.world.hint
        safe = float(hint.hi[2]) + self.rho + self.params.approach_margin
        here = np.asarray(self._last_pos, dtype=float)
        last = self._last_move
        near = (
            bool(self.contacts)
            and float(np.linalg.norm(np.asarray(self.contacts[-1].centre) - here)) < 3.0 * self.rho
        )
        if near or (last is not None and last.event == "blocked"):
            # leave the surface first: away from the last contact (or back the way the last
            # motion came, when no sensor felt it)
            back = (
                -np.asarray(self.contacts[-1].direction, dtype=float)
                if near
                else -np.asarray(last.direction if last else (0.0, 0.0, -1.0), dtype=float)
            )
            for _ in range(2):  # a bulge in the way: once more
                m = self._move_on(here, back, self.rho)
                here = np.asarray(m.end, dtype=float)
                if m.event in ("none", "release"):
                    break
                back = back + _Z
                if float(np.linalg.norm(back)) < 1e-6:  # it was straight down: out sideways
                    back = np.array([here[0] - hint.centre[0], here[1] - hint.centre[1], 0.0])
                    if float(np.linalg.norm(back)) < 1e-9:
                        back = np.array([1.0, 0.0, 0.0])
                back = _unit(back)
        if self.world.sense(_v3(here)):  # still on a surface: away from the middle
            centre = np.asarray(hint.centre, dtype=float)
            away = _unit(np.array([here[0] - centre[0], here[1] - centre[1], 0.0]))
            if float(np.linalg.norm(away)) > 0.5:
                m = self._move_on(here, away, self.rho)
                here = np.asarray(m.end, dtype=float)
        for leg, waypoint in enumerate(
            (
                np.array([here[0], here[1], max(safe, float(here[2]))]),
                np.array([goal[0], goal[1], max(safe, float(goal[2]))]),
                goal,
            )
        ):
            if leg == 1 and pose is not None and not self._index(pose, here, why):
                return False
            d = waypoint - here
            length = float(np.linalg.norm(d))
            if length < 1e-9:
                continue
            m = self._move_on(here, d / length, length)
            here = np.asarray(m.end, dtype=float)
            if leg == 0 and m.event not in ("none", "release", "limit"):
                # under an overhang (a lying prism's lower side): out of the object's
                # footprint horizontally, then up
                m = self._out_and_up(here, safe)
                if m.event not in ("none", "release"):
                    m = self._retrace_up(safe) or m
                here = np.asarray(m.end, dtype=float)
            if m.event not in ("none", "release"):
                self._note(f"the way to a probe ({why}) is blocked at {_fmt(m.end)} ({m.event})")
                return False
        return True

    def _free(self, start: FloatArray, direction: FloatArray, length: float) -> bool:
        """Whether the world lets the tip move ``length`` along ``direction`` from ``start``
        without meeting anything (losses of contact aside). Asked, not moved: nothing is
        recorded."""
        m, done = _through_releases(
            lambda p, u, n: self.world.move(_v3(p), _v3(u), n), start, direction, length
        )
        return m.event in ("none", "release") and done >= length - 1e-9

    def _retrace_up(self, safe: float) -> Motion | None:
        """Back along the finger's own way until the way straight up to ``safe`` is free, then
        up; the last motion, or None when no point of the last :data:`RETRACE_POINTS` on the way
        back has a free way up (nothing is moved then). The way back runs straight between the
        points of the way in where no sensor touched, each leg free.

        Under an overhang that also closes the way out sideways (a wing of a compound object),
        the way the finger came in is the one known way out: a robot can always run its own
        motions backwards. The points are the true positions of the tip (the record's path
        holds the measured ones)."""
        trail = [np.asarray(p, dtype=float) for p in self._trail]
        if len(trail) < 2:
            return None
        cur = trail[-1]
        legs: list[tuple[FloatArray, FloatArray, float]] = []
        for point in reversed(trail[:-1]):
            d = point - cur
            length = float(np.linalg.norm(d))
            if length > 1e-9:
                # a point where the tip touched is passed by: the way runs between free points
                if self.world.sense(_v3(point)) or not self._free(cur, d / length, length):
                    continue
                legs.append((cur, d / length, length))
                cur = point
            rise = safe - float(cur[2])
            if rise > 1e-9 and not self._free(cur, _Z, rise):
                continue
            for start, direction, length in legs:
                m = self._move_on(start, direction, length)
                if m.event not in ("none", "release"):
                    return m
            if rise <= 1e-9:
                return self._last_move
            return self._move_on(cur, _Z, rise)
        return None

    def _out_and_up(self, here: FloatArray, safe: float) -> Motion:
        """Leave the hint box's footprint horizontally (away from its middle), then rise to
        ``safe``; the last motion."""
        hint = self.world.hint
        lo, hi = np.asarray(hint.lo, dtype=float), np.asarray(hint.hi, dtype=float)
        away = np.array([here[0] - 0.5 * (lo[0] + hi[0]), here[1] - 0.5 * (lo[1] + hi[1]), 0.0])
        if float(np.linalg.norm(away)) < 1e-9:
            away = np.array([1.0, 0.0, 0.0])
        away = _unit(away)
        clear = self.rho + self.params.approach_margin
        out = min(
            ((hi[k] if away[k] > 0 else lo[k]) - here[k]) / away[k]
            for k in range(2)
            if abs(away[k]) > 1e-9
        )
        m = self._move_on(here, away, max(float(out), 0.0) + clear)
        if m.event not in ("none", "release"):
            return m
        here = np.asarray(m.end, dtype=float)
        if safe - float(here[2]) < 1e-9:
            return m
        return self._move_on(here, _Z, safe - float(here[2]))

    @overload
    def _first_contact(
        self, heights: list[float] | None = None, *, quiet: Literal[False] = False
    ) -> tuple[FloatArray, _Follow]: ...

    @overload
    def _first_contact(
        self, heights: list[float] | None = None, *, quiet: Literal[True]
    ) -> tuple[FloatArray, _Follow] | None: ...

    def _first_contact(
        self, heights: list[float] | None = None, *, quiet: bool = False
    ) -> tuple[FloatArray, _Follow] | None:
        """Approach the object horizontally (+x) on lines across the hint until a sensor closes.

        When every approach along +x met the object only where no sensor faces (a side leaning
        over the finger: an oblique block on the table), the same lines are tried along −x,
        then +y and −y."""
        hint = self.world.hint
        gap = self.rho + self.params.approach_margin
        lo, hi = np.asarray(hint.lo, dtype=float), np.asarray(hint.hi, dtype=float)
        if heights is None:
            heights = [self.z_first]
            while heights[-1] + self.z_step < float(hint.hi[2]):
                heights.append(heights[-1] + self.z_step)
        tried = []
        sides = [(axis, sign, False) for axis, sign in ((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0))]
        if isinstance(self.world, OrientableWorld) and self.finger.wrist is not None:
            # every side leaning over the finger (a frustum on its small end): the head indexed
            # towards the approach and up
            sides += [(axis, sign, True) for axis, sign, _ in sides]
        for axis, sign, tilted in sides:
            across = 1 - axis
            x0 = float(lo[axis]) - gap if sign > 0 else float(hi[axis]) + gap
            length = float(hi[axis] - lo[axis]) + 2 * gap
            yc, qy = 0.5 * float(lo[across] + hi[across]), float(hi[across] - lo[across]) / 6.0
            ys = [yc + k * qy for k in (0.1, 1.1, -0.9, 2.1, -1.9)]
            direction = np.zeros(3)
            direction[axis] = sign
            tried.append(f"{'+' if sign > 0 else '-'}{'xy'[axis]}" + (" tilted" if tilted else ""))
            blind = False
            for z in heights:
                for y in ys:
                    start = np.zeros(3)
                    start[axis], start[across], start[2] = x0, y, z
                    if not self.world.workspace.contains(_v3(start)):
                        continue
                    if tilted:
                        pose = self.finger.index_towards(_v3(_unit(direction + _Z)))
                        if not self._index(pose, start, "first contact"):
                            continue
                    m = self._move(_v3(start), _v3(direction), length)
                    if m.event == "touch":
                        f = self._follow(m.closed)
                        self._record(m, f, "touch")
                        return np.asarray(m.end, dtype=float), f
                    if m.event == "blocked":
                        blind = True
                        self._note(f"blind contact (no sensor fired) at {_fmt(m.end)}")
            if not blind:
                break  # nothing there at all: no other side will find it
        if quiet:
            return None
        raise ExplorationError(
            f"the finger never touched the object ({len(heights) * 5} approaches along "
            f"{', '.join(tried)} at heights {', '.join(f'{h:.3f}' for h in heights)} m)"
        )

    def _tangent(self, f: _Follow) -> FloatArray | None:
        """The horizontal direction associated with the followed contact (object on the left)."""
        n = -f.r0
        t = np.cross(_Z, n)
        norm = float(np.linalg.norm(t))
        if norm < 1e-6:
            return None
        return t / norm

    def _slide_sampled(
        self,
        pos: FloatArray,
        direction: FloatArray,
        f: _Follow,
        length: float,
        *,
        until: Callable[[FloatArray], bool] | None = None,
    ) -> tuple[Motion, float]:
        """Slide up to ``length`` along the surface under ``f``, recording a ``"slide"`` contact
        every :attr:`spacing`; the last motion (not recorded) and the distance travelled.
        The slide also stops at a contact where ``until`` holds (that motion is recorded).

        With ``comply`` on, a slide that stops before the surface ends (a bump blocks it, or
        the surface recedes a little) rides over the irregularity (:meth:`_ride`) and goes on.
        """
        travelled = 0.0
        start = np.asarray(pos, dtype=float)
        while True:
            piece = min(self.spacing, length - travelled)
            m = self._slide(pos, direction, piece, f.sensor)
            travelled += m.distance
            if (
                self.params.comply
                and travelled + current().servo.ride_step * self.rho < length
                and (m.event == "blocked" or (m.event == "release" and f.sensor not in m.fired))
            ):
                ahead = _chord(start, np.asarray(m.end, dtype=float), self.rho, m.direction)
                ridden = self._ride(m, f, ahead)
                if ridden is not None:
                    pos, hop = ridden
                    travelled += hop
                    self.rides += 1
                    if until is not None and until(pos):  # stopped where the ride regained it
                        here = _v3(pos)
                        gone = float(np.linalg.norm(pos - np.asarray(m.start, dtype=float)))
                        stop = replace(m, end=here, distance=gone, event="none", measured=here)
                        return stop, travelled
                    continue
            if m.event != "none" or m.distance < piece - 1e-9 or travelled >= length - 1e-9:
                return m, travelled
            self._record(m, f, "slide")
            pos = np.asarray(m.end, dtype=float)
            if until is not None and until(pos):
                return m, travelled

    def _ride(self, m: Motion, f: _Follow, ahead: FloatArray) -> tuple[FloatArray, float] | None:
        """Ride over an irregularity that stopped the slide ``m`` of ``f``'s surface.

        The compliance of a finger under force control, made of the servo logic's own
        motions: back off the surface by :attr:`bump`, step on by :data:`RIDE_STEP` ρ along
        ``ahead`` (the slide's mean direction so far), and press back towards the surface
        (along r0, squared to ``ahead``) to :attr:`bump` deeper than where the slide ran. A bump
        higher than that is tried once more, lifting twice as far. The surface is regained when the followed sensor fires again: that
        contact is recorded as a ``"slide"`` contact (the finger never left the surface it
        follows) and the slide goes on from there.

        The step is long enough that at a real convex edge the press misses the edge or meets
        the next face with sensors turned further than :data:`RIDE_DEG`, so a real edge still ends the slide as the paper's rules say: the finger goes
        back to where the slide stopped and None is returned (the caller then runs the search
        cycle, or ends the contour).
        """
        r0 = _unit(f.r0)
        horizontal = float(np.hypot(r0[0], r0[1]))
        if horizontal > 1e-6:  # press square to the slide's mean direction, at r0's elevation
            r0 = _unit(np.cross(_Z, ahead) * horizontal + np.array([0.0, 0.0, r0[2]]))
        regained: Motion | None = None
        for lift in (self.bump, 2.0 * self.bump):  # a bump higher than expected: lift more
            pos = np.asarray(m.end, dtype=float)
            legs: list[tuple[FloatArray, float]] = []
            back = self._move_on(pos, -r0, lift)
            legs.append((r0, back.distance))
            pos = np.asarray(back.end, dtype=float)
            if back.event in ("none", "release"):
                step = self._move(pos, ahead, current().servo.ride_step * self.rho)
                legs.append((-ahead, step.distance))
                pos = np.asarray(step.end, dtype=float)
                if step.event == "touch" and step.distance > 0.25 * self.rho:
                    regained = step
                elif step.event == "none":
                    press = self._move(pos, r0, lift + self.bump)
                    legs.append((-r0, press.distance))
                    if press.event == "touch":
                        regained = press
                    pos = np.asarray(press.end, dtype=float)
            if regained is not None and not self._same_surface(regained, f, r0):
                regained = None
            if regained is not None:
                break
            # not regained: back to where the slide stopped, for the paper's rules from there
            pos = self._retrace(pos, legs)
            if m.event == "release":  # the surface fell away: a real edge
                return None
        if regained is None:
            return None
        if f.sensor not in regained.fired:  # the surface turned a little: follow what closed
            nf = self._follow(regained.closed)
            f.sensor, f.group, f.r0 = nf.sensor, nf.group, nf.r0
        self._record(regained, f, "slide")
        end = np.asarray(regained.end, dtype=float)
        if m.event == "release":
            self._under_edge(end, r0, ahead)
        return end, max(0.0, float((end - np.asarray(m.end, dtype=float)) @ ahead))

    def _rise(self, pos: FloatArray, f: _Follow) -> None:
        """Look for an opening in a side face between this layer and the next one up.

        Layers are ``z_step`` apart, and a slot or a tunnel lower than that (a U-block lying on
        its arm, its gap facing sideways) can lie wholly between two of them. Where a contour
        first touches a vertical face (its followed sensor on the equator), the finger rises
        along it, pressed to it, to ρ under the next layer (or under the top of the hint box).
        Contact kept all the way: the face is whole there, and the finger goes back down;
        nothing is recorded. The face falling away on the way up is a rim: the finger rises
        ρ + :attr:`bump` over it and presses in. The face met again with the followed sensor is
        the same face, sloping inwards; nothing met within 2ρ + (1 + :data:`UNDER_DEPTH`)
        ``bump`` is an opening the whole tip entered: the finger presses on to the opening's
        back wall, or else goes down onto its floor, and records what it touched (a face
        inside the envelope: the object is not convex), sliding a little along it. Then it
        goes back the way it came. Each face is risen along once per layer.
        """
        if (
            self._phase != "layers"
            or self._looking_under
            or not self.orientation.vertical
            or abs(float(f.r0[2])) > 0.05
            or any(float(r @ f.r0) > 0.98 for r in self._risen)
        ):
            return
        z = float(pos[2])
        ceiling = float(self.world.hint.hi[2]) - self.rho - self.bump
        if self._next_z is not None and self._next_z > z + 1e-9:
            ceiling = min(ceiling, self._next_z - self.rho)
        if ceiling - z < 2.0 * self.rho:
            return
        self._risen.append(np.asarray(f.r0, dtype=float).copy())
        press = _unit(np.array([f.r0[0], f.r0[1], 0.0]))
        with _Look(self, pos) as look:
            up = look.go(_Z, ceiling - z, rigid=True)
            if up.event != "release" or f.sensor in up.fired:
                return  # the face is whole up there, or overhangs: nothing to look into
            if ceiling - float(look.here[2]) < self.rho + self.bump:
                return  # too near the next layer for the tip to enter what lies above the rim
            if look.go(_Z, self.rho + self.bump).event not in ("none", "release"):
                return
            enter = look.go(press, 2.0 * self.rho + (1.0 + UNDER_DEPTH) * self.bump, rigid=True)
            if enter.event != "none":
                return  # the face again (sloping inwards), or a corner
            depth = float(np.hypot(*np.asarray(self.world.hint.size, dtype=float)[:2]))
            hit = look.go(press, depth, rigid=True)
            if hit.event != "touch" or not hit.closed:
                if hit.event != "none":
                    return
                hit = look.go(-_Z, 2.0 * (self.rho + self.bump), rigid=True)  # onto the floor
                if hit.event != "touch" or not hit.closed:
                    return
            look.found(hit, self._tangent(self._follow(hit.closed)))

    def _under_edge(self, pos: FloatArray, press: FloatArray, ahead: FloatArray) -> None:
        """Look under the edge a ride came back on: is the face followed there one tip radius
        lower, or does an opening (a U-block's tunnel, a slot) lie under that edge?

        A side face that fell away under the followed sensor and came back a step on may have
        been a dent, or the mouth of an opening whose upper rim lies less than ρ above the tip's
        centre: the tip, too tall for it, met the rim with its upper half and took it for the
        face. From ``pos`` (on the rim, in a layer, the finger vertical) the finger backs off by
        :attr:`bump`, goes down by ρ and presses back up to :data:`UNDER_DEPTH` ``bump`` deeper
        than the slide ran. The face met there with sensors facing ``press`` (within
        :data:`RIDE_DEG`) was a dent: nothing is recorded. Otherwise the opening's side is
        found: a corner touched with sensors turned sideways says on which side the opening's
        wall stands (none touched: the side the slide came from); the finger enters the opening
        wholly, beside that wall, and moves towards it; the wall it touches is recorded as a
        touch (a face inside the envelope: the object is not convex) and slid along inwards.
        The finger then goes back to ``pos`` the way it came, and the slide goes on. Nothing
        is looked for where the tip would meet the table, on a sloped face, or with the head
        indexed.
        """
        if (
            self._phase != "layers"
            or self._looking_under
            or not self.orientation.vertical
            or abs(float(press[2])) > 0.05
        ):
            return
        lo = float(self.world.hint.lo[2])
        if float(pos[2]) - 2.0 * self.rho < lo + self.bump:
            return
        # a rough face rides over many dents: look under the first few rims of each face only
        looked = [r for r in self._looked if float(r @ press) > 0.98]
        if len(looked) >= UNDER_LOOKS:
            return
        self._looked.append(np.asarray(press, dtype=float).copy())
        press = _unit(np.array([press[0], press[1], 0.0]))
        side = _unit(np.array([ahead[0], ahead[1], 0.0]))
        side = _unit(side - (side @ press) * press)
        with _Look(self, pos) as look:
            if look.go(-press, self.bump).event not in ("none", "release"):
                return
            if look.go(-_Z, self.rho).event not in ("none", "release"):
                return
            below = look.go(press, (1.0 + UNDER_DEPTH) * self.bump, rigid=True)
            if below.event == "blocked":
                return
            wall = -side  # the slide came from there: the opening began behind
            if below.event == "touch":
                dirs = self._dirs[list(below.closed or below.fired)]
                mean = _unit(dirs.sum(axis=0))
                if float(mean @ press) >= math.cos(math.radians(current().servo.ride_deg)):
                    return  # the face is there one tip radius lower: a dent
                lateral = float(mean @ side)
                if abs(lateral) < math.sin(math.radians(current().servo.ride_deg)):
                    return  # a rim above or below, not a side: too low an opening for the tip
                wall = side if lateral > 0 else -side
                # off the corner, far enough sideways for the whole tip to pass it
                if look.go(-press, self.bump).event not in ("none", "release"):
                    return
                if look.go(-wall, self.rho * (1.0 - abs(lateral)) + self.bump).event != "none":
                    return
            inside = look.go(press, 2.0 * self.rho + (1.0 + UNDER_DEPTH) * self.bump, rigid=True)
            if inside.event != "none":
                return
            hit = look.go(wall, 2.0 * self.rho + current().servo.ride_step * self.rho, rigid=True)
            if hit.event != "touch" or not hit.closed:
                return
            if float(self._follow(hit.closed).r0 @ wall) < math.cos(
                math.radians(current().servo.ride_deg)
            ):
                return  # not a wall square to the way there: an edge or a corner inside
            look.found(hit, press)  # slid along inwards

    def _same_surface(self, m: Motion, f: _Follow, press: FloatArray) -> bool:
        """Whether a touch while riding is the followed surface again: the followed sensor
        fired, or the sensors that closed point within :data:`RIDE_DEG` of the press."""
        if f.sensor in m.fired:
            return True
        if not m.closed:
            return False
        mean = _unit(self._dirs[list(m.closed)].sum(axis=0))
        return float(mean @ press) >= math.cos(math.radians(current().servo.ride_deg))

    def _contour(
        self, pos: FloatArray, f: _Follow, *, last: bool = False
    ) -> tuple[bool, FloatArray, _Follow]:
        """Follow the contour in the current plane z = const; return (closed, position, follow).

        The layer is closed when the first surface slid along is touched a second time, when
        the contour comes back on any surface it already followed, or, in the ``last`` layer,
        when the surface before the first one ends where the layer began (no touch needed).

        A touch whose slide rolls off at once (within ``edge_slide``) touched an edge or a
        vertex: it is dropped from the record, unless the touch before or after it is such a
        touch too (a curved surface is all edges to a sliding tip, and is kept).
        """
        edges = _EdgeTouches()
        segs: list[_Segment] = []
        try:
            return self._trace(pos, f, last, edges, segs)
        finally:
            for index in sorted(edges.final(), reverse=True):
                del self.contacts[index]
            self._surfaces += [(float(pos[2]), g) for g in _surfaces(segs)]

    def _trace(
        self, pos: FloatArray, f: _Follow, last: bool, edges: _EdgeTouches, segs: list[_Segment]
    ) -> tuple[bool, FloatArray, _Follow]:
        p = self.params
        fresh: int | None = len(self.contacts) - 1 if self._last_is_touch() else None
        since = 0.0  # distance slid since the fresh touch
        while self._layer_motions < p.max_layer_motions:
            new_touch = fresh is not None and since == 0.0
            surfaces = _surfaces(segs)
            halfway = self._halfway()
            if new_touch and surfaces and halfway and self._on_first(surfaces, pos, f):
                return self._close_on_first(surfaces[0], segs, pos, f)
            round_on = self._gone_round(segs, pos) if p.comply and not new_touch else None
            if round_on is not None:
                return self._close_on_first(round_on, segs, pos, f)
            if new_touch and surfaces and halfway and self._back_on(surfaces, pos, f):
                return True, pos, f
            if new_touch and self._top_met(pos, f):
                return False, pos, f
            if new_touch and p.comply:
                self._rise(pos, f)
            t = self._tangent(f)
            if t is None:
                self._note("a horizontal surface met while contouring; contour stopped")
                return False, pos, f
            start = pos
            until = (lambda here: self._gone_round(segs, here) is not None) if p.comply else None
            m, travelled = self._slide_sampled(pos, t, f, self.reach, until=until)
            pos = np.asarray(m.end, dtype=float)
            since += travelled
            edge = False
            if fresh is not None and since >= self.edge_slide:
                edges.surface()
                fresh = None
            elif fresh is not None and self._rolled(m, f):
                edge = True
            if travelled > 0:
                if segs and segs[-1].group == frozenset(f.group) and since > travelled:
                    segs[-1].length += travelled  # the same surface, after another sensor opened
                else:
                    direction = _chord(start, pos, self.rho, m.direction)
                    segs.append(
                        _Segment(frozenset(f.group), start, direction, travelled, f.r0.copy())
                    )
            if edge and fresh is not None:
                edges.edge(fresh, segs[-1] if travelled > 0 else None)
                fresh = None
            round_on = self._gone_round(segs, pos) if p.comply and m.event == "none" else None
            if round_on is not None:
                return self._close_on_first(round_on, segs, pos, f)
            if m.event == "touch":
                if p.comply and fresh is None and self._ripple(m, f):
                    self.ripples += 1
                    self._record(m, f, "slide")  # the same surface, turned a little
                    continue
                if not edge:
                    self._record(m, f, "slide")  # the end of the surface followed
                f = self._follow(m.closed)
                self._record(m, f, "touch")
                fresh, since = len(self.contacts) - 1, 0.0
                continue
            if m.event == "release":
                if f.sensor in m.fired:  # another surface's sensor opened: keep following
                    continue
                if not edge:
                    self._record(m, f, "slide")
                fresh = None
                if last and self._before_first(_surfaces(segs), pos, f):
                    return True, pos, f
                before = f
                found = self._search(pos, np.asarray(m.direction, dtype=float), f)
                if found is None:
                    return False, np.asarray(self._last_pos, dtype=float), f
                pos, f = found
                if p.comply and not edge and segs and self._dent(segs[-1], before, f, pos):
                    # the same face beyond a dent: a slide contact, the finger follows on
                    self.contacts[-1] = self.contacts[-1].model_copy(update={"kind": "slide"})
                    self.dents += 1
                    continue
                fresh, since = len(self.contacts) - 1, 0.0
                continue
            self._record(m, f, "slide")
            if m.event == "blocked" and p.comply:
                again = self._persist(pos, m.direction, f)
                if again is not None:
                    pos, f, touched = again
                    if touched:
                        fresh, since = len(self.contacts) - 1, 0.0
                    continue
            what = {
                "none": "the slide found no end",
                "limit": "the workspace ends",
                "blocked": "a surface blocked the slide without a sensor change",
            }
            self._note(f"contour stopped at {_fmt(m.end)}: {what.get(m.event, m.event)}")
            self._blocked_end = m.event == "blocked"
            return False, pos, f
        self._note(f"contour budget of {p.max_layer_motions} motions exhausted")
        return False, pos, f

    def _close_on_first(
        self, first: _Segment, segs: list[_Segment], pos: FloatArray, f: _Follow
    ) -> tuple[bool, FloatArray, _Follow]:
        """The contour is back on the layer's ``first`` surface: slide on to where the layer
        began (more tip centres on it, no touch); the layer is closed."""
        rest = -first.place(pos)[0]
        t = self._tangent(f)
        if rest > self.spacing and t is not None:
            m, travelled = self._slide_sampled(pos, t, f, rest)
            segs.append(_Segment(frozenset(f.group), pos, first.direction, travelled, f.r0.copy()))
            pos = np.asarray(m.end, dtype=float)
            self._record(m, f, "slide")
        else:
            segs.append(_Segment(frozenset(f.group), pos, first.direction, 0.0, f.r0))
        return True, pos, f

    def _halfway(self) -> bool:
        """Whether a touch on a surface the layer already followed may close it: with
        ``comply``, once the tip centres have turned :data:`HALF_DEG` round the object."""
        if not self.params.comply or self._turning is None:
            return True
        return self._turning.total >= math.radians(HALF_DEG)

    def _gone_round(self, segs: list[_Segment], pos: FloatArray) -> _Segment | None:
        """The layer's first surface when the contour went round the object without a touch
        closing it and is back on that surface (None otherwise): its tip centres have turned
        :data:`ROUND_DEG` or more, and ``pos`` lies on the surface's line (within
        max(2 mm, 0.2 ρ) in x–y, as :meth:`_on_first` asks of a touch), before where the layer
        began or at most ``l3`` + ρ past it."""
        if self._turning is None or self._turning.total < math.radians(ROUND_DEG):
            return None
        surfaces = _surfaces(segs)
        if not surfaces:
            return None
        along, off = surfaces[0].place(pos, flat=True)
        if off <= max(0.002, 0.2 * self.rho) and along <= self.params.l3 + self.rho:
            return surfaces[0]
        return None

    def _persist(
        self,
        start: FloatArray,
        direction: FloatArray | Vec3,
        f: _Follow,
    ) -> tuple[FloatArray, _Follow, bool] | None:
        """Re-acquire the surface of ``f`` where a slide along ``direction`` was blocked at
        ``start`` without a sensor change and riding over the obstacle failed. Returns
        (position, follow, whether it was a new touch), or None (the contour ends).

        The finger backs off horizontally from the surface, steps on along the slide, and
        searches back towards the object as the paper's cycle does (``l2``, then ``l3`` back):
        a contact on the way is followed. A contact whose sensors include one of the followed
        group, or point within :data:`RIDE_DEG` of the approach, is the surface followed (a
        ``"slide"`` contact); any other is a new touch. A wall no sensor feels ahead of the
        step ends the re-acquisition (not an irregularity). When the approach meets the object
        blind, or comes back no further along the slide, the finger backs off and steps twice
        as far, up to :data:`PERSIST_TRIES` times: the obstacle is at most a few tip radii
        long, and the layer's motion budget bounds the whole contour.
        """
        p = self.params
        t = _unit(np.array([direction[0], direction[1], 0.0]))
        towards = _unit(np.cross(_Z, t))
        if float(np.linalg.norm(t)) < 0.5:
            return None
        start = np.asarray(start, dtype=float)
        step = current().servo.ride_step * self.rho
        here = start
        for attempt in range(current().servo.persist_tries):
            scale = float(2**attempt)
            back = self._move_on(here, -towards, scale * 2.0 * self.bump)
            here = np.asarray(back.end, dtype=float)
            if back.event not in ("none", "release"):
                continue
            fwd = self._move_on(here, t, scale * step)
            here = np.asarray(fwd.end, dtype=float)
            hit: Motion | None = None
            if fwd.event == "blocked":  # no sensor feels what is ahead: a bump above them?
                hit = self._over_blind(here, t, scale * step - fwd.distance)
                if hit is None:
                    return None  # a wall: not an irregularity
                here = np.asarray(hit.end, dtype=float)
            elif fwd.event == "touch":
                hit = fwd
            elif fwd.event == "none":
                press = self._move(here, towards, scale * 2.0 * self.bump + p.l2)
                here = np.asarray(press.end, dtype=float)
                if press.event == "touch":
                    hit = press
                elif press.event == "none":  # the surface fell away: the cycle goes on
                    found = self._search(here, t, f, first=False)
                    if found is None:
                        return None
                    npos, nf = found
                    self.persisted += 1
                    return npos, nf, True
            if hit is None or float((np.asarray(hit.end) - start) @ t) < 0.25 * step:
                continue
            self.persisted += 1
            if hit is fwd or not self._kin(hit, f, towards):
                nf = self._follow(hit.closed)
                self._record(hit, nf, "touch")
                return np.asarray(hit.end, dtype=float), nf, True
            if f.sensor not in hit.fired:  # the surface turned a little: follow what closed
                nf = self._follow(hit.closed)
                f.sensor, f.group, f.r0 = nf.sensor, nf.group, nf.r0
            self._record(hit, f, "slide")
            return np.asarray(hit.end, dtype=float), f, False
        return None

    def _dent(self, seg: _Segment, before: _Follow, f: _Follow, pos: FloatArray) -> bool:
        """Whether the contact ``f`` at ``pos`` that a search cycle found after the surface
        ``before`` (slid along as ``seg``) fell away is the same face beyond a dent or a rough
        patch: its tip centre lies within 2 ``bump`` of the line the tip centres followed on
        that face, and its sensors point within 60° of ``before``'s (a rough scan's local
        normal swings by 30–50° from one contact to the next, so the position decides). Past a
        real edge turned by θ the search (``l1`` on, then towards the object) meets the next
        face about l1 · tan θ off that line: 2.5 mm at 17°, 4.6 mm for the 30° edges of a
        12-sided prism; faces meeting at less than that are one face to the touch count (the
        model is built from the contacts, whatever their kind)."""
        if float(f.r0 @ before.r0) < 0.5:
            return False
        u = np.array([seg.direction[0], seg.direction[1]])
        nu = float(np.linalg.norm(u))
        if nu < 1e-9:
            return False
        d = np.asarray(pos, dtype=float)[:2] - np.asarray(seg.start, dtype=float)[:2]
        off = abs(float(d[0] * u[1] - d[1] * u[0])) / nu
        return off <= 2.0 * self.bump

    def _ripple(self, m: Motion, f: _Follow) -> bool:
        """Whether a sensor closing during a slide is a ripple of the surface followed (a scan's
        vertex noise or bump turning the contact a little), not a new surface: the followed
        sensor stays ON, every sensor that closed is a neighbour of it (within
        :data:`RIPPLE_DEG`), and the sensors ON now point within :data:`RIDE_DEG` of r0 on
        average. A new face met in a straight slide turns the contact by its whole angle."""
        if f.sensor not in m.fired or not m.closed:
            return False
        cos_n = math.cos(math.radians(current().servo.ripple_deg))
        if not bool((self._dirs[list(m.closed)] @ self._dirs[f.sensor] >= cos_n).all()):
            return False
        mean = _unit(self._dirs[list(m.fired)].sum(axis=0))
        return float(mean @ f.r0) >= math.cos(math.radians(current().servo.ride_deg))

    def _kin(self, m: Motion, f: _Follow, press: FloatArray) -> bool:
        """Whether a contact met while re-acquiring a surface is the surface followed: one of
        the followed sensors fired, or the sensors that closed point within
        :data:`RIDE_DEG` of the (horizontal) approach ``press``."""
        if set(f.group) & set(m.fired):
            return True
        return self._same_surface(m, f, press)

    def _last_is_touch(self) -> bool:
        return bool(self.contacts) and self.contacts[-1].kind == "touch"

    def _rolled(self, m: Motion, f: _Follow) -> bool:
        """Whether a slide ended by rolling off an edge: the followed sensor opened, or a
        neighbouring sensor (within 40° of the followed direction) closed."""
        if m.event == "release":
            return f.sensor not in m.fired
        if m.event == "touch" and m.closed:
            return bool((self._dirs[list(m.closed)] @ f.r0 >= math.cos(math.radians(40.0))).all())
        return False

    def _on_first(self, segs: list[_Segment], pos: FloatArray, f: _Follow) -> bool:
        """Whether a new touch at ``pos`` is the first surface of the layer met a second time."""
        first = segs[0]
        if not (set(f.group) & first.group) or all(s.group == first.group for s in segs):
            return False
        along, off = first.place(pos)
        return off <= max(0.002, 0.2 * self.rho) and along <= self.params.l3 + self.rho

    def _before_first(self, segs: list[_Segment], pos: FloatArray, f: _Follow) -> bool:
        """Whether the surface just left ends where the layer's first surface begins."""
        if len(segs) < 2 or set(f.group) & segs[0].group:
            return False
        along, off = segs[0].place(pos)
        return off <= 2.0 * self.rho and along <= self.rho

    def _back_on(self, segs: list[_Segment], pos: FloatArray, f: _Follow) -> bool:
        """Whether ``pos`` (a new contact of ``f``) lies on a surface already followed in this layer."""
        reach_back = self.params.l3 + self.rho
        for seg in segs[:-1]:
            if not seg.group & set(f.group):
                continue
            along, off = seg.place(pos)
            if off <= max(0.002, 0.2 * self.rho) and -reach_back <= along <= seg.length + 1e-6:
                return True
        return False

    def _search(
        self,
        pos: FloatArray,
        t: FloatArray,
        f: _Follow,
        *,
        first: bool = True,
    ) -> tuple[FloatArray, _Follow] | None:
        """The l1, l2, l3 cycle after a loss of contact; the new contact, or None.

        ``first=False``: the cycle's first legs were already made (a re-acquisition that
        stepped on and searched towards the object): only ``l3`` back remains. A cycle that
        met the object only blind (no sensor fired) ends the contour: on ideal solids lying
        in any pose that is an overhang, which the completion probes with the head indexed."""
        p = self.params
        towards = np.cross(_Z, t)
        towards = _unit(np.array([towards[0], towards[1], 0.0]))
        blind = False
        legs = ((t, p.l1), (towards, p.l2), (-t, p.l3))
        for direction, length in legs if first else legs[2:]:
            m = self._move(pos, direction, length)
            pos = np.asarray(m.end, dtype=float)
            if m.event == "touch":
                nf = self._follow(m.closed)
                self._record(m, nf, "touch")
                return pos, nf
            if m.event == "blocked":
                blind = True
                self._note(f"blind contact (no sensor fired) at {_fmt(m.end)}")
                over = self._over_blind(pos, direction, length - m.distance) if p.comply else None
                if over is not None:
                    nf = self._follow(over.closed)
                    self._record(over, nf, "touch")
                    return np.asarray(over.end, dtype=float), nf
            elif m.event == "limit":
                self._note(f"the workspace ends at {_fmt(m.end)}")
                return None
        if blind:  # the object was met, only where no sensor feels it: no size can be inferred
            self._note(
                f"the l1-l2-l3 cycle at z = {pos[2]:.4f} m met the object only where no sensor "
                f"of finger '{self.world.finger.name}' fires"
            )
        else:
            self._note(
                f"no contact after the l1-l2-l3 cycle at z = {pos[2]:.4f} m: the object has at "
                f"least one dimension smaller than l2 = {p.l2:g} m"
            )
        return None

    def _over_blind(self, pos: FloatArray, direction: FloatArray, length: float) -> Motion | None:
        """A motion of the contour blocked where no sensor fires: on a rough face, a bump met by
        the tip above its sensors' cones (a blocked slide's re-acquisition, a leg of the
        cycle). The finger backs off 2 ``bump`` and tries the rest of the motion again at the
        layer's height (when an earlier try left it above), then ``servo.blind_rise`` and
        twice that (tip radii) above it, each try gone back when it touches nothing. Returns
        the touch it made, the finger where it touched (None: nothing touched, the finger
        back at ``pos``)."""
        start = np.asarray(pos, dtype=float)
        way = np.asarray(direction, dtype=float)
        base = self._layer_z if self._layer_z is not None else float(start[2])
        rise = current().servo.blind_rise * self.rho
        if rise <= 0:
            return None
        for height in (base, base + rise, base + 2.0 * rise):
            if abs(height - float(start[2])) < 0.05 * self.rho:
                continue
            with _Look(self, start) as look:
                back = look.go(-way, 2.0 * self.bump, rigid=True)
                if back.event != "none":
                    continue
                dz = height - float(look.here[2])
                if look.go(_Z if dz > 0 else -_Z, abs(dz), rigid=True).event != "none":
                    continue
                m = look.go(way, length + back.distance + self.bump, rigid=True)
                if m.event == "touch" and m.closed:
                    look.legs.clear()  # the finger stays where it touched
                    return m
        return None

    def _retrace(self, pos: FloatArray, legs: list[tuple[FloatArray, float]]) -> FloatArray:
        """Move back along ``legs`` (each the direction back and its length), last first, from
        ``pos``; where the finger ends."""
        here = np.asarray(pos, dtype=float)
        for direction, length in reversed(legs):
            if length > 1e-12:
                here = np.asarray(self._move(here, direction, length).end, dtype=float)
        return here

    def _move_on(self, pos: FloatArray, direction: FloatArray, length: float) -> Motion:
        """Move ``length`` along ``direction`` through losses of contact; stop at anything else."""
        return _through_releases(self._move, pos, direction, length)[0]

    def _top_met(self, pos: FloatArray, f: _Follow) -> bool:
        """Whether the touch just made in a layer followed a direction more than
        :data:`TOP_UNDER_DEG` below the equator: a top lies just under the tip's centre (the
        layer grazes a step, such as a T block's crossbar, by a fraction of a millimetre), and
        following it would trace the top's edges instead of the sides. Its height is kept for
        :meth:`_lower_under_top`, once per exploration."""
        if self._lowered or self._looking_under or self._phase != "layers":
            return False
        if float(f.r0[2]) > -math.sin(math.radians(TOP_UNDER_DEG)):
            return False
        self._top_under = float(pos[2]) + self.rho * float(f.r0[2])
        return True

    def _next_layer_note(self, z: float, step_z: float, topped: bool, blocked: bool) -> str:
        """The note on a layer after ``z`` found by a new approach at ``step_z``: after the
        top was touched first (``topped``), after a blocked slide, or after a z increment
        that lost contact."""
        if topped:
            where = (
                f"{TOP_CLEAR_RHO:g} ρ under the top touched first"
                if step_z < z + self.z_step - 1e-9
                else "found by a new approach after the top was touched first"
            )
            return f"the layer after z = {z:.4f} m runs at {step_z:.4f} m, {where}"
        if blocked:
            return (
                f"the contour at z = {z:.4f} m ended open at a blocked slide: the next plane, "
                f"{step_z:.4f} m, was found by a new approach"
            )
        return (
            f"contact lost after the z increment to {step_z:.4f} m below the top of the visual "
            "estimate: found again by a new approach"
        )

    def _under_touched_top(
        self, z: float, top: float, contacts: list[Contact], *, whole: bool
    ) -> float | None:
        """The height of the layer after ``z`` when it may run over the object's top: the top
        touched first, from above the middle of ``contacts`` (the layer's; or, when a blocked
        slide ended it short of ``whole``, the hint's middle, which the part of a contour
        may lie far from), and the layer :data:`TOP_CLEAR_RHO` × ρ under it; None when the
        next layer lies more than :data:`TOP_NEAR_RHO` × ρ under the hint's ``top`` (the
        visual estimate), or the touch found no top there (once per exploration).

        The hint is a few millimetres loose: on a slab (a phone, a book lying flat) the
        layer one ``z_step`` up may run above the top's edge, and its touches of the edge
        from above tilt the sides' planes by ten degrees and more. A top is where a sensor
        pointing more than :data:`TOP_UNDER_DEG` below the equator closes. The touch gives
        a height, not a contact of the record: one touch from above cannot tell a top from
        an apex (the top phase slides to tell them, and keeps no apex either), and a six-
        sided pyramid's apex kept as a top's contact made it curved. The top phase still
        runs after the layers, over the last contour, whose middle the top's is (a lying
        prism's narrow top is not the lower contour's)."""
        if (
            not self.params.top
            or self._top_touched
            or z + self.z_step <= top - TOP_NEAR_RHO * self.rho
        ):
            return None
        self._top_touched = True
        middle = _centre(contacts) if whole else None
        mid = np.asarray(self.world.hint.centre if middle is None else middle, dtype=float)[:2]
        high = top + self.rho + self.params.approach_margin
        start = (float(mid[0]), float(mid[1]), high)
        if self.finger.nearest((0.0, 0.0, -1.0)) is None or not self.world.workspace.contains(
            start
        ):
            return None
        saved, self._phase = self._phase, "top"  # no contact is recorded: the phase alone
        try:
            m = self._move(start, -_Z, high - self.rho)
        finally:
            self._phase = saved
        f = self._follow(m.closed) if m.event == "touch" else None
        if f is None or float(f.r0[2]) > -math.sin(math.radians(TOP_UNDER_DEG)):
            self._note(f"the touch from above at {_fmt(start)} found no top ({m.event})")
            return None
        height = float(m.end[2]) - self.rho
        self._note(f"the top touched from above at {_fmt(m.end)}: {height:.4f} m high")
        return height - TOP_CLEAR_RHO * self.rho

    def _lower_under_top(self, z: float) -> tuple[FloatArray, _Follow] | None:
        """After a layer at ``z`` that met a top just under the tip (:meth:`_top_met`): the
        first contact of a layer :data:`UNDER_TOP_RHO` × ρ under that top, found by a new
        approach, where the equator meets the step's sides; None when there was no such top,
        the lower layer would graze the table, or the approach finds nothing."""
        top, self._top_under = self._top_under, None
        if top is None:
            return None
        self._lowered = True
        lower = top - UNDER_TOP_RHO * self.rho
        if lower < self.rho + 0.001:
            return None
        found = self._first_contact([lower], quiet=True)
        if found is not None:
            self._note(
                f"the layer at z = {z:.4f} m met a top at {top:.4f} m just under the tip: "
                f"a layer at {lower:.4f} m was contoured under it"
            )
        return found

    def _z_increment(
        self, pos: FloatArray, f: _Follow, centre: FloatArray | None = None
    ) -> tuple[FloatArray, _Follow] | None:
        """Move up by z_step; the first contact of the next layer, or None when contact is lost.

        Contact kept (a vertical surface): go on from there. Contact lost (a surface sloping
        inwards): finish the step, then search horizontally towards ``centre`` (the middle of
        the layer, or along r0). Blocked (a surface overhanging): step away from it, up, and
        search towards ``centre``.
        """
        start_z = float(pos[2])
        m = self._move(pos, _Z, self.z_step)
        pos = np.asarray(m.end, dtype=float)
        if m.event == "none" and f.sensor in m.fired:
            self._phase = "layers"
            nf = _Follow(f.sensor, tuple(s for s in f.group if s in m.fired) or (f.sensor,), f.r0)
            self._record(m, nf, "slide")
            return pos, nf
        if m.event == "touch" and m.distance >= self.z_step - 1e-6:
            nf = self._follow(m.closed)
            self._record(m, nf, "touch")
            return pos, nf
        if m.event == "none" and not m.fired:  # not in contact (the layer ended off a surface)
            return self._regain(pos, f, centre)
        if m.event == "release":
            rest = self.z_step - m.distance
            if rest > 1e-9:
                m = self._move_on(pos, _Z, rest)
                pos = np.asarray(m.end, dtype=float)
                if m.event == "touch" and self.params.comply:
                    # met a little higher: a scan's bump on the face just left, or a surface;
                    # a bump the tip clears by stepping back :attr:`bump` is ridden over
                    past = self._clear_upwards(pos, f, start_z + self.z_step)
                    if past is not None and past.event != "touch":
                        return self._regain(np.asarray(past.end, dtype=float), f, centre)
                    if past is not None:  # the next surface, more than half a step up
                        m, pos = past, np.asarray(past.end, dtype=float)
                if m.event == "touch":
                    nf = self._follow(m.closed)
                    self._record(m, nf, "touch")
                    return pos, nf
                if m.event not in ("none", "release"):
                    self._note(f"the z increment stopped at {_fmt(m.end)} ({m.event}): layers end")
                    return None
            return self._regain(pos, f, centre)
        if m.event in ("blocked", "touch"):
            # the surface overhangs (the tip is stopped, or rolls onto it): clear it (up to 31°
            # of overhang), go up the rest of the step, and search back towards the middle
            away = _unit(np.array([-f.r0[0], -f.r0[1], 0.0]))
            if float(np.linalg.norm(away)) < 1e-9:
                self._note(f"the z increment is blocked at {_fmt(m.end)}: layers end")
                return None
            rest = start_z + self.z_step - float(pos[2])
            for direction, length in ((away, 0.6 * self.z_step + self.rho), (_Z, rest)):
                m = self._move_on(pos, direction, length)
                pos = np.asarray(m.end, dtype=float)
                if m.event not in ("none", "release"):
                    self._note(f"the z increment stopped at {_fmt(m.end)} ({m.event}): layers end")
                    return None
            return self._regain(pos, f, centre)
        self._note(f"the z increment stopped at {_fmt(m.end)} ({m.event}): layers end")
        return None

    def _clear_upwards(self, pos: FloatArray, f: _Follow, z: float) -> Motion | None:
        """After a z increment that lost the face followed by ``f`` met something a little
        higher (at ``pos``), step back from the face by :attr:`bump` and rise on towards the
        height ``z``, through losses of contact. The last motion when the rise went past what
        it met (a bump): free to ``z``, or touching again more than half-way there; else None,
        the finger back at ``pos`` (a surface: an overhang, a step)."""
        away = _unit(np.array([-f.r0[0], -f.r0[1], 0.0]))
        rise = z - float(pos[2])
        legs: list[tuple[FloatArray, float]] = []
        here = np.asarray(pos, dtype=float)
        for leg, (direction, length) in enumerate(((away, self.bump), (_Z, rise))):
            m = self._move_on(here, direction, max(length, 0.0))
            legs.append((-direction, m.distance))
            here = np.asarray(m.end, dtype=float)
            if m.event in ("none", "release"):
                continue
            if leg == 1 and m.event == "touch" and m.distance > 0.5 * rise:
                return m
            self._retrace(here, legs)
            return None
        return m

    def _regain(
        self, pos: FloatArray, f: _Follow, centre: FloatArray | None
    ) -> tuple[FloatArray, _Follow] | None:
        """Search horizontally for the object after a z increment: towards ``centre`` or r0."""
        towards = _unit(np.array([f.r0[0], f.r0[1], 0.0]))
        if centre is not None:
            to_centre = np.array([centre[0] - pos[0], centre[1] - pos[1], 0.0])
            if float(np.linalg.norm(to_centre)) > 1e-6:
                towards = _unit(to_centre)
        if float(np.linalg.norm(towards)) < 1e-9:
            return None
        m = self._move(pos, towards, self.reach)
        pos = np.asarray(m.end, dtype=float)
        if m.event == "touch":
            nf = self._follow(m.closed)
            self._record(m, nf, "touch")
            return pos, nf
        self._note(f"contact not kept after the z increment to {pos[2]:.4f} m: layers end")
        return None

    def _narrow(self, contacts: list[Contact], below: list[Contact]) -> bool:
        """Whether a layer's contour is narrower than the tip's diameter (beyond the tip centres'
        offset ρ) and under 60 % of the layer below it: it ran round an apex, not faces."""
        if not below:
            return False
        if len(contacts) < 3:
            return True
        size, size_below = _radius(contacts), _radius(below)
        return size - self.rho < 2.0 * self.rho and size < 0.6 * size_below

    def _finish_layer(self, index: int, z: float, path: list[Vec3], closed: bool) -> None:
        # the controller computes no geometry: the model traces contours from the contacts
        self.layers.append(Layer(index=index, z=float(z), path=list(path), closed=closed))


class _SideProbes:
    """The probe phase: every surface that only one layer slid along (narrow there, or skipped
    by a search cycle) is touched once more at another height, approached along its normal
    from outside the object, so that every face has tip centres at two heights."""

    def __init__(self, controller: Controller) -> None:
        self._c = controller

    def run(self, centre: FloatArray | None) -> None:
        """Touch every surface slid along in one layer only once more, at another height."""
        c = self._c
        heights = sorted(set(c._heights))
        if len(heights) < 2 or centre is None:
            return
        seen: dict[frozenset[int], list[tuple[float, _Segment]]] = {}
        for z, seg in c._surfaces:
            seen.setdefault(seg.group, []).append((z, seg))
        for found in seen.values():
            zs = {z for z, _ in found}
            if len(zs) > 1:
                continue
            z0 = zs.pop()
            segs = [g for _, g in found]
            seg = max(segs, key=lambda g: g.length)
            out = np.array([-seg.r0[0], -seg.r0[1], 0.0])
            if float(np.linalg.norm(out)) < 0.3:  # a top or a bottom: not for a horizontal probe
                continue
            # the surface's stretch in that layer, from every tip centre on it: aim at 30 % of it
            # and slide across the rest (it may be narrower at the other height)
            ends = np.asarray(
                [p for g in segs for p in (g.start, g.start + g.length * g.direction)]
            )
            along = (ends - seg.start) @ seg.direction
            aim = seg.start + (0.7 * along.min() + 0.3 * along.max()) * seg.direction
            z1 = min((z for z in heights if z != z0), key=lambda z: abs(z - z0))
            z = z0 + 0.6 * (z1 - z0)
            if not self._one(aim, _unit(out), z, centre, seg.group):
                return

    def _one(
        self, aim: FloatArray, out: FloatArray, z: float, centre: FloatArray, group: frozenset[int]
    ) -> bool:
        """Approach a surface at height ``z`` along its outward normal ``out``, from outside the
        hint box, towards the point ``aim`` of its stretch in a layer, and slide along it;
        False when the way there is blocked (no more probes).

        The touch is kept when it fired the surface's own sensors (``group``), even if the
        surface is too narrow there to slide far; otherwise it must slide like a surface.
        """
        c = self._c
        hint = c.world.hint
        lo, hi = np.asarray(hint.lo, dtype=float), np.asarray(hint.hi, dtype=float)
        clear = c.rho + c.params.approach_margin
        # the way out: away from the middle of the object, then up over it, then down outside it
        here = np.asarray(c._last_pos, dtype=float)
        away = _unit(np.array([here[0] - centre[0], here[1] - centre[1], 0.0]))
        target = np.array([aim[0], aim[1], z])
        far = target + out * (_exit(target, out, lo, hi) + clear)
        safe = float(hi[2]) + clear
        legs: list[tuple[FloatArray, float]] = []
        if float(np.linalg.norm(away)) > 0.5:
            legs.append((away, _exit(here, away, lo, hi) + clear))
        for leg_dir, length in legs:
            m = c._move(here, leg_dir, length)
            here = np.asarray(m.end, dtype=float)
            if m.event in ("touch", "blocked"):
                c._note(f"the way to a probe is blocked at {_fmt(m.end)}")
                return False
        for goal in (
            np.array([here[0], here[1], safe]),
            np.array([far[0], far[1], safe]),
            far,
        ):
            d = goal - here
            length = float(np.linalg.norm(d))
            if length < 1e-9:
                continue
            m = c._move_on(here, d / length, length)
            here = np.asarray(m.end, dtype=float)
            if m.event not in ("none", "release"):
                c._note(f"the way to a probe is blocked at {_fmt(m.end)} ({m.event})")
                return False
        m = c._move(here, -out, float(np.linalg.norm(far - target)) + c.params.l2)
        if m.event != "touch":
            c._note(f"a probe at z = {z:.4f} m found nothing ({m.event})")
            return True
        f = c._follow(m.closed)
        first = len(c.contacts)
        c._record(m, f, "touch")
        t = c._tangent(f)
        if t is None:
            return True
        sm, travelled = c._slide_sampled(np.asarray(m.end, dtype=float), t, f, c.reach)
        same = frozenset(m.closed) == group
        if not same and travelled < c.edge_slide and c._rolled(sm, f):
            del c.contacts[first:]  # an edge, not the surface
            return True
        if travelled > 1e-6:
            c._record(sm, f, "slide")
        return True


class _TopPhase:
    """The top phase: tops, which contouring in horizontal planes cannot touch, are explored
    from above over the middle of the last contour."""

    def __init__(self, controller: Controller) -> None:
        self._c = controller
        self._rough = False
        self._seats = 0
        self._down = 0

    def _follow_down(self, m: Motion) -> _Follow:
        """Follow the sensor pointing down, among the sensors ``m`` closed: the top's, where
        the others are a rough top's."""
        c = self._c
        return _Follow(self._down, tuple(sorted(m.closed)), c._dirs[self._down].copy())

    def run(self, contacts: list[Contact]) -> None:
        """Approach from above over the middle of the last contour; slide round a diamond on it.

        The diamond's corners lie on the contour's principal axes at ``top_spread`` × its
        half-widths, so that the tip centres on the top span it; then round a wider one
        (``top_outer``), kept only when it closes on the top without riding over anything
        (on a rough top: with its tip centres on the first diamond's plane within
        :attr:`bump`). A touch that cannot slide (an apex or an edge) is noted and not
        recorded as a plane. On a scan's rough top (the touch closes more than the sensor
        pointing down, on a surface the contours rode over at least :data:`ROUGH_RIDES`
        times) that sensor is followed, the tip seated first (:meth:`_seat`) when it did not
        close.
        """
        c = self._c
        if c.finger.nearest((0.0, 0.0, -1.0)) is None:
            c._note("no sensor points down: tops are not explored")
            return
        if len(contacts) < 2:
            return
        xy = np.asarray([c.centre[:2] for c in contacts], dtype=float)
        mid = xy.mean(axis=0)
        _, _, vt = np.linalg.svd(xy - mid, full_matrices=False)
        half = np.abs((xy - mid) @ vt.T).max(axis=0) - c.rho
        reach = np.maximum(c.params.top_spread * half, 0.001)
        top = float(c.world.hint.hi[2]) + c.rho + c.params.approach_margin
        start = (float(mid[0]), float(mid[1]), top)
        if not c.world.workspace.contains(start):
            return
        m = c._move(start, -_Z, top - c.rho)
        if m.event != "touch":
            c._note(f"the approach from above at {_fmt(start)} found nothing ({m.event})")
            return
        a1 = np.array([vt[0, 0], vt[0, 1], 0.0])
        a2 = np.array([vt[1, 0], vt[1, 1], 0.0])
        r1, r2 = float(reach[0]), float(reach[1])
        mid3 = np.array([mid[0], mid[1], 0.0])
        inner = [mid3 + d for d in (a1 * r1, a2 * r2, -a1 * r1, -a2 * r2)]
        self._down = down = int(np.argmax(c._dirs @ -_Z))
        f = c._follow(m.closed)
        # a scan's rough top: the tip rests on a few high points, and the sensors that close
        # are the roughness's; a finger under force control seats itself on the top
        self._rough = c.params.comply and set(m.closed) != {down} and c.rides >= ROUGH_RIDES
        if self._rough and down not in m.closed:
            here = np.asarray(m.end, dtype=float)
            seated = self._seat(here, inner[0] - here, (0.5 * c.rho, c.rho, 1.5 * c.rho))
            if seated is not None:
                m = seated
                f = c._follow(m.closed)
        if self._rough and down in m.closed:
            # the sensor pointing down is the top's: follow it (a tilted one, the roughness's,
            # loses the top at the first slide)
            f = self._follow_down(m)
        first = len(c.contacts)
        c._record(m, f, "touch")
        pos = np.asarray(m.end, dtype=float)
        # the first diamond lies inside the top whenever its corners do (the top is convex)
        rides0 = c.rides
        moved, at = self._diamond(pos, f, inner, rides0)
        if at is not None and c.params.top_outer is not None and _spans(c.contacts[first:], c.rho):
            # the wider diamond, led out from the first one's corner on a1 (where the tip is)
            # to its own: each corner top_outer of the way from the middle to where the
            # contour's tip centres, less ρ, lie along that axis (a box's top is its contour)
            reach_out = _ray_extents(xy, mid, [a1[:2], a2[:2], -a1[:2], -a2[:2]])
            if reach_out is not None:
                outer = [
                    mid3 + a * (c.params.top_outer * max(float(t) - c.rho, 0.0))
                    for a, t in zip((a1, a2, -a1, -a2), reach_out, strict=True)
                ]
                kept, rides = len(c.contacts), c.rides + self._seats
                closed = self._diamond(at, f, outer, rides0)[1] is not None
                if not closed or (
                    c.rides + self._seats > rides
                    and not (
                        self._rough and _on_plane(c.contacts[first:kept], c.contacts[kept:], c.bump)
                    )
                ):
                    # it left the top (a frustum's smaller one), or rode over its sensors'
                    # turn (a lying cylinder's ridge curving away): only a whole diamond slid
                    # with the one sensor is known to lie on one flat top; on a rough top,
                    # one whose tip centres stay on the first diamond's plane within a bump
                    del c.contacts[kept:]
        if moved < c.edge_slide:
            del c.contacts[first:]
            c._note(f"the touch from above at {_fmt(m.end)} is an apex or an edge: not a plane")

    def _seat(self, pos: FloatArray, toward: FloatArray, steps: Sequence[float]) -> Motion | None:
        """Seat the tip on a scan's rough top, as a finger under force control settles on it.

        On a rough top the tip rests on a few high points, and the sensors that close are
        the roughness's, turned from straight down; a tilted one, followed, loses the top at
        the first slide. From ``pos`` the tip lifts by :attr:`bump` (twice that when something
        blocks the step: a letter, a bump), steps each of ``steps`` along ``toward``
        (horizontal) and presses down again, each time from ``pos``: the first press that
        closes the sensor pointing down is returned, the tip there. None
        when none does (an apex, an edge, a slanted face, where a smaller top ended), the tip
        back at ``pos``."""
        c = self._c
        u = np.array([toward[0], toward[1], 0.0])
        size = float(np.linalg.norm(u))
        if size < 1e-9:
            return None
        u /= size
        base = np.asarray(pos, dtype=float)
        for k in steps:
            for lift in (c.bump, 2.0 * c.bump):  # a letter or a bump in the way: lift more
                here = base
                legs: list[tuple[FloatArray, float]] = []
                up = c._move_on(here, _Z, lift)
                legs.append((-_Z, up.distance))
                here = np.asarray(up.end, dtype=float)
                blocked = up.event not in ("none", "release")
                if not blocked:
                    step = c._move(here, u, k)
                    legs.append((-u, step.distance))
                    here = np.asarray(step.end, dtype=float)
                    blocked = step.event != "none"
                    if not blocked:
                        press = c._move(here, -_Z, lift + c.bump)
                        if press.event == "touch" and self._down in press.closed:
                            return press
                        legs.append((_Z, press.distance))
                        here = np.asarray(press.end, dtype=float)
                c._retrace(here, legs)
                if not blocked:
                    break
        return None

    def _diamond(
        self, pos: FloatArray, f: _Follow, corners: list[FloatArray], rides: int
    ) -> tuple[float, FloatArray | None]:
        """From ``pos``, slide straight to the first of the diamond's ``corners`` (their z
        ignored: the slides follow the top), then round the diamond back to it. Returns the
        distance slid and where the tip is when the diamond closed, None when a slide ended
        early (the top ended, or an obstacle).

        On a rough top (the touch from above closed more than the sensor pointing down on a
        surface ridden over, or a slide rode over something since ``rides``), a slide that
        ends early is not yet the top's end: the tip seats itself again ρ/2, ρ or 3ρ/2
        further on (:meth:`_seat`, no further than the corner), follows the sensor pointing
        down from there and slides on, to the next corner once a seat leaves it near this one
        or no nearer (:data:`CORNER_RHO`). Where a smaller top ends, the press meets its slanted
        side or nothing, and the diamond ends there."""
        c = self._c
        ring = [*corners, corners[0]]
        lead = ring[0] - pos
        lead[2] = 0.0
        legs = [(lead, float(np.linalg.norm(lead)), ring[0])]
        legs += [(b - a, float(np.linalg.norm(b - a)), b) for a, b in itertools.pairwise(ring)]
        moved = 0.0
        for direction, length, corner in legs:
            u = _unit(direction)
            left = length
            while left > 1e-9:
                before = left
                sm, travelled = c._slide_sampled(pos, u, f, left)
                moved += travelled
                left -= travelled
                pos = np.asarray(sm.end, dtype=float)
                if travelled > 1e-6:
                    c._record(sm, f, "slide")
                if sm.event == "none":
                    break
                if not (self._rough or c.rides > rides or self._seats):
                    return moved, None
                steps = sorted({min(k * c.rho, left) for k in (0.5, 1.0, 1.5)})
                seated = self._seat(pos, u, steps)
                if seated is None:
                    return moved, None
                self._seats += 1
                nf = self._follow_down(seated)
                f.sensor, f.group, f.r0 = nf.sensor, nf.group, nf.r0
                c._record(seated, f, "slide")
                # the hop is not slid: a tip seated again and again round an apex slides
                # nowhere, and is still an apex's touch
                pos = np.asarray(seated.end, dtype=float)
                # on for the rest of the leg, aimed at its corner again (the seat and the
                # rides before it may have turned the tip a little off the leg's line)
                ahead = np.array([corner[0] - pos[0], corner[1] - pos[1], 0.0])
                left = float(np.linalg.norm(ahead))
                if left <= CORNER_RHO * c.rho or left >= before:
                    break  # at the corner, or no nearer: on to the next one from here
                u = ahead / left
        return moved, pos


CORNER_RHO = 0.1
"""Tip radii: a rough top's diamond (:meth:`_TopPhase._diamond`) has reached a corner when a
seat leaves the tip this near it, or no nearer than the slide before it did (else a tip that
drifts by a hundredth of a millimetre each way at a corner is seated there again and again);
it goes on to the next corner from there."""

ROUGH_RIDES = 3
"""A top is taken for a scan's rough one (:class:`_TopPhase` seats the tip on it) when the
touch from above closes more than the sensor pointing down and the contours before it rode
over at least this many irregularities: an ideal solid's contours ride over none, or over a
facet or two of a curved one, and its tops are explored as the paper's rules say."""


def _on_plane(inner: Sequence[Contact], outer: Sequence[Contact], tol: float) -> bool:
    """The tip centres of ``outer`` lie within ``tol`` of the plane fitted (least squares)
    through those of ``inner``: a rough top's wider diamond stayed on the first one's plane,
    where a ridge curving away falls below it by its sagitta."""
    if len(inner) < 3 or not outer:
        return not outer
    a = np.asarray([x.centre for x in inner], dtype=float)
    b = np.asarray([x.centre for x in outer], dtype=float)
    mid = a.mean(axis=0)
    normal = np.linalg.svd(a - mid, full_matrices=False)[2][2]
    return bool((np.abs((b - mid) @ normal) <= tol).all())


def _spans(contacts: Sequence[Contact], rho: float) -> bool:
    """The tip centres of ``contacts`` spread across their main line by at least ρ/2 (RMS):
    they span a flat top, not a ridge (a lying cylinder's, which the diamond's slides
    across do not leave)."""
    if len(contacts) < 3:
        return False
    xyz = np.asarray([x.centre for x in contacts], dtype=float)
    s = np.linalg.svd(xyz - xyz.mean(axis=0), compute_uv=False)
    return bool(s[1] / math.sqrt(len(xyz)) >= 0.5 * rho)


def _ray_extents(
    points: FloatArray, origin: FloatArray, directions: Sequence[FloatArray]
) -> list[float] | None:
    """How far from ``origin`` each ray along ``directions`` (unit, 2-D) leaves the convex
    hull of the 2-D ``points``; None when they span no polygon."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        return None
    normals, offsets = hull.equations[:, :2], -hull.equations[:, 2]  # normal · x ≤ offset
    room = offsets - normals @ origin
    if (room <= 0).any():
        return None  # the origin is not inside
    out = []
    for d in directions:
        rate = normals @ d
        ahead = rate > 1e-12
        out.append(float((room[ahead] / rate[ahead]).min()) if ahead.any() else 0.0)
    return out


class _Look:
    """Motions away from where a contour stands, gone back in reverse at the end (a
    ``with`` block): a look into an opening (:meth:`Controller._rise`,
    :meth:`Controller._under_edge`) leaves the contour where it was, its motions outside the
    contour's budget, and no blind contacts of its own."""

    def __init__(self, controller: Controller, start: FloatArray) -> None:
        self.c = controller
        self.here = np.asarray(start, dtype=float)
        self.legs: list[tuple[FloatArray, float]] = []  # (the way back, its length)
        self.budget = controller._layer_motions

    def __enter__(self) -> _Look:
        self.c._looking_under = True
        return self

    def __exit__(self, *exc: object) -> None:
        for direction, length in reversed(self.legs):
            if length > 1e-12:
                self.here = np.asarray(self.c._move(self.here, direction, length).end, dtype=float)
        self.c._looking_under = False
        self.c._layer_motions = self.budget

    def go(self, direction: FloatArray, length: float, *, rigid: bool = False) -> Motion:
        """Move (``rigid``: stop at any event; else through losses of contact)."""
        m = (self.c._move if rigid else self.c._move_on)(self.here, direction, length)
        self.legs.append((-direction, m.distance))
        self.here = np.asarray(m.end, dtype=float)
        return m

    def found(self, hit: Motion, along: FloatArray | None) -> None:
        """Record the surface inside the opening that the last leg, ``hit``, touched; slide up to
        ρ ``along`` it, recording the tip centres; step off it back along the way there."""
        c = self.c
        at = len(self.legs) - 1
        wall = c._follow(hit.closed)
        c.openings += 1
        c._record(hit, wall, "touch")
        start = self.here
        while along is not None and float(np.linalg.norm(self.here - start)) < c.rho - 1e-9:
            piece = min(c.spacing, c.rho - float(np.linalg.norm(self.here - start)))
            run = c._slide(self.here, along, piece, wall.sensor)
            moved = run.distance > 1e-9
            self.here = np.asarray(run.end, dtype=float)
            if run.event != "none" or not moved:
                break
            c._record(run, wall, "slide")
        back, length = self.legs[at]
        off = c._move(self.here, back, c.bump)
        self.here = np.asarray(off.end, dtype=float)
        self.legs[at] = (back, max(0.0, length - off.distance))
        slid = np.asarray(off.start, dtype=float) - start  # undone first, off the surface
        length = float(np.linalg.norm(slid))
        if length > 1e-12:
            self.legs.append((-slid / length, length))


@dataclass
class _Turning:
    """How far a layer's contour has turned: the sum of the changes of heading between its
    successive tip centres (x–y) at least ``least`` apart, each taken within ±180°; 2π once
    round an object counter-clockwise (a search cycle's detour, out and back, adds nothing)."""

    last: FloatArray
    least: float
    heading: float | None = None
    total: float = 0.0

    def add(self, centre: Sequence[float]) -> None:
        here = np.asarray(centre[:2], dtype=float)
        d = here - self.last
        if float(np.hypot(d[0], d[1])) < self.least:
            return
        heading = math.atan2(float(d[1]), float(d[0]))
        if self.heading is not None:
            self.total += (heading - self.heading + math.pi) % (2.0 * math.pi) - math.pi
        self.heading, self.last = heading, here


@dataclass
class _Segment:
    """A surface slid along in a layer: its sensors, where the slide began, its direction."""

    group: frozenset[int]
    start: FloatArray
    direction: FloatArray
    length: float
    r0: FloatArray
    edge: bool = False

    def place(self, pos: FloatArray, *, flat: bool = False) -> tuple[float, float]:
        """Where ``pos`` lies from the segment's line: how far along it from :attr:`start`, and
        how far off it (``flat``: in x–y only)."""
        d = np.asarray(pos, dtype=float) - np.asarray(self.start, dtype=float)
        u = np.asarray(self.direction, dtype=float)
        if flat:
            d, u = d[:2], u[:2]
        along = float(d @ u)
        return along, float(np.linalg.norm(d - along * u))


@dataclass
class _EdgeTouches:
    """The verdicts on a layer's touches: edges (to drop) or surfaces.

    Edge touches are dropped once a touch turns out to be a surface, unless they came in a run
    of :data:`CURVED_RUN` or more: a curved surface is all edges to a sliding tip, and is kept.
    """

    run: list[tuple[int, _Segment | None]] = field(default_factory=list)
    dropped: list[int] = field(default_factory=list)

    def edge(self, index: int, segment: _Segment | None) -> None:
        self.run.append((index, segment))
        curved = len(self.run) >= current().servo.curved_run
        for _, seg in self.run:
            if seg is not None:
                seg.edge = not curved

    def surface(self) -> None:
        if len(self.run) < current().servo.curved_run:
            self.dropped += [index for index, _ in self.run]
        self.run = []

    def final(self) -> list[int]:
        """The indices of the contacts to drop (the layer is over)."""
        self.surface()
        return self.dropped


def _surfaces(segs: list[_Segment]) -> list[_Segment]:
    """The segments of a layer that slid along surfaces (not edges)."""
    return [g for g in segs if not g.edge]


def _exit(point: FloatArray, direction: FloatArray, lo: FloatArray, hi: FloatArray) -> float:
    """How far from ``point`` along horizontal unit ``direction`` the box ``lo``–``hi`` ends (x, y)."""
    t = math.inf
    for k in range(2):
        if direction[k] > 1e-12:
            t = min(t, (hi[k] - point[k]) / direction[k])
        elif direction[k] < -1e-12:
            t = min(t, (lo[k] - point[k]) / direction[k])
    return max(t, 0.0) if math.isfinite(t) else 0.0


def _chord(start: FloatArray, end: FloatArray, least: float, fallback: Vec3) -> FloatArray:
    """The horizontal unit direction from ``start`` to ``end`` when they lie at least ``least``
    apart (a slide's mean direction over an irregular surface), else ``fallback``."""
    chord = np.array([end[0] - start[0], end[1] - start[1], 0.0])
    if float(np.linalg.norm(chord)) >= least:
        return _unit(chord)
    return np.asarray(fallback, dtype=float)


def _radius(contacts: Sequence[Contact]) -> float:
    """Mean horizontal distance of the contacts' tip centres from their mean."""
    xy = np.asarray([c.centre[:2] for c in contacts], dtype=float)
    return float(np.linalg.norm(xy - xy.mean(axis=0), axis=1).mean())


def _centre(contacts: Sequence[Contact]) -> FloatArray | None:
    """The mean tip centre of ``contacts`` (None without any)."""
    if not contacts:
        return None
    centre: FloatArray = np.asarray([c.centre for c in contacts], dtype=float).mean(axis=0)
    return centre


def _line_exit(
    point: FloatArray, direction: FloatArray, lo: FloatArray, hi: FloatArray
) -> float | None:
    """The largest t with ``point + t · direction`` inside the box [``lo``, ``hi``], or None
    when the line misses the box."""
    enter, leave = -math.inf, math.inf
    for k in range(3):
        if abs(float(direction[k])) < 1e-12:
            if not float(lo[k]) <= float(point[k]) <= float(hi[k]):
                return None
            continue
        a = (float(lo[k]) - float(point[k])) / float(direction[k])
        b = (float(hi[k]) - float(point[k])) / float(direction[k])
        enter, leave = max(enter, min(a, b)), min(leave, max(a, b))
    return leave if enter <= leave and math.isfinite(leave) else None


def _fmt(p: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v:.4f}" for v in p) + ")"
