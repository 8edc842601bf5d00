"""Scan-like imperfections of ideal solids: what a real object's mesh looks like to the finger.

Public scans of grocery boxes and cans, CAD parts and simulator toys are not the ideal
polyhedra of :mod:`tactile_kb.solids`: their faces carry ripples and vertex noise of a few
tenths of a millimetre, bumps and bulges, printed or embossed relief up to a millimetre,
rounded edges (radius up to about 10 % of an edge), small holes where the scanner saw nothing,
and floating specks of stray points. :func:`perturb` adds these to a watertight mesh resting
on the table, deterministically from a seed, at one of three :data:`LEVELS` (or with a
:class:`Perturbation` of one's own):

=====  ===========  ==========  ==========  ===============  =====  ======
level  vertex σ     rounding    bumps       relief (letters) holes  specks
=====  ===========  ==========  ==========  ===============  =====  ======
1      0.2 mm       3 % edge    3 × 0.3 mm  none             0      0
2      0.5 mm       6 % edge    5 × 0.6 mm  0.5 mm on 1 face 0      0
3      1.0 mm       10 % edge   8 × 1.0 mm  1.0 mm on 2 faces 2     2
=====  ===========  ==========  ==========  ===============  =====  ======

"Edge" is the shortest edge between two faces of the solid (its sharp edges: the polyhedron's
edges, a cylinder's rims). Rounding keeps a convex solid convex: each vertex of the subdivided
surface is moved to distance r from the solid shrunk by r (every plane moved inwards by r), so
faces stay flat and exactly where they were, and each edge becomes a cylinder of radius r. Non-convex solids (blocks made of boxes) are not rounded.
Vertex noise, bumps and relief displace vertices along their normals after the surface is
subdivided fine enough to carry them; the face resting on the table stays flat at z = 0.
Holes remove the triangles within a few millimetres of random points on the sides (the mesh is
then open); specks are tiny closed bodies a centimetre or two off the object.

Examples
--------
>>> from tactile_kb.solids import box
>>> ideal = box(0.08, 0.06, 0.04)
>>> scan = perturb(ideal, 2, seed=1)
>>> bool(scan.is_watertight), scan.body_count, len(scan.faces) > 1000
(True, 1, True)
>>> [round(float(v), 3) for v in scan.extents]  # within a millimetre or two of the box
[0.083, 0.063, 0.043]
>>> bool(perturb(ideal, 2, seed=1).vertices.tolist() == scan.vertices.tolist())  # by seed
True
>>> holed = perturb(ideal, 3, seed=1)
>>> bool(holed.is_watertight), holed.body_count
(False, 3)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import NDArray

from tactile_kb.errors import UsageError
from tactile_kb.geometry.planes import nearest_points
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import Finger
from tactile_kb.touch.synthetic import mesh_faces

__all__ = ["LEVELS", "Perturbation", "perturb", "rounded", "sharp_edge_length", "touch_record"]

FloatArray = NDArray[np.float64]

SHARP_DEG = 20.0
"""Two adjacent triangles whose normals differ by more than this meet at a sharp edge."""


@dataclass(frozen=True)
class Perturbation:
    """How a solid is made to look scanned (lengths in metres).

    Attributes
    ----------
    noise
        σ of the Gaussian displacement of each vertex along its normal.
    rounding
        Radius of the rounded edges as a fraction of the solid's shortest sharp edge.
    bumps, bump_height
        Number of smooth bumps (Gaussian, as wide as a fifth of the object) and their height;
        half of them are dents.
    relief, relief_height
        Faces carrying embossed letters, and the letters' height.
    holes, hole_radius
        Holes cut in the sides (the mesh is then open) and their radius.
    specks, speck_radius
        Floating specks (small separate bodies) and their radius.
    resolution
        Largest triangle edge after subdivision, as a fraction of the object's smallest extent
        (the mesh also never exceeds about ``max_triangles``).
    max_triangles
        Bound on the subdivided mesh's size.
    """

    noise: float = 0.0
    rounding: float = 0.0
    bumps: int = 0
    bump_height: float = 0.0
    relief: int = 0
    relief_height: float = 0.0
    holes: int = 0
    hole_radius: float = 0.002
    specks: int = 0
    speck_radius: float = 0.0015
    resolution: float = 0.04
    max_triangles: int = 15_000


LEVELS: dict[int, Perturbation] = {
    1: Perturbation(noise=0.0002, rounding=0.03, bumps=3, bump_height=0.0003),
    2: Perturbation(
        noise=0.0005, rounding=0.06, bumps=5, bump_height=0.0006, relief=1, relief_height=0.0005
    ),
    3: Perturbation(
        noise=0.001,
        rounding=0.10,
        bumps=8,
        bump_height=0.001,
        relief=2,
        relief_height=0.001,
        holes=2,
        specks=2,
    ),
}
"""The three levels of :func:`perturb`: 1 a careful scan, 2 a typical one, 3 a poor one."""


def sharp_edge_length(mesh: trimesh.Trimesh, *, sharp_deg: float = SHARP_DEG) -> float:
    """Length (m) of the solid's shortest sharp edge: the shortest chain of mesh edges between
    two faces meeting at more than ``sharp_deg``, measured as the distance between the edge's
    two polyhedron vertices (vertices where three or more sharp edges meet). A solid whose
    sharp edges have no corners (a cylinder's rims) gives its smallest extent."""
    sharp = mesh.face_adjacency_angles > math.radians(sharp_deg)
    edges = mesh.face_adjacency_edges[sharp]
    if len(edges) == 0:
        return float(mesh.extents.min())
    degree = np.bincount(edges.ravel(), minlength=len(mesh.vertices))
    corners = set(np.flatnonzero(degree >= 3).tolist())
    # walk each chain of sharp edges from one corner to the next
    nbrs: dict[int, list[int]] = {}
    for a, b in edges.tolist():
        nbrs.setdefault(a, []).append(b)
        nbrs.setdefault(b, []).append(a)
    best = math.inf
    v = mesh.vertices
    for c in corners:
        for nxt in nbrs[c]:
            prev, cur = c, nxt
            for _ in range(len(edges)):
                if cur in corners or len(nbrs[cur]) != 2:
                    break
                prev, cur = cur, next(n for n in nbrs[cur] if n != prev)
            if cur != c:
                best = min(best, float(np.linalg.norm(v[cur] - v[c])))
    if not math.isfinite(best):  # closed rims without corners (a cylinder's)
        best = float(mesh.extents.min())
    return best


def rounded(mesh: trimesh.Trimesh, radius: float, *, iterations: int = 60) -> trimesh.Trimesh:
    """A convex ``mesh`` with every edge rounded to ``radius`` (m), faces kept where they are.

    Each vertex ``x`` moves to ``q + radius · (x − q)/|x − q|``, ``q`` its nearest point of the
    solid shrunk by ``radius`` (every plane moved inwards; found by Dykstra's alternating
    projections): a vertex inside a face stays where it is, one near an edge moves onto the
    edge's cylinder of radius ``radius``, a corner onto a ball. The triangles are kept, so a
    watertight mesh stays watertight; subdivide it first for a smooth rounding. A non-convex
    mesh, or a radius too large for the solid, raises :class:`~tactile_kb.errors.UsageError`.
    """
    if not mesh.is_convex:
        raise UsageError("only a convex solid can be rounded")
    if radius <= 0:
        return mesh.copy()
    normals, offsets = _planes(mesh)
    inner = offsets - radius
    centre = np.asarray(mesh.center_mass, dtype=float)
    if (normals @ centre - inner).max() >= 0:
        raise UsageError(f"a rounding radius of {radius * 1000:.3g} mm is too large for the solid")
    x = np.asarray(mesh.vertices, dtype=float)
    # most vertices violate one shrunk plane only: their nearest point is on that plane
    over = x @ normals.T - inner
    worst = over.argmax(axis=1)
    q = x - np.maximum(over[np.arange(len(x)), worst], 0.0)[:, None] * normals[worst]
    hard = np.flatnonzero((q @ normals.T - inner).max(axis=1) > 1e-12)
    if len(hard):
        near = np.flatnonzero((over[hard] > -radius).any(axis=0))  # planes that can matter
        q[hard] = nearest_points(x[hard], normals[near], inner[near], iterations=iterations)
    away = x - q
    length = np.linalg.norm(away, axis=1)
    ok = length > 1e-12
    v = x.copy()
    v[ok] = q[ok] + radius * away[ok] / length[ok, None]
    return trimesh.Trimesh(v, mesh.faces, process=False)


def _planes(mesh: trimesh.Trimesh) -> tuple[FloatArray, FloatArray]:
    """The distinct planes of a convex mesh: unit outward normals (k, 3) and offsets (k,)."""
    n = np.asarray(mesh.face_normals, dtype=float)
    d = np.einsum("ij,ij->i", n, mesh.triangles[:, 0])
    key = np.round(np.column_stack([n, d / max(float(mesh.scale), 1e-12)]), 6)
    _, first = np.unique(key, axis=0, return_index=True)
    return n[np.sort(first)], d[np.sort(first)]


def perturb(mesh: trimesh.Trimesh, level: int | Perturbation, *, seed: int = 0) -> trimesh.Trimesh:
    """``mesh`` (watertight, resting on z = 0) made to look scanned; see the module's table.

    Parameters
    ----------
    mesh
        An ideal solid, e.g. from :mod:`tactile_kb.solids`. It is not modified.
    level
        1, 2 or 3 (:data:`LEVELS`), or a :class:`Perturbation`.
    seed
        The same seed gives the same mesh.
    """
    if isinstance(level, Perturbation):
        p = level
    elif level in LEVELS:
        p = LEVELS[level]
    else:
        raise UsageError(f"level must be 1, 2 or 3 or a Perturbation, got {level!r}")
    if not mesh.is_watertight:
        raise UsageError("perturb needs a watertight mesh")
    rng = np.random.default_rng(seed)
    out = _subdivide(mesh, p)
    if p.rounding > 0 and mesh.is_convex and _has_sharp_edges(mesh):
        out = rounded(out, p.rounding * sharp_edge_length(mesh))
    on_table = out.vertices[:, 2] <= 1e-9
    normals = np.asarray(out.vertex_normals, dtype=float)
    shift = np.zeros(len(out.vertices))
    if p.noise > 0:
        shift += rng.normal(0.0, p.noise, len(shift))
    size = float(np.linalg.norm(out.extents))
    if p.bumps and p.bump_height > 0:
        shift += _bumps(out, rng, p.bumps, p.bump_height, 0.2 * size)
    if p.relief and p.relief_height > 0:
        shift += _relief(out, rng, p.relief, p.relief_height)
    v = out.vertices + shift[:, None] * normals
    v[on_table, 2] = 0.0  # the face on the table stays on it
    out = trimesh.Trimesh(v, out.faces, process=False)
    out.apply_translation((0.0, 0.0, -float(out.bounds[0, 2])))
    if p.holes:
        out = _holes(out, rng, p.holes, p.hole_radius)
    if p.specks:
        out = _specks(out, rng, p.specks, p.speck_radius)
    return out


def _has_sharp_edges(mesh: trimesh.Trimesh) -> bool:
    return bool((mesh.face_adjacency_angles > math.radians(SHARP_DEG)).any())


def _subdivide(mesh: trimesh.Trimesh, p: Perturbation) -> trimesh.Trimesh:
    edge = p.resolution * float(mesh.extents.min())
    # equilateral triangles of edge e cover e²·√3/4 each; bisection ends between e/2 and e
    edge = max(edge, 2.0 * math.sqrt(4.0 / math.sqrt(3.0) * float(mesh.area) / p.max_triangles))
    v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge=edge)  # type: ignore[no-untyped-call]
    return trimesh.Trimesh(v, f, process=True)


