"""Feature extractors: the geometric facts that decide the propositions of a rule file.

"Computer calculations give other information, such as cross-sections, angles between
planes, existence of parallelism and perpendicularity, etc., which form propositions for
object identifications." A feature is a function ``fn(model, **params) -> bool`` of an
:class:`~tactile_kb.geometry.model.ObjectModel`; rule files name it (``feature: surface_plane`` or
``feature: {name: face_count, params: {equals: 6}}``).

Features live in a registry filled from the entry-point group ``tactile_kb.features``; the
built-ins join it the same way (``builtin = "tactile_kb.features.builtin:BUILTIN_FEATURES"``), and a
third-party package adds its own by exposing a :class:`Feature` (or a mapping of them).

Every threshold is a keyword parameter with a default that works for the 33-sensor finger
(normals refined from the tip centres are within about 2° of the truth):

=============================  ==================================================  =========
parameter                      meaning                                              default
=============================  ==================================================  =========
``tolerance_deg``              angle below which two directions count as equal      5°
``sigmas``                     faces' normal uncertainties widen the tolerance:     3
                               ``max(tolerance_deg, sigmas·√(u₁² + u₂²))``
``residual_tol``               RMS misfit (m) of a face's tip centres meaning       0.3 ρ, ≥ 3σ
                               curved (ρ the tip radius, σ the declared noise)
``sagitta_tol``                bending (m) of a face's tip centres over the face    max(0.5 ρ,
                               meaning curved (:func:`face_sagitta`)                3 % extent,
                                                                                    4σ)
``spread_deg``                 turn of a face between two contacts inside it        10°
                               (away from its edges) that fired different sensors,
                               measured from the tip centres (:func:`spread_bend`),
                               meaning curved
``smooth_deg``                 edges whose normals differ by less are "smooth"      35°
``min_smooth_edges``           that many smooth edges mean curved                   6
``rel_tol``                    relative spread of lengths counted as equal          0.06
                               (edges: or within ``sigmas`` × their uncertainty,
                               ``sigmas`` = 4 for ``equal_edges``)
``point_tol``                  RMS miss distance of concurrent lines / diameter     0.1
``horizontal_deg``             a face within this of ±z is the base or the top      10°
=============================  ==================================================  =========

``orthogonal_faces`` (every two faces of the object parallel or perpendicular: with
``convex`` false, an object composed of rectangular parallelepipeds) reads every face of the
model, the concave ones too, with the same ``tolerance_deg`` and ``sigmas``.

A model closed by an assumed top (``model.assumed_top``: the top was never touched) does not
know its height: ``equal_edges`` and ``congruent_faces``, which would compare the unknown
lateral edges, are then False (not established), so a cube felt only by the 4-sensor finger
is answered as what it certainly is, a rectangular parallelepiped.

The "lateral" edges are those not on the base nor on the top face: the vertical edges of a
prism, the edges to a pyramid's apex. Base and top are found from the shape, whatever face the
object rests on (a prism's two ends, the face opposite a pyramid's apex; see ``_caps``), else
the faces within ``horizontal_deg`` of −z and +z; on its base, the base is the table face.

Examples
--------
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.geometry.model import build_model
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.synthetic import sample_record
>>> model = build_model(sample_record(box(0.08, 0.08, 0.08), builtin_finger("33"), per_face=12, seed=4))
>>> [get_feature(n).fn(model) for n in ("contact", "surface_plane", "lateral_edges_parallel", "equal_edges")]
[True, True, True, True]
>>> get_feature("face_count").fn(model, equals=6), side_count(model)
(True, 4)
>>> check_binding("face_count", {"equal": 6})
"feature 'face_count' has no parameter 'equal' (parameters: equals, max, min)"
"""

from __future__ import annotations

import inspect
import math
from collections import Counter
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import TYPE_CHECKING, Any, Literal, TypeVar

import numpy as np
from numpy.typing import NDArray

from tactile_kb.errors import GeometryError, PluginError, UsageError
from tactile_kb.plugins import Registry
from tactile_kb.settings import DEFAULTS, current

if TYPE_CHECKING:  # the geometry (scipy) is imported when a feature is evaluated, so that
    # checking a rule file's bindings stays light
    from tactile_kb.geometry.model import ObjectModel
    from tactile_kb.geometry.planes import Face
    from tactile_kb.geometry.polyhedron import Polyhedron
    from tactile_kb.record import ExplorationRecord
    from tactile_kb.types import FloatArray, IntArray

__all__ = [
    "BUILTIN_FEATURES",
    "Feature",
    "available_features",
    "centres_on_circle",
    "centres_on_sphere",
    "check_binding",
    "edge_uncertainties",
    "evaluate_feature",
    "face_angles",
    "face_sagitta",
    "feature_registry",
    "get_feature",
    "interior_spread_deg",
    "lateral_common_point",
    "lateral_edges",
    "measure",
    "measure_names",
    "orthogonal_faces",
    "parallelism_table",
    "perpendicularity_table",
    "sagitta_tolerance",
    "section_at",
    "side_count",
    "spread_bend",
]

FeatureFn = Callable[..., bool]

_T = TypeVar("_T")


def _derived(model: ObjectModel, key: Hashable, compute: Callable[[], _T]) -> _T:
    """:func:`tactile_kb.geometry.model.derived` (the geometry is imported when a feature is
    evaluated). Every key here holds the feature settings in force, so an override of them
    never reads a value derived under others."""
    from tactile_kb.geometry.model import derived

    return derived(model, key, compute)


TOLERANCE_DEG = DEFAULTS.features.tolerance_deg
SIGMAS = DEFAULTS.features.sigmas
RESIDUAL_RHO = DEFAULTS.features.residual_rho
"""A face whose tip centres miss its plane by more than this × the tip radius (RMS) is curved:
1.5 mm for the 5 mm tip, three times the 0.5 mm noise and above a scanned box face's 0.4 mm."""
SAGITTA_RHO = DEFAULTS.features.sagitta_rho
"""A face whose centres bend by more than this × the tip radius over the face is curved …"""
SAGITTA_FRACTION = DEFAULTS.features.sagitta_fraction
"""… and by more than this fraction of the face's extent (a cardboard bulge of 1 mm on a 10 cm
face is 1 %; a cylinder's face seen by one sensor, 25° of arc, bends by 5.5 % of its width)."""
MIN_SAGITTA_CONTACTS = DEFAULTS.features.min_sagitta_contacts
SPREAD_DEG = DEFAULTS.features.spread_deg
"""A face whose tip centres turn by more than this between two interior contacts that fired
different sensors is curved (:func:`spread_bend`)."""
SMOOTH_DEG = DEFAULTS.features.smooth_deg
MIN_SMOOTH_EDGES = DEFAULTS.features.min_smooth_edges
REL_TOL = DEFAULTS.features.rel_tol
EDGE_SIGMAS = DEFAULTS.features.edge_sigmas
"""The largest of a dozen edge differences is a range statistic: the range of 12 Gaussian
lengths exceeds 4·√2·σ with a probability below 1 %."""
POINT_TOL = DEFAULTS.features.point_tol
HORIZONTAL_DEG = DEFAULTS.features.horizontal_deg
PRECISION_RHO = 1e-3
"""Tip radii: contacts scatter about their face's plane by at least this (5 µm for the 5 mm
tip) in :func:`_uncertainty`, however exactly they fit it: the explorers' own precision."""

RELIEF_DOF = 4.0
"""Degrees of freedom the assumed relief (``geometry.relief_rho``) is worth when it is pooled
with the scatter a face's tip centres show about their bent fit (:func:`spread_bend`)."""
SPOT_RHO = 0.5
"""Tip radii: tip centres this near each other on a face are one spot to the jackknife of
:func:`spread_bend` (a touch and the slides that stay by it, a probe's touches at one place)."""

SPLIT_CORNER_RHO = 2.0
"""Tip radii: the longest edge :func:`_split_corners` takes for a corner that noisy planes split
on its length's uncertainty alone. Four planes that miss one point by their bumps and
roundings leave an edge of a few millimetres (7.5 mm on a 19 cm octahedron); a face touched
over a patch a tenth of its size may leave its far edges uncertain by centimetres, and a
long box's 24 mm end edges, 4 σ long, were taken for split corners and left a cube."""


@dataclass(frozen=True)
class Feature:
    """A registered feature extractor.

    Attributes
    ----------
    name
        The name rule files use.
    fn
        ``fn(model, **params) -> bool``.
    requires
        ``"contact"`` (only the record's contacts) or ``"model"`` (a closed polyhedron).
    doc
        One-line description.
    params
        Keyword parameters and their defaults (``None``: no default, optional).
    """

    name: str
    fn: FeatureFn
    requires: Literal["contact", "model"] = "model"
    doc: str = ""
    params: Mapping[str, Any] = field(default_factory=dict)

    def __call__(self, model: ObjectModel, **params: Any) -> bool:
        return evaluate_feature(self, model, params)


# ---------------------------------------------------------------------------------------------
# geometry helpers (values, not booleans)


def _poly(model: ObjectModel, name: str) -> Polyhedron:
    if model.polyhedron is None:
        reason = model.open_reason or "no polyhedron"
        raise GeometryError(f"feature {name!r} needs a closed model: {reason}")
    return model.polyhedron


def _uncertainty(model: ObjectModel) -> FloatArray:
    """Per polyhedron face, the normal uncertainty (degrees) of its model face, with the
    scatter of its tip centres pooled with the surface's (:func:`_pooled_scatter`)."""
    if not model.face_of:
        return np.zeros(0)

    def compute() -> FloatArray:
        faces = [model.faces[i] for i in model.face_of]
        surface = [f.residual for f in model.faces if f.refined and f.n_contacts >= 6]
        detail = float(np.median(surface)) if surface else 0.0
        # the scatter the face's uncertainty was computed from is never below the declared
        # noise, nor the contacts' own precision: an exact record's faces fit their planes
        # to rounding (1e-17 m), and pooled with a surface that shows a micrometre they
        # would turn by up to 90°
        least = max(model.record.noise, PRECISION_RHO * model.record.tip_radius)
        out = []
        for f in faces:
            unc = f.normal_uncertainty_deg
            m = f.places or f.n_contacts  # independent centres: one patch's touches count once
            if f.refined and m > 3 and detail > 0.0:
                own = max(f.residual * math.sqrt(m / (m - 3)), least)  # σ of the fit, m − 3 dof
                if m <= 4:
                    # four centres fit a plane nearly exactly: the model computed the face's
                    # uncertainty from the scatter its other faces show (the offset's
                    # uncertainty is that σ / √m), so that is the scatter to pool
                    own = max(own, f.offset_uncertainty * math.sqrt(m))
                pooled = _pooled_scatter(own, m - 3, detail)
                if pooled > own:
                    unc = math.degrees(math.atan(math.tan(math.radians(unc)) * pooled / own))
            out.append(unc)
        return np.asarray(out, dtype=float)

    return _derived(model, (__name__, current().features, "uncertainty"), compute)


def _pooled_scatter(own: float, dof: int, surface: float) -> float:
    """A face's scatter about its plane, ``own`` measured with ``dof`` degrees of freedom,
    pooled with the surface's (``surface``: the median RMS of the faces touched six or more
    times) as a prior worth :data:`RELIEF_DOF` degrees of freedom. A face touched five
    times fits its plane with two degrees of freedom and may by chance show little of the
    relief and noise the others show; its normal is then no more certain than theirs."""
    return math.sqrt((dof * own**2 + RELIEF_DOF * surface**2) / (dof + RELIEF_DOF))


LINE_RHO = 2.0
"""A face whose tip centres lie along one line (they span no plane) at least this many tip
radii long knows its normal's turn about the line's perpendicular from the line's direction;
only its turn about the line itself is the sensors' (:func:`_line_axes`)."""


