"""The finger: a hemispherical tip of radius ρ carrying on/off pressure sensors.

Each sensor sits at a unit direction on the tip (pointing from the tip centre outwards, the
tip points down, −z) and fires when the direction of a contact from the tip centre lies
inside its acceptance cone. Two built-in layouts follow the paper's prototypes:

* ``"4"``: four sensors 90° apart on the equator (for objects composed of rectangular
  parallelepipeds);
* ``"33"``: 33 sensors at the cross-points of meridians and parallels: the pole, 8 on the
  parallel 60° below the equator, 12 on the parallel 30° below, and 12 on the equator, i.e.
  30° apart, so that plane surfaces 30° apart are told apart.

Examples
--------
>>> f = builtin_finger("4")
>>> f.fired([(1.0, 0.0, 0.0)])
(0,)
>>> len(builtin_finger("33").directions)
33
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator

from tactile_kb.errors import UsageError

__all__ = ["BUILTIN_LAYOUTS", "DEFAULT_TIP_RADIUS", "Finger", "builtin_finger"]

Vec3 = tuple[float, float, float]

DEFAULT_TIP_RADIUS = 0.005
"""ρ for the built-in layouts: a 5 mm hemispherical tip (objects of 2–30 cm)."""


class Finger(BaseModel):
    """A tip of ``radius`` metres with sensors at unit ``directions``."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: str
    radius: float = Field(default=DEFAULT_TIP_RADIUS, gt=0.0, description="ρ, metres")
    directions: tuple[Vec3, ...] = Field(description="unit sensor directions, tip centre outwards")
    cone_deg: float = Field(gt=0.0, lt=90.0, description="half-angle of each acceptance cone")

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


def _ring(elevation_deg: float, count: int, phase_deg: float = 0.0) -> list[Vec3]:
    e = math.radians(elevation_deg)
    out = []
    for k in range(count):
        a = math.radians(phase_deg + 360.0 * k / count)
        out.append((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    return out


def _layout_4() -> Finger:
    return Finger(name="4", directions=tuple(_ring(0.0, 4)), cone_deg=46.0)


def _layout_33() -> Finger:
    dirs: list[Vec3] = [(0.0, 0.0, -1.0)]
    dirs += _ring(-60.0, 8)
    dirs += _ring(-30.0, 12)
    dirs += _ring(0.0, 12)
    return Finger(name="33", directions=tuple(dirs), cone_deg=20.0)


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
