"""Objects to explore: meshes from STL, OBJ, PLY, OFF or glTF (or a trimesh.Trimesh), checked and put on the table.

:func:`load_object` reads a mesh in metres with trimesh, validates it (readable, not empty,
a solid, one object, fits the workspace), cleans it (floating specks dropped, holes filled)
and rests it on the table: the lowest point is moved to z = 0, the orientation and the x–y
position are kept (a mesh that lies outside the workspace, a scan in its scanner's
coordinates, is first centred over the origin). Every problem is one
:class:`~tactile_kb.errors.ObjectError` line naming the file. The input mesh is never
modified: the result is a copy.

Examples
--------
>>> import trimesh
>>> box = trimesh.creation.box((0.1, 0.06, 0.04))
>>> obj = load_object(box)
>>> [round(float(v), 3) for v in obj.bounds[:, 2]]
[0.0, 0.04]
>>> round(float(box.bounds[0, 2]), 3)
-0.02
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from scipy.cluster.hierarchy import DisjointSet

from tactile_kb.errors import ObjectError
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.types import FloatArray

__all__ = [
    "MAX_SIZE",
    "MIN_SIZE",
    "NOTES_KEY",
    "OBJECT_SUFFIXES",
    "SPECK_FRACTION",
    "THIN_FACTOR",
    "UNITS",
    "WORKSPACE_HALF_WIDTH",
    "Y_UP_SUFFIXES",
    "ObjectLike",
    "check_thickness",
    "load_object",
    "min_width",
    "object_name",
]

ObjectLike = trimesh.Trimesh | str | Path
"""What the explorers accept: a mesh, or a path to an STL/OBJ/PLY file."""

OBJECT_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")

Y_UP_SUFFIXES = (".glb", ".gltf")
"""Formats whose up axis is +y (glTF's convention): read with +y turned to +z, the table's up."""

MAX_SIZE = DEFAULTS.objects.max_size
"""Metres: the largest extent an object may have (the motors' range, 2–30 cm objects)."""

MIN_SIZE = DEFAULTS.objects.min_size
"""Metres: an object thinner than this in any direction is degenerate for a 5 mm tip."""

THIN_FACTOR = DEFAULTS.objects.thin_factor
"""An object must be at least this many tip radii wide in every direction (:func:`check_thickness`);
measured: a 5 mm tip classifies a 7.5 mm plate standing on its edge, not a 7 mm one."""

SPECK_FRACTION = DEFAULTS.objects.speck_fraction
"""A separate body whose bounding-box diagonal is under this fraction of the largest body's is a
floating speck (scan debris): it is dropped with a note. Larger second bodies are refused."""

NOTES_KEY = "tactile_kb_notes"
"""Key of ``mesh.metadata`` under which :func:`load_object` lists what it changed (specks
dropped, holes filled, an open mesh kept as it is); explorers copy them into the record."""

WORKSPACE_HALF_WIDTH = DEFAULTS.objects.workspace_half_width
"""Metres: every point of the object must lie within this distance of the z axis in x and y."""


def object_name(obj: ObjectLike) -> str:
    """A name for reports: the path as given, or the mesh's metadata name, or ``"<mesh>"``."""
    if isinstance(obj, str | Path):
        return str(obj)
    meta = getattr(obj, "metadata", None)
    name = meta.get("name") if isinstance(meta, dict) else None
    return str(name) if name else "<mesh>"


def _read(path: Path) -> trimesh.Trimesh:
    """The mesh in ``path``, unprocessed (vertices are merged after the finiteness check)."""
    name = str(path)
    if not path.exists():
        raise ObjectError(f"{name}: no such file")
    suffix = path.suffix.lower()
    if suffix not in OBJECT_SUFFIXES:
        known = ", ".join(OBJECT_SUFFIXES)
        raise ObjectError(f"{name}: unsupported mesh format {path.suffix!r} (use {known})")
    unreadable = f"{name}: not a readable {suffix[1:].upper()} mesh file"
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            loaded: Any = trimesh.load(str(path), force="mesh", process=False)
    except Exception:  # trimesh and numpy raise many kinds on a bad file
        raise ObjectError(unreadable) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ObjectError(f"{unreadable}: no triangles found")
    if suffix in Y_UP_SUFFIXES:  # a quarter turn about x: (x, y, z) -> (x, -z, y)
        loaded.vertices = np.asarray(loaded.vertices, dtype=float) @ np.array(
            [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]
        )
    return loaded


HULL_POINTS = 4000
"""At most this many hull vertices enter the width computation (:func:`min_width`)."""


def min_width(mesh: trimesh.Trimesh) -> float:
    """The smallest width of the mesh's convex hull (over the hull's face normals), metres.

    A dense hull (a scanned sphere has every vertex on it) is first reduced to
    :data:`HULL_POINTS` of its vertices, evenly spread along trimesh's order: the reduced hull
    lies inside the true one, so the width is never overestimated (a thin plate is never let
    through), and it is smaller by at most the spacing's sagitta. The spans are computed in
    blocks of normals, never as one vertices × normals matrix.
    """
    try:
        hull = mesh.convex_hull
        pts = np.asarray(hull.vertices, dtype=float)
        if len(pts) > HULL_POINTS:
            pts = pts[np.linspace(0, len(pts) - 1, HULL_POINTS).astype(np.intp)]
            hull = trimesh.convex.convex_hull(pts)
            pts = np.asarray(hull.vertices, dtype=float)
    except Exception:  # a flat or degenerate point set: Qhull cannot build a hull
        return 0.0
    normals = np.asarray(hull.face_normals, dtype=float)
    if len(normals) == 0:
        return 0.0
    width = np.inf
    for k in range(0, len(normals), 512):
        spans = pts @ normals[k : k + 512].T
        width = min(width, float((spans.max(axis=0) - spans.min(axis=0)).min()))
    return float(width)


def check_thickness(mesh: trimesh.Trimesh, tip_radius: float, *, name: str = "<mesh>") -> None:
    """Raise :class:`~tactile_kb.errors.ObjectError` when the object is too thin for the tip.

    A tip of radius ρ resolves faces only where the object is at least :data:`THIN_FACTOR` × ρ
    wide in every direction (the width of its convex hull): a thinner plate is touched on its
    edges only and comes out open or misclassified.

    Examples
    --------
    >>> plate = trimesh.creation.box((0.05, 0.05, 0.004))
    >>> check_thickness(plate, 0.005, name="plate.stl")
    Traceback (most recent call last):
    ...
    tactile_kb.errors.ObjectError: plate.stl: too thin for the finger: 4 mm across at its thinnest, a tip of radius 5 mm needs at least 7.5 mm
    """
    width = min_width(mesh)
    need = current().objects.thin_factor * tip_radius
    if width < need:
        raise ObjectError(
            f"{name}: too thin for the finger: {width * 1000:.3g} mm across at its thinnest, "
            f"a tip of radius {tip_radius * 1000:.3g} mm needs at least {need * 1000:.3g} mm"
        )


def load_object(obj: ObjectLike, *, name: str | None = None) -> trimesh.Trimesh:
    """Read and check an object; return a copy resting on the table (lowest point at z = 0).

    Parameters
    ----------
    obj
        A ``trimesh.Trimesh`` or a path to an STL, OBJ, PLY, OFF or glTF (``.glb``, ``.gltf``:
        +y up, turned to +z) file, in the units of ``objects.units`` (metres by default).
    name
        The name used in error messages (default: the path, or the mesh's name).

    Raises
    ------
    ObjectError
        Unreadable file, empty mesh, non-finite coordinates, more than one object (bodies
        neither parts of the largest one nor floating specks, :func:`_one_object`), not a solid (a plane, a line, a
        point set: no volume or thinner than :data:`MIN_SIZE`), or larger than the workspace
        (even centred on it).
        The tip's own limit is :func:`check_thickness`.

    Seams closer than ``objects.weld_fraction`` of the size are welded, shells inside the
    object and specks are dropped and holes filled (``trimesh.repair.fill_holes``); a mesh trimesh cannot
    close is explored as it is. Each such change is listed in ``mesh.metadata[NOTES_KEY]``.
    A mesh that reaches beyond the workspace in x or y (a scan in its scanner's coordinates)
    is centred over the origin; the shifts are ``mesh.metadata["moved_xy"]`` and
    ``mesh.metadata["moved_z"]``, and the explorers report them in the record's notes.
    """
    label = name or object_name(obj)
    if isinstance(obj, str | Path):
        mesh = _read(Path(obj))
    elif isinstance(obj, trimesh.Trimesh):
        mesh = obj.copy()
    else:
        raise ObjectError(
            f"{label}: expected a trimesh.Trimesh or a mesh file path, got {type(obj).__name__}"
        )
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise ObjectError(f"{label}: the mesh is empty")
    with np.errstate(all="ignore"):
        finite = bool(np.isfinite(np.asarray(mesh.vertices, dtype=float)).all())
    if not finite:
        raise ObjectError(f"{label}: the mesh has non-finite (NaN or infinite) vertex coordinates")
    units = current().objects.units
    if units != "m":
        mesh.apply_scale(UNITS[units])  # type: ignore[no-untyped-call]
    mesh.process()
    unique = mesh.unique_faces()
    if not bool(unique.all()):  # the same triangle twice (an export glitch, a part pasted twice)
        mesh.update_faces(unique)
    notes: list[str] = []
    if not mesh.is_watertight:
        mesh = _weld(mesh, notes)
    if not mesh.is_watertight:
        mesh = _separate_touching(mesh)
    if int(mesh.body_count) > 1:
        mesh = _one_object(mesh, label, notes)
    extent = mesh.extents
    if float(extent.min()) < current().objects.min_size:
        raise ObjectError(
            f"{label}: not a solid: {float(extent.min()) * 1000:.3g} mm thick "
            f"(at least {current().objects.min_size * 1000:g} mm needed; a single plane, a line or a point set "
            f"cannot be touched all round): degenerate mesh{_units_hint(extent, units)}"
        )
    if not mesh.is_watertight:
        mesh = _close(mesh, notes)
    solid = mesh if mesh.is_watertight else mesh.convex_hull
    signed = _signed_volume(solid)
    volume = abs(signed)
    if not volume >= current().objects.min_size ** 3:  # NaN too
        raise ObjectError(f"{label}: not a solid: degenerate mesh with no volume")
    if float(extent.max()) > current().objects.max_size:
        raise ObjectError(
            f"{label}: larger than the workspace: {float(extent.max()):.3g} m across "
            f"(at most {current().objects.max_size:g} m){_units_hint(extent, units)}"
        )
    half = current().objects.workspace_half_width
    moved_xy = (0.0, 0.0)
    if _reach_xy(mesh) > half:
        # a scan in its scanner's coordinates: its bounding box centred over the origin, where
        # it fits unless the workspace is set narrower than objects.max_size
        lo, hi = mesh.bounds
        moved_xy = (-0.5 * float(lo[0] + hi[0]), -0.5 * float(lo[1] + hi[1]))
        mesh.apply_translation((moved_xy[0], moved_xy[1], 0.0))
        if _reach_xy(mesh) > half:
            lo, hi = mesh.bounds
            raise ObjectError(
                f"{label}: does not fit the workspace (|x|, |y| ≤ {half:g} m) even centred "
                f"on it: {float(hi[0] - lo[0]):.3g} × {float(hi[1] - lo[1]):.3g} m"
            )
    if mesh.is_watertight and signed < 0:  # (solid is mesh)
        mesh.invert()
    if current().objects.rest == "stable":
        mesh = _rest_stable(mesh, solid, notes)
    lo, _ = mesh.bounds
    mesh.apply_translation((0.0, 0.0, -float(lo[2])))
    mesh.metadata["moved_z"] = -float(lo[2])  # reported in the exploration's notes
    mesh.metadata["moved_xy"] = moved_xy  # reported in the notes too
    mesh.metadata["name"] = label
    mesh.metadata[NOTES_KEY] = notes
    return mesh


def _reach_xy(mesh: trimesh.Trimesh) -> float:
    """How far (m) the mesh reaches from the z axis along x or y: the largest |x| or |y| of
    its bounding box."""
    return float(np.abs(np.asarray(mesh.bounds, dtype=float)[:, :2]).max())


UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
"""Metres per unit of the length units a mesh file may be in (setting ``objects.units``)."""
UNIT_NAMES = {"m": "the metre", "cm": "the centimetre", "mm": "the millimetre", "in": "the inch"}


def _rest_stable(
    mesh: trimesh.Trimesh, solid: trimesh.Trimesh, notes: list[str]
) -> trimesh.Trimesh:
    """``mesh`` turned to the most probable pose it comes to rest in when dropped on the table
    (``trimesh.poses.compute_stable_poses`` of ``solid``, the closed mesh or its convex hull,
    with its centre of mass), its centre kept where it was in x and y."""
    if solid.is_watertight and abs(_signed_volume(solid)) > 0:
        centre = np.asarray(solid.center_mass, dtype=float)
    else:
        centre = np.asarray(solid.bounds, dtype=float).mean(axis=0)
    transforms, probs = trimesh.poses.compute_stable_poses(solid.convex_hull, center_mass=centre)
    if len(transforms) == 0:
        return mesh
    best = int(np.argmax(probs))
    turned = np.asarray(transforms[best], dtype=float)
    was = 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    out = mesh.copy()
    out.apply_transform(turned)
    now = 0.5 * (out.bounds[0] + out.bounds[1])
    out.apply_translation((float(was[0] - now[0]), float(was[1] - now[1]), 0.0))
    if not np.allclose(turned[:3, :3], np.eye(3), atol=1e-9):
        down = turned[:3, :3].T @ np.array([0.0, 0.0, -1.0])  # the resting side, as given
        notes.append(
            "turned to rest in its most probable stable pose "
            f"(p = {float(probs[best]):.2f}; it lies on the side facing "
            f"({down[0]:+.2f}, {down[1]:+.2f}, {down[2]:+.2f}) of the mesh as given)"
        )
    return out


WELD_FRACTION = DEFAULTS.objects.weld_fraction
"""Vertices closer than this fraction of the object's diagonal are one vertex when a mesh is
not closed (CAD exports whose seams are a few nanometres apart: robosuite's can)."""


def _weld(mesh: trimesh.Trimesh, notes: list[str]) -> trimesh.Trimesh:
    """``mesh`` with seams closer than ``objects.weld_fraction`` (:data:`WELD_FRACTION`) of
    its size welded, when that joins bodies or closes it; else ``mesh`` as it is."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    size = float(np.linalg.norm(mesh.extents))
    tol = current().objects.weld_fraction * size
    vertices = np.asarray(mesh.vertices, dtype=float)
    pairs = cKDTree(vertices).query_pairs(tol, output_type="ndarray")
    if not size > 0 or len(pairs) == 0:
        return mesh
    n = len(vertices)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    count, group = connected_components(graph, directed=False)
    merged = np.zeros((count, 3))
    np.add.at(merged, group, vertices)
    merged /= np.bincount(group, minlength=count)[:, None]  # each cluster at its mean
    welded = trimesh.Trimesh(merged, group[np.asarray(mesh.faces)], process=False)
    welded.update_faces(welded.nondegenerate_faces())
    welded.remove_unreferenced_vertices()
    welded.process()
    better = welded.is_watertight or int(welded.body_count) < int(mesh.body_count)
    if not better or len(welded.faces) < 0.99 * len(mesh.faces):
        return mesh
    notes.append(f"seams under {tol * 1e6:.2g} µm apart welded (the mesh was not closed)")
    return welded


def _signed_volume(mesh: trimesh.Trimesh) -> float:
    """The signed volume of a closed mesh, Σ v0·(v1 × v2) / 6: trimesh's ``volume`` computes
    all the mass properties (0.2 s on 200k triangles) for it."""
    tri = np.asarray(mesh.triangles, dtype=float)
    with np.errstate(all="ignore"):
        return float(np.einsum("ij,ij->", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))) / 6.0


def _separate_touching(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` with its bodies apart when closed bodies only share vertices or edges (parts
    modelled overlapping, meeting at a corner): trimesh then sees one open body, whose edges
    belong to more than two triangles. Faces are grouped through the edges of exactly two
    triangles; when every group is closed, they are the bodies. Otherwise ``mesh`` as it is."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    inverse = np.asarray(mesh.edges_unique_inverse)
    counts = np.bincount(inverse)
    if not bool((counts > 2).any()):
        return mesh
    faces_of_edge = np.arange(len(inverse)) // 3  # edges come three per face, in order
    order = np.argsort(inverse, kind="stable")
    manifold = counts[inverse[order]] == 2
    pairs = faces_of_edge[order][manifold].reshape(-1, 2)
    n = len(mesh.faces)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    count, group = connected_components(graph, directed=False)
    if count < 2:
        return mesh
    parts = [mesh.submesh([np.flatnonzero(group == k)], append=True) for k in range(count)]
    if not all(isinstance(p, trimesh.Trimesh) and p.is_watertight for p in parts):
        return mesh
    out = trimesh.util.concatenate(parts)
    assert isinstance(out, trimesh.Trimesh)
    return out


MAX_PARTS = 256
"""At most this many bodies of a mesh (the largest) are tried as parts of one object
(:func:`_one_object`); smaller ones can only be specks."""


def _units_hint(extent: FloatArray, units: str) -> str:
    """For a mesh too large or too thin as read in ``units``: the other units in which it
    would be an object the finger can explore (``objects.min_size`` to ``objects.max_size``),
    the likeliest (nearest a 10 cm object) first; "" when there is none."""
    limits = current().objects
    raw = np.asarray(extent, dtype=float) / UNITS[units]
    fits = [
        (abs(math.log(float(raw.max()) * per / 0.1)), unit, float(raw.max()) * per)
        for unit, per in UNITS.items()
        if unit != units
        and limits.min_size <= float(raw.min()) * per
        and float(raw.max()) * per <= limits.max_size
    ]
    if not fits:
        return ""
    ways = " or ".join(f"--units {u} ({size * 100:.3g} cm across)" for _, u, size in sorted(fits))
    unit = UNIT_NAMES[units]
    return f"; if its unit is not {unit}, read it with {ways}, or the setting objects.units"


def _one_object(mesh: trimesh.Trimesh, label: str, notes: list[str]) -> trimesh.Trimesh:
    """The object of a mesh made of several bodies.

    Bodies closer to the largest one (directly or through each other) than
    ``objects.join_fraction`` of its size are parts of one object — a convex decomposition, a
    mug and its handle modelled apart, islands of surface between a scan's holes — and stay,
    closed ones joined by their union (manifold3d). Every other body must be a floating speck
    (under :data:`SPECK_FRACTION` of the size or ``objects.speck_volume_fraction`` of the
    bounding volume), and is dropped; a larger one is a second object, refused. Bodies inside
    the largest one (:func:`_enclosed`: a cavity's wall, a part modelled inside another) are
    dropped first: no finger reaches them.
    """
    limits = current().objects
    bodies = list(mesh.split(only_watertight=False))
    sizes = np.array([float(np.linalg.norm(b.extents)) for b in bodies])
    main = int(np.argmax(sizes))
    inside = _enclosed(bodies, main)
    if inside:
        notes.append(
            f"{len(inside)} shell(s) inside the object dropped (a cavity or an enclosed part: "
            "the finger touches only the outside)"
        )
        gone = set(inside)
        bodies = [b for k, b in enumerate(bodies) if k not in gone]
        if len(bodies) == 1:
            return bodies[0]
        sizes = np.array([float(np.linalg.norm(b.extents)) for b in bodies])
        main = int(np.argmax(sizes))
    volumes = np.array([float(np.prod(b.extents)) for b in bodies])
    reach = limits.join_fraction * sizes[main]
    # only the largest bodies may be parts: a mesh of thousands of loose triangles would
    # otherwise take hours; pairs whose bounding boxes lie further apart than ``reach`` are
    # never measured, nor a pair already joined through others
    candidates = [int(k) for k in np.argsort(-sizes)[:MAX_PARTS]]
    lo = np.asarray([bodies[k].bounds[0] for k in candidates], dtype=float) - reach
    hi = np.asarray([bodies[k].bounds[1] for k in candidates], dtype=float)
    boxes_meet = np.all(lo[:, None, :] <= hi[None, :, :], axis=2)
    boxes_meet &= boxes_meet.T
    joined_up = DisjointSet(candidates)
    for i, j in zip(*np.nonzero(np.triu(boxes_meet, 1)), strict=True):
        a, b = candidates[int(i)], candidates[int(j)]
        if not joined_up.connected(a, b) and _gap(bodies[a], bodies[b], reach) <= reach:
            joined_up.merge(a, b)
    group = sorted(joined_up.subset(main), key=lambda k: (-sizes[k], k))
    others = [k for k in range(len(bodies)) if k not in group]
    large = [
        k
        for k in others
        if sizes[k] >= limits.speck_fraction * sizes[main]
        and volumes[k] >= limits.speck_volume_fraction * volumes[main]
    ]
    if large:
        raise ObjectError(
            f"{label}: the mesh holds {1 + len(large)} separate objects (bodies more than "
            f"{reach * 1000:.2g} mm apart); explore one object at a time"
        )
    if others:
        notes.append(
            f"{len(others)} floating speck(s) dropped (each under {limits.speck_fraction:.0%} "
            f"of the object's size or {limits.speck_volume_fraction:.0%} of its bounding "
            "volume)" + ("; the largest body is explored" if len(group) == 1 else "")
        )
    if len(group) == 1:
        kept: trimesh.Trimesh = bodies[main]
        return kept
    parts = [bodies[k] for k in group]
    joined: trimesh.Trimesh | None = None
    if all(p.is_watertight for p in parts):
        try:
            union = trimesh.boolean.union(parts, engine="manifold")
        except Exception:  # the engine refused the parts: they are kept side by side
            union = None
        if isinstance(union, trimesh.Trimesh) and union.is_watertight and len(union.faces):
            joined = union
    if joined is None:
        together = trimesh.util.concatenate(parts)
        assert isinstance(together, trimesh.Trimesh)
        joined = together
    notes.append(
        f"{len(parts)} parts under {reach * 1000:.2g} mm apart explored as one object"
        + (" (their union)" if joined.is_watertight else "")
    )
    return joined


ENCLOSED_POINTS = 200
"""At most this many vertices of a body are tested inside the object (:func:`_enclosed`)."""


def _enclosed(bodies: list[trimesh.Trimesh], outer: int) -> list[int]:
    """The bodies that lie inside the closed body ``bodies[outer]``: a cavity's inner wall (a
    hollow part's, its triangles facing inwards) or a part modelled inside another, which no
    finger reaches. Each is judged on at most :data:`ENCLOSED_POINTS` of its vertices, all of
    them tested in one call of trimesh's ray test."""
    shell = bodies[outer]
    if not shell.is_watertight:
        return []
    lo, hi = shell.bounds
    which, points = [], []
    for k, body in enumerate(bodies):
        blo, bhi = body.bounds
        if k == outer or bool(np.any(blo < lo) or np.any(bhi > hi)):
            continue
        pts = np.asarray(body.vertices, dtype=float)
        if len(pts) > ENCLOSED_POINTS:
            pts = pts[np.linspace(0, len(pts) - 1, ENCLOSED_POINTS).astype(int)]
        which.append(k)
        points.append(pts)
    if not which:
        return []
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inside = np.asarray(shell.contains(np.vstack(points)), dtype=bool)
    ends = np.cumsum([len(p) for p in points])
    return [k for k, part in zip(which, np.split(inside, ends[:-1]), strict=True) if part.all()]


def _gap(a: trimesh.Trimesh, b: trimesh.Trimesh, reach: float) -> float:
    """The distance between bodies ``a`` and ``b`` (from at most 2000 vertices of each to the
    other's surface; 0 when closed bodies share volume, :func:`_overlap`), or infinity when
    their bounding boxes are further apart than ``reach``."""
    (alo, ahi), (blo, bhi) = a.bounds, b.bounds
    if bool(np.any(alo - reach > bhi) or np.any(blo - reach > ahi)):
        return math.inf
    if a.is_watertight and b.is_watertight and _overlap(a, b):
        return 0.0  # the pieces of a convex decomposition, say: neither's vertices need be near
    best = math.inf
    for one, other in ((a, b), (b, a)):
        pts = np.asarray(one.vertices, dtype=float)
        if len(pts) > 2000:
            pts = pts[np.linspace(0, len(pts) - 1, 2000).astype(int)]
        _, dist, _ = trimesh.proximity.closest_point(other, pts)  # type: ignore[no-untyped-call]
        best = min(best, float(np.min(dist)))
    return best


def _overlap(a: trimesh.Trimesh, b: trimesh.Trimesh) -> bool:
    """Whether closed bodies ``a`` and ``b`` share volume (their intersection, by manifold3d)."""
    (alo, ahi), (blo, bhi) = a.bounds, b.bounds
    if bool(np.any(alo >= bhi) or np.any(blo >= ahi)):
        return False
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a body with no volume has no centre of mass
            common = trimesh.boolean.intersection([a, b], engine="manifold")
    except Exception:  # the engine refused them: their distance decides
        return False
    return isinstance(common, trimesh.Trimesh) and len(common.faces) > 0 and bool(common.volume > 0)


def _close(mesh: trimesh.Trimesh, notes: list[str]) -> trimesh.Trimesh:
    """``mesh`` with its holes filled by trimesh when it can; else as it is, with a note."""
    repaired = mesh.copy()
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        trimesh.repair.fill_holes(repaired)
    if repaired.is_watertight:
        notes.append("holes in the mesh filled (trimesh.repair.fill_holes)")
        return repaired
    trimesh.repair.fix_normals(mesh)  # type: ignore[no-untyped-call]
    uses = np.bincount(mesh.edges_unique_inverse)
    flaws = [
        f"{count} {what}"
        for count, what in (
            (int(np.sum(uses == 1)), "boundary edges trimesh cannot fill"),
            (int(np.sum(uses > 2)), "edges shared by more than two triangles"),
        )
        if count
    ]
    notes.append(
        f"the mesh is not closed ({', '.join(flaws) or 'trimesh finds it not watertight'}); "
        "explored as it is"
    )
    return mesh
