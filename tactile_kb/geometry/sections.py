"""Cross-sections: of the polyhedron at a height, and of non-convex objects layer by layer.

The paper explores objects composed of rectangular parallelepipeds (its Fig. 1) in horizontal
layers: in each plane z = const the finger follows the contour, touching planes P1, P2, ...
in turn. :func:`contour_from_contacts` turns one layer's contacts (in contact order) into the
contour polygon by intersecting consecutive touched lines; :func:`layer_sections` does it for
every layer of a record, and :func:`distinct_planes` counts the different planes over all
layers (seven, P1…P7, in Fig. 1).

Examples
--------
>>> import numpy as np
>>> from tactile_kb.geometry.polyhedron import polyhedron_from_planes
>>> box = polyhedron_from_planes(np.vstack([np.eye(3), -np.eye(3)]), [0.05, 0.03, 0.04, 0.05, 0.03, 0.0])
>>> s = cross_section(box, 0.02)
>>> len(s), round(polygon_area(s) * 1e4, 6)
(4, 60.0)
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
import shapely.geometry.polygon

from tactile_kb.errors import UsageError
from tactile_kb.geometry.polyhedron import Polyhedron
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray

__all__ = [
    "FAR_CORNER",
    "LayerSection",
    "TouchedLine",
    "contour_from_contacts",
    "cross_section",
    "distinct_planes",
    "layer_sections",
    "polygon_area",
]


LINE_TOL = DEFAULTS.geometry.line_tol
"""Two touched lines within this distance (m) and ``PLANE_DEG`` are the same plane."""

PLANE_DEG = DEFAULTS.geometry.plane_deg
"""Two touched lines within this angle (degrees) and ``LINE_TOL`` are the same plane."""

SPAN_2D = DEFAULTS.geometry.span_2d
"""A side's line is refined from its tip centres when they spread this much (m, RMS)."""


def polygon_area(polygon: FloatArray | Sequence[Sequence[float]]) -> float:
    """Signed area of a 2-D polygon (positive when counter-clockwise)."""
    p = np.asarray(polygon, dtype=float).reshape(-1, 2)
    if len(p) < 3:
        return 0.0
    return float(shapely.geometry.polygon.signed_area(shapely.LinearRing(p)))


def cross_section(poly: Polyhedron, z: float) -> FloatArray:
    """The polygon (k, 2), counter-clockwise seen from above, where the plane at height ``z``
    cuts ``poly``; empty (0, 2) when the plane misses it."""
    v = poly.vertices
    e = np.asarray(poly.edges, dtype=np.intp).reshape(-1, 2)
    va, vb = v[e[:, 0]], v[e[:, 1]]
    za, zb = va[:, 2] - z, vb[:, 2] - z
    cut = za * zb < 0
    t = za[cut] / (za[cut] - zb[cut])
    pts = np.concatenate(
        [
            va[za == 0.0, :2],
            vb[zb == 0.0, :2],
            va[cut, :2] + t[:, None] * (vb[cut, :2] - va[cut, :2]),
        ]
    )
    if len(pts) < 3:
        return np.zeros((0, 2))
    r = np.round(pts, 12)
    r = r[np.lexsort((r[:, 1], r[:, 0]))]  # np.unique(r, axis=0), without its overhead
    p = r[np.concatenate([[True], (r[1:] != r[:-1]).any(axis=1)])]
    if len(p) < 3:
        return np.zeros((0, 2))
    c = p.mean(axis=0)
    order = np.argsort(np.arctan2(p[:, 1] - c[1], p[:, 0] - c[0]))
    return np.asarray(p[order], dtype=float)


@dataclass(frozen=True)
class TouchedLine:
    """A side of a layer's contour: ``normal · (x, y) = offset`` with ``normal`` outward."""

    normal: tuple[float, float]
    offset: float
    contacts: tuple[int, ...]
    refined: bool


@dataclass(frozen=True)
class LayerSection:
    """One z-layer of a non-convex exploration: its touched lines and contour polygon."""

    index: int
    z: float
    lines: tuple[TouchedLine, ...]
    contour: FloatArray
    closed: bool

    @property
    def area(self) -> float:
        """Area of the contour polygon, m²."""
        return abs(polygon_area(self.contour))


def _contact_line(c: Contact) -> tuple[FloatArray, float] | None:
    n = np.asarray(c.normal, dtype=float)
    nxy = n[:2]
    length = float(np.linalg.norm(nxy))
    if length < 0.5:  # mostly horizontal surface: not a side of the contour
        return None
    d = float(n @ np.asarray(c.point)) - n[2] * c.point[2]
    return nxy / length, d / length


