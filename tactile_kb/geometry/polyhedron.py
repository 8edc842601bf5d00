"""The enveloping polyhedron: the region bounded by the touched planes, with its topology.

"In this way the touched body will be represented by one polyhedron which envelopes the body
and is composed of the group of planes whose equations are known. Coordinates of the vertices
and equations of the edges are easy to calculate." Each plane is ``normal · x = offset`` with
the unit normal pointing out of the object, so the body lies in ``normal · x ≤ offset``.

:func:`polyhedron_from_planes` checks that the planes bound a region (else
:class:`~tactile_kb.errors.OpenModelError` naming the open directions), finds an interior
point (the Chebyshev centre, by linear programming), intersects the half-spaces (Qhull through
scipy, without joggling), merges vertices closer than a tolerance scaled to the object, and
builds faces from the planes active at each vertex.

Examples
--------
>>> import numpy as np
>>> normals = np.vstack([np.eye(3), -np.eye(3)])
>>> offsets = np.array([0.05, 0.03, 0.04, 0.05, 0.03, 0.0])
>>> p = polyhedron_from_planes(normals, offsets)
>>> len(p.vertices), len(p.edges), len(p.faces)
(8, 12, 6)
>>> round(p.volume * 1e6, 3), [round(float(v), 3) + 0.0 for v in p.centroid]
(240.0, [0.0, 0.0, 0.02])
>>> sorted({round(float(a), 6) for a in p.dihedral_deg})
[90.0]
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, HalfspaceIntersection, QhullError

from tactile_kb.errors import GeometryError, OpenModelError, UsageError
from tactile_kb.geometry.memo import Memo
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray

__all__ = [
    "DEFAULT_MERGE_FRACTION",
    "Polyhedron",
    "collapse_short_edges",
    "face_width",
    "open_directions",
    "opposed",
    "opposed_edges",
    "polyhedron_from_planes",
    "vertex_covariances",
]


DEFAULT_MERGE_FRACTION = DEFAULTS.geometry.merge_fraction
"""Vertices closer than this fraction of the object's diameter are merged into one.

