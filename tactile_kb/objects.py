"""Objects to explore: meshes from STL, OBJ or PLY (or a trimesh.Trimesh), checked and put on the table.

:func:`load_object` reads a mesh in metres with trimesh, validates it (readable, not empty,
watertight, no degenerate volume, fits the workspace) and rests it on the table: the lowest
point is moved to z = 0, the orientation and the x–y position are kept. Every problem is one
:class:`~tactile_kb.errors.ObjectError` line naming the file. The input mesh is never modified:
the result is a copy.

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

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from tactile_kb.errors import ObjectError

__all__ = [
    "MAX_SIZE",
    "MIN_SIZE",
    "OBJECT_SUFFIXES",
    "THIN_FACTOR",
    "WORKSPACE_HALF_WIDTH",
    "ObjectLike",
    "check_thickness",
    "load_object",
    "object_name",
]

ObjectLike = trimesh.Trimesh | str | Path
"""What the explorers accept: a mesh, or a path to an STL/OBJ/PLY file."""

OBJECT_SUFFIXES = (".stl", ".obj", ".ply")

MAX_SIZE = 0.6
"""Metres: the largest extent an object may have (the motors' range, 2–30 cm objects)."""

MIN_SIZE = 0.002
"""Metres: an object thinner than this in any direction is degenerate for a 5 mm tip."""

THIN_FACTOR = 1.5
"""An object must be at least this many tip radii wide in every direction (:func:`check_thickness`);
measured: a 5 mm tip classifies a 7.5 mm plate standing on its edge, not a 7 mm one."""

WORKSPACE_HALF_WIDTH = 0.5
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
    return loaded


def _min_width(mesh: trimesh.Trimesh) -> float:
    """The smallest width of the mesh's convex hull (over the hull's face normals), metres."""
    try:
        hull = mesh.convex_hull
    except Exception:  # a flat or degenerate point set: Qhull cannot build a hull
        return 0.0
    pts = np.asarray(hull.vertices, dtype=float)
    normals = np.asarray(hull.face_normals, dtype=float)
    if len(normals) == 0:
        return 0.0
    spans = pts @ normals.T
    return float((spans.max(axis=0) - spans.min(axis=0)).min())


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
    width = _min_width(mesh)
    need = THIN_FACTOR * tip_radius
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
        A ``trimesh.Trimesh`` or a path to an STL, OBJ or PLY file, in metres.
    name
        The name used in error messages (default: the path, or the mesh's name).

    Raises
    ------
    ObjectError
        Unreadable file, empty mesh, non-finite coordinates, more than one body, open (not
        watertight) mesh, degenerate (no volume or thinner than :data:`MIN_SIZE`), or larger
        than the workspace. The tip's own limit is :func:`check_thickness`.
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
    mesh.process()
    bodies = int(mesh.body_count)
    if bodies > 1:
        raise ObjectError(
            f"{label}: the mesh holds {bodies} separate bodies; explore one object at a time"
        )
    extent = mesh.extents
    if float(extent.min()) < MIN_SIZE:
        raise ObjectError(
            f"{label}: degenerate mesh: {float(extent.min()) * 1000:.3g} mm thick "
            f"(at least {MIN_SIZE * 1000:g} mm needed)"
        )
    if not mesh.is_watertight:
        raise ObjectError(f"{label}: the mesh is open (not watertight); close it first")
    volume = abs(float(mesh.volume))
    if volume < MIN_SIZE**3:
        raise ObjectError(f"{label}: degenerate mesh: no volume")
    if float(extent.max()) > MAX_SIZE:
        raise ObjectError(
            f"{label}: larger than the workspace: {float(extent.max()):.3g} m across "
            f"(at most {MAX_SIZE:g} m; is the mesh in millimetres?)"
        )
    lo, hi = mesh.bounds
    if (
        max(abs(float(lo[0])), abs(float(lo[1])), abs(float(hi[0])), abs(float(hi[1])))
        > WORKSPACE_HALF_WIDTH
    ):
        raise ObjectError(
            f"{label}: lies outside the workspace (|x|, |y| ≤ {WORKSPACE_HALF_WIDTH:g} m); "
            "move it near the origin"
        )
    if float(mesh.volume) < 0:
        mesh.invert()
    mesh.apply_translation((0.0, 0.0, -float(lo[2])))
    mesh.metadata["moved_z"] = -float(lo[2])  # reported in the exploration's notes
    mesh.metadata["name"] = label
    return mesh
