r"""The finger: a hemispherical tip of radius ρ carrying on/off pressure sensors.

Each sensor sits at a unit direction on the tip (pointing from the tip centre outwards, the
tip points down, −z) and fires when the direction of a contact from the tip centre lies
inside its acceptance cone. Two built-in layouts follow the paper's prototypes:

* ``"4"``: four sensors 90° apart on the equator (for objects composed of rectangular
  parallelepipeds); it has no indexing head (``wrist=None``), so it behaves as the paper's
  finger and never feels a top. The same sensors in a layout file with a ``wrist`` index,
  and then feel a top with the head tilted;
* ``"33"``: 33 sensors at the cross-points of meridians and parallels: the pole, 8 on the
  parallel 60° below the equator, 12 on the parallel 30° below, and 12 on the equator, i.e.
  30° apart, so that plane surfaces 30° apart are told apart. Their cones (25°) cover the
  whole lower hemisphere (the largest angle to the nearest sensor there is 20.7°) and reach
  20° above the equator at every heading, so that faces overhanging by up to 20° (a regular
  octahedron's lower faces: 19.47°) are felt whatever the object's turn. Overlapping cones
  fire two or three neighbouring sensors together; the controller takes their mean direction,
  and quantisation (the nearest sensor) is unchanged.

Custom layouts load from YAML (:func:`load_layout`) with located errors
(:class:`~tactile_kb.errors.LayoutFileError`), and :func:`coverage` reports, for a layout,
the largest angle between a surface's contact direction and the sensor that fires for it,
and the directions where none fires.

Examples
--------
>>> f = builtin_finger("4")
>>> f.fired([(1.0, 0.0, 0.0)])
(0,)
>>> len(builtin_finger("33").directions)
33
>>> f = load_layout("name: two\ncone_deg: 30\nsensors:\n  - [1, 0, 0]\n  - {elevation: -90, azimuth: 0}\n")
>>> [tuple(round(c, 3) for c in d) for d in f.directions]
[(1.0, 0.0, 0.0), (0.0, 0.0, -1.0)]
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator

from tactile_kb.errors import LayoutFileError, Problem, UsageError
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import Vec3
from tactile_kb.yaml_source import Source, format_path, load_yaml, validate

__all__ = [
    "ALIGN_4_DEG",
    "BUILTIN_LAYOUTS",
    "DEFAULT_TIP_RADIUS",
    "MAX_USABLE_ERROR_DEG",
    "VERTICAL",
    "Coverage",
    "Finger",
    "Orientation",
    "Wrist",
    "builtin_finger",
    "coverage",
    "layout_warnings",
    "load_finger",
    "load_layout",
]


DEFAULT_TIP_RADIUS = 0.005
"""ρ for the built-in layouts: a 5 mm hemispherical tip (objects of 2–30 cm)."""


ALIGN_4_DEG = DEFAULTS.finger.align_4_deg
"""Degrees: the 4-sensor finger is meant for surfaces facing its sensors (axis-aligned objects
made of rectangular parallelepipeds); a surface turned further from its sensor is reported."""


@dataclass(frozen=True)
class Orientation:
    """A pose of the indexing head: the finger tilted by ``tilt_deg`` about a horizontal axis,
    then turned by ``turn_deg`` about the vertical.

    At ``(0, 0)`` the finger hangs vertically (tip down, shaft up: the paper's finger). Tilting
    by θ swings the tip's pole from −z towards −x (and the shaft from +z towards +x); the turn
    then rotates both about +z. Sensor directions given in the finger frame are seen in the
    world as ``rotation @ d``.

    Examples
    --------
    >>> o = Orientation(90.0, 180.0)
    >>> [round(c, 6) + 0.0 for c in o.pole], [round(c, 6) + 0.0 for c in o.axis]
    ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0])
    """

    tilt_deg: float = 0.0
    turn_deg: float = 0.0

    @property
    def vertical(self) -> bool:
        """Whether the finger hangs vertically (no tilt)."""
        return abs(self.tilt_deg) < 1e-9

    @property
    def rotation(self) -> NDArray[np.float64]:
        """The 3×3 rotation from the finger frame to the world."""
        t, a = math.radians(self.tilt_deg), math.radians(self.turn_deg)
        ry = np.array(
            [[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0], [-math.sin(t), 0.0, math.cos(t)]]
        )
        rz = np.array(
            [[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
        )
        out: NDArray[np.float64] = rz @ ry
        return out

    @property
    def axis(self) -> Vec3:
        """The shaft's direction in the world (tip centre towards the head)."""
        r = self.rotation[:, 2]
        return (float(r[0]), float(r[1]), float(r[2]))

    @property
    def pole(self) -> Vec3:
        """The direction the tip points to in the world (−:attr:`axis`)."""
        a = self.axis
        return (-a[0], -a[1], -a[2])


