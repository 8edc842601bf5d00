"""One plane per face, more exact than the sensors.

Every contact gives a plane (paper eq. 6), but many contacts hit one face, and with quantised
sensor directions and noisy positions they give near-identical planes that would make Qhull
build dozens of sliver faces. :func:`merge_planes` turns the contacts of a record into one
:class:`Face` per face of the object:

1. **Cluster the sensor normals** by average linkage on the cosine distance, cut at an angle
   derived from the finger's sensor spacing (``0.6 ×`` the median angle between neighbouring
   sensors, between 5° and 20°: 15.5° for the 33-sensor finger).
2. **Fit and split.** In each cluster the finger-tip *centres* lie on a plane parallel to the
   face at distance ρ, whatever sensor fired, so a least-squares plane through them gives the
   face normal more exactly than the sensors (when they span the face: three or more
   non-collinear centres; otherwise the sensor plane is kept). A cluster whose centres do not
   fit one plane within ``split_tol`` (two parallel faces at different offsets, as in
   objects made of boxes, or two faces that fired the same sensor) is split in two by
   k-planes iterations, recursively. The fit is robust: centres that lie well inside the
   plane the others share (the tip touched an edge or a vertex beside the face, so its
   centre is nearer than ρ to the face's plane) are found by soft-L1 reweighting and left
   out (:data:`INSIDE_SIGMAS`), unless that would leave out more than a quarter of them.
   The k-planes iterations start from gaps along the normal and from straight cuts across
   the face (:func:`_two_plane_starts`). A cluster that fits one plane within ``split_tol``
   still splits where two planes meeting at a convex fold fit it as exactly as the noise
   allows (two faces of an icosahedron, one per contour layer, that fired one sensor:
   :func:`_fold`), gives up a line of touches of an edge beside its face (:func:`_edge_line`)
   and the one or two touches that alone lift a line into a plane (:func:`_stray_touches`).
   Exact centres span a plane over a narrower spread than noisy ones (:func:`_exact_fitter`).
   With declared noise, a cluster whose touches closed a few distinct sensors is first split
   by its readings where one plane misses them by more than the noise allows and each
   reading's touches fit a plane of their own (:func:`_readings_apart`, :func:`_two_planes`):
   the clustering joins a sensor and the mean of it and its neighbour, 15° apart, and two
   faces of an icosahedron, 41.8° apart, can close exactly those; and the fold split also
   takes two planes where one misses the centres beyond the noise (:func:`_beyond_noise`).
3. **Merge coplanar faces** (a face whose contacts fired two neighbouring sensors; with
   declared noise, not two groups that :func:`_two_planes` tells apart).
4. **Add the table**: "the equation of the support plane is the same as the equation of the
   polyhedron's supported surface", so the plane z = 0 with outward normal (0, 0, −1) is a
   face. Contacts on the table top itself (normal +z at z ≈ 0) are ignored.

Examples
--------
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.synthetic import sample_record
>>> rec = sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), per_face=8, seed=2)
>>> faces = merge_planes(rec)
>>> len(faces), sum(f.refined for f in faces)
(6, 5)
>>> top = max(faces, key=lambda f: f.normal[2])
>>> round(top.offset, 3), top.n_contacts
(0.04, 8)
"""

from __future__ import annotations

import functools
import itertools
import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.optimize import nnls
from scipy.special import gammaincinv

from tactile_kb.errors import GeometryError, UsageError
from tactile_kb.geometry.memo import Memo
from tactile_kb.geometry.polyhedron import Polyhedron, face_width, polyhedron_from_planes
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray, Vec3

__all__ = [
    "ACUTE_COS",
    "APART_LEVEL",
    "CROSS_SIGMAS",
    "DEFAULT_CUT_DEG",
    "DEFAULT_MERGE_DEG",
    "DEFAULT_SPAN",
    "DEFAULT_SPLIT_TOL",
    "DETAIL_SIGMAS",
    "EDGE_MIN_WIDTH",
    "EDGE_ROUNDING",
    "EDGE_SIGMAS",
    "EDGE_SPOTS",
    "FOLD_RATIO",
    "INSIDE_SIGMAS",
    "LOPSIDED",
    "MAX_REJECTED",
    "NARROW_MIN",
    "NARROW_SCALES",
    "NARROW_SPAN_SCALES",
    "OUTSIDE_SIGMAS",
    "SMOOTH_RHO",
    "TABLE_TOL",
    "Face",
    "contact_arrays",
    "cut_angle",
    "edge_faces",
    "explained_faces",
    "fit_face",
    "merge_plane_arrays",
    "merge_planes",
    "nearest_points",
    "refit_past_roundings",
    "rounded_edge_slack",
    "rounding_zone",
    "segment_distances",
    "surface_detail",
]


DEFAULT_CUT_DEG = DEFAULTS.geometry.cut_deg
"""Cut of the normal clustering when the record names no sensor directions, degrees."""

DEFAULT_SPLIT_TOL = DEFAULTS.geometry.split_tol
"""Largest distance (m) of a tip centre from its face's fitted plane before the face is split
(and the largest for two faces to be merged as coplanar). 2.5 mm is five times the 0.5 mm
position noise; records that declare a larger ``noise`` use six times that."""

DEFAULT_SPAN = DEFAULTS.geometry.span
"""Centres span a face when their spread across the fitted line is at least this (m, RMS)."""

DEFAULT_MERGE_DEG = DEFAULTS.geometry.merge_deg
"""Two faces whose normals differ by less than this (degrees) may merge if coplanar."""

TABLE_TOL = DEFAULTS.geometry.table_tol
"""Contacts whose plane is the table top (normal within 10° of +z, |offset| below this) are
ignored."""

EDGE_ROUNDING = DEFAULTS.geometry.edge_rounding
"""Real edges are rounded with a radius up to this fraction of the narrower of the two faces
they join (:func:`edge_faces`): contacts there tilt the sensor direction and make a narrow
"face" that is not one."""

EDGE_MIN_WIDTH = DEFAULTS.geometry.edge_min_width
"""Edge faces are looked for only against faces at least this many tip radii wide: next to
narrower faces (a small pyramid's, a thin cylinder's facets) the tip's own size, not a
rounding, decides where it touches, and such narrow faces are faces of the object."""

EDGE_SIGMAS = DEFAULTS.geometry.edge_sigmas
"""An edge face's penetration is allowed ``EDGE_SIGMAS`` × σ/√m of noise on top."""

MAX_REFINE_DEG = DEFAULTS.geometry.max_refine_deg
"""A fitted normal further than this from the contacts' sensor normal is not trusted."""


INSIDE_SIGMAS = 4.0
"""A tip centre further inside a face's robustly fitted plane than this many times the fit's
scale touched an edge or a vertex beside the face, not the face (:func:`fit_face`)."""

MAX_REJECTED = 0.25
"""The robust fit of a face rejects at most this fraction of its centres."""

OUTSIDE_SIGMAS = 4.0
"""A tip centre further outside a face's robustly fitted plane than this many times the fit's
scale touched relief on it (a plane's centres lie on it, within the noise)."""


DETAIL_SIGMAS = 4.0
"""A touch of relief lies up to this many times the faces' median scatter (RMS of their tip
centres about their planes) further out than the relief height (:func:`explained_faces`)."""

_ROUGH_MIN = 6
"""Faces with at least this many contacts show the surface's detail in their centres' scatter
(:func:`_faces_from_contacts` lends it to faces of three or four contacts)."""


@dataclass(frozen=True)
class Face:
    """One face of the model: the plane ``normal · x = offset`` with ``normal`` outward.

    Attributes
    ----------
    normal
        Unit outward normal.
    offset
        ``normal · x = offset`` on the face.
    n_contacts
        Number of contacts on the face.
    residual
        RMS distance (m) of the tip centres from the fitted plane (0 when not refined from
        three or more centres).
    normal_uncertainty_deg
        Estimated (1σ) uncertainty of the normal: from the fit when refined, else the
        sensor's resolution (the finger's cone half-angle for quantised directions).
    contacts
        Indices into ``record.contacts``.
    refined
        True when the normal comes from the least-squares fit of the tip centres.
    source
        ``"contacts"`` or ``"table"`` (the support plane z = 0).
    offset_uncertainty
        Estimated (1σ) uncertainty of ``offset`` (m) at the centre of the face's contacts:
        the tip centres' scatter about the plane over √(number of places); 0 for the table.
    places
        How many distinct places its tip centres lie at (:func:`places`: centres within
        :data:`PLACE_RHO` ρ of each other, on one patch of the surface, count once); its
        uncertainties count that many independent centres. 0: not counted (the table, an
        assumed face).
    """

    normal: Vec3
    offset: float
    n_contacts: int
    residual: float
    normal_uncertainty_deg: float
    contacts: tuple[int, ...]
    refined: bool
    source: str = "contacts"
    offset_uncertainty: float = 0.0
    places: int = 0

    @property
    def normal_array(self) -> FloatArray:
        """The normal as a numpy array."""
        return np.asarray(self.normal, dtype=float)


def cut_angle(sensor_directions: Sequence[Sequence[float]] | FloatArray) -> float:
    """The clustering cut (degrees) for a finger: 0.6 × median neighbour spacing, in [5, 20]."""
    m = np.asarray(sensor_directions, dtype=float).reshape(-1, 3)
    if len(m) < 2:
        return current().geometry.cut_deg
    m = m / np.linalg.norm(m, axis=1)[:, None]
    c = m @ m.T
    np.fill_diagonal(c, -1.0)
    spacing = np.degrees(np.arccos(np.clip(c.max(axis=1), -1.0, 1.0)))
    return float(np.clip(0.6 * np.median(spacing), 5.0, 20.0))


@dataclass(frozen=True)
class _Fit:
    normal: FloatArray
    centre_offset: float  # normal · centre on the plane of the tip centres
    residuals: FloatArray
    refined: bool
    span: float  # RMS spread across the best line, metres

    @property
    def max_res(self) -> float:
        return float(np.abs(self.residuals).max()) if len(self.residuals) else 0.0


_FITS_SIZE = 8192
"""Fits kept by their exact inputs (:class:`~tactile_kb.geometry.memo.Memo`): the model is built
again after every completion probe, and most of its groups of contacts are those of the last
build."""

_FITS_ROWS = 256
"""The largest group of contacts whose fit is kept (its key holds the group's bytes: at most
12 KiB, so the memo stays under about 100 MiB)."""

_FITS: Memo[tuple[bytes, bytes, float, float, float, float, float, float], _Fit] = Memo(_FITS_SIZE)


def _fit(
    centres: FloatArray, sensor_normals: FloatArray, span_min: float, scale: float = 0.0
) -> _Fit:
    """The plane of the tip ``centres`` (k, 3) touched with sensor normals ``sensor_normals``
    (k, 3) (see :func:`fit_face`; robust, least scale ``scale``, when that is positive).

    The same inputs, under the same tolerances, give the same (read-only) fit, made once
    (groups of more than :data:`_FITS_ROWS` contacts are fitted afresh each time, which
    bounds the memo's memory)."""
    c = np.ascontiguousarray(centres, dtype=float)
    n = np.ascontiguousarray(sensor_normals, dtype=float)
    if len(c) > _FITS_ROWS:
        return _frozen_fit(_fit_anew(c, n, span_min, scale))
    key = (
        c.tobytes(),
        n.tobytes(),
        float(span_min),
        float(scale),
        current().geometry.max_refine_deg,
        INSIDE_SIGMAS,
        OUTSIDE_SIGMAS,
        MAX_REJECTED,
    )
    return _FITS.get(key, lambda: _frozen_fit(_fit_anew(c, n, span_min, scale)))


def _frozen_fit(f: _Fit) -> _Fit:
    """``f`` with its arrays read-only: a kept fit is shared by its callers."""
    f.normal.flags.writeable = False
    f.residuals.flags.writeable = False
    return f


def _fit_anew(
    centres: FloatArray, sensor_normals: FloatArray, span_min: float, scale: float = 0.0
) -> _Fit:
    """:func:`_fit`, computed."""
    mean_n = sensor_normals.mean(axis=0)
    mean_n /= math.sqrt(float(mean_n @ mean_n))
    mean_c = centres.mean(axis=0)
    m = len(centres)
    if m >= 3:
        _, s, vt = np.linalg.svd(centres - mean_c, full_matrices=False)
        span = float(s[1] / math.sqrt(m))
        normal = vt[2] if vt[2] @ mean_n >= 0 else -vt[2]
        if span >= span_min and normal @ mean_n >= math.cos(
            math.radians(current().geometry.max_refine_deg)
        ):
            res = (centres - mean_c) @ normal
            if scale > 0 and m >= 4 and float(np.abs(res).max()) > 2.0 * scale:
                robust = _robust_plane(centres, normal, mean_c, scale)
                if robust is not None:
                    normal, mean_c = robust
                    normal = normal if normal @ mean_n >= 0 else -normal
                    res = (centres - mean_c) @ normal
            return _Fit(normal, float(normal @ mean_c), res, True, span)
        line = vt[0]
    elif m == 2:
        line = centres[1] - centres[0]
        length = np.linalg.norm(line)
        line = line / length if length > span_min else np.zeros(3)
        span = 0.0
    else:
        line, span = np.zeros(3), 0.0
    # the sensors' normal, square to the centres' line; but a "line" that runs along the
    # sensors' normal further than a fitted normal is trusted to turn is no face's line: two
    # parallel faces at different offsets (an L-block's step, each touched along one line)
    # whose residuals along the sensors' normal let the group be split
    if m >= 2 and abs(float(mean_n @ line)) < math.sin(
        math.radians(current().geometry.max_refine_deg)
    ):
        normal = mean_n - line * (mean_n @ line)
    else:
        normal = mean_n
    normal = normal / np.linalg.norm(normal)
    res = (centres - mean_c) @ normal
    return _Fit(normal, float(normal @ mean_c), res, False, span)