BOUND_SIGMAS = 2.0
"""The sensors' bound on the turn of a face touched along one line about that line counts as
this many standard errors (:func:`_tolerance`)."""


def _line_axes(model: ObjectModel) -> tuple[FloatArray, FloatArray]:
    """Per polyhedron face, ``(axes, across)``: for a face touched along one line (its tip
    centres span no plane, the normal square to the line, the line at least :data:`LINE_RHO`
    tip radii long), the line's unit direction, about which the normal turns by at most the
    face's uncertainty (the sensors' resolution: a bound, the cone of the sensors), and the
    standard error (degrees) of its turn about the other axis square to the normal, which
    the line's direction measures (the centres' scatter across it over their spread along
    it, √m of them); zeros elsewhere.

    A side of a slab touched along one contour line (a phone lying flat: its sides are 12 mm
    tall) has a tilt the sensors know to 15° or 30°, but its direction round the vertical is
    the line's, to a degree or better: it is parallel to the side opposite, not to the ones
    beside it."""

    def compute() -> tuple[FloatArray, FloatArray]:
        n_faces = len(model.face_of)
        axes, across = np.zeros((n_faces, 3)), np.zeros(n_faces)
        contacts = model.record.contacts
        rho = model.record.tip_radius
        least = max(model.record.noise, PRECISION_RHO * rho)
        for k, i in enumerate(model.face_of):
            f = model.faces[i]
            if f.refined or f.source != "contacts" or len(f.contacts) < 2:
                continue
            c = np.asarray([contacts[j].centre for j in f.contacts], dtype=float)
            c -= c.mean(axis=0)
            _, sv, vt = np.linalg.svd(c, full_matrices=False)
            line = vt[0]
            along = c @ line
            if float(along.max() - along.min()) < LINE_RHO * rho:
                continue
            if abs(float(line @ np.asarray(f.normal, dtype=float))) > 0.1:
                continue
            m = max(f.places or len(f.contacts), 2)
            scatter = max(float(sv[1]) / math.sqrt(len(c)), least) if len(sv) > 1 else least
            spread = float(np.sqrt((along**2).mean()))
            axes[k] = line
            across[k] = math.degrees(math.atan2(scatter, spread * math.sqrt(m)))
        return axes, across

    return _derived(model, (__name__, current().features, "line_axes"), compute)


def _tolerance(model: ObjectModel, tolerance_deg: float, sigmas: float) -> FloatArray:
    """(F, F) angle tolerances: the larger of ``tolerance_deg`` and the combined uncertainty
    of the two faces' normals about the axis square to both (the only turn that changes the
    angle between them), each face's uncertainty the same about every axis but for a face
    touched along one line (:func:`_line_axes`)."""

    def compute() -> FloatArray:
        u = _uncertainty(model)
        axes, across = _line_axes(model)
        var = np.broadcast_to((u**2)[:, None], (len(u), len(u))).copy()
        lined = np.flatnonzero(np.abs(axes).sum(axis=1) > 0)
        if len(lined):
            normals = _poly(model, "tolerance").normals
            k = np.cross(normals[:, None, :], normals[None, :, :])
            size = np.linalg.norm(k, axis=2)
            ok = size > 1e-6
            k = np.where(ok[:, :, None], k / np.maximum(size, 1e-12)[:, :, None], 0.0)
            for i in lined.tolist():
                # the sensors' bound on the turn about the line (the spread of their cones)
                # counts as BOUND_SIGMAS standard errors: a rough face's bumps turn them
                # beyond it at times
                along = (k[i] @ axes[i]) ** 2  # (F,): the axes' parts about the line
                about = u[i] / BOUND_SIGMAS
                turned = about**2 * along + across[i] ** 2 * (1.0 - along)
                var[i] = np.where(ok[i], turned, var[i])
        comb = np.sqrt(var + var.T)
        return np.asarray(np.maximum(tolerance_deg, sigmas * comb), dtype=float)

    return _derived(
        model, (__name__, current().features, "tolerance", tolerance_deg, sigmas), compute
    )


def _face_angles(model: ObjectModel) -> FloatArray:
    def compute() -> FloatArray:
        p = _poly(model, "face_angles")
        c = np.clip(p.normals @ p.normals.T, -1.0, 1.0)
        return np.asarray(np.degrees(np.arccos(c)), dtype=float)

    return _derived(model, (__name__, current().features, "face_angles"), compute)


def face_angles(model: ObjectModel) -> FloatArray:
    """(F, F) angles between the outward normals of the polyhedron's faces, degrees.

    0 for the same direction, 180 for parallel faces on opposite sides, 90 for
    perpendicular ones.
    """
    return _face_angles(model).copy()


def _parallelism(model: ObjectModel, tolerance_deg: float, sigmas: float) -> NDArray[np.bool_]:
    def compute() -> NDArray[np.bool_]:
        ang = _face_angles(model)
        return np.asarray(180.0 - ang <= _tolerance(model, tolerance_deg, sigmas), dtype=bool)

    return _derived(
        model, (__name__, current().features, "parallel", tolerance_deg, sigmas), compute
    )


def _perpendicularity(model: ObjectModel, tolerance_deg: float, sigmas: float) -> NDArray[np.bool_]:
    def compute() -> NDArray[np.bool_]:
        ang = _face_angles(model)
        return np.asarray(
            np.abs(ang - 90.0) <= _tolerance(model, tolerance_deg, sigmas), dtype=bool
        )

    return _derived(
        model, (__name__, current().features, "perpendicular", tolerance_deg, sigmas), compute
    )


_N = TypeVar("_N", int, float)


def _default(value: _N | None, name: str) -> _N:
    """``value``, or the current ``features.<name>`` setting when it is None."""
    if value is None:
        setting: _N = getattr(current().features, name)
        return setting
    return value


def parallelism_table(
    model: ObjectModel, *, tolerance_deg: float | None = None, sigmas: float | None = None
) -> NDArray[np.bool_]:
    """(F, F) True where two faces are parallel (opposite normals within the tolerance)."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = _default(sigmas, "sigmas")
    return _parallelism(model, tolerance_deg, sigmas).copy()


def perpendicularity_table(
    model: ObjectModel, *, tolerance_deg: float | None = None, sigmas: float | None = None
) -> NDArray[np.bool_]:
    """(F, F) True where two faces are perpendicular within the tolerance."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = _default(sigmas, "sigmas")
    return _perpendicularity(model, tolerance_deg, sigmas).copy()


def _base_top(p: Polyhedron, horizontal_deg: float) -> tuple[set[int], set[int]]:
    c = math.cos(math.radians(horizontal_deg))
    z = p.normals[:, 2]
    base = {int(i) for i in np.flatnonzero(z <= -c)}
    top = {int(i) for i in np.flatnonzero(z >= c)}
    return base, top


def _caps(model: ObjectModel, name: str, horizontal_deg: float) -> tuple[set[int], set[int]]:
    """The base and top faces of the polyhedron (raises if the model is open).

    Found from the shape, not from z, so that a prism lying on a side is still a prism:

    1. a *base pair*: two parallel faces that every other face touches (along an edge or
       at a vertex: a prism's or a frustum's ends); among several, those whose other edges
       are parallel (a prism's ends, not a lying trapezoidal prism's two parallel sides),
       and among those (a box) the pair holding the table face;
    2. else an *apex*: a vertex where all faces but one meet (a pyramid's), or a group of
       corners joined by edges no longer than 2 × ``point_tol`` × the diameter (an apex split
       by a face whose turn is known coarsely: lines that miss one point by the concurrency
       tolerance can leave corners that far apart), unless the group holds every corner of
       a face (a slender frustum's small top); the base is the face not there (among
       several, a tetrahedron's, the table face);
    3. else the faces within ``horizontal_deg`` of −z (base) and +z (top).

    For an object resting on its base all three agree with the paper's "vertical" edges.
    """
    p = _poly(model, name)

    def compute() -> tuple[set[int], set[int]]:
        base, top = _base_top(p, horizontal_deg)
        f_ = len(p.faces)
        touches = np.zeros((f_, f_), dtype=bool)  # faces sharing a vertex
        at: list[list[int]] = [[] for _ in range(len(p.vertices))]
        for f, poly in enumerate(p.faces):
            for v in poly:
                at[v].append(f)
        for fs in at:
            touches[np.ix_(fs, fs)] = True
        parallel = _parallelism(model, current().features.tolerance_deg, current().features.sigmas)
        pairs = [
            (f, g)
            for f, g in zip(*np.nonzero(np.triu(parallel, 1)), strict=True)
            if np.delete(touches[f] & touches[g], [f, g]).all()
        ]
        if pairs:
            # a prism's ends: the pair whose lateral edges are parallel (a lying trapezoidal
            # prism also has a pair of parallel sides, one of them on the table); among
            # several (a box) the pair holding the table face
            parallel_ends = [q for q in pairs if _edges_parallel_apart_from(p, set(q))]
            choice = parallel_ends or pairs
            f, g = next((q for q in choice if base & set(q)), choice[0])
            return ({int(g)}, {int(f)}) if int(g) in base else ({int(f)}, {int(g)})
        if f_ >= 4:
            missing = [set(range(f_)) - set(fs) for fs in at if len(fs) == f_ - 1]
            if not missing:
                # an apex split by a face whose turn is known coarsely (touched at one spot
                # or only low): its corners lie closer together than lines that miss one
                # point by the concurrency tolerance may, so they count as one vertex
                near = 2.0 * current().features.point_tol * p.diameter
                missing = [
                    set(range(f_)) - fs for fs in _near_corners(p, near) if len(fs) == f_ - 1
                ]
            if missing:
                b = next((m for m in missing if m & base), missing[0])
                return {int(next(iter(b)))}, set()
        return base, top

    return _derived(model, (__name__, current().features, "caps", horizontal_deg), compute)


def _near_corners(p: Polyhedron, distance: float) -> list[set[int]]:
    """The faces meeting at each group of the polyhedron's vertices joined by edges no longer
    than ``distance`` (groups of two or more vertices only), but no group that holds every
    corner of a face: that is a small face (a slender frustum's top), not a split apex."""
    parent = list(range(len(p.vertices)))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in p.edges:
        if float(np.linalg.norm(p.vertices[a] - p.vertices[b])) <= distance:
            parent[root(int(a))] = root(int(b))
    groups: dict[int, set[int]] = {}
    sizes: Counter[int] = Counter(root(i) for i in range(len(p.vertices)))
    whole = {root(int(poly[0])) for poly in p.faces if len({root(int(v)) for v in poly}) == 1}
    for f, poly in enumerate(p.faces):
        for v in poly:
            r = root(int(v))
            if sizes[r] > 1 and r not in whole:
                groups.setdefault(r, set()).add(f)
    return list(groups.values())


def _edges_parallel_apart_from(p: Polyhedron, cap: set[int]) -> bool:
    """The edges on neither face of ``cap`` are parallel (within :data:`TOLERANCE_DEG`)."""
    e = np.asarray(
        [
            e
            for e, (f, g) in zip(p.edges, p.edge_faces, strict=True)
            if f not in cap and g not in cap
        ],
        dtype=np.intp,
    ).reshape(-1, 2)
    if len(e) < 2:
        return False
    d = p.vertices[e[:, 1]] - p.vertices[e[:, 0]]
    d /= np.linalg.norm(d, axis=1)[:, None]
    return bool(
        (np.abs(d @ d[0]) >= math.cos(math.radians(current().features.tolerance_deg))).all()
    )


def _sides(model: ObjectModel, name: str, horizontal_deg: float) -> list[int]:
    """The lateral faces: neither base nor top."""
    p = _poly(model, name)
    base, top = _caps(model, name, horizontal_deg)
    return [f for f in range(len(p.faces)) if f not in base and f not in top]


