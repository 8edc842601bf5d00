"""The layered model of objects made of boxes: stacked layer contours extruded as blocks.

Objects made of boxes (the paper's Fig. 1) are explored in layers, and their model is not a
convex polyhedron. :func:`section_solid` extrudes each layer's contour polygon as vertical
walls, from the table to the highest layer at which contact was kept (or to the top when the
finger touched it), consecutive layers with the same contour forming one block. The grasp
planner and the pictures use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.geometry

from tactile_kb.geometry.model import ObjectModel
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray, vec3

__all__ = [
    "SAME_CONTOUR",
    "SECTION_TOL",
    "TOP_NORMAL_DEG",
    "SectionBlock",
    "SectionSolid",
    "section_solid",
]

SAME_CONTOUR = DEFAULTS.geometry.same_contour
"""Consecutive layers form one block when their contours differ by less than this fraction of
the smaller one's area (symmetric difference)."""

TOP_NORMAL_DEG = DEFAULTS.geometry.top_normal_deg
"""A contact whose normal is within this angle of "up" touched a top."""

SECTION_TOL = DEFAULTS.geometry.section_tol
"""Gaps and obstacles thinner than this (m) along the grasp line are slivers of noise."""


def _polygon_moments(polygon: FloatArray) -> tuple[float, FloatArray, float]:
    """Area, centroid and E|p − c|² (m²) of a simple polygon given counter-clockwise.

    Area and centroid are shapely's; shapely has no second moment, so ∫|p|² dA is summed over
    the polygon's edges (Green's theorem).
    """
    shape = shapely.Polygon(polygon)
    area = float(shape.area)
    c = np.array([shape.centroid.x, shape.centroid.y])
    x, y = polygon[:, 0], polygon[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    polar = float(((x * x + x * xn + xn * xn + y * y + y * yn + yn * yn) * cross).sum()) / 12.0
    return area, c, polar / area - float(c @ c)


@dataclass(frozen=True, eq=False)
class SectionBlock:
    """Material between heights ``z0`` and ``z1`` whose horizontal section is ``polygon``.

    Attributes
    ----------
    polygon
        (k, 2) corners, counter-clockwise seen from above; side k joins corners k and k + 1.
    z0, z1
        The block's bottom and top, metres.
    layers
        Indices of the exploration layers (:attr:`~tactile_kb.geometry.model.ObjectModel.layers`) it
        comes from.
    """

    polygon: FloatArray
    z0: float
    z1: float
    layers: tuple[int, ...]

    @property
    def shape(self) -> shapely.Polygon:
        """The polygon as a shapely polygon."""
        return shapely.Polygon(self.polygon)

    @property
    def area(self) -> float:
        """Area of the section, m²."""
        return _polygon_moments(self.polygon)[0]

    @property
    def volume(self) -> float:
        """Volume of the block, m³."""
        return self.area * (self.z1 - self.z0)


@dataclass(frozen=True, eq=False)
class SectionSolid:
    """A prism-like model of a layered exploration: contour polygons extruded as vertical walls.

    Attributes
    ----------
    blocks
        Bottom up; the first stands on the table (z = 0), the last ends at ``height``.
    height
        The top: the touched top when ``top_touched``, else the highest layer at which contact
        was kept (a lower bound: the true top lies below the next z-increment).
    top_touched
        True when a contact found a top above the highest layer.
    volume
        m³.
    centroid
        The centre of mass (uniform density), metres.
    second_moment
        E|x − c|² over the solid, m² (λ = √(2 · second_moment) is its :func:`torque_scale`).
    """

    blocks: tuple[SectionBlock, ...]
    height: float
    top_touched: bool
    volume: float
    centroid: tuple[float, float, float]
    second_moment: float

    @property
    def torque_scale(self) -> float:
        """λ = √(tr I / m), metres."""
        return math.sqrt(2.0 * self.second_moment)

    @property
    def note(self) -> str:
        """The height assumption in words."""
        top = (
            "the top the finger touched"
            if self.top_touched
            else "the highest layer at which contact was kept (the top was not touched: the "
            "true top lies higher, up to one z-increment, and the centre of mass with it)"
        )
        blocks = "" if len(self.blocks) == 1 else f" in {len(self.blocks)} blocks"
        return (
            f"planned on the layer contours extruded as vertical walls{blocks} from the table "
            f"to z = {self.height * 1000:.1f} mm, {top}"
        )


def _layer_polygon(contour: FloatArray) -> FloatArray | None:
    """A layer contour as a simple counter-clockwise polygon (the largest part), or None."""
    c = np.asarray(contour, dtype=float).reshape(-1, 2)
    if len(c) < 3:
        return None
    shape = shapely.Polygon(c)
    if not shape.is_valid:
        fixed = shapely.validation.make_valid(shape)
        parts = [g for g in getattr(fixed, "geoms", [fixed]) if isinstance(g, shapely.Polygon)]
        if not parts:
            return None
        shape = max(parts, key=lambda g: g.area)
    if shape.area <= 1e-8:  # below 0.1 cm²: not a section of an object
        return None
    shape = shapely.geometry.polygon.orient(shape.simplify(0.0), 1.0)
    return np.asarray(shape.exterior.coords, dtype=float)[:-1]


def section_solid(model: ObjectModel) -> SectionSolid | None:
    """The layered model of ``model``: its closed layer contours extruded, or None without any.

    Consecutive layers whose contours differ by less than :data:`SAME_CONTOUR` of their area
    form one block (its polygon is the smaller contour); block boundaries lie half-way between
    layers, the first block starts on the table (z = 0), and the last ends at the top the
    finger touched, or else at the highest layer (the walls are assumed vertical).

    Examples
    --------
    >>> from tactile_kb.touch.finger import builtin_finger
    >>> from tactile_kb.geometry.model import build_model
    >>> from tactile_kb.solids import l_shape
    >>> from tactile_kb.touch.synthetic import sample_layers
    >>> record = sample_layers(l_shape(0.12, 0.08, 0.04, 0.04), builtin_finger("4"), [0.01, 0.03])
    >>> solid = section_solid(build_model(record))
    >>> len(solid.blocks), solid.height, solid.top_touched
    (1, 0.03, False)
    >>> [round(x, 4) + 0.0 for x in solid.centroid], round(solid.volume * 1e6, 1)
    ([-0.01, -0.01, 0.015], 192.0)
    """
    layers = []
    for lay in sorted(model.layers, key=lambda s: s.z):
        if not lay.closed:
            continue
        poly = _layer_polygon(lay.contour)
        if poly is not None:
            layers.append((lay.index, lay.z, poly))
    if not layers:
        return None
    top_layer = layers[-1][1]
    cos_up = math.cos(math.radians(current().geometry.top_normal_deg))
    tops = [c.point[2] for c in model.record.contacts if c.normal[2] >= cos_up]
    touched = [z for z in tops if z > top_layer + current().geometry.section_tol]
    height = max(touched) if touched else top_layer
    groups: list[list[tuple[int, float, FloatArray]]] = [[layers[0]]]
    for item in layers[1:]:
        a, b = shapely.Polygon(groups[-1][-1][2]), shapely.Polygon(item[2])
        if a.symmetric_difference(b).area <= current().geometry.same_contour * min(a.area, b.area):
            groups[-1].append(item)
        else:
            groups.append([item])
    blocks = []
    for k, group in enumerate(groups):
        z0 = 0.0 if k == 0 else (groups[k - 1][-1][1] + group[0][1]) / 2.0
        z1 = height if k == len(groups) - 1 else (group[-1][1] + groups[k + 1][0][1]) / 2.0
        poly = min((g[2] for g in group), key=lambda p: _polygon_moments(p)[0])
        blocks.append(SectionBlock(poly, z0, z1, tuple(g[0] for g in group)))
    masses, centres, spreads = [], [], []
    for b in blocks:
        area, c, spread = _polygon_moments(b.polygon)
        h = b.z1 - b.z0
        masses.append(area * h)
        centres.append([c[0], c[1], (b.z0 + b.z1) / 2.0])
        spreads.append(spread + h * h / 12.0)  # about the block's own centroid
    m = np.asarray(masses)
    volume = float(m.sum())
    if volume <= 0.0:
        return None
    cs = np.asarray(centres)
    com = (m[:, None] * cs).sum(axis=0) / volume
    second = float((m * (np.asarray(spreads) + ((cs - com) ** 2).sum(axis=1))).sum()) / volume
    return SectionSolid(tuple(blocks), height, bool(touched), volume, vec3(com), second)