def touched_lines(
    contacts: Sequence[Contact], tip_radius: float, *, indices: Sequence[int] | None = None
) -> list[TouchedLine]:
    """The distinct lines touched in one layer, in contact order (runs of the same side)."""
    idx = list(range(len(contacts))) if indices is None else list(indices)
    runs: list[tuple[FloatArray, float, list[int]]] = []
    cos_tol = math.cos(math.radians(5.0))
    for k, c in zip(idx, contacts, strict=True):
        line = _contact_line(c)
        if line is None:
            continue
        n, d = line
        if runs and float(n @ runs[-1][0]) >= cos_tol:
            runs[-1][2].append(k)
            continue
        runs.append((n, d, [k]))
    pos = {k: i for i, k in enumerate(idx)}
    out = []
    for n, d, ks in runs:
        centres = np.asarray([contacts[pos[k]].centre[:2] for k in ks], dtype=float)
        refined = False
        if len(ks) >= 2:
            mean = centres.mean(axis=0)
            _, s, vt = np.linalg.svd(centres - mean)
            if s[0] / math.sqrt(len(ks)) >= current().geometry.span_2d:
                m = np.array([-vt[0, 1], vt[0, 0]])
                m = m if m @ n >= 0 else -m
                if m @ n >= math.cos(math.radians(35.0)):
                    n, d, refined = m, float(m @ mean) - tip_radius, True
        out.append(TouchedLine((float(n[0]), float(n[1])), float(d), tuple(ks), refined))
    # the contour closes on the side it started from
    if len(out) > 2:
        a, b = out[0], out[-1]
        if (
            np.dot(a.normal, b.normal) >= cos_tol
            and abs(a.offset - b.offset) <= current().geometry.line_tol
        ):
            out[0] = TouchedLine(
                a.normal, a.offset, b.contacts + a.contacts, a.refined or b.refined
            )
            out.pop()
    return out


def contour_from_contacts(
    contacts: Sequence[Contact], tip_radius: float, *, closed: bool = True
) -> list[tuple[float, float]]:
    """The contour polygon of one layer, counter-clockwise, from its contacts in order.

    Consecutive contacts on the same side give one line (refined by a least-squares line
    through the tip centres when they spread along it), and consecutive lines are intersected:
    P1 ∩ P2, P2 ∩ P3, …, and, when ``closed``, the last with the first.

    Raises
    ------
    UsageError
        Fewer than three distinct sides were touched.
    """
    lines = touched_lines(contacts, tip_radius)
    points = {i: np.asarray(c.point[:2], dtype=float) for i, c in enumerate(contacts)}
    return [(float(x), float(y)) for x, y in _polygon(lines, closed, points)]


FAR_CORNER = 0.25
"""A contour corner (two touched lines meeting) further outside the box of its layer's contact
points than this share of the box's diagonal is not a corner: the two lines are nearly
parallel, with an unexplored side between them. The contour runs from the last contact on the
one line to the first on the other instead."""


def _project(line: TouchedLine, point: FloatArray) -> FloatArray:
    n = np.asarray(line.normal, dtype=float)
    return np.asarray(point - (float(n @ point) - line.offset) * n, dtype=float)


def _polygon(
    lines: Sequence[TouchedLine], closed: bool, points: Mapping[int, FloatArray]
) -> FloatArray:
    """The contour through consecutive ``lines``' corners; ``points`` are the layer's contact
    points (x, y) by the indices the lines hold."""
    if len(lines) < 3:
        raise UsageError(f"a contour needs at least three touched sides, got {len(lines)}")
    pairs = list(itertools.pairwise(lines))
    if closed:
        pairs.append((lines[-1], lines[0]))
    touched = np.asarray(list(points.values()), dtype=float).reshape(-1, 2)
    lo, hi = touched.min(axis=0), touched.max(axis=0)
    slack = FAR_CORNER * float(np.linalg.norm(hi - lo))
    pts = []
    for a, b in pairs:
        m = np.array([a.normal, b.normal])
        if abs(np.linalg.det(m)) < 1e-6:
            continue  # parallel neighbours (an unexplored side in between)
        corner = np.linalg.solve(m, [a.offset, b.offset])
        if bool(np.all(corner >= lo - slack) & np.all(corner <= hi + slack)):
            pts.append(corner)
        else:  # nearly parallel: the chord across the unexplored side between them
            pts.append(_project(a, points[a.contacts[-1]]))
            pts.append(_project(b, points[b.contacts[0]]))
    poly = np.asarray(pts, dtype=float).reshape(-1, 2)
    if polygon_area(poly) < 0:
        poly = poly[::-1]
    return poly


def layer_sections(record: ExplorationRecord) -> tuple[LayerSection, ...]:
    """The contour of every layer of ``record`` (contacts with a ``layer`` index), bottom up."""
    by_layer: dict[int, list[int]] = {}
    for i, c in enumerate(record.contacts):
        if c.layer is not None:
            by_layer.setdefault(c.layer, []).append(i)
    out = []
    for layer, idx in sorted(by_layer.items()):
        idx.sort(key=lambda i: record.contacts[i].step)
        cs = [record.contacts[i] for i in idx]
        lines = tuple(touched_lines(cs, record.tip_radius, indices=idx))
        z = float(np.median([c.point[2] for c in cs]))
        closed = any(lay.index == layer and lay.closed for lay in record.layers) or len(lines) >= 3
        points = {i: np.asarray(record.contacts[i].point[:2], dtype=float) for i in idx}
        try:
            contour = _polygon(lines, closed, points)
        except UsageError:
            contour = np.zeros((0, 2))
        out.append(LayerSection(layer, z, lines, contour, closed))
    return tuple(out)


def distinct_planes(
    sections: Sequence[LayerSection],
    *,
    angle_deg: float | None = None,
    offset_tol: float | None = None,
) -> list[tuple[tuple[float, float], float]]:
    """The different vertical planes ``(normal_xy, offset)`` touched over all layers."""
    if angle_deg is None:
        angle_deg = current().geometry.plane_deg
    if offset_tol is None:
        offset_tol = current().geometry.line_tol
    out: list[tuple[tuple[float, float], float]] = []
    cos_tol = math.cos(math.radians(angle_deg))
    for s in sections:
        for line in s.lines:
            if not any(
                np.dot(line.normal, n) >= cos_tol and abs(line.offset - d) <= offset_tol
                for n, d in out
            ):
                out.append((line.normal, line.offset))
    return out