@dataclass(frozen=True)
class _Lateral:
    edges: list[tuple[int, int]]
    points: FloatArray  # (k, 3) first vertex of each lateral edge
    directions: FloatArray  # (k, 3) unit direction of each lateral edge
    faces: NDArray[np.intp]  # (k, 2) the polyhedron faces each lateral edge joins


def _lateral(model: ObjectModel, name: str, horizontal_deg: float) -> _Lateral:
    p = _poly(model, name)

    def compute() -> _Lateral:
        base, top = _caps(model, name, horizontal_deg)
        cap = base | top
        pairs = [
            (e, fg)
            for e, fg in zip(p.edges, p.edge_faces, strict=True)
            if fg[0] not in cap and fg[1] not in cap
        ]
        edges = [e for e, _ in pairs]
        e = np.asarray(edges, dtype=int).reshape(-1, 2)
        a = p.vertices[e[:, 0]]
        d = p.vertices[e[:, 1]] - a
        d = d / np.linalg.norm(d, axis=1)[:, None]
        faces = np.asarray([fg for _, fg in pairs], dtype=np.intp).reshape(-1, 2)
        return _Lateral(edges, a, d, faces)

    return _derived(model, (__name__, current().features, "lateral", horizontal_deg), compute)


def lateral_edges(
    model: ObjectModel, *, horizontal_deg: float | None = None
) -> list[tuple[int, int]]:
    """Edges (vertex index pairs) on neither the base nor a top face."""
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    return list(_lateral(model, "lateral_edges", horizontal_deg).edges)


def side_count(model: ObjectModel, *, horizontal_deg: float | None = None) -> int:
    """Number of lateral faces (neither base nor top): n of an n-gonal prism, pyramid, frustum."""
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    return len(_sides(model, "side_count", horizontal_deg))


def _lateral_lines(model: ObjectModel, horizontal_deg: float) -> tuple[FloatArray, FloatArray]:
    lat = _lateral(model, "lateral edges", horizontal_deg)
    return lat.points, lat.directions


