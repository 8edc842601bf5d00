"""The exploration record: every contact, the path, the layers; saved as JSON and loaded back.

A contact is what the finger reports when a sensor closes (``kind="touch"``, an OFF→ON event)
or, while it slides along a surface, at the end of each tangential move (``kind="slide"``).
The sensor that closed gives the unit direction ``r0`` (from the tip centre towards the
object); the contact point ``r1`` and the tangential plane follow the paper's eq. (6):
``(r − r1)·r0 = 0``.

Examples
--------
>>> c = Contact(step=3, centre=(0.0, -0.012, 0.02), sensors=(7,), direction=(0.0, 1.0, 0.0),
...             point=(0.0, -0.002, 0.02))
>>> c.normal
(-0.0, -1.0, -0.0)
>>> round(c.plane.offset, 6)
0.002
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from tactile_kb.errors import RecordError
from tactile_kb.files import MAX_RECORD_BYTES, InputFileError, atomic_write, read_text
from tactile_kb.types import Vec3

__all__ = [
    "APPROACHES",
    "APPROACH_LEVEL",
    "APPROACH_SIDES",
    "APPROACH_STRAIGHT",
    "OPEN_ITEMS_SHOWN",
    "READABLE_VERSIONS",
    "RECORD_VERSION",
    "Contact",
    "ExplorationRecord",
    "Layer",
    "Plane",
    "Vec2",
    "Vec3",
    "open_items",
]

Vec2 = tuple[float, float]

RECORD_VERSION = 2
"""The format written now. Version 2 (0.2) leaves :attr:`Layer.contour` empty: the model
computes layer contours from the contacts. Records of version 1 (0.1) still load."""

READABLE_VERSIONS = frozenset({1, RECORD_VERSION})
"""Every record format :meth:`ExplorationRecord.from_json` reads."""


APPROACH_LEVEL = ", approached level"
"""The ending of the item of a face touched at one height, approached level at its other
height (:mod:`tactile_kb.completion` words its items with these endings)."""

APPROACH_STRAIGHT = ", straight"
"""The ending of the item of a direction in which the planes close far, approached straight
along it."""

APPROACH_SIDES = {1.0: " (+ side)", -1.0: " (- side)"}
"""The endings of the items of a top touched along one line, probed from either side of it."""

APPROACHES = (APPROACH_LEVEL, APPROACH_STRAIGHT, *APPROACH_SIDES.values())
"""Endings of an item of :attr:`ExplorationRecord.unreachable` that name one more approach to
the same item."""

OPEN_ITEMS_SHOWN = 4
"""At most this many open items are named in :attr:`ExplorationRecord.open_ending`; the rest
are counted (``unreachable`` keeps them all)."""

DEFAULT_BUDGET = "the exploration's budget"
"""What :attr:`ExplorationRecord.open_ending` says ran out when the record does not name the
budget (records written before ``budget`` was kept)."""


def open_items(unreachable: list[str] | tuple[str, ...]) -> list[str]:
    """Each item of ``unreachable`` once, in order: the approaches to one item
    (:data:`APPROACHES`) are that item.

    >>> open_items(["the face facing (+1.0, +0.0, +0.0) touched at one height",
    ...             "the face facing (+1.0, +0.0, +0.0) touched at one height, approached level",
    ...             "the top facing (+0.0, +0.0, +1.0) touched along one line (- side)"])
    ['the face facing (+1.0, +0.0, +0.0) touched at one height', \
'the top facing (+0.0, +0.0, +1.0) touched along one line']
    """
    out: dict[str, None] = {}
    for item in unreachable:
        for ending in APPROACHES:
            if item.endswith(ending):
                item = item[: -len(ending)]
                break
        out.setdefault(item, None)
    return list(out)


class Plane(BaseModel):
    """The plane ``normal · x = offset`` with a unit ``normal`` pointing out of the object."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    normal: Vec3
    offset: float

    def distance(self, point: Vec3) -> float:
        """Signed distance of ``point`` from the plane (positive outside)."""
        return float(np.dot(self.normal, point) - self.offset)