def _surface_points(
    mesh: trimesh.Trimesh, rng: np.random.Generator, count: int, *, sides_only: bool = True
) -> tuple[FloatArray, FloatArray]:
    """``count`` random points (and their face normals) on the surface, off the table face."""
    weights = np.asarray(mesh.area_faces, dtype=float).copy()
    if sides_only:
        weights[mesh.face_normals[:, 2] < -0.9] = 0.0
    tri = rng.choice(len(weights), size=count, p=weights / weights.sum())
    r = rng.random((count, 2))
    flip = r.sum(axis=1) > 1
    r[flip] = 1 - r[flip]
    t = mesh.triangles[tri]
    pts = t[:, 0] + r[:, :1] * (t[:, 1] - t[:, 0]) + r[:, 1:] * (t[:, 2] - t[:, 0])
    return np.asarray(pts, dtype=float), np.asarray(mesh.face_normals[tri], dtype=float)


def _bumps(
    mesh: trimesh.Trimesh, rng: np.random.Generator, count: int, height: float, width: float
) -> FloatArray:
    centres, _ = _surface_points(mesh, rng, count)
    sign = np.where(np.arange(count) % 2 == 0, 1.0, -1.0)
    d2 = ((mesh.vertices[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
    sigma = max(width / 2.0, 1e-6)
    return np.asarray((height * sign[None, :] * np.exp(-d2 / (2 * sigma**2))).sum(axis=1))


# Strokes of block letters in a unit cell (x0, y0, x1, y1): "T", "K" (as bars), "B" (as bars).
_LETTERS = (
    ((0.0, 0.8, 1.0, 1.0), (0.4, 0.0, 0.6, 0.8)),
    ((0.0, 0.0, 0.2, 1.0), (0.2, 0.4, 0.6, 0.6), (0.6, 0.6, 0.8, 1.0), (0.6, 0.0, 0.8, 0.4)),
    ((0.0, 0.0, 0.2, 1.0), (0.2, 0.8, 0.8, 1.0), (0.2, 0.4, 0.8, 0.6), (0.2, 0.0, 0.8, 0.2)),
)


def _relief(
    mesh: trimesh.Trimesh, rng: np.random.Generator, faces: int, height: float
) -> FloatArray:
    """Embossed block letters on ``faces`` of the mesh's largest flat regions (not the base)."""
    shift = np.zeros(len(mesh.vertices))
    facets = [
        (float(a), n, f)
        for a, n, f in zip(mesh.facets_area, mesh.facets_normal, mesh.facets, strict=True)
        if n[2] > -0.9
    ]
    facets.sort(key=lambda t: -t[0])
    for _, normal, tris in facets[:faces]:
        verts = np.unique(mesh.faces[tris])
        pts = mesh.vertices[verts]
        u = np.cross(normal, [0.0, 0.0, 1.0] if abs(normal[2]) < 0.9 else [1.0, 0.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(normal, u)
        uv = np.column_stack([(pts - pts.mean(0)) @ u, (pts - pts.mean(0)) @ w])
        lo, hi = uv.min(0), uv.max(0)
        cell = 0.6 * float(min(hi - lo)) / 1.0
        text = rng.permutation(len(_LETTERS))[:2]
        start = (lo + hi) / 2 - np.array([cell * 1.1, cell / 2])
        inside = np.zeros(len(verts), dtype=bool)
        for k, letter in enumerate(text):
            origin = start + np.array([k * cell * 1.2, 0.0])
            for x0, y0, x1, y1 in _LETTERS[int(letter)]:
                a = origin + cell * np.array([x0, y0]) * np.array([0.9, 1.0])
                b = origin + cell * np.array([x1, y1]) * np.array([0.9, 1.0])
                inside |= (uv >= a).all(1) & (uv <= b).all(1)
        shift[verts[inside]] += height
    return shift


def _holes(
    mesh: trimesh.Trimesh, rng: np.random.Generator, count: int, radius: float
) -> trimesh.Trimesh:
    centres, _ = _surface_points(mesh, rng, count)
    tc = mesh.triangles_center
    d = np.linalg.norm(tc[:, None, :] - centres[None, :, :], axis=2).min(axis=1)
    keep = d > radius
    out = trimesh.Trimesh(mesh.vertices, mesh.faces[keep], process=False)
    out.remove_unreferenced_vertices()
    return out


def _specks(
    mesh: trimesh.Trimesh, rng: np.random.Generator, count: int, radius: float
) -> trimesh.Trimesh:
    lo, hi = mesh.bounds
    parts = [mesh]
    for _ in range(count):
        side = rng.integers(2)
        at = np.array([rng.uniform(lo[0], hi[0]), rng.uniform(lo[1], hi[1]), 0.0])
        gap = float(rng.uniform(0.01, 0.02))
        at[side] = hi[side] + gap if rng.random() < 0.5 else lo[side] - gap
        at[2] = float(rng.uniform(radius, hi[2]))
        speck = trimesh.creation.icosphere(subdivisions=1, radius=radius)
        speck.apply_translation(at)
        parts.append(speck)
    out = trimesh.util.concatenate(parts)
    assert isinstance(out, trimesh.Trimesh)
    return out


def touch_record(
    mesh: trimesh.Trimesh,
    ideal: trimesh.Trimesh,
    finger: Finger,
    *,
    per_face: int = 6,
    total: int | None = None,
    noise: float = 0.0,
    seed: int = 0,
    margin: float = 0.05,
    name: str = "",
) -> ExplorationRecord:
    """Contacts of the finger tip on a scanned ``mesh``, approached along ``ideal``'s faces.

    The ground truth of :func:`tactile_kb.touch.synthetic.sample_record`, but on the real surface:
    for ``per_face`` points drawn on each face of the ideal solid (except the one on the
    table, triangles shrunk by ``margin``), the tip moves along the face's inward normal from
    outside until it touches ``mesh`` (its centre at distance ρ); the contact reports the
    sensor nearest to the true direction from the centre to the touched point (contacts no
    sensor feels are dropped) and every sensor whose cone holds it. With ``total``, that many
    points are drawn over all faces by area instead (for curved solids of many small faces). So contacts near a rounded
    edge report a tilted direction, and bumps and relief move the tip centre. Gaussian noise of
    σ ``noise`` is added to each centre.
    """
    rng = np.random.default_rng(seed)
    rho = finger.radius
    probes: list[FloatArray] = []
    normals: list[FloatArray] = []
    size = float(np.linalg.norm(ideal.extents))
    faces = [
        (normal, tris)
        for normal, tris in mesh_faces(ideal)
        if not (
            normal[2] < -0.999
            and float(np.abs(ideal.vertices[ideal.faces[tris]][..., 2]).max()) <= 1e-9
        )
    ]
    if total is not None and faces:
        areas = np.array([ideal.area_faces[t].sum() for _, t in faces])
        counts = rng.multinomial(total, areas / areas.sum())
    else:
        counts = np.full(len(faces), per_face)
    for (normal, tris), count in zip(faces, counts, strict=True):
        if count == 0:
            continue
        tri = ideal.triangles[tris]
        area = ideal.area_faces[tris]
        pick = rng.choice(len(tris), size=count, p=area / area.sum())
        r = rng.random((count, 2))
        flip = r.sum(axis=1) > 1
        r[flip] = 1 - r[flip]
        t = tri[pick]
        pts = t[:, 0] + r[:, :1] * (t[:, 1] - t[:, 0]) + r[:, 1:] * (t[:, 2] - t[:, 0])
        centre = t.mean(axis=1)
        probes.append(centre + (1.0 - margin) * (pts - centre))
        normals.append(np.repeat(normal[None, :], count, axis=0))
    contacts: list[Contact] = []
    if probes:
        p0 = np.vstack(probes)
        n = np.vstack(normals)
        centres, touched = _approach(mesh, p0 + (rho + 0.1 * size) * n, -n, rho, 0.1 * size + rho)
        for c, q, ok in zip(centres, touched, np.isfinite(centres[:, 0]), strict=True):
            if not ok:
                continue
            d = q - c
            d /= np.linalg.norm(d)
            direction = (float(d[0]), float(d[1]), float(d[2]))
            sensor = finger.nearest(direction)
            if sensor is None:
                continue
            cc = c + rng.normal(0.0, noise, 3) if noise > 0 else c
            r0 = finger.directions[sensor]
            contacts.append(
                Contact(
                    step=len(contacts),
                    centre=(float(cc[0]), float(cc[1]), float(cc[2])),
                    sensors=finger.fired([direction]),
                    sensor=sensor,
                    direction=r0,
                    point=(
                        float(cc[0] + rho * r0[0]),
                        float(cc[1] + rho * r0[1]),
                        float(cc[2] + rho * r0[2]),
                    ),
                    kind="touch",
                    phase="synthetic",
                )
            )
    return ExplorationRecord(
        object=name,
        explorer="synthetic",
        finger=finger.name,
        tip_radius=rho,
        sensor_directions=list(finger.directions),
        seed=seed,
        noise=float(noise),
        params={"per_face": float(per_face), "quantise": 1.0},
        contacts=contacts,
        path=[c.centre for c in contacts],
        contacts_per_phase={"synthetic": len(contacts)} if contacts else {},
        complete=True,
    )


def _approach(
    mesh: trimesh.Trimesh, start: FloatArray, direction: FloatArray, rho: float, reach: float
) -> tuple[FloatArray, FloatArray]:
    """Move spheres of radius ``rho`` from ``start`` along ``direction`` until they touch the
    mesh: their centres and touched points (NaN rows for those that touch nothing within
    ``reach``). Marches in steps of ρ/4, then bisects to 1 µm."""
    m = len(start)
    step = rho / 4.0
    lo = np.zeros(m)
    hi = np.full(m, np.nan)
    t = np.zeros(m)
    active = np.ones(m, dtype=bool)
    while active.any() and float(t[active].min()) <= reach:
        idx = np.flatnonzero(active)
        _, dist, _ = trimesh.proximity.closest_point(
            mesh, start[idx] + t[idx, None] * direction[idx]
        )  # type: ignore[no-untyped-call]
        hit = dist <= rho
        hi[idx[hit]] = t[idx[hit]]
        lo[idx[~hit]] = t[idx[~hit]]
        active[idx[hit]] = False
        t[idx[~hit]] += step
        active &= t <= reach
    found = np.isfinite(hi)
    idx = np.flatnonzero(found)
    while len(idx) and float((hi[idx] - lo[idx]).max()) > 1e-6:
        mid = (lo[idx] + hi[idx]) / 2
        _, dist, _ = trimesh.proximity.closest_point(
            mesh, start[idx] + mid[:, None] * direction[idx]
        )  # type: ignore[no-untyped-call]
        hit = dist <= rho
        hi[idx[hit]] = mid[hit]
        lo[idx[~hit]] = mid[~hit]
    centres = np.full((m, 3), np.nan)
    touched = np.full((m, 3), np.nan)
    if len(idx):
        centres[idx] = start[idx] + hi[idx, None] * direction[idx]
        q, _, _ = trimesh.proximity.closest_point(mesh, centres[idx])  # type: ignore[no-untyped-call]
        touched[idx] = q
    return centres, touched