def _common_point(model: ObjectModel, horizontal_deg: float) -> tuple[FloatArray, float] | None:
    def compute() -> tuple[FloatArray, float] | None:
        a, d = _lateral_lines(model, horizontal_deg)
        if len(a) < 2:
            return None
        proj = np.eye(3)[None, :, :] - d[:, :, None] * d[:, None, :]
        m = proj.sum(axis=0)
        sv = np.linalg.svd(m, compute_uv=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            if not sv[0] / sv[-1] <= 1e6:  # the condition number (inf/nan: singular)
                return None
        point = np.linalg.solve(m, np.einsum("kij,kj->i", proj, a))
        miss = np.einsum("kij,kj->ki", proj, point[None, :] - a)
        return point, float(np.sqrt((miss**2).sum(axis=1).mean()))

    return _derived(model, (__name__, current().features, "common_point", horizontal_deg), compute)


def lateral_common_point(
    model: ObjectModel, *, horizontal_deg: float | None = None
) -> tuple[FloatArray, float] | None:
    """Least-squares common point of the lateral edge lines and its RMS miss distance (m).

    ``p = (Σ(I − ddᵀ))⁻¹ Σ(I − ddᵀ)a``; None when there are fewer than two lateral edges or
    the lines are (nearly) parallel, so that no finite point is determined.
    """
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    found = _common_point(model, horizontal_deg)
    return None if found is None else (found[0].copy(), found[1])


def _diameter(model: ObjectModel, name: str) -> float:
    p = _poly(model, name)
    return _derived(model, (__name__, current().features, "diameter"), lambda: p.diameter)


def section_at(model: ObjectModel, z: float) -> FloatArray:
    """The cross-section polygon (k, 2) of the polyhedron at height ``z`` (counter-clockwise)."""
    from tactile_kb.geometry.sections import cross_section

    return cross_section(_poly(model, "section_at"), z)


# ---------------------------------------------------------------------------------------------
# boolean extractors


def contact(model: ObjectModel) -> bool:
    """There is contact between the object and the finger."""
    return len(model.record.contacts) > 0


def surface_curved(
    model: ObjectModel,
    *,
    residual_tol: float | None = None,
    smooth_deg: float | None = None,
    min_smooth_edges: int | None = None,
    sagitta_tol: float | None = None,
    spread_deg: float | None = None,
) -> bool:
    """The surface is curved: a face's tip centres miss its plane (RMS above ``residual_tol``)
    or bend over the face (sagitta above ``sagitta_tol``, :func:`face_sagitta`), or the
    polyhedron has many smooth edges (without a polyhedron: many faces with a neighbour
    direction that close).

    Both tolerances are relative by default: :data:`RESIDUAL_RHO` × the tip radius, and the
    larger of :data:`SAGITTA_RHO` × the tip radius and :data:`SAGITTA_FRACTION` × the face's
    extent; never below 3 (residual) or 4 (sagitta) σ of the record's declared noise.

    Which sensors fired matters only inside a face, and only as a hint: a touch near a
    (rounded) edge of any real box fires a neighbouring sensor, so only contacts further than
    ρ·sin(spread) plus the largest edge rounding (``geometry.edge_rounding``
    (:mod:`tactile_kb.settings`) × the face's width) from the face's edges count
    (:func:`interior_spread_deg`), and a flat face turned between two sensors fires either.
    Where such contacts fired sensors more than ``spread_deg`` apart, the face's tip centres
    measure its turn (:func:`spread_bend`): beyond ``spread_deg`` by ``features.bend_sigmas``
    standard errors, curved; below it, the sensors' quantisation or the face's relief. Where
    the centres cannot tell, the face counts as one gentle fold towards
    ``min_smooth_edges``."""
    smooth_deg = _default(smooth_deg, "smooth_deg")
    spread_deg = _default(spread_deg, "spread_deg")
    min_smooth_edges = _default(min_smooth_edges, "min_smooth_edges")
    rho = model.record.tip_radius
    noise = model.record.noise
    res_tol = (
        residual_tol
        if residual_tol is not None
        else max(current().features.residual_rho * rho, 3.0 * noise)
    )
    if any(f.refined and f.residual > res_tol for f in model.faces):
        return True
    for f in model.contact_faces:
        found = face_sagitta(model, f)
        if found is None:
            continue
        sag, extent = found
        tol = sagitta_tol if sagitta_tol is not None else sagitta_tolerance(model, extent)
        if sag > tol:
            return True
    bent, folds = _spread_evidence(model, spread_deg)
    if bent or centres_on_circle(model) or centres_on_sphere(model):
        return True
    p = model.polyhedron
    cos_smooth = math.cos(math.radians(smooth_deg))
    if p is None:
        # no polyhedron (vertices of many narrow faces merged away): count the faces whose
        # nearest neighbour direction is within ``smooth_deg``, as the smooth edges they make
        n = np.asarray([f.normal for f in model.contact_faces], dtype=float).reshape(-1, 3)
        if len(n) < 2:
            return False
        c = n @ n.T
        np.fill_diagonal(c, -1.0)
        return int((c.max(axis=1) > cos_smooth).sum()) >= min_smooth_edges
    smooth = int((_edge_cosines(model, p) > cos_smooth).sum())
    return smooth + folds >= min_smooth_edges


def _round_fit(pts: FloatArray) -> tuple[FloatArray, float, FloatArray]:
    """The circle through 2-D points, or the sphere through 3-D ones: its centre, radius and
    the points' signed misses (algebraic fit, refined by Gauss-Newton steps on the geometric
    distances)."""
    dim = pts.shape[1]
    a = np.column_stack([2.0 * pts, np.ones(len(pts))])
    sol = np.linalg.lstsq(a, (pts**2).sum(axis=1), rcond=None)[0]
    c = np.asarray(sol[:dim], dtype=float)
    r = math.sqrt(max(float(sol[dim] + c @ c), 0.0))
    for _ in range(5):
        d = pts - c
        dist = np.linalg.norm(d, axis=1)
        if float(dist.min()) < 1e-12:
            break
        jac = np.column_stack([-d / dist[:, None], -np.ones(len(pts))])
        step = np.linalg.lstsq(jac, -(dist - r), rcond=None)[0]
        c, r = c + step[:dim], r + float(step[dim])
    miss = np.linalg.norm(pts - c, axis=1) - r
    return c, r, np.asarray(miss, dtype=float)


def _off_axis(pts: FloatArray, d: FloatArray, rho: float, tol: float) -> FloatArray | None:
    """Tip centres ``pts`` seen along an axis (2-D) and their sensors' directions ``d`` seen
    along it: the angle (radians) of each sensor from the circle's centre, when the centres lie
    on one circle of radius over 1.5 ρ (a sharp edge's centres lie at ρ) with an RMS miss
    (n − 3 degrees of freedom) of at most ``tol``, round it by at least ``circle_arc_deg``
    (a flat face's centres lie on a line, which fits a huge circle over a small arc); None
    when they do not."""
    s = current().features
    if len(pts) < max(4, 2 * s.circle_faces):
        return None
    c, r, miss = _round_fit(pts)
    rms = math.sqrt(float((miss**2).sum()) / (len(miss) - 3))
    if not (r > 1.5 * rho and rms <= tol):
        return None
    gaps = _turn_gaps(pts - c)
    if math.degrees(2.0 * math.pi - float(gaps.max())) < s.circle_arc_deg:
        return None
    inward = c - pts
    cosang = (d * inward).sum(axis=1) / np.maximum(
        np.linalg.norm(d, axis=1) * np.linalg.norm(inward, axis=1), 1e-12
    )
    return np.asarray(np.arccos(np.clip(cosang, -1.0, 1.0)), dtype=float)


def _readings(d: FloatArray, quantum: float) -> int:
    """How many distinct directions the 2-D directions ``d`` take about the axis: runs of
    directions each within ``quantum`` (radians) of the next count as one."""
    if len(d) == 0:
        return 0
    return max(1, int((_turn_gaps(d) > quantum).sum()))


def _turn_gaps(v: FloatArray) -> FloatArray:
    """The angles (radians) between successive 2-D directions ``v`` in turn order, the last
    to the first round the full turn included."""
    a = np.sort(np.arctan2(v[:, 1], v[:, 0]))
    return np.asarray(np.diff(np.append(a, a[0] + 2.0 * math.pi)), dtype=float)


def centres_on_circle(model: ObjectModel) -> bool:
    """Faces around one axis whose tip centres lie on one circle: a curved surface touched in
    narrow facets (a thin cylinder lying on its side, whose contour layers and probes each
    fit a facet a few millimetres wide, meeting the next at an angle the touches never saw).

    Tip centres lie on the surface offset by ρ: on a cylinder of radius R they lie on a
    circle of radius R + ρ about its axis, whichever facet the model made of them, and each
    contact's sensor points at that axis (within the finger's sensor spacing). On a prism
    they lie on the faces' offset planes, straight across each face, joined by arcs of
    radius ρ at its edges. Candidate axes are the cross products of two faces' normals; the
    faces whose normals lie within ``horizontal_deg`` of square to one (the features'
    lateral tolerance) are the chain around it. Curved when at least ``circle_faces`` (5) such
    faces have centres that, seen along the axis,

    * miss one circle by an RMS of at most ``circle_rho`` ρ, or ``circle_ratio`` × the faces'
      own scatter about their planes when more (pooled over the chain's refined faces, the
      declared σ when they have fewer than three degrees of freedom; ``circle_ratio`` is 0 by
      default: at 1.25 a lying cylinder under 0.5 mm noise is mostly found curved, but so is
      a small octagonal prism, 1.5 cm across, standing): under noise a
      polyhedron's faces fit their planes within the noise and a circle only worse (a small
      icosahedron's ring of faces misses a circle by as much again), a curved surface's
      facets fit their planes no better than the circle (a ring of four faces of an
      icosahedron lies square to one axis and, touched near their middles, on a circle within
      the noise: hence five faces),
    * go round it by at least ``circle_arc_deg`` (a flat face's centres lie on a line, which
      fits a huge circle over a small arc),
    * on a circle of radius over 1.5 ρ (a surface radius over ρ/2: a sharp edge's centres
      lie on a circle of radius ρ about it),

    and each contact's sensor points within the finger's median sensor spacing of the circle's
    centre.

    Under noise the model often makes fewer than five facets of a lying cylinder (neighbouring
    lines of contacts merge), and its faces fit their planes no better than a small prism's
    faces fit a circle (an octagonal prism of radius 1.5 cm: within 1.1–1.3 σ).
    So every contact whose sensor is square to a candidate axis also counts, whichever face
    the model made of it: curved when their sensors take at least ``circle_faces`` readings
    about the axis (directions more than a reading's quantisation apart: a third of the median
    sensor spacing, within which the mean of two neighbouring sensors lies of a normal that
    closes both), their centres miss one circle by an RMS of at most ``circle_sigmas`` × the
    declared σ (or ``circle_rho`` ρ) over ``circle_arc_deg`` with a radius over 1.5 ρ, and
    at most ``circle_off_fraction`` of their sensors point off its centre by more than a
    reading's quantisation. On a cylinder the sensor that closes turns with the tip centre
    round the axis; on a prism one face keeps one sensor while its centres go round the axis
    by the face's angle (under 0.5 mm noise an octagonal prism of radius 1.5 cm leaves 42–53 %
    of its sensors more than 10° off, a lying cylinder of radius 1 cm at most 17 %). Settings
    ``features.circle_*``.
    """

    def compute() -> bool:
        s = current().features
        record = model.record
        rho, sigma = record.tip_radius, record.noise
        faces = [f for f in model.contact_faces if f.contacts]
        if len(faces) < 2:
            return False
        normals = np.asarray([f.normal for f in faces], dtype=float)
        centres = np.asarray([c.centre for c in record.contacts], dtype=float)
        directions = np.asarray([c.direction for c in record.contacts], dtype=float)
        spacing = _sensor_spacing(record)
        # a reading's quantisation: two neighbouring sensors' mean lies within a third of
        # their spacing of the normal that closes both (cones overlapping by a third)
        quantum = spacing / 3.0
        square = math.sin(math.radians(s.horizontal_deg))
        tried: list[FloatArray] = []
        for i in range(len(faces)):
            for j in range(i + 1, len(faces)):
                axis = np.cross(normals[i], normals[j])
                norm = float(np.linalg.norm(axis))
                if norm < math.sin(math.radians(5.0)):
                    continue
                axis = axis / norm
                if any(abs(float(axis @ t)) > math.cos(math.radians(5.0)) for t in tried):
                    continue
                tried.append(axis)
                e1 = np.cross(axis, [1.0, 0.0, 0.0])
                if float(np.linalg.norm(e1)) < 0.5:
                    e1 = np.cross(axis, [0.0, 1.0, 0.0])
                e1 = e1 / float(np.linalg.norm(e1))
                basis = np.column_stack([e1, np.cross(axis, e1)])
                chain = [k for k in range(len(faces)) if abs(float(normals[k] @ axis)) < square]
                if len(chain) >= s.circle_faces:
                    idx = sorted({c for k in chain for c in faces[k].contacts})
                    # the faces' own scatter about their planes (pooled over the refined
                    # ones; the declared noise when they have too few degrees of freedom)
                    dof = sum(len(faces[k].contacts) - 3 for k in chain if faces[k].refined)
                    sse = sum(
                        len(faces[k].contacts) * faces[k].residual ** 2
                        for k in chain
                        if faces[k].refined
                    )
                    scatter = math.sqrt(sse / dof) if dof >= 3 else sigma
                    tol = max(s.circle_rho * rho, s.circle_ratio * scatter)
                    off = _off_axis(centres[idx] @ basis, directions[idx] @ basis, rho, tol)
                    if off is not None and float(off.max()) <= spacing:
                        return True
                # every contact whose sensor is square to the axis, whichever face the
                # model made of it: at least circle_faces readings apart, and few sensors
                # off the axis by more than a reading's quantisation
                sel = np.flatnonzero(np.abs(directions @ axis) < square)
                if len(sel) < 2 * s.circle_faces:
                    continue
                d = directions[sel] @ basis
                if _readings(d, quantum) < s.circle_faces:
                    continue
                tol = max(s.circle_rho * rho, s.circle_sigmas * sigma)
                off = _off_axis(centres[sel] @ basis, d, rho, tol)
                if off is not None and float((off > quantum).mean()) <= s.circle_off_fraction:
                    return True
        return False

    return _derived(model, (__name__, current().features, "centres_on_circle"), compute)


def _sensor_spacing(record: ExplorationRecord) -> float:
    """The finger's median angle (radians) from a sensor to its nearest neighbour (30° when
    the record names fewer than two sensors)."""
    sensors = np.asarray(record.sensor_directions, dtype=float).reshape(-1, 3)
    if len(sensors) < 2:
        return math.radians(30.0)
    m = sensors / np.linalg.norm(sensors, axis=1)[:, None]
    cos = m @ m.T
    np.fill_diagonal(cos, -1.0)
    return float(np.median(np.arccos(np.clip(cos.max(axis=1), -1.0, 1.0))))


def _distinct_directions(d: FloatArray, quantum: float) -> int:
    """How many of the unit directions ``d`` (rows) lie more than ``quantum`` (radians) from
    every one counted before them."""
    kept: list[FloatArray] = []
    cos_q = math.cos(quantum)
    for v in d:
        if all(float(v @ k) < cos_q for k in kept):
            kept.append(v)
    return len(kept)


def centres_on_sphere(model: ObjectModel) -> bool:
    """Every tip centre of the record lies on one sphere: a ball, whichever faces the model
    made of its touches (a ball's contour layers are circles, and a slide along one fits a
    plane of its own within a fraction of a millimetre).

    Tip centres on a ball of radius R lie at R + ρ from its centre, each contact's sensor
    pointing at it; a polyhedron's tip centres lie on its faces' offset planes, nearer the
    centre in a face's middle than at its edges, so they miss their best sphere by a share
    of its radius that the polyhedron's shape sets, not its size. Curved when the centres
    (at least 2 × ``circle_faces``) miss one sphere by an RMS (n − 4 degrees of freedom) of
    at most ``sphere_fraction`` × its radius, that radius is over 1.5 ρ and no larger than
    the centres' extent (a flat face's centres fit a huge sphere over a small cap), their
    sensors take at least ``circle_faces`` directions more than a reading's quantisation
    apart (a third of the median sensor spacing), and the median sensor points within the
    median sensor spacing of the sphere's centre (a bowl touched from inside has its
    sensors point away from it). The tolerance is relative only: where noise or relief
    swamps it (a small ball), the other tests decide."""

    def compute() -> bool:
        s = current().features
        record = model.record
        rho = record.tip_radius
        centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
        if len(centres) < max(5, 2 * s.circle_faces):
            return False
        directions = np.asarray([c.direction for c in record.contacts], dtype=float)
        directions /= np.linalg.norm(directions, axis=1)[:, None]
        centre, radius, miss = _round_fit(centres)
        extent = float(np.ptp(centres, axis=0).max())
        if not (1.5 * rho < radius <= extent):
            return False
        rms = math.sqrt(float((miss**2).sum()) / (len(miss) - 4))
        if rms > s.sphere_fraction * radius:
            return False
        spacing = _sensor_spacing(record)
        if _distinct_directions(directions, spacing / 3.0) < s.circle_faces:
            return False
        inward = centre - centres
        inward /= np.maximum(np.linalg.norm(inward, axis=1), 1e-12)[:, None]
        off = np.arccos(np.clip((directions * inward).sum(axis=1), -1.0, 1.0))
        return float(np.median(off)) <= spacing

    return _derived(model, (__name__, current().features, "centres_on_sphere"), compute)


@dataclass(frozen=True)
class _Spread:
    angle: float  # largest angle (degrees) between two interior contacts' directions
    pair: tuple[int, int]  # the two contacts (record indices) that make it, or (-1, -1)
    interior: tuple[int, ...]  # the face's contacts away from its edges (record indices)
    any_angle: float = 0.0  # largest angle between any two of the face's contacts
    any_pair: tuple[int, int] = (-1, -1)
    on_face: tuple[int, ...] = ()  # contacts whose feet lie inside the face's polygon
    flat: tuple[int, ...] = ()  # those further inside than the edge rounding allowance


def _face_spreads(model: ObjectModel) -> list[_Spread]:
    """Per polyhedron face, the largest angle between the directions of two of its contacts
    that both lie inside the face, those two contacts, and the contacts inside the face.

    A contact is inside when it is further from each of the face's edges than ρ·sin of its
    largest angle to another contact of the face (the tip touches the face, not the edge,
    before its direction turns that far) plus the edge rounding allowance
    (``geometry.edge_rounding`` × the face's width)."""
    p = model.polyhedron
    if p is None or not model.face_of:
        return []

    def compute() -> list[_Spread]:
        assert p is not None
        out: list[_Spread] = []
        contacts = model.record.contacts
        rho = model.record.tip_radius
        for fi, poly in enumerate(p.faces):
            face = model.faces[model.face_of[fi]]
            if len(face.contacts) < 2:
                out.append(_Spread(0.0, (-1, -1), tuple(face.contacts)))
                continue
            v = p.vertices[list(poly)]
            n = p.normals[fi]
            c = np.asarray([contacts[i].centre for i in face.contacts], dtype=float)
            d = np.asarray([contacts[i].direction for i in face.contacts], dtype=float)
            d /= np.linalg.norm(d, axis=1)[:, None]
            foot = c - np.outer(c @ n - p.offsets[fi], n)  # onto the face's plane
            edge_dist = _polygon_edge_distance(foot, v, n)
            centred = v - v.mean(axis=0)
            _, _, vt = np.linalg.svd(centred, full_matrices=False)
            width = float(np.ptp(centred @ vt[1]))
            ang = np.degrees(np.arccos(np.clip(d @ d.T, -1.0, 1.0)))
            rounding = current().geometry.edge_rounding * width
            band = rho * np.sin(np.radians(ang)) + rounding
            inside = (edge_dist[:, None] > band) & (edge_dist[None, :] > band)
            own = edge_dist > rho * np.sin(np.radians(ang.max(axis=1))) + rounding
            interior = tuple(int(face.contacts[k]) for k in np.flatnonzero(own))
            on_face = tuple(int(face.contacts[k]) for k in np.flatnonzero(edge_dist > 0.0))
            flat = tuple(int(face.contacts[k]) for k in np.flatnonzero(edge_dist > rounding))
            e, f = np.unravel_index(int(np.argmax(ang)), ang.shape)
            anywhere = (float(ang[e, f]), (int(face.contacts[e]), int(face.contacts[f])))
            if not inside.any():
                out.append(_Spread(0.0, (-1, -1), interior, *anywhere, on_face, flat))
                continue
            masked = np.where(inside, ang, -1.0)
            a, b = np.unravel_index(int(np.argmax(masked)), masked.shape)
            pair = (int(face.contacts[a]), int(face.contacts[b]))
            out.append(_Spread(float(masked[a, b]), pair, interior, *anywhere, on_face, flat))
        return out

    return _derived(
        model, (__name__, current().features, current().geometry, "face_spreads"), compute
    )


def interior_spread_deg(model: ObjectModel) -> float:
    """Largest angle (degrees) between the contact directions of two contacts of one
    polyhedron face, both inside the face: further from each of its edges than ρ·sin of
    their angle plus the edge rounding allowance (``geometry.edge_rounding`` (:mod:`tactile_kb.settings`) ×
    the face's width). 0 without a polyhedron.

    This reads which sensors fired, and the 33-sensor finger quantises directions (its
    sensors lie 30° apart; a face turned between two of them fires either, or both, as the
    approach goes): on its own it is weak evidence. :func:`surface_curved` lets the tip
    centres decide wherever they can (:func:`spread_bend`)."""
    return max((s.angle for s in _face_spreads(model)), default=0.0)


def spread_bend(
    model: ObjectModel, face: int, *, anywhere: bool = False
) -> tuple[float, float] | None:
    """The turn of polyhedron face ``face`` measured from its tip centres, in the direction
    its interior sensors spread: ``(turn, sigma)`` in degrees, or None when no two interior
    contacts fired different sensors.

    Tip centres on a plane face lie on the plane offset by ρ, whichever sensor closed; on a
    surface that turns they fall away from it. Along ``u``, the in-plane direction in which
    the two most different interior sensor normals differ, the heights of the face's centres
    are fitted by a plane plus ``a·u²``: the curvature ``−2a/W²`` over the centres' extent
    ``W`` along ``u``, and the turn is that curvature over the extent of all the face's
    contacts along ``u`` (radians; positive: convex). The centres fitted are those whose feet
    lie inside the face's polygon, when five or more do (a foot beyond an edge touched that
    edge, rounded on a real object, or the face beyond), else all of them. Centres more than
    :data:`~tactile_kb.geometry.planes.INSIDE_SIGMAS` scales (their own scatter, 1.4826 × the
    median absolute deviation) inside the least-squares plane of them all are touches of an
    edge beside the face and left out, unless more than a quarter would be (then the face
    bends away itself).
    The turn is at most the extent over ρ (tip centres lie on the surface offset by ρ, whose
    radius of curvature is at least ρ where the surface is convex); a steeper fit, from
    centres crowded within a few millimetres along ``u``, is cut to that.
    ``sigma`` is the turn's standard error from the larger of the declared noise σ,
    ``features.bend_sigma_rho`` × ρ and the centres' scatter about the bent fit (relief):
    infinite when the centres cannot show a bend at all (fewer than five, or on two lines
    across ``u``: :func:`_on_two_lines`)."""
    found = _bend(model, face, anywhere)
    return None if found is None else found[:2]


def _bend(model: ObjectModel, face: int, anywhere: bool) -> tuple[float, float, float] | None:
    """:func:`spread_bend`'s ``(turn, sigma)`` and the turn's standard error by the
    jackknife (:func:`_jackknife_se`), when that is larger (a turn that rests on one or two
    centres)."""
    spreads = _face_spreads(model)
    if (
        not 0 <= face < len(spreads)
        or (spreads[face].any_pair if anywhere else spreads[face].pair)[0] < 0
    ):
        return None
    s = spreads[face]
    pair = s.any_pair if anywhere else s.pair
    p = model.polyhedron
    assert p is not None
    contacts = model.record.contacts
    n = p.normals[face]
    d = -np.asarray([contacts[i].direction for i in pair], dtype=float)
    turn = d[1] / np.linalg.norm(d[1]) - d[0] / np.linalg.norm(d[0])
    u_dir = turn - (turn @ n) * n
    from tactile_kb.geometry.planes import INSIDE_SIGMAS, MAX_REJECTED, SMOOTH_RHO

    rho = model.record.tip_radius
    floor = max(model.record.noise, current().features.bend_sigma_rho * rho)
    # every contact of the face whose centre is not well inside the least-squares plane of
    # them all (a touch of an edge beside the face: nearer than ρ to its plane), at the
    # scale of their own scatter about it: a bent face's outer centres stay
    face_contacts = model.faces[model.face_of[face]].contacts
    every = np.asarray([contacts[i].centre for i in face_contacts], dtype=float)
    if len(s.on_face) >= 5:  # the face's own centres: not those of its (rounded) edges
        face_contacts = s.on_face
    c = np.asarray([contacts[i].centre for i in face_contacts], dtype=float)
    if len(c) >= 3:
        mean = c.mean(axis=0)
        ls_normal = np.linalg.svd(c - mean, full_matrices=False)[2][2]
        r = (c - mean) @ (ls_normal if ls_normal @ n >= 0 else -ls_normal)
        scale = max(floor, current().geometry.robust_rho * rho, _mad(r))
        on = r >= -INSIDE_SIGMAS * scale
        if on.sum() >= (1.0 - MAX_REJECTED) * len(on):  # else the face itself bends away
            c = c[on]
    if len(c) < 5 or float(np.linalg.norm(u_dir)) < 1e-9:
        return 0.0, math.inf, math.inf
    u_dir /= np.linalg.norm(u_dir)
    v_dir = np.cross(n, u_dir)
    c = c - c.mean(axis=0)
    u, v, h = c @ u_dir, c @ v_dir, c @ n
    width = float(np.ptp(u))
    # exact touches of an ideal face lie on its plane (to SMOOTH_RHO ρ): two lines of them
    # slightly oblique to u still tell a flat face; jittered ones (noise, a scan) fit any bend
    exact = model.record.noise <= 0 and float(
        np.linalg.svd(c, compute_uv=False)[2]
    ) <= SMOOTH_RHO * rho * math.sqrt(len(c))
    if width <= 0 or (not exact and _on_two_lines(u, SPOT_RHO * rho)):
        return 0.0, math.inf, math.inf
    us, vs = u / width, v / width  # well-conditioned unknowns
    plane = np.column_stack([np.ones_like(us), us, vs])
    q = us * us
    q_perp = q - plane @ np.linalg.lstsq(plane, q, rcond=None)[0]
    norm2 = float(q_perp @ q_perp)
    if norm2 <= 1e-12:
        return 0.0, math.inf, math.inf
    a = float(q_perp @ h) / norm2  # metres per (u/W)²: h ≈ a·(u/W)² + plane
    design = np.column_stack([plane, q])
    rest = h - design @ np.linalg.lstsq(design, h, rcond=None)[0]
    scatter = math.sqrt(float(rest @ rest) / (len(h) - 4))  # about the bent fit: relief
    # a's standard error, robust to a few stray centres and to centres crowded at one spot
    jack = _jackknife_se(design, rest, _spots(np.column_stack([u, v]), SPOT_RHO * rho))
    # relief of height h (geometry.relief_rho × ρ) under the contacts, heights uniform in
    # [0, h]: σ = h/√12, pooled with the measured scatter as a prior worth RELIEF_DOF
    # degrees of freedom (a face touched a few times cannot show its own relief; one touched
    # often shows it, whatever the prior says)
    dof = len(h) - 4
    prior = current().geometry.relief_rho * rho / math.sqrt(12.0)
    pooled = math.sqrt((dof * scatter**2 + RELIEF_DOF * prior**2) / (dof + RELIEF_DOF))
    sigma = max(floor, scatter, pooled)
    # κ = −2a/W², turned over the extent of all the face's contacts (its rounded edges too)
    whole = max(width, float(np.ptp(every @ u_dir)))
    k = whole / width
    # tip centres lie on the surface offset by ρ, bent by at most 1/ρ where the surface is
    # convex: over ``whole`` no face turns by more than whole/ρ (a steeper fit is the noise's)
    bound = whole / rho
    turn = max(-bound, min(bound, -2.0 * a / width * k))
    per_a = 2.0 / width * k  # radians of turn per metre of a
    return (
        math.degrees(turn),
        math.degrees(sigma / math.sqrt(norm2) * per_a),
        math.degrees(max(sigma / math.sqrt(norm2), jack) * per_a),
    )


def _spots(points: FloatArray, reach: float) -> IntArray:
    """A label per point: points within ``reach`` of each other (in chains) share a spot.

    A touch and the slides that stay by it, or a probe's touches at one place, rest on one
    patch of the surface and share its relief: they tell a face's bend no more than one
    centre does."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(points).query_pairs(reach, output_type="ndarray")
    graph = coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points), len(points))
    )
    labels: IntArray = np.asarray(connected_components(graph, directed=False)[1], dtype=np.intp)
    return labels


def _on_two_lines(u: FloatArray, reach: float) -> bool:
    """Whether positions ``u`` (m) lie on one or two lines across ``u``: in at most two runs
    (each a chain of positions within ``reach`` of the next), each no wider than ``reach``.
    Two rows of centres across the bend direction (two layers on a pyramid's side, seen
    along its slope) cannot show a bend, whatever their jitter along it; a row along it
    can."""
    runs = _spots(u[:, None], reach)
    return len(np.unique(runs)) <= 2 and all(
        float(np.ptp(u[runs == k])) <= reach for k in np.unique(runs)
    )


def _jackknife_se(design: FloatArray, rest: FloatArray, groups: IntArray | None = None) -> float:
    """The jackknife standard error of the last coefficient of the least-squares fit whose
    design matrix is ``design`` and residuals ``rest``: from the fits that leave out one
    group of rows each (``groups``: a label per row, by default one row per group; closed
    form through the hat matrix).
    Unlike the error the residuals' scatter implies, it grows when the coefficient rests on
    one or two spots: a bump or an edge's touch at the end of a face's row of centres, or a
    face touched a few times at each of a few places (the centres at one place share its
    relief), as a bent fit of a flat face with relief does. Where the fit cannot do without
    a group, one row is left out at a time; 0 when it cannot do without a row."""
    n = len(rest)
    if n < 2:
        return 0.0
    if groups is None:
        groups = np.arange(n)
    gram = np.linalg.pinv(design.T @ design)
    labels = np.unique(groups)
    shifts = np.empty(len(labels))
    for k, label in enumerate(labels):
        rows = np.flatnonzero(groups == label)
        x = design[rows]
        inner = np.eye(len(rows)) - x @ gram @ x.T
        if float(np.linalg.eigvalsh(inner)[0]) <= 1e-9:  # the fit needs this group
            if len(labels) < n:
                return _jackknife_se(design, rest, np.arange(n))
            return 0.0
        # β − β₍G₎ = (XᵀX)⁻¹ X_Gᵀ (I − H_GG)⁻¹ e_G: the last coefficient of each
        shifts[k] = float((gram @ x.T @ np.linalg.solve(inner, rest[rows]))[-1])
    g = len(labels)
    return math.sqrt((g - 1) / g * float(((shifts - shifts.mean()) ** 2).sum()))


def _mad(r: FloatArray) -> float:
    """σ of residuals from their median absolute deviation (robust to a few outliers)."""
    return 1.4826 * float(np.median(np.abs(r - np.median(r))))


def _leans(turn: float, sigma: float, spread_deg: float) -> bool:
    """A face whose turn the centres do not establish beyond ``spread_deg`` still counts as a
    gentle fold when they cannot measure it at all (``sigma`` infinite), or when their
    estimate itself reaches ``spread_deg`` and half its standard error (a small cylinder's
    narrow faces under 0.5 mm of noise are too uncertain to establish their turn, but they
    lean to it). An estimate below ``spread_deg``, or below half its own standard error, is
    no evidence: a flat face with relief (bumps, a scan's
    roughness under a few contacts) measures a turn of a few degrees, or tens with few
    touches, with a standard error as large, and six such faces made a polyhedron curved."""
    return math.isinf(sigma) or abs(turn) >= max(spread_deg, 0.5 * sigma)


def _spread_evidence(model: ObjectModel, spread_deg: float) -> tuple[bool, int]:
    """What the faces whose interior contacts fired sensors more than ``spread_deg`` apart
    tell: ``(bent, folds)``.

    The face's tip centres measure its turn (:func:`spread_bend`). Beyond ``spread_deg`` by
    ``features.bend_sigmas`` (3) standard errors, both the one the centres' scatter implies
    and the jackknife's (a turn that rests on one or two centres, a bump's or an edge's touch
    at the end of a row, is not established): ``bent``. Every face whose sensors spread is
    tested, so the false alarms of all of them add up: at two errors a model of six such
    flat faces would be curved one time in eight (on ``bench_real.py``'s scans, a prism's
    side touched 8 or 15 times measured a turn of 43° or 82° and made it so). Otherwise the
    spread is weak evidence where the centres cannot tell at all (on two lines, too few) or
    where their estimate itself reaches ``spread_deg`` (:func:`_leans`): the face counts as
    one gentle fold, as a smooth edge does (``folds``); an estimate below it is the sensors'
    quantisation (a flat face turned between two sensors fires either) or the face's relief.
    So does a face whose contacts fired sensors that far apart only near its edges: a small
    cylinder's faces are too narrow to have an inside, a box's are measured flat."""

    def outward(turn: float) -> float:
        # a convex object's surface, and the tip centres' offset of it, only turn outwards:
        # an inward turn measured on it is relief or a mix of two faces
        return turn if model.convex else abs(turn)

    def compute() -> tuple[bool, int]:
        folds = 0
        for fi, s in enumerate(_face_spreads(model)):
            if s.angle <= spread_deg:
                if s.any_angle > spread_deg:  # near its edges only: a fold at most
                    found = spread_bend(model, fi, anywhere=True)
                    if found is not None and _leans(*found, spread_deg):
                        folds += 1
                continue
            bend = _bend(model, fi, False)
            if bend is None:
                continue
            turn, sigma, jack = bend
            if outward(turn) - current().features.bend_sigmas * jack > spread_deg:
                return True, folds  # measured: it turns by more than spread_deg
            if _leans(turn, sigma, spread_deg):
                folds += 1  # the centres cannot tell: the sensors' weak evidence
        return False, folds

    return _derived(
        model,
        (__name__, current().features, current().geometry, "spread_evidence", spread_deg),
        compute,
    )


def _polygon_edge_distance(
    points: FloatArray, vertices: FloatArray, normal: FloatArray
) -> FloatArray:
    """Distance (m) of points in a face's plane to the nearest edge of the face's convex
    polygon, negative outside it (a foot beyond an edge is a touch of the edge or of the
    face beyond)."""
    a = vertices
    b = np.roll(vertices, -1, axis=0)
    ab = b - a
    t = np.clip(
        np.einsum("pkj,kj->pk", points[:, None, :] - a[None], ab) / (ab * ab).sum(axis=1), 0, 1
    )
    closest = a[None] + t[..., None] * ab[None]
    dist = np.linalg.norm(points[:, None, :] - closest, axis=2).min(axis=1)
    # outside the (convex) polygon: beyond one of its sides, as its centroid is not
    side = np.einsum("kj,pkj->pk", np.cross(ab, normal), points[:, None, :] - a[None])
    centre = np.einsum("kj,kj->k", np.cross(ab, normal), vertices.mean(axis=0) - a)
    outside = (side * np.sign(centre)[None, :] < 0).any(axis=1)
    return np.asarray(np.where(outside, -dist, dist))


def face_sagitta(model: ObjectModel, face: Face) -> tuple[float, float] | None:
    """How far a face's tip centres bend away from a plane over the face: ``(sagitta,
    extent)`` in metres, or None with fewer than :data:`MIN_SAGITTA_CONTACTS` contacts.

    The centres' heights above the face's plane are fitted robustly
    (``scipy.optimize.least_squares`` with the soft-L1 loss, so that a bump or a letter
    under one contact does not bend the fit) by a quadric ``h = a·u² + b·uv + c·v² + d·u +
    e·v + f`` in the face's own coordinates; the sagitta is the range, over the contacts, of
    the quadric's departure from its best plane, and the extent is the contacts' largest
    spread in the face. A cylinder's face bends by ``w²/8R`` over a width ``w``.

    Only the contacts on the face's flat part are fitted, when at least
    ``features.min_sagitta_contacts`` of them are: those whose feet lie further from the
    edges of the face's polygon than the largest edge rounding (``geometry.edge_rounding`` ×
    the face's width, as :func:`interior_spread_deg` leaves out). A tip on a rounded edge
    sits lower the further it rolls round it (by ``(r + ρ)(1 − cos θ)``, 2 mm at 30° for a
    1 cm rounding), and those touches, at one side of a face, bent its quadric by more than
    the tolerance: a scanned frustum's side was read curved.
    """
    if len(face.contacts) < current().features.min_sagitta_contacts or face.source != "contacts":
        return None

    def compute() -> tuple[float, float]:
        c = np.asarray([model.record.contacts[i].centre for i in face.contacts], dtype=float)
        flat = _on_flat_part(model, face)
        if int(flat.sum()) >= current().features.min_sagitta_contacts:
            c = c[flat]
        n = face.normal_array
        u = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
        u /= np.linalg.norm(u)
        v = np.cross(n, u)
        centred = c - c.mean(axis=0)
        x, y, h = centred @ u, centred @ v, centred @ n
        extent = float(max(np.ptp(x), np.ptp(y)))
        if extent <= 0:
            return 0.0, 0.0
        xs, ys = x / extent, y / extent  # well-conditioned unknowns
        design = np.column_stack([xs * xs, xs * ys, ys * ys, xs, ys, np.ones_like(xs)])
        start = np.linalg.lstsq(design, h, rcond=None)[0]
        scale = max(model.record.noise, 1e-4)
        from scipy.optimize import least_squares  # scipy only when a feature runs

        fit = least_squares(lambda p: design @ p - h, start, loss="soft_l1", f_scale=scale)
        quad = design[:, :3] @ fit.x[:3]
        lin = design[:, 3:]
        dev = quad - lin @ np.linalg.lstsq(lin, quad, rcond=None)[0]
        return float(np.ptp(dev)), extent

    return _derived(
        model,
        (__name__, current().features, current().geometry, "sagitta", face.contacts),
        compute,
    )


def sagitta_tolerance(model: ObjectModel, extent: float) -> float:
    """The default sagitta (metres) beyond which a face of ``extent`` (metres) is bent
    (:func:`surface_curved`): the largest of ``features.sagitta_rho`` × the tip radius,
    ``features.sagitta_fraction`` × the extent and 4 σ of the record's declared noise, plus
    ``geometry.relief_rho`` × the tip radius (bumps and letters under a few contacts bend the
    fit by up to their height)."""
    rho = model.record.tip_radius
    feats = current().features
    return max(
        feats.sagitta_rho * rho, feats.sagitta_fraction * extent, 4.0 * model.record.noise
    ) + (current().geometry.relief_rho * rho)


def _on_flat_part(model: ObjectModel, face: Face) -> NDArray[np.bool_]:
    """Per contact of ``face``, whether its foot lies on the face's flat part: further from the
    edges of its polygon than ``geometry.edge_rounding`` × its width (:func:`_face_spreads`'
    ``flat``; none for a face of fewer than two contacts, which it does not measure). All of
    them when the face has no polygon (no polyhedron, or not one of its faces)."""
    mine = [fi for fi, k in enumerate(model.face_of) if model.faces[k] is face]
    spreads = _face_spreads(model)
    if not mine or mine[0] >= len(spreads):
        return np.ones(len(face.contacts), dtype=bool)
    return np.isin(np.asarray(face.contacts, dtype=np.intp), spreads[mine[0]].flat)


def _edge_cosines(model: ObjectModel, p: Polyhedron) -> FloatArray:
    """(E,) cosine of the angle between the normals of the two faces at each edge."""

    def compute() -> FloatArray:
        ef = np.asarray(p.edge_faces, dtype=int).reshape(-1, 2)
        return np.asarray(
            np.einsum("ij,ij->i", p.normals[ef[:, 0]], p.normals[ef[:, 1]]), dtype=float
        )

    return _derived(model, (__name__, current().features, "edge_cosines"), compute)


def surface_plane(
    model: ObjectModel,
    *,
    residual_tol: float | None = None,
    smooth_deg: float | None = None,
    min_smooth_edges: int | None = None,
    sagitta_tol: float | None = None,
    spread_deg: float | None = None,
) -> bool:
    """The surface is plane: touched somewhere, and not curved (see ``surface_curved``)."""
    return contact(model) and not surface_curved(
        model,
        residual_tol=residual_tol,
        smooth_deg=smooth_deg,
        min_smooth_edges=min_smooth_edges,
        sagitta_tol=sagitta_tol,
        spread_deg=spread_deg,
    )


def lateral_edges_parallel(
    model: ObjectModel,
    *,
    tolerance_deg: float | None = None,
    horizontal_deg: float | None = None,
    min_edges: int = 3,
    sigmas: float | None = None,
    point_tol: float | None = None,
) -> bool:
    """ "Vertical" (lateral) edges are parallel: all within ``tolerance_deg`` of their mean
    axis; or, where their lines meet at no point (:func:`lateral_edges_concurrent`'s test
    with ``point_tol`` fails), each within its own tolerance of it: the larger of
    ``tolerance_deg`` and ``sigmas`` × the uncertainty of its direction, at most twice
    ``tolerance_deg`` (:func:`_edge_tolerances`). The narrow walls of a many-sided prism
    lying on one, touched a few times each, tilt their edges by more than a fixed tolerance
    allows, and a frustum's edges, however noisy, still meet near one point."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    sigmas = _default(sigmas, "sigmas")
    point_tol = _default(point_tol, "point_tol")
    _, d = _lateral_lines(model, horizontal_deg)
    if len(d) < min_edges:
        return False
    if _lateral_spread_deg(model, horizontal_deg) <= tolerance_deg:
        return True
    if sigmas <= 0 or _meet_at_point(model, horizontal_deg, point_tol):
        return False
    axis = _lateral_axis(model, horizontal_deg)
    angles = np.degrees(np.arccos(np.clip(np.abs(d @ axis), -1.0, 1.0)))
    allowed = _edge_tolerances(model, horizontal_deg, tolerance_deg, sigmas)
    return bool((angles <= allowed).all())


