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

The grasp metrics (the contact model, ε and the least force) are in
:mod:`tactile_kb.grasp.quality`; the layered solid of box unions in
:mod:`tactile_kb.geometry.blocks`.

Examples
--------
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.touch.synthetic import sample_record
>>> plan = plan_grasp(sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), seed=1))
>>> plan.ok, plan.best.force_closure
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
import shapely.geometry
import shapely.ops
import shapely.validation

from tactile_kb.errors import UsageError
from tactile_kb.geometry.blocks import SectionSolid, section_solid
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.geometry.polyhedron import Polyhedron
from tactile_kb.grasp.quality import (
    DEFAULT_CONE_EDGES,
    DEFAULT_MU,
    DEFAULT_PAD_RADIUS,
    ferrari_canny,
    force_closure,
    least_force,
    torque_scale,
)
from tactile_kb.record import ExplorationRecord
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray, vec3

__all__ = [
    "DEFAULT_DENSITY",
    "DEFAULT_MARGIN",
    "DEFAULT_MAX_COM_OFFSET",
    "DEFAULT_MAX_OPENING",
    "QUALITY_MEASURE",
    "RANK_ANGLE_STEP_DEG",
    "GraspCandidate",
    "GraspPlan",
    "Rejection",
    "plan_grasp",
]


DEFAULT_MAX_OPENING = 0.15
"""Widest jaw opening of the pincers, metres."""

DEFAULT_MARGIN = 0.005
"""Each grasp point must lie at least this far (m) inside its face: the pad radius."""

DEFAULT_MAX_COM_OFFSET = 0.02
"""The grasp line may pass at most this far (m) from the centre of mass."""

DEFAULT_DENSITY = 1000.0
"""kg/m³, for the object's mass when none is given (touch does not weigh)."""

RANK_ANGLE_STEP_DEG = DEFAULTS.grasp.rank_angle_step_deg
"""Candidates whose planes' angles fall in the same step of this many degrees rank as equally
parallel (0.4° and 0.6° apart are both "parallel" to a finger with 0.5 mm of noise)."""

QUALITY_MEASURE = "ferrari_canny_soft"
"""The name of :attr:`GraspCandidate.quality` in JSON output."""

TABLE_ANGLE_DEG = DEFAULTS.grasp.table_angle_deg
TABLE_HEIGHT_TOL = DEFAULTS.grasp.table_height_tol


@dataclass(kw_only=True, frozen=True)
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
        step = math.floor(self.angle_deg / current().grasp.rank_angle_step_deg + 1e-9)
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


@dataclass(kw_only=True, frozen=True)
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
    cos_tol = math.cos(math.radians(current().grasp.table_angle_deg))
    for k, (n, d) in enumerate(zip(poly.normals, poly.offsets, strict=True)):
        if (
            n[2] <= -cos_tol
            and abs(d) <= current().grasp.table_height_tol
            and zmin <= current().grasp.table_height_tol
        ):
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
    opts = _Options(
        mu=mu,
        max_opening=max_opening,
        min_opening=min_opening,
        margin=margin,
        max_com_offset=max_com_offset,
        pad_radius=pad_radius,
        cone_edges=cone_edges,
        limit=math.degrees(math.atan(mu)) if max_angle_deg is None else max_angle_deg,
    )
    if solid is not None:
        found = _on_sections(solid, opts, mass, density)
    elif poly is not None:
        found = _on_polyhedron(model, poly, opts, mass, density)
    else:
        why = model.open_reason or "the touched planes do not bound a region"
        if model.layers:
            why += "; no layer contour closed"
        return GraspPlan(
            object=name,
            best=None,
            candidates=(),
            reason=f"no closed model to grasp: {why}",
            params=params,
        )
    candidates = sorted(found.candidates, key=lambda c: c.rank_key)
    best = next((c for c in candidates if c.force_closure), None)
    reason = (
        "" if best is not None else _reason(found.parallel, opts.limit, candidates, found.rejected)
    )
    return GraspPlan(
        object=name,
        best=best,
        candidates=tuple(candidates),
        reason=reason,
        rejected=tuple(found.rejected),
        com=vec3(found.com),
        mass=found.weight,
        params=params,
        basis=found.basis,
        notes=found.notes,
        solid=solid,
    )


@dataclass(frozen=True, kw_only=True)
class _Options:
    """The pincers and the contact model, as :func:`plan_grasp` was given them."""

    mu: float
    max_opening: float
    min_opening: float
    margin: float
    max_com_offset: float
    pad_radius: float
    cone_edges: int
    limit: float
    """The largest angle between the two planes, degrees."""


@dataclass(kw_only=True)
class _Found:
    """What one strategy found: the candidates, the rejections, and what they were judged on."""

    basis: str
    com: FloatArray
    weight: float
    scale: float
    notes: tuple[str, ...] = ()
    candidates: list[GraspCandidate] = field(default_factory=list)
    rejected: list[Rejection] = field(default_factory=list)
    parallel: int = 0

    def add(self, out: GraspCandidate | Rejection) -> None:
        if isinstance(out, Rejection):
            self.rejected.append(out)
        else:
            self.candidates.append(out)


