"""Grasping by the minimal angle of prehension, in line with the centre of mass.

"Grasping is based on the simple principle of minimal angle of prehension; that is, when the
two tangential planes at the points of contact between the two fingers of the pincers and the
object are essentially parallel. Moreover, the grasping points should be in line with the
object's center of mass." :func:`plan_grasp` turns that sentence into a plan:

1. **Pairs of (nearly) parallel faces** of the model's polyhedron: the angle between the two
   planes at most the friction angle ``arctan μ`` (26.6° for μ = 0.5). The table face (z = 0,
   the support) cannot be grasped: pairs using it are rejected.
2. **A grasp line along their common normal** (the bisector of the two inward normals) through
   the centre of mass; when that line leaves one of the faces (with ``margin`` to spare), the
   nearest line that stays inside both is taken, and its distance from the centre of mass is
   the ``com_offset``. Both grasp points are where the line meets the two planes; their
   distance is the jaw opening, which must lie within the pincers' range.
3. **Validation**: the two-contact force-closure test of Nguyen (1988) (the line through both
   contacts lies inside both friction cones) and a quality measure, the soft-finger
   Ferrari–Canny ε (:func:`ferrari_canny`), with the least total contact force that holds the
   object against gravity (:func:`least_force`) beside it.
4. **Ranking** by the angle between the planes (in steps of :data:`RANK_ANGLE_STEP_DEG`, 2°:
   angles within the noise of a measurement count as equal), then the offset of the grasp
   line from the centre of mass (whole millimetres), then the jaw opening (narrower first).

When no pair survives, :attr:`GraspPlan.reason` says why: no parallel pair, every pair wider
than the pincers, the grasp line outside a face, or only the table face.

**Objects made of boxes** (the paper's Fig. 1) are explored in layers, and their model is not
a convex polyhedron: the 4-sensor finger never touches the top (the planes stay open), and
with the 33-sensor finger the polyhedron is only the convex envelope. Their grasp is planned
on the stacked layer contours instead (:func:`section_solid`): each contour polygon is
extruded as vertical walls, from the table to the highest layer at which contact was kept (or
to the top when the finger touched it), consecutive layers with the same contour forming one
block. The centre of mass is that of the extruded polygons; the pairs are antiparallel sides
of a block's contour facing away from each other; the grasp line is horizontal, at the height
of the centre of mass (kept ``margin`` inside the block), along the pair's common normal; and
besides the margins it must satisfy two conditions of a non-convex body: the segment between
the two grasp points lies inside the material (no grasp across the notch of a U), and each
jaw, a pad of radius ``margin`` approaching horizontally from outside along the grasp line,
meets no other part of the object on its way. When the centre of mass lies outside the
material (an L) the line passing closest to it wins, and its offset is reported.
:attr:`GraspPlan.notes` states the height assumption.

The contact model (the pincers' pads are soft): each contact pushes with a force inside its
friction cone (linearised by ``cone_edges`` unit forces on the cone's boundary, one of them
pointing straight up so holding against gravity is exact) and may twist about its normal by
torsional friction, modelled as two extra wrench primitives ``±ρ·n`` (a unit force acting at
the pad radius ρ, 5 mm by default). The grasp wrench set is the convex hull of these
primitives (total contact force ≤ 1 N); ε is the radius of the largest ball about the
origin inside it (torques divided by the object's size ``λ = √(tr I / m)``), and the least
force is its gauge at the gravity wrench. With hard point contacts (``soft=False``) two
contacts cannot resist a torque about the line joining them, so ε = 0.

Examples
--------
>>> import numpy as np
>>> points = np.array([[0.05, 0.0, 0.02], [-0.05, 0.0, 0.02]])
>>> normals = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
>>> force_closure(points, normals, mu=0.5)
True
>>> round(least_force(points, normals, com=(0.0, 0.0, 0.02), mass=0.2), 2)
4.39
>>> ferrari_canny(points, normals, com=(0.0, 0.0, 0.02), torque_scale=0.05, soft=False)
0.0
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
import shapely.geometry
import shapely.ops
import shapely.validation
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from tactile_kb.errors import UsageError
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.geometry.polyhedron import Polyhedron
from tactile_kb.record import ExplorationRecord

__all__ = [
    "DEFAULT_CONE_EDGES",
    "DEFAULT_DENSITY",
    "DEFAULT_MARGIN",
    "DEFAULT_MAX_COM_OFFSET",
    "DEFAULT_MAX_OPENING",
    "DEFAULT_MU",
    "DEFAULT_PAD_RADIUS",
    "GRAVITY",
    "QUALITY_MEASURE",
    "RANK_ANGLE_STEP_DEG",
    "GraspCandidate",
    "GraspPlan",
    "Rejection",
    "SectionBlock",
    "SectionSolid",
    "ferrari_canny",
    "force_closure",
    "least_force",
    "plan_grasp",
    "section_solid",
    "torque_scale",
    "wrench_primitives",
]

FloatArray = NDArray[np.float64]

DEFAULT_MU = 0.5
"""Coefficient of friction between the pads and the object (friction angle 26.6°)."""

DEFAULT_MAX_OPENING = 0.15
"""Widest jaw opening of the pincers, metres."""

DEFAULT_MARGIN = 0.005
"""Each grasp point must lie at least this far (m) inside its face: the pad radius."""

DEFAULT_MAX_COM_OFFSET = 0.02
"""The grasp line may pass at most this far (m) from the centre of mass."""

DEFAULT_PAD_RADIUS = 0.005
"""ρ of the soft pads, metres: torsional friction is modelled as a unit force at this radius."""

DEFAULT_CONE_EDGES = 8
"""Unit forces on the boundary of each friction cone (its linearisation)."""

DEFAULT_DENSITY = 1000.0
"""kg/m³, for the object's mass when none is given (touch does not weigh)."""