def _lateral_spread_deg(model: ObjectModel, horizontal_deg: float) -> float:
    """Largest angle (degrees) between a lateral edge and the edges' mean axis."""

    def compute() -> float:
        _, d = _lateral_lines(model, horizontal_deg)
        axis = _lateral_axis(model, horizontal_deg)
        return float(np.degrees(np.arccos(np.clip(np.abs(d @ axis).min(), -1.0, 1.0))))

    return _derived(
        model, (__name__, current().features, "lateral_spread", horizontal_deg), compute
    )


def _lateral_axis(model: ObjectModel, horizontal_deg: float) -> FloatArray:
    """The lateral edges' mean axis (the principal direction of their unit directions)."""

    def compute() -> FloatArray:
        _, d = _lateral_lines(model, horizontal_deg)
        _, vecs = np.linalg.eigh(d.T @ d)
        return np.asarray(vecs[:, -1], dtype=float)

    return _derived(model, (__name__, current().features, "lateral_axis", horizontal_deg), compute)


def _edge_tolerances(
    model: ObjectModel, horizontal_deg: float, tolerance_deg: float, sigmas: float
) -> FloatArray:
    """Per lateral edge, the angle (degrees) its direction may stray from the edges' axis:
    ``max(tolerance_deg, sigmas · √(u₁² + u₂²) / sin β)``, at most ``2 · tolerance_deg``,
    for the normal uncertainties u₁, u₂ of the two faces it joins and the angle β between
    their normals (an edge's direction turns by a normal's turn over sin β). The cap: a
    face known from its sensors alone has an uncertainty of the sensors' spacing, which
    would allow any direction."""
    lat = _lateral(model, "lateral edges", horizontal_deg)
    u = _uncertainty(model)
    p = _poly(model, "lateral edges")
    if len(lat.faces) == 0 or len(u) != len(p.faces):
        return np.full(len(lat.faces), tolerance_deg)
    a, b = lat.faces[:, 0], lat.faces[:, 1]
    sin = np.linalg.norm(np.cross(p.normals[a], p.normals[b]), axis=1)
    comb = np.sqrt(u[a] ** 2 + u[b] ** 2) / np.maximum(sin, 1e-6)
    return np.asarray(np.clip(sigmas * comb, tolerance_deg, 2.0 * tolerance_deg), dtype=float)


