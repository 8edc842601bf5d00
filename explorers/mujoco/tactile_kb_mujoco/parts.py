"""Split an object mesh into the convex parts MuJoCo collides with.

MuJoCo collides a mesh geom through its convex hull, so a non-convex object must be given as
several convex geoms. Four cases, tried in order:

* a convex mesh is one part, its own hull (``kind="mesh"``);
* an *orthogonal* mesh, whose face normals all lie along three mutually perpendicular axes (the
  paper's unions of rectangular parallelepipeds, in any rotation), is split **exactly** into
  boxes: the distinct vertex coordinates along each axis cut space into a grid, the cells whose
  centre lies inside the mesh (generalised winding number) are kept, and runs of cells are
  merged greedily into as few boxes as the greedy sweep finds (``kind="box"``);
* a *nearly convex* mesh, a convex solid with the imperfections of a scan (vertex noise,
  dents, relief, ripples), is one part, its convex hull, when no concavity under the hull is
  deeper than ``concavity_tol`` *as the tip feels it* (:func:`felt_concavity`): the tip of
  radius ρ rests on the surface around a hollow and reaches into it only as far as the
  hollow's width lets it. Decomposing such a mesh would take CoACD tens of seconds and cut
  its faces into dozens of pieces whose seams the finger then meets;
* any other mesh goes through CoACD (approximate convex decomposition, ``kind="mesh"``).

Meshes MuJoCo cannot take raise :class:`~tactile_kb.errors.ObjectError` with one line: empty,
non-finite, degenerate (no volume), or a convex part whose hull has more vertices than
``max_hull_vertices``.

Examples
--------
>>> import trimesh
>>> [p.kind for p in convex_parts(trimesh.creation.box((0.04, 0.02, 0.01)))]
['mesh']
>>> from tactile_kb.solids import l_shape
>>> ell = l_shape(0.06, 0.05, 0.02, 0.03)
>>> parts = convex_parts(ell)  # 6 × 2 cm and 2 × 3 cm arms, 3 cm high: 54 cm³
>>> [p.kind for p in parts], round(sum(p.volume for p in parts) * 1e6, 3)
(['box', 'box'], 54.0)
>>> c = felt_concavity(ell, 0.005)  # the L's notch: 1 cm deep under the hull, a smooth surface
>>> round(c.depth * 1000, 1), c.roughness
(10.0, 0.0)
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial import ConvexHull, cKDTree

from tactile_kb.errors import ObjectError

__all__ = [
    "CONCAVITY_RHO",
    "MAX_HULL_VERTICES",
    "ROUGHNESS_SIGMAS",
    "Concavity",
    "ConvexPart",
    "convex_parts",
    "felt_concavity",
    "orthogonal_frame",
    "winding_number",
]

MAX_HULL_VERTICES = 10_000
"""Hull vertices above which a part is refused: MuJoCo's collision cost grows with them."""

CONCAVITY_RHO = 1.0
"""Tip radii: a mesh whose concavities a tip reaches no deeper than this (beyond its
roughness, :data:`ROUGHNESS_SIGMAS`) is collided as its convex hull (:func:`convex_parts`)."""

ROUGHNESS_SIGMAS = 6.0
"""The convex hull of a rough surface rests on its highest points: a surface with vertex noise
σ lies about 4σ under the hull of a few thousand vertices, and a tip resting on its
neighbours about 2σ less. Concavities up to this many roughness σ deeper are the surface's
roughness, not its shape."""

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ConvexPart:
    """One convex piece of the object, in world coordinates.

    ``kind="box"``: a box of half-extents ``size`` centred at ``centre`` whose axes are the
    columns of ``rotation``. ``kind="mesh"``: the convex hull of ``vertices``.
    """

    kind: Literal["box", "mesh"]
    centre: FloatArray
    size: FloatArray = field(default_factory=lambda: np.zeros(3))
    rotation: FloatArray = field(default_factory=lambda: np.eye(3))
    vertices: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def volume(self) -> float:
        """Volume of the part, cubic metres."""
        if self.kind == "box":
            return float(8.0 * np.prod(self.size))
        return float(trimesh.convex.convex_hull(self.vertices).volume)


