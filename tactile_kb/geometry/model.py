"""The mathematical model of a touched object: its faces, enveloping polyhedron and sections.

"If the object is scanned by being touched at more points, we can have the assembly of all
surface equations of the enveloping polyhedron, which gives us the mathematical model of the
object." :func:`build_model` takes an exploration record through the whole chain — contacts →
one plane per face (:mod:`tactile_kb.geometry.planes`) → the enveloping polyhedron
(:mod:`tactile_kb.geometry.polyhedron`) → layer contours for non-convex objects
(:mod:`tactile_kb.geometry.sections`) — and returns an :class:`ObjectModel`, the value the feature
extractors read.

A face whose plane has touched points of the object outside it is *concave* (the inner sides
of an L-shaped block): the polyhedron is built from the supporting faces only, so for a
non-convex object it is its convex envelope, and the layer contours are the other view.
A partial record (an unexplored side) gives ``polyhedron=None`` and ``open_reason``. With
``assume_top=True``, a model open only at the top is closed instead: the 4-sensor finger,
whose sensors lie on the equator, never feels a top face, and contour following of a U-shaped
block does not reach it either. Then the model is closed by an *assumed top*, the horizontal plane through the highest touched
point (the object reaches at least that high), recorded as ``assumed_top``: features that
depend on the true height must not trust it (see :func:`tactile_kb.features.builtin.equal_edges`).
With ``assume_reach=True``, a model open in other directions (a side the finger could not touch)
is closed by an assumed face across each, through the farthest touched point that way, recorded
in ``assumed_reach``.

Examples
--------
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.synthetic import sample_record
>>> model = build_model(sample_record(box(0.08, 0.08, 0.08), builtin_finger("33"), seed=3))
>>> model.polyhedron is not None, len(model.faces), model.convex
(True, 6, True)
>>> partial = sample_record(box(0.08, 0.08, 0.08), builtin_finger("4"), noise=0.0, seed=3)
>>> m2 = build_model(partial)
>>> m2.polyhedron is None, m2.open_directions
(True, [(0.0, 0.0, 1.0)])
>>> m3 = build_model(partial, assume_top=True)
>>> m3.polyhedron is not None, len(m3.faces), m3.faces[-1].source, m3.assumed_top is not None
(True, 6, 'assumed', True)
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar, cast

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from tactile_kb.errors import GeometryError, OpenModelError, UsageError
from tactile_kb.geometry.planes import (
    SMOOTH_RHO,
    Face,
    contact_arrays,
    edge_faces,
    explained_faces,
    merge_plane_arrays,
    nearest_points,
    refit_past_roundings,
    surface_detail,
)
from tactile_kb.geometry.polyhedron import (
    Polyhedron,
    collapse_short_edges,
    face_width,
    polyhedron_from_planes,
)
from tactile_kb.geometry.rounded import unexplained
from tactile_kb.geometry.sections import LayerSection, distinct_planes, layer_sections
from tactile_kb.record import ExplorationRecord
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray

__all__ = [
    "ASSUMED_TOP_DEG",
    "COLLAPSE_SIGMAS",
    "NOISY_MERGE_FRACTION",
    "ObjectModel",
    "build_model",
    "derived",
]

ASSUMED_TOP_DEG = DEFAULTS.geometry.assumed_top_deg
"""An open model is closed by an assumed top when every open direction is within this angle
(degrees) of +z."""

NOISY_MERGE_FRACTION = DEFAULTS.geometry.noisy_merge_fraction
"""Vertex merge fraction of the object's smallest extent when the record declares
contact-position noise: four or more noisy planes meeting at one vertex (an octahedron's)
leave a gap of 3.5–5 % of an edge. Of the smallest extent, not the diameter: a thin
heptagonal prism 29 cm tall has 1.1 cm edges (4 % of its diameter)."""

COLLAPSE_SIGMAS = DEFAULTS.geometry.collapse_sigmas
"""Edges of a noisy model shorter than this many σ of their length are collapsed: four noisy
planes meeting at an octahedron's vertex split it into two joined by an edge of 1–4 mm
(2–4 σ), while the shortest real edges of the test families are more than 5 σ long."""

FAR_TOUCH_RHO = 2.0
"""A face of one or two touches that :func:`~tactile_kb.geometry.planes.edge_faces` takes for
an edge's stays when each of its tip centres lies further than ρ plus this many tip radii (and
3 σ) outside the polyhedron of the other faces (:func:`_far_from_edges`): a tip on an edge
of that polyhedron, sharp or rounded, has its centre within ρ of it, and bumps, letters and a
scan's roughness lift it by a millimetre or two, while a touch that far out met a face the
others lack. A 27 cm box lying on a side, whose contour ran out of motions before its far
end, had that end met by one probe as two contacts 35 mm further than ρ outside the
others' polyhedron (their sensors' normal 29° off on a rough scan), taken for an edge's: the
model stayed open."""

SUPPORT_SIGMAS = 3.0
"""Under declared noise a face's fitted plane may be turned by up to this many σ of its
normal's uncertainty before a touched point beyond it makes it concave (:func:`_support`; a
face known from its sensors alone turns by their quantisation cone, a bound): a 27 cm
hexagonal disc's bulged scan top fitted a patch of 11 touches 9.3° off (2σ of its 4.6°), and
at 1σ the touches 19–20 cm away on the rest of the top lay beyond it, so the disc was not
convex."""

ROUNDED_MAX_FACES = 14
"""More faces than this (a curved object's facets) are not examined against the rounded
envelope (:func:`_rounded_drop`)."""

T = TypeVar("T")


@dataclass(frozen=True, eq=False, kw_only=True)
class ObjectModel:
    """What the touch told: the record, its faces, the enveloping polyhedron, the layers.

    Attributes
    ----------
    record
        The exploration record the model was built from.
    faces
        One :class:`~tactile_kb.geometry.planes.Face` per face touched, then the table.
    polyhedron
        The enveloping polyhedron of the supporting faces, or None when they do not bound a
        region (then ``open_reason`` says why and ``open_directions`` where to explore).
    supporting
        Per face: True when no touched point lies outside its plane (False: a concave face).
    layers
        Layer contours of non-convex explorations (contacts with a ``layer``), bottom up.
    options
        The options the model was built with.
    """

    record: ExplorationRecord
    faces: tuple[Face, ...]
    polyhedron: Polyhedron | None
    supporting: tuple[bool, ...]
    open_reason: str = ""
    open_directions: list[tuple[float, float, float]] = field(default_factory=list)
    open_points: list[tuple[float, float, float]] = field(default_factory=list)
    """When the planes close, but only far from the touched points: the far vertex of each
    of ``open_directions`` (metres); otherwise empty."""
    layers: tuple[LayerSection, ...] = ()
    options: dict[str, Any] = field(default_factory=dict)
    face_of: tuple[int, ...] = ()
    """For each polyhedron face, the index of its :class:`Face` in ``faces``."""
    assumed_top: float | None = None
    """Height (m) of the assumed top face when the top was never touched and the model was
    closed at the highest touched point (its :class:`Face` has ``source == "assumed"`` and
    comes last in ``faces``); None when every face was touched. The true top is at least
    this high."""

    @property
    def convex(self) -> bool:
        """True when every face supports the object (no concave face was touched)."""
        return all(self.supporting)

    @property
    def assumed_reach(self) -> tuple[tuple[float, float, float], ...]:
        """The normals of the assumed faces that closed a model open in other directions than
        up (``build_model(assume_reach=True)``: each through the farthest touched point that
        way); empty when none was needed or the model was closed by an assumed top."""
        if self.assumed_top is not None:
            return ()
        return tuple(f.normal for f in self.faces if f.source == "assumed")

    @property
    def contact_faces(self) -> tuple[Face, ...]:
        """The faces found from contacts (without the table)."""
        return tuple(f for f in self.faces if f.source == "contacts")

    @property
    def sections(self) -> tuple[LayerSection, ...]:
        """Alias of ``layers``: the stacked contour polygons."""
        return self.layers

    def distinct_planes(self) -> list[tuple[tuple[float, float], float]]:
        """The different vertical planes touched over all layers (P1…P7 of the paper's Fig. 1)."""
        return distinct_planes(self.layers)


def build_model(
    record: ExplorationRecord,
    *,
    cut_deg: float | None = None,
    split_tol: float | None = None,
    merge_fraction: float | None = None,
    include_table: bool = True,
    support_tol: float | None = None,
    open_factor: float = 3.0,
    assume_top: bool = False,
    assume_reach: bool = False,
    collapse_sigmas: float | Literal["settings"] | None = "settings",
    edge_rounding: float | Literal["settings"] | None = "settings",
    rounded: bool = True,
) -> ObjectModel:
    """Build the :class:`ObjectModel` of ``record``.

    Parameters
    ----------
    record
        Contacts from an explorer or :func:`tactile_kb.touch.synthetic.sample_record`.
    cut_deg, split_tol
        Passed to :func:`tactile_kb.geometry.planes.merge_planes`.
    merge_fraction
        Passed to :func:`tactile_kb.geometry.polyhedron.polyhedron_from_planes`; None: the
        settings' ``geometry.merge_fraction``. When ``record.noise`` is positive and this is
        None, vertices merge within
        :data:`NOISY_MERGE_FRACTION` × the touched points' smallest extent if that is larger
        (``options["merge_tol"]``).
    include_table
        Add the support plane z = 0 as a face.
    support_tol
        A face is concave when a touched point lies more than this (m) outside its plane;
        default: the split tolerance.
    open_factor
        The planes must close within this many times the radius of the touched points
        (about their centre); further out the model counts as open (nearly parallel sides
        that meet only far away mean an unexplored end).
    assume_top
        When the planes are open only upwards (within :data:`ASSUMED_TOP_DEG` of +z), close
        them by a horizontal face through the highest touched point and record its height
        in ``assumed_top``.
    assume_reach
        When the planes stay open in other directions (a side the finger could not touch: a
        housing's flat mounting ear, lower than the tip, lies beyond the side above it, so
        that side supports nothing and no face closes the envelope there), close each open
        direction by a face across it through the farthest touched point that way (the object
        reaches at least that far), up to :data:`MAX_ASSUMED` faces, and list their normals
        in ``assumed_reach``.
    collapse_sigmas
        When ``record.noise`` is positive, polyhedron edges shorter than this many
        σ of their length (from the faces' uncertainties) are collapsed into a vertex
        (:func:`tactile_kb.geometry.polyhedron.collapse_short_edges`); None never collapses;
        ``"settings"``: the settings' ``geometry.collapse_sigmas``.
    edge_rounding
        Faces made of touches of the other faces' (sharp or rounded) edges are dropped
        (:func:`tactile_kb.geometry.planes.edge_faces` with this ``rounding``); their contacts are
        listed in ``options["edge_contacts"]``, and so are faces the others explain
        (:func:`tactile_kb.geometry.planes.explained_faces`); then each face whose touches
        that rolled onto a rounded edge beside it turn its plane is refitted without them
        (:func:`tactile_kb.geometry.planes.refit_past_roundings`). None keeps every face as
        fitted; ``"settings"``: the settings' ``geometry.edge_rounding``.
    rounded
        After those, drop the faces the rounded envelope of the others explains
        (:func:`tactile_kb.geometry.rounded.unexplained`, when ``geometry.rounded_fit_sigmas``
        is positive and ``edge_rounding`` is not None); their contacts join
        ``options["edge_contacts"]``, and so do those of a face that does not support the object
        but lies on the outside of the touches (:func:`_on_the_hull`): no concave face. The
        completion's models in the exploration loop leave all this out (False): it costs a fit
        per face, and only the final model is classified.

    Returns
    -------
    ObjectModel
        Never raises for a record that is merely incomplete or contradictory: then
        ``polyhedron`` is None and ``open_reason`` says why.
    """
    if not isinstance(record, ExplorationRecord):
        raise UsageError(f"build_model needs an ExplorationRecord, got {type(record).__name__}")
    geo = current().geometry
    if collapse_sigmas == "settings":
        collapse_sigmas = geo.collapse_sigmas
    if edge_rounding == "settings":
        edge_rounding = geo.edge_rounding
    noisy_merge = merge_fraction is None
    if merge_fraction is None:
        merge_fraction = geo.merge_fraction
    arrays = contact_arrays(record.contacts)
    faces = merge_plane_arrays(
        record,
        arrays,
        range(len(record.contacts)),
        cut_deg=cut_deg,
        split_tol=split_tol,
        include_table=include_table,
    )
    noise = record.noise
    tol = support_tol if support_tol is not None else max(split_tol or geo.split_tol, 6.0 * noise)
    points, normals, offsets, supporting = _support(arrays[0], record.tip_radius, faces, tol, noise)
    edge_contacts: tuple[int, ...] = ()
    if edge_rounding is not None and len(faces) >= 5:
        drop = edge_faces(
            faces,
            arrays[0],
            record.tip_radius,
            noise=noise,
            rounding=edge_rounding,
            sensed=_sensed(record, arrays[1]),
        )
        drop = _far_from_edges(faces, drop, arrays[0], record.tip_radius, noise, edge_rounding)
        if drop:
            faces, edge_contacts = _without(faces, drop, edge_contacts)
            points, normals, offsets, supporting = _support(
                arrays[0], record.tip_radius, faces, tol, noise
            )
    if edge_rounding is not None and len(faces) >= 5:
        drop = explained_faces(
            faces, supporting, arrays[0], record.tip_radius, noise=noise, rounding=edge_rounding
        )
        if drop:
            faces, edge_contacts = _without(faces, drop, edge_contacts)
            points, normals, offsets, supporting = _support(
                arrays[0], record.tip_radius, faces, tol, noise
            )
    if edge_rounding is not None and len(faces) >= 5:
        refitted = refit_past_roundings(
            faces, supporting, arrays, record.tip_radius, noise=noise, rounding=edge_rounding
        )
        if refitted != faces:
            faces = refitted
            points, normals, offsets, supporting = _support(
                arrays[0], record.tip_radius, faces, tol, noise
            )
    if (
        rounded
        and edge_rounding is not None
        and geo.rounded_fit_sigmas > 0
        and 5 <= len(faces) <= ROUNDED_MAX_FACES
    ):
        drop = _rounded_drop(faces, supporting, arrays[0], record.tip_radius, noise, edge_rounding)
        drop = sorted({*drop, *_on_the_hull(faces, supporting, arrays[0], record.tip_radius, tol)})
        if drop:
            faces, edge_contacts = _without(faces, drop, edge_contacts)
            points, normals, offsets, supporting = _support(
                arrays[0], record.tip_radius, faces, tol, noise
            )
    options = {
        "cut_deg": cut_deg,
        "split_tol": split_tol,
        "merge_fraction": merge_fraction,
        "merge_tol": None,
        "include_table": include_table,
        "support_tol": tol,
        "open_factor": open_factor,
        "assume_top": assume_top,
        "collapse_sigmas": collapse_sigmas,
        "edge_rounding": edge_rounding,
        "edge_contacts": edge_contacts,
    }
    layers = layer_sections(record)
    kept = [i for i, s in enumerate(supporting) if s]
    merge_tol = None
    if noise > 0 and noisy_merge and len(points) >= 4:
        merge_tol = _noisy_merge_tol(points, merge_fraction, geo.noisy_merge_fraction)
        options["merge_tol"] = merge_tol

    off_sigma = np.asarray([f.offset_uncertainty for f in faces], dtype=float)
    ang_sigma = np.radians([f.normal_uncertainty_deg for f in faces])

    def close(which: list[int], extra: tuple[Face, ...] = ()) -> Polyhedron:
        n, d = normals[which], offsets[which]
        off, ang = off_sigma[which], ang_sigma[which]
        for f in extra:  # assumed faces (where the object reaches at least), as exact as the table
            n, d = np.vstack([n, f.normal]), np.append(d, f.offset)
            off, ang = np.append(off, 0.0), np.append(ang, 0.0)
        poly = polyhedron_from_planes(
            n,
            d,
            merge_fraction=merge_fraction,
            tol=merge_tol,
            bound=_bound(points, open_factor),
            interior=points.mean(axis=0) if len(points) >= 4 else None,
        )
        if collapse_sigmas is None or noise <= 0:
            return poly
        at = list(poly.plane_index)
        return collapse_short_edges(poly, off[at], ang[at], sigmas=collapse_sigmas)

    def still_open(exc: OpenModelError) -> ObjectModel:
        return ObjectModel(
            record=record,
            faces=faces,
            polyhedron=None,
            supporting=tuple(supporting),
            open_reason=str(exc),
            open_directions=exc.open_directions,
            open_points=exc.far_points,
            layers=layers,
            options=options,
        )

    try:
        poly = close(kept)
    except OpenModelError as exc:
        top: float | None = None
        if assume_top and len(points) >= 4 and _only_upwards(exc.open_directions):
            top = float(points[:, 2].max())
            extra: tuple[Face, ...] = (
                Face((0.0, 0.0, 1.0), top, 0, 0.0, 0.0, (), False, "assumed"),
            )
            try:
                poly = close(kept, extra)
            except GeometryError:  # the sides do not close under that lid either
                return still_open(exc)
        elif assume_reach and len(points) >= 4:
            reached = _assumed_reach(points, exc, lambda more: close(kept, more))
            if reached is None:
                return still_open(exc)
            poly, extra = reached
        else:
            return still_open(exc)
        faces = (*faces, *extra)
        supporting.extend(True for _ in extra)
        kept.extend(range(len(faces) - len(extra), len(faces)))
        return ObjectModel(
            record=record,
            faces=faces,
            polyhedron=poly,
            supporting=tuple(supporting),
            layers=layers,
            options=options,
            face_of=tuple(kept[p] for p in poly.plane_index),
            assumed_top=top,
        )
    except GeometryError as exc:
        return ObjectModel(
            record=record,
            faces=faces,
            polyhedron=None,
            supporting=tuple(supporting),
            open_reason=str(exc),
            layers=layers,
            options=options,
        )
    face_of = tuple(kept[p] for p in poly.plane_index)
    return ObjectModel(
        record=record,
        faces=faces,
        polyhedron=poly,
        supporting=tuple(supporting),
        layers=layers,
        options=options,
        face_of=face_of,
    )


def _far_from_edges(
    faces: tuple[Face, ...],
    drop: list[int],
    centres: FloatArray,
    rho: float,
    noise: float,
    rounding: float,
) -> list[int]:
    """``drop`` without the faces whose touches lie far from every edge of the others.

    :func:`~tactile_kb.geometry.planes.edge_faces` drops a narrow face whose tip centres the
    other faces' polyhedron, grown by ρ, explains. A touch of an edge (sharp, or rounded with
    a radius up to ``rounding`` × the face's width) has its nearest point on that polyhedron
    at the edge, or within that radius of it. A row of touches whose nearest points lie, in
    the median, further from every edge than that (plus ρ for the model's own error, and
    3 σ of noise) touched a face the others do not have: a corner cut off the envelope (a
    lying octagonal prism's slanted side, met by one layer near its lower edge), not an
    edge. So did a row whose tip centres lie, in the median, further than 1.25 ρ (and 3 σ)
    outside that polyhedron: an edge's touch is ρ from it, a rounded edge's nearer; one
    further out met a part beyond a concave face (an L-block's foot). Such faces stay, and
    so does a face of one or two touches (no row) whose every tip centre lies further than
    (1 + :data:`FAR_TOUCH_RHO`) ρ and 3 σ outside it (a face the others lack, met once).
    """
    if not drop:
        return drop
    kept = [k for k in range(len(faces)) if k not in drop]
    normals = np.asarray([faces[k].normal for k in kept], dtype=float).reshape(-1, 3)
    offsets = np.asarray([faces[k].offset for k in kept], dtype=float)
    pts = centres[[i for f in faces for i in f.contacts]]
    bound = (pts.mean(axis=0), 3.0 * float(np.ptp(pts, axis=0).max()) + rho)
    try:
        poly = polyhedron_from_planes(normals, offsets, bound=bound, interior=bound[0])
    except GeometryError:
        return drop
    v = poly.vertices
    a = np.asarray([v[i] for i, _ in poly.edges], dtype=float).reshape(-1, 3)
    b = np.asarray([v[j] for _, j in poly.edges], dtype=float).reshape(-1, 3)
    if len(a) == 0:
        return drop
    widths = np.asarray([face_width(poly, f) for f in range(len(poly.faces))])
    out = []
    for k in drop:
        c = centres[list(faces[k].contacts)]
        q = nearest_points(c, poly.normals, poly.offsets)
        if len(c) < 3:
            # one or two touches are no row: an edge's, as edge_faces said, unless every one
            # lies too far outside the others' polyhedron for any edge of it
            gap = float((np.linalg.norm(c - q, axis=1) - rho).min())
            if gap <= FAR_TOUCH_RHO * rho + 3.0 * noise:
                out.append(k)
            continue
        seg = b - a
        t = np.clip(
            np.einsum("pij,ij->pi", q[:, None, :] - a[None], seg) / (seg * seg).sum(axis=1), 0, 1
        )
        far = np.linalg.norm(q[:, None, :] - (a[None] + t[..., None] * seg[None]), axis=2).min(1)
        on = np.abs(q @ poly.normals.T - poly.offsets) <= 1e-6
        width = np.where(on, widths[None, :], 0.0).max(axis=1)
        allowed = rounding * width + rho + 3.0 * noise
        beyond = np.linalg.norm(c - q, axis=1) - rho - 0.25 * rho - 3.0 * noise
        if float(np.median(far - allowed)) <= 0.0 and float(np.median(beyond)) <= 0.0:
            out.append(k)
    return out


def _sensed(record: ExplorationRecord, directions: FloatArray) -> FloatArray:
    """Per contact, the outward normal its sensors read at a touch; NaN for a slide's (it
    repeats the direction of the sensor its touch chose)."""
    out = -np.asarray(directions, dtype=float).reshape(-1, 3)
    slide = np.asarray([c.kind != "touch" for c in record.contacts], dtype=bool)
    out[slide] = np.nan
    return out


def _without(
    faces: tuple[Face, ...], drop: list[int], edge_contacts: tuple[int, ...]
) -> tuple[tuple[Face, ...], tuple[int, ...]]:
    """``faces`` without those in ``drop``, and ``edge_contacts`` with their contacts."""
    contacts = tuple(sorted((*edge_contacts, *(i for k in drop for i in faces[k].contacts))))
    return tuple(f for k, f in enumerate(faces) if k not in drop), contacts


def _rounded_drop(
    faces: tuple[Face, ...],
    supporting: list[bool],
    centres: FloatArray,
    rho: float,
    noise: float,
    rounding: float,
) -> list[int]:
    """The supporting faces the rounded envelope of the others explains
    (:func:`tactile_kb.geometry.rounded.unexplained`; the robust scale at least the declared
    noise and :data:`~tactile_kb.geometry.planes.SMOOTH_RHO` ρ)."""
    js = [k for k, s in enumerate(supporting) if s]
    if len(js) < 5:
        return []
    normals = np.asarray([faces[k].normal for k in js], dtype=float)
    offsets = np.asarray([faces[k].offset for k in js], dtype=float) + rho
    fixed = [faces[k].source != "contacts" for k in js]
    groups = [list(faces[k].contacts) for k in js]
    cand = [p for p, k in enumerate(js) if faces[k].source == "contacts" and faces[k].contacts]
    removed, _ = unexplained(
        centres,
        groups,
        normals,
        offsets,
        rho,
        fixed=fixed,
        candidates=cand,
        rounding=rounding,
        floor=max(noise, SMOOTH_RHO * rho),
        sigmas=current().geometry.rounded_fit_sigmas,
        min_width=current().geometry.rounded_min_width * rho,
    )
    return sorted(js[p] for p in removed)


HULL_FACING_DEG = 75.0
"""The facets of the tip centres' convex hull that a face's touches may lie on
(:func:`_on_the_hull`) face within this angle of its normal: not the hull's bottom or top,
which a layer of touches across a concave face lies on too (an L-block felt by the 4-sensor
finger at one height)."""


STEP_DEG = 10.0
"""A face that supports nothing is a step's (concave, :func:`_on_the_hull`) when a face that
supports the object lies within this angle of parallel to it …"""

STEP_RHO = 2.0
"""… and further out than this many tip radii: a T-block standing on its stem, felt by nine
touches, has its stem's sides touched where they lie on the hull of the touches, but the
crossbar's ends 4 cm further out the same way. A second plane fitted to part of a scan's
face lies a few millimetres off its face."""


def _on_the_hull(
    faces: tuple[Face, ...],
    supporting: list[bool],
    centres: FloatArray,
    rho: float,
    tol: float,
) -> list[int]:
    """The faces that do not support the object although every one of their tip centres lies
    within ``tol`` of the convex hull of all the tip centres (scipy's Qhull), on its facets
    facing their way (:data:`HULL_FACING_DEG`), and are no step's (:data:`STEP_DEG`,
    :data:`STEP_RHO`).

    Such a face touched the object's outside where the other faces are: a plane fitted to a
    rounded edge's or a bump's few touches, or to part of a face whose normal (its sensors',
    or a fit to a short row) lies a few degrees off. It made a convex scan concave: 44 of the
    138 wrong answers of levels 2 and 3 on four draws of ``bench_real.py`` came from such
    faces. A concave face's touches lie deep inside the hull, by the depth of the notch or
    hollow they are in, unless they were all made at its rim: then the face beside the notch
    that reaches further out the same way tells."""
    ks = [
        k
        for k, f in enumerate(faces)
        if not supporting[k] and f.source == "contacts" and f.contacts
    ]
    if not ks or len(centres) < 4:
        return []
    try:
        hull = ConvexHull(centres)
    except QhullError:  # the touches span no solid: no hull to lie on
        return []
    facets = hull.equations
    facing = math.cos(math.radians(HULL_FACING_DEG))
    parallel = math.cos(math.radians(STEP_DEG))
    out = []
    for k in ks:
        n = faces[k].normal_array
        if any(
            supporting[j]
            and g.source == "contacts"
            and float(g.normal_array @ n) >= parallel
            and g.offset - faces[k].offset > STEP_RHO * rho
            for j, g in enumerate(faces)
        ):
            continue  # a step: a face beside it reaches further out the same way
        near = facets[facets[:, :3] @ n >= facing]
        if not len(near):
            continue
        c = centres[list(faces[k].contacts)]
        depth = (-(c @ near[:, :3].T + near[:, 3])).min(axis=1)
        if float(depth.max()) <= tol:
            out.append(k)
    return out


def _support(
    centres: FloatArray, rho: float, faces: tuple[Face, ...], tol: float, noise: float = 0.0
) -> tuple[FloatArray, FloatArray, FloatArray, list[bool]]:
    """Surface points, face normals and offsets, and which faces support the object: no tip
    that touched lies wholly beyond their plane, by more than ``tol`` (the ball touched the
    object there, so the object reaches beyond the plane: a concave face). The tip centres
    are used, not the surface points estimated from each contact's face: a slide past the
    end of a face touches its edge, and the point estimated on the face's plane lies beyond
    the neighbouring face's.

    Under ``noise``, a face's plane may be turned by :data:`SUPPORT_SIGMAS` × its fitted
    normal's uncertainty σ, or by its sensors' quantisation cone when it is known from them
    alone (a bound, not a σ), about its own tip centres: one at a distance ``d`` from them
    lies beyond the plane by up to ``d · tan(3σ)`` (or ``d · tan(cone)``) more (at most 45°; an
    undercut face of a lying frustum touched along one line, its quantised normal 5.6° off,
    put a tip 133 mm away 10 mm beyond it, and the frustum was taken for a concave object);
    not so a face of one or two touches, which is no row to turn a plane about. The same
    holds for exact touches of a scan (its faces scatter by more than
    :data:`~tactile_kb.geometry.planes.SMOOTH_RHO` ρ,
    :func:`~tactile_kb.geometry.planes.surface_detail`): fitted to bumps and roundings, its
    planes are no more exact than noisy ones. Exact touches of an ideal surface keep the
    strict test: there the other faces' planes are exact, and a face an exact touch lies
    beyond is left out of the envelope rather than let in turned (let in, two faces of a
    3.3 cm icosahedron fitted as one turned five exact models curved)."""
    points = _surface_points(centres, rho, faces)
    normals = np.asarray([f.normal for f in faces], dtype=float).reshape(-1, 3)
    offsets = np.asarray([f.offset for f in faces], dtype=float)
    touched = [i for f in faces for i in f.contacts]
    if touched:
        c = centres[touched]
        beyond = c @ normals.T - offsets - rho
        allowed = np.full(beyond.shape, tol)
        # a scan's faces (detail beyond SMOOTH_RHO ρ) are no exact planes either
        inexact = noise > 0 or surface_detail(faces) > SMOOTH_RHO * rho
        for k, f in enumerate(faces if inexact else ()):
            if len(f.contacts) < 3:
                continue  # one or two touches are no row to turn a plane about
            own = centres[list(f.contacts)]
            d = np.sqrt(((c[:, None, :] - own[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
            # a fitted normal's uncertainty is a σ; a sensors' normal's, their quantisation
            # cone, is a bound already (three of it would turn a plane by 39°)
            sigmas = SUPPORT_SIGMAS if f.refined else 1.0
            turn = min(sigmas * f.normal_uncertainty_deg, 45.0)
            allowed[:, k] += d * math.tan(math.radians(turn))
        supporting = [bool(s) for s in (beyond - allowed).max(axis=0) <= 0.0]
    else:
        supporting = [True] * len(faces)
    return points, normals, offsets, supporting


MAX_ASSUMED = 6
"""At most this many assumed faces close an open model (``build_model(assume_reach=True)``)."""


def _assumed_reach(
    points: FloatArray, exc: OpenModelError, close: Callable[[tuple[Face, ...]], Polyhedron]
) -> tuple[Polyhedron, tuple[Face, ...]] | None:
    """The polyhedron closed by assumed faces, and those faces: one across each open
    direction through the farthest of ``points`` that way, then across the directions still
    open, at most :data:`MAX_ASSUMED`; None when they do not close it."""
    extra: list[Face] = []
    while True:
        directions = [np.asarray(d, dtype=float) for d in exc.open_directions]
        if not directions or len(extra) + len(directions) > MAX_ASSUMED:
            return None
        for d in directions:
            n = d / float(np.linalg.norm(d))
            normal = (float(n[0]), float(n[1]), float(n[2]))
            extra.append(Face(normal, float((points @ n).max()), 0, 0.0, 0.0, (), False, "assumed"))
        try:
            return close(tuple(extra)), tuple(extra)
        except OpenModelError as again:
            exc = again
        except GeometryError:
            return None


def _only_upwards(directions: list[tuple[float, float, float]]) -> bool:
    """True when ``directions`` is not empty and each is within :data:`ASSUMED_TOP_DEG` of +z."""
    c = math.cos(math.radians(current().geometry.assumed_top_deg))
    return bool(directions) and all(
        d[2] >= c * math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2) for d in directions
    )


def _noisy_merge_tol(
    points: np.ndarray[Any, np.dtype[np.float64]], fraction: float, noisy_fraction: float
) -> float:
    """The vertex merge distance (m) for a noisy record: ``fraction`` × the touched points'
    largest extent, or ``noisy_fraction`` (:data:`NOISY_MERGE_FRACTION`) × their smallest extent (along their
    principal axes) if that is larger. Four noisy planes meeting at one vertex of a compact
    object (an octahedron) split it by 3.5–5 % of an edge; an elongated object (a thin prism)
    has short edges across its length, which its smallest extent protects."""
    centred = points - points.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    extents = np.ptp(centred @ vt.T, axis=0)
    return float(max(fraction * extents.max(), noisy_fraction * extents.min()))


def _bound(
    points: np.ndarray[Any, np.dtype[np.float64]], factor: float
) -> tuple[Any, float] | None:
    if len(points) < 4:
        return None
    centre = points.mean(axis=0)
    radius = float(np.linalg.norm(points - centre, axis=1).max())
    return (centre, factor * max(radius, 1e-6))


def _surface_points(
    centres: np.ndarray[Any, np.dtype[np.float64]], rho: float, faces: tuple[Face, ...]
) -> np.ndarray[Any, np.dtype[np.float64]]:
    """Each contact's point on the object: its tip centre moved ρ along −(its face's normal)."""
    parts = [centres[list(f.contacts)] - rho * f.normal_array for f in faces if f.contacts]
    return np.vstack(parts) if parts else np.zeros((0, 3))


_DERIVED: weakref.WeakKeyDictionary[ObjectModel, dict[Hashable, Any]] = weakref.WeakKeyDictionary()


def derived(model: ObjectModel, key: Hashable, compute: Callable[[], T]) -> T:
    """``compute()``, evaluated once per model and ``key``: a value derived from the model.

    The model is immutable, so feature extractors share what they derive from it (face
    angles, lateral edges, …) instead of computing it again for every proposition. The
    values live in a weak cache beside the model (not in it), and go when the model goes.
    The key must name everything the value depends on besides the model (e.g. a tolerance,
    or the settings in force), and begin with the caller's module name, so that two modules
    never share a key.

    Examples
    --------
    >>> from tactile_kb.record import ExplorationRecord
    >>> model = build_model(ExplorationRecord())
    >>> derived(model, (__name__, "answer"), lambda: 42)
    42
    >>> derived(model, (__name__, "answer"), lambda: 0)  # computed once per model
    42
    """
    values = _DERIVED.setdefault(model, {})
    try:
        return cast(T, values[key])
    except KeyError:
        value = values[key] = compute()
        return value
