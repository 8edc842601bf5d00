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

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import HalfspaceIntersection, QhullError

from tactile_kb.errors import GeometryError, OpenModelError, UsageError

__all__ = ["DEFAULT_MERGE_FRACTION", "Polyhedron", "open_directions", "polyhedron_from_planes"]

FloatArray = NDArray[np.float64]

DEFAULT_MERGE_FRACTION = 0.03
"""Vertices closer than this fraction of the object's diameter are merged into one.

Noisy planes that should meet in one vertex (a pyramid's apex, the four-face vertices of an
octahedron) meet in a cluster of nearby vertices a millimetre or two apart; 3 % of the
diameter (3 mm for a 10 cm object) merges them while keeping real edges."""


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
    candidates: list[FloatArray] = []
    # line space of the cone: null space of the normals, both senses
    _, s, vt = np.linalg.svd(n)
    rank = int((s > 1e-9).sum())
    for row in vt[rank:]:
        candidates += [row, -row]
    i, j = np.triu_indices(len(n), 1)
    cross = np.cross(n[i], n[j])
    length = np.linalg.norm(cross, axis=1)
    good = length > 1e-9
    cross = cross[good] / length[good][:, None]
    # only the rays inside the cone can be open directions: test them all at once
    both = np.vstack([cross, -cross])
    inside = both[(both @ n.T <= tol).all(axis=1)] if len(both) else both
    candidates += list(inside)
    # when the cone is a half-space or wedge with one bounding plane, its rays include
    # directions inside single planes; the axes cover the remaining generic cases
    candidates += [np.array(v, dtype=float) for v in np.vstack([np.eye(3), -np.eye(3)])]
    out: list[FloatArray] = []
    for c in candidates:
        if (n @ c <= tol).all() and not any(float(c @ o) > 1.0 - 1e-6 for o in out):
            out.append(c)
    if not out:
        return []
    # a direction strictly blocked by none of the planes exists whenever the cone is not {0}
    return [
        (round(float(x), 6) + 0.0, round(float(y), 6) + 0.0, round(float(z), 6) + 0.0)
        for x, y, z in out
    ]


def _fmt(d: tuple[float, float, float]) -> str:
    return "(" + ", ".join(f"{round(v, 2) + 0.0:+.2f}" for v in d) + ")"


def _far_directions(
    raw: FloatArray, centre: FloatArray, radius: float
) -> list[tuple[float, float, float]]:
    rel = raw - centre
    dist = np.linalg.norm(rel, axis=1)
    out: list[FloatArray] = []
    for i in np.argsort(-dist):
        if dist[i] <= radius:
            break
        d = rel[i] / dist[i]
        if not any(float(d @ o) > math.cos(math.radians(30.0)) for o in out):
            out.append(d)
    return [
        (round(float(x), 6) + 0.0, round(float(y), 6) + 0.0, round(float(z), 6) + 0.0)
        for x, y, z in out
    ]


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
    """The centre and radius of the largest ball inside ``n · x ≤ d``."""
    c = np.zeros(4)
    c[3] = -1.0
    a = np.hstack([n, np.ones((len(n), 1))])
    res = linprog(c, A_ub=a, b_ub=d, bounds=[(None, None)] * 3 + [(0.0, None)], method="highs")
    if res.status == 2:
        raise GeometryError("the planes enclose no region (their half-spaces do not intersect)")
    if res.status != 0:
        raise GeometryError(f"cannot find a point inside the planes: {res.message}")
    return np.asarray(res.x[:3], dtype=float), float(res.x[3])


def _order_polygon(points: FloatArray, normal: FloatArray) -> list[int]:
    """Indices ordering ``points`` counter-clockwise seen from the side ``normal`` points to."""
    centre = points.mean(axis=0)
    u = points[0] - centre
    if np.linalg.norm(u) < 1e-15:
        u = np.cross(normal, [1.0, 0.0, 0.0])
        if np.linalg.norm(u) < 1e-9:
            u = np.cross(normal, [0.0, 1.0, 0.0])
    u = u - normal * (u @ normal)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    rel = points - centre
    ang = np.arctan2(rel @ v, rel @ u)
    return [int(i) for i in np.argsort(ang, kind="stable")]


def _least_squares_point(n: FloatArray, d: FloatArray, fallback: FloatArray) -> FloatArray:
    if len(n) >= 3:
        a = n.T @ n
        if np.linalg.cond(a) < 1e8:
            return np.asarray(np.linalg.solve(a, n.T @ d), dtype=float)
    return fallback