Noisy planes that should meet in one vertex (a pyramid's apex, the four-face vertices of an
octahedron) meet in a cluster of nearby vertices a millimetre or two apart; 3 % of the
diameter (3 mm for a 10 cm object) merges them while keeping real edges."""


def opposed(
    active: NDArray[np.bool_], normals: FloatArray, tolerance_deg: float, pairs: NDArray[np.intp]
) -> NDArray[np.bool_]:
    """(K,) for each pair of vertices in ``pairs`` (K, 2), whether a plane active at one and a
    plane active at the other face away from each other: ``active`` (V, P) marks the planes
    through each vertex, ``normals`` (P, 3) are their unit outward normals, antiparallel
    within ``tolerance_deg``.

    The planes of one corner never do (they would enclose no volume there), so two such
    vertices are the ends of a thickness, however short: a plate's 8 mm edge between its top
    and its bottom, never one corner that noisy planes split
    (:func:`polyhedron_from_planes` merges no such pair, :func:`collapse_short_edges` collapses
    no such edge)."""
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    if len(pairs) == 0:
        return np.zeros(0, dtype=bool)
    used, local = np.unique(pairs, return_inverse=True)
    rows, cols = np.nonzero(active[used])
    counts = np.bincount(rows, minlength=len(used))
    # each vertex's normals, padded with zeros (a zero is never antiparallel to anything)
    mine = np.zeros((len(used), max(int(counts.max()), 1), 3))
    mine[rows, np.arange(len(rows)) - (np.cumsum(counts) - counts)[rows]] = normals[cols]
    local = local.reshape(-1, 2)
    dots = np.einsum("pai,pbi->pab", mine[local[:, 0]], mine[local[:, 1]])
    return np.asarray((dots <= -math.cos(math.radians(tolerance_deg))).any(axis=(1, 2)), dtype=bool)


def opposed_edges(poly: Polyhedron, tolerance_deg: float | None = None) -> NDArray[np.bool_]:
    """(E,) whether each edge of ``poly`` runs between faces that face away from each other,
    one at each of its corners (:func:`opposed`; ``tolerance_deg`` by default
    ``features.tolerance_deg``). A corner that noisy planes split never does, so a short
    edge that does is a thickness (a plate's), not a split corner. Long edges often do too:
    every edge of a box, or of an octahedron, whose opposite faces are parallel.

    >>> import numpy as np
    >>> n = np.vstack([np.eye(3), -np.eye(3)])
    >>> plate = polyhedron_from_planes(n, [0.1, 0.1, 0.004, 0.1, 0.1, 0.004])
    >>> short = plate.edge_lengths() < 0.01
    >>> np.round(plate.edge_lengths()[short], 3).tolist(), bool(opposed_edges(plate)[short].all())
    ([0.008, 0.008, 0.008, 0.008], True)
    """
    if tolerance_deg is None:
        tolerance_deg = current().features.tolerance_deg
    at = np.zeros((len(poly.vertices), len(poly.faces)), dtype=bool)
    for f, ring in enumerate(poly.faces):
        at[list(ring), f] = True
    e = np.asarray(poly.edges, dtype=np.intp).reshape(-1, 2)
    return opposed(at, np.asarray(poly.normals, dtype=float), tolerance_deg, e)


@dataclass(frozen=True, eq=False)
class Polyhedron:
    """A convex polyhedron with its topology.

    Attributes
    ----------
    vertices
        (V, 3) vertex coordinates, metres.
    faces
        Vertex indices of each face, counter-clockwise seen from outside.
    normals, offsets
        (F, 3) outward unit normals and (F,) offsets: face ``i`` lies in
        ``normals[i] · x = offsets[i]``.
    edges
        Pairs of vertex indices ``(i, j)`` with ``i < j``.
    edge_faces
        The two faces meeting at each edge, ``(f, g)`` with ``f < g``.
    dihedral_deg
        (E,) interior dihedral angle at each edge: 90 for a cube, 70.53 for a regular
        tetrahedron, 109.47 for a regular octahedron (180° minus the angle between normals).
    volume, centroid
        Volume (m³) and centre of mass for uniform density.
    face_areas, face_centroids
        (F,) areas and (F, 3) area centroids of the faces.
    plane_index
        For each face, the index of the input plane it lies on.
    """

    vertices: FloatArray
    faces: tuple[tuple[int, ...], ...]
    normals: FloatArray
    offsets: FloatArray
    edges: tuple[tuple[int, int], ...]
    edge_faces: tuple[tuple[int, int], ...]
    dihedral_deg: FloatArray
    volume: float
    centroid: FloatArray
    face_areas: FloatArray
    face_centroids: FloatArray
    plane_index: tuple[int, ...] = field(default=())
    _widths: dict[int, float] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )  # face_width's answers

    @property
    def diameter(self) -> float:
        """Largest distance between two vertices."""
        v = self.vertices
        d = np.linalg.norm(v[:, None, :] - v[None, :, :], axis=2)
        return float(d.max())

    def face_adjacency(self) -> dict[int, set[int]]:
        """Faces sharing an edge with each face."""
        adj: dict[int, set[int]] = {i: set() for i in range(len(self.faces))}
        for f, g in self.edge_faces:
            adj[f].add(g)
            adj[g].add(f)
        return adj

    def edge_lengths(self) -> FloatArray:
        """(E,) length of each edge."""
        e = np.asarray(self.edges, dtype=int).reshape(-1, 2)
        return np.asarray(
            np.linalg.norm(self.vertices[e[:, 0]] - self.vertices[e[:, 1]], axis=1), dtype=float
        )

    def contains(self, point: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``point`` lies inside or on the polyhedron."""
        p = np.asarray(point, dtype=float)
        return bool(np.all(self.normals @ p - self.offsets <= tol))


def _as_planes(normals: ArrayLike, offsets: ArrayLike) -> tuple[FloatArray, FloatArray]:
    n = np.asarray(normals, dtype=float)
    d = np.asarray(offsets, dtype=float).reshape(-1)
    if n.ndim != 2 or n.shape[1] != 3 or n.shape[0] != d.shape[0]:
        raise UsageError(
            f"normals must be (m, 3) and offsets (m,), got {n.shape} and {np.shape(offsets)}"
        )
    if not (np.isfinite(n).all() and np.isfinite(d).all()):
        raise UsageError("plane normals and offsets must be finite")
    length = np.linalg.norm(n, axis=1)
    if (length < 1e-12).any():
        raise UsageError(f"plane {int(np.argmin(length))} has a zero normal")
    return n / length[:, None], d / length


def open_directions(normals: ArrayLike, *, tol: float = 1e-9) -> list[tuple[float, float, float]]:
    """Unit directions in which the half-spaces ``normals · x ≤ offset`` are unbounded.

    Empty when the normals positively span R³ (every direction is blocked by some plane).
    Otherwise the extreme rays of the recession cone ``{d : normals · d ≤ 0}`` (or a basis of
    its line space when the cone contains whole lines), which name the unexplored sides.

    Examples
    --------
    >>> open_directions([(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, -1)])
    [(0.0, 0.0, 1.0)]
    """
    n = np.asarray(normals, dtype=float).reshape(-1, 3)
    if n.shape[0] == 0:
        return [
            (1.0, 0.0, 0.0),
            (0.0, 1.0, 0.0),
            (0.0, 0.0, 1.0),
            (-1.0, 0.0, 0.0),
            (0.0, -1.0, 0.0),
            (0.0, 0.0, -1.0),
        ]
    n = n / np.linalg.norm(n, axis=1)[:, None]
    if len(n) >= _HULL_TEST and _surrounds_origin(n, 1e3 * max(tol, 1e-9)):
        return []
    # line space of the cone: null space of the normals, both senses
    rank = int((np.linalg.svd(n, compute_uv=False) > 1e-9).sum())
    null = np.linalg.svd(n)[2][rank:] if rank < 3 else np.zeros((0, 3))
    i, j = _pairs(len(n))
    cross = _cross(n[i], n[j])
    length = np.linalg.norm(cross, axis=1)
    good = length > 1e-9
    cross = cross[good] / length[good][:, None]
    # the rays of the cone are among ± the pairwise cross products; when the cone is a
    # half-space or wedge with one bounding plane, its rays include directions inside single
    # planes: the axes cover the remaining generic cases
    candidates = np.vstack(
        [np.stack([null, -null], axis=1).reshape(-1, 3), cross, -cross, np.eye(3), -np.eye(3)]
    )
    out: list[FloatArray] = []
    for c in candidates[(candidates @ n.T <= tol).all(axis=1)]:
        if not any(float(c @ o) > 1.0 - 1e-6 for o in out):
            out.append(c)
    if not out:
        return []
    # a direction strictly blocked by none of the planes exists whenever the cone is not {0}
    return [
        (round(float(x), 6) + 0.0, round(float(y), 6) + 0.0, round(float(z), 6) + 0.0)
        for x, y, z in out
    ]


_HULL_TEST = 12
"""From this many normals on, :func:`open_directions` first tries the convex-hull test."""


def _surrounds_origin(n: FloatArray, margin: float) -> bool:
    """True when the convex hull of the unit normals ``n`` holds the ball of radius ``margin``
    about the origin: then every unit direction ``c`` has ``max(n · c) ≥ margin``, so no
    direction is open (a quick answer for many planes; False means "not sure")."""
    try:
        hull = ConvexHull(n)
    except QhullError:  # flat or degenerate set of normals: let the exact test decide
        return False
    return bool((hull.equations[:, 3] < -margin).all())


def _fmt(d: tuple[float, float, float]) -> str:
    return "(" + ", ".join(f"{round(v, 2) + 0.0:+.2f}" for v in d) + ")"


def _far_directions(
    raw: FloatArray, centre: FloatArray, radius: float
) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
    """``(direction, vertex)`` of the vertices ``raw`` further than ``radius`` from
    ``centre``, furthest first, one per direction (those within 30° of one kept are left
    out)."""
    rel = raw - centre
    dist = np.linalg.norm(rel, axis=1)
    out: list[tuple[FloatArray, FloatArray]] = []
    for i in np.argsort(-dist):
        if dist[i] <= radius:
            break
        d = rel[i] / dist[i]
        if not any(float(d @ o) > math.cos(math.radians(30.0)) for o, _ in out):
            out.append((d, raw[i]))
    return [(_rounded(d), _rounded(v)) for d, v in out]


def _rounded(v: FloatArray) -> tuple[float, float, float]:
    return (round(float(v[0]), 6) + 0.0, round(float(v[1]), 6) + 0.0, round(float(v[2]), 6) + 0.0)


def _interior_point(
    n: FloatArray, d: FloatArray, hint: ArrayLike | None
) -> tuple[FloatArray, float]:
    if hint is not None:
        x = np.asarray(hint, dtype=float).reshape(3)
        depth = float((d - n @ x).min())
        spread = float((d - n @ x).max())
        if np.isfinite(depth) and depth > 0.05 * spread:
            return x, depth
    return _chebyshev(n, d)


def _chebyshev(n: FloatArray, d: FloatArray) -> tuple[FloatArray, float]:
    """The centre and radius of the largest ball inside ``n · x ≤ d`` (the last few answers
    are kept, by the exact planes: the linear programme costs more than the intersection)."""

    def solve() -> tuple[FloatArray, float] | Callable[[], GeometryError]:
        try:
            return _chebyshev_lp(n, d)
        except GeometryError as exc:
            return _maker(exc)

    hit = _CENTRES.get((n.tobytes(), d.tobytes()), solve)
    if callable(hit):
        raise hit()
    return hit[0].copy(), hit[1]


_BUILT_SIZE = 1024
"""Plane sets whose polyhedra, and Chebyshev centres, are kept (least recently used first
out): a model is rebuilt after every completion probe from mostly the same faces, and the
edge and explained-face tests build the polyhedron of every subset of them again."""

_CENTRES: Memo[tuple[bytes, bytes], tuple[FloatArray, float] | Callable[[], GeometryError]] = Memo(
    _BUILT_SIZE
)


def _chebyshev_lp(n: FloatArray, d: FloatArray) -> tuple[FloatArray, float]:
    """:func:`_chebyshev` by linear programming."""
    c = np.zeros(4)
    c[3] = -1.0
    a = np.hstack([n, np.ones((len(n), 1))])
    res = linprog(c, A_ub=a, b_ub=d, bounds=[(None, None)] * 3 + [(0.0, None)], method="highs")
    if res.status == 2:
        raise GeometryError("the planes enclose no region (their half-spaces do not intersect)")
    if res.status != 0:
        raise GeometryError(f"cannot find a point inside the planes: {res.message}")
    return np.asarray(res.x[:3], dtype=float), float(res.x[3])


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise cross products of (k, 3) arrays (``np.cross`` without its overhead)."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def _cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """The cross product of two 3-vectors (the same arithmetic as :func:`_cross`)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


@functools.lru_cache(maxsize=16)
def _pairs(m: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``np.triu_indices(m, 1)``, read-only and computed once per ``m``."""
    i, j = np.triu_indices(m, 1)
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


def _components(close: NDArray[np.bool_]) -> NDArray[np.intp]:
    """Connected-component labels of a symmetric adjacency matrix, numbered in the order of
    each component's smallest member (as ``scipy.sparse.csgraph.connected_components``).

    Each member takes the smallest index among itself and its neighbours until nothing
    changes (as many rounds as the longest path in a component: one or two for the few
    merged vertices of a polyhedron); past :data:`_PROPAGATE_ROUNDS` rounds scipy's graph
    search finishes the job.
    """
    k = len(close)
    if k == 0:
        return np.zeros(0, dtype=np.intp)
    link = close | close.T
    np.fill_diagonal(link, True)
    low = np.arange(k)
    for _ in range(_PROPAGATE_ROUNDS):
        nxt = np.where(link, low[None, :], k).min(axis=1)
        if np.array_equal(nxt, low):
            return np.asarray(np.unique(low, return_inverse=True)[1], dtype=np.intp).reshape(-1)
        low = nxt
    _, labels = connected_components(csr_array(link), directed=False)
    return np.asarray(labels, dtype=np.intp).reshape(-1)


_PROPAGATE_ROUNDS = 8


def _cluster_vertices(
    raw: FloatArray,
    labels: NDArray[np.intp],
    k: int,
    active: NDArray[np.bool_],
    n: FloatArray,
    d: FloatArray,
    max_shift: float,
) -> FloatArray:
    """One vertex per cluster of raw vertices: the least-squares point of the planes active
    there (at least three, well conditioned), else — or if that point lies more than
    ``max_shift`` from the cluster — the cluster's mean."""
    sums = np.zeros((k, 3))
    np.add.at(sums, labels, raw)
    means = sums / np.bincount(labels, minlength=k)[:, None]
    verts = means.copy()
    count = active.sum(axis=1)
    solvable = np.flatnonzero(count >= 3)
    if len(solvable):
        # n[P]ᵀ n[P] and n[P]ᵀ d[P] of the planes P active at each vertex, the vertices with
        # the same number of planes in one stacked product
        mats = np.empty((len(solvable), 3, 3))
        rhs = np.empty((len(solvable), 3))
        for c in np.unique(count[solvable]).tolist():
            pos = np.flatnonzero(count[solvable] == c)
            planes = np.nonzero(active[solvable[pos]])[1].reshape(len(pos), c)
            nt = n[planes].transpose(0, 2, 1)
            mats[pos] = nt @ n[planes]
            rhs[pos] = (nt @ d[planes][:, :, None])[:, :, 0]
        sv = np.linalg.svd(mats, compute_uv=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            good = sv[:, 0] / sv[:, -1] < 1e8  # the condition number (inf/nan: singular)
        if good.any():
            which = solvable[good]
            verts[which] = np.linalg.solve(mats[good], rhs[good][:, :, None])[:, :, 0]
    far = np.linalg.norm(verts - means, axis=1) > max_shift
    verts[far] = means[far]
    return verts


def _order_polygon(points: FloatArray, normal: FloatArray) -> list[int]:
    """Indices ordering ``points`` counter-clockwise seen from the side ``normal`` points to."""
    centre = points.sum(axis=0) / len(points)  # points.mean(axis=0), without its overhead
    u = points[0] - centre
    if math.sqrt(u @ u) < 1e-15:
        u = _cross3(normal, np.array([1.0, 0.0, 0.0]))
        if math.sqrt(u @ u) < 1e-9:
            u = _cross3(normal, np.array([0.0, 1.0, 0.0]))
    u = u - normal * (u @ normal)
    u /= math.sqrt(u @ u)
    v = _cross3(normal, u)
    rel = points - centre
    ang = np.arctan2(rel @ v, rel @ u)
    return [int(i) for i in np.argsort(ang, kind="stable")]


def _order_polygons(points: FloatArray, normals: FloatArray) -> list[list[int]]:
    """:func:`_order_polygon` of each polygon ``points[i]`` (B, m, 3) about ``normals[i]``,
    computed together (the same arithmetic; a polygon whose first point is its centre goes
    alone)."""
    m = points.shape[1]
    centre = points.sum(axis=1) / m
    u = points[:, 0] - centre
    lone = np.sqrt((u[:, None, :] @ u[:, :, None])[:, 0, 0]) < 1e-15
    with np.errstate(divide="ignore", invalid="ignore"):  # the lone ones are redone below
        u = u - normals * (u[:, None, :] @ normals[:, :, None])[:, 0]
        u /= np.sqrt((u[:, None, :] @ u[:, :, None])[:, 0])
        v = _cross(normals, u)
        rel = points - centre[:, None, :]
        ang = np.arctan2((rel @ v[:, :, None])[:, :, 0], (rel @ u[:, :, None])[:, :, 0])
    out = np.argsort(ang, axis=1, kind="stable").tolist()
    for i in np.flatnonzero(lone).tolist():
        out[i] = _order_polygon(points[i], normals[i])
    return [list(map(int, o)) for o in out]


def polyhedron_from_planes(
    normals: ArrayLike,
    offsets: ArrayLike,
    *,
    tol: float | None = None,
    merge_fraction: float | None = None,
    bound: tuple[ArrayLike, float] | None = None,
    interior: ArrayLike | None = None,
) -> Polyhedron:
    """The convex polyhedron ``{x : normals · x ≤ offsets}``.

    Parameters
    ----------
    normals
        (m, 3) outward normals (normalised here).
    offsets
        (m,) offsets.
    tol
        Distance (metres) below which vertices are merged; by default ``merge_fraction``
        times the diameter of the raw vertex set.
    merge_fraction
        See :data:`DEFAULT_MERGE_FRACTION`.
    bound
        ``(centre, radius)``: a vertex further than ``radius`` from ``centre`` means the
        planes close only far from where they were touched (nearly parallel sides of an
        unexplored end), reported as open towards that vertex.
    interior
        A point expected inside the polyhedron, where Qhull starts: used when it lies deep
        enough inside (else the Chebyshev centre is found by a linear programme). Part of the
        cache's key, unlike ``bound``: callers that pass a bound usually pass its centre too,
        the middle of where the planes were touched.

    Returns
    -------
    Polyhedron
        With only the planes that carry a face (≥ 3 vertices); ``plane_index`` maps faces
        back to the input planes.

    Raises
    ------
    OpenModelError
        The normals do not positively span R³; ``open_directions`` names the open sides.
    GeometryError
        The half-spaces are empty or flat, or the topology fails Euler's formula.
    """
    if merge_fraction is None:
        merge_fraction = current().geometry.merge_fraction
    n, d = _as_planes(normals, offsets)
    hint = None if interior is None else np.asarray(interior, dtype=float).reshape(-1)
    apart = float(current().features.tolerance_deg)
    key = (
        n.tobytes(),
        d.tobytes(),
        None if hint is None else hint.tobytes(),
        None if tol is None else float(tol),
        float(merge_fraction),
        apart,
    )
    mf = float(merge_fraction)
    built = _BUILT.get(key, lambda: _build(n, d, tol, mf, hint, apart))
    if built.early is not None:
        raise built.early()
    if bound is not None:
        far = _far_directions(built.raw, np.asarray(bound[0], dtype=float), float(bound[1]))
        if far:
            names = ", ".join(_fmt(o) for o, _ in far[:6])
            raise OpenModelError(
                f"the {len(n)} planes close only far from the touched points: open towards "
                f"{names} (explore that side)",
                [o for o, _ in far],
                [v for _, v in far],
            )
    if built.late is not None:
        raise built.late()
    assert built.poly is not None
    return built.poly


@dataclass(frozen=True)
class _Built:
    """What :func:`polyhedron_from_planes` makes of one plane set, before its ``bound`` test:
    the error raised before Qhull (``early``), Qhull's raw vertices, and the polyhedron or the
    error its assembly raised (``late``). Errors are kept as makers, so each raise is new."""

    early: Callable[[], GeometryError] | None
    raw: FloatArray
    poly: Polyhedron | None
    late: Callable[[], GeometryError] | None


_BUILT: Memo[tuple[bytes, bytes, bytes | None, float | None, float, float], _Built] = Memo(
    _BUILT_SIZE
)


def _maker(exc: GeometryError) -> Callable[[], GeometryError]:
    """A function that makes a fresh copy of ``exc`` (same class, message and directions)."""
    if isinstance(exc, OpenModelError):
        message, dirs = str(exc), list(exc.open_directions)
        return lambda: OpenModelError(message, list(dirs))
    cls, message = type(exc), str(exc)
    return lambda: cls(message)


def _frozen(poly: Polyhedron) -> Polyhedron:
    """``poly`` with its arrays read-only: a cached polyhedron is shared by its callers."""
    for name in (
        "vertices",
        "normals",
        "offsets",
        "dihedral_deg",
        "centroid",
        "face_areas",
        "face_centroids",
    ):
        getattr(poly, name).flags.writeable = False
    return poly


MERGE_RETRIES = 3
"""When the merged vertices make no polyhedron (its faces shrank to edges and Euler's formula
fails), :func:`polyhedron_from_planes` merges again within half the distance, at most this
many times: a bar lying on the table, 1 cm across and 40 cm long, has the corners of its end
within 3 % of its diameter, and merged they leave no end face."""


def _build(
    n: FloatArray,
    d: FloatArray,
    tol: float | None,
    merge_fraction: float,
    hint: FloatArray | None,
    apart_deg: float,
) -> _Built:
    """:func:`polyhedron_from_planes` of the normalised planes ``n``, ``d``, without the
    ``bound`` test (made on ``raw`` by the caller)."""
    empty = np.zeros((0, 3))
    opened = open_directions(n)
    if opened:
        names = ", ".join(_fmt(o) for o in opened[:6])
        return _Built(
            _maker(
                OpenModelError(
                    f"the {len(n)} planes do not bound a region: open towards {names} "
                    "(explore that side)",
                    opened,
                )
            ),
            empty,
            None,
            None,
        )
    try:
        centre, radius = _interior_point(n, d, hint)
    except GeometryError as exc:
        return _Built(_maker(exc), empty, None, None)
    scale = max(float(np.abs(d - n @ centre).max()), 1e-12)
    if radius <= 1e-9 * scale:
        return _Built(
            _maker(GeometryError("the planes enclose a flat or empty region (no interior point)")),
            empty,
            None,
            None,
        )
    try:
        hs = HalfspaceIntersection(np.hstack([n, -d[:, None]]), centre)
    except QhullError as exc:  # pragma: no cover - guarded by the checks above
        message = f"Qhull could not intersect the planes: {str(exc).splitlines()[0]}"
        return _Built(_maker(GeometryError(message)), empty, None, None)
    raw = np.asarray(hs.intersections, dtype=float)
    raw.flags.writeable = False
    diam = float(np.ptp(raw, axis=0).max()) if len(raw) else 0.0
    merge = tol if tol is not None else merge_fraction * diam
    first: GeometryError | None = None
    for _ in range(MERGE_RETRIES + 1):
        try:
            poly = _topology(n, d, merge, raw, hs.dual_facets, apart_deg)
        except GeometryError as exc:  # merged into no polyhedron: merge less
            first = first or exc
            merge *= 0.5
            continue
        return _Built(None, raw, _frozen(poly), None)
    assert first is not None
    return _Built(None, raw, None, _maker(first))


def _topology(
    n: FloatArray,
    d: FloatArray,
    merge_tol: float,
    raw: FloatArray,
    facets: list[list[int]],
    apart_deg: float,
) -> Polyhedron:
    """The polyhedron of Qhull's vertices ``raw`` and the planes active at each
    (``facets``): vertices within ``merge_tol`` merged, faces, topology. Vertices on planes
    that face away from each other within ``apart_deg`` are never merged (:func:`opposed`):
    a 30 cm plate's top and bottom corners lie within 3 % of its diameter when it is under
    12.7 mm thick."""
    # tolerance: the exact activity of every plane at every raw vertex, by distance
    diam = float(np.ptp(raw, axis=0).max()) if len(raw) else 0.0
    eps = max(1e-9 * diam, 1e-12)
    # hit[v, p]: plane p passes through raw vertex v (Qhull's facet, or within eps of a member)
    hit = np.abs(raw @ n.T - d[None, :]) <= eps
    sizes = [len(f) for f in facets]
    flat = np.fromiter(itertools.chain.from_iterable(facets), dtype=np.intp, count=sum(sizes))
    hit[np.repeat(np.arange(len(facets)), sizes), flat] = True
    if len(raw) > 1 and merge_tol > 0:  # single linkage: connected components of close pairs
        close = np.linalg.norm(raw[:, None, :] - raw[None, :, :], axis=2) <= merge_tol
        pairs = np.argwhere(np.triu(close, 1))
        apart = pairs[opposed(hit, n, apart_deg, pairs)]  # a plate's top and bottom corners
        close[apart[:, 0], apart[:, 1]] = close[apart[:, 1], apart[:, 0]] = False
        labels = _components(close)
    else:
        labels = np.arange(len(raw))
    k = int(labels.max()) + 1 if len(raw) else 0
    active = np.zeros((k, len(n)), dtype=bool)
    np.logical_or.at(active, labels, hit)
    verts = _cluster_vertices(raw, labels, k, active, n, d, 2 * merge_tol + eps)
    # faces: planes active at ≥ 3 distinct vertices
    kept = active.sum(axis=0) >= 3
    # keep only vertices that lie on ≥ 3 kept faces (a vertex on two is inside an edge)
    corner = (active & kept[None, :]).sum(axis=1) >= 3
    on_face = active & corner[:, None] & kept[None, :]
    face_planes = [int(p) for p in np.flatnonzero(on_face.sum(axis=0) >= 3)]
    # (near-)duplicate planes carry the same vertex set: one face each, the first plane's
    seen: set[bytes] = set()
    unique = []
    for p in face_planes:
        key = np.packbits(on_face[:, p]).tobytes()
        if key not in seen:
            seen.add(key)
            unique.append(p)
    face_planes = unique
    used = np.flatnonzero(on_face[:, face_planes].any(axis=1))
    remap = np.full(k, -1, dtype=np.intp)
    remap[used] = np.arange(len(used))
    vertices = verts[used]
    # each face's vertices counter-clockwise, the faces with as many vertices in one batch
    rows = on_face[:, face_planes].T
    sizes = rows.sum(axis=1)
    faces: list[tuple[int, ...]] = [()] * len(face_planes)
    for m in np.unique(sizes).tolist():
        which = np.flatnonzero(sizes == m)
        idx = remap[np.nonzero(rows[which])[1].reshape(len(which), m)]
        order = _order_polygons(vertices[idx], n[np.asarray(face_planes)[which]])
        for w, ix, o in zip(which.tolist(), idx, order, strict=True):
            faces[w] = tuple(ix[o].tolist())
    return _assemble(vertices, faces, n[face_planes], d[face_planes], tuple(face_planes))


def _assemble(
    vertices: FloatArray,
    faces: list[tuple[int, ...]],
    normals: FloatArray,
    offsets: FloatArray,
    plane_index: tuple[int, ...],
) -> Polyhedron:
    edge_to_faces: dict[tuple[int, int], list[int]] = {}
    for f, poly in enumerate(faces):
        for a, b in zip(poly, poly[1:] + poly[:1], strict=True):
            key = (min(a, b), max(a, b))
            edge_to_faces.setdefault(key, []).append(f)
    bad = [e for e, fs in edge_to_faces.items() if len(fs) != 2]
    if bad:
        raise GeometryError(
            f"the planes give an inconsistent polyhedron: edge {bad[0]} lies on "
            f"{len(edge_to_faces[bad[0]])} faces (try another merge tolerance)"
        )
    edges = tuple(sorted(edge_to_faces))
    edge_faces = tuple((min(edge_to_faces[e]), max(edge_to_faces[e])) for e in edges)
    v_, e_, f_ = len(vertices), len(edges), len(faces)
    if v_ - e_ + f_ != 2:
        raise GeometryError(f"Euler's formula fails: V − E + F = {v_} − {e_} + {f_} ≠ 2")
    ef = np.asarray(edge_faces, dtype=int).reshape(-1, 2)
    cosang = np.clip(np.einsum("ij,ij->i", normals[ef[:, 0]], normals[ef[:, 1]]), -1.0, 1.0)
    dihedral = 180.0 - np.degrees(np.arccos(cosang))
    # areas, centroids, volume by fans: one triangle (f0, fi, fi+1) per face corner
    tri_face = np.asarray(
        [f for f, poly in enumerate(faces) for _ in range(len(poly) - 2)], dtype=int
    )
    tri = np.asarray(
        [(poly[0], poly[i], poly[i + 1]) for poly in faces for i in range(1, len(poly) - 1)],
        dtype=int,
    )
    a0, a1, a2 = vertices[tri[:, 0]], vertices[tri[:, 1]], vertices[tri[:, 2]]
    tri_area = 0.5 * np.einsum("ij,ij->i", _cross(a1 - a0, a2 - a0), normals[tri_face])
    tri_centre = (a0 + a1 + a2) / 3.0
    areas = np.asarray(np.bincount(tri_face, weights=tri_area, minlength=f_), dtype=float)
    fcent = (
        np.stack(
            [
                np.bincount(tri_face, weights=tri_area * tri_centre[:, k], minlength=f_)
                for k in range(3)
            ],
            axis=1,
        )
        / np.where(areas > 0, areas, 1.0)[:, None]
    )
    ref = vertices.mean(axis=0)
    tet = np.einsum("ij,ij->i", a0 - ref, _cross(a1 - ref, a2 - ref)) / 6.0
    vol = float(tet.sum())
    mom = (tet[:, None] * (ref + a0 + a1 + a2) / 4.0).sum(axis=0)
    if vol <= 0:
        raise GeometryError("the polyhedron has no volume")
    return Polyhedron(
        vertices=vertices,
        faces=tuple(faces),
        normals=normals,
        offsets=offsets,
        edges=edges,
        edge_faces=edge_faces,
        dihedral_deg=dihedral,
        volume=float(vol),
        centroid=mom / vol,
        face_areas=areas,
        face_centroids=fcent,
        plane_index=plane_index,
    )


def vertex_covariances(
    poly: Polyhedron, offset_sigma: ArrayLike, normal_sigma_rad: ArrayLike
) -> FloatArray:
    """(V, 3, 3) covariance of each vertex from its faces' plane uncertainties.

    Each vertex is the least-squares point of the planes of its faces; plane ``f`` is off at
    the vertex by its offset error and its tilt error times the distance from the face's
    centroid (``offset_sigma[f]``, ``normal_sigma_rad[f]``: 1σ, one value per face).
    """
    off = np.asarray(offset_sigma, dtype=float).reshape(-1)
    ang = np.asarray(normal_sigma_rad, dtype=float).reshape(-1)
    if off.shape != (len(poly.faces),) or ang.shape != (len(poly.faces),):
        raise UsageError(
            f"need one offset and one normal uncertainty per face ({len(poly.faces)}), "
            f"got {off.shape[0]} and {ang.shape[0]}"
        )
    at: list[list[int]] = [[] for _ in range(len(poly.vertices))]
    for f, face in enumerate(poly.faces):
        for v in face:
            at[v].append(f)
    cov = np.zeros((len(poly.vertices), 3, 3))
    for v, fs in enumerate(at):
        lever = np.linalg.norm(poly.vertices[v] - poly.face_centroids[fs], axis=1)
        var = off[fs] ** 2 + (ang[fs] * lever) ** 2
        a = np.linalg.pinv(poly.normals[fs])
        cov[v] = (a * var[None, :]) @ a.T
    return cov


def face_width(poly: Polyhedron, face: int) -> float:
    """The in-plane width of a polyhedron face: its extent across its longest direction
    (computed once per face of ``poly``)."""
    memo = poly._widths
    if not memo:  # every face's at once: the faces of one size in one batch
        sizes = np.asarray([len(f) for f in poly.faces], dtype=np.intp)
        for m in np.unique(sizes).tolist():
            which = np.flatnonzero(sizes == m)
            if m < 3:
                memo.update(dict.fromkeys(which.tolist(), 0.0))
                continue
            v = poly.vertices[np.asarray([poly.faces[f] for f in which], dtype=np.intp)]
            centred = v - v.sum(axis=1)[:, None, :] / m  # v.mean(axis=1), as before per face
            _, _, vt = np.linalg.svd(centred, full_matrices=False)
            across = (centred @ vt[:, 1][:, :, None])[:, :, 0]
            memo.update(zip(which.tolist(), np.ptp(across, axis=1).tolist(), strict=True))
    return memo[face] if 0 <= face < len(poly.faces) else _face_width(poly, face)


def _face_width(poly: Polyhedron, face: int) -> float:
    """:func:`face_width` of one face, computed alone (an index out of range raises)."""
    v = poly.vertices[list(poly.faces[face])]
    if len(v) < 3:
        return 0.0
    centred = v - v.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    return float(np.ptp(centred @ vt[1]))


def collapse_short_edges(
    poly: Polyhedron,
    offset_sigma: ArrayLike,
    normal_sigma_rad: ArrayLike,
    *,
    sigmas: float = 4.0,
    max_fraction: float = 0.15,
) -> Polyhedron:
    """``poly`` with the edges its planes' uncertainties cannot tell from a point collapsed.

    Four or more noisy planes that should meet in one vertex (an octahedron's) meet in two
    or more vertices joined by short edges, making triangles into 4- and 5-gons. An edge
    shorter than ``sigmas`` times the 1σ uncertainty of its length (its end vertices' errors
    along it, from :func:`vertex_covariances`) and than ``max_fraction`` of the median edge
    length is collapsed: the vertices it joins become one, the least-squares point of all their
    faces' planes, and the faces and edges are rebuilt.

    Parameters
    ----------
    poly
        The polyhedron.
    offset_sigma, normal_sigma_rad
        Per face of ``poly``: the 1σ offset (m) and normal (radians) uncertainty.
    sigmas
        How many σ an edge must be long to stay.
    max_fraction
        Edges at least this fraction of the median edge length always stay: σ from tilted
        planes is large at the far ends of long faces (the top of a tall thin prism), while
        a split vertex leaves an edge far shorter than the others.

    Returns
    -------
    Polyhedron
        ``poly`` itself when no edge is that short (exact planes: σ = 0) or when collapsing
        would not give a valid polyhedron; else the collapsed one.

    Examples
    --------
    >>> import numpy as np
    >>> n = np.vstack([np.eye(3), -np.eye(3), [[0.6, 0.8, 0.0]]])
    >>> d = np.array([0.05, 0.05, 0.05, 0.05, 0.05, 0.05, 0.0699])  # clips one vertical edge
    >>> p = polyhedron_from_planes(n, d, tol=0.0)
    >>> len(p.vertices), len(p.faces)
    (10, 7)
    >>> q = collapse_short_edges(p, np.full(7, 1e-4), np.zeros(7))
    >>> len(q.vertices), len(q.faces)
    (8, 6)
    >>> collapse_short_edges(p, np.zeros(7), np.zeros(7)) is p  # exact planes: unchanged
    True
    """
    if not poly.edges:
        return poly
    cov = vertex_covariances(poly, offset_sigma, normal_sigma_rad)
    e = np.asarray(poly.edges, dtype=np.intp).reshape(-1, 2)
    lengths = poly.edge_lengths()
    u = (poly.vertices[e[:, 1]] - poly.vertices[e[:, 0]]) / np.maximum(lengths, 1e-300)[:, None]
    sig = np.sqrt(np.einsum("ei,eij,ej->e", u, cov[e[:, 0]] + cov[e[:, 1]], u))
    short = (lengths < sigmas * sig) & (lengths < max_fraction * float(np.median(lengths)))
    if short.any():
        short &= ~opposed_edges(poly)  # a plate's thickness is no split vertex
    if not short.any():
        return poly
    close = np.zeros((len(poly.vertices),) * 2, dtype=bool)
    close[e[short, 0], e[short, 1]] = close[e[short, 1], e[short, 0]] = True
    labels = _components(close)
    k = int(labels.max()) + 1
    active = np.zeros((k, len(poly.faces)), dtype=bool)
    for f, face in enumerate(poly.faces):
        active[labels[list(face)], f] = True
    shift = float(lengths[short].max())
    verts = _cluster_vertices(
        poly.vertices, labels, k, active, poly.normals, poly.offsets, 2.0 * shift
    )
    faces: list[tuple[int, ...]] = []
    keep: list[int] = []
    for f, face in enumerate(poly.faces):
        idx = list(dict.fromkeys(int(labels[v]) for v in face))
        if len(idx) < 3:  # the face shrank to an edge or a point
            continue
        order = _order_polygon(verts[idx], poly.normals[f])
        faces.append(tuple(idx[i] for i in order))
        keep.append(f)
    if len(faces) < 4:
        return poly
    try:
        return _assemble(
            verts,
            faces,
            poly.normals[keep],
            poly.offsets[keep],
            tuple(poly.plane_index[f] for f in keep) if poly.plane_index else (),
        )
    except GeometryError:  # collapsing broke the topology: keep the polyhedron as it was
        return poly