def _meet_at_point(model: ObjectModel, horizontal_deg: float, point_tol: float) -> bool:
    """The lateral edge lines miss their least-squares common point by at most ``point_tol``
    × the diameter (RMS)."""
    found = _common_point(model, horizontal_deg)
    return found is not None and found[1] <= point_tol * _diameter(model, "lateral edges")


def lateral_edges_concurrent(
    model: ObjectModel,
    *,
    point_tol: float | None = None,
    tolerance_deg: float | None = None,
    horizontal_deg: float | None = None,
    min_edges: int = 3,
) -> bool:
    """ "Vertical" edges join at one point: their least-squares common point misses each line
    by at most ``point_tol`` × the object's diameter (RMS), and they are not parallel."""
    point_tol = _default(point_tol, "point_tol")
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    _, d = _lateral_lines(model, horizontal_deg)
    if len(d) < min_edges or not _meet_at_point(model, horizontal_deg, point_tol):
        return False
    # meeting near a point, they are parallel only within tolerance_deg itself
    return _lateral_spread_deg(model, horizontal_deg) > tolerance_deg


def face_count(
    model: ObjectModel, *, equals: int | None = None, min: int | None = None, max: int | None = None
) -> bool:
    """The object has ``equals`` faces (or between ``min`` and ``max``), the base included.

    For a convex object these are the faces of the enveloping polyhedron; for a non-convex one
    (an object composed of boxes, whose concave faces the envelope leaves out) they are all
    the distinct planes touched, the table (and an assumed top) included: an L-shaped block
    has 8.
    """
    poly = _poly(model, "face_count")
    n = len(poly.faces) if model.convex else len(model.faces)
    if equals is not None and n != equals:
        return False
    if min is not None and n < min:
        return False
    return not (max is not None and n > max)


