"""Ground-truth contacts sampled from a mesh's true faces, without any explorer.

For each face (a group of coplanar triangles) of a watertight mesh resting on the table,
:func:`sample_record` draws points ``p`` on the face and places the finger tip where it would
touch the face there: centre ``c = p + ρ·n`` (``n`` the true outward normal, ``ρ`` the tip
radius). The contact then reports

* (a) ``quantise=False``: the exact direction ``r0 = −n``;
* (b) ``quantise=True``: the direction of the finger's sensor nearest to ``−n`` (faces that
  no sensor's cone covers are skipped and listed in the record's notes);

and the contact point ``r1 = c + ρ·r0``, after Gaussian noise of standard deviation ``noise``
(metres) on the centre. The supporting face on the table is never touched.

Examples
--------
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.solids import box
>>> rec = sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), per_face=4, seed=1)
>>> len(rec.contacts), rec.finger, rec.explorer
(20, '33', 'synthetic')
"""

from __future__ import annotations

import itertools

import numpy as np
import shapely.geometry
import shapely.ops
import trimesh

from tactile_kb.errors import UsageError
from tactile_kb.record import Contact, ExplorationRecord, Layer
from tactile_kb.touch.finger import Finger
from tactile_kb.types import FloatArray, vec3

__all__ = ["mesh_faces", "mesh_planes", "sample_layers", "sample_record"]


def mesh_faces(mesh: trimesh.Trimesh) -> list[tuple[FloatArray, list[int]]]:
    """The mesh's planar faces: ``(unit outward normal, triangle indices)`` per coplanar group.

    Adjacent coplanar triangles form one face (``mesh.facets``); every other triangle is a
    face of its own (a tetrahedron has four faces but no facets).
    """
    groups: list[tuple[FloatArray, list[int]]] = []
    in_facet = np.zeros(len(mesh.faces), dtype=bool)
    for normal, tris in zip(mesh.facets_normal, mesh.facets, strict=True):
        groups.append((np.asarray(normal, dtype=float), [int(t) for t in tris]))
        in_facet[tris] = True
    for t in np.flatnonzero(~in_facet):
        groups.append((np.asarray(mesh.face_normals[t], dtype=float), [int(t)]))
    return groups


def mesh_planes(mesh: trimesh.Trimesh) -> list[tuple[FloatArray, float]]:
    """The mesh's distinct planes, ``(unit outward normal, offset)`` with ``normal · x = offset``.

    Triangles on one plane count once, whether adjacent or not (the ground truth a model's
    merged planes are compared with).
    """
    seen: list[tuple[FloatArray, float]] = []
    for n, tri in zip(mesh.face_normals, mesh.triangles, strict=True):
        d = float(n @ tri[0])
        if not any(float(n @ m) > 1 - 1e-6 and abs(d - e) < 1e-6 for m, e in seen):
            seen.append((np.asarray(n, dtype=float), d))
    return seen


def _sample_in_face(
    mesh: trimesh.Trimesh, tris: list[int], count: int, rng: np.random.Generator, margin: float
) -> FloatArray:
    """``count`` points drawn uniformly by area on the triangles, kept away from their edges."""
    tri = mesh.triangles[tris]
    area = mesh.area_faces[tris]
    pick = rng.choice(len(tris), size=count, p=area / area.sum())
    r = rng.random((count, 2))
    flip = r.sum(axis=1) > 1.0
    r[flip] = 1.0 - r[flip]
    t = tri[pick]
    pts = t[:, 0] + r[:, :1] * (t[:, 1] - t[:, 0]) + r[:, 1:] * (t[:, 2] - t[:, 0])
    centre = t.mean(axis=1)
    return np.asarray(centre + (1.0 - margin) * (pts - centre), dtype=float)


def sample_record(
    mesh: trimesh.Trimesh,
    finger: Finger,
    *,
    per_face: int = 6,
    total: int | None = None,
    quantise: bool = True,
    noise: float = 0.0005,
    seed: int = 0,
    margin: float = 0.15,
    name: str = "",
) -> ExplorationRecord:
    """An exploration record of contacts sampled on the true faces of ``mesh``.

    Parameters
    ----------
    mesh
        A watertight mesh resting on z = 0 (see :mod:`tactile_kb.solids`).
    finger
        The finger: its radius ρ, sensor directions and acceptance cone.
    per_face
        Contacts on each face (ignored when ``total`` is given).
    total
        Draw this many contacts over all touchable faces, by area (for curved meshes with
        hundreds of small faces).
    quantise
        Report the nearest sensor direction (b) instead of the exact one (a).
    noise
        Standard deviation of the Gaussian noise on the tip-centre position, metres.
    seed
        Seed of the random generator: the same seed gives the same record.
    margin
        Points are drawn in each triangle shrunk by this fraction about its centroid, away
        from edges the tip would also touch.
    name
        The record's ``object`` field.
    """
    if per_face < 1 or (total is not None and total < 1):
        raise UsageError("per_face and total must be at least 1")
    if noise < 0:
        raise UsageError(f"noise must be ≥ 0, got {noise}")
    rng = np.random.default_rng(seed)
    rho = finger.radius
    height = float(mesh.extents.max())
    faces = []
    notes: list[str] = []
    for normal, tris in mesh_faces(mesh):
        zs = mesh.vertices[mesh.faces[tris]].reshape(-1, 3)[:, 2]
        if normal[2] < -0.999 and float(np.abs(zs).max()) <= 1e-9 * height + 1e-12:
            continue  # the face resting on the table
        sensor = finger.nearest(vec3(-normal))
        if quantise and sensor is None:
            notes.append(f"no sensor feels the face with normal {np.round(normal, 3).tolist()}")
            continue
        faces.append((normal, tris, sensor))
    if not faces:
        return _record(mesh, finger, [], seed, per_face, noise, quantise, notes, name)
    if total is not None:
        areas = np.array([mesh.area_faces[t].sum() for _, t, _ in faces])
        counts = rng.multinomial(total, areas / areas.sum())
    else:
        counts = np.full(len(faces), per_face)
    convex = bool(mesh.is_convex)
    contacts: list[Contact] = []
    for (normal, tris, sensor), count in zip(faces, counts, strict=True):
        if count == 0:
            continue
        pts = _sample_in_face(mesh, tris, int(count), rng, margin)
        centres = pts + rho * normal
        if not convex:  # drop tips that would cut into another part of the object
            _, dist, _ = trimesh.proximity.closest_point(mesh, centres)  # type: ignore[no-untyped-call]
            keep = dist >= rho * (1.0 - 1e-6)
            centres = centres[keep]
        centres = centres + rng.normal(0.0, noise, size=centres.shape) if noise > 0 else centres
        r0 = (
            np.asarray(finger.directions[sensor], dtype=float)
            if quantise and sensor is not None
            else -normal
        )
        fired = finger.fired([vec3(-normal)])
        for c in centres:
            contacts.append(
                Contact(
                    step=len(contacts),
                    centre=vec3(c),
                    sensors=fired,
                    sensor=-1 if sensor is None else sensor,
                    direction=vec3(r0),
                    point=vec3(c + rho * r0),
                    kind="touch",
                    phase="synthetic",
                )
            )
    return _record(mesh, finger, contacts, seed, per_face, noise, quantise, notes, name)


