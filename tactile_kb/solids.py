"""Test objects: watertight trimesh meshes in metres, resting on the table z = 0.

Every builder returns a new watertight :class:`trimesh.Trimesh` whose lowest point is at
z = 0 and whose bounding box is centred on the z axis (x = y = 0), resting on a face (the
sphere rests on its lowest point). Convex solids are convex hulls of known vertices, so the
ground truth (faces, edges, vertices, angles) is known independently of the modelling code.

The 33-sensor finger feels a face only when some sensor's cone contains the direction from
the tip centre to the face, and no sensor looks upwards: faces that overhang (outward normal
pointing below the horizon) by more than about 12° are not felt at every azimuth. The
builders therefore keep overhangs small (the nonrectangular parallelepiped is sheared by
10° at most by default; the octahedron's three lower faces overhang by 19.47° and are felt
only when their azimuths line up with the equator sensors, which :func:`fig5_objects` does).

Examples
--------
>>> m = box(0.1, 0.06, 0.04)
>>> bool(m.is_watertight), float(m.bounds[0][2]), [round(float(v), 3) for v in m.extents]
(True, 0.0, [0.1, 0.06, 0.04])
>>> [name for name, _, _ in fig5_objects()][:4]
['OCTA', 'CUBE1', 'CUBE2', 'TETRA']
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely.geometry
import shapely.ops
import trimesh
from numpy.typing import ArrayLike

from tactile_kb.errors import UsageError

__all__ = [
    "FIG5_LABELS",
    "box",
    "box_union",
    "cylinder",
    "fig5_objects",
    "frustum",
    "l_shape",
    "octahedron",
    "parallelepiped",
    "place",
    "prism",
    "pyramid",
    "rest_on_face",
    "resting",
    "rhombohedron",
    "rotate_about_z",
    "sphere",
    "stable_poses",
    "t_shape",
    "tetrahedron",
    "u_shape",
]

FIG5_LABELS = {
    "OCTA": "not_hexahedron",
    "CUBE1": "cube",
    "CUBE2": "cube",
    "TETRA": "not_hexahedron",
    "PRAPAR": "rectangular_parallelepiped",
    "KOPAR": "nonrectangular_parallelepiped",
    "TETRA1": "not_hexahedron",
    "TETRA2": "not_hexahedron",
    "CUBE11": "cube",
    "CUBE22": "cube",
    "PRAPA1": "rectangular_parallelepiped",
    "KOPAR1": "nonrectangular_parallelepiped",
}
"""The paper's Fig. 5: object name → the label its answer names."""


def _positive(**values: float) -> None:
    for name, v in values.items():
        if not (math.isfinite(v) and v > 0.0):
            raise UsageError(f"{name} must be a positive number of metres, got {v!r}")