def _check_mesh(mesh: trimesh.Trimesh, name: str) -> None:
    if len(mesh.faces) == 0 or len(mesh.vertices) < 4:
        raise ObjectError(f"{name}: the mesh is empty (MuJoCo needs a closed solid)")
    if not np.isfinite(mesh.vertices).all():
        raise ObjectError(f"{name}: the mesh has non-finite vertex coordinates")
    extent = float(np.ptp(mesh.vertices, axis=0).max())
    if extent <= 0.0:
        raise ObjectError(f"{name}: the mesh is degenerate (all vertices coincide)")
    centred = np.asarray(mesh.vertices, dtype=float) - np.asarray(mesh.vertices).mean(axis=0)
    spread = np.linalg.svd(centred, compute_uv=False)
    if spread[-1] <= 1e-9 * spread[0]:
        raise ObjectError(
            f"{name}: the mesh is degenerate (flat: its vertices span no volume), "
            "MuJoCo cannot collide with it"
        )


def orthogonal_frame(mesh: trimesh.Trimesh, *, tol_deg: float = 1e-3) -> FloatArray | None:
    """Three perpendicular unit axes (columns) carrying every face normal, or ``None``.

    The first axis is the normal of the largest face; the frame is right-handed.
    """
    normals = np.asarray(mesh.face_normals, dtype=float)
    areas = np.asarray(mesh.area_faces, dtype=float)
    ok = areas > 0
    normals, areas = normals[ok], areas[ok]
    if len(normals) == 0:
        return None
    cos_tol = np.cos(np.radians(tol_deg))
    sin_tol = np.sin(np.radians(tol_deg))
    a = normals[int(np.argmax(areas))]
    rest = normals[np.abs(normals @ a) < sin_tol]
    if len(rest) == 0:
        return None
    b = rest[0] - (rest[0] @ a) * a
    b /= np.linalg.norm(b)
    c = np.cross(a, b)
    frame = np.column_stack([a, b, c])
    if (np.abs(normals @ frame).max(axis=1) < cos_tol).any():
        return None
    return frame


def winding_number(mesh: trimesh.Trimesh, points: FloatArray) -> FloatArray:
    """Generalised winding number of a closed mesh at each point (1 inside, 0 outside).

    The sum of the signed solid angles of the triangles (Van Oosterom and Strackee), which is
    exact for any point off the surface, whatever the ray geometry.
    """
    tri = np.asarray(mesh.triangles, dtype=float)  # (T, 3, 3)
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    a = tri[None, :, 0, :] - p[:, None, :]
    b = tri[None, :, 1, :] - p[:, None, :]
    c = tri[None, :, 2, :] - p[:, None, :]
    la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
    num = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
    den = (
        la * lb * lc
        + np.einsum("ptk,ptk->pt", a, b) * lc
        + np.einsum("ptk,ptk->pt", b, c) * la
        + np.einsum("ptk,ptk->pt", c, a) * lb
    )
    return np.asarray(np.arctan2(num, den).sum(axis=1) / (2.0 * np.pi), dtype=float)


def _levels(values: FloatArray, tol: float) -> FloatArray:
    """Sorted distinct values, merging those closer than ``tol``."""
    v = np.sort(values)
    out = [v[0]]
    for x in v[1:]:
        if x - out[-1] > tol:
            out.append(x)
    return np.asarray(out, dtype=float)