def _assess(
    found: _Found,
    opts: _Options,
    pair: tuple[int, int],
    points: FloatArray,
    normals: FloatArray,
    angle: float,
    offset: float,
    section: int | None,
) -> GraspCandidate | Rejection:
    """A candidate on two grasp points, with its quality; or why the pincers cannot take it."""
    width = float(np.linalg.norm(points[0] - points[1]))
    if width > opts.max_opening:
        return Rejection(
            pair,
            "too_wide",
            f"{width * 1000:.1f} mm apart, wider than the pincers "
            f"({opts.max_opening * 1000:.1f} mm)",
        )
    if width < opts.min_opening:
        return Rejection(pair, "too_narrow", f"{width * 1000:.1f} mm apart, below the minimum")
    return GraspCandidate(
        faces=pair,
        points=(vec3(points[0]), vec3(points[1])),
        normals=(vec3(normals[0]), vec3(normals[1])),
        angle_deg=angle,
        com_offset=offset,
        width=width,
        force_closure=force_closure(points, normals, mu=opts.mu),
        quality=ferrari_canny(
            points,
            normals,
            found.com,
            mu=opts.mu,
            pad_radius=opts.pad_radius,
            cone_edges=opts.cone_edges,
            torque_scale=found.scale,
        ),
        least_force=least_force(
            points,
            normals,
            found.com,
            found.weight,
            mu=opts.mu,
            pad_radius=opts.pad_radius,
            cone_edges=opts.cone_edges,
        ),
        section=section,
    )


def _on_sections(solid: SectionSolid, opts: _Options, mass: float | None, density: float) -> _Found:
    """The strategy for layered models: antiparallel sides of each block's contour."""
    found = _Found(
        basis="sections",
        com=np.asarray(solid.centroid, dtype=float),
        weight=float(mass) if mass is not None else density * solid.volume,
        scale=solid.torque_scale,
        notes=(solid.note,),
    )
    for b in range(len(solid.blocks)):
        for pair, angle, got in _section_pairs(
            solid, b, found.com, opts.limit, opts.margin, opts.max_com_offset
        ):
            found.parallel += 1
            if isinstance(got, Rejection):
                found.rejected.append(got)
                continue
            points, normals, offset = got
            found.add(_assess(found, opts, pair, points, normals, angle, offset, b))
    return found


def _on_polyhedron(
    model: ObjectModel, poly: Polyhedron, opts: _Options, mass: float | None, density: float
) -> _Found:
    """The strategy for closed polyhedra: pairs of (nearly) parallel faces."""
    notes: tuple[str, ...] = ()
    if not model.convex:
        notes = (
            "the model is not convex and has no layer contours: its centre of mass is that "
            "of the convex envelope, and grasp lines crossing a concave face are refused",
        )
    found = _Found(
        basis="polyhedron",
        com=np.asarray(poly.centroid, dtype=float),
        weight=float(mass) if mass is not None else density * poly.volume,
        scale=torque_scale(poly),
        notes=notes,
    )
    table = _table_faces(model, poly)
    nf = len(poly.faces)
    for i in range(nf):
        for j in range(i + 1, nf):
            ni, nj = poly.normals[i], poly.normals[j]
            angle = math.degrees(math.acos(float(np.clip(-np.dot(ni, nj), -1.0, 1.0))))
            if angle > opts.limit + 1e-9:
                continue
            found.parallel += 1
            pair = (i, j)
            if i in table or j in table:
                found.rejected.append(Rejection(pair, "table", "uses the table face (the support)"))
                continue
            got = _grasp_on_pair(poly, pair, found.com, opts.margin, opts.max_com_offset)
            if isinstance(got, Rejection):
                found.rejected.append(got)
                continue
            points, offset = got
            if not model.convex and _crosses_concave_face(model, points):
                found.rejected.append(
                    Rejection(
                        pair,
                        "outside_material",
                        "the segment between the grasp points crosses a concave face",
                    )
                )
                continue
            normals = np.vstack([ni, nj])
            found.add(_assess(found, opts, pair, points, normals, angle, offset, None))
    return found


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
        if along.max() - along.min() < current().geometry.section_tol or part.area <= 0.0:
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
            if (
                (starts[i] + ends[i]) / 2.0 - (starts[j] + ends[j]) / 2.0
            ) @ a <= current().geometry.section_tol:
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
        push = sign * a * current().geometry.section_tol
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
            (s0 < -current().geometry.section_tol and s1 > current().geometry.section_tol)
            or (s0 > current().geometry.section_tol and s1 < -current().geometry.section_tol)
        ):
            continue
        q = p0 + s0 / (s0 - s1) * (p1 - p0)
        u, v = _basis(n)
        pts = centres[list(face.contacts)] - rho * n
        hull = shapely.MultiPoint(np.column_stack([pts @ u, pts @ v])).convex_hull
        if hull.buffer(max(rho, current().geometry.section_tol)).covers(
            shapely.Point(float(q @ u), float(q @ v))
        ):
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
