"""The array and vector type aliases every stage shares (one place, for mypy --strict).

Examples
--------
>>> import numpy as np
>>> a: FloatArray = np.zeros(3)
>>> v: Vec3 = (0.0, 0.0, 1.0)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "FloatArray", "IntArray", "Vec3", "vec3"]

FloatArray = NDArray[np.float64]
"""An array of float64 (points, normals, offsets), any shape."""

IntArray = NDArray[np.intp]
"""An array of indices."""

BoolArray = NDArray[np.bool_]
"""An array of flags."""

Vec3 = tuple[float, float, float]
"""A point or direction as plain floats, as records store them (JSON-ready)."""


def vec3(v: Sequence[float] | FloatArray) -> Vec3:
    """The first three components of ``v`` as plain floats."""
    return (float(v[0]), float(v[1]), float(v[2]))