def _box_parts(mesh: trimesh.Trimesh, frame: FloatArray, max_cells: int) -> list[ConvexPart]:
    local = np.asarray(mesh.vertices, dtype=float) @ frame  # coordinates along the axes
    tol = 1e-9 * max(1.0, float(np.abs(local).max()))
    grids = [_levels(local[:, k], tol) for k in range(3)]
    shape = tuple(len(g) - 1 for g in grids)
    if int(np.prod(shape)) > max_cells:
        raise ObjectError(
            f"the orthogonal mesh cuts into {int(np.prod(shape))} grid cells "
            f"(more than {max_cells}); simplify it"
        )
    mids = [(g[1:] + g[:-1]) / 2.0 for g in grids]
    cx, cy, cz = np.meshgrid(*mids, indexing="ij")
    centres = np.column_stack([cx.ravel(), cy.ravel(), cz.ravel()]) @ frame.T
    inside = (winding_number(mesh, centres) > 0.5).reshape(shape)
    parts: list[ConvexPart] = []
    todo = inside.copy()
    # Greedy merge: grow each first free cell along x, then y, then z while the whole slab is
    # inside and still free.
    for i, j, k in zip(*np.nonzero(todo), strict=True):
        if not todo[i, j, k]:
            continue
        i1 = i + 1
        while i1 < shape[0] and todo[i1, j, k]:
            i1 += 1
        j1 = j + 1
        while j1 < shape[1] and todo[i:i1, j1, k].all():
            j1 += 1
        k1 = k + 1
        while k1 < shape[2] and todo[i:i1, j:j1, k1].all():
            k1 += 1
        todo[i:i1, j:j1, k:k1] = False
        lo = np.array([grids[0][i], grids[1][j], grids[2][k]])
        hi = np.array([grids[0][i1], grids[1][j1], grids[2][k1]])
        parts.append(
            ConvexPart(
                kind="box",
                centre=frame @ ((lo + hi) / 2.0),
                size=(hi - lo) / 2.0,
                rotation=frame.copy(),
            )
        )
    return parts


def _surface_points(mesh: trimesh.Trimesh, spacing: float) -> FloatArray:
    """The mesh's vertices, plus the centres of triangles with an edge longer than ``spacing``
    (a coarse mesh's large faces may sink under the hull away from their corners)."""
    v = np.asarray(mesh.vertices, dtype=float)
    tri = np.asarray(mesh.triangles, dtype=float)
    if len(tri) == 0:
        return v
    edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2).max(axis=1)
    return np.vstack([v, tri[edges > spacing].mean(axis=1)])