def parallel_face_pairs(
    model: ObjectModel,
    *,
    count: int | None = 3,
    min: int | None = None,
    tolerance_deg: float | None = None,
    sigmas: float | None = None,
) -> bool:
    """Exactly ``count`` (or at least ``min``) pairs of parallel faces exist."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = _default(sigmas, "sigmas")
    table = _parallelism(model, tolerance_deg, sigmas)
    pairs = int(np.triu(table, 1).sum())
    if min is not None:
        return pairs >= min
    return count is not None and pairs == count


def adjacent_faces_perpendicular(
    model: ObjectModel, *, tolerance_deg: float | None = None, sigmas: float | None = None
) -> bool:
    """Every two faces that share an edge are perpendicular."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = _default(sigmas, "sigmas")
    p = _poly(model, "adjacent_faces_perpendicular")
    table = _perpendicularity(model, tolerance_deg, sigmas)
    ef = np.asarray(p.edge_faces, dtype=int).reshape(-1, 2)
    return bool(table[ef[:, 0], ef[:, 1]].all())


def _edge_sigmas(model: ObjectModel) -> FloatArray:
    def compute() -> FloatArray:
        p = _poly(model, "edge_uncertainties")
        f_ = len(p.faces)
        if len(model.face_of) == f_:
            faces = [model.faces[i] for i in model.face_of]
            off = np.asarray([f.offset_uncertainty for f in faces], dtype=float)
            ang = np.radians([f.normal_uncertainty_deg for f in faces])
        else:  # a polyhedron without model faces: exact planes
            off, ang = np.zeros(f_), np.zeros(f_)
        at: list[list[int]] = [[] for _ in range(len(p.vertices))]
        for f, poly in enumerate(p.faces):
            for v in poly:
                at[v].append(f)
        cov = np.zeros((len(p.vertices), 3, 3))
        for v, fs in enumerate(at):
            n = p.normals[fs]
            # a tilt of plane i by δθ about its contacts' centre moves it at the vertex by
            # δθ·|v − centre|: each plane's offset error there, then least squares
            lever = np.linalg.norm(p.vertices[v] - p.face_centroids[fs], axis=1)
            var = off[fs] ** 2 + (ang[fs] * lever) ** 2
            a = np.linalg.pinv(n)  # (3, k): the least-squares vertex of the planes
            cov[v] = (a * var[None, :]) @ a.T
        e = np.asarray(p.edges, dtype=np.intp).reshape(-1, 2)
        u = p.vertices[e[:, 1]] - p.vertices[e[:, 0]]
        u /= np.linalg.norm(u, axis=1)[:, None]
        c = cov[e[:, 0]] + cov[e[:, 1]]
        var = np.einsum("ei,eij,ej->e", u, c, u)  # ≥ 0 but for rounding
        return np.asarray(np.sqrt(np.maximum(var, 0.0)), dtype=float)

    return _derived(model, (__name__, current().features, "edge_sigmas"), compute)


def edge_uncertainties(model: ObjectModel) -> FloatArray:
    """(E,) estimated 1σ uncertainty (m) of each polyhedron edge's length.

    Each vertex is the least-squares point of the planes meeting there; each plane's error
    at the vertex combines its offset uncertainty and its normal uncertainty times the
    distance from the face's centre (:class:`~tactile_kb.geometry.planes.Face` reports both), and the
    two end vertices' errors along the edge add in quadrature. Exact planes give 0.
    """
    return _edge_sigmas(model).copy()


def equal_edges(
    model: ObjectModel, *, rel_tol: float | None = None, sigmas: float | None = None
) -> bool:
    """Distances between neighbouring vertices are equal: the mean lengths of every two
    classes of parallel edges (directions within ``features.tolerance_deg``; an edge parallel
    to none is a class of its own) differ by at most ``max(rel_tol · mean, sigmas · √(σ₁² +
    σ₂²))``, and each edge lies that close to its class's mean (σ² of a class's mean: the sum
    of its edges' σ² over their count squared; σ from :func:`edge_uncertainties`). A face
    whose plane a rough surface tilts by a degree or two lengthens the edges on one side of it
    and shortens those opposite by as much (a 95 mm cube's lateral edges 91.8–97.6 mm under
    a top tilted by 1.7°): their mean keeps the length.
    An edge no longer than ``sigmas`` σ (and :data:`SPLIT_CORNER_RHO` ρ), or than ``rel_tol``
    of the mean edge, is a corner that noisy planes split (four faces of an octahedron meet at
    each corner, and four noisy planes meet in no one point), not an edge
    (:func:`_split_corners`).

    False on a model closed by an assumed top (``model.assumed_top``): the lateral edges'
    true length is unknown."""
    rel_tol = _default(rel_tol, "rel_tol")
    if sigmas is None:
        sigmas = current().features.edge_sigmas
    p = _poly(model, "equal_edges")
    if model.assumed_top is not None or model.assumed_reach:
        return False
    lengths = _derived(model, (__name__, current().features, "edge_lengths"), p.edge_lengths)
    sig = _edge_sigmas(model)
    kept = ~_split_corners(model, sigmas, rel_tol)
    lengths, sig = lengths[kept], sig[kept]
    if not len(lengths):
        return False
    least = rel_tol * float(lengths.mean())
    # parallel edges in classes: each class's mean length, and its σ
    e = np.asarray(p.edges, dtype=np.intp).reshape(-1, 2)[kept]
    u = p.vertices[e[:, 1]] - p.vertices[e[:, 0]]
    u /= np.linalg.norm(u, axis=1)[:, None]
    cos_par = math.cos(math.radians(current().features.tolerance_deg))
    from scipy.sparse.csgraph import connected_components  # scipy only when a feature runs

    _, label = connected_components(np.abs(u @ u.T) >= cos_par, directed=False)
    count = np.bincount(label).astype(float)
    mean = np.bincount(label, weights=lengths) / count
    msig = np.sqrt(np.bincount(label, weights=sig**2)) / count
    # every edge as long as its class's mean, and the classes' means alike
    if (np.abs(lengths - mean[label]) > np.maximum(least, sigmas * sig)).any():
        return False
    diff = np.abs(mean[:, None] - mean[None, :])
    allowed = np.maximum(least, sigmas * np.sqrt(msig[:, None] ** 2 + msig[None, :] ** 2))
    return bool((diff <= allowed).all())


def _split_corners(model: ObjectModel, sigmas: float, rel_tol: float) -> NDArray[np.bool_]:
    """(E,) whether each polyhedron edge is a split corner: no longer than ``sigmas`` times its
    length's uncertainty (:func:`edge_uncertainties`) and than :data:`SPLIT_CORNER_RHO` tip
    radii, or than ``rel_tol`` of the mean edge (the tolerance within which lengths count
    equal), so indistinguishable from none. Where more than three faces meet, noisy planes
    meet in no one point and leave such an edge; so do exact touches of a rough scan, whose
    fits report no uncertainty while a bump or a rounded edge tilts a plane by a degree or
    two.

    An edge between two faces that face away from each other (its end faces, one at each of
    its corners, antiparallel within ``features.tolerance_deg``) is never a split corner: the
    faces of one corner cannot be parallel, and such an edge is the thickness of a plate (a
    20 × 20 × 0.8 cm tile's 8 mm edges are under 6 % of its mean edge, and without them its
    edges were all equal: a cube)."""
    p = _poly(model, "edge_uncertainties")
    lengths = _derived(model, (__name__, current().features, "edge_lengths"), p.edge_lengths)
    least = rel_tol * float(lengths.mean()) if len(lengths) else 0.0
    cap = SPLIT_CORNER_RHO * model.record.tip_radius
    unsure = (lengths <= sigmas * _edge_sigmas(model)) & (lengths <= cap)
    short = unsure | (lengths <= least)
    from tactile_kb.geometry.polyhedron import opposed_edges  # scipy only when a feature runs

    return np.asarray(short & ~opposed_edges(p), dtype=bool)


def _face_cycles(
    model: ObjectModel, sigmas: float, rel_tol: float
) -> tuple[list[list[int]], FloatArray]:
    """Each polyhedron face's corners in order, and the corners' positions: the two ends of
    a split corner (:func:`_split_corners`) are one corner, at their middle."""
    p = _poly(model, "congruent_faces")
    split = _split_corners(model, sigmas, rel_tol)
    group = list(range(len(p.vertices)))

    def root(v: int) -> int:
        while group[v] != v:
            v = group[v]
        return v

    for (a, b), joined in zip(p.edges, split, strict=True):
        if joined:
            group[root(int(b))] = root(int(a))
    roots = sorted({root(v) for v in range(len(p.vertices))})
    number = {r: i for i, r in enumerate(roots)}
    corner = np.asarray([number[root(v)] for v in range(len(p.vertices))], dtype=np.intp)
    sums = np.zeros((len(roots), 3))
    np.add.at(sums, corner, p.vertices)
    positions = sums / np.bincount(corner, minlength=len(roots))[:, None]
    cycles = []
    for face in p.faces:
        ring = [int(corner[int(v)]) for v in face]
        kept = [c for c, d in zip(ring, ring[1:] + ring[:1], strict=True) if c != d]
        cycles.append(kept or ring[:1])
    return cycles, np.asarray(positions, dtype=float)