def _settle(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Translate ``mesh`` so that its lowest point is at z = 0 and its box is centred in x, y."""
    lo, hi = mesh.bounds
    mesh.apply_translation([-(lo[0] + hi[0]) / 2.0, -(lo[1] + hi[1]) / 2.0, -lo[2]])
    return mesh


def _hull(points: ArrayLike) -> trimesh.Trimesh:
    mesh = trimesh.convex.convex_hull(np.asarray(points, dtype=float))
    if not mesh.is_watertight:  # pragma: no cover - a hull of non-degenerate points always is
        raise UsageError("the solid's vertices are degenerate (flat or repeated)")
    return _settle(mesh)


def box(a: float, b: float, c: float) -> trimesh.Trimesh:
    """A rectangular box of extents ``a`` (x) × ``b`` (y) × ``c`` (z, height)."""
    _positive(a=a, b=b, c=c)
    return _settle(trimesh.creation.box(extents=(a, b, c)))


def parallelepiped(
    a: float,
    b: float,
    c: float,
    *,
    angle_deg: float = 90.0,
    shear_deg: float = 0.0,
    shear_azimuth_deg: float = 0.0,
) -> trimesh.Trimesh:
    """The hull of a parallelepiped spanned by three edge vectors, resting on a face.

    Parameters
    ----------
    a, b
        Lengths of the two base edges (the first along x).
    c
        Height (vertical extent) of the solid.
    angle_deg
        Angle between the base edges (90 gives a rectangular base).
    shear_deg
        Tilt of the lateral edges from the vertical; faces overhang by at most this angle,
        so keep it ≤ 12° for the 33-sensor finger to feel every face at any azimuth.
    shear_azimuth_deg
        Horizontal direction of that tilt.

    With ``angle_deg=90`` and ``shear_deg=0`` this is :func:`box`; anything else is a
    nonrectangular parallelepiped (its three pairs of faces are still parallel).
    """
    _positive(a=a, b=b, c=c)
    if not 10.0 <= angle_deg <= 170.0:
        raise UsageError(f"angle_deg must lie in [10, 170], got {angle_deg}")
    if not 0.0 <= shear_deg <= 60.0:
        raise UsageError(f"shear_deg must lie in [0, 60], got {shear_deg}")
    t, s, p = math.radians(angle_deg), math.radians(shear_deg), math.radians(shear_azimuth_deg)
    u = np.array([a, 0.0, 0.0])
    v = np.array([b * math.cos(t), b * math.sin(t), 0.0])
    w = np.array([c * math.tan(s) * math.cos(p), c * math.tan(s) * math.sin(p), c])
    pts = [i * u + j * v + k * w for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    return _hull(pts)


def rhombohedron(edge: float, angle_deg: float = 80.0) -> trimesh.Trimesh:
    """A rhombohedron: six congruent rhombi, every edge ``edge``, face angle ``angle_deg``.

    The three edges at one vertex make the same angle ``angle_deg`` with each other; the solid
    rests on a rhombus. Its lateral edges tilt from the vertical (13° at the default 80°).
    """
    _positive(edge=edge)
    if not 45.0 <= angle_deg <= 120.0:
        raise UsageError(f"angle_deg must lie in [45, 120], got {angle_deg}")
    al = math.radians(angle_deg)
    ca, sa = math.cos(al), math.sin(al)
    u = np.array([1.0, 0.0, 0.0])
    v = np.array([ca, sa, 0.0])
    wy = (ca - ca * ca) / sa
    w = np.array([ca, wy, math.sqrt(1.0 - ca * ca - wy * wy)])
    pts = [edge * (i * u + j * v + k * w) for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    return _hull(pts)


def tetrahedron(edge: float) -> trimesh.Trimesh:
    """A regular tetrahedron with edges ``edge``, resting on a face."""
    _positive(edge=edge)
    r = edge / math.sqrt(3.0)
    base = [
        (r * math.cos(k * 2 * math.pi / 3), r * math.sin(k * 2 * math.pi / 3), 0.0)
        for k in range(3)
    ]
    return _hull([*base, (0.0, 0.0, edge * math.sqrt(2.0 / 3.0))])


def octahedron(edge: float) -> trimesh.Trimesh:
    """A regular octahedron with edges ``edge``, resting on a face (its top face is parallel).

    Three of its faces overhang by 19.47°; the bottom face's vertex points along +x.
    """
    _positive(edge=edge)
    s = edge / math.sqrt(2.0)
    pts = np.array(
        [[s, 0, 0], [-s, 0, 0], [0, s, 0], [0, -s, 0], [0, 0, s], [0, 0, -s]], dtype=float
    )
    mesh = trimesh.convex.convex_hull(pts)
    mesh = rest_on_face(mesh, (-1.0, -1.0, -1.0))
    # turn it so that a vertex of the bottom triangle lies on +x
    bottom = mesh.vertices[np.abs(mesh.vertices[:, 2]) < 1e-9 * edge]
    ang = math.atan2(bottom[0, 1], bottom[0, 0])
    return rotate_about_z(mesh, -math.degrees(ang), about=(0.0, 0.0))


def _ngon(n: int, r: float, z: float) -> list[tuple[float, float, float]]:
    return [
        (r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n), z) for k in range(n)
    ]


def _check_n(n: int) -> None:
    if not isinstance(n, int) or n < 3:
        raise UsageError(f"n (number of sides) must be an integer ≥ 3, got {n!r}")


def prism(n: int, circumradius: float, height: float) -> trimesh.Trimesh:
    """A right prism over a regular ``n``-gon (circumradius ``circumradius``), standing on it."""
    _check_n(n)
    _positive(circumradius=circumradius, height=height)
    return _hull(_ngon(n, circumradius, 0.0) + _ngon(n, circumradius, height))


def pyramid(n: int, circumradius: float, height: float) -> trimesh.Trimesh:
    """A right pyramid over a regular ``n``-gon, standing on its base, apex above the centre."""
    _check_n(n)
    _positive(circumradius=circumradius, height=height)
    return _hull([*_ngon(n, circumradius, 0.0), (0.0, 0.0, height)])


def frustum(n: int, r_bottom: float, r_top: float, height: float) -> trimesh.Trimesh:
    """A frustum of a right ``n``-gonal pyramid: base circumradius ``r_bottom``, top ``r_top``."""
    _check_n(n)
    _positive(r_bottom=r_bottom, r_top=r_top, height=height)
    if r_top >= r_bottom:
        raise UsageError(f"r_top ({r_top}) must be smaller than r_bottom ({r_bottom})")
    return _hull(_ngon(n, r_bottom, 0.0) + _ngon(n, r_top, height))


def cylinder(radius: float, height: float, *, sections: int = 48) -> trimesh.Trimesh:
    """A circular cylinder (``sections`` facets around) standing on its base."""
    _positive(radius=radius, height=height)
    return _settle(trimesh.creation.cylinder(radius=radius, height=height, sections=sections))


def sphere(radius: float, *, subdivisions: int = 3) -> trimesh.Trimesh:
    """An icosphere of ``radius`` resting on its lowest point."""
    _positive(radius=radius)
    return _settle(trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius))


def box_union(rects: Sequence[tuple[float, float, float, float]], height: float) -> trimesh.Trimesh:
    """The union of axis-aligned boxes ``(x0, y0, x1, y1)`` of the same ``height`` on the table.

    Built by extruding the union of the footprints (shapely), so the mesh is watertight
    without a boolean engine. The footprint union must be one polygon without holes.
    """
    _positive(height=height)
    if not rects:
        raise UsageError("box_union needs at least one rectangle")
    polys = []
    for x0, y0, x1, y1 in rects:
        if not (x1 > x0 and y1 > y0):
            raise UsageError(f"rectangle {(x0, y0, x1, y1)} must have x1 > x0 and y1 > y0")
        polys.append(shapely.geometry.box(x0, y0, x1, y1))
    shape = shapely.ops.unary_union(polys).simplify(0.0)
    if not isinstance(shape, shapely.geometry.Polygon) or shape.interiors:
        raise UsageError("the rectangles must overlap or touch into one polygon without holes")
    return _settle(_extrude(shape, height))


def _extrude(shape: shapely.geometry.Polygon, height: float) -> trimesh.Trimesh:
    """A watertight prism over a simple polygon (constrained Delaunay triangles of shapely)."""
    ring = np.asarray(shape.exterior.coords, dtype=float)[:-1]
    index = {(float(x), float(y)): i for i, (x, y) in enumerate(ring)}
    tris = []
    for tri in shapely.constrained_delaunay_triangles(shape).geoms:
        tris.append([index[(float(x), float(y))] for x, y in list(tri.exterior.coords)[:3]])
    k = len(ring)
    vertices = np.vstack([np.c_[ring, np.zeros(k)], np.c_[ring, np.full(k, height)]])
    faces = [[c, b, a] for a, b, c in tris] + [[a + k, b + k, c + k] for a, b, c in tris]
    for i in range(k):
        j = (i + 1) % k
        faces += [[i, j, j + k], [i, j + k, i + k]]
    mesh = trimesh.Trimesh(vertices=vertices, faces=np.asarray(faces), process=True)
    mesh.fix_normals()
    return mesh


def l_shape(a: float, b: float, width: float, height: float) -> trimesh.Trimesh:
    """An L block: legs of length ``a`` (along x) and ``b`` (along y), each ``width`` wide."""
    _positive(a=a, b=b, width=width, height=height)
    return box_union([(0, 0, a, width), (0, 0, width, b)], height)


def t_shape(a: float, b: float, width: float, height: float) -> trimesh.Trimesh:
    """A T block: a bar ``a`` long (along x) and a stem ``b`` long below its middle."""
    _positive(a=a, b=b, width=width, height=height)
    return box_union(
        [(-a / 2, 0, a / 2, width), (-width / 2, -b + width, width / 2, width)], height
    )


def u_shape(a: float, b: float, width: float, height: float) -> trimesh.Trimesh:
    """A U block: a base ``a`` long (along x) and two arms ``b`` long (along y)."""
    _positive(a=a, b=b, width=width, height=height)
    if a <= 2 * width:
        raise UsageError(f"a ({a}) must exceed twice the width ({width}) to leave a gap")
    return box_union([(0, 0, a, width), (0, 0, width, b), (a - width, 0, a, b)], height)


def rest_on_face(mesh: trimesh.Trimesh, face: Sequence[float] | int) -> trimesh.Trimesh:
    """A copy of ``mesh`` turned to rest on the face with outward normal ``face`` (or facet index).

    The chosen normal is rotated onto (0, 0, −1), then the mesh is settled on z = 0 and
    centred on the z axis.
    """
    if isinstance(face, int | np.integer):
        try:
            normal = np.asarray(mesh.facets_normal[int(face)], dtype=float)
        except IndexError:
            raise UsageError(f"mesh has no facet {face}") from None
    else:
        normal = np.asarray(face, dtype=float)
        if normal.shape != (3,) or not np.isfinite(normal).all() or np.linalg.norm(normal) < 1e-12:
            raise UsageError(f"face normal must be three finite numbers, not all 0: {face!r}")
    out = mesh.copy()
    rot = trimesh.geometry.align_vectors(  # type: ignore[no-untyped-call]
        normal / np.linalg.norm(normal), [0.0, 0.0, -1.0]
    )
    out.apply_transform(rot)
    return _settle(out)


def stable_poses(
    mesh: trimesh.Trimesh, *, min_probability: float = 0.02
) -> list[tuple[trimesh.Trimesh, float]]:
    """Copies of ``mesh`` in the poses it comes to rest in when dropped on the table, most
    probable first, with their probabilities (``trimesh.poses.compute_stable_poses``): those
    of probability ≥ ``min_probability``, or the most probable one when none reaches it (a
    sphere). Each rests on z = 0, centred on the z axis.

    >>> [round(p, 2) for _, p in stable_poses(box(0.06, 0.04, 0.02))]
    [0.32, 0.32, 0.12, 0.12, 0.06, 0.06]
    """
    if not 0.0 <= min_probability <= 1.0:
        raise UsageError(f"min_probability must be between 0 and 1, got {min_probability}")
    transforms, probs = trimesh.poses.compute_stable_poses(mesh)
    order = np.argsort(-np.asarray(probs, dtype=float), kind="stable")
    out: list[tuple[trimesh.Trimesh, float]] = []
    for k in order:
        if probs[k] < min_probability and out:
            break
        posed = mesh.copy()
        posed.apply_transform(transforms[k])
        out.append((_settle(posed), float(probs[k])))
    return out


def resting(
    mesh: trimesh.Trimesh, pose: int = 0, turn_deg: float = 0.0, *, min_probability: float = 0.02
) -> trimesh.Trimesh:
    """``mesh`` in its ``pose``-th stable pose (:func:`stable_poses`, most probable first),
    turned by ``turn_deg`` about the vertical: the objects of ``benchmarks/bench_poses.py``.

    >>> lying = resting(prism(6, 0.03, 0.1), 0, 30.0)  # a hexagonal pencil on a side
    >>> [round(float(x), 3) for x in lying.extents[2:]]
    [0.052]
    """
    poses = stable_poses(mesh, min_probability=min_probability)
    if not 0 <= pose < len(poses):
        raise UsageError(
            f"pose must be 0 to {len(poses) - 1} (the mesh has {len(poses)}), got {pose}"
        )
    return rotate_about_z(poses[pose][0], turn_deg)


def rotate_about_z(
    mesh: trimesh.Trimesh, angle_deg: float, *, about: Sequence[float] | None = None
) -> trimesh.Trimesh:
    """A copy of ``mesh`` turned by ``angle_deg`` (degrees, counter-clockwise seen from above).

    The vertical axis passes through ``about`` = (x, y), by default the centre of the mesh's
    bounding box, so the object stays where it was.
    """
    out = mesh.copy()
    if about is None:
        lo, hi = out.bounds
        cx, cy = (lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0
    else:
        cx, cy = float(about[0]), float(about[1])
    rot = trimesh.transformations.rotation_matrix(  # type: ignore[no-untyped-call]
        math.radians(angle_deg), [0, 0, 1], [cx, cy, 0]
    )
    out.apply_transform(rot)
    return out


def place(mesh: trimesh.Trimesh, xy: Sequence[float]) -> trimesh.Trimesh:
    """A copy of ``mesh`` moved horizontally so that its bounding box is centred on ``xy``."""
    out = mesh.copy()
    lo, hi = out.bounds
    out.apply_translation([xy[0] - (lo[0] + hi[0]) / 2.0, xy[1] - (lo[1] + hi[1]) / 2.0, 0.0])
    return out


def _aligned_octahedron(edge: float) -> trimesh.Trimesh:
    """An octahedron whose overhanging faces look along equator sensors (multiples of 30°)."""
    mesh = octahedron(edge)
    n = mesh.face_normals
    low = n[n[:, 2] < -0.1]
    low = low[low[:, 2] > -0.99]
    az = math.degrees(math.atan2(low[0, 1], low[0, 0]))
    return rotate_about_z(mesh, round(az / 30.0) * 30.0 - az)


def fig5_objects() -> list[tuple[str, trimesh.Trimesh, str]]:
    """The twelve objects of the paper's Fig. 5, in order: ``(name, mesh, expected_label)``.

    Sizes are 2–30 cm; positions are near the origin. The labels are those of
    :data:`FIG5_LABELS`.
    """
    cube = box(0.08, 0.08, 0.08)
    items: list[tuple[str, trimesh.Trimesh]] = [
        ("OCTA", _aligned_octahedron(0.10)),
        ("CUBE1", cube),
        ("CUBE2", rotate_about_z(cube, 30.0)),
        ("TETRA", tetrahedron(0.12)),
        ("PRAPAR", box(0.16, 0.08, 0.05)),
        ("KOPAR", parallelepiped(0.14, 0.09, 0.06, angle_deg=65.0, shear_deg=8.0)),
        ("TETRA1", place(rotate_about_z(tetrahedron(0.06), 45.0), (0.03, -0.02))),
        ("TETRA2", place(rotate_about_z(tetrahedron(0.20), 100.0), (-0.02, 0.04))),
        ("CUBE11", place(rotate_about_z(box(0.03, 0.03, 0.03), 15.0), (0.04, 0.01))),
        ("CUBE22", place(rotate_about_z(box(0.25, 0.25, 0.25), 52.0), (-0.03, 0.02))),
        ("PRAPA1", place(rotate_about_z(box(0.30, 0.12, 0.04), 75.0), (0.02, 0.03))),
        (
            "KOPAR1",
            place(
                rotate_about_z(
                    parallelepiped(
                        0.10, 0.18, 0.08, angle_deg=110.0, shear_deg=6.0, shear_azimuth_deg=40.0
                    ),
                    -35.0,
                ),
                (-0.01, -0.02),
            ),
        ),
    ]
    return [(name, mesh, FIG5_LABELS[name]) for name, mesh in items]