def _hull_depths(points: FloatArray, equations: FloatArray, chunk_cells: int) -> FloatArray:
    """Distance of each point inside a convex hull to its boundary (0 on or outside it).

    For a point inside a convex polytope, the distance to the boundary is the least distance
    to a facet's plane; computed in chunks of points so that no (points × facets) matrix
    larger than ``chunk_cells`` is built.
    """
    normals, offsets = equations[:, :3], equations[:, 3]
    out = np.empty(len(points))
    step = max(1, chunk_cells // max(1, len(equations)))
    for i in range(0, len(points), step):
        signed = points[i : i + step] @ normals.T + offsets  # ≤ 0 inside each facet's plane
        out[i : i + step] = np.maximum(0.0, -signed.max(axis=1))
    return out


@dataclass(frozen=True)
class Concavity:
    """How far a tip reaches under a mesh's convex hull (:func:`felt_concavity`), metres.

    ``depth`` is the deepest reach found (when the search stopped early, only a lower bound
    above its ``stop_above``); ``roughness`` is the surface's own small-scale roughness, the
    median spread (standard deviation) of the depths under the hull among the points within a
    tip radius of each other: vertex noise of σ gives about σ, a smooth surface 0.
    """

    depth: float
    roughness: float


def _thinned(points: FloatArray, depth: FloatArray, cell: float) -> tuple[FloatArray, FloatArray]:
    """The deepest and the shallowest point of each cube of side ``cell``."""
    keys = np.floor(points / cell).astype(np.int64)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    group = group.ravel()
    order = np.lexsort((depth, group))  # by cube, shallowest first
    g = group[order]
    first = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    last = np.r_[first[1:] - 1, len(order) - 1]
    keep = np.unique(np.concatenate([order[first], order[last]]))
    return points[keep], depth[keep]


def felt_concavity(
    mesh: trimesh.Trimesh,
    tip_radius: float,
    *,
    roughness_sigmas: float | None = None,
    stop_above: float = np.inf,
    chunk_cells: int = 4_000_000,
    samples: int = 400,
    max_points: int = 20_000,
) -> Concavity:
    """How deep under its convex hull a tip of radius ``tip_radius`` reaches into ``mesh``.

    Each surface point p lies at depth δ(p) under the hull (its distance to the hull's
    boundary). A sphere of radius ρ lowered onto p rests on the surface points q around it:
    standing on q, at distance r ≤ ρ from p across the surface (|p − q|² = r² + (δ(p) −
    δ(q))²), its lowest point stays ρ − √(ρ² − r²) below q, so it reaches p's hollow to depth
    min_q (δ(q) + ρ − √(ρ² − r²)) at most (q = p included). The
    largest such depth over the surface is returned with the surface's roughness
    (:class:`Concavity`): vertex noise, embossed letters and narrow grooves give little, a wide
    dent its depth, a real notch (an L-shape's) its full depth.

    Only points deeper than every answer so far are examined; the search stops as soon as a
    depth above ``stop_above`` (plus ``roughness_sigmas`` times the roughness, when given) is
    found, the answer then being only a lower bound. The roughness is measured on ``samples``
    points chosen with a fixed seed. Memory stays within ``chunk_cells`` numbers per step,
    whatever the mesh's size; a surface of more than ``max_points`` points is thinned to the
    deepest and the shallowest point of each cube of ρ/4 (the hollows and the points a tip
    rests on), which can only overstate the depth, by about a tenth of ρ at most.
    """
    rho = float(tip_radius)
    if rho <= 0:
        raise ValueError(f"tip_radius must be > 0, got {tip_radius}")
    pts = _surface_points(mesh, rho)
    try:
        hull = ConvexHull(np.asarray(mesh.vertices, dtype=float))
    except Exception as exc:  # qhull refuses flat or degenerate point sets
        raise ObjectError(f"the mesh has no convex hull: {str(exc).splitlines()[0]}") from None
    depth = _hull_depths(pts, np.asarray(hull.equations, dtype=float), chunk_cells)
    if len(pts) > max_points:
        pts, depth = _thinned(pts, depth, rho / 4.0)
    tree = cKDTree(pts)
    rng = np.random.default_rng(0)
    some = rng.choice(len(pts), size=min(samples, len(pts)), replace=False)
    spreads = [
        float(np.std(depth[near]))
        for near in tree.query_ball_point(pts[some], rho)
        if len(near) > 3
    ]
    roughness = float(np.median(spreads)) if spreads else 0.0
    limit = stop_above + (roughness_sigmas or 0.0) * roughness
    order = np.argsort(-depth)
    worst = 0.0
    block = 512
    for i in range(0, len(order), block):
        idx = order[i : i + block]
        idx = idx[depth[idx] > worst]
        if len(idx) == 0:
            break  # every remaining point is shallower than the answer already found
        found = tree.query_ball_point(pts[idx], rho)
        counts = np.fromiter((len(f) for f in found), dtype=np.intp, count=len(found))
        p = np.repeat(idx, counts)
        q = np.fromiter(itertools.chain.from_iterable(found), dtype=np.intp, count=len(p))
        # Distance across the surface: the depth difference is the normal component.
        r2 = np.sum((pts[q] - pts[p]) ** 2, axis=1) - (depth[q] - depth[p]) ** 2
        reach = depth[q] + rho - np.sqrt(np.clip(rho * rho - r2, 0.0, None))
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        worst = max(worst, float(np.minimum.reduceat(reach, starts).max()))
        if worst > limit:
            break
    return Concavity(worst, roughness)


def _coacd_parts(
    mesh: trimesh.Trimesh, threshold: float, seed: int, options: Mapping[str, Any]
) -> list[ConvexPart]:
    import coacd

    coacd.set_log_level("error")
    kwargs: dict[str, Any] = {"preprocess_mode": "off"} | dict(options)
    pieces = coacd.run_coacd(
        coacd.Mesh(np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=int)),
        threshold=threshold,
        seed=seed,
        **kwargs,
    )
    parts = []
    for vertices, _faces in pieces:
        v = np.asarray(vertices, dtype=float)
        parts.append(ConvexPart(kind="mesh", centre=v.mean(axis=0), vertices=v))
    return parts