def polyhedron_from_planes(
    normals: ArrayLike,
    offsets: ArrayLike,
    *,
    tol: float | None = None,
    merge_fraction: float = DEFAULT_MERGE_FRACTION,
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
    n, d = _as_planes(normals, offsets)
    opened = open_directions(n)
    if opened:
        names = ", ".join(_fmt(o) for o in opened[:6])
        raise OpenModelError(
            f"the {len(n)} planes do not bound a region: open towards {names} (explore that side)",
            opened,
        )
    centre, radius = _interior_point(n, d, interior)
    scale = max(float(np.abs(d - n @ centre).max()), 1e-12)
    if radius <= 1e-9 * scale:
        raise GeometryError("the planes enclose a flat or empty region (no interior point)")
    try:
        hs = HalfspaceIntersection(np.hstack([n, -d[:, None]]), centre)
    except QhullError as exc:  # pragma: no cover - guarded by the checks above
        raise GeometryError(
            f"Qhull could not intersect the planes: {str(exc).splitlines()[0]}"
        ) from None
    raw = np.asarray(hs.intersections, dtype=float)
    if bound is not None:
        far = _far_directions(raw, np.asarray(bound[0], dtype=float), float(bound[1]))
        if far:
            names = ", ".join(_fmt(o) for o in far[:6])
            raise OpenModelError(
                f"the {len(n)} planes close only far from the touched points: open towards "
                f"{names} (explore that side)",
                far,
            )
    active_raw = [{int(i) for i in f} for f in hs.dual_facets]
    # tolerance: the exact activity of every plane at every raw vertex, by distance
    diam = float(np.ptp(raw, axis=0).max()) if len(raw) else 0.0
    merge_tol = tol if tol is not None else merge_fraction * diam
    eps = max(1e-9 * diam, 1e-12)
    if len(raw) > 1 and merge_tol > 0:  # single linkage: connected components of close pairs
        close = np.linalg.norm(raw[:, None, :] - raw[None, :, :], axis=2) <= merge_tol
        _, labels = connected_components(csr_matrix(close), directed=False)
    else:
        labels = np.arange(len(raw))
    k = int(labels.max()) + 1 if len(raw) else 0
    active: list[set[int]] = [set() for _ in range(k)]
    near = np.abs(raw @ n.T - d[None, :]) <= eps
    for i, lab in enumerate(labels):
        active[lab] |= active_raw[i]
        active[lab] |= {int(j) for j in np.flatnonzero(near[i])}
    verts = np.zeros((k, 3))
    for lab in range(k):
        members = raw[labels == lab]
        act = sorted(active[lab])
        verts[lab] = _least_squares_point(n[act], d[act], members.mean(axis=0))
        if np.linalg.norm(verts[lab] - members.mean(axis=0)) > 2 * merge_tol + eps:
            verts[lab] = members.mean(axis=0)
    # faces: planes active at ≥ 3 distinct vertices
    on_plane: dict[int, list[int]] = {}
    for v, planes in enumerate(active):
        for p in planes:
            on_plane.setdefault(p, []).append(v)
    face_planes = sorted(p for p, vs in on_plane.items() if len(vs) >= 3)
    # keep only vertices that lie on ≥ 3 kept faces (a vertex on two is inside an edge)
    kept = set(face_planes)
    corner = {v for v, planes in enumerate(active) if len(planes & kept) >= 3}
    for p in face_planes:
        on_plane[p] = [v for v in on_plane[p] if v in corner]
    face_planes = [p for p in face_planes if len(on_plane[p]) >= 3]
    # (near-)duplicate planes carry the same vertex set: one face each
    seen: set[frozenset[int]] = set()
    unique = []
    for p in face_planes:
        key = frozenset(on_plane[p])
        if key not in seen:
            seen.add(key)
            unique.append(p)
    face_planes = unique
    used = sorted({v for p in face_planes for v in on_plane[p]})
    remap = {v: i for i, v in enumerate(used)}
    vertices = verts[used]
    faces: list[tuple[int, ...]] = []
    for p in face_planes:
        idx = [remap[v] for v in on_plane[p]]
        order = _order_polygon(vertices[idx], n[p])
        faces.append(tuple(idx[o] for o in order))
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
    tri_area = 0.5 * np.einsum("ij,ij->i", np.cross(a1 - a0, a2 - a0), normals[tri_face])
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
    tet = np.einsum("ij,ij->i", a0 - ref, np.cross(a1 - ref, a2 - ref)) / 6.0
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
