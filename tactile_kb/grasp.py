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
4. **Ranking** by the angle between the planes (whole degrees), then the offset of the grasp
   line from the centre of mass (whole millimetres), then the jaw opening (narrower first).

When no pair survives, :attr:`GraspPlan.reason` says why: no parallel pair, every pair wider
than the pincers, the grasp line outside a face, or only the table face.

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
import shapely.ops
import trimesh
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from tactile_kb.errors import UsageError
from tactile_kb.model import ObjectModel, build_model
from tactile_kb.polyhedron import Polyhedron
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
    "GraspCandidate",
    "GraspPlan",
    "Rejection",
    "ferrari_canny",
    "force_closure",
    "least_force",
    "plan_grasp",
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

QUALITY_MEASURE = "ferrari_canny_soft"
"""The name of :attr:`GraspCandidate.quality` in JSON output."""

TABLE_ANGLE_DEG = 5.0
TABLE_HEIGHT_TOL = 0.002

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

    @property
    def rank_key(self) -> tuple[int, int, float]:
        """Angle in whole degrees, then COM offset in whole millimetres, then the opening."""
        return (round(self.angle_deg), round(self.com_offset * 1000.0), self.width)

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
        }


@dataclass(frozen=True)
class Rejection:
    """A pair of faces that gives no grasp, and why."""

    faces: tuple[int, int]
    kind: str
    """``"table"``, ``"too_wide"``, ``"too_narrow"``, ``"outside_face"`` or ``"not_closed"``."""
    message: str


@dataclass(frozen=True)
class GraspPlan:
    """The best grasp of an object and the ranked alternatives, or why there is none."""

    object: str
    best: GraspCandidate | None
    candidates: tuple[GraspCandidate, ...]
    reason: str
    rejected: tuple[Rejection, ...] = ()
    com: tuple[float, float, float] | None = None
    mass: float | None = None
    params: dict[str, float] = field(default_factory=dict)

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
        An :class:`~tactile_kb.model.ObjectModel`, or an exploration record (the model is
        built with :func:`~tactile_kb.model.build_model`).
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
    if poly is None:
        why = model.open_reason or "the touched planes do not bound a region"
        return GraspPlan(name, None, (), f"no closed model to grasp: {why}", params=params)
    limit = math.degrees(math.atan(mu)) if max_angle_deg is None else max_angle_deg
    com = np.asarray(poly.centroid, dtype=float)
    weight = float(mass) if mass is not None else density * poly.volume
    scale = torque_scale(poly)
    table = _table_faces(model, poly)
    nf = len(poly.faces)
    candidates: list[GraspCandidate] = []
    rejected: list[Rejection] = []
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
            width = float(np.linalg.norm(points[0] - points[1]))
            if width > max_opening:
                rejected.append(
                    Rejection(
                        pair,
                        "too_wide",
                        f"{width * 1000:.1f} mm apart, wider than the pincers "
                        f"({max_opening * 1000:.1f} mm)",
                    )
                )
                continue
            if width < min_opening:
                rejected.append(
                    Rejection(pair, "too_narrow", f"{width * 1000:.1f} mm apart, below the minimum")
                )
                continue
            normals = np.vstack([ni, nj])
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
            candidates.append(
                GraspCandidate(
                    faces=pair,
                    points=(_vec(points[0]), _vec(points[1])),
                    normals=(_vec(ni), _vec(nj)),
                    angle_deg=angle,
                    com_offset=offset,
                    width=width,
                    force_closure=closed,
                    quality=eps,
                    least_force=force,
                )
            )
    candidates.sort(key=lambda c: c.rank_key)
    best = next((c for c in candidates if c.force_closure), None)
    reason = "" if best is not None else _reason(parallel, limit, candidates, rejected)
    return GraspPlan(
        name, best, tuple(candidates), reason, tuple(rejected), _vec(com), weight, params
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
    return "; ".join(sorted({f"faces {r.faces[0]}-{r.faces[1]}: {r.message}" for r in usable}))
