"""The rounded envelope: one convex polyhedron, its edges rounded, fitted to all the tip centres.

A real object's edges are rounded. A tip of radius ρ sliding over an object ``K ⊕ B(r)``
(a convex polyhedron ``K`` grown by a ball of radius ``r``: every edge a cylinder of radius
``r``) keeps its centre on ``K ⊕ B(ρ + r)``: at distance ``R = ρ + r`` from ``K``, whether it
touches a face, the rounding of an edge or that of a corner. A sharp solid is the case
``r = 0``. Fitted face by face, the touches of the roundings either make faces of their own
(a plane through a rounding's touches, its normal between two faces') or, kept with a face,
turn its plane by degrees: the faces' planes and the roundings are one model, and are
fitted as one here.

:func:`fit_rounded` fits the planes of ``K`` and the shared radius ``r`` to the tip centres
by a robust least-squares fit (scipy's ``least_squares`` with the ``soft_l1`` loss, an
M-estimator, and an analytic Jacobian): each centre's residual is its distance from ``K``
less ``R``, measured to the nearest face, edge or corner of ``K`` (re-assigned between
rounds). :func:`unexplained` then asks of each face in turn whether the model *without* it
explains its touches as well as with it: a rounding's face does (its touches lie on the
rounding of the edge its two neighbours make), a face of the object does not (without it
``K`` overshoots: a corner that is not there, its touches inside the model by that corner's
depth).

Only faces that support the object (no touch beyond them: a convex object's faces) make
``K``; a non-convex object's hollows are left to :mod:`tactile_kb.geometry.blocks`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from tactile_kb.errors import GeometryError
from tactile_kb.geometry.polyhedron import Polyhedron, face_width, polyhedron_from_planes
from tactile_kb.types import FloatArray

__all__ = ["RoundedFit", "fit_rounded", "unexplained"]

ROUNDS = 4
"""Rounds of :func:`fit_rounded`: each fits with the centres' features fixed, then assigns
them anew (a centre that moved from a face to an edge's rounding)."""

PREFILTER = 2.0
"""A face is refitted without only when its touches lie within this many times the
``sigmas`` limit of :func:`unexplained` of the envelope fitted with it, that face's plane left
out (no refit): a face of the object lies far inside, by the corner it cuts off."""

MAX_EVALUATIONS = 30
"""Evaluations of the residuals per round of :func:`fit_rounded` (a few Gauss-Newton steps
from the faces' own planes, a start within a few degrees)."""

LIGHT_FRACTION = 0.5
"""A plane touched fewer than this × the median plane's touches is touched in passing, as a
rounding is, not explored as a face: when :data:`PREFILTER` rules it out, a quick refit
without it (:data:`QUICK_EVALUATIONS`) asks again (:func:`unexplained`). So is a rounding's
strip (:func:`_joined_width`) touched at most as often as the median plane. Asking it of
every plane touched at most that often made a thin heptagonal prism's facet a rounding
under noise; of every plane, three small cylinders' facets (``bench_accuracy.py``)."""

QUICK_EVALUATIONS = 8
"""Evaluations of the one-round refit that asks again for a lightly touched plane: enough to
move the radius and the neighbouring planes most of the way."""

STRIP_WIDTH = 0.5
"""A face is a rounding's strip, whose radius the two faces across its long sides bound
(:func:`_joined_width`), only when at most this × as wide as the narrower of them: a curved
object's facet is about as wide as its neighbours (a 14.3 mm cylinder's 11 mm facet between
facets 21 and 23 mm wide), and each facet dropped widens the next."""

FACE, EDGE, CORNER = 0, 1, 2

_Packed = tuple[
    NDArray[np.intp], NDArray[np.intp], NDArray[np.intp], list[tuple[int, tuple[int, ...]]]
]


def _pack(features: list[tuple[int, tuple[int, ...]]]) -> _Packed:
    kinds = np.asarray([k for k, _ in features], dtype=np.intp)
    fi = np.asarray([p[0] for _, p in features], dtype=np.intp)
    fj = np.asarray([p[1] if k == EDGE else p[0] for k, p in features], dtype=np.intp)
    corner = [(i, p) for i, (k, p) in enumerate(features) if k == CORNER]
    return kinds, fi, fj, corner


@dataclass(frozen=True)
class RoundedFit:
    """A fitted rounded envelope.

    Attributes
    ----------
    normals, offsets
        (m, 3) and (m,): the planes of the tip centres, ``normals · x = offsets`` (``K``'s
        planes moved out by ``R``); the faces of the object lie ρ inside them.
    radius
        ``r``, the edges' rounding radius (m).
    residuals
        Per centre, its distance from ``K`` less ``R`` (m; negative inside).
    scale
        The robust scale of the residuals (m), 1.4826 × their median absolute value, at least
        the floor it was fitted with.
    kinds
        Per centre, the feature of ``K`` it lies against: ``FACE`` (0), ``EDGE`` (1) or
        ``CORNER`` (2).
    planes
        (n, 2) per centre, the planes of that feature (a face's twice; a corner's first two).
    """

    normals: FloatArray
    offsets: FloatArray
    radius: float
    residuals: FloatArray
    scale: float
    kinds: NDArray[np.intp]
    planes: NDArray[np.intp]


def _tangents(n: FloatArray) -> tuple[FloatArray, FloatArray]:
    a = np.where(np.abs(n[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    u = np.cross(n, a)
    u /= np.linalg.norm(u, axis=1)[:, None]
    return u, np.cross(n, u)


def _features(
    c: FloatArray, normals: FloatArray, offsets: FloatArray, bound: tuple[FloatArray, float]
) -> list[tuple[int, tuple[int, ...]]] | None:
    """Per centre, the feature of ``K`` (the planes ``normals · x ≤ offsets``) nearest it:
    ``(FACE, (j,))``, ``(EDGE, (j, k))`` or ``(CORNER, planes)``; None when ``K`` is open."""
    try:
        poly = polyhedron_from_planes(normals, offsets, bound=bound, interior=bound[0])
    except GeometryError:
        return None
    return _nearest_features(c, poly)


def _nearest_features(c: FloatArray, poly: Polyhedron) -> list[tuple[int, tuple[int, ...]]]:
    plane = poly.plane_index
    best = np.full(len(c), np.inf)
    out: list[tuple[int, tuple[int, ...]]] = [(FACE, (0,))] * len(c)
    # faces: the projection inside the polygon
    for f, loop_ix in enumerate(poly.faces):
        loop = poly.vertices[list(loop_ix)]
        n = poly.normals[f]
        h = c @ n - poly.offsets[f]
        inward = np.cross(n, np.roll(loop, -1, axis=0) - loop)
        depth = np.einsum("ijk,jk->ij", c[:, None, :] - loop[None, :, :], inward)
        inside = (depth >= 0).all(axis=1)
        d = np.where(inside, np.abs(h), np.inf)
        better = d < best
        best[better] = d[better]
        for i in np.flatnonzero(better):
            out[i] = (FACE, (int(plane[f]),))
    # edges, and their ends
    faces_at: dict[int, set[int]] = {}
    for (a, b), (f, g) in zip(poly.edges, poly.edge_faces, strict=True):
        faces_at.setdefault(a, set()).update((int(plane[f]), int(plane[g])))
        faces_at.setdefault(b, set()).update((int(plane[f]), int(plane[g])))
    for (a, b), (f, g) in zip(poly.edges, poly.edge_faces, strict=True):
        p, q = poly.vertices[a], poly.vertices[b]
        e = q - p
        t = np.clip((c - p) @ e / max(float(e @ e), 1e-30), 0.0, 1.0)
        d = np.linalg.norm(c - (p + t[:, None] * e), axis=1)
        better = d < best - 1e-12
        best[better] = d[better]
        for i in np.flatnonzero(better):
            if 0.0 < t[i] < 1.0:
                out[i] = (EDGE, (int(plane[f]), int(plane[g])))
            else:
                v = a if t[i] <= 0.0 else b
                out[i] = (CORNER, tuple(sorted(faces_at[v])))
    # a centre inside K: its nearest face
    h = c @ poly.normals.T - poly.offsets
    for i in np.flatnonzero((h < 0).all(axis=1)):
        out[i] = (FACE, (int(plane[int(np.argmax(h[i]))]),))
    return out


def _residuals(
    c: FloatArray,
    normals: FloatArray,
    offsets: FloatArray,
    r: float,
    rho: float,
    features: _Packed,
) -> FloatArray:
    """Each centre's distance from its feature of ``K`` less ``R = ρ + r`` (``K``'s planes are
    the centres' planes moved in by ``R``)."""
    return _evaluate(c, normals, offsets, r, rho, features, gradients=False)[0]


_Gradients = list[tuple[NDArray[np.intp], NDArray[np.intp], FloatArray, FloatArray]]
"""Per block of residuals: their rows, the plane each depends on, and the residuals'
derivatives by that plane's normal (rows × 3) and by its offset (rows)."""


def _evaluate(
    c: FloatArray,
    normals: FloatArray,
    offsets: FloatArray,
    r: float,
    rho: float,
    features: _Packed,
    *,
    gradients: bool,
) -> tuple[FloatArray, _Gradients, FloatArray]:
    """:func:`_residuals`, and with ``gradients`` their derivatives: by each plane they
    depend on (normal and offset, see :data:`_Gradients`) and by ``r`` (per centre)."""
    big = rho + r
    d = offsets - big  # K's offsets
    kinds, fi, fj, corner = features
    out = np.empty(len(c))
    grads: _Gradients = []
    by_r = np.zeros(len(c))
    if len(fi):
        rows = np.flatnonzero(kinds == FACE)
        out[rows] = np.einsum("ij,ij->i", c[rows], normals[fi[rows]]) - offsets[fi[rows]]
        if gradients and len(rows):
            grads.append((rows, fi[rows], c[rows], -np.ones(len(rows))))
        rows = np.flatnonzero(kinds == EDGE)
        if len(rows):
            j, k = fi[rows], fj[rows]
            nj, nk, cr = normals[j], normals[k], c[rows]
            a = np.einsum("ij,ij->i", cr, nj) - d[j]
            b = np.einsum("ij,ij->i", cr, nk) - d[k]
            cos = np.einsum("ij,ij->i", nj, nk)
            sin2 = np.maximum(1.0 - cos * cos, 1e-9)
            dist = np.sqrt(np.maximum(a * a + b * b - 2.0 * a * b * cos, 0.0) / sin2)
            out[rows] = dist - big
            if gradients:
                # dist² = (a² + b² − 2ab·cos) / sin²: its derivatives by a, b and cos
                w = 1.0 / np.maximum(sin2 * dist, 1e-12)
                by_a = (a - b * cos) * w
                by_b = (b - a * cos) * w
                by_cos = (dist * dist * cos - a * b) * w
                grads.append((rows, j, by_a[:, None] * cr + by_cos[:, None] * nk, -by_a))
                grads.append((rows, k, by_b[:, None] * cr + by_cos[:, None] * nj, -by_b))
                by_r[rows] = by_a + by_b - 1.0
    # a corner's point v = argmin |N v − d| depends on its planes only: one solve per corner
    at: dict[tuple[int, ...], list[int]] = {}
    for i, ix in corner:
        at.setdefault(ix, []).append(i)
    for ix, members in at.items():
        planes = np.asarray(ix, dtype=np.intp)
        n = normals[planes]
        v, *_ = np.linalg.lstsq(n, d[planes], rcond=None)
        rows = np.asarray(members, dtype=np.intp)
        diff = c[rows] - v
        length = np.linalg.norm(diff, axis=1)
        out[rows] = length - big
        if gradients:
            # dv = G (dNᵀ ρ + Nᵀ (dd − dN v)), G = (NᵀN)⁺, ρ = d − N v; d(res) = −û · dv
            g = np.linalg.pinv(n.T @ n)
            u = diff / np.maximum(length, 1e-12)[:, None]
            ug = u @ g  # (rows, 3): û G
            lack = d[planes] - n @ v
            for p, plane in enumerate(planes):
                along = ug @ n[p]  # û G n_p
                # by n_p in direction t: −û G (t ρ_p − n_p (t · v))
                by_n = -lack[p] * ug + along[:, None] * v[None, :]
                grads.append((rows, np.full(len(rows), plane), by_n, -along))
            by_r[rows] = ug @ n.sum(axis=0) - 1.0
    return out, grads, by_r


def fit_rounded(
    centres: FloatArray,
    normals: FloatArray,
    offsets: FloatArray,
    rho: float,
    *,
    fixed: Sequence[bool] | NDArray[np.bool_] | None = None,
    max_radius: float,
    floor: float,
    rounds: int = ROUNDS,
    evaluations: int = MAX_EVALUATIONS,
) -> RoundedFit | None:
    """Fit the rounded envelope to ``centres`` from the tip-centre planes ``normals · x =
    offsets`` (a start: each face's own fit); planes flagged ``fixed`` (the table) stay.
    ``r`` lies in ``[0, max_radius]``; ``floor`` (m) is the least scale of the robust loss;
    ``rounds`` fits, each of at most ``evaluations`` evaluations of the residuals, with the
    centres' features assigned anew between them. None when the planes do not close."""
    m = len(normals)
    fixed_a = np.zeros(m, dtype=bool) if fixed is None else np.asarray(fixed, dtype=bool)
    free = np.flatnonzero(~fixed_a)
    n0 = np.asarray(normals, dtype=float).copy()
    e0 = np.asarray(offsets, dtype=float).copy()
    u, v = _tangents(n0)
    bound = _bound(centres)

    k = len(free)
    column = np.full(m, -1, dtype=np.intp)
    column[free] = np.arange(k)

    def unpack(x: FloatArray) -> tuple[FloatArray, FloatArray, float, FloatArray]:
        """The planes, ``r`` and each normal's length before it was made unit."""
        n = n0.copy()
        e = e0.copy()
        a, b, off = x[:k], x[k : 2 * k], x[2 * k : 3 * k]
        n[free] = n0[free] + a[:, None] * u[free] + b[:, None] * v[free]
        norms = np.ones(m)
        norms[free] = np.linalg.norm(n[free], axis=1)
        n[free] /= norms[free, None]
        e[free] = e0[free] + off
        return n, e, float(x[-1]), norms

    def jacobian(x: FloatArray, fs: _Packed) -> FloatArray:
        """The residuals' derivatives by ``x``: by each free plane's two tilts (along ``u``
        and ``v``, the normal then made unit), its offset, and ``r``."""
        n, e, r, norms = unpack(x)
        _, grads, by_r = _evaluate(centres, n, e, r, rho, fs, gradients=True)
        # the unit normal's derivative by a tilt t: (t − n (n · t)) / |n0 + a u + b v|
        du = (u - n * np.einsum("ij,ij->i", n, u)[:, None]) / norms[:, None]
        dv = (v - n * np.einsum("ij,ij->i", n, v)[:, None]) / norms[:, None]
        jac = np.zeros((len(centres), 3 * k + 1))
        for rows, planes, by_n, by_e in grads:
            q = column[planes]
            sel = q >= 0
            if not sel.any():
                continue
            rr, qq, pp, gn = rows[sel], q[sel], planes[sel], by_n[sel]
            jac[rr, qq] += np.einsum("ij,ij->i", gn, du[pp])
            jac[rr, k + qq] += np.einsum("ij,ij->i", gn, dv[pp])
            jac[rr, 2 * k + qq] += by_e[sel]
        jac[:, -1] = by_r
        return jac

    def residuals(x: FloatArray, fs: _Packed) -> FloatArray:
        n, e, r, _ = unpack(x)
        return _residuals(centres, n, e, r, rho, fs)

    x = np.zeros(3 * k + 1)
    lo = np.full(len(x), -np.inf)
    hi = np.full(len(x), np.inf)
    lo[-1], hi[-1] = 0.0, max(max_radius, 1e-9)
    x[-1] = min(max(0.5 * max_radius, 0.0), hi[-1])
    feats = _features(centres, n0, e0 - rho - x[-1], bound)
    if feats is None:
        return None
    for _ in range(rounds):
        fs = _pack(feats)
        scale = max(floor, _robust_scale(residuals(x, fs)))
        try:
            sol = least_squares(
                residuals,
                x,
                jac=jacobian,
                args=(fs,),
                loss="soft_l1",
                f_scale=scale,
                bounds=(lo, hi),
                max_nfev=evaluations,
                ftol=1e-6,
                xtol=1e-6,
            )
        except np.linalg.LinAlgError:
            return None
        x = sol.x
        n, e, r, _ = unpack(x)
        new = _features(centres, n, e - rho - r, bound)
        if new is None:
            return None
        if new == feats:
            break
        feats = new
    n, e, r, _ = unpack(x)
    packed = _pack(feats)
    res = _residuals(centres, n, e, r, rho, packed)
    kinds, fi, fj, _ = packed
    return RoundedFit(
        normals=n,
        offsets=e,
        radius=r,
        residuals=res,
        scale=max(floor, _robust_scale(res)),
        kinds=kinds,
        planes=np.column_stack([fi, fj]),
    )


def unexplained(
    centres: FloatArray,
    groups: Sequence[Sequence[int]],
    normals: FloatArray,
    offsets: FloatArray,
    rho: float,
    *,
    fixed: Sequence[bool],
    candidates: Sequence[int],
    rounding: float,
    floor: float,
    sigmas: float = 2.5,
    growth: float = 1.25,
    min_width: float = 0.0,
) -> tuple[list[int], RoundedFit | None]:
    """Which of the ``candidates`` (indices into the planes) the rounded envelope of the other
    planes explains, removed one at a time (fewest touches first), and the final fit.

    ``normals · x = offsets`` are the planes of the tip centres (the faces' planes moved out
    by ρ); planes flagged ``fixed`` (the table) are not fitted. ``groups[j]`` are the indices
    (into ``centres``) of plane ``j``'s touches. A plane is explained when, with the envelope
    fitted again without it to all the touches, a dropped face's too (``r`` at most
    ``rounding`` × the narrowest width of the object's faces at least ``min_width`` wide, or,
    when the plane is a strip between the two faces across its long sides and that is more,
    × the wider of them: see :func:`_joined_width`):

    * every one of its touches lies within ``sigmas`` × the robust scale of the fit with it
      (at least ``floor``) of the envelope, and their mean within 2 scales/√m (a face of the
      object leaves its touches inside, all on one side);
    * at least half of them lie on an edge's or a corner's rounding, against faces at least
      ``min_width`` wide (a curved object's facets stay);
    * the other touches' RMS, clipped at 3 scales, grows by at most ``growth`` ×.

    A plane whose touches lie further than :data:`PREFILTER` × that limit from the envelope
    with it, its own plane left out and nothing refitted, is not fitted again, unless it is
    touched lightly (fewer touches than :data:`LIGHT_FRACTION` × the median free plane's,
    or, for a strip between two wider faces, at most the median's): a rounding's plane holds
    the fitted radius small, and the envelope without it misses its touches until the radius
    and the neighbouring planes move. Such a plane is refitted without it once quickly (one
    round of :data:`QUICK_EVALUATIONS`), then fully when its touches lie within the
    prefilter's limit of that; and since the refit moved the envelope to them, more than
    half of its touches (not half) must then lie on roundings.
    """
    keep = list(range(len(normals)))
    fixed_a = np.asarray(fixed, dtype=bool)
    # every touch, a dropped face's too, lies on the envelope: one set of centres throughout
    idx = np.asarray(sorted({i for g in groups for i in g}), dtype=np.intp)
    pts = centres[idx]
    bound = _bound(pts)
    pos = {int(i): p for p, i in enumerate(idx)}

    def radius_cap(planes: list[int]) -> float | None:
        poly = _closed(normals[planes], offsets[planes] - rho, pts)
        if poly is None:
            return None
        # the narrowest face that is no rounding itself (at least min_width wide) caps r:
        # a second rounding's narrow plane must not stop the first from being explained
        widths = [face_width(poly, f) for f in range(len(poly.faces))]
        wide = [w for w in widths if w >= min_width] or widths
        return rounding * float(min(wide)) if wide else 0.0

    def fit(planes: list[int], cap: float, quick: bool = False) -> RoundedFit | None:
        return fit_rounded(
            pts,
            normals[planes],
            offsets[planes],
            rho,
            fixed=fixed_a[planes],
            max_radius=cap,
            floor=floor,
            rounds=1 if quick else ROUNDS,
            evaluations=QUICK_EVALUATIONS if quick else MAX_EVALUATIONS,
        )

    def limit(fitted: RoundedFit) -> float:
        return PREFILTER * sigmas * max(fitted.scale, floor)

    def near(k: int, fitted: RoundedFit, cap: float) -> bool:
        """Whether ``k``'s touches lie within ``PREFILTER`` × ``sigmas`` scales of the fitted
        envelope without ``k``, refitting nothing (at three radii up to ``cap``): a face of
        the object lies far inside it, and its costly refit is skipped."""
        at = [p for p, j in enumerate(keep) if j != k]
        c = centres[list(groups[k])]
        n, e = fitted.normals[at], fitted.offsets[at]
        for r in (fitted.radius, 0.5 * cap, cap):
            feats = _features(c, n, e - rho - r, bound)
            if feats is None:
                return True  # no judgement without a closed envelope: refit
            res = _residuals(c, n, e, r, rho, _pack(feats))
            if float(np.abs(res).max()) <= limit(fitted):
                return True
        return False

    def light(k: int, strip: bool) -> bool:
        """Whether ``k`` is touched fewer than :data:`LIGHT_FRACTION` × the median free plane
        of those kept, or, a ``strip``, at most as often as that median (its refit near
        enough is then asked again)."""
        touches = [len(groups[j]) for j in keep if not fixed_a[j]]
        if not touches:
            return False
        median = float(np.median(touches))
        return len(groups[k]) < LIGHT_FRACTION * median or (strip and len(groups[k]) <= median)

    def near_refitted(
        mine: NDArray[np.intp], fitted: RoundedFit, rest: list[int], cap: float
    ) -> bool:
        """Whether the touches ``mine`` (indices into ``pts``) lie within ``PREFILTER`` ×
        ``sigmas`` scales (of ``fitted``, the envelope with their plane) of the envelope
        quickly refitted on the planes ``rest``."""
        quick = fit(rest, cap, quick=True)
        return quick is not None and float(np.abs(quick.residuals[mine]).max()) <= limit(fitted)

    cap = radius_cap(keep)
    current = fit(keep, cap) if cap is not None else None
    if current is None:
        return [], None
    removed: list[int] = []
    while True:
        order = sorted((k for k in candidates if k in keep), key=lambda k: (len(groups[k]), k))
        whole = _closed(normals[keep], offsets[keep] - rho, pts)
        found = False
        for k in order:
            rest = [j for j in keep if j != k]
            if len(rest) < 4:
                continue
            cap = radius_cap(rest)
            if cap is None:
                continue
            joined = _joined_width(whole, keep.index(k))
            cap = max(cap, rounding * joined)
            mine = np.asarray([pos[i] for i in groups[k]], dtype=np.intp)
            refitted = False  # near only once the envelope without k was refitted
            if not near(k, current, cap):
                if not (light(k, joined > 0) and near_refitted(mine, current, rest, cap)):
                    continue
                refitted = True
            trial = fit(rest, cap)
            if trial is None:
                continue
            others = np.setdiff1d(np.arange(len(idx)), mine)
            before = _robust_rms(current.residuals[others], current.scale)
            after = _robust_rms(trial.residuals[others], trial.scale)
            res = trial.residuals[mine]
            s = max(current.scale, floor)
            ok = _wide(trial, rest, mine, rho, min_width) and (
                float(np.abs(res).max()) <= sigmas * s
                and abs(float(res.mean())) <= 2.0 * s / math.sqrt(len(res))
                and _on_roundings(float(np.mean(trial.kinds[mine] != FACE)), strict=refitted)
                and after <= growth * max(before, floor)
            )
            if ok:
                keep = rest
                removed.append(k)
                current = trial
                found = True
                break
        if not found:
            return removed, current


def _joined_width(poly: Polyhedron | None, plane: int) -> float:
    """The width of the wider of the two faces the face of ``plane`` (an index into the
    planes ``poly`` was made of) meets along its two longest sides, when that face is a strip
    between them (at most :data:`STRIP_WIDTH` × as wide as the narrower); else 0.

    A rounding's plane is a long strip along the edge it rounds: the faces across its long
    sides are the two the edge joins, and they bound that edge's radius. The narrowest face
    of the whole model is no bound when other roundings' strips are still in it (a strip 2 cm
    wide would cap a 2 cm radius at 2 mm); the narrower of the two is often a face those
    strips have cut down."""
    if poly is None:
        return 0.0
    mine = [f for f in range(len(poly.faces)) if poly.plane_index[f] == plane]
    if not mine:
        return 0.0
    sides = sorted(
        (
            (float(np.linalg.norm(poly.vertices[a] - poly.vertices[b])), g if h == mine[0] else h)
            for (a, b), (g, h) in zip(poly.edges, poly.edge_faces, strict=True)
            if mine[0] in (g, h)
        ),
        reverse=True,
    )
    if len(sides) < 2:
        return 0.0
    joined = sorted(face_width(poly, g) for _, g in sides[:2])
    return joined[1] if face_width(poly, mine[0]) <= STRIP_WIDTH * joined[0] else 0.0


def _on_roundings(fraction: float, *, strict: bool) -> bool:
    """Whether ``fraction`` of a plane's touches on roundings explains it: at least half;
    more than half (``strict``) when only a refit brought the envelope to them."""
    return fraction > 0.5 if strict else fraction >= 0.5


def _wide(
    fit: RoundedFit, planes: list[int], mine: NDArray[np.intp], rho: float, min_width: float
) -> bool:
    """Whether every face of the object the touches ``mine`` lie against (in ``fit``, whose
    planes are ``planes``) is at least ``min_width`` wide: a rounding joins faces, a curved
    object's facets are narrow and stay."""
    if min_width <= 0:
        return True
    try:
        poly = polyhedron_from_planes(fit.normals, fit.offsets - rho)
    except GeometryError:
        return False
    width = dict.fromkeys(range(len(planes)), 0.0)
    for f in range(len(poly.faces)):
        width[int(poly.plane_index[f])] = face_width(poly, f)
    against = np.unique(fit.planes[mine])
    return all(width[int(j)] >= min_width for j in against)


def _robust_scale(res: FloatArray) -> float:
    """1.4826 × the median absolute residual: σ of normal residuals, robust to outliers."""
    return 1.4826 * float(np.median(np.abs(res)))


def _robust_rms(res: FloatArray, scale: float) -> float:
    clipped = np.clip(res, -3.0 * scale, 3.0 * scale)
    return float(np.sqrt(np.mean(clipped * clipped))) if len(res) else 0.0


def _bound(pts: FloatArray) -> tuple[FloatArray, float]:
    """Where planes must close: within three times the touched points' radius about their
    centre (as :func:`tactile_kb.geometry.model.build_model` asks)."""
    middle = pts.mean(axis=0)
    return middle, 3.0 * float(np.linalg.norm(pts - middle, axis=1).max())


def _closed(normals: FloatArray, offsets: FloatArray, pts: FloatArray) -> Polyhedron | None:
    try:
        bound = _bound(pts)
        return polyhedron_from_planes(normals, offsets, bound=bound, interior=bound[0])
    except GeometryError:
        return None