def _congruence(
    model: ObjectModel, sigmas: float, rel_tol: float
) -> tuple[bool, FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """How far the faces are from congruent with the first: ``(same number of sides,
    differences of the sorted side lengths (F − 1, sides), their uncertainty (F − 1,),
    largest difference of a sorted corner angle in degrees (F − 1,), its uncertainty in
    degrees (F − 1,), mean side length)``. Corners that noise split count once
    (:func:`_split_corners`); a face's side length is as uncertain as its most uncertain
    edge (:func:`edge_uncertainties`), and two faces' in quadrature. A corner's angle between
    sides of lengths a and b is uncertain by about s·√(1/a² + 1/b²) radians, s that side
    uncertainty (each side's direction by s over its length); a face's angles by the most
    uncertain of its corners."""
    p = _poly(model, "congruent_faces")
    cycles, corners = _face_cycles(model, sigmas, rel_tol)
    counts = np.asarray([len(f) for f in cycles], dtype=np.intp)
    none = np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(0)
    if (counts != counts[0]).any() or counts[0] < 3:
        return False, *none, 0.0
    sig = _edge_sigmas(model)
    index = {tuple(sorted(e)): i for i, e in enumerate(p.edges)}
    face_sigma = np.asarray(
        [
            max(sig[index[(min(v, w), max(v, w))]] for v, w in zip(f, f[1:] + f[:1], strict=True))
            for f in ([int(v) for v in face] for face in p.faces)
        ],
        dtype=float,
    )
    v = corners[np.asarray(cycles, dtype=np.intp)]  # (F, c, 3): faces' corners in order
    nxt = np.roll(v, -1, axis=1)
    prv = np.roll(v, 1, axis=1)
    a, b = nxt - v, prv - v
    lengths = np.linalg.norm(a, axis=2)
    back = np.linalg.norm(b, axis=2)
    cos = np.einsum("fij,fij->fi", a, b) / (lengths * back)
    angles = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    angle_sigma = np.degrees(face_sigma * np.sqrt(1.0 / lengths**2 + 1.0 / back**2).max(axis=1))
    lengths.sort(axis=1)
    angles.sort(axis=1)
    scale = float(np.mean(lengths.mean(axis=1)))
    if len(counts) < 2:
        return True, *none, scale
    diffs = np.abs(lengths[1:] - lengths[0])
    pair = np.hypot(face_sigma[1:], face_sigma[0])
    dangles = np.abs(angles[1:] - angles[0]).max(axis=1)
    return True, diffs, pair, dangles, np.hypot(angle_sigma[1:], angle_sigma[0]), scale


def congruent_faces(
    model: ObjectModel, *, rel_tol: float | None = None, tolerance_deg: float | None = None
) -> bool:
    """All faces are congruent: same number of sides, side lengths and angles (False on a
    model closed by an assumed top, whose lateral faces' height is unknown). Side lengths
    may differ by ``rel_tol`` of the mean side or by ``features.edge_sigmas`` times their
    uncertainty, whichever is more (as in :func:`equal_edges`), and corner angles by
    ``tolerance_deg`` or as many times theirs (a 3 cm octahedron under 0.5 mm noise: sides
    uncertain by 1 mm make its angles so by 4° between two faces, and two faces' angles
    differed by 6°); corners that noise split count once (:func:`_congruence`)."""
    rel_tol = _default(rel_tol, "rel_tol")
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = current().features.edge_sigmas
    _poly(model, "congruent_faces")
    if model.assumed_top is not None or model.assumed_reach:
        return False
    same, diffs, pair, dangles, angle_pair, scale = _derived(
        model,
        (__name__, current().features, "congruence", rel_tol),
        lambda: _congruence(model, sigmas, rel_tol),
    )
    allowed = np.maximum(rel_tol * scale, sigmas * pair)[:, None]
    return (
        same
        and bool((diffs <= allowed).all())
        and bool((dangles <= np.maximum(tolerance_deg, sigmas * angle_pair)).all())
    )


def top_face(model: ObjectModel, *, horizontal_deg: float | None = None) -> bool:
    """A top face parallel to the base exists (the base: the table face, or a prism's or a
    frustum's end when it lies on a side)."""
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    _, top = _caps(model, "top_face", horizontal_deg)
    return bool(top)


def lateral_faces_triangles(model: ObjectModel, *, horizontal_deg: float | None = None) -> bool:
    """Every lateral face (neither base nor top) is a triangle."""
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    p = _poly(model, "lateral_faces_triangles")
    sides = _sides(model, "lateral_faces_triangles", horizontal_deg)
    return bool(sides) and all(len(p.faces[f]) == 3 for f in sides)


def lateral_faces_vertical(
    model: ObjectModel,
    *,
    tolerance_deg: float | None = None,
    horizontal_deg: float | None = None,
) -> bool:
    """Every lateral face is "vertical": perpendicular to the base within ``tolerance_deg``."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    horizontal_deg = _default(horizontal_deg, "horizontal_deg")
    p = _poly(model, "lateral_faces_vertical")
    sides = _sides(model, "lateral_faces_vertical", horizontal_deg)
    base, _ = _caps(model, "lateral_faces_vertical", horizontal_deg)
    axis = p.normals[min(base)] if base else np.array([0.0, 0.0, -1.0])
    s = math.sin(math.radians(tolerance_deg))
    return bool(sides) and all(abs(p.normals[f] @ axis) <= s for f in sides)


def triangle_faces(model: ObjectModel) -> bool:
    """Every face of the polyhedron is a triangle."""
    return all(len(f) == 3 for f in _poly(model, "triangle_faces").faces)


def convex(model: ObjectModel) -> bool:
    """No concave face was touched (an object of several boxes is not convex)."""
    return model.convex


def orthogonal_faces(
    model: ObjectModel, *, tolerance_deg: float | None = None, sigmas: float | None = None
) -> bool:
    """Every two faces of the object are parallel or perpendicular (all its faces, the concave
    ones and the table too, not only the envelope's): a box, or with ``convex`` false an
    object composed of rectangular parallelepipeds. Two normals count as parallel or
    perpendicular within ``max(tolerance_deg, sigmas · √(u₁² + u₂²))``, u the faces' normal
    uncertainties."""
    tolerance_deg = _default(tolerance_deg, "tolerance_deg")
    sigmas = _default(sigmas, "sigmas")

    def compute() -> bool:
        n = np.asarray([f.normal for f in model.faces], dtype=float).reshape(-1, 3)
        if len(n) < 2:
            return False
        u = np.asarray([f.normal_uncertainty_deg for f in model.faces], dtype=float)
        tol = np.maximum(tolerance_deg, sigmas * np.sqrt(u[:, None] ** 2 + u[None, :] ** 2))
        ang = np.degrees(np.arccos(np.clip(n @ n.T, -1.0, 1.0)))
        off = np.minimum(np.minimum(ang, 180.0 - ang), np.abs(ang - 90.0))
        return bool((off <= tol).all())

    return _derived(
        model, (__name__, current().features, "orthogonal_faces", tolerance_deg, sigmas), compute
    )


# ---------------------------------------------------------------------------------------------
# measures: numbers a class's answer may report (``report: [sides]`` in a rule file)


_MEASURES: dict[str, tuple[Callable[[Polyhedron], float | int], str]] = {
    "faces": (lambda p: len(p.faces), "number of faces of the polyhedron"),
    "vertices": (lambda p: len(p.vertices), "number of vertices"),
    "edges": (lambda p: len(p.edges), "number of edges"),
    "volume": (lambda p: float(p.volume), "volume, cubic metres"),
    "height": (lambda p: float(np.ptp(p.vertices[:, 2])), "height above the table, metres"),
}


def measure_names() -> list[str]:
    """The measures a rule file's class may report, sorted."""
    return sorted([*_MEASURES, "sides"])


def measure(model: ObjectModel, name: str) -> float | int | None:
    """The measure ``name`` of ``model`` (see :func:`measure_names`); None when the model
    cannot give it (no closed polyhedron, no base to count sides from).

    ``sides`` is the n of an n-gonal prism, pyramid or frustum: the number of lateral faces.
    """
    if name not in measure_names():
        raise UsageError(f"unknown measure {name!r} (known: {', '.join(measure_names())})")
    if model.polyhedron is None:
        return None
    if name == "sides":
        try:
            return side_count(model)
        except GeometryError:
            return None
    if name == "faces" and not model.convex:  # as face_count counts them
        return len(model.faces)
    return _MEASURES[name][0](model.polyhedron)


def _feature(fn: FeatureFn, requires: Literal["contact", "model"] = "model") -> Feature:
    sig = inspect.signature(fn)
    params = {
        n: (None if p.default is inspect.Parameter.empty else p.default)
        for n, p in sig.parameters.items()
        if p.kind is inspect.Parameter.KEYWORD_ONLY
    }
    doc = (fn.__doc__ or "").strip().split("\n\n")[0].replace("\n", " ")
    return Feature(fn.__name__, fn, requires, doc, params)


BUILTIN_FEATURES: Mapping[str, Feature] = {
    f.name: f
    for f in (
        _feature(contact, "contact"),
        _feature(surface_curved),
        _feature(surface_plane),
        _feature(lateral_edges_parallel),
        _feature(lateral_edges_concurrent),
        _feature(face_count),
        _feature(parallel_face_pairs),
        _feature(adjacent_faces_perpendicular),
        _feature(equal_edges),
        _feature(congruent_faces),
        _feature(top_face),
        _feature(lateral_faces_triangles),
        _feature(lateral_faces_vertical),
        _feature(triangle_faces),
        _feature(convex),
        _feature(orthogonal_faces),
    )
}
"""The built-in features by name; the entry point ``builtin`` of ``tactile_kb.features.builtin``."""


def _valid(obj: Any) -> bool:
    return isinstance(obj, Feature) or callable(obj)


_REGISTRY: Registry[Feature] = Registry("tactile_kb.features", "feature", check=_valid)
_BUILTINS_CHECKED = False


def feature_registry() -> Registry[Feature]:
    """The registry of feature extractors (built-ins load through their entry point)."""
    global _BUILTINS_CHECKED
    if not _BUILTINS_CHECKED:
        _BUILTINS_CHECKED = True
        declared = any(
            ep.value == "tactile_kb.features.builtin:BUILTIN_FEATURES"
            for ep in entry_points(group="tactile_kb.features")
        )
        if not declared:  # a source checkout that is not installed: register them from code
            for name, feat in BUILTIN_FEATURES.items():
                _REGISTRY.register(name, feat, source="builtin")
    return _REGISTRY


def get_feature(name: str | Feature) -> Feature:
    """The feature called ``name`` (a :class:`Feature` is returned as it is)."""
    if isinstance(name, Feature):
        return name
    obj: Any = feature_registry().get(name)
    if isinstance(obj, Feature):
        return obj
    return _feature(obj) if obj.__name__ == name else Feature(name, obj, "model", obj.__doc__ or "")


def available_features() -> list[str]:
    """Names of the features that load, sorted."""
    return feature_registry().available()


def check_binding(name: str, params: Mapping[str, Any]) -> str | None:
    """Why a rule file's binding of feature ``name`` with ``params`` is wrong, or None."""
    try:
        feat = get_feature(name)
    except PluginError as exc:
        return str(exc)
    sig = inspect.signature(feat.fn)
    accepted = [n for n, p in sig.parameters.items() if p.kind is inspect.Parameter.KEYWORD_ONLY]
    for key, value in params.items():
        if key not in accepted:
            listed = ", ".join(sorted(accepted)) or "none"
            return f"feature {name!r} has no parameter {key!r} (parameters: {listed})"
        default = feat.params.get(key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            return f"feature {name!r}: parameter {key!r} must be a number, got {value!r}"
        if (
            isinstance(default, int)
            and not isinstance(default, bool)
            and not isinstance(value, int)
        ):
            return f"feature {name!r}: parameter {key!r} must be an integer, got {value!r}"
        if value < 0:
            return f"feature {name!r}: parameter {key!r} must be ≥ 0, got {value!r}"
    if name == "face_count" and not any(k in params for k in ("equals", "min", "max")):
        return "feature 'face_count' needs one of the parameters equals, min, max"
    return None


def evaluate_feature(
    feature: str | Feature, model: ObjectModel, params: Mapping[str, Any] | None = None
) -> bool:
    """Evaluate a feature on ``model`` with ``params``, checking the binding first."""
    feat = get_feature(feature)
    problem = check_binding(feat.name, params or {}) if not isinstance(feature, Feature) else None
    if problem:
        raise UsageError(problem)
    return bool(feat.fn(model, **(params or {})))
