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

from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from tactile_kb.errors import ObjectError

__all__ = [
    "MAX_SIZE",
    "MIN_SIZE",
    "OBJECT_SUFFIXES",
    "WORKSPACE_HALF_WIDTH",
    "ObjectLike",
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
    name = str(path)
    if not path.exists():
        raise ObjectError(f"{name}: no such file")
    if path.suffix.lower() not in OBJECT_SUFFIXES:
        known = ", ".join(OBJECT_SUFFIXES)
        raise ObjectError(f"{name}: unsupported mesh format {path.suffix!r} (use {known})")
    try:
        loaded: Any = trimesh.load(str(path), force="mesh", process=True)
    except Exception as exc:  # trimesh raises many kinds on a bad file
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ObjectError(f"{name}: cannot read mesh: {msg}") from None
    if not isinstance(loaded, trimesh.Trimesh):
        raise ObjectError(f"{name}: cannot read mesh: no triangles found")
    return loaded


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
        Unreadable file, empty mesh, open (not watertight) mesh, degenerate (no volume or thinner
        than :data:`MIN_SIZE`), non-finite coordinates, or larger than the workspace.
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
    if not np.isfinite(mesh.vertices).all():
        raise ObjectError(f"{label}: the mesh has non-finite vertex coordinates")
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
    mesh.metadata["name"] = label
    return mesh