GRAVITY = 9.81
"""m/s²."""

RANK_ANGLE_STEP_DEG = 2.0
"""Candidates whose planes' angles fall in the same step of this many degrees rank as equally
parallel (0.4° and 0.6° apart are both "parallel" to a finger with 0.5 mm of noise)."""

QUALITY_MEASURE = "ferrari_canny_soft"
"""The name of :attr:`GraspCandidate.quality` in JSON output."""

TABLE_ANGLE_DEG = 5.0
TABLE_HEIGHT_TOL = 0.002

SAME_CONTOUR = 0.05
"""Consecutive layers form one block when their contours differ by less than this fraction of
the smaller one's area (symmetric difference)."""

TOP_NORMAL_DEG = 20.0
"""A contact whose normal is within this angle of "up" touched a top."""

SECTION_TOL = 0.001
"""Gaps and obstacles thinner than this (m) along the grasp line are slivers of noise."""

_UP = np.array([0.0, 0.0, 1.0])


# ---------------------------------------------------------------------------------------------
# Contact mechanics
# ---------------------------------------------------------------------------------------------


def _contacts(points: ArrayLike, normals: ArrayLike) -> tuple[FloatArray, FloatArray]:
    p = np.asarray(points, dtype=float)
    n = np.asarray(normals, dtype=float)
    if p.shape != n.shape or p.ndim != 2 or p.shape[1] != 3 or len(p) < 1:
        raise UsageError(f"points and normals must both be (k, 3) arrays, got {p.shape}, {n.shape}")
    lengths = np.linalg.norm(n, axis=1)
    if np.any(lengths < 1e-12) or not np.all(np.isfinite(p)):
        raise UsageError("contact normals must be non-zero and points finite")
    return p, n / lengths[:, None]


def force_closure(points: ArrayLike, normals: ArrayLike, *, mu: float = DEFAULT_MU) -> bool:
    """Nguyen's two-contact test: the line through both contacts lies in both friction cones.

    Parameters
    ----------
    points, normals
        (2, 3) contact points and the object's outward unit normals there.
    mu
        Coefficient of friction; the cones' half-angle is ``arctan mu``.

    Returns
    -------
    bool
        True when the angle between the line and each inward normal is at most ``arctan mu``.
    """
    p, n = _contacts(points, normals)
    if len(p) != 2:
        raise UsageError(f"the two-contact test needs exactly 2 contacts, got {len(p)}")
    line = p[1] - p[0]
    length = float(np.linalg.norm(line))
    if length < 1e-12:
        return False
    line /= length
    half = math.atan(mu) + 1e-9
    a0 = math.acos(float(np.clip(np.dot(line, -n[0]), -1.0, 1.0)))
    a1 = math.acos(float(np.clip(np.dot(-line, -n[1]), -1.0, 1.0)))
    return a0 <= half and a1 <= half


def _tangents(inward: FloatArray) -> tuple[FloatArray, FloatArray]:
    """A tangent basis whose first vector is the projection of "up" (x when the face is level)."""
    t1 = _UP - np.dot(_UP, inward) * inward
    if np.linalg.norm(t1) < 1e-6:
        t1 = np.array([1.0, 0.0, 0.0]) - inward[0] * inward
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(inward, t1)


def wrench_primitives(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    torque_scale: float = 1.0,
) -> FloatArray:
    """The wrenches (force, torque / ``torque_scale``) one newton of contact force can exert.

    Parameters
    ----------
    points, normals
        (k, 3) contact points and outward unit normals of the object there.
    com
        The object's centre of mass: torques are taken about it.
    mu
        Coefficient of friction.
    soft
        Add the soft-finger torsion primitives ``±pad_radius · n`` at each contact.
    pad_radius
        Radius (m) at which the torsional friction of a soft pad acts.
    cone_edges
        Unit forces on each friction cone's boundary; the first is tilted straight up.
    torque_scale
        λ, metres: torques are divided by it so forces and torques compare.

    Returns
    -------
    numpy.ndarray
        (k · (cone_edges + 2·soft), 6) rows ``(fx, fy, fz, τx/λ, τy/λ, τz/λ)``.
    """
    p, n = _contacts(points, normals)
    c = np.asarray(com, dtype=float).reshape(3)
    if cone_edges < 3:
        raise UsageError(f"cone_edges must be at least 3, got {cone_edges}")
    if mu < 0 or torque_scale <= 0 or pad_radius < 0:
        raise UsageError("mu and pad_radius must be ≥ 0 and torque_scale > 0")
    rows = []
    angles = 2.0 * np.pi * np.arange(cone_edges) / cone_edges
    for point, normal in zip(p, n, strict=True):
        inward = -normal
        t1, t2 = _tangents(inward)
        forces = inward + mu * (np.cos(angles)[:, None] * t1 + np.sin(angles)[:, None] * t2)
        forces /= np.linalg.norm(forces, axis=1)[:, None]
        torques = np.cross(point - c, forces) / torque_scale
        rows.append(np.hstack([forces, torques]))
        if soft:
            twist = pad_radius * inward / torque_scale
            rows.append(np.array([[0, 0, 0, *twist], [0, 0, 0, *(-twist)]], dtype=float))
    return np.vstack(rows)


