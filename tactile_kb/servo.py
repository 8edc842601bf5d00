"""The servo logic of the exploring finger (the paper's "Tactile Exploration", Fig. 1 and Fig. 2).

:class:`Controller` decides every motion from the sensors alone and drives any
:class:`~tactile_kb.world.World`; it never knows which world it is in. The rules:

* **Contour following.** While a sensor is ON the finger moves along the plane tangential at
  the contact, parallel to x–y, in the sense associated with that sensor (the object on the
  left, i.e. counter-clockwise seen from above: the direction ẑ × n for the outward normal
  n = −r0). The motion is a compliant :meth:`~tactile_kb.world.World.slide`.
* **Block E, gate 1 (block N).** A sensor passing OFF→ON inhibits the commands of every other
  ON sensor: the finger follows the *last sensor that closed*. A sensor of another surface
  opening meanwhile does not interrupt the slide.
* **The search cycle** (monostables M1, M2, M3). On ON→OFF of the followed sensor the finger
  continues ``l1`` in the previous direction, then searches ``l2`` orthogonally towards the
  object, then ``l3`` orthogonally to ``l2`` (back). A contact during the cycle stops it
  (gates 1–3) and is followed. Blocks C and D: the end of ``l2`` or ``l3`` never starts a new
  cycle. If the cycle ends without contact, the object has at least one dimension smaller
  than ``l2``: the layer ends with that note.
* **z increments.** When the first contact of a layer is met a second time (the same sensor
  on the same surface, reached by sliding back to the first contact point), the finger moves
  up by ``z_step`` and explores the new plane z = const. The increments end when contact is
  no longer kept after one — unless a short horizontal search towards the object regains it
  (a face sloping inwards, as on a pyramid, loses contact on every step).
* **Other planes.** Tops and faces sloping away, which contouring in horizontal planes cannot
  touch, are explored from above: a vertical approach over the middle of the last contour,
  then two short orthogonal slides on what was touched (three non-collinear tip centres per
  face). A touch that cannot slide (an apex or an edge) is noted and not recorded as a plane.

Contacts: a ``"touch"`` contact on every OFF→ON of the followed sensor and a ``"slide"`` contact
at the end of every tangential move (several tip centres per face, over the layers, so that
face normals can be refined by fitting them). ``r0`` is the followed sensor's direction or,
when neighbouring sensors with overlapping cones closed together with it, the normalised mean
of their directions.

Examples
--------
>>> p = ServoParams()
>>> p.l1, p.l2, p.l3
(0.008, 0.01, 0.016)
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from tactile_kb.errors import ExplorationError, UsageError
from tactile_kb.record import Contact, ExplorationRecord, Layer
from tactile_kb.world import Motion, Vec3, World

__all__ = ["Controller", "Mark", "ServoParams"]

Mark = Literal["contact", "layer", "complete"]
"""What :meth:`Controller.run` yields: the first touch, a finished layer, the end."""

FArray = NDArray[np.float64]

_Z = np.array([0.0, 0.0, 1.0])


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
        The fixed z increment between layers; ``None``: 0.45 × the height of the world's
        visual hint (two layers on most objects).
    z_first
        Height of the first layer (tip centre); ``None``: 0.3 × the hint's height, at least
        ρ + 1 mm.
    top
        Explore tops from above after the layers.
    top_slide
        Least length of the two slides that check a touch from above (they also reach 0.3 of
        the last contour's width); ``None``: ``l1``.
    approach_margin
        Free space kept outside the hint box when approaching.
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
    top: bool = True
    top_slide: float | None = None
    approach_margin: float = 0.01
    max_motions: int = 3000
    max_layer_motions: int = 400
    max_layers: int = 40

    def __post_init__(self) -> None:
        for name in ("l1", "l2", "l3", "approach_margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise UsageError(f"servo parameter {name} must be > 0 metres, got {v}")
        for name in ("z_step", "z_first", "top_slide"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise UsageError(f"servo parameter {name} must be > 0 metres or None, got {v}")
        for name in ("max_motions", "max_layer_motions", "max_layers"):
            if getattr(self, name) < 1:
                raise UsageError(f"servo parameter {name} must be ≥ 1")


class _Budget(Exception):
    pass


@dataclass
class _Follow:
    """The contact being followed: the sensor, the sensors that closed with it, r0."""

    sensor: int
    group: tuple[int, ...]
    r0: FArray = field(default_factory=lambda: np.zeros(3))


def _v3(a: Sequence[float] | FArray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def _unit(v: FArray) -> FArray:
    n = float(np.linalg.norm(v))
    return v / n if n > 1e-12 else v


class Controller:
    """The exploration controller for one object in one :class:`~tactile_kb.world.World`.

    Parameters
    ----------
    world
        The world to explore (any implementation of the protocol).
    params
        The servo parameters.
    explorer, object_name, seed, extra_params
        Copied into the record.
    """

    def __init__(
        self,
        world: World,
        params: ServoParams | None = None,
        *,
        explorer: str = "",
        object_name: str = "",
        seed: int | None = None,
        extra_params: dict[str, float] | None = None,
    ) -> None:
        self.world = world
        self.params = params or ServoParams()
        self.explorer = explorer
        self.object_name = object_name
        self.seed = seed
        self.extra_params = dict(extra_params or {})
        self.finger = world.finger
        self.rho = float(self.finger.radius)
        self._dirs = self.finger.matrix
        hint = world.hint
        height = max(float(hint.hi[2]), 2.0 * self.rho)
        self.z_step = self.params.z_step or max(0.45 * height, 0.5 * self.rho)
        self.z_first = self.params.z_first or max(0.3 * height, self.rho + 0.001)
        self.top_slide = self.params.top_slide or self.params.l1
        size = hint.size
        self.reach = float(
            math.hypot(size[0], size[1]) + 2 * (self.rho + self.params.approach_margin)
        )
        self.contacts: list[Contact] = []
        self.path: list[Vec3] = []
        self.layers: list[Layer] = []
        self.notes: list[str] = []
        self.motions = 0
        self._layer_motions = 0
        self._phase = "first-contact"
        self._layer: int | None = None
        self._last_pos: Vec3 | None = None

    # bookkeeping -----------------------------------------------------------------------------
    def _note(self, text: str) -> None:
        if text not in self.notes:
            self.notes.append(text)

    def _track(self, m: Motion) -> Motion:
        self.motions += 1
        self._layer_motions += 1
        if self._last_pos is None or m.start != self._last_pos:
            self.path.append(m.start)
        self.path.append(m.measured)
        self._last_pos = m.end
        if self.motions >= self.params.max_motions:
            raise _Budget(f"motion budget of {self.params.max_motions} exhausted")
        return m

    def _move(self, start: FArray | Vec3, direction: FArray | Vec3, length: float) -> Motion:
        return self._track(self.world.move(_v3(start), _v3(direction), float(length)))

    def _slide(self, start: FArray | Vec3, direction: FArray, length: float, sensor: int) -> Motion:
        return self._track(self.world.slide(_v3(start), _v3(direction), float(length), sensor))

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
        )
        self.contacts.append(c)
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
        params.update(z_step=self.z_step, z_first=self.z_first, top_slide=self.top_slide)
        params.update(self.extra_params)
        return ExplorationRecord(
            object=self.object_name,
            explorer=self.explorer,
            finger=self.finger.name,
            tip_radius=self.rho,
            sensor_directions=list(self.finger.directions),
            seed=self.seed,
            params=params,
            contacts=list(self.contacts),
            path=list(self.path),
            layers=list(self.layers),
            contacts_per_phase=per_phase,
            complete=complete,
            notes=list(self.notes),
        )

    # the exploration ---------------------------------------------------------------------------
    def run(self) -> Iterator[Mark]:
        """Explore step by step; yield ``"contact"`` at the first touch, ``"layer"`` after each
        layer, ``"complete"`` at the end (then stop)."""
        try:
            pos, follow = self._first_contact()
            yield "contact"
            self._phase = "layers"
            last_path: list[Vec3] = []
            z = float(pos[2])
            index = 0
            while index < self.params.max_layers:
                self._layer = index
                # the contact that starts the layer belongs to it
                self.contacts[-1] = self.contacts[-1].model_copy(update={"layer": index})
                self._layer_motions = 0
                start_path = len(self.path)
                start_contacts = len(self.contacts) - 1
                closed, pos, follow = self._contour(pos, follow)
                layer_path = self.path[start_path - 1 if start_path else 0 :]
                self._finish_layer(index, z, layer_path, start_contacts, closed)
                last_path = layer_path
                yield "layer"
                if not closed:
                    break
                nxt = self._z_increment(pos, follow)
                if nxt is None:
                    break
                pos, follow = nxt
                z = float(pos[2])
                index += 1
            else:
                self._note(f"stopped after {self.params.max_layers} layers")
            self._layer = None
            if self.params.top:
                self._phase = "top"
                self._top(last_path)
        except _Budget as exc:
            self._note(str(exc))
        yield "complete"

    def _first_contact(self) -> tuple[FArray, _Follow]:
        """Approach the object horizontally (+x) on lines across the hint until a sensor closes."""
        hint = self.world.hint
        gap = self.rho + self.params.approach_margin
        x0 = float(hint.lo[0]) - gap
        length = float(hint.size[0]) + 2 * gap
        yc, qy = float(hint.centre[1]), float(hint.size[1]) / 6.0
        ys = [yc + k * qy for k in (0.1, 1.1, -0.9, 2.1, -1.9)]
        heights = [self.z_first]
        while heights[-1] + self.z_step < float(hint.hi[2]):
            heights.append(heights[-1] + self.z_step)
        for z in heights:
            for y in ys:
                start = (x0, y, z)
                if not self.world.workspace.contains(start):
                    continue
                m = self._move(start, (1.0, 0.0, 0.0), length)
                if m.event == "touch":
                    f = self._follow(m.closed)
                    self._record(m, f, "touch")
                    return np.asarray(m.end, dtype=float), f
                if m.event == "blocked":
                    self._note(f"blind contact (no sensor fired) at {_fmt(m.end)}")
        raise ExplorationError(
            f"the finger never touched the object ({len(heights) * len(ys)} approaches along +x "
            f"at heights {', '.join(f'{h:.3f}' for h in heights)} m)"
        )

    def _tangent(self, f: _Follow) -> FArray | None:
        """The horizontal direction associated with the followed contact (object on the left)."""
        n = -f.r0
        t = np.cross(_Z, n)
        norm = float(np.linalg.norm(t))
        if norm < 1e-6:
            return None
        return t / norm

    def _contour(self, pos: FArray, f: _Follow) -> tuple[bool, FArray, _Follow]:
        """Follow the contour in the current plane z = const; return (closed, position, follow)."""
        p = self.params
        first_c = np.asarray(pos, dtype=float)
        first_group = set(f.group)
        first_dir: FArray | None = None
        touches = 0
        other_seen = False
        followed: list[
            tuple[frozenset[int], FArray, FArray, float]
        ] = []  # group, start, dir, length
        while self._layer_motions < p.max_layer_motions:
            t = self._tangent(f)
            if t is None:
                self._note("a horizontal surface met while contouring; contour stopped")
                return False, pos, f
            direction, length, closing = t, self.reach, False
            if not set(f.group) & first_group:
                other_seen = True
            if other_seen and first_dir is not None and set(f.group) & first_group:
                # the first contact met a second time? slide back to the first contact point
                d = first_c - pos
                s = float(d @ first_dir)
                off = float(np.linalg.norm(d - s * first_dir))
                if off <= max(0.002, 0.2 * self.rho) and s >= -(p.l3 + self.rho):
                    if s < 0:
                        self._record_here(pos, f)
                        return True, pos, f
                    direction, length, closing = first_dir, s, True
            if not closing and self._back_on(followed, pos, f):
                # the contour is back on a surface it already followed: the layer is closed
                return True, pos, f
            m = self._slide(pos, direction, length, f.sensor)
            if first_dir is None:
                first_dir = np.asarray(m.direction, dtype=float)
            pos = np.asarray(m.end, dtype=float)
            if closing and m.event == "none":
                self._record(m, f, "slide")
                return True, pos, f
            if m.distance > 0:
                followed.append(
                    (
                        frozenset(f.group),
                        np.asarray(m.start, dtype=float),
                        np.asarray(m.direction, dtype=float),
                        m.distance,
                    )
                )
            f, touches, done = self._after_slide(m, f, touches)
            if done is not None:
                return done, pos, f
            if m.event == "release" and f.sensor not in m.fired:
                found = self._search(pos, np.asarray(m.direction, dtype=float), f)
                if found is None:
                    return False, np.asarray(self._last_pos, dtype=float), f
                pos, f = found
                touches += 1
        self._note(f"contour budget of {p.max_layer_motions} motions exhausted")
        return False, pos, f

    def _back_on(
        self, followed: list[tuple[frozenset[int], FArray, FArray, float]], pos: FArray, f: _Follow
    ) -> bool:
        """Whether ``pos`` (a new contact of ``f``) lies on a surface already followed in this layer."""
        reach_back = self.params.l3 + self.rho
        for group, start, direction, length in followed[:-1] if followed else []:
            if not group & set(f.group):
                continue
            d = pos - start
            s = float(d @ direction)
            off = float(np.linalg.norm(d - s * direction))
            if off <= max(0.002, 0.2 * self.rho) and -reach_back <= s <= length + 1e-6:
                return True
        return False

    def _record_here(self, pos: FArray, f: _Follow) -> None:
        """A slide contact where the finger is (the contour closes behind the first contact)."""
        fired = self.world.sense(_v3(pos))
        p = _v3(pos)
        m = Motion("slide", p, p, (1.0, 0.0, 0.0), 0.0, "none", fired, fired, (), (), p)
        self._record(m, f, "slide")

    def _after_slide(self, m: Motion, f: _Follow, touches: int) -> tuple[_Follow, int, bool | None]:
        """Handle the end of a slide; return (follow, touches, closed-or-None-to-continue)."""
        if m.event == "touch":
            self._record(m, f, "slide")
            nf = self._follow(m.closed)
            self._record(m, nf, "touch")
            return nf, touches + 1, None
        if m.event == "release":
            if f.sensor in m.fired:  # another surface's sensor opened: keep following
                return f, touches, None
            self._record(m, f, "slide")
            return f, touches, None
        self._record(m, f, "slide")
        what = {
            "none": "the slide found no end",
            "limit": "the workspace ends",
            "blocked": "a surface blocked the slide without a sensor change",
        }
        self._note(f"contour stopped at {_fmt(m.end)}: {what.get(m.event, m.event)}")
        return f, touches, False

    def _search(self, pos: FArray, t: FArray, f: _Follow) -> tuple[FArray, _Follow] | None:
        """The l1, l2, l3 cycle after a loss of contact; the new contact, or None."""
        p = self.params
        towards = np.cross(_Z, t)
        towards = _unit(np.array([towards[0], towards[1], 0.0]))
        for direction, length in ((t, p.l1), (towards, p.l2), (-t, p.l3)):
            m = self._move(pos, direction, length)
            pos = np.asarray(m.end, dtype=float)
            if m.event == "touch":
                nf = self._follow(m.closed)
                self._record(m, nf, "touch")
                return pos, nf
            if m.event == "blocked":
                self._note(f"blind contact (no sensor fired) at {_fmt(m.end)}")
            elif m.event == "limit":
                self._note(f"the workspace ends at {_fmt(m.end)}")
                return None
        self._note(
            f"no contact after the l1-l2-l3 cycle at z = {pos[2]:.4f} m: the object has at least "
            f"one dimension smaller than l2 = {p.l2:g} m"
        )
        return None

    def _z_increment(self, pos: FArray, f: _Follow) -> tuple[FArray, _Follow] | None:
        """Move up by z_step; the first contact of the next layer, or None when contact is lost."""
        m = self._move(pos, _Z, self.z_step)
        pos = np.asarray(m.end, dtype=float)
        if m.event == "none" and f.sensor in m.fired:
            self._phase = "layers"
            nf = _Follow(f.sensor, tuple(s for s in f.group if s in m.fired) or (f.sensor,), f.r0)
            self._record(m, nf, "slide")
            return pos, nf
        if m.event == "touch":
            nf = self._follow(m.closed)
            self._record(m, nf, "touch")
            return pos, nf
        if m.event == "release":
            rest = self.z_step - m.distance
            if rest > 1e-9:
                m = self._move(pos, _Z, rest)
                pos = np.asarray(m.end, dtype=float)
                if m.event == "touch":
                    nf = self._follow(m.closed)
                    self._record(m, nf, "touch")
                    return pos, nf
                if m.event != "none":
                    return None
            towards = _unit(np.array([f.r0[0], f.r0[1], 0.0]))
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
        self._note(f"the z increment stopped at {_fmt(m.end)} ({m.event}): layers end")
        return None

    def _finish_layer(
        self, index: int, z: float, path: list[Vec3], first: int, closed: bool
    ) -> None:
        contacts = [c for c in self.contacts[max(first, 0) :] if c.layer == index]
        contour: list[tuple[float, float]] = []
        try:
            from tactile_kb.sections import contour_from_contacts
        except ImportError:  # pragma: no cover - the geometry module is part of the package
            contour_from_contacts = None  # type: ignore[assignment]
        if contour_from_contacts is not None:
            try:
                contour = contour_from_contacts(contacts, self.rho, closed=closed)
            except (UsageError, np.linalg.LinAlgError, ValueError):
                contour = []
        self.layers.append(
            Layer(index=index, z=float(z), path=list(path), contour=contour, closed=closed)
        )

    def _top(self, last_path: list[Vec3]) -> None:
        """Approach from above over the middle of the last contour; check the touch by slides."""
        if self.finger.nearest((0.0, 0.0, -1.0)) is None:
            self._note("no sensor points down: tops are not explored")
            return
        if not last_path:
            return
        pts = np.asarray(last_path, dtype=float)[:, :2]
        xy = pts.mean(axis=0)
        # spread the three tip centres on the top over a good part of it (noise averages out)
        spread = max(self.top_slide, 0.3 * float((pts.max(axis=0) - pts.min(axis=0)).min()))
        top = float(self.world.hint.hi[2]) + self.rho + self.params.approach_margin
        start = (float(xy[0]), float(xy[1]), top)
        if not self.world.workspace.contains(start):
            return
        m = self._move(start, -_Z, top - self.rho)
        if m.event != "touch":
            self._note(f"the approach from above at {_fmt(start)} found nothing ({m.event})")
            return
        f = self._follow(m.closed)
        touch = self._record(m, f, "touch")
        pos = np.asarray(m.end, dtype=float)
        moved = 0.0
        slides: list[Contact] = []
        for direction in (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
            sm = self._slide(pos, direction, spread, f.sensor)
            moved += sm.distance
            pos = np.asarray(sm.end, dtype=float)
            if sm.distance > 1e-4:
                slides.append(self._record(sm, f, "slide"))
            if sm.event != "none":
                break
        if moved <= 1e-4:
            self.contacts.remove(touch)
            for c in slides:
                self.contacts.remove(c)
            self._note(f"the touch from above at {_fmt(m.end)} is an apex or an edge: not a plane")


def _fmt(p: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v:.4f}" for v in p) + ")"