class Contact(BaseModel):
    """One contact between the finger and the object."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    step: int = Field(description="index of the motion at whose end the contact was recorded")
    centre: Vec3 = Field(description="finger-tip centre, metres")
    sensors: tuple[int, ...] = Field(description="indices of every sensor ON, in the finger layout")
    sensor: int = Field(default=-1, description="the sensor followed (the last that closed)")
    direction: Vec3 = Field(description="r0: unit direction of that sensor, tip centre → object")
    point: Vec3 = Field(description="r1: the contact point, centre + radius · r0")
    kind: Literal["touch", "slide"] = "touch"
    phase: str = Field(default="", description="exploration phase (first-contact, layer, top, …)")
    layer: int | None = Field(default=None, description="index of the z-layer, if any")
    orientation: Vec2 = Field(
        default=(0.0, 0.0),
        description="the head's pose (tilt, turn), degrees, when the contact was recorded; "
        "(0, 0): the finger hanging vertically; direction is in the world frame either way",
    )

    @property
    def normal(self) -> Vec3:
        """The outward normal of the touched surface as the sensor sees it: −r0."""
        x, y, z = self.direction
        return (-x, -y, -z)

    @property
    def plane(self) -> Plane:
        """The tangential plane of eq. (6), ``(r − r1)·r0 = 0``, with its normal outward."""
        n = self.normal
        return Plane(normal=n, offset=float(np.dot(n, self.point)))


class Layer(BaseModel):
    """One horizontal plane z = const of the exploration, with the contour traced in it."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    index: int
    z: float
    path: list[Vec3] = Field(default_factory=list, description="tip-centre path in this layer")
    contour: list[Vec2] = Field(
        default_factory=list,
        description="version 1 only: the cross-section polygon the explorer traced (the model "
        "now computes it from the contacts, see tactile_kb.geometry.sections)",
    )
    closed: bool = Field(default=False, description="the contour returned to its first contact")