def ferrari_canny(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    torque_scale: float = 1.0,
) -> float:
    """Ferrari–Canny ε (L1): the largest ball about the origin inside the grasp wrench hull.

    The hull is that of :func:`wrench_primitives` (total contact force ≤ 1 N); ε is in
    newtons (torques divided by ``torque_scale``). 0 when the grasp cannot resist some wrench
    (two hard contacts never resist a torque about the line joining them).
    """
    w = wrench_primitives(
        points,
        normals,
        com,
        mu=mu,
        soft=soft,
        pad_radius=pad_radius,
        cone_edges=cone_edges,
        torque_scale=torque_scale,
    )
    if np.linalg.matrix_rank(w, tol=1e-9) < 6:
        return 0.0
    try:
        hull = ConvexHull(w)
    except QhullError:  # flat: the wrenches span fewer than six dimensions
        return 0.0
    distances = -hull.equations[:, -1]  # offsets b of n·x + b ≤ 0, n unit
    return float(max(0.0, distances.min()))


def least_force(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    mass: float,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    gravity: float = GRAVITY,
) -> float | None:
    """The least total contact force (N) that holds ``mass`` kg against gravity, or None.

    A linear programme over :func:`wrench_primitives`: non-negative amounts of each unit
    primitive whose wrenches cancel the weight ``(0, 0, −m g)`` acting at ``com``; the sum of
    the amounts is the total force (the twist primitives count as a force at the pad radius).
    None when no contact forces can hold the object (hard contacts off the centre of mass).
    """
    if mass <= 0:
        raise UsageError(f"mass must be > 0 kg, got {mass}")
    w = wrench_primitives(
        points, normals, com, mu=mu, soft=soft, pad_radius=pad_radius, cone_edges=cone_edges
    )
    weight = np.array([0.0, 0.0, -mass * gravity, 0.0, 0.0, 0.0])
    res = linprog(np.ones(len(w)), A_eq=w.T, b_eq=-weight, bounds=(0, None), method="highs")
    if res.status != 0:
        return None
    return float(res.fun)


def torque_scale(poly: Polyhedron) -> float:
    """λ = √(tr I / m) of a uniform solid polyhedron, metres (for a box a×b×c: √((a²+b²+c²)/6))."""
    return math.sqrt(_second_moment(poly) * 2.0)


def _mesh(poly: Polyhedron) -> trimesh.Trimesh:
    tris = [(f[0], f[k], f[k + 1]) for f in poly.faces for k in range(1, len(f) - 1)]
    return trimesh.Trimesh(vertices=poly.vertices, faces=np.asarray(tris), process=False)


def _second_moment(poly: Polyhedron) -> float:
    """E|x − c|² over the solid, m²."""
    mesh = _mesh(poly)
    inertia = np.asarray(mesh.moment_inertia, dtype=float)  # density 1, about the centre of mass
    volume = float(mesh.volume)
    if volume <= 0:
        raise UsageError("the polyhedron has no volume")
    return float(np.trace(inertia)) / (2.0 * volume)


# ---------------------------------------------------------------------------------------------
# The layered model of objects made of boxes
# ---------------------------------------------------------------------------------------------