def _record(
    mesh: trimesh.Trimesh,
    finger: Finger,
    contacts: list[Contact],
    seed: int,
    per_face: int,
    noise: float,
    quantise: bool,
    notes: list[str],
    name: str,
) -> ExplorationRecord:
    return ExplorationRecord(
        object=name,
        explorer="synthetic",
        finger=finger.name,
        tip_radius=finger.radius,
        sensor_directions=list(finger.directions),
        seed=seed,
        noise=float(noise),
        params={"per_face": float(per_face), "quantise": float(quantise)},
        contacts=contacts,
        path=[c.centre for c in contacts],
        contacts_per_phase={"synthetic": len(contacts)} if contacts else {},
        complete=True,
        notes=notes,
    )


def layer_polygon(mesh: trimesh.Trimesh, z: float) -> shapely.geometry.Polygon:
    """The cross-section of ``mesh`` at height ``z`` as a counter-clockwise shapely polygon."""
    lines = trimesh.intersections.mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z])  # type: ignore[no-untyped-call]
    segs = [shapely.geometry.LineString(np.round(seg[:, :2], 9)) for seg in lines]
    polys = list(shapely.ops.polygonize(shapely.ops.unary_union(segs)))
    if not polys:
        raise UsageError(f"the plane z = {z} misses the object")
    shape = shapely.ops.unary_union(polys).simplify(1e-9)
    if not isinstance(shape, shapely.geometry.Polygon):
        shape = max(shape.geoms, key=lambda g: g.area)
    return shapely.geometry.polygon.orient(shape, 1.0)


def sample_layers(
    mesh: trimesh.Trimesh,
    finger: Finger,
    heights: list[float],
    *,
    spacing: float = 0.01,
    quantise: bool = True,
    noise: float = 0.0,
    seed: int = 0,
    name: str = "",
) -> ExplorationRecord:
    """Contacts around the contour of each horizontal layer, in order, as the paper's Fig. 1.

    In each plane z = h the finger walks the cross-section counter-clockwise (seen from
    above), touching each side every ``spacing`` metres and never closer than 2ρ to a corner;
    contacts carry their ``layer`` index, and the record lists the layers. Sides are assumed
    vertical (objects made of boxes, prisms).
    """
    rng = np.random.default_rng(seed)
    rho = finger.radius
    contacts: list[Contact] = []
    layers: list[Layer] = []
    for li, z in enumerate(heights):
        ring = np.asarray(layer_polygon(mesh, z).exterior.coords, dtype=float)
        start = len(contacts)
        for a, b in itertools.pairwise(ring):
            length = float(np.linalg.norm(b - a))
            if length <= 4 * rho:
                continue
            t_dir = (b - a) / length
            normal = np.array([t_dir[1], -t_dir[0], 0.0])
            k = max(2, int(length / spacing))
            sensor = finger.nearest(vec3(-normal))
            if quantise and sensor is None:
                continue
            r0 = (
                np.asarray(finger.directions[sensor], float)
                if quantise and sensor is not None
                else -normal
            )
            for t in np.linspace(2 * rho, length - 2 * rho, k):
                p = np.array([*(a + t * t_dir), z])
                c = p + rho * normal + (rng.normal(0.0, noise, 3) if noise > 0 else 0.0)
                contacts.append(
                    Contact(
                        step=len(contacts),
                        centre=vec3(c),
                        sensors=finger.fired([vec3(-normal)]),
                        sensor=-1 if sensor is None else sensor,
                        direction=vec3(r0),
                        point=vec3(c + rho * r0),
                        kind="slide",
                        phase="layer",
                        layer=li,
                    )
                )
        path = [c.centre for c in contacts[start:]]
        layers.append(Layer(index=li, z=float(z), path=path, closed=True))
    return ExplorationRecord(
        object=name,
        explorer="synthetic-layers",
        finger=finger.name,
        tip_radius=rho,
        sensor_directions=list(finger.directions),
        seed=seed,
        noise=float(noise),
        params={"spacing": float(spacing), "quantise": float(quantise)},
        contacts=contacts,
        path=[c.centre for c in contacts],
        layers=layers,
        contacts_per_phase={"layer": len(contacts)} if contacts else {},
        complete=True,
    )