class ExplorationRecord(BaseModel):
    """Everything an exploration produced; enough to rebuild the model without exploring again."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    version: int = RECORD_VERSION
    object: str = ""
    explorer: str = ""
    finger: str = Field(default="", description="the finger layout's name")
    tip_radius: float = Field(default=0.0, description="ρ, metres")
    sensor_directions: list[Vec3] = Field(default_factory=list)
    seed: int | None = None
    noise: float = Field(
        default=0.0,
        ge=0.0,
        description="σ of the encoder noise the exploration ran with, metres (0: exact contacts)",
    )
    params: dict[str, float] = Field(default_factory=dict)
    contacts: list[Contact] = Field(default_factory=list)
    path: list[Vec3] = Field(default_factory=list, description="the tip-centre polyline")
    layers: list[Layer] = Field(default_factory=list)
    contacts_per_phase: dict[str, int] = Field(default_factory=dict)
    complete: bool = Field(default=True, description="False when lazy exploration stopped early")
    notes: list[str] = Field(default_factory=list)
    ending: str = Field(
        default="",
        description="how the model-driven completion ended: 'closed' (a closed model, every "
        "face touched at two heights or every tip centre on one sphere), 'budget' or "
        "'unreachable'; '' when none ran",
    )
    unreachable: list[str] = Field(
        default_factory=list, description="what stayed open when the completion ended"
    )
    budget: str = Field(
        default="",
        description="with ending 'budget', which budget ran out and its size (\"the "
        'completion\'s budget of 24 touches", "… of 1.2 m of path", "the motion budget of '
        "6000 motions\"); '' otherwise, and in records written before it was kept",
    )
    orientations: list[tuple[int, float, float]] = Field(
        default_factory=list,
        description="(path index, tilt, turn): the head was indexed to (tilt, turn) degrees at "
        "path[index] and kept that pose until the next entry; empty: vertical all along",
    )
    blind: list[tuple[Vec3, Vec3]] = Field(
        default_factory=list,
        description="blind contacts: (tip centre, direction of the motion) where a motion was "
        "blocked with no sensor closed (the object met where no sensor faces: an overhang)",
    )

    @model_validator(mode="before")
    @classmethod
    def _noise_from_version_1(cls, data: Any) -> Any:
        """Version 1 kept σ in ``params["noise"]``; it is a field of its own now."""
        if isinstance(data, dict) and "noise" not in data and isinstance(data.get("params"), dict):
            params = dict(data["params"])
            if "noise" in params:
                data = {**data, "noise": params.pop("noise"), "params": params}
        return data

    @property
    def touches(self) -> int:
        """Number of touches: sensor OFF→ON events."""
        return sum(1 for c in self.contacts if c.kind == "touch")

    @property
    def path_length(self) -> float:
        """Length of the tip-centre path, metres."""
        if len(self.path) < 2:
            return 0.0
        p = np.asarray(self.path, dtype=float)
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())

    @property
    def open_ending(self) -> str:
        """Why the exploration ended without a closed model, in one line; "" when it closed
        (or when no completion ran, as in records of version 0.1). It names each open item
        once (:func:`open_items`) and at most :data:`OPEN_ITEMS_SHOWN` of them, and counts
        the rest; ``unreachable`` lists every item and approach."""
        if self.ending in ("", "closed"):
            return ""
        what = {
            "budget": f"{self.budget or DEFAULT_BUDGET} ran out",
            "unreachable": "what stayed open could not be reached",
        }.get(self.ending, f"the exploration ended ({self.ending})")
        items = open_items(self.unreachable)
        still = "; ".join(items[:OPEN_ITEMS_SHOWN]) or "unknown"
        if len(items) > OPEN_ITEMS_SHOWN:
            still += (
                f"; and {len(items) - OPEN_ITEMS_SHOWN} more (the record's `unreachable` "
                "lists them all)"
            )
        return f"{what} after {self.touches} touches; still open: {still}"

    def to_json(self, *, indent: int | None = None) -> str:
        """The record as JSON text."""
        return self.model_dump_json(indent=indent)

    @classmethod
    def from_json(cls, text: str, *, file: str = "<string>") -> ExplorationRecord:
        """Load a record from JSON text; a bad record raises :class:`RecordError` naming ``file``."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise RecordError(f"{file}:{exc.lineno}:{exc.colno}: not JSON: {exc.msg}") from None
        except RecursionError:
            raise RecordError(f"{file}: not an exploration record (nested too deeply)") from None
        if not isinstance(data, dict):
            raise RecordError(f"{file}: not an exploration record (expected a JSON object)")
        try:
            rec = cls.model_validate(data)
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            where = ".".join(str(p) for p in err["loc"])
            raise RecordError(f"{file}: {where}: {err['msg']}") from None
        if rec.version not in READABLE_VERSIONS:
            raise RecordError(f"{file}: version {rec.version} is not supported")
        if not rec.finger or rec.tip_radius <= 0:
            raise RecordError(
                f"{file}: not an exploration record (it names no finger and tip radius)"
            )
        for c in rec.contacts:
            if not all(math.isfinite(v) for v in (*c.centre, *c.direction, *c.point)):
                raise RecordError(f"{file}: contact at step {c.step} has a non-finite coordinate")
        return rec

    def save(self, path: str | Path) -> None:
        """Write the record to ``path`` atomically (see :func:`tactile_kb.files.atomic_write`).

        Nothing is left half-written: a failure raises :class:`RecordError` naming the path
        and leaves any earlier file at ``path`` as it was. A path that exists and is not a
        regular file (a directory, a device) is refused.
        """
        p = Path(path)
        if not str(path) or not p.name:
            raise RecordError(f"{str(path)!r}: give a file name for the record")
        if p.exists() and not p.is_file():
            raise RecordError(f"{p}: not a regular file; give a file name for the record")
        data = self.to_json(indent=1).encode("utf-8")
        try:
            atomic_write(p, lambda f: f.write(data))
        except OSError as exc:
            raise RecordError(f"{p}: cannot write: {exc.strerror or exc}") from None

    @classmethod
    def load(cls, path: str | Path) -> ExplorationRecord:
        """Read a record saved by :meth:`save` (a regular file of at most
        :data:`~tactile_kb.files.MAX_RECORD_BYTES`)."""
        p = Path(path)
        if not str(path):
            raise RecordError("'': give a record file name")
        try:
            text = read_text(p, max_bytes=MAX_RECORD_BYTES)
        except InputFileError as exc:
            where = f"{p}:{exc.line}:{exc.column}" if exc.line else str(p)
            raise RecordError(f"{where}: {exc.message}") from None
        return cls.from_json(text, file=str(p))