def _nearly_convex(mesh: trimesh.Trimesh, name: str, tip_radius: float | None, tol: float) -> bool:
    if tip_radius is None or tol <= 0:
        return False
    try:
        c = felt_concavity(mesh, tip_radius, roughness_sigmas=ROUGHNESS_SIGMAS, stop_above=tol)
    except ObjectError as exc:
        raise ObjectError(f"{name}: {exc}") from None
    return c.depth <= tol + ROUGHNESS_SIGMAS * c.roughness


def convex_parts(
    mesh: trimesh.Trimesh,
    *,
    name: str = "object",
    max_hull_vertices: int = MAX_HULL_VERTICES,
    max_cells: int = 20_000,
    coacd_threshold: float = 0.05,
    coacd_options: Mapping[str, Any] | None = None,
    seed: int = 0,
    tip_radius: float | None = None,
    concavity_tol: float = 0.0,
) -> tuple[ConvexPart, ...]:
    """The convex parts of ``mesh`` (world coordinates), exact for convex and orthogonal meshes.

    Parameters
    ----------
    mesh
        A closed mesh (not modified).
    name
        What error messages call the object.
    max_hull_vertices
        A part whose convex hull has more vertices raises :class:`ObjectError`.
    max_cells
        Largest grid an orthogonal mesh may cut into.
    coacd_threshold
        CoACD's concavity threshold for meshes that are neither convex nor orthogonal.
    coacd_options
        Further keyword arguments of ``coacd.run_coacd`` (e.g. ``mcts_iterations``).
    seed
        CoACD's random seed (the decomposition is deterministic for a seed).
    tip_radius, concavity_tol
        A mesh that is neither convex nor orthogonal is taken as its convex hull (one part)
        when a tip of radius ``tip_radius`` reaches no deeper than ``concavity_tol`` metres
        under the hull beyond the surface's roughness (:func:`felt_concavity`: depth ≤
        ``concavity_tol`` + :data:`ROUGHNESS_SIGMAS` × roughness); without a tip radius, or
        with a tolerance of 0, it always goes through CoACD.
    """
    _check_mesh(mesh, name)
    frame = orthogonal_frame(mesh)
    if mesh.is_convex:
        parts = [
            ConvexPart(
                kind="mesh",
                centre=np.asarray(mesh.vertices, dtype=float).mean(axis=0),
                vertices=np.asarray(mesh.vertices, dtype=float).copy(),
            )
        ]
    elif frame is not None:
        try:
            return tuple(_box_parts(mesh, frame, max_cells))
        except ObjectError as exc:
            raise ObjectError(f"{name}: {exc}") from None
    elif _nearly_convex(mesh, name, tip_radius, concavity_tol):
        v = np.asarray(mesh.vertices, dtype=float)
        hull_v = v[np.unique(np.asarray(ConvexHull(v).simplices))]
        parts = [ConvexPart(kind="mesh", centre=hull_v.mean(axis=0), vertices=hull_v)]
    else:
        parts = _coacd_parts(mesh, coacd_threshold, seed, coacd_options or {})
    for part in parts:
        n_hull = len(trimesh.convex.convex_hull(part.vertices).vertices)
        if n_hull > max_hull_vertices:
            raise ObjectError(
                f"{name}: a convex part has {n_hull} hull vertices, more than MuJoCo is "
                f"given here ({max_hull_vertices}); simplify the mesh"
            )
    return tuple(parts)