VERTICAL = Orientation()
"""The paper's finger: hanging vertically, tip down."""


class Wrist(BaseModel):
    """The indexing head: tilts of 0…``max_tilt_deg`` and turns of 0…360°, both in steps of
    ``step_deg`` (a divisor of 90°, so that the vertical, the horizontal and the four axis
    headings are poses)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    step_deg: float = Field(default=15.0, gt=0.0, le=90.0, description="index step, degrees")
    max_tilt_deg: float = Field(
        default=90.0, ge=0.0, le=180.0, description="the largest tilt, degrees"
    )

    @field_validator("step_deg")
    @classmethod
    def _divides_90(cls, v: float) -> float:
        k = 90.0 / v
        if abs(k - round(k)) > 1e-9:
            raise ValueError(f"the index step must divide 90°, got {v:g}° (e.g. 7.5, 15, 30)")
        return v

    def poses(self) -> list[Orientation]:
        """Every indexed pose, the vertical first, then by increasing tilt."""
        out = [VERTICAL]
        tilts = math.floor(self.max_tilt_deg / self.step_deg + 1e-9)
        turns = round(360.0 / self.step_deg)
        for i in range(1, tilts + 1):
            for j in range(turns):
                out.append(Orientation(i * self.step_deg, j * self.step_deg))
        return out


class Finger(BaseModel):
    """A tip of ``radius`` metres with sensors at unit ``directions``.

    ``align_deg`` says which surfaces the layout is meant for: with a value, a surface whose
    normal lies further than that from the sensor that fires for it (an object turned away
    from the sensors of a sparse layout) stops the exploration with an
    :class:`~tactile_kb.errors.ExplorationError` instead of being recorded as a wrong plane.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str
    radius: float = Field(default=DEFAULT_TIP_RADIUS, gt=0.0, description="ρ, metres")
    directions: tuple[Vec3, ...] = Field(description="unit sensor directions, tip centre outwards")
    cone_deg: float = Field(gt=0.0, lt=90.0, description="half-angle of each acceptance cone")
    align_deg: float | None = Field(
        default=None,
        gt=0.0,
        lt=90.0,
        description="the largest angle between a felt surface's normal and its sensor that the "
        "layout is meant for (None: any within the cone)",
    )
    wrist: Wrist | None = Field(
        default_factory=Wrist, description="the indexing head (None: the finger stays vertical)"
    )
    shaft_radius: float | None = Field(
        default=None,
        gt=0.0,
        description="radius of the shaft (stem) above the tip, metres; it collides with the "
        "object (None: the shaft is not modelled)",
    )
    shaft_length: float = Field(default=0.25, gt=0.0, description="shaft length, metres")

    @field_validator("directions")
    @classmethod
    def _unit(cls, v: tuple[Vec3, ...]) -> tuple[Vec3, ...]:
        if not v:
            raise ValueError("a finger needs at least one sensor")
        out = []
        for d in v:
            n = math.sqrt(sum(c * c for c in d))
            if not math.isfinite(n) or n < 1e-9:
                raise ValueError(f"sensor direction {d} has no length")
            out.append((d[0] / n, d[1] / n, d[2] / n))
        return tuple(out)

    @property
    def matrix(self) -> NDArray[np.float64]:
        """Sensor directions as an (n, 3) array."""
        return np.asarray(self.directions, dtype=float)

    @property
    def cos_cone(self) -> float:
        return math.cos(math.radians(self.cone_deg))

    def fired(self, contact_directions: Iterable[Sequence[float]]) -> tuple[int, ...]:
        """Indices of the sensors whose cone contains any of the unit contact directions."""
        d = np.asarray(list(contact_directions), dtype=float).reshape(-1, 3)
        if d.size == 0:
            return ()
        cos = d @ self.matrix.T  # (k, n)
        return tuple(int(i) for i in np.flatnonzero((cos >= self.cos_cone - 1e-12).any(axis=0)))

    def nearest(self, direction: Sequence[float]) -> int | None:
        """The sensor closest in angle to ``direction`` if inside its cone, else ``None``."""
        cos = self.matrix @ np.asarray(direction, dtype=float)
        i = int(np.argmax(cos))
        return i if cos[i] >= self.cos_cone - 1e-12 else None

    def directions_at(self, orientation: Orientation) -> NDArray[np.float64]:
        """The sensor directions in the world with the head at ``orientation``, (n, 3)."""
        if orientation.vertical and abs(orientation.turn_deg) < 1e-12:
            return self.matrix
        out: NDArray[np.float64] = self.matrix @ orientation.rotation.T
        return out

    def index_towards(self, direction: Sequence[float]) -> Orientation:
        """The indexed pose whose tip points nearest to ``direction`` (the vertical without a
        wrist).

        Examples
        --------
        >>> builtin_finger("33").index_towards((-1.0, 0.2, 0.0))
        Orientation(tilt_deg=90.0, turn_deg=345.0)
        """
        if self.wrist is None:
            return VERTICAL
        d = np.asarray(direction, dtype=float)
        poses = self.wrist.poses()
        poles = np.asarray([p.pole for p in poses])
        return poses[int(np.argmax(poles @ d))]

    def index_for(self, normal: Sequence[float]) -> Orientation | None:
        """The head pose for touching a surface whose outward normal is ``normal``.

        The vertical finger when a sensor faces the surface (its contact direction −n lies in a
        cone) and, with a shaft, the shaft leans away from the surface (n_z ≥ 0): the paper's
        finger. Otherwise the indexed pose (:meth:`Wrist.poses`) in which a sensor faces the
        surface and the shaft leans furthest away from it (the least tilt among equals);
        ``None`` when no pose has a sensor facing it.

        Examples
        --------
        >>> f = builtin_finger("33")
        >>> f.index_for((1.0, 0.0, 0.0))
        Orientation(tilt_deg=0.0, turn_deg=0.0)
        >>> f.index_for((0.0, 0.0, -1.0))  # an underside: the tip points up as far as it can
        Orientation(tilt_deg=90.0, turn_deg=0.0)
        """
        n = np.asarray(normal, dtype=float)
        n = n / float(np.linalg.norm(n))
        sees = self.nearest(_v(-n)) is not None
        overhang = float(n[2]) < -math.sin(math.radians(self.cone_deg * 0.5))
        if sees and not (overhang and self.wrist is not None):
            return VERTICAL
        if self.wrist is None:
            return None
        best: tuple[float, Orientation] | None = None
        for pose in self.wrist.poses():
            d = self.directions_at(pose)
            cos = d @ -n
            if float(cos.max()) < self.cos_cone + 0.05:  # a sensor must face it, with a margin
                continue
            score = float(np.asarray(pose.axis) @ n) - 1e-3 * pose.tilt_deg / 90.0
            if best is None or score > best[0] + 1e-12:
                best = (score, pose)
        return best[1] if best else None