def _robust_plane(
    centres: FloatArray, normal: FloatArray, point: FloatArray, scale: float, iterations: int = 20
) -> tuple[FloatArray, FloatArray] | None:
    """The plane of ``centres`` fitted robustly, from the least-squares ``normal`` through
    ``point``, so that a few centres off the others' plane no longer tilt it. The loss's
    scale is the residuals' own (1.4826 × their median absolute deviation: the scatter of a
    scanned surface's detail), at least ``scale`` (the declared noise, or a floor).

    Iteratively reweighted least squares with the soft-L1 loss of ``scale`` (weights
    ``1/√(1 + (r/scale)²)``) finds the plane most centres lie on; the centres the tip cannot
    have reached on that plane are rejected and the least-squares plane of the rest returned: those inside it by more than
    :data:`INSIDE_SIGMAS` × ``scale`` (the tip touched an edge or a vertex beside the face: its
    centre is then nearer than ρ to the face's plane) or outside by more than
    :data:`OUTSIDE_SIGMAS` × ``scale`` (relief). None when that would leave fewer than three
    or reject more than :data:`MAX_REJECTED` of them: the centres are then no plane with a few
    stray touches (a patch of a curved surface), and when none is rejected: the least-squares
    plane of all of them stands."""
    floor = scale
    for _ in range(iterations):
        r = (centres - point) @ normal
        scale = max(floor, _mad_sigma(r))
        w = 1.0 / np.sqrt(1.0 + (r / scale) ** 2)
        new_point = (w[:, None] * centres).sum(axis=0) / w.sum()
        _, _, vt = np.linalg.svd(np.sqrt(w)[:, None] * (centres - new_point), full_matrices=False)
        new_normal = vt[2] if vt[2] @ normal >= 0 else -vt[2]
        done = float(new_normal @ normal) > 1.0 - 1e-12
        normal, point = new_normal, new_point
        if done:
            break
    rejected = False
    for _ in range(3):
        r = (centres - point) @ normal
        scale = max(floor, _mad_sigma(r))
        keep = (r >= -INSIDE_SIGMAS * scale) & (r <= OUTSIDE_SIGMAS * scale)
        if keep.all():
            break
        rejected = True
        if keep.sum() < max(3, (1.0 - MAX_REJECTED) * len(centres)):
            return None  # not a plane with a few stray touches: a curved patch
        point = centres[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(centres[keep] - point, full_matrices=False)
        normal = vt[2] if vt[2] @ normal >= 0 else -vt[2]
    return (normal, point) if rejected else None


def _median(a: FloatArray) -> float:
    """``np.median`` of a 1-D array, by partition alone (the same value, without the
    generic function's overhead: the robust fits call it thousands of times)."""
    n = len(a)
    k = n // 2
    if n % 2:
        return float(np.partition(a, k)[k])
    p = np.partition(a, [k - 1, k])
    return float((p[k - 1] + p[k]) / 2)


def _mad_sigma(r: FloatArray) -> float:
    """σ of residuals estimated from their median absolute deviation (robust to outliers)."""
    return 1.4826 * _median(np.abs(r - _median(r)))


def fit_face(
    centres: FloatArray, sensor_normals: FloatArray, *, span_min: float | None = None
) -> tuple[FloatArray, float, FloatArray, bool]:
    """Fit the plane of the tip centres: ``(normal, normal·centre, residuals, refined)``.

    The normal is the least-squares one when the centres span a plane (RMS spread across
    their best line ≥ ``span_min``) and it lies within 35° of the sensors' mean normal;
    otherwise the mean sensor normal, made perpendicular to the centres' line if they are
    collinear.
    """
    if span_min is None:
        span_min = current().geometry.span
    f = _fit(np.asarray(centres, float), np.asarray(sensor_normals, float), span_min)
    return f.normal, f.centre_offset, f.residuals, f.refined


def _sse(f: _Fit) -> float:
    return float((f.residuals**2).sum())


FitFn = Callable[[NDArray[np.intp]], _Fit]


def _least_sse(c: FloatArray) -> float:
    """The least summed squared distance of the points ``c`` from any plane (0 for three or
    fewer): a lower bound of :func:`_sse` of any fit of them, cheap to screen partitions."""
    if len(c) <= 3:
        return 0.0
    s = np.linalg.svd(c - c.mean(axis=0), compute_uv=False)
    return float(s[2] ** 2)


def _fitter(centres: FloatArray, normals: FloatArray, span_min: float, scale: float = 0.0) -> FitFn:
    """``_fit`` of a group of contact indices, computed once per group (keyed by its indices);
    robust (:func:`_robust_plane`, least scale ``scale``) when ``scale`` is positive."""
    cache: dict[bytes, _Fit] = {}

    def fit(idx: NDArray[np.intp]) -> _Fit:
        key = idx.tobytes()
        found = cache.get(key)
        if found is None:
            found = cache[key] = _fit(centres[idx], normals[idx], span_min, scale)
        return found

    return fit


def _split(
    idx: NDArray[np.intp],
    centres: FloatArray,
    normals: FloatArray,
    span_min: float,
    tol: float,
    fit: FitFn,
    depth: int = 0,
    scale: float = 0.0,
    reach_deg: float = 90.0,
    noise: float = 0.0,
    readings: _Readings | None = None,
    straight: float = 0.0,
) -> list[NDArray[np.intp]]:
    """Recursively split ``idx`` until each part's centres fit one plane within ``tol``.

    The two parts are the best (least summed squared residuals) of k-planes iterations
    (:func:`_kplanes`) started from several partitions (:func:`_two_plane_starts`). A part
    that fits within ``tol`` still gives up the touches of an edge beside its face
    (:func:`_edge_line`, with ``scale`` the least scale of the fits; none when 0).

    A partition is taken only when each part's plane lies within ``reach_deg`` of every
    sensor normal of its touches (a sensor fires only for a surface within its reach): the
    centres of a face touched along one line fit a plane through that line at any tilt, and
    with a few touches of another face they fit one that no sensor could have felt.
    ``straight`` (exact touches of an ideal surface: :data:`SMOOTH_RHO` × ρ, else 0) is
    :func:`_stray_touches`' tolerance of a straight line."""
    f = fit(idx)
    if len(idx) < 2 or depth > 8:
        return [idx]

    def deeper(part: NDArray[np.intp]) -> list[NDArray[np.intp]]:
        return _split(
            part,
            centres,
            normals,
            span_min,
            tol,
            fit,
            depth + 1,
            scale,
            reach_deg,
            noise,
            readings,
            straight,
        )

    # touches that closed different sensors and lie on two planes, not one, within the
    # declared noise: two faces whose sensors the clustering joined (k-planes below may part
    # them otherwise, each side a mix of both)
    apart = _readings_apart(idx, centres, normals, fit, noise) if noise > 0 else None
    if apart is not None:
        return deeper(idx[apart]) + deeper(idx[~apart])
    if f.max_res <= tol:
        layers = _parallel_lines(idx, centres, normals, f, tol, readings)
        if layers is not None:
            return deeper(idx[layers]) + deeper(idx[~layers])
        # the two-plane partitions, once for both looks (only where one plane misses some
        # centres by more than the least scale allows)
        pairs = (
            [
                (start, _kplanes(idx, start, centres, normals, span_min))
                for start in _two_plane_starts(idx, centres, normals, f.normal)
            ]
            if scale > 0
            and len(idx) >= 5
            and (f.max_res > INSIDE_SIGMAS * scale or _beyond_noise(f, noise))
            else []
        )
        edge = _edge_line(idx, centres, normals, fit, scale, pairs) if scale > 0 else None
        if edge is None:
            fold = _fold(idx, normals, centres, fit, scale, reach_deg, pairs, noise)
            if fold is not None:
                return deeper(idx[fold]) + deeper(idx[~fold])
            if noise <= 0 < scale:
                # exact touches of faces that show no detail: the readings' partition, with the
                # fits' least scale as the noise (two faces 41.8° apart whose V hides within the
                # split tolerance); a scan's bumps and relief part a face on any partition
                apart = _readings_apart(idx, centres, normals, fit, scale)
                if apart is not None and _smooth_parts(fit, idx, apart, scale, straight > 0):
                    return deeper(idx[apart]) + deeper(idx[~apart])
            edge = _stray_touches(idx, centres, span_min, f, straight)
            return [idx] if edge is None else [idx[~edge], idx[edge]]
        rest = deeper(idx[~edge])
        return [idx[edge], *rest]
    best: tuple[float, NDArray[np.bool_]] | None = None
    cos_reach = math.cos(math.radians(reach_deg))
    for start in _two_plane_starts(idx, centres, normals, f.normal):
        mask = _kplanes(idx, start, centres, normals, span_min)
        if mask.all() or not mask.any():
            continue
        if _least_sse(centres[idx[mask]]) + _least_sse(centres[idx[~mask]]) >= 0.5 * _sse(f):
            continue  # no fit of the two parts can split it (below)
        a, b = fit(idx[mask]), fit(idx[~mask])
        if (
            float((normals[idx[mask]] @ a.normal).min()) < cos_reach
            or float((normals[idx[~mask]] @ b.normal).min()) < cos_reach
        ):
            continue
        score = _sse(a) + _sse(b)
        if best is None or score < best[0]:
            best = (score, mask)
    if best is None or best[0] >= 0.5 * _sse(f):
        return [idx]
    mask = best[1]
    return deeper(idx[mask]) + deeper(idx[~mask])


def _edge_line(
    idx: NDArray[np.intp],
    centres: FloatArray,
    normals: FloatArray,
    fit: FitFn,
    scale: float,
    pairs: Sequence[tuple[NDArray[np.bool_], NDArray[np.bool_]]],
) -> NDArray[np.bool_] | None:
    """The centres of ``idx`` that touched an edge beside their face rather than the face, as
    a mask, or None.

    A tip resting on an edge has its centre nearer than ρ to the plane of either face, and
    may fire the same sensor as the face's own touches: such touches along the edge (a
    contour layer's corner, repeated at each height) can be more than the robust fit leaves
    out (:data:`MAX_REJECTED`), and with the face's touches along one or two lines they
    tilt its plane by degrees while fitting it within a fraction of a millimetre. They are
    found among the two-plane partitions (:func:`_two_plane_starts`, :func:`_kplanes`),
    at no more than :data:`EDGE_SPOTS` places (ten least scales apart): the rest span a plane of their own, fitted within :data:`INSIDE_SIGMAS` × their scatter
    (at least ``scale``), and these span none (one spot, or a line: the edge) and lie
    inside that plane by more than :data:`INSIDE_SIGMAS` × that scatter, every one of them.
    Whether they are an edge's touches or a narrow face of their own is left to the model
    (:func:`edge_faces`)."""
    if len(idx) < 5:
        return None
    # the touches that fired another sensor than the rest, and the two-plane partitions
    # (``pairs``: each start and where k-planes took it), as cut too: k-planes lets a line's
    # plane (its sensors' normal) take in the face's touches beside it
    _, which = _unique_rows(np.round(normals[idx], 9))
    masks = [which == k for k in range(int(which.max()) + 1)] if which.max() < 4 else []
    for start, mask in pairs:
        masks += [mask, ~mask, start, ~start]
    # the fewest touches win, the first such mask on a tie: trying the masks in that order
    # (a stable sort by size), the first that passes is the one
    seen: set[bytes] = set()
    candidates: list[NDArray[np.bool_]] = []
    for edge in masks:
        if edge.all() or not edge.any() or (~edge).sum() < 3 or edge.tobytes() in seen:
            continue
        seen.add(edge.tobytes())
        candidates.append(edge)
    candidates.sort(key=lambda e: int(e.sum()))
    for edge in candidates:
        if _spots(centres[idx[edge]], 10.0 * scale, EDGE_SPOTS) > EDGE_SPOTS:
            continue  # a line of many touches is a face explored, not an edge met in passing
        if fit(idx[edge]).refined:
            continue
        face = fit(idx[~edge])
        if not face.refined:
            continue
        sigma = max(scale, _mad_sigma(face.residuals))
        if face.max_res > INSIDE_SIGMAS * sigma:
            continue
        depth = centres[idx[edge]] @ face.normal - face.centre_offset
        if float(depth.max()) >= -INSIDE_SIGMAS * sigma:
            continue
        return edge
    return None


FOLD_RATIO = 25.0
"""Two planes explain a face's centres in place of one (:func:`_fold`) when their summed
squared residuals are at most 1/this of the one plane's: 1/16 is what halving a curved
patch gives (each half's sagitta a quarter of the whole's), so a curved face stays one."""


def _fold(
    idx: NDArray[np.intp],
    normals: FloatArray,
    centres: FloatArray,
    fit: FitFn,
    scale: float,
    reach_deg: float,
    pairs: Sequence[tuple[NDArray[np.bool_], NDArray[np.bool_]]],
    noise: float = 0.0,
) -> NDArray[np.bool_] | None:
    """Two faces meeting at a fold in the centres ``idx`` that one plane fits within the split
    tolerance, as the mask of one of them, or None.

    Faces whose normals differ by less than about two sensor spacings can fire one sensor
    (an icosahedron's, 41.8° apart, both fire the sensor between them), and where they are
    touched near their common edge one plane passes within a millimetre or two of all their
    centres. They are two faces when two planes fit them as well as the fits' least
    ``scale`` allows (every centre within :data:`INSIDE_SIGMAS` × ``scale`` of its plane),
    each spanned by four or more centres, with summed squared residuals at most
    1/:data:`FOLD_RATIO` of the one plane's, each within ``reach_deg`` of its touches' sensor
    normals, and the fold convex: each face's centres inside the other's plane (a concave
    fold, the inside of an L-block, is left to the split tolerance). With declared ``noise``
    (σ) the fold hides within a few σ (a 1.9 mm worst residual against 4 σ = 2 mm, a ratio of
    9 against 25), so where the one plane misses the centres beyond the noise
    (:func:`_beyond_noise`), two planes that leave its summed squared residuals above the
    same chi-square quantile of their own scatter (at least σ², ``m − 6`` degrees of
    freedom), their normals more than ``reach_deg`` (one sensor spacing) apart, also do.
    ``pairs`` are the two-plane partitions (:func:`_two_plane_starts`, each with where
    :func:`_kplanes` took it)."""
    f = fit(idx)
    bent = _beyond_noise(f, noise)
    if scale <= 0 or len(idx) < 8 or (f.max_res <= INSIDE_SIGMAS * scale and not bent):
        return None
    n = len(idx)
    cos_reach = math.cos(math.radians(reach_deg))
    best: tuple[float, NDArray[np.bool_]] | None = None
    for _, mask in pairs:
        if mask.sum() < 4 or (~mask).sum() < 4:
            continue
        least = _least_sse(centres[idx[mask]]) + _least_sse(centres[idx[~mask]])
        if least * FOLD_RATIO > _sse(f) and not bent:
            continue  # no fit of the two parts explains the centres well enough (below)
        parts = (fit(idx[mask]), fit(idx[~mask]))
        if not all(p.refined and p.max_res <= INSIDE_SIGMAS * scale for p in parts):
            continue
        if any(
            float((normals[idx[m]] @ p.normal).min())
            < math.cos(math.radians(reach_deg + _noise_turn(p, noise)))
            for p, m in zip(parts, (mask, ~mask), strict=True)
        ):
            continue
        # a convex fold: each face's centres lie inside the other's plane (two parallel lines of
        # touches lie in one plane whatever faces they are on; a wrong pairing of them crosses)
        a_in_b = centres[idx[mask]] @ parts[1].normal - parts[1].centre_offset
        b_in_a = centres[idx[~mask]] @ parts[0].normal - parts[0].centre_offset
        if max(float(a_in_b.max()), float(b_in_a.max())) > INSIDE_SIGMAS * scale:
            continue
        score = _sse(parts[0]) + _sse(parts[1])
        # with declared noise: the one plane misses them beyond the noise, or the two
        # planes' own scatter when larger (a curved patch halved keeps its sagitta)
        # (and the fold sharper than the reach, one sensor spacing: the best of a dozen
        # partitions of one noisy face can beat the chi-square, a few degrees apart)
        own = max(noise * noise, score / max(n - 6, 1))
        ok = score * FOLD_RATIO <= _sse(f) or (
            bent
            and _sse(f) > own * _chi2_quantile(n - 3)
            and float(parts[0].normal @ parts[1].normal) <= cos_reach
        )
        if ok and (best is None or score < best[0]):
            best = (score, mask)
    return None if best is None else best[1]


def _turn_deg(f: _Fit, sigma: float, spots: int | None = None) -> float:
    """Degrees: the standard error of the normal of the fit ``f`` when its centres scatter by
    ``sigma`` about its plane (σ over its span times √m, m its centres or the ``spots`` they
    lie at)."""
    m = len(f.residuals) if spots is None else spots
    return math.degrees(math.atan2(sigma, f.span * math.sqrt(max(m, 1))))


def _scatter(f: _Fit, spots: int) -> float:
    """σ of the centres of the fit ``f`` about its plane, which lie at ``spots`` places
    (:func:`places`): their mean squared residual over the degrees of freedom of the places
    (three spent on a fitted plane, one on an offset), so that the touches of one patch
    count once."""
    m = len(f.residuals)
    if m == 0:
        return 0.0
    dof = spots - 3 if f.refined else spots - 1
    return math.sqrt(_sse(f) / m * spots / max(dof, 1))


def _noise_turn(f: _Fit, noise: float) -> float:
    """Degrees: how far the declared ``noise`` (σ) may turn the plane of the fit ``f``,
    :data:`CROSS_SIGMAS` standard errors (:func:`_turn_deg`); 0 without noise. A part of a
    face touched along a few millimetres turns by degrees under 0.5 mm."""
    if noise <= 0 or f.span <= 0:
        return 0.0
    return CROSS_SIGMAS * _turn_deg(f, noise)


APART_LEVEL = 0.99
"""Two groups of tip centres lie on two planes, not one (:func:`_two_planes`), when the one
plane through all of them misses them by more than this quantile of the chi-square spread the
declared noise (or the groups' own scatter about their planes, when larger) gives."""


def _smooth_parts(
    fit: FitFn, idx: NDArray[np.intp], mask: NDArray[np.bool_], scale: float, ideal: bool = False
) -> bool:
    """Whether the tip centres ``idx[mask]`` and ``idx[~mask]`` each lie on their own plane
    within :data:`NARROW_SCALES` × ``scale`` (their scatter, with three degrees of freedom
    taken by each plane, or two by a line's), one of them spanning a plane: exact touches of
    plane faces, not a surface whose bumps and relief the planes of any two parts fit better
    than one (a few touches along a line lie on their plane within that by chance). On an
    ``ideal`` surface (no scan detail), centres inside a plane by more than
    :data:`INSIDE_SIGMAS` × ``scale`` are left out of its scatter, as the robust fit leaves
    them out of the plane: the tip touched an edge beside the face, nearer than ρ to its
    plane (a slide that ends at the face's rim)."""
    a, b = fit(idx[mask]), fit(idx[~mask])
    inside = INSIDE_SIGMAS * scale if ideal else math.inf
    kept = [p.residuals[p.residuals >= -inside] for p in (a, b)]
    dof = sum(map(len, kept)) - (3 if a.refined else 2) - (3 if b.refined else 2)
    if dof < 1 or not (a.refined or b.refined):
        return False  # two lines of a few touches lie on their planes by chance
    return math.sqrt(sum(float(r @ r) for r in kept) / dof) <= NARROW_SCALES * scale


@functools.lru_cache(maxsize=256)
def _chi2_quantile(dof: int) -> float:
    """The :data:`APART_LEVEL` quantile of a chi-square of ``dof`` degrees of freedom
    (``scipy.special.gammaincinv``, as ``scipy.stats.chi2.ppf`` computes it, without importing
    ``scipy.stats``: 0.3 s at start-up)."""
    return 2.0 * float(gammaincinv(dof / 2.0, APART_LEVEL))


def _two_planes(
    fit: FitFn, centres: FloatArray, idx: NDArray[np.intp], mask: NDArray[np.bool_], noise: float
) -> bool:
    """Whether the tip centres ``idx[mask]`` and ``idx[~mask]`` lie on two planes rather than
    one, as the declared ``noise`` (σ, metres) tells.

    On one plane, the summed squared residuals of the plane through all of them are σ² times
    a chi-square of ``m − 3`` degrees of freedom; ``σ²`` is the declared noise's, or the two
    groups' own scatter about their planes (each fitted plane, or a line's plane through its
    sensors' normal, takes three or two degrees of freedom) when that is larger (a scanned
    surface's detail). Two faces 41.8° apart (an icosahedron's) each touched along one line
    fit one plane within the split tolerance and the merge's loose median (both a few σ), yet
    miss it by a V that sums to far more than the noise gives: they are two faces when the
    sum exceeds the :data:`APART_LEVEL` quantile."""
    m = len(idx)
    joint, a, b = fit(idx), fit(idx[mask]), fit(idx[~mask])
    own_dof = m - (3 if a.refined else 2) - (3 if b.refined else 2)
    if m < 6 or own_dof < 1 or noise <= 0:
        return False
    var = max(noise * noise, (_sse(a) + _sse(b)) / own_dof)
    if _sse(joint) <= var * _chi2_quantile(m - 3):
        return False
    return _crosses(centres, fit, idx, mask, noise)


_READINGS = 4
"""A group whose touches closed more than this many distinct sensors (or sensor pairs) is not
split by its readings (:func:`_readings_apart`): a curved patch's."""


def _crosses(
    centres: FloatArray, fit: FitFn, idx: NDArray[np.intp], mask: NDArray[np.bool_], noise: float
) -> bool:
    """Whether the groups ``idx[mask]`` and ``idx[~mask]`` can be two faces by their lie: a
    line of touches (a group whose centres span no plane) must cross the plane of the other
    group, when that spans one, or else the plane of both: its centres' heights above it
    change along it by more than :data:`CROSS_SIGMAS` standard errors of the slope (σ the
    declared ``noise``, or their own scatter about that slope when larger). Two spanning
    groups can always be two faces.

    A contour line on the next face of an icosahedron runs across the face's plane at 15° or
    so, and two such lines, one on each face, across the plane of both; a line of touches of
    the edge beside a face (closing a sensor between the two faces') runs along the face's
    plane, at the rounding's depth inside it, and two parallel lines (a lying cylinder's,
    along its axis) lie in one plane whatever faces they are on: those stay as they were,
    left to :func:`_edge_line`, :func:`edge_faces` and the curvature tests."""
    a, b = idx[mask], idx[~mask]
    fa, fb = fit(a), fit(b)
    if fa.refined and fb.refined:
        return True
    if fa.refined != fb.refined:
        lines, face = ([a], fb) if fb.refined else ([b], fa)
    else:
        lines, face = [a, b], fit(idx)
    for line in lines:
        c = centres[line] - centres[line].mean(axis=0)
        _, _, vt = np.linalg.svd(c, full_matrices=False)
        t = c @ vt[0]
        h = c @ face.normal
        stt = float(t @ t)
        if stt <= 0.0:
            continue  # one spot
        slope = float(t @ h) / stt
        rest = h - slope * t
        sigma = max(noise, math.sqrt(float(rest @ rest) / max(len(line) - 2, 1)))
        if abs(slope) > CROSS_SIGMAS * sigma / math.sqrt(stt):
            return True
    return False


CROSS_SIGMAS = 3.0
"""A line of touches crosses a plane (:func:`_crosses`) when its slope out of it exceeds this
many standard errors."""


def _readings_apart(
    idx: NDArray[np.intp], centres: FloatArray, normals: FloatArray, fit: FitFn, noise: float
) -> NDArray[np.bool_] | None:
    """The touches of ``idx`` that closed one sensor (or one pair) and lie on a plane of their
    own, apart from the rest's (:func:`_two_planes`), as a mask, or None.

    The normal clustering joins sensor readings less than its cut apart (15.5° for the
    33-sensor finger: a sensor and the mean of it and its neighbour), and two faces 41.8°
    apart can close exactly those (one 22.7° from its sensor, the other 5.7° from the
    pair's mean). Exact centres tell them apart by the split tolerance and :func:`_fold`;
    with noise, their planes' fold hides within a few σ, and only the noise-aware test of
    the readings' own partition finds it. Each side has three or more touches; of several
    readings, the one whose partition leaves the least summed squared residuals wins."""
    _, which = _unique_rows(np.round(normals[idx], 9))
    count = int(which.max()) + 1
    if count < 2 or count > _READINGS:
        return None
    best: tuple[float, NDArray[np.bool_]] | None = None
    for r in range(count if count > 2 else 1):
        mask = which == r
        if mask.sum() < 3 or (~mask).sum() < 3 or not _two_planes(fit, centres, idx, mask, noise):
            continue
        score = _sse(fit(idx[mask])) + _sse(fit(idx[~mask]))
        if best is None or score < best[0]:
            best = (score, mask)
    return None if best is None else best[1]


def _beyond_noise(f: _Fit, noise: float) -> bool:
    """Whether one plane misses the (eight or more) centres of the fit ``f`` by more than the
    declared ``noise`` (σ) allows: summed squared residuals above σ² times the
    :data:`APART_LEVEL` quantile of a chi-square of ``m − 3`` degrees of freedom."""
    m = len(f.residuals)
    if noise <= 0 or not f.refined or m < 8:
        return False
    return _sse(f) > noise * noise * _chi2_quantile(m - 3)


_STRAY = 2
"""At most this many touches off a line make a face of a line of touches and those (their
plane is unchecked: :func:`_stray_touches`)."""

_STRAY_CANDIDATES = 24
"""Pairs of strays (:func:`_stray_touches`) are sought among this many touches, those whose
removal alone leaves the rest nearest one line (each of the two strays is among them)."""


PARALLEL_SPREAD = 0.5
"""Two parallel faces touched along a line each (:func:`_parallel_lines`) lie apart along
their sensor's normal by a gap at least 1 / this times either line's own spread along it."""

SENSOR_MARGIN_DEG = 5.0
"""Degrees: a plane contradicts a touch's sensors when a sensor that stayed OFF points this
much nearer its normal than one that closed (:class:`_Readings`)."""


class _Readings:
    """Which of the finger's sensors were ON at each contact, read from the record only when
    asked (:meth:`contradicted`).

    A layout's sensors share one acceptance cone, so a sensor that points nearer a touched
    plane's normal than one that closed closes too. A plane with a sensor that stayed OFF
    well nearer its normal than one that closed, at every touch of a face, is not the
    face those touches felt."""

    def __init__(
        self, record: ExplorationRecord, chosen: Sequence[int], sensors: FloatArray
    ) -> None:
        self._record = record
        self._chosen = chosen
        self.sensors = sensors
        self._on: NDArray[np.bool_] | None = None
        self._orientations: FloatArray | None = None

    def _read(self) -> tuple[NDArray[np.bool_], FloatArray]:
        if self._on is None or self._orientations is None:
            contacts = [self._record.contacts[i] for i in self._chosen]
            m, k = len(contacts), len(self.sensors)
            fired = list(map(operator.attrgetter("sensors"), contacts))
            counts = np.fromiter(map(len, fired), dtype=np.intp, count=m)
            which = np.fromiter(itertools.chain.from_iterable(fired), dtype=np.intp)
            rows = np.repeat(np.arange(m), counts)
            valid = (which >= 0) & (which < k)
            on = np.zeros((m, k), dtype=bool)
            on[rows[valid], which[valid]] = True
            orientations = _column(contacts, "orientation", 2)
            # a reading is used only where the direction reported is that of a sensor ON
            # (the nearest to it): hand-made records may name sensors that do not match
            seen = _head_frame(_column(contacts, "direction"), orientations)
            nearest = np.argmax(seen @ self.sensors.T, axis=1)
            on[~on[np.arange(len(contacts)), nearest]] = False
            self._on, self._orientations = on, orientations
        return self._on, self._orientations

    def _angles(
        self, idx: NDArray[np.intp], normal: FloatArray
    ) -> tuple[NDArray[np.bool_], FloatArray] | None:
        """The sensors ON at each contact ``idx`` and each sensor's angle (degrees) to the
        plane of outward ``normal`` seen in the contact's finger frame, or None unless every
        contact closed the same sensors: a rough surface's touches, whose sensors the bumps
        turn one way and another, say nothing of the plane they lie on."""
        if len(self.sensors) < 2:
            return None
        on, orientations = self._read()
        on = on[idx]
        if not on[0].any() or not (on == on[0]).all():
            return None  # only one reading, the same at every touch, says which way
        seen = _head_frame(np.repeat(-normal[None, :], len(idx), axis=0), orientations[idx])
        return on, np.degrees(np.arccos(np.clip(seen @ self.sensors.T, -1.0, 1.0)))

    def contradicted(self, idx: NDArray[np.intp], normal: FloatArray) -> bool:
        """Whether the plane of outward ``normal`` contradicts the sensors of every contact
        ``idx`` (each finger frame turned with its head), all of which closed the same
        sensors: a sensor that stayed OFF lies :data:`SENSOR_MARGIN_DEG` nearer its normal
        than one that closed."""
        found = self._angles(idx, normal)
        if found is None:
            return False
        on, angle = found
        closed = np.where(on, angle, -np.inf).max(axis=1)
        nearer_off = np.where(on, np.inf, angle).min(axis=1)
        return bool((nearer_off + SENSOR_MARGIN_DEG < closed).all())

    def unfelt(self, idx: NDArray[np.intp], normal: FloatArray, reach_deg: float) -> bool:
        """Whether no sensor the contacts ``idx`` closed (the same at every one) could have
        felt the plane of outward ``normal``: even the nearest lies more than ``reach_deg``
        (about one sensor spacing) from it, as a corner's touch beside a face does. A touch
        beside an edge closes the sensors of both faces, and one of them faces its own."""
        found = self._angles(idx, normal)
        if found is None:
            return False
        on, angle = found
        return bool((np.where(on, angle, np.inf).min(axis=1) > reach_deg).all())


def _parallel_lines(
    idx: NDArray[np.intp],
    centres: FloatArray,
    normals: FloatArray,
    f: _Fit,
    tol: float,
    readings: _Readings | None,
) -> NDArray[np.bool_] | None:
    """Touches of two parallel faces fitted as one face between them: the part beyond the
    widest gap along the touches' mean sensor normal, or None.

    The centres of two lines (a T-block's stem side touched high and its crossbar's end
    low, both with the same sensor) fit one plane through both exactly, tilted by however
    far apart they lie. When that plane contradicts the sensors of every touch
    (:meth:`_Readings.contradicted`) and the touches lie at offsets along their sensors'
    normal with a gap wider than ``tol``, they are two faces, told apart by that gap."""
    if readings is None or not f.refined or len(idx) < 4:
        return None
    mean = normals[idx].sum(axis=0)
    length = float(np.linalg.norm(mean))
    if length < 1e-9:
        return None
    depth = centres[idx] @ (mean / length)
    order = np.sort(depth)
    gaps = np.diff(order)
    k = int(np.argmax(gaps))
    gap = float(gaps[k])
    # each part square to the sensor, as a face it felt is: its depths spread far less
    # than the gap (a bump that turned a few touches' sensors leaves them spread along it)
    spread = max(float(order[k] - order[0]), float(order[-1] - order[k + 1]))
    if gap <= tol or spread > PARALLEL_SPREAD * gap:
        return None
    # the sensors last: reading them is the dearest test, and most groups fail the gap's
    if not readings.contradicted(idx, f.normal):
        return None
    return np.asarray(depth > 0.5 * (order[k] + order[k + 1]), dtype=bool)


def _stray_touches(
    idx: NDArray[np.intp], centres: FloatArray, span_min: float, f: _Fit, straight: float = 0.0
) -> NDArray[np.bool_] | None:
    """The touches of ``idx`` that alone lift a line of touches into a plane, as a mask, or
    None.

    A face touched along one line (one contour pass) and, well off that line, at one or two
    more points (``f`` refined only thanks to them) has a plane that nothing checks: two
    points and a line fit a plane exactly, at whatever tilt their noise gives, and a touch
    of the next face that the two-plane split left here tilts it by degrees. Those
    :data:`_STRAY` or fewer touches are handed back as a group of their own: the line keeps
    its sensors' normal, and each joins the face whose plane it lies on
    (:func:`_merge_coplanar`), the same face again when that is the one.

    The strays are the touches furthest from the line of the rest, one at a time, until the
    rest lie within ``span_min`` of one line. With ``straight`` (exact touches: a contour
    line of an ideal face is straight within it), the set of one or two whose removal leaves
    the rest straight within ``straight``, each of them more than ``span_min`` off the rest's
    line, is sought first among all such sets: a spot far off the line (a corner touched
    21 mm above it) turns the line of all towards itself, and the touch furthest from that
    line is one of the line's own."""
    m = len(idx)
    if not f.refined or m < _STRAY + 3:
        return None
    c = centres[idx]
    if _second_spread(c, np.zeros((1, 0), dtype=np.intp))[0] < span_min**2 * m:
        return None  # a line already
    if straight > 0:
        candidates = np.arange(m)
        for k in range(1, _STRAY + 1):
            # sets of two among the touches whose removal alone leaves the rest nearest a line
            sets = np.asarray(list(itertools.combinations(candidates, k)), dtype=np.intp)
            spread = _second_spread(c, sets)
            if k == 1:
                candidates = np.sort(np.argsort(spread)[:_STRAY_CANDIDATES])
            straightest = np.flatnonzero(spread <= straight**2 * (m - k))
            for best in straightest[np.argsort(spread[straightest])]:
                stray = np.zeros(m, dtype=bool)
                stray[sets[best]] = True
                # each of them off the line of the rest by more than ``span_min``: what lifts
                # the line into a plane, not a touch beside it (a slide's end 0.4 mm off)
                if _off_line(c[~stray], c[stray]) > span_min:
                    return stray
    stray = np.zeros(m, dtype=bool)
    for _ in range(_STRAY):
        rest = c[~stray]
        mean = rest.mean(axis=0)
        _, sv, vt = np.linalg.svd(rest - mean, full_matrices=False)
        if sv[1] / math.sqrt(len(rest)) < span_min:
            break
        off = c - mean
        across = np.linalg.norm(off - np.outer(off @ vt[0], vt[0]), axis=1)
        across[stray] = -1.0
        stray[int(np.argmax(across))] = True
    else:
        rest = c[~stray]
        mean = rest.mean(axis=0)
        _, sv, vt = np.linalg.svd(rest - mean, full_matrices=False)
        if sv[1] / math.sqrt(len(rest)) >= span_min:
            return None
    if not stray.any():
        return None
    return stray


def _off_line(rest: FloatArray, points: FloatArray) -> float:
    """The least distance of ``points`` from the least-squares line of ``rest``."""
    mean = rest.mean(axis=0)
    axis = np.linalg.svd(rest - mean, full_matrices=False)[2][0]
    off = points - mean
    return float(np.linalg.norm(off - np.outer(off @ axis, axis), axis=1).min())


def _on_one_plane(centres: FloatArray, idx: NDArray[np.intp], tol: float) -> bool:
    """Whether the centres ``idx`` lie on one plane within ``tol`` (RMS, three degrees of
    freedom taken by the plane): an ideal face's touches along a line and at a spot, not a
    rough surface's, whose bumps and relief scatter a line's touches off any plane."""
    c = centres[idx] - centres[idx].mean(axis=0)
    return float(np.linalg.svd(c, compute_uv=False)[-1]) ** 2 <= tol * tol * max(len(idx) - 3, 1)


def _second_spread(c: FloatArray, removed: NDArray[np.intp]) -> FloatArray:
    """For each row of ``removed`` ((r, k) indices into ``c``, (m, 3)), the second-largest
    eigenvalue of the scatter of the other points about their mean: how far they stray from
    one line (the squared second singular value of their centred coordinates). One 3×3
    eigenproblem per row, from the sums downdated."""
    gone = c[removed]  # (r, k, 3)
    n = len(c) - removed.shape[1]
    sums = c.sum(axis=0)[None, :] - gone.sum(axis=1)
    outer = (c.T @ c)[None, :, :] - np.einsum("rki,rkj->rij", gone, gone)
    scatter = outer - sums[:, :, None] * sums[:, None, :] / n
    out: FloatArray = np.linalg.eigvalsh(scatter)[:, 1]
    return out


EDGE_SPOTS = 3
"""An edge beside a face is met in passing, at a contour layer's corner or by a short slide:
its touches lie at no more than this many distinct places (:func:`_edge_line`); a line of
more is a face of its own (a low-poly cylinder's next facet)."""


def _spots(c: FloatArray, radius: float, limit: int | None = None) -> int:
    """How many places the points ``c`` lie at: each point further than ``radius`` from
    every earlier place starts a new one. With ``limit``, counting stops at ``limit + 1``
    (enough to tell that there are more than ``limit``)."""
    if len(c) == 0:
        return 0
    far = np.ones(len(c), dtype=bool)  # further than ``radius`` from every place so far
    count, i = 0, 0
    while True:
        count += 1  # the point i starts a place
        if limit is not None and count > limit:
            return count
        far[i + 1 :] &= np.sqrt(((c[i + 1 :] - c[i]) ** 2).sum(axis=1)) > radius
        later = np.flatnonzero(far[i + 1 :])
        if len(later) == 0:
            return count
        i += 1 + int(later[0])


PLACE_RHO = 1.0
"""Tip radii: tip centres nearer each other than this touched one place of the surface
(:func:`places`). The tip rests on a patch about its own radius across: the touches of one
patch (a touch and the slide recorded where it starts, a slide's samples a few millimetres
apart) ride the same bumps and the same roughness."""


def places(centres: FloatArray, rho: float) -> int:
    """How many distinct places the tip ``centres`` lie at (each centre further than
    :data:`PLACE_RHO` ρ from every earlier place starts a new one): the independent
    observations of a face's plane. A face's uncertainties count these, not its contacts: on
    a scan the touches of one patch share its bumps, and a plane through a few patches is
    turned by their bumps however often each was touched."""
    return _spots(np.asarray(centres, dtype=float).reshape(-1, 3), PLACE_RHO * rho)


_CUT_DIRECTIONS = 8
"""In-plane directions along which :func:`_two_plane_starts` cuts a group's centres."""


def _two_plane_starts(
    idx: NDArray[np.intp], centres: FloatArray, normals: FloatArray, normal: FloatArray
) -> list[NDArray[np.bool_]]:
    """Partitions of the centres ``idx`` to start two-plane k-means from.

    The widest gap along the fitted ``normal`` and along the sensors' mean normal (two
    parallel faces at different offsets); and, for each of :data:`_CUT_DIRECTIONS`
    directions in the fitted plane, the straight cut across it that leaves the two sides
    with the least summed squared residuals about their own least-squares planes (two faces
    meeting at a fold: their centres lie on either side of the fold line, and a plane
    through both misses them by a V-shaped residual that no gap shows)."""
    c = centres[idx]
    m = len(c)
    sensor_mean = normals[idx].mean(axis=0)
    starts: list[NDArray[np.bool_]] = []
    for axis in (normal, sensor_mean / np.linalg.norm(sensor_mean)):
        h = c @ axis
        order = np.argsort(h)
        cut = int(np.argmax(np.diff(h[order])))
        mask = np.zeros(m, dtype=bool)
        mask[order[cut + 1 :]] = True
        starts.append(mask)
    if m < 6:
        return starts
    u = np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    x = c - c.mean(axis=0)
    sizes = np.arange(1, m + 1, dtype=float)
    for k in range(_CUT_DIRECTIONS):
        a = math.pi * k / _CUT_DIRECTIONS
        order = np.argsort(x @ (math.cos(a) * u + math.sin(a) * v), kind="stable")
        s = x[order]
        s1 = np.cumsum(s, axis=0)
        s2 = np.cumsum(s[:, :, None] * s[:, None, :], axis=0)
        # the first j + 1 centres against the other m - j - 1, each side at least three
        j = np.arange(2, m - 3)
        na, nb = sizes[j], m - sizes[j]
        sa, sb = s1[j], s1[-1] - s1[j]
        cov_a = s2[j] - sa[:, :, None] * sa[:, None, :] / na[:, None, None]
        cov_b = (s2[-1] - s2[j]) - sb[:, :, None] * sb[:, None, :] / nb[:, None, None]
        sse = np.linalg.eigvalsh(cov_a)[:, 0] + np.linalg.eigvalsh(cov_b)[:, 0]
        best = int(j[int(np.argmin(sse))])
        mask = np.zeros(m, dtype=bool)
        mask[order[: best + 1]] = True
        starts.append(mask)
    unique: dict[bytes, NDArray[np.bool_]] = {}
    for mask in starts:
        unique.setdefault((mask if mask[0] else ~mask).tobytes(), mask)
    return list(unique.values())


def _kplanes(
    idx: NDArray[np.intp],
    mask: NDArray[np.bool_],
    centres: FloatArray,
    normals: FloatArray,
    span_min: float,
    iterations: int = 10,
) -> NDArray[np.bool_]:
    """Two-plane k-means: reassign each centre to the nearer plane, refit, repeat."""
    c = centres[idx]
    for _ in range(iterations):
        if mask.all() or not mask.any():
            return mask
        a = _fit(c[mask], normals[idx[mask]], span_min)
        b = _fit(c[~mask], normals[idx[~mask]], span_min)
        da = np.abs(c @ a.normal - a.centre_offset)
        db = np.abs(c @ b.normal - b.centre_offset)
        new = da < db
        if (new == mask).all():
            break
        mask = new
    return mask


def _unique_rows(a: FloatArray) -> tuple[FloatArray, NDArray[np.intp]]:
    """``np.unique(a, axis=0, return_inverse=True)`` for (m, 3) floats, without its slow
    structured-dtype sort: rows in lexicographic order and each input row's index among them."""
    order = np.lexsort((a[:, 2], a[:, 1], a[:, 0]))
    s = a[order]
    first = np.ones(len(s), dtype=bool)
    first[1:] = (s[1:] != s[:-1]).any(axis=1)
    inverse = np.empty(len(a), dtype=np.intp)
    inverse[order] = np.cumsum(first) - 1
    return s[first], inverse


def _normal_clusters(normals: FloatArray, cut_deg: float) -> NDArray[np.intp]:
    """Cluster labels (0-based) of unit normals: average linkage on distinct directions."""
    if len(normals) == 1:
        return np.zeros(1, dtype=np.intp)
    uniq, inverse = _unique_rows(np.round(normals, 9))
    if len(uniq) == 1:
        return np.zeros(len(normals), dtype=np.intp)
    uniq = uniq / np.linalg.norm(uniq, axis=1)[:, None]
    z = linkage(uniq, method="average", metric="cosine")
    labels = fcluster(z, t=1.0 - math.cos(math.radians(cut_deg)), criterion="distance") - 1
    return np.asarray(labels[inverse], dtype=np.intp)


def _is_quantised(directions: FloatArray, sensors: FloatArray) -> bool:
    """Whether every direction is a sensor's, or the normalised mean of two to four
    neighbouring sensors' (the direction a contact that closed them together reports)."""
    if len(sensors) == 0:
        return False
    cos = directions @ sensors.T
    if bool((cos.max(axis=1) > 1.0 - 1e-9).all()):
        return True
    near = np.argsort(-cos, axis=1)[:, : min(4, len(sensors))]
    found = cos.max(axis=1) > 1.0 - 1e-9
    for size in range(2, near.shape[1] + 1):
        for subset in itertools.combinations(range(near.shape[1]), size):
            mean = sensors[near[:, list(subset)]].sum(axis=1)
            mean /= np.maximum(np.linalg.norm(mean, axis=1), 1e-12)[:, None]
            found |= np.einsum("ij,ij->i", mean, directions) > 1.0 - 1e-9
    return bool(found.all())


def _head_frame(
    directions: FloatArray, orientations: Sequence[Sequence[float]] | FloatArray
) -> FloatArray:
    """The world ``directions`` in the frame of the finger that reported each (its head at
    ``orientations``, tilt and turn in degrees, as :attr:`tactile_kb.record.Contact.orientation`
    holds them): a tilted probe's sensors are the layout's sensors turned with the head, and
    their quantisation is read in the layout's frame."""
    o = np.radians(np.asarray(orientations, dtype=float).reshape(-1, 2))
    if len(o) == 0 or not o.any():
        return directions
    ct, st, ca, sa = np.cos(o[:, 0]), np.sin(o[:, 0]), np.cos(o[:, 1]), np.sin(o[:, 1])
    x, y, z = directions[:, 0], directions[:, 1], directions[:, 2]
    # undo the turn about +z, then the tilt about the horizontal axis
    xt, yt = ca * x + sa * y, -sa * x + ca * y
    return np.column_stack([ct * xt - st * z, yt, st * xt + ct * z])


def contact_arrays(contacts: Sequence[Contact]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The contacts' tip centres, sensor directions r0 and points r1 as three (m, 3) arrays.

    Reading the attributes of hundreds of (pydantic) contacts is the slowest single step of
    modelling a record, so :func:`tactile_kb.geometry.model.build_model` does it once and hands the
    arrays to :func:`merge_plane_arrays`.
    """
    return _column(contacts, "centre"), _column(contacts, "direction"), _column(contacts, "point")


def _column(contacts: Sequence[Contact], name: str, width: int = 3) -> FloatArray:
    m = len(contacts)
    flat = itertools.chain.from_iterable(map(operator.attrgetter(name), contacts))
    return np.fromiter(flat, dtype=float, count=width * m).reshape(m, width)


def merge_planes(
    record: ExplorationRecord,
    *,
    cut_deg: float | None = None,
    split_tol: float | None = None,
    span_min: float | None = None,
    merge_deg: float | None = None,
    include_table: bool = True,
    contacts: Sequence[int] | None = None,
) -> tuple[Face, ...]:
    """One :class:`Face` per face of the object touched in ``record``.

    Parameters
    ----------
    record
        The exploration record (its finger's tip radius and sensor directions are used).
    cut_deg
        Cut of the average-linkage clustering of sensor normals (degrees); by default
        :func:`cut_angle` of the record's sensor directions.
    split_tol
        See :data:`DEFAULT_SPLIT_TOL`.
    span_min
        See :data:`DEFAULT_SPAN`.
    merge_deg
        See :data:`DEFAULT_MERGE_DEG`.
    include_table
        Add the support plane z = 0 as a face.
    contacts
        Use only these contact indices (default: all).

    Returns
    -------
    tuple of Face
        Faces from contacts (ordered by their first contact), then the table.
    """
    if span_min is None:
        span_min = current().geometry.span
    if merge_deg is None:
        merge_deg = current().geometry.merge_deg
    chosen: Sequence[int]
    if contacts is None:
        chosen = range(len(record.contacts))
        arrays = contact_arrays(record.contacts)
    else:
        chosen = list(contacts)
        arrays = contact_arrays([record.contacts[i] for i in chosen])
    return merge_plane_arrays(
        record,
        arrays,
        chosen,
        cut_deg=cut_deg,
        split_tol=split_tol,
        span_min=span_min,
        merge_deg=merge_deg,
        include_table=include_table,
    )


def merge_plane_arrays(
    record: ExplorationRecord,
    arrays: tuple[FloatArray, FloatArray, FloatArray],
    chosen: Sequence[int],
    *,
    cut_deg: float | None = None,
    split_tol: float | None = None,
    span_min: float | None = None,
    merge_deg: float | None = None,
    include_table: bool = True,
) -> tuple[Face, ...]:
    """:func:`merge_planes` of contacts already read into arrays by :func:`contact_arrays`.

    Parameters
    ----------
    record
        Gives the finger's tip radius, its sensor directions and the declared noise.
    arrays
        ``(centres, directions, points)``, each (m, 3), of the contacts ``chosen``.
    chosen
        The m indices into ``record.contacts`` of those contacts (the faces report them).
    cut_deg, split_tol, span_min, merge_deg, include_table
        As for :func:`merge_planes`.

    Returns
    -------
    tuple of Face
        Faces from contacts (ordered by their first contact), then the table.
    """
    if span_min is None:
        span_min = current().geometry.span
    if merge_deg is None:
        merge_deg = current().geometry.merge_deg
    if any(np.shape(a) != (len(chosen), 3) for a in arrays):
        shapes = ", ".join(str(np.shape(a)) for a in arrays)
        raise UsageError(f"arrays must be three ({len(chosen)}, 3) arrays, got {shapes}")
    for name, value in (("merge_deg", merge_deg), ("span_min", span_min)):
        if not value >= 0:
            raise UsageError(f"{name} must be ≥ 0, got {value}")
    sensors, spacing_cut, cone = _finger(tuple(record.sensor_directions))
    cut = spacing_cut if cut_deg is None else float(cut_deg)
    if not 0.0 < cut < 90.0:
        raise UsageError(f"cut_deg must lie in (0, 90), got {cut_deg}")
    noise = record.noise
    tol = split_tol if split_tol is not None else max(current().geometry.split_tol, 6.0 * noise)
    faces: list[Face] = []
    if len(chosen):
        quantised = _is_quantised(arrays[1], sensors) or _is_quantised(
            _head_frame(arrays[1], [record.contacts[i].orientation for i in chosen]), sensors
        )
        faces = _faces_from_contacts(
            record.tip_radius,
            arrays,
            chosen,
            cut,
            tol,
            span_min,
            merge_deg,
            cone if quantised else 0.0,
            noise,
            merge_cone=cone,
            readings=_Readings(record, chosen, sensors),
        )
    if include_table and not any(
        f.normal[2] < -math.cos(math.radians(merge_deg)) and abs(f.offset) <= tol for f in faces
    ):
        faces.append(Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table"))
    return tuple(faces)


def _faces_from_contacts(
    tip_radius: float,
    arrays: tuple[FloatArray, FloatArray, FloatArray],
    chosen: Sequence[int],
    cut: float,
    tol: float,
    span_min: float,
    merge_deg: float,
    cone: float,
    noise: float = 0.0,
    merge_cone: float = 0.0,
    readings: _Readings | None = None,
) -> list[Face]:
    centres, directions, points = arrays
    normals = -directions
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    rho = tip_radius
    if rho <= 0:
        rho = float(np.median(np.linalg.norm(points - centres, axis=1)))
    # contacts on the table top are not the object
    table = (normals[:, 2] > math.cos(math.radians(10.0))) & (
        np.abs(np.einsum("ij,ij->i", normals, points)) <= current().geometry.table_tol
    )
    keep = np.flatnonzero(~table)
    if len(keep) == 0:
        return []
    # the least scale of the robust face fits: the declared noise, or a flat face's detail
    scale = max(noise, current().geometry.robust_rho * rho)
    fit = _exact_fitter(
        _fitter(centres, normals, span_min, scale),
        _fitter(centres, normals, min(span_min, NARROW_SPAN_SCALES * scale), scale),
        scale,
    )
    # a sensor fires for a surface within about one sensor spacing (twice the worst
    # quantisation) of its direction
    reach = 2.0 * merge_cone if merge_cone > 0 else current().geometry.max_refine_deg
    labels = _normal_clusters(normals[keep], cut)

    def faces(straight: float) -> list[NDArray[np.intp]]:
        groups: list[NDArray[np.intp]] = []
        for lab in np.unique(labels):
            groups += _split(
                keep[labels == lab],
                centres,
                normals,
                span_min,
                tol,
                fit,
                0,
                scale,
                reach,
                noise,
                readings,
                straight,
            )
        return _merge_coplanar(
            groups,
            fit,
            tol,
            merge_deg,
            merge_cone,
            centres,
            scale,
            noise,
            readings,
            normals,
            straight,
        )

    groups = faces(0.0)
    # exact touches of an ideal surface (its faces' centres scatter by no more than
    # SMOOTH_RHO × ρ about their planes) lie on their faces' planes and lines to its
    # numerics: split again with that tolerance of a straight line; a scan is exactly flat
    # between its bumps, and its lines are not straight within it
    if noise <= 0 and _ideal(groups, fit, SMOOTH_RHO * rho):
        groups = faces(SMOOTH_RHO * rho)
    groups.sort(key=lambda g: int(g.min()))
    index = (
        np.arange(chosen.start, chosen.stop, chosen.step)
        if isinstance(chosen, range)
        else np.asarray(chosen)
    )
    # the surface's own detail: the median scatter of the faces that show it
    rough = [math.sqrt(_sse(f) / (len(f.residuals) - 3)) for f in _detailed(groups, fit)]
    detail = float(np.median(rough)) if rough else 0.0
    out = []
    for g in groups:
        f = fit(g)
        m = len(g)
        k = places(centres[g], rho)
        # the centres' scatter about the plane, never less than the declared noise: a few
        # centres can fit a plane better than their noise by chance
        sigma = max(_scatter(f, k), noise)
        if k <= 4:  # three or four places fit a plane (nearly) exactly: trust the detail
            sigma = max(sigma, detail)  # the other faces show
        if f.refined:
            unc = _turn_deg(f, sigma, k)
        else:
            spread = float(np.degrees(np.arccos(np.clip(normals[g] @ f.normal, -1, 1))).max())
            unc = max(spread, cone)
        rms = math.sqrt(float((f.residuals**2).mean())) if f.refined else 0.0
        n = f.normal
        out.append(
            Face(
                normal=(float(n[0]), float(n[1]), float(n[2])),
                offset=f.centre_offset - rho,
                n_contacts=m,
                residual=rms,
                normal_uncertainty_deg=unc,
                contacts=tuple(index[np.sort(g)].tolist()),
                refined=f.refined,
                offset_uncertainty=sigma / math.sqrt(k),
                places=k,
            )
        )
    return out


NARROW_SPAN_SCALES = 10.0
"""Centres that lie on a plane within :data:`NARROW_SCALES` × the fits' least scale (no
noise, no surface detail) span it when their spread across their line is this many least
scales, below the ``span`` setting (:func:`_exact_fitter`)."""

NARROW_SCALES = 2.0
"""See :data:`NARROW_SPAN_SCALES`."""

NARROW_MIN = 6
"""Least number of centres a narrow span is trusted with (:func:`_exact_fitter`)."""


def _detailed(groups: list[NDArray[np.intp]], fit: FitFn) -> list[_Fit]:
    """The fits of the faces touched often enough to show the surface's own detail (a scan's
    bumps and ripples) in their centres' scatter about their planes (:data:`_ROUGH_MIN`)."""
    return [f for g in groups if len(g) >= _ROUGH_MIN and (f := fit(g)).refined]


def _ideal(groups: list[NDArray[np.intp]], fit: FitFn, straight: float) -> bool:
    """Whether the faces that show the surface's detail (:func:`_detailed`) show none: their
    centres' robust scatter about their planes (1.4826 × the median absolute deviation,
    which the touches of an edge beside a face, nearer than ρ to its plane, do not move) is
    at most ``straight`` at the median. A scan's bumps and ripples scatter them by tenths of
    a millimetre; exact touches of an ideal solid lie on its planes to its numerics."""
    scatter = [_mad_sigma(f.residuals) for f in _detailed(groups, fit)]
    return bool(scatter) and float(np.median(scatter)) <= straight


def _exact_fitter(fit: FitFn, narrow: FitFn, scale: float) -> FitFn:
    """``fit``, or where it does not refine a group, ``narrow`` (the same fit with a smaller
    least span) when that refines it and the centres lie on their plane within
    :data:`NARROW_SCALES` × ``scale`` (their scatter about it, with three degrees of freedom
    taken by the plane), and there are at least :data:`NARROW_MIN` of them.

    A face met by two passes a few millimetres apart (an undercut touched with the head
    indexed, a small face near an apex) spans a plane of its own: exact touches fix its
    normal to a fraction of a degree over a millimetre or two, where the sensors leave it
    to half a sensor spacing. The ``span`` setting guards against noise and surface detail;
    where the centres show neither, it need not."""

    def best(idx: NDArray[np.intp]) -> _Fit:
        f = fit(idx)
        if f.refined:
            return f
        if len(idx) < NARROW_MIN:
            return f  # three to five centres fit a plane whatever surface they lie on
        g = narrow(idx)
        if g.refined and math.sqrt(_sse(g) / (len(idx) - 3)) <= NARROW_SCALES * scale:
            return g
        return f

    return best


@functools.lru_cache(maxsize=8)
def _finger(directions: tuple[Vec3, ...]) -> tuple[FloatArray, float, float]:
    """A finger layout's sensor directions as a read-only (k, 3) array, its clustering cut
    (:func:`cut_angle`) and its worst quantisation (half the median neighbour spacing),
    degrees: computed once per layout."""
    sensors = np.asarray(directions, dtype=float).reshape(-1, 3)
    sensors.setflags(write=False)
    cut = cut_angle(sensors)
    cone = cut / 0.6 / 2.0 if len(sensors) >= 2 else current().geometry.cut_deg
    return sensors, cut, cone


LOPSIDED = 4.0
"""Two faces that both span a plane, one touched at least this many times as often as the
other, merge within the loose angle of :func:`_merge_coplanar` when every centre of the
smaller lies on the larger one's plane within its scatter."""


def _merge_coplanar(
    groups: list[NDArray[np.intp]],
    fit: FitFn,
    tol: float,
    merge_deg: float,
    cone: float = 0.0,
    centres: FloatArray | None = None,
    scale: float = 0.0,
    noise: float = 0.0,
    readings: _Readings | None = None,
    sensor_normals: FloatArray | None = None,
    straight: float = 0.0,
) -> list[NDArray[np.intp]]:
    """Merge groups whose fitted planes coincide (normals within ``merge_deg``, one plane fits).

    A group whose centres do not span a plane (touched at one spot or along one line) has the
    sensors' normal, quantised to within ``cone`` degrees (a scanned face's bump makes a
    neighbouring sensor fire, or two together, which give their mean): it merges with another
    group when the normals differ by less than ``geometry.unrefined_merge_cones`` × ``cone``,
    the centres of both span one plane, that plane is the spanning group's (within
    ``merge_deg``; with two groups that span none, within the same loose angle of both), and
    the other group's centres lie on it within ``geometry.unrefined_merge_sigmas`` × the
    spanning group's scatter (at least ``scale``, the robust fits' least scale), by their
    median: they are on one face, and their sensors' tilt is the quantisation or the
    surface's detail, not another face. Two groups that both span a plane, one with at least
    :data:`LOPSIDED` times the other's centres, merge within the same loose angle when the
    plane of both is the larger one's (within ``merge_deg``) and *every* centre of the smaller
    lies on the larger one's plane within ``geometry.unrefined_merge_sigmas`` × its scatter
    (at least ``scale``): a few touches over a short spread fit a plane turned by the noise
    or a rounding's dips, but they lie on the face. With declared ``noise`` (σ, metres) the
    plane of both must also fit them as one plane does within that noise
    (:func:`_two_planes`): a line of touches of the next face of an icosahedron, 41.8° away,
    lies within that median of the plane through both, but misses it by a V far beyond the
    noise. Nor do two groups merge that :func:`_parallel_lines` would part again (with the
    sensors' ``readings`` and ``sensor_normals``): two parallel faces touched along a line each."""
    cos_min = math.cos(math.radians(merge_deg))
    loose = max(merge_deg, current().geometry.unrefined_merge_cones * cone)
    if centres is None:
        loose = merge_deg
    cos_loose = math.cos(math.radians(loose))
    changed = True
    while changed and len(groups) > 1:
        changed = False
        fits = [fit(g) for g in groups]
        normals = np.asarray([f.normal for f in fits])
        refined = np.asarray([f.refined for f in fits])
        cos = normals @ normals.T
        # candidate pairs (i < j, row by row) from one matrix product, each confirmed below
        unspanned = ~(refined[:, None] & refined[None, :])
        sizes = np.asarray([len(g) for g in groups])
        # a face touched a few times beside one touched far more often: its few centres can
        # fit a plane turned by several degrees (noise, a rounding's dips at its lines' ends)
        lopsided = np.maximum(sizes[:, None], sizes[None, :]) >= LOPSIDED * np.minimum(
            sizes[:, None], sizes[None, :]
        )
        near = np.triu(
            (cos >= cos_min - 1e-9)
            | ((unspanned | (lopsided & (centres is not None))) & (cos >= cos_loose - 1e-9)),
            1,
        )
        pairs = list(zip(*np.nonzero(near), strict=True))
        # a line joins a face that spans a plane before two lines join each other
        pairs.sort(key=lambda ij: 2 - int(refined[ij[0]]) - int(refined[ij[1]]))
        for i, j in pairs:
            both = np.concatenate([groups[i], groups[j]])
            joint = fit(both)
            if joint.max_res > tol:
                continue
            if (
                sensor_normals is not None
                and centres is not None
                and _parallel_lines(both, centres, sensor_normals, joint, tol, readings) is not None
            ):
                continue
            if fits[i].normal @ fits[j].normal < cos_min:
                if not joint.refined or centres is None:
                    continue
                spanning = [fits[k] for k in (i, j) if fits[k].refined]
                line = groups[j] if fits[i].refined else groups[i]
                if len(spanning) == 2:  # the plane is the far larger group's
                    big, small = (i, j) if len(groups[i]) >= len(groups[j]) else (j, i)
                    if joint.normal @ fits[big].normal < cos_min:
                        continue
                    # the larger face's scatter, its centres' standard deviation: a scan's
                    # roughness strays in heavier tails than the robust σ of their median
                    own = fits[big].residuals
                    sd = math.sqrt(_sse(fits[big]) / max(len(own) - 3, 1))
                    scatter = max(scale, _mad_sigma(own), sd)
                    off = np.abs(
                        centres[groups[small]] @ fits[big].normal - fits[big].centre_offset
                    )
                    if float(off.max()) > current().geometry.unrefined_merge_sigmas * scatter:
                        continue
                elif spanning:  # the plane is the spanning group's
                    if joint.normal @ spanning[0].normal < cos_min:
                        continue
                    if _beyond(
                        centres,
                        line,
                        groups[i] if fits[i].refined else groups[j],
                        fits[j if fits[i].refined else i].normal,
                        spanning[0].normal,
                        tol,
                    ):
                        continue
                    scatter = max(scale, _mad_sigma(spanning[0].residuals))
                else:  # two lines (or spots) that together span a plane near both normals
                    if min(joint.normal @ fits[i].normal, joint.normal @ fits[j].normal) < (
                        cos_loose
                    ):
                        continue
                    # and felt it, as exact touches of an ideal surface tell (``straight``):
                    # a line and a spot fit a plane exactly wherever the spot lies (a corner
                    # touched above a contour line)
                    if (
                        straight > 0
                        and cone > 0
                        and readings is not None
                        and _on_one_plane(centres, both, straight)
                        and any(
                            readings.unfelt(groups[k], joint.normal, 2.0 * cone) for k in (i, j)
                        )
                    ):
                        continue
                    scatter, line = scale, both
                # and the two groups on one plane as the declared noise allows (a line of
                # touches on the next face, 41.8° away, lies within a few σ of it too)
                first = np.arange(len(both)) < len(groups[i])
                if _two_planes(fit, centres, both, first, noise):
                    continue
                if len(spanning) < 2:
                    # the other group's centres on that plane, as close as a face's own lie to
                    # it (their median: a bump under one of them is the surface's detail)
                    off = np.abs(centres[line] @ joint.normal - joint.centre_offset)
                    if float(np.median(off)) > current().geometry.unrefined_merge_sigmas * scatter:
                        continue
            groups = [g for k, g in enumerate(groups) if k not in (i, j)] + [both]
            changed = True
            break
    return groups


def _beyond(
    centres: FloatArray,
    line: NDArray[np.intp],
    face: NDArray[np.intp],
    line_normal: FloatArray,
    face_normal: FloatArray,
    tol: float,
) -> bool:
    """True when the tip centres ``line``, whose normal tilts away from the face's, lie past
    the face's touched extent in the direction of that tilt: where a fold would start (a
    lying octagonal prism's slanted side, met by the layer above the vertical side's), not a
    bump on the face (met between the face's own touches, or at their edge)."""
    tilt = line_normal - float(line_normal @ face_normal) * face_normal
    size = float(np.linalg.norm(tilt))
    if size < 1e-9:
        return False
    u = tilt / size
    return bool(np.median(centres[line] @ u) > float(np.max(centres[face] @ u)) + tol)


def nearest_points(
    x: FloatArray, normals: FloatArray, offsets: FloatArray, *, iterations: int = 60
) -> FloatArray:
    """The nearest point of the convex set ``normals · q ≤ offsets`` to each row of ``x``.

    A point outside one half-space only is projected onto its plane; the others by Dykstra's
    alternating projections over the half-spaces they are outside of or near, for at most
    ``iterations`` sweeps. A sweep that leaves every point and every correction as it was,
    bit for bit, has reached the projections' fixed point: every later sweep would repeat it,
    so none is made, and the result is the one all the sweeps give. Many calls settle within
    a dozen sweeps; some (points near two planes at a small angle) creep on to the last.
    """
    x = np.asarray(x, dtype=float).reshape(-1, 3)
    n = np.asarray(normals, dtype=float).reshape(-1, 3)
    d = np.asarray(offsets, dtype=float).reshape(-1)
    if len(n) == 0 or len(x) == 0:
        return x.copy()
    over = x @ n.T - d
    worst = over.argmax(axis=1)
    q: FloatArray = x - np.maximum(over[np.arange(len(x)), worst], 0.0)[:, None] * n[worst]
    hard = np.flatnonzero((q @ n.T - d).max(axis=1) > 1e-12)
    if len(hard) == 0:
        return q
    y = x[hard].copy()
    corr = np.zeros((len(n), *y.shape))
    live = np.zeros(len(n), dtype=bool)  # corr[i] is not all zero
    for _ in range(iterations):
        fixed = True
        i = 0
        while i < len(n):
            # A step on a plane with no correction to undo, that every point lies inside of,
            # adds and removes nothing: skip to the next plane that can act (the margin covers
            # the rounding of this batched product against the step's own).
            idle = ~live[i:] & ((y @ n[i:].T - d[i:]) < -_IDLE_MARGIN).all(axis=0)
            busy = np.flatnonzero(~idle)
            if len(busy) == 0:
                break
            i += int(busy[0])
            z = y + corr[i]
            step = z - np.maximum(z @ n[i] - d[i], 0.0)[:, None] * n[i][None, :]
            undo = z - step
            fixed = fixed and np.array_equal(step, y) and np.array_equal(undo, corr[i])
            y, corr[i] = step, undo
            live[i] = bool(corr[i].any())
            i += 1
        if fixed:  # the sweep left every point and every correction as it was
            break
    q[hard] = y
    return q


_IDLE_MARGIN = 1e-12
"""Metres: :func:`nearest_points` skips a plane that every point lies further inside of."""


def edge_faces(
    faces: Sequence[Face],
    centres: FloatArray,
    rho: float,
    *,
    noise: float = 0.0,
    rounding: float | None = None,
    max_faces: int = 40,
    sensed: FloatArray | None = None,
) -> list[int]:
    """Indices of the contact faces that are touches of the other faces' edges, not faces.

    A tip touching an edge (sharp, or rounded as real edges are) sees a direction between
    the two faces' and its contacts form a narrow face of their own. Such a face adds nothing
    to the envelope of the others: its tip centres lie (about) ρ outside the polyhedron the
    other faces bound, while a face of the object lies where the others' polyhedron would
    overshoot it. A face is an edge face when the largest *penetration* of its tip centres into
    the others' polyhedron grown by ρ is at most ``rounding`` × the width of the widest face it
    lies against (the largest rounding of such an edge penetrates by about its radius) plus
    :data:`EDGE_SIGMAS` × ``noise``/√m, and that face is at least
    :data:`EDGE_MIN_WIDTH` tip radii wide. A centre lies against a face within ρ/2 of its
    grown plane, or against two faces as deep below both their grown planes as a tip on
    their edge rounded by ``rounding`` × the narrower one's width sinks
    (:func:`_sunk_by_rounding`). Only faces whose centres span no plane of their own
    (one contact, or contacts along a line) and no more touched than the faces they lie
    against (an edge is touched in passing, a face is explored) are candidates; they are
    removed one at a time, those with fewest contacts first, while the others still close; at most ``max_faces`` faces are examined (a curved
    object's many narrow faces are left to the curvature tests).

    Parameters
    ----------
    faces
        The faces from :func:`merge_planes` (the table included).
    centres
        (n, 3) tip centres of all contacts of the record (faces index them).
    rho
        The tip radius.
    noise
        σ of the contact positions (m).
    rounding
        See :data:`EDGE_ROUNDING`.
    sensed
        (n, 3) per contact, the outward normal its sensors read at the touch (NaN where none
        was read afresh: a slide repeats its touch's). With it, a face of three or more
        contacts whose touches read normals away from every edge they lie by stays
        (:func:`_facing_off_edges`).
    """
    if rounding is None:
        rounding = current().geometry.edge_rounding
    kept = list(range(len(faces)))
    removed: list[int] = []
    if len(faces) > max_faces:
        return removed
    normals = np.asarray([f.normal for f in faces], dtype=float).reshape(-1, 3)
    offsets = np.asarray([f.offset for f in faces], dtype=float)
    pts = centres[[i for f in faces for i in f.contacts]] if len(centres) else centres
    bound = (pts.mean(axis=0), 3.0 * float(np.ptp(pts, axis=0).max()) + rho)
    # A point inside the polyhedron of all kept faces lies inside that of any of them: the
    # polyhedra below start from it instead of solving a linear programme each (the first
    # from the touched points' centre, when it lies deep enough inside).
    inner: FloatArray = bound[0]
    while True:
        best: int | None = None
        try:
            full = polyhedron_from_planes(normals[kept], offsets[kept], bound=bound, interior=inner)
        except GeometryError:
            return sorted(removed)
        inner = full.vertices.mean(axis=0)
        # each face's width: in the polyhedron of the faces that span planes of their own
        # (and the table) when they close, where narrow edge faces do not cut them short;
        # else in the model as it stands
        widths = {kept[int(j)]: face_width(full, fi) for fi, j in enumerate(full.plane_index)}
        adjacent: dict[int, set[int]] = {}
        for a, b in full.edge_faces:
            fa, fb = kept[int(full.plane_index[a])], kept[int(full.plane_index[b])]
            adjacent.setdefault(fa, set()).add(fb)
            adjacent.setdefault(fb, set()).add(fa)
        core = [k for k in kept if faces[k].refined or faces[k].source != "contacts"]
        if len(core) < len(kept):
            try:
                solid = polyhedron_from_planes(
                    normals[core], offsets[core], bound=bound, interior=inner
                )
                widths.update(
                    {core[int(j)]: face_width(solid, fi) for fi, j in enumerate(solid.plane_index)}
                )
            except GeometryError:
                pass
        # the likeliest edge faces first: not spanning a plane of their own, few contacts
        for k in sorted(kept, key=lambda k: (faces[k].refined, faces[k].n_contacts)):
            f = faces[k]
            if f.source != "contacts" or not f.contacts or f.refined:
                continue  # a face whose centres span a plane of its own is a face
            if max((widths.get(j, 0.0) for j in adjacent.get(k, ())), default=1.0) < (
                current().geometry.edge_min_width * rho
            ):
                continue  # only narrow faces around (a curved object): cheap early answer
            others = [j for j in kept if j != k]
            try:
                poly = polyhedron_from_planes(
                    normals[others], offsets[others], bound=bound, interior=inner
                )
            except GeometryError:
                continue  # without it the others do not close: a face
            c = centres[list(f.contacts)]
            grown = poly.offsets + rho
            q = nearest_points(c, poly.normals, grown)
            outside = c @ poly.normals.T - grown
            # inside the grown polyhedron: the distance to its nearest plane; outside: minus
            # the distance to it
            penetration = np.where(
                outside.max(axis=1) < 0,
                -outside.max(axis=1),
                -np.linalg.norm(c - q, axis=1),
            )
            # nearer: the tip's own reach past an edge sharper than 60° (ACUTE_COS); the
            # faces it lies against: those near it, and at a sharp edge those of the edge
            acute, at_edge = _acute_penetration(c, poly, rho)
            penetration = np.minimum(penetration, acute)
            depth = np.abs(q @ poly.normals.T - grown)
            near = (depth <= 0.5 * rho + 1e-9) | at_edge
            near |= _sunk_by_rounding(depth, poly, rho, rounding, widths, others)
            against = [others[int(poly.plane_index[fi])] for fi in np.flatnonzero(near.any(0))]
            # the widest of them: next to it may lie another edge face, not yet removed
            width = max((widths.get(j, 0.0) for j in against), default=0.0)
            if width < current().geometry.edge_min_width * rho:
                continue  # against narrow faces (a small or curved object) a face stays
            if any(faces[j].n_contacts < f.n_contacts for j in against if faces[j].contacts):
                continue  # touched more than a face it lies against: explored as a face
            allowed = rounding * width + current().geometry.edge_sigmas * noise / math.sqrt(len(c))
            if (
                sensed is not None
                and len(c) >= 3
                and _facing_off_edges(
                    sensed[list(f.contacts)],
                    c,
                    poly,
                    rounding * width + 3.0 * noise,
                    rho,
                    EDGE_FACING * f.normal_uncertainty_deg,
                )
            ):
                continue  # a row whose touches read normals away from every edge: a face
            if float(penetration.max()) <= allowed:
                best = k
                break
        if best is None:
            return sorted(removed)
        kept.remove(best)
        removed.append(best)


def _sunk_by_rounding(
    depth: FloatArray,
    poly: Polyhedron,
    rho: float,
    rounding: float,
    widths: dict[int, float],
    others: list[int],
) -> NDArray[np.bool_]:
    """(centres, planes of ``poly``): the planes each tip centre lies against as a tip on a
    rounded edge of two of them, sunk ``depth`` below their planes moved out by ρ.

    A tip resting on an edge rounded with radius r, between faces whose normals are θ apart,
    has its centre (ρ + r)(1 − cos α) below the grown plane of a face whose normal is α from
    the tip's direction, the two α summing to θ: (ρ + r)(1 − cos θ/2) below both where it
    rests half way round (3.8 mm at a box's edge for ρ = 5 mm and r = 8 mm). ρ/2 is allowed
    on top, as for a single plane, which also takes in a tip somewhat off the middle. r is at
    most ``rounding`` × the narrower face's width (a rounding is no wider than its faces).
    Only edges whose faces meet at 60° or more count (``ACUTE_COS``: a spike's faces, wide
    far from its tip, would explain a small face cutting it off)."""
    out = np.zeros(depth.shape, dtype=bool)
    if len(depth) == 0 or rounding <= 0:
        return out
    w = np.asarray([widths.get(others[int(j)], 0.0) for j in poly.plane_index], dtype=float)
    cos = np.clip(poly.normals @ poly.normals.T, -1.0, 1.0)
    half = np.sqrt((1.0 + cos) / 2.0)  # cos(θ/2)
    allowed = 0.5 * rho + (rho + rounding * np.minimum(w[:, None], w[None, :])) * (1.0 - half)
    np.fill_diagonal(allowed, -1.0)
    allowed[cos < ACUTE_COS] = -1.0
    for i in np.flatnonzero((depth > 0.5 * rho).any(axis=1)):
        pair = (depth[i][:, None] <= allowed) & (depth[i][None, :] <= allowed)
        out[i] = pair.any(axis=1)
    return out


EDGE_FACING = 2.0
"""A touch of an edge (sharp or rounded) senses a normal between the normals of the edge's
faces: :func:`edge_faces` keeps a face whose touches read normals further than this many
times its normal's uncertainty outside that range (:func:`_facing_off_edges`)."""


def _facing_off_edges(
    normals: FloatArray, c: FloatArray, poly: Polyhedron, reach: float, rho: float, limit: float
) -> bool:
    """Whether the normals sensed at tip centres ``c`` (rows; NaN where none was sensed) face
    away from every edge those centres could have touched on ``poly`` (the other faces'
    polyhedron).

    A tip centre of an edge's touch lies outside ``poly``, and its nearest point there lies
    on the edge, or, where the edge is rounded (with a radius up to ``reach``), on a face
    within ``reach`` of it: the planes that pass within ``reach`` of that point are the
    edge's, and the sensed normal lies between their normals (in the cone they span),
    within the sensors' resolution. A face met where ``poly`` has no edge (a small end face
    cut off a pyramid's apex, touched beside its rim) is sensed facing elsewhere. True when
    the median of the sensed normals outside ``poly`` lies more than ``limit`` degrees from
    its cone; False when no sensed centre lies outside ``poly``."""
    tol = 0.05 * rho  # Dykstra's nearest points lie on their planes only so nearly
    use = ~np.isnan(normals).any(axis=1) & ((c @ poly.normals.T - poly.offsets).max(axis=1) > tol)
    if not use.any():
        return False
    q = nearest_points(c[use], poly.normals, poly.offsets)
    near = np.abs(q @ poly.normals.T - poly.offsets) <= reach + tol
    angles = []
    for n, row in zip(normals[use], near, strict=True):
        cone = poly.normals[row].T  # the normals' cone: nonnegative sums of them
        m = cone @ nnls(cone, n)[0] if row.any() else np.zeros(3)
        norm = float(np.linalg.norm(m))
        cos = float(n @ m) / norm if norm > 1e-12 else -1.0
        angles.append(math.degrees(math.acos(min(1.0, max(-1.0, cos)))))
    return float(np.median(angles)) > limit


ACUTE_COS = -0.5
"""Two planes whose normals' cosine is below this meet at a sharp edge (less than 60°), where
:func:`edge_faces` measures a touch's penetration from the edge itself
(:func:`_acute_penetration`): at a right angle the planes moved out by ρ overshoot the tip's
reach by 0.41 ρ only, and a box's corners, whose normals are about 90° apart, keep the
planes' measure."""


def _acute_penetration(
    c: FloatArray, poly: Polyhedron, rho: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """How far each tip centre ``c`` outside ``poly`` lies nearer than ρ to it, where its
    nearest point is on an edge or a vertex at which two planes meet at less than 60°
    (their normals' cosine below :data:`ACUTE_COS`); ``inf`` elsewhere. With it, which of
    ``poly``'s planes pass within ρ/2 of that nearest point (none for the others).

    The planes moved out by ρ (:func:`edge_faces`' penetration) meet beyond such an edge,
    by ρ (1/sin(α/2) − 1) for an angle α (2.2 ρ at a tetrahedron's 37°), far beyond any
    tip that touches it, whose centre lies ρ from the edge itself. Only the centres outside
    ``poly`` are projected onto it (the others are no edge's)."""
    out = np.full(len(c), np.inf)
    at_edge = np.zeros((len(c), len(poly.normals)), dtype=bool)
    tol = 0.05 * rho  # Dykstra's nearest points lie on their planes only so nearly
    outside = np.flatnonzero((c @ poly.normals.T - poly.offsets).max(axis=1) > tol)
    if len(outside) == 0:
        return out, at_edge
    q = nearest_points(c[outside], poly.normals, poly.offsets)
    gaps = q @ poly.normals.T - poly.offsets
    for i, qi, gap in zip(outside, q, gaps, strict=True):
        on = np.flatnonzero(np.abs(gap) <= tol)
        if len(on) >= 2 and float((poly.normals[on] @ poly.normals[on].T).min()) < ACUTE_COS:
            out[i] = rho - float(np.linalg.norm(c[i] - qi))
            at_edge[i] = np.abs(gap) <= 0.5 * rho + 1e-9
    return out, at_edge


def _signed_distance(x: FloatArray, normals: FloatArray, offsets: FloatArray) -> FloatArray:
    """Signed distance of each row of ``x`` to the convex set ``normals · q ≤ offsets``:
    positive outside (to its nearest point), negative inside (to its nearest plane)."""
    over = x @ normals.T - offsets
    inside = over.max(axis=1) <= 0
    q = nearest_points(x, normals, offsets)
    return np.asarray(np.where(inside, over.max(axis=1), np.linalg.norm(x - q, axis=1)))


def _rounded_edge_planes(
    over: FloatArray, normals: FloatArray, radii: FloatArray, rho: float
) -> NDArray[np.intp]:
    """The planes of the edge (or corner) whose rounding a tip centre may lie on: the plane
    it lies furthest out of (``over``: its heights above each plane), with every plane ``B``
    it lies against as a tip on the edge rounded with radius ``r`` does. Such a centre lies
    at ``ρ + r`` from the rounding's axis, ``r`` inside both planes: above ``B`` by at least
    ``(ρ + r)·cos β − r`` (β the angle between the two normals; r the smaller of the two
    planes' ``radii``). Empty when the centre is above no plane by more than −ρ."""
    a = int(np.argmax(over))
    if over[a] < -rho:
        return np.zeros(0, dtype=np.intp)
    cos_b = normals @ normals[a]
    r = np.minimum(radii, radii[a])
    against = over >= np.minimum(-rho, (rho + r) * cos_b - r)
    against[a] = True
    return np.flatnonzero(against)


SMOOTH_RHO = 0.01
"""Tip radii: a surface whose faces scatter by no more than this beyond the declared noise
(the median RMS of the faces touched six or more times) shows no scan detail, and
:func:`explained_faces` explains none of its faces away but a spot or a line the object
reaches beyond: an ideal solid's narrow faces and edge touches are left to
:func:`edge_faces`. Exact touches whose faces scatter robustly by no more than this
(:func:`_ideal`) are an ideal surface's, split with the tests that hold only for them."""


def surface_detail(faces: Sequence[Face], noise: float = 0.0) -> float:
    """The surface's own detail as its faces show it (m): the median RMS scatter of the tip
    centres of the faces touched six or more times about their planes, beyond the declared
    ``noise`` (in quadrature). An ideal solid's exact touches show none; a scan's faces
    scatter by tenths of a millimetre (its bumps, relief and roughness); beyond
    :data:`SMOOTH_RHO` ρ the surface is a scan's."""
    scatter = [f.residual for f in faces if f.refined and f.n_contacts >= 6]
    rough = float(np.median(scatter)) if scatter else 0.0
    return math.sqrt(max(rough * rough - noise * noise, 0.0))


def explained_faces(
    faces: Sequence[Face],
    supporting: Sequence[bool],
    centres: FloatArray,
    rho: float,
    *,
    noise: float = 0.0,
    rounding: float | None = None,
    relief: float | None = None,
    max_faces: int = 40,
) -> list[int]:
    """Indices of the contact faces whose touches the other faces already explain.

    A real surface makes faces that are not faces of the object: touches of a rounded edge
    (their normals between two faces', their tip centres near both planes' line), a bump or
    a letter under a few contacts that fired a tilted sensor, one face fitted in two halves.
    Their tip centres lie where the tip touching the polyhedron ``P`` of the *other* faces
    would be: at distance ρ from ``P``, less a rounded edge's inset, plus relief and noise.
    A face of the object lies elsewhere: without it ``P`` overshoots it (a corner that is
    not there), and its centres lie inside the ρ-offset of ``P`` by the depth of that corner.

    For each centre the *misfit* ``e = dist(c, P) − ρ`` is measured (positive outside). The
    face is explained when every one of its centres has

    * ``e ≤ relief + detail + 3σ`` (bumps and relief lift a centre by at most their height,
      a scan's roughness by a few times the scatter the faces show), and
    * ``e ≥ −(inset + detail + 3σ)``: a tip on an edge rounded with radius ``r``, against
      faces of ``P`` whose normals' mean is at most ψ from each (at most 75°), lies up to
      ``inset = r·(1/cos ψ − 1)`` inside the sharp edge's ρ-offset (``r(√2 − 1)`` at a
      box's edge), ``r`` being ``rounding`` × the width of the narrowest of those faces;
      against one face the inset is 0. The faces a centre lies against are those of the
      edge whose rounding it may be on (:func:`_rounded_edge_planes`: within ρ of their
      planes, or as far inside them as a rounding of radius ``r`` puts a tip). A face the
      touched object reaches beyond (not supporting: no face of a convex object) may be
      inset by ``rounding`` × that width, at most ρ; one whose centres span a plane of
      their own (a concave face fitted as a plane) only as a part of a face fitted apart:
      with no inset but a rounded edge's (a plane through a contour round a rounded edge
      and one spot of the next face), and never more than ρ/2 inside ``P``'s ρ-offset (a
      U-block's hollow lies inside by its depth, and stays).

    σ is the declared noise; ``detail`` is :data:`DETAIL_SIGMAS` × the median RMS scatter of
    the tip centres of the faces of six or more contacts about their planes, less the
    declared noise (in quadrature). On a surface that shows no detail beyond the noise
    (:data:`SMOOTH_RHO`), only faces touched at one spot or along one line that the touched
    object reaches beyond are examined, with no relief and no detail (their normal is their
    sensors', quantised). Faces are
    examined fewest contacts first and removed one at a time while the others still close;
    the table is never removed, and faces are only looked for against faces at least
    ``geometry.edge_min_width`` tip radii wide (next to narrow faces only, as on a curved
    object, every face stays), or against one face alone, every centre ρ or more inside its
    edges (:func:`_within_face`: a bump on a small top; a facet lies by its neighbours').

    Parameters
    ----------
    faces
        The faces (the table included).
    supporting
        Per face, whether it supports the object (:func:`tactile_kb.geometry.model.build_model`):
        only supporting faces make ``P``.
    centres
        (n, 3) tip centres of the record's contacts (faces index them).
    rho
        The tip radius.
    noise
        σ of the contact positions (m).
    rounding
        ``geometry.edge_rounding`` by default.
    relief
        Height of surface detail (m); by default ``geometry.relief_rho`` × ρ.
    max_faces
        More faces than this are not examined (a curved object's many narrow faces).
    """
    geo = current().geometry
    if rounding is None:
        rounding = geo.edge_rounding
    if relief is None:
        relief = geo.relief_rho * rho
    removed: list[int] = []
    if len(faces) > max_faces or len(faces) < 5:
        return removed
    normals = np.asarray([f.normal for f in faces], dtype=float).reshape(-1, 3)
    offsets = np.asarray([f.offset for f in faces], dtype=float)
    pts = centres[[i for f in faces for i in f.contacts]] if len(centres) else centres
    if len(pts) < 4:
        return removed
    # the others must close where the model's polyhedron must (three times the touched
    # points' radius about their centre, as :func:`tactile_kb.geometry.model.build_model`)
    centre = pts.mean(axis=0)
    bound = (centre, 3.0 * float(np.linalg.norm(pts - centre, axis=1).max()))
    kept = list(range(len(faces)))
    cos_cap = math.cos(math.radians(75.0))
    # the surface's detail as the faces measure it (a scan's noise lifts a tip by a few
    # times that), beyond the declared noise, which the slack below covers
    excess = surface_detail(faces, noise)
    # a surface with no detail beyond the noise: no relief and no detail; only a face touched
    # at one spot or along one line that the touched object reaches beyond (no face of a
    # convex object: its sensors' normal, quantised, turned it) is looked at, against the
    # noise and a rounding's inset alone
    smooth = excess <= SMOOTH_RHO * rho
    relief = 0.0 if smooth else relief
    detail = 0.0 if smooth else DETAIL_SIGMAS * excess
    while True:
        best: int | None = None
        order = sorted(
            (
                k
                for k in kept
                if faces[k].source == "contacts"
                and faces[k].contacts
                and not (smooth and (supporting[k] or faces[k].refined))
            ),
            key=lambda k: (faces[k].n_contacts, k),
        )
        for k in order:
            # a concave face explored as a plane (a U-block's hollow) lies inside the others'
            # polyhedron by the hollow's depth: a face; one that lies on it within the
            # surface's detail is a part of a face fitted apart (a top in two halves, one
            # tilted a little out of the other's plane)
            part = not supporting[k] and faces[k].refined
            others = [j for j in kept if j != k and supporting[j]]
            if len(others) < 4:
                continue
            try:
                poly = polyhedron_from_planes(
                    normals[others], offsets[others], bound=bound, interior=centre
                )
            except GeometryError:
                continue  # the others do not close without it: a face
            c = centres[list(faces[k].contacts)]
            misfit = _signed_distance(c, poly.normals, poly.offsets) - rho
            over = c @ poly.normals.T - poly.offsets
            near = over >= -rho  # the planes each centre lies against (within ρ of the offset)
            widths = np.asarray([face_width(poly, f) for f in range(len(poly.faces))])
            if not near.any():
                continue
            against = np.flatnonzero(near.any(axis=0))
            if float(widths[against].max()) < geo.edge_min_width * rho and not (
                len(against) == 1 and _within_face(c, poly, int(against[0]), rho)
            ):
                # only narrow faces around: a curved object's facets stay; but not a spot
                # against one face alone, ρ or more inside its edges (a bump on a small top)
                continue
            inset = np.zeros(len(c))
            edge_inset = np.zeros(len(c))  # a rounded edge's, as for a face of the object
            for i in range(len(c)):
                at = _rounded_edge_planes(over[i], poly.normals, rounding * widths, rho)
                if not len(at):
                    continue
                width = float(widths[at].min())
                if len(at) >= 2:  # none against one face: a flat face's touch
                    mean = poly.normals[at].sum(axis=0)
                    mean /= max(float(np.linalg.norm(mean)), 1e-12)
                    cos_psi = max(float((poly.normals[at] @ mean).min()), cos_cap)
                    edge_inset[i] = rounding * width * (1.0 / cos_psi - 1.0)
                # a plane the touched object reaches beyond is no face of a convex object: a
                # rounding as deep as any edge's of these faces explains it, up to the tip's
                # own radius; a face of the object, a rounded edge's inset
                inset[i] = edge_inset[i] if supporting[k] else min(rounding * width, rho)
            slack = 3.0 * noise
            reach = rounding * float(widths[against].max()) + detail + slack
            fitted = np.tile(faces[k].normal_array, (len(c), 1))
            limit = max(EDGE_FACING * faces[k].normal_uncertainty_deg, EXPLAINED_FACING_DEG)
            if faces[k].refined and _facing_off_edges(fitted, c, poly, reach, rho, limit):
                continue  # its plane faces away from every edge it lies by: a face
            if part:
                # only a rounded edge's inset (a plane through a few touches of the rounding
                # and one spot of a face: tilted out of the others), and never a tip centre
                # half its radius inside
                inset = np.minimum(edge_inset + detail + slack, 0.5 * rho) - detail - slack
            if float(misfit.max()) <= relief + detail + slack and bool(
                (misfit >= -(inset + detail + slack)).all()
            ):
                best = k
                break
        if best is None:
            return sorted(removed)
        kept.remove(best)
        removed.append(best)


def _within_face(c: FloatArray, poly: Polyhedron, face: int, margin: float) -> bool:
    """Whether the points ``c``, projected on ``poly``'s face ``face``, all lie inside its
    polygon by at least ``margin`` from every edge."""
    loop = poly.vertices[list(poly.faces[face])]
    if len(loop) < 3:
        return False
    n = poly.normals[face]
    inward = np.cross(n, np.roll(loop, -1, axis=0) - loop)  # left of each edge, seen from outside
    inward /= np.maximum(np.linalg.norm(inward, axis=1), 1e-12)[:, None]
    depth = np.einsum("ijk,jk->ij", c[:, None, :] - loop[None, :, :], inward)
    return bool(depth.min() >= margin)


EXPLAINED_FACING_DEG = 20.0
"""Degrees: :func:`explained_faces` keeps a face whose fitted normal lies further than this
(and :data:`EDGE_FACING` × its uncertainty) outside the normals of the edges and faces its
tip centres lie by (:func:`_facing_off_edges`): a rounding's or a bump's plane faces between
them, a face cut off the others' corner faces elsewhere."""


def refit_past_roundings(
    faces: Sequence[Face],
    supporting: Sequence[bool],
    arrays: tuple[FloatArray, FloatArray, FloatArray],
    rho: float,
    *,
    noise: float = 0.0,
    rounding: float | None = None,
    min_contacts: int = 5,
) -> tuple[Face, ...]:
    """The faces, each refitted without the tip centres that touched a rounded edge beside it
    when those centres tilt its plane.

    A contour line that runs up to a rounded edge ends with touches on the rounding: the tip
    rolls over it and its centre dips inside the face's plane by up to about ``ρ + r`` times
    ``1 − cos`` of the turn, a millimetre or more, while the sensor that fires is still the
    face's. Such dips at the ends of a face's short lines fit a plane turned by several
    degrees about as well as the face itself does (an octahedron's side touched along two
    lines of 16 and 4 mm whose last touches lie 1 mm inside: 4.4° off), and the robust fit
    (:func:`_robust_plane`) keeps them when they are more than a quarter of the centres.

    The centres that may lie on a rounding are found on the polyhedron ``P`` of the
    supporting faces (:func:`rounding_zone`, with ``rounding``); :func:`_past_rounding` sets
    aside those of them that dip inside the plane the face's other centres share, and the
    face is refitted without them when that plane is the face's and the dips turned the
    plane of all its centres beyond what the noise does. On a sharp edge the centres near it
    lie on the plane, nothing dips, and nothing changes. The refitted face keeps all its
    contacts (they were touched there); its residual and uncertainties are the kept centres'
    (σ at least the declared noise).

    Parameters
    ----------
    faces, supporting, rho, noise, rounding
        As for :func:`explained_faces`.
    arrays
        ``(centres, directions, points)`` of the record's contacts (:func:`contact_arrays`).
    min_contacts
        Faces with fewer contacts are left as they are.
    """
    geo = current().geometry
    if rounding is None:
        rounding = geo.edge_rounding
    centres, directions, _ = arrays
    which = [k for k, s in enumerate(supporting) if s]
    if len(which) < 4 or rounding <= 0:
        return tuple(faces)
    normals = np.asarray([faces[k].normal for k in which], dtype=float).reshape(-1, 3)
    offsets = np.asarray([faces[k].offset for k in which], dtype=float)
    pts = centres[[i for f in faces for i in f.contacts]] if len(centres) else centres
    if len(pts) < 4:
        return tuple(faces)
    middle = pts.mean(axis=0)
    bound = (middle, 3.0 * float(np.linalg.norm(pts - middle, axis=1).max()))
    try:
        poly = polyhedron_from_planes(normals, offsets, bound=bound, interior=middle)
    except GeometryError:
        return tuple(faces)
    plane_of = {which[int(j)]: p for p, j in enumerate(poly.plane_index)}
    scale = max(noise, geo.robust_rho * rho)
    sensors = -directions / np.linalg.norm(directions, axis=1)[:, None]
    out = list(faces)
    for k in which:
        f = faces[k]
        m = len(f.contacts)
        if f.source != "contacts" or not f.refined or m < min_contacts or k not in plane_of:
            continue
        idx = np.asarray(f.contacts, dtype=np.intp)
        zone = rounding_zone(centres[idx], poly, plane_of[k], rho, rounding)
        if not zone.any():
            continue
        found = _past_rounding(centres[idx], sensors[idx], zone, max(3, (m + 1) // 2), scale)
        if found is not None:
            fit, kept = found
            out[k] = _refitted(f, fit, rho, noise, places(centres[idx[kept]], rho))
    return tuple(out)


def rounding_zone(
    centres: FloatArray, poly: Polyhedron, face: int, rho: float, rounding: float
) -> NDArray[np.bool_]:
    """Which tip ``centres`` touching face ``face`` of ``poly`` may lie on the rounding of one
    of its edges: those whose *edge radius* is at most ``rounding`` × the narrower face's
    width. The edge radius is the least radius ``r`` of a rounding of the edge with another
    face ``B`` (normals β apart, at most 120°) that puts a tip there, ``(ρ·cos β − h_B) /
    (1 − cos β)`` for the centre's height ``h_B`` above ``B``'s plane: a tip on a rounding
    lies at ``ρ + r`` from its axis, ``r`` inside both planes (:func:`_rounded_edge_planes`
    turned round)."""
    cos_b = poly.normals @ poly.normals[face]
    others = np.flatnonzero((cos_b < 1.0 - 1e-9) & (cos_b > -0.5))
    if len(others) == 0 or len(centres) == 0:
        return np.zeros(len(centres), dtype=bool)
    widths = np.asarray([face_width(poly, f) for f in others.tolist()])
    over = centres @ poly.normals[others].T - poly.offsets[others]
    need = (rho * cos_b[others] - over) / (1.0 - cos_b[others])
    cap = rounding * np.minimum(widths, face_width(poly, face))
    return np.asarray((need <= cap).any(axis=1))


def rounded_edge_slack(poly: Polyhedron, rounding: float) -> tuple[FloatArray, FloatArray]:
    """How a rounded edge moves the touch away from each edge of ``poly``: ``(inside,
    beside)``, (E,) metres each, for an edge rounded with the largest radius allowed, ``r``
    = ``rounding`` × the narrower of its two faces' widths, its faces' normals θ apart.

    * ``inside = r (1/cos(θ/2) − 1)``: how much nearer than ρ to the model's sharp edge a
      tip centre passes that goes round the rounding (its arc, ρ + r from the rounding's
      axis, against the edge's r / cos(θ/2)): 0.41 r at a right angle.
    * ``beside = r tan(θ/2)``: how far from the sharp edge a touch on the rounding may lie
      (where the rounding meets its faces): r at a right angle.

    Both are 0 at an edge whose faces meet at less than 60° (``ACUTE_COS``, as in
    :func:`edge_faces`: a spike's wide faces would explain a small face cutting it off)."""
    n_edges = len(poly.edges)
    if n_edges == 0 or rounding <= 0:
        return np.zeros(n_edges), np.zeros(n_edges)
    pairs = np.asarray(poly.edge_faces, dtype=np.intp).reshape(-1, 2)
    widths = np.asarray([face_width(poly, f) for f in range(len(poly.faces))], dtype=float)
    r = rounding * np.minimum(widths[pairs[:, 0]], widths[pairs[:, 1]])
    cos = np.clip((poly.normals[pairs[:, 0]] * poly.normals[pairs[:, 1]]).sum(axis=1), -1, 1)
    half = np.sqrt((1.0 + cos) / 2.0)  # cos(θ/2)
    ok = cos >= ACUTE_COS
    inside = np.where(ok, r * (1.0 / np.maximum(half, 1e-9) - 1.0), 0.0)
    beside = np.where(ok, r * np.sqrt(np.maximum(1.0 - half**2, 0.0)) / np.maximum(half, 1e-9), 0.0)
    return inside, beside


def segment_distances(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """(P, E) distance of each of ``points`` from each segment ``a[e]``–``b[e]``."""
    ab = b - a
    length2 = np.maximum((ab * ab).sum(axis=1), 1e-18)
    t = np.clip(((points[:, None, :] - a[None]) * ab[None]).sum(axis=2) / length2, 0.0, 1.0)
    foot = a[None] + t[:, :, None] * ab[None]
    return np.asarray(np.linalg.norm(points[:, None, :] - foot, axis=2), dtype=float)


def _past_rounding(
    centres: FloatArray, sensors: FloatArray, zone: NDArray[np.bool_], least: int, scale: float
) -> tuple[_Fit, NDArray[np.bool_]] | None:
    """The plane of a face's ``centres`` without those in ``zone`` (near enough to an edge to
    lie on its rounding) that dip inside it, and which centres it is the plane of; or None
    when no such set explains a dip (:func:`refit_past_roundings`); at least ``least``
    centres are kept. A set set aside explains a dip when the rest lie on their plane within
    4 ``s`` (``s`` the larger of ``scale`` and their robust scatter), none of the set lies
    outside it by more than 4 ``s`` and one lies inside by more; and only when the plane of
    all the centres misses the kept ones by an RMS above ``scale`` (the noise, at least) and
    above twice their scatter about their own plane (σ with three degrees of freedom spent;
    so four centres at least): the dips turned it, which the noise alone does not.

    The whole zone is set aside first, and those of its centres that lie on the plane of the
    rest are given back; when that leaves too few, the zone's deepest centre (below the plane
    of those kept) is set aside one at a time, and once the rest share a plane, any of the
    zone's still more than 2 ``s`` inside it too."""
    span = current().geometry.span
    m = len(centres)
    whole = _fit(centres, sensors, span)

    def explains(keep: NDArray[np.bool_]) -> tuple[_Fit, float] | None:
        if keep.all():
            return None
        fit = _fit(centres[keep], sensors[keep], span)
        if not fit.refined:
            return None
        s = max(scale, _mad_sigma(fit.residuals))
        dips = centres[~keep] @ fit.normal - fit.centre_offset
        # the plane of them all misses the kept centres, by more than the noise and at least
        # twice as far as their own plane: the dips turned it
        missed = centres[keep] @ whole.normal - whole.centre_offset
        n = int(keep.sum())
        own = math.sqrt(_sse(fit) / (n - 3)) if n > 3 else math.inf
        turned = _rms(missed) > max(scale, 2.0 * own)
        ok = (
            turned
            and float(np.abs(fit.residuals).max()) <= INSIDE_SIGMAS * s
            and float(dips.max()) <= INSIDE_SIGMAS * s
            and float(dips.min()) < -INSIDE_SIGMAS * s
        )
        return (fit, s) if ok else None

    if int((~zone).sum()) >= least:
        found = explains(~zone)
        if found is not None:
            fit, s = found
            back = zone & (np.abs(centres @ fit.normal - fit.centre_offset) <= 2.0 * s)
            kept = ~zone
            if back.any():
                again = _fit(centres[~zone | back], sensors[~zone | back], span)
                if again.refined:
                    fit, kept = again, ~zone | back
            return fit, kept
    keep = np.ones(m, dtype=bool)
    fit = whole
    while zone[keep].any() and int(keep.sum()) > least:
        res = centres @ fit.normal - fit.centre_offset
        keep[int(np.argmin(np.where(keep & zone, res, np.inf)))] = False
        found = explains(keep)
        if found is None:
            fit = _fit(centres[keep], sensors[keep], span)
            if not fit.refined:
                return None
            continue
        fit, s = found
        # the rounding's shallower touches, inside the plane the rest now share
        while int(keep.sum()) > least:
            res = centres @ fit.normal - fit.centre_offset
            shallow = keep & zone & (res < -2.0 * s)
            if not shallow.any():
                break
            j = int(np.argmin(np.where(shallow, res, np.inf)))
            keep[j] = False
            trimmed = _fit(centres[keep], sensors[keep], span)
            if not trimmed.refined:
                keep[j] = True
                break
            fit = trimmed
        return fit, keep
    return None


def _rms(r: FloatArray) -> float:
    return math.sqrt(float((r**2).mean())) if len(r) else 0.0


def _refitted(face: Face, fit: _Fit, rho: float, noise: float, spots: int) -> Face:
    """``face`` with the plane ``fit`` of some of its centres (all its contacts kept), which lie
    at ``spots`` places (:func:`places`); their scatter is taken as at least the declared
    ``noise`` (a few centres can fit a plane better than their noise by chance)."""
    sigma = max(_scatter(fit, spots), noise)
    return Face(
        normal=(float(fit.normal[0]), float(fit.normal[1]), float(fit.normal[2])),
        offset=fit.centre_offset - rho,
        n_contacts=face.n_contacts,
        residual=math.sqrt(float((fit.residuals**2).mean())),
        normal_uncertainty_deg=_turn_deg(fit, sigma, spots),
        contacts=face.contacts,
        refined=True,
        offset_uncertainty=sigma / math.sqrt(spots),
        places=face.places,
    )