def _polygon_moments(polygon: FloatArray) -> tuple[float, FloatArray, float]:
    """Area, centroid and E|p − c|² (m²) of a simple polygon given counter-clockwise."""
    x, y = polygon[:, 0], polygon[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * float(cross.sum())
    cx = float(((x + xn) * cross).sum()) / (6.0 * area)
    cy = float(((y + yn) * cross).sum()) / (6.0 * area)
    ixx = float(((y * y + y * yn + yn * yn) * cross).sum()) / 12.0  # ∫ y² dA
    iyy = float(((x * x + x * xn + xn * xn) * cross).sum()) / 12.0  # ∫ x² dA
    return area, np.array([cx, cy]), (ixx + iyy) / area - (cx * cx + cy * cy)


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
    cos_up = math.cos(math.radians(TOP_NORMAL_DEG))
    tops = [c.point[2] for c in model.record.contacts if c.normal[2] >= cos_up]
    touched = [z for z in tops if z > top_layer + SECTION_TOL]
    height = max(touched) if touched else top_layer
    groups: list[list[tuple[int, float, FloatArray]]] = [[layers[0]]]
    for item in layers[1:]:
        a, b = shapely.Polygon(groups[-1][-1][2]), shapely.Polygon(item[2])
        if a.symmetric_difference(b).area <= SAME_CONTOUR * min(a.area, b.area):
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
    return SectionSolid(tuple(blocks), height, bool(touched), volume, _vec(com), second)


# ---------------------------------------------------------------------------------------------
# Planning
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class GraspCandidate:
    """One two-finger grasp on a pair of (nearly) parallel faces.

    Attributes
    ----------
    faces
        The two polyhedron face indices.
    points
        (2, 3) grasp points, metres, on the two faces.
    normals
        (2, 3) outward unit normals of the two faces.
    angle_deg
        Angle between the two planes (0: parallel).
    com_offset
        Distance (m) from the centre of mass to the grasp line.
    width
        Jaw opening: the distance between the grasp points, metres.
    force_closure
        Nguyen's two-contact test.
    quality
        Soft-finger Ferrari–Canny ε (see :func:`ferrari_canny`).
    least_force
        Least total contact force holding the object against gravity, N (None: cannot).
    section
        For a grasp planned on the layer contours: the index of the block in
        :attr:`SectionSolid.blocks`, and ``faces`` are sides of its contour (side k joins
        corners k and k + 1); None for polyhedron faces.
    """

    faces: tuple[int, int]
    points: tuple[tuple[float, float, float], tuple[float, float, float]]
    normals: tuple[tuple[float, float, float], tuple[float, float, float]]
    angle_deg: float
    com_offset: float
    width: float
    force_closure: bool
    quality: float
    least_force: float | None
    section: int | None = None

    @property
    def rank_key(self) -> tuple[int, int, float]:
        """Angle in steps of :data:`RANK_ANGLE_STEP_DEG`, then COM offset in whole millimetres,
        then the opening."""
        step = math.floor(self.angle_deg / RANK_ANGLE_STEP_DEG + 1e-9)
        return (step, round(self.com_offset * 1000.0), self.width)

    def to_dict(self) -> dict[str, Any]:
        """The candidate as JSON-ready values."""
        return {
            "faces": list(self.faces),
            "points": [[_r(x) for x in p] for p in self.points],
            "normals": [[_r(x) for x in n] for n in self.normals],
            "angle_deg": _r(self.angle_deg, 4),
            "com_offset": _r(self.com_offset),
            "width": _r(self.width),
            "quality": _r(self.quality),
            "least_force": None if self.least_force is None else _r(self.least_force, 4),
            "force_closure": self.force_closure,
            "section": self.section,
        }


@dataclass(frozen=True)
class Rejection:
    """A pair of faces that gives no grasp, and why."""

    faces: tuple[int, int]
    kind: str
    """``"table"``, ``"too_wide"``, ``"too_narrow"``, ``"outside_face"``, ``"not_closed"``,
    ``"outside_material"`` (the segment between the grasp points leaves the object) or
    ``"jaw_collision"`` (a jaw meets another part of the object on its way in)."""
    message: str


@dataclass(frozen=True)
class GraspPlan:
    """The best grasp of an object and the ranked alternatives, or why there is none.

    ``basis`` names the model the grasp was planned on: ``"polyhedron"`` (the enveloping
    polyhedron's faces) or ``"sections"`` (the layer contours extruded, :attr:`solid`);
    ``notes`` state the assumptions made (the height of a layered object).
    """

    object: str
    best: GraspCandidate | None
    candidates: tuple[GraspCandidate, ...]
    reason: str
    rejected: tuple[Rejection, ...] = ()
    com: tuple[float, float, float] | None = None
    mass: float | None = None
    params: dict[str, float] = field(default_factory=dict)
    basis: str = "polyhedron"
    notes: tuple[str, ...] = ()
    solid: SectionSolid | None = None

    @property
    def ok(self) -> bool:
        """True when there is a grasp."""
        return self.best is not None

    def to_dict(self) -> dict[str, Any]:
        """The JSON line of ``tactile-kb grasp --json``."""
        b = self.best
        return {
            "object": self.object,
            "points": None if b is None else [[_r(x) for x in p] for p in b.points],
            "normals": None if b is None else [[_r(x) for x in n] for n in b.normals],
            "angle_deg": None if b is None else _r(b.angle_deg, 4),
            "com_offset": None if b is None else _r(b.com_offset),
            "width": None if b is None else _r(b.width),
            "quality": None if b is None else _r(b.quality),
            "quality_measure": QUALITY_MEASURE,
            "least_force": None if b is None or b.least_force is None else _r(b.least_force, 4),
            "force_closure": False if b is None else b.force_closure,
            "reason": self.reason or None,
            "com": None if self.com is None else [_r(x) for x in self.com],
            "mass": None if self.mass is None else _r(self.mass),
            "candidates": len(self.candidates),
            "basis": self.basis,
            "notes": list(self.notes),
        }


def _r(x: float, digits: int = 6) -> float:
    return round(float(x), digits) + 0.0  # + 0.0 turns -0.0 into 0.0


def _unit(v: FloatArray) -> FloatArray:
    return v / float(np.linalg.norm(v))


def _table_faces(model: ObjectModel | None, poly: Polyhedron) -> set[int]:
    out = set()
    zmin = float(poly.vertices[:, 2].min())
    cos_tol = math.cos(math.radians(TABLE_ANGLE_DEG))
    for k, (n, d) in enumerate(zip(poly.normals, poly.offsets, strict=True)):
        if n[2] <= -cos_tol and abs(d) <= TABLE_HEIGHT_TOL and zmin <= TABLE_HEIGHT_TOL:
            out.add(k)
        known = model is not None and len(model.face_of) == len(poly.faces)
        if known and model is not None and model.faces[model.face_of[k]].source == "table":
            out.add(k)
    return out


def _basis(axis: FloatArray) -> tuple[FloatArray, FloatArray]:
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = _unit(np.cross(axis, helper))
    return u, np.cross(axis, u)


def _project(poly: Polyhedron, face: int, u: FloatArray, v: FloatArray) -> shapely.Polygon:
    pts = poly.vertices[list(poly.faces[face])]
    return shapely.Polygon(np.column_stack([pts @ u, pts @ v])).buffer(0)


def plan_grasp(
    model_or_record: ObjectModel | ExplorationRecord,
    *,
    mu: float = DEFAULT_MU,
    max_opening: float = DEFAULT_MAX_OPENING,
    min_opening: float = 0.0,
    margin: float = DEFAULT_MARGIN,
    max_com_offset: float = DEFAULT_MAX_COM_OFFSET,
    max_angle_deg: float | None = None,
    mass: float | None = None,
    density: float = DEFAULT_DENSITY,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
) -> GraspPlan:
    """Plan a two-finger grasp on two (nearly) parallel faces in line with the centre of mass.

    Parameters
    ----------
    model_or_record
        An :class:`~tactile_kb.geometry.model.ObjectModel`, or an exploration record (the model is
        built with :func:`~tactile_kb.geometry.model.build_model`).
    mu
        Coefficient of friction of the pads.
    max_opening, min_opening
        The pincers' range, metres.
    margin
        Each grasp point must be this far (m) inside its face.
    max_com_offset
        Largest distance (m) of the grasp line from the centre of mass.
    max_angle_deg
        Largest angle between the two planes; default the friction angle ``arctan mu``.
    mass
        The object's mass (kg) for :attr:`GraspCandidate.least_force`; default its
        polyhedron's volume times ``density``.
    density
        kg/m³, used when ``mass`` is None.
    pad_radius, cone_edges
        The contact model (see :func:`wrench_primitives`).

    Returns
    -------
    GraspPlan
        ``best`` is the first force-closure candidate in rank order; ``reason`` says why
        there is none.
    """
    for name, value in (("mu", mu), ("max_opening", max_opening), ("margin", margin)):
        if not (math.isfinite(value) and value >= 0):
            raise UsageError(f"{name} must be a finite number ≥ 0, got {value}")
    if min_opening < 0 or min_opening > max_opening:
        raise UsageError(f"min_opening must lie in [0, max_opening], got {min_opening}")
    if isinstance(model_or_record, ExplorationRecord):
        model = build_model(model_or_record)
    elif isinstance(model_or_record, ObjectModel):
        model = model_or_record
    else:
        raise UsageError(
            f"plan_grasp needs an ObjectModel or an ExplorationRecord, "
            f"got {type(model_or_record).__name__}"
        )
    name = model.record.object
    params = {
        "mu": mu,
        "max_opening": max_opening,
        "min_opening": min_opening,
        "margin": margin,
        "max_com_offset": max_com_offset,
        "pad_radius": pad_radius,
    }
    poly = model.polyhedron
    solid = section_solid(model) if poly is None or not model.convex else None

    def assess(
        pair: tuple[int, int],
        points: FloatArray,
        normals: FloatArray,
        angle: float,
        offset: float,
        com: FloatArray,
        scale: float,
        weight: float,
        section: int | None,
    ) -> GraspCandidate | Rejection:
        width = float(np.linalg.norm(points[0] - points[1]))
        if width > max_opening:
            return Rejection(
                pair,
                "too_wide",
                f"{width * 1000:.1f} mm apart, wider than the pincers "
                f"({max_opening * 1000:.1f} mm)",
            )
        if width < min_opening:
            return Rejection(pair, "too_narrow", f"{width * 1000:.1f} mm apart, below the minimum")
        closed = force_closure(points, normals, mu=mu)
        eps = ferrari_canny(
            points,
            normals,
            com,
            mu=mu,
            pad_radius=pad_radius,
            cone_edges=cone_edges,
            torque_scale=scale,
        )
        force = least_force(
            points, normals, com, weight, mu=mu, pad_radius=pad_radius, cone_edges=cone_edges
        )
        return GraspCandidate(
            faces=pair,
            points=(_vec(points[0]), _vec(points[1])),
            normals=(_vec(normals[0]), _vec(normals[1])),
            angle_deg=angle,
            com_offset=offset,
            width=width,
            force_closure=closed,
            quality=eps,
            least_force=force,
            section=section,
        )

    limit = math.degrees(math.atan(mu)) if max_angle_deg is None else max_angle_deg
    candidates: list[GraspCandidate] = []
    rejected: list[Rejection] = []
    notes: tuple[str, ...] = ()
    if solid is not None:
        basis = "sections"
        com = np.asarray(solid.centroid, dtype=float)
        weight = float(mass) if mass is not None else density * solid.volume
        scale = solid.torque_scale
        notes = (solid.note,)
        parallel = 0
        for b in range(len(solid.blocks)):
            for pair, angle, found in _section_pairs(solid, b, com, limit, margin, max_com_offset):
                parallel += 1
                if isinstance(found, Rejection):
                    rejected.append(found)
                    continue
                points, normals, offset = found
                out = assess(pair, points, normals, angle, offset, com, scale, weight, b)
                if isinstance(out, Rejection):
                    rejected.append(out)
                else:
                    candidates.append(out)
    else:
        if poly is None:
            why = model.open_reason or "the touched planes do not bound a region"
            if model.layers:
                why += "; no layer contour closed"
            return GraspPlan(name, None, (), f"no closed model to grasp: {why}", params=params)
        basis = "polyhedron"
        com = np.asarray(poly.centroid, dtype=float)
        weight = float(mass) if mass is not None else density * poly.volume
        scale = torque_scale(poly)
        if not model.convex:
            notes = (
                "the model is not convex and has no layer contours: its centre of mass is that "
                "of the convex envelope, and grasp lines crossing a concave face are refused",
            )
        table = _table_faces(model, poly)
        nf = len(poly.faces)
        parallel = 0
        for i in range(nf):
            for j in range(i + 1, nf):
                ni, nj = poly.normals[i], poly.normals[j]
                angle = math.degrees(math.acos(float(np.clip(-np.dot(ni, nj), -1.0, 1.0))))
                if angle > limit + 1e-9:
                    continue
                parallel += 1
                pair = (i, j)
                if i in table or j in table:
                    rejected.append(Rejection(pair, "table", "uses the table face (the support)"))
                    continue
                got = _grasp_on_pair(poly, pair, com, margin, max_com_offset)
                if isinstance(got, Rejection):
                    rejected.append(got)
                    continue
                points, offset = got
                if not model.convex and _crosses_concave_face(model, points):
                    rejected.append(
                        Rejection(
                            pair,
                            "outside_material",
                            "the segment between the grasp points crosses a concave face",
                        )
                    )
                    continue
                normals = np.vstack([ni, nj])
                out = assess(pair, points, normals, angle, offset, com, scale, weight, None)
                if isinstance(out, Rejection):
                    rejected.append(out)
                else:
                    candidates.append(out)
    candidates.sort(key=lambda c: c.rank_key)
    best = next((c for c in candidates if c.force_closure), None)
    reason = "" if best is not None else _reason(parallel, limit, candidates, rejected)
    return GraspPlan(
        name,
        best,
        tuple(candidates),
        reason,
        tuple(rejected),
        _vec(com),
        weight,
        params,
        basis,
        notes,
        solid,
    )


def _vec(v: Sequence[float] | FloatArray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _grasp_on_pair(
    poly: Polyhedron, pair: tuple[int, int], com: FloatArray, margin: float, max_offset: float
) -> tuple[FloatArray, float] | Rejection:
    """The grasp points on faces ``pair`` nearest in line with ``com``, and the line's offset."""
    i, j = pair
    ni, nj = poly.normals[i], poly.normals[j]
    axis = _unit(ni - nj)  # towards face i
    u, v = _basis(axis)
    region = (
        _project(poly, i, u, v)
        .buffer(-margin)
        .intersection(_project(poly, j, u, v).buffer(-margin))
    )
    if region.is_empty or region.area <= 0.0:
        return Rejection(
            pair,
            "outside_face",
            f"no grasp line stays {margin * 1000:.1f} mm inside both faces",
        )
    target = shapely.Point(float(com @ u), float(com @ v))
    q = target if region.covers(target) else shapely.ops.nearest_points(region, target)[0]
    shift = np.array([q.x - target.x, q.y - target.y])
    offset = float(np.hypot(*shift))
    if offset > max_offset:
        return Rejection(
            pair,
            "outside_face",
            f"the grasp line through the centre of mass leaves a face: the nearest line inside "
            f"both is {offset * 1000:.1f} mm off (limit {max_offset * 1000:.1f} mm)",
        )
    base = com + shift[0] * u + shift[1] * v
    ti = (poly.offsets[i] - float(ni @ base)) / float(ni @ axis)
    tj = (poly.offsets[j] - float(nj @ base)) / float(nj @ axis)
    return np.vstack([base + ti * axis, base + tj * axis]), offset


Interval = tuple[float, float]


def _subtract(keep: list[Interval], bad: list[Interval]) -> list[Interval]:
    """The closed intervals ``keep`` minus the open intervals ``bad``."""
    out = keep
    for lo, hi in bad:
        nxt = []
        for a, b in out:
            if hi <= a or lo >= b:
                nxt.append((a, b))
                continue
            if a < lo:
                nxt.append((a, lo))
            if hi < b:
                nxt.append((hi, b))
        out = nxt
    return out


def _parts(geom: shapely.Geometry) -> list[shapely.Polygon]:
    if isinstance(geom, shapely.Polygon):
        return [] if geom.is_empty else [geom]
    return [g for g in getattr(geom, "geoms", []) if isinstance(g, shapely.Polygon)]


def _spans(geom: shapely.Geometry, u: FloatArray, a: FloatArray, grow: float) -> list[Interval]:
    """The u-extents (grown by ``grow``) of the parts of ``geom`` thicker than the tolerance
    along ``a``: the grasp lines ``x · u = s`` they block."""
    out = []
    for part in _parts(geom):
        xy = np.asarray(part.exterior.coords, dtype=float)
        along = xy @ a
        if along.max() - along.min() < SECTION_TOL or part.area <= 0.0:
            continue
        across = xy @ u
        out.append((float(across.min()) - grow, float(across.max()) + grow))
    return out


def _side_range(
    start: FloatArray, end: FloatArray, u: FloatArray, margin: float
) -> Interval | None:
    """The lines ``x · u = s`` meeting side start→end at least ``margin`` from its ends."""
    length = float(np.linalg.norm(end - start))
    if length < 2.0 * margin or length <= 0.0:
        return None
    e = (end - start) / length
    s0 = float(start @ u) + float(e @ u) * margin
    s1 = float(start @ u) + float(e @ u) * (length - margin)
    return (min(s0, s1), max(s0, s1))


def _section_pairs(
    solid: SectionSolid,
    index: int,
    com: FloatArray,
    limit: float,
    margin: float,
    max_offset: float,
) -> list[tuple[tuple[int, int], float, tuple[FloatArray, FloatArray, float] | Rejection]]:
    """Every pair of antiparallel sides of block ``index`` facing away from each other, with
    its grasp (points, outward normals, offset from ``com``) or why there is none."""
    block = solid.blocks[index]
    poly = block.polygon
    k = len(poly)
    starts, ends = poly, np.roll(poly, -1, axis=0)
    d = ends - starts
    lengths = np.linalg.norm(d, axis=1)
    good = lengths > 1e-9
    normals = np.zeros_like(d)
    normals[good] = np.column_stack([d[good, 1], -d[good, 0]]) / lengths[good, None]
    offsets = np.einsum("ij,ij->i", normals, starts)
    shape = block.shape
    low, high = block.z0 + margin, block.z1 - margin
    z = float(np.clip(com[2], low, high)) if low <= high else float(com[2])
    band = shapely.ops.unary_union(
        [b.shape for b in solid.blocks if b.z0 < z + margin and b.z1 > z - margin]
    )
    lo_xy, hi_xy = poly.min(axis=0), poly.max(axis=0)
    far = 2.0 * float(np.linalg.norm(hi_xy - lo_xy)) + 1.0
    target = com[:2]
    out: list[tuple[tuple[int, int], float, tuple[FloatArray, FloatArray, float] | Rejection]] = []
    for i in range(k):
        for j in range(i + 1, k):
            if not (good[i] and good[j]):
                continue
            ni, nj = normals[i], normals[j]
            angle = math.degrees(math.acos(float(np.clip(-ni @ nj, -1.0, 1.0))))
            if angle > limit + 1e-9:
                continue
            a = _unit(ni - nj)  # along the grasp line, towards side i
            if ((starts[i] + ends[i]) / 2.0 - (starts[j] + ends[j]) / 2.0) @ a <= SECTION_TOL:
                continue  # the sides look at each other (the walls of a notch)
            pair = (i, j)
            out.append(
                (
                    pair,
                    angle,
                    _section_grasp(
                        pair,
                        a,
                        (starts, ends, normals, offsets),
                        shape,
                        band,
                        far,
                        z,
                        (low, high),
                        target,
                        com,
                        margin,
                        max_offset,
                    ),
                )
            )
    return out


def _section_grasp(
    pair: tuple[int, int],
    a: FloatArray,
    sides: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    shape: shapely.Polygon,
    band: shapely.Geometry,
    far: float,
    z: float,
    heights: Interval,
    target: FloatArray,
    com: FloatArray,
    margin: float,
    max_offset: float,
) -> tuple[FloatArray, FloatArray, float] | Rejection:
    starts, ends, normals, offsets = sides
    i, j = pair
    if heights[0] > heights[1]:
        return Rejection(
            pair,
            "outside_face",
            f"the sides are {(heights[1] - heights[0]) * 1000 + 2 * margin * 1000:.1f} mm high, "
            f"less than twice the margin ({margin * 1000:.1f} mm)",
        )
    u = np.array([-a[1], a[0]])
    ri = _side_range(starts[i], ends[i], u, margin)
    rj = _side_range(starts[j], ends[j], u, margin)
    if ri is None or rj is None or max(ri[0], rj[0]) > min(ri[1], rj[1]):
        return Rejection(
            pair, "outside_face", f"no grasp line stays {margin * 1000:.1f} mm inside both sides"
        )
    s0, s1 = max(ri[0], rj[0]), min(ri[1], rj[1])

    def at(side: int, s: float) -> FloatArray:
        """Where the line x · u = s meets the line of ``side``."""
        n = normals[side]
        t = (offsets[side] - s * float(n @ u)) / float(n @ a)
        return np.asarray(s * u + t * a, dtype=float)

    feasible = [(s0, s1)]
    if s1 - s0 > 1e-12:
        between = shapely.Polygon([at(i, s0), at(i, s1), at(j, s1), at(j, s0)])
        feasible = _subtract(feasible, _spans(between.difference(shape), u, a, 0.0))
    elif not shape.buffer(1e-9).covers(shapely.LineString([at(i, s0), at(j, s0)])):
        feasible = []
    if not feasible:
        return Rejection(
            pair,
            "outside_material",
            "the segment between the grasp points leaves the material (a gap between the sides)",
        )
    for side, sign in ((i, 1.0), (j, -1.0)):
        near0, near1 = at(side, s0 - margin), at(side, s1 + margin)
        push = sign * a * SECTION_TOL
        corridor = shapely.Polygon(
            [near0 + push, near1 + push, near1 + sign * far * a, near0 + sign * far * a]
        )
        feasible = _subtract(feasible, _spans(corridor.intersection(band), u, a, margin))
    if not feasible:
        return Rejection(
            pair,
            "jaw_collision",
            "a jaw approaching along the grasp line meets another part of the object",
        )
    want = float(target @ u)
    s = min((float(np.clip(want, lo, hi)) for lo, hi in feasible), key=lambda v: abs(v - want))
    offset = math.hypot(s - want, z - float(com[2]))
    if offset > max_offset:
        return Rejection(
            pair,
            "outside_face",
            f"the grasp line through the centre of mass leaves a side: the nearest line inside "
            f"both is {offset * 1000:.1f} mm off (limit {max_offset * 1000:.1f} mm)",
        )
    pi, pj = at(i, s), at(j, s)
    points = np.array([[pi[0], pi[1], z], [pj[0], pj[1], z]])
    normals3 = np.array([[*normals[i], 0.0], [*normals[j], 0.0]])
    return points, normals3, offset


def _crosses_concave_face(model: ObjectModel, points: FloatArray) -> bool:
    """True when the segment between ``points`` passes through a concave face's touched area
    (so it leaves the material): its crossing lies within the face's contacts, grown by ρ."""
    p0, p1 = points
    rho = model.record.tip_radius
    centres = np.asarray([c.centre for c in model.record.contacts], dtype=float).reshape(-1, 3)
    for face, supports in zip(model.faces, model.supporting, strict=True):
        if supports or not face.contacts:
            continue
        n = face.normal_array
        s0, s1 = float(n @ p0) - face.offset, float(n @ p1) - face.offset
        if not (
            (s0 < -SECTION_TOL and s1 > SECTION_TOL) or (s0 > SECTION_TOL and s1 < -SECTION_TOL)
        ):
            continue
        q = p0 + s0 / (s0 - s1) * (p1 - p0)
        u, v = _basis(n)
        pts = centres[list(face.contacts)] - rho * n
        hull = shapely.MultiPoint(np.column_stack([pts @ u, pts @ v])).convex_hull
        if hull.buffer(max(rho, SECTION_TOL)).covers(shapely.Point(float(q @ u), float(q @ v))):
            return True
    return False


def _reason(
    parallel: int, limit: float, candidates: list[GraspCandidate], rejected: list[Rejection]
) -> str:
    if parallel == 0:
        return f"no pair of parallel faces (within {limit:.1f}° of parallel)"
    if candidates:
        return "no candidate is in force closure"
    kinds = {r.kind for r in rejected}
    if kinds == {"table"}:
        return "the only parallel pair uses the table face (the support cannot be grasped)"
    usable = [r for r in rejected if r.kind != "table"]
    if all(r.kind == "too_wide" for r in usable):
        return "every parallel pair is wider than the pincers: " + usable[0].message
    if all(r.kind == "outside_face" for r in usable):
        return "the grasp line lies outside a face for every parallel pair: " + usable[0].message
    if all(r.kind == "outside_material" for r in usable):
        return "the grasp segment leaves the material for every parallel pair: " + usable[0].message
    if all(r.kind == "jaw_collision" for r in usable):
        return "a jaw would hit the object for every parallel pair: " + usable[0].message
    counts = {kind: sum(1 for r in usable if r.kind == kind) for kind in _KINDS}
    parts = [f"{n} {_KINDS[kind]}" for kind, n in counts.items() if n]
    return "no parallel pair gives a grasp: " + ", ".join(parts)


_KINDS = {
    "too_wide": "wider than the pincers",
    "too_narrow": "narrower than the least opening",
    "outside_face": "with the grasp line outside a face",
    "outside_material": "with the grasp segment leaving the material",
    "jaw_collision": "with a jaw blocked by the object",
    "not_closed": "not in force closure",
}
