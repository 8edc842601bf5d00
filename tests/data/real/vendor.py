"""Rebuild the vendored real meshes of this folder from the packages they come from.

Run once by hand (never by the tests), with the two wheels unpacked into ``SOURCE``::

    pip download --no-deps pybullet==3.2.7 robosuite==1.5.2 -d wheels
    mkdir src && cd src && for w in ../wheels/*.whl; do unzip -oq "$w"; done
    python tests/data/real/vendor.py src

Each mesh is read as its package ships it, scaled to metres as the package's own URDF or
MJCF file scales it, its coincident vertices merged (OBJ files split them by texture
coordinate), turned to rest on a face, decimated when it has more than ``MAX_TRIANGLES``
triangles (``fast_simplification`` through trimesh), and written as binary PLY.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
MAX_TRIANGLES = 2000

# name, file inside the unpacked wheels, scale (from the package's URDF/MJCF), rotation
# (axis, degrees) to a resting pose
OBJECTS: list[tuple[str, str, tuple[float, float, float], tuple[tuple[int, int, int], float]]] = [
    ("jenga_block", "pybullet_data/jenga/jenga.obj", (0.15, 0.05, 0.03), ((1, 0, 0), 0.0)),
    ("toy_prism", "pybullet_data/toys/prism.obj", (1.0, 1.0, 1.0), ((1, 0, 0), 90.0)),
    ("toy_half_cylinder", "pybullet_data/toys/cylinder.obj", (1.0, 1.0, 1.0), ((1, 0, 0), 180.0)),
    ("duck", "pybullet_data/duck.obj", (0.05, 0.05, 0.05), ((1, 0, 0), 90.0)),
    (
        "cereal_box",
        "robosuite/models/assets/objects/meshes/cereal.stl",
        (1.0, 1.0, 1.0),
        ((1, 0, 0), 0.0),
    ),
    ("can", "robosuite/models/assets/objects/meshes/can.stl", (1.0, 1.0, 1.0), ((1, 0, 0), 0.0)),
    (
        "milk_carton",
        "robosuite/models/assets/objects/meshes/milk.stl",
        (0.9, 0.9, 0.9),
        ((1, 0, 0), 0.0),
    ),
    (
        "lemon",
        "robosuite/models/assets/objects/meshes/lemon.stl",
        (1.5, 1.0, 1.0),
        ((1, 0, 0), 0.0),
    ),
]


def vendor(
    source: Path,
    name: str,
    rel: str,
    scale: tuple[float, float, float],
    turn: tuple[tuple[int, int, int], float],
) -> trimesh.Trimesh:
    loaded = trimesh.load(str(source / rel), force="mesh", process=False)
    mesh = trimesh.Trimesh(
        np.asarray(loaded.vertices) * np.asarray(scale), loaded.faces, process=True
    )
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    if not mesh.is_watertight:  # seams a few µm apart (robosuite's can): weld them
        mesh.merge_vertices(merge_tex=True, merge_norm=True, digits_vertex=6)
        mesh.update_faces(mesh.nondegenerate_faces())
        mesh.remove_unreferenced_vertices()
    axis, angle = turn
    if angle:
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.radians(angle), axis))
    if len(mesh.faces) > MAX_TRIANGLES:
        mesh = mesh.simplify_quadric_decimation(face_count=MAX_TRIANGLES)
    trimesh.repair.fix_normals(mesh)
    lo, hi = mesh.bounds
    mesh.apply_translation((-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]))
    if not (mesh.is_watertight and mesh.body_count == 1):
        raise SystemExit(f"{name}: not one closed body after vendoring")
    return mesh


def main(argv: list[str]) -> None:
    source = Path(argv[0])
    for name, rel, scale, turn in OBJECTS:
        mesh = vendor(source, name, rel, scale, turn)
        out = HERE / f"{name}.ply"
        mesh.export(str(out), encoding="binary")
        ", ".join(f"{v * 100:.1f}" for v in mesh.extents)


if __name__ == "__main__":
    main(sys.argv[1:])