def _v(a: NDArray[np.float64]) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


def _ring(elevation_deg: float, count: int, phase_deg: float = 0.0) -> list[Vec3]:
    e = math.radians(elevation_deg)
    out = []
    for k in range(count):
        a = math.radians(phase_deg + 360.0 * k / count)
        out.append((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    return out


def _layout_4() -> Finger:
    return Finger(
        name="4",
        directions=tuple(_ring(0.0, 4)),
        cone_deg=46.0,
        align_deg=current().finger.align_4_deg,
        # the paper's 4-sensor finger stays vertical (it never feels a top, and its answers
        # say so: an assumed top); a layout file with these sensors and a ``wrist`` indexes
        wrist=None,
    )


def _layout_33() -> Finger:
    dirs: list[Vec3] = [(0.0, 0.0, -1.0)]
    dirs += _ring(-60.0, 8)
    dirs += _ring(-30.0, 12)
    dirs += _ring(0.0, 12)
    return Finger(name="33", directions=tuple(dirs), cone_deg=25.0)


BUILTIN_LAYOUTS = {"4": _layout_4, "33": _layout_33}


def builtin_finger(name: str, *, radius: float | None = None) -> Finger:
    """The built-in layout ``"4"`` or ``"33"``, optionally with another tip radius."""
    try:
        finger = BUILTIN_LAYOUTS[name]()
    except KeyError:
        known = ", ".join(sorted(BUILTIN_LAYOUTS))
        raise UsageError(
            f"unknown finger layout {name!r} (built-in: {known}, or a YAML file)"
        ) from None
    return finger if radius is None else finger.model_copy(update={"radius": radius})


# --- custom layouts from YAML ----------------------------------------------------------------


class _Ring(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    elevation: float = Field(ge=-90.0, le=90.0)
    count: int = Field(ge=1, le=360)
    phase: float = 0.0


class _LayoutFile(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    name: str = Field(min_length=1)
    description: str = ""
    radius: float = Field(default=DEFAULT_TIP_RADIUS, gt=0.0, le=0.1)
    cone_deg: float = Field(gt=0.0, lt=90.0)
    align_deg: float | None = Field(default=None, gt=0.0, lt=90.0)
    sensors: list[Any] = Field(default_factory=list)  # each entry checked by _sensor()
    rings: list[_Ring] = Field(default_factory=list)
    wrist: Wrist | None = Field(default_factory=Wrist)
    shaft_radius: float | None = Field(default=None, gt=0.0, le=0.1)
    shaft_length: float = Field(default=0.25, gt=0.0, le=2.0)


_SENSOR_FORM = "a sensor is [x, y, z] or {elevation: degrees, azimuth: degrees}"


def _number(src: Source, path: tuple[str | int, ...], value: Any, what: str) -> Problem | float:
    """``value`` as a finite float, or the problem located at ``path``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return src.problem(path, f"{what} must be a number, got {value!r}")
    if not math.isfinite(value):
        return src.problem(path, f"{what} is not finite ({value})")
    return float(value)


def _sensor(src: Source, i: int, item: Any) -> list[Problem] | Vec3:
    """One ``sensors`` entry as a unit direction, or its problems (each at its own column)."""
    where: tuple[str | int, ...] = ("sensors", i)
    if isinstance(item, list):
        if len(item) != 3:
            return [
                src.problem(where, f"a sensor direction needs 3 numbers [x, y, z], got {len(item)}")
            ]
        out: list[float] = []
        problems: list[Problem] = []
        for j, (axis, value) in enumerate(zip("xyz", item, strict=True)):
            got = _number(src, (*where, j), value, axis)
            if isinstance(got, Problem):
                problems.append(got)
            else:
                out.append(got)
        if problems:
            return problems
        n = math.sqrt(sum(c * c for c in out))
        if n < 1e-9:
            return [src.problem(where, "a sensor direction needs a non-zero length")]
        return (out[0] / n, out[1] / n, out[2] / n)
    if isinstance(item, dict):
        problems = [
            src.problem((*where, k), f"unknown field ({_SENSOR_FORM})", key=True)
            for k in item
            if k not in ("elevation", "azimuth")
        ]
        angles: dict[str, float] = {}
        for k in ("elevation", "azimuth"):
            if k not in item:
                problems.append(src.problem(where, f"a sensor given by angles needs {k}"))
                continue
            got = _number(src, (*where, k), item[k], k)
            if isinstance(got, Problem):
                problems.append(got)
            elif k == "elevation" and not -90.0 <= got <= 90.0:
                problems.append(
                    src.problem((*where, k), f"elevation must lie in [-90, 90], got {got:g}")
                )
            else:
                angles[k] = got
        if problems:
            return problems
        return _ring(angles["elevation"], 1, angles["azimuth"])[0]
    return [src.problem(where, f"{_SENSOR_FORM}, got {item!r}")]


def load_layout(source: str | Path, *, file: str | None = None) -> Finger:
    """A finger layout from a YAML file (a ``Path``) or YAML text (a ``str``).

    The file gives ``name``, ``cone_deg`` (half-angle of every acceptance cone), optionally
    ``radius`` (ρ, metres, default 0.005), ``align_deg`` (see :class:`Finger`) and
    ``description``, and the sensors: ``sensors``, a
    list of unit vectors ``[x, y, z]`` (tip centre outwards; normalised on load) or
    ``{elevation, azimuth}`` in degrees, and/or ``rings``, each ``{elevation, count, phase}``
    (``count`` sensors evenly spaced in azimuth starting at ``phase``). Sensors may lie on the
    upper hemisphere too (a ball stylus on a stem). Optionally ``wrist`` (the indexing head,
    :class:`Wrist`: ``{step_deg: 15, max_tilt_deg: 90}``, or ``null`` for a finger that stays
    vertical; the step must divide 90°), ``shaft_radius`` and ``shaft_length`` (metres: the
    shaft or stem above the tip, which collides with the object). Every problem of the
    file (duplicate keys, wrong fields, bad sensor entries, repeated directions) is reported
    at once with its ``file:line:column`` in one :class:`~tactile_kb.errors.LayoutFileError`.

    Examples
    --------
    >>> load_layout("name: x\\ncone_deg: 30\\nsensors:\\n  - [1, 0, .inf]\\n", file="f.yaml")
    Traceback (most recent call last):
    ...
    tactile_kb.errors.LayoutFileError: f.yaml:4:12: sensors[0][2]: z is not finite (inf)
    """
    src = load_yaml(source, file=file, error_cls=LayoutFileError, keep_going=True)
    problems: list[Problem] = list(src.problems)

    def fail() -> LayoutFileError:
        first = min(problems, key=lambda p: (p.line, p.column))
        return LayoutFileError(problems, src.excerpt(first.line, first.column))

    if not isinstance(src.data, dict):
        problems.append(
            Problem(
                src.file, 1, 1, "", "a layout file must be a mapping with name, cone_deg, sensors"
            )
        )
        raise fail()
    spec: _LayoutFile | None = None
    try:
        spec = validate(src, _LayoutFile, error_cls=LayoutFileError)
    except LayoutFileError as exc:
        problems += exc.problems
    raw = spec.sensors if spec is not None else src.data.get("sensors")
    dirs: list[Vec3] = []
    origin: list[tuple[str | int, ...]] = []  # where each direction came from in the file
    for i, item in enumerate(raw if isinstance(raw, list) else []):
        got = _sensor(src, i, item)
        if isinstance(got, list):
            problems += got
            continue
        dirs.append(got)
        origin.append(("sensors", i))
    if spec is not None:
        for r, ring in enumerate(spec.rings):
            dirs += _ring(ring.elevation, ring.count, ring.phase)
            origin += [("rings", r)] * ring.count
        if not dirs and not problems:
            problems.append(
                src.problem(("sensors",), "a finger needs at least one sensor (sensors or rings)")
            )
    seen: dict[tuple[float, float, float], tuple[str | int, ...]] = {}
    for d, where in zip(dirs, origin, strict=True):
        key = (round(d[0], 9) + 0.0, round(d[1], 9) + 0.0, round(d[2], 9) + 0.0)
        if key in seen:
            problems.append(src.problem(where, f"the same direction as {format_path(seen[key])}"))
        seen.setdefault(key, where)
    if problems or spec is None:
        raise fail()
    return Finger(
        name=spec.name,
        radius=spec.radius,
        directions=tuple(dirs),
        cone_deg=spec.cone_deg,
        align_deg=spec.align_deg,
        wrist=spec.wrist,
        shaft_radius=spec.shaft_radius,
        shaft_length=spec.shaft_length,
    )


def load_finger(finger: Finger | str | Path, *, radius: float | None = None) -> Finger:
    """A :class:`Finger`, a built-in layout name (``"4"``, ``"33"``) or a layout YAML file."""
    if isinstance(finger, Finger):
        out = finger
    elif isinstance(finger, str) and finger in BUILTIN_LAYOUTS:
        out = builtin_finger(finger)
    else:
        path = Path(finger)
        if not str(finger):
            raise UsageError("no finger given (--finger ''): give 4, 33 or a YAML layout file")
        if not path.exists():
            known = ", ".join(sorted(BUILTIN_LAYOUTS))
            raise UsageError(
                f"unknown finger {str(finger)!r} (built-in: {known}, or a YAML layout file)"
            )
        out = load_layout(path)
    return out if radius is None else out.model_copy(update={"radius": radius})


# --- coverage ---------------------------------------------------------------------------------


def _sphere_points(n: int) -> NDArray[np.float64]:
    i = np.arange(n) + 0.5
    polar = np.arccos(1.0 - 2.0 * i / n)
    az = math.pi * (1.0 + math.sqrt(5.0)) * i
    pts: NDArray[np.float64] = np.c_[
        np.cos(az) * np.sin(polar), np.sin(az) * np.sin(polar), np.cos(polar)
    ]
    return pts


@dataclass(frozen=True)
class Coverage:
    """How well a layout's cones cover contact directions up to ``max_elevation_deg``.

    Attributes
    ----------
    finger
        The layout's name.
    max_elevation_deg
        The region examined: contact directions (tip centre → contact) whose elevation is at
        most this (−90 is straight down; 0 the lower hemisphere).
    max_error_deg
        The largest angle between a direction that fires and the nearest sensor firing for
        it: the worst quantisation of a surface normal.
    covering_radius_deg
        The largest angle from any direction in the region to its nearest sensor.
    uncovered_fraction
        The fraction of the region (by area) where no sensor fires.
    gaps
        The directions where none fires, grouped: ``(elevation_deg, azimuth_deg, size_deg)``
        per group, the largest first (``size_deg`` is the group's angular radius).
    """

    finger: str
    max_elevation_deg: float
    max_error_deg: float
    covering_radius_deg: float
    uncovered_fraction: float
    gaps: tuple[tuple[float, float, float], ...]

    @property
    def complete(self) -> bool:
        """Whether every direction of the region fires at least one sensor.

        Complete is not enough: a direction is reported as the direction of the sensor that
        fires, up to :attr:`max_error_deg` away. See :attr:`adequate`.
        """
        return not self.gaps

    @property
    def adequate(self) -> bool:
        """Complete, and no contact direction is more than :data:`MAX_USABLE_ERROR_DEG` from
        the sensor that reports it: the planes found are then close enough to the faces for the
        features (parallel faces, perpendicular faces, edges) to be decided."""
        return self.complete and self.max_error_deg <= current().finger.max_usable_error_deg

    @property
    def problems(self) -> tuple[str, ...]:
        """What is wrong with the layout for exploring polyhedra, one sentence each."""
        out = []
        if self.gaps:
            e, a, size = self.gaps[0]
            out.append(
                f"{self.uncovered_fraction:.0%} of the contact directions fire no sensor "
                f"(the largest gap: {size:g}° around elevation {e:g}°, azimuth {a:g}°), so "
                "faces there are never sensed"
            )
        if self.max_error_deg > current().finger.max_usable_error_deg:
            out.append(
                f"a contact direction can be {self.max_error_deg:.0f}° from the sensor that "
                f"reports it (at most {current().finger.max_usable_error_deg:g}° keeps faces and edges right), "
                "so the planes found are that far off"
            )
        return tuple(out)


MAX_USABLE_ERROR_DEG = DEFAULTS.finger.max_usable_error_deg
"""The largest quantisation of a contact direction a layout may have for the features to be
decided reliably (the 33-sensor finger: 20.3°; the parallel and perpendicular tests allow 15–20°)."""


def layout_warnings(finger: Finger) -> list[str]:
    r"""Warnings about a layout that is not built in: its :attr:`Coverage.problems`.

    The built-in layouts are known (the 4-sensor finger is meant for layer contours and is
    documented as such), so they give none.

    Examples
    --------
    >>> tripod = load_layout("name: tripod\ncone_deg: 70\nsensors:\n"
    ...     "  - {elevation: -20, azimuth: 0}\n  - {elevation: -20, azimuth: 120}\n"
    ...     "  - {elevation: -20, azimuth: 240}\n")
    >>> print(layout_warnings(tripod)[0])  # doctest: +ELLIPSIS
    finger 'tripod': a contact direction can be 69° from the sensor that reports it ...
    """
    if finger.name in BUILTIN_LAYOUTS:
        builtin = builtin_finger(finger.name)
        if np.allclose(builtin.matrix, finger.matrix) and builtin.cone_deg == finger.cone_deg:
            return []
    report = coverage(finger, samples=8000)
    return [f"finger {finger.name!r}: {p}; answers may be wrong" for p in report.problems]


def coverage(finger: Finger, *, max_elevation_deg: float = 0.0, samples: int = 40000) -> Coverage:
    """The coverage report of ``finger`` over contact directions up to ``max_elevation_deg``.

    Directions are sampled uniformly (a Fibonacci sphere of ``samples`` points); the angles are
    exact for the samples, so their resolution is about ``sqrt(41253 / samples)`` degrees.

    Examples
    --------
    >>> c = coverage(builtin_finger("33"))
    >>> c.complete, round(c.covering_radius_deg, 1)
    (True, 20.6)
    >>> c4 = coverage(builtin_finger("4"))
    >>> c4.complete, c4.gaps[0][0] < -40
    (False, True)
    >>> c.adequate, c4.adequate
    (True, False)
    """
    pts = _sphere_points(samples)
    elev = np.degrees(np.arcsin(np.clip(pts[:, 2], -1.0, 1.0)))
    pts = pts[elev <= max_elevation_deg + 1e-9]
    cos = np.clip(pts @ finger.matrix.T, -1.0, 1.0)
    best = cos.max(axis=1)
    covering = float(np.degrees(np.arccos(best.max() if len(best) == 0 else best.min())))
    fires = best >= finger.cos_cone - 1e-12
    err = float(np.degrees(np.arccos(best[fires].min()))) if fires.any() else 0.0
    gaps: list[tuple[float, float, float]] = []
    miss = pts[~fires]
    if len(miss):
        spacing = math.sqrt(4.0 * math.pi / samples) * 2.5
        if len(miss) == 1:
            labels = np.array([1])
        else:
            from scipy.cluster.hierarchy import fcluster, linkage

            labels = fcluster(linkage(miss, method="single"), t=spacing, criterion="distance")
        for lab in np.unique(labels):
            grp = miss[labels == lab]
            c = grp.mean(axis=0)
            c /= np.linalg.norm(c)
            size = float(np.degrees(np.arccos(np.clip(grp @ c, -1.0, 1.0)).max()))
            e = float(np.degrees(np.arcsin(np.clip(c[2], -1.0, 1.0))))
            a = float(np.degrees(np.arctan2(c[1], c[0]))) % 360.0
            gaps.append((round(e, 1), round(a, 1), round(size, 1)))
        gaps.sort(key=lambda g: -g[2])
    return Coverage(
        finger=finger.name,
        max_elevation_deg=max_elevation_deg,
        max_error_deg=err,
        covering_radius_deg=covering,
        uncovered_fraction=float((~fires).mean()) if len(fires) else 0.0,
        gaps=tuple(gaps),
    )
