"""Ground truth put into saved exploration records: which of a scan's imperfections cost answers.

A perturbed solid's touches differ from an ideal one's in three ways the model has to cope
with, and ``bench_real.py --rejudge DIR --truth ITEMS`` (or ``--faces DIR --truth ITEMS``)
takes any of them away, from the solid the record was explored on, before classifying again:

``roundings``
    The contacts whose tip rests on a rounded edge or corner are dropped. The perturbation
    rounds a convex solid's sharp edges with radius ``r`` (:func:`rounding_radius`): the
    rounded solid is the solid shrunk by ``r`` (every plane moved in by ``r``), grown by a
    ball of radius ``r``. A tip centre lies over a rounding where its nearest point on the
    shrunk solid lies on two of its planes whose normals are more than
    :data:`tactile_kb.perturb.SHARP_DEG` apart (an edge or a corner of the shrunk solid).
``readings``
    Every contact off the roundings reads what an ideal face would make the finger read there: the
    sensor followed is the finger's sensor (turned with the head at the contact's
    orientation) nearest to the inward normal of the solid's surface nearest the tip centre,
    and the sensors on are those whose cones hold that normal.
``centres``
    Every contact off the roundings has its tip centre moved along that normal to lie ρ from
    the solid's surface (the bumps, letters, dents and vertex noise taken away).

The touches of the roundings are changed by ``roundings`` alone (the ideal solid's sharp
surface is no truth for them), so the three take away three things apart. Each is a
measurement, not a method: the figure with an item given is what a perfect cure
of that imperfection could gain with the exploration as it was.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np
import trimesh

from tactile_kb.geometry.planes import nearest_points
from tactile_kb.perturb import LEVELS, SHARP_DEG, _has_sharp_edges, sharp_edge_length
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import BUILTIN_LAYOUTS, Finger, Orientation, builtin_finger

ITEMS = ("roundings", "readings", "centres")
"""What ``--truth`` can take away, in the order it is applied."""

ON_PLANE = 0.02
"""Fraction of the rounding's radius: a nearest point this near a shrunk plane lies on it
(Dykstra's projection, :func:`tactile_kb.geometry.planes.nearest_points`, meets its planes to
a few micrometres only; a tip centre so near where the rounding begins is hardly on it)."""


def parse_items(text: str) -> tuple[str, ...]:
    """The items of a ``--truth`` argument (comma-separated); one line naming a bad one."""
    items = tuple(s.strip() for s in text.split(",") if s.strip())
    for s in items:
        if s not in ITEMS:
            raise SystemExit(f"--truth {text}: no item {s!r} (choose from {', '.join(ITEMS)})")
    if not items:
        raise SystemExit(f"--truth {text!r}: name at least one of {', '.join(ITEMS)}")
    return tuple(s for s in ITEMS if s in items)


def true_planes(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """The planes ``n · x = d`` of ``mesh`` (outward unit normals ``n``, offsets ``d``): its
    facets (coplanar triangles) and the triangles in none."""
    normals = [np.asarray(n, dtype=float) for n in mesh.facets_normal]
    offsets = [
        float(np.asarray(n) @ mesh.vertices[mesh.faces[facet[0], 0]])
        for n, facet in zip(mesh.facets_normal, mesh.facets, strict=True)
    ]
    alone = np.ones(len(mesh.faces), dtype=bool)
    for facet in mesh.facets:
        alone[facet] = False
    for k in np.flatnonzero(alone):
        n = np.asarray(mesh.face_normals[k], dtype=float)
        normals.append(n)
        offsets.append(float(n @ mesh.vertices[mesh.faces[k, 0]]))
    return np.asarray(normals, dtype=float).reshape(-1, 3), np.asarray(offsets, dtype=float)


def rounding_radius(ideal: trimesh.Trimesh, group: str) -> float:
    """The radius (m) :func:`tactile_kb.perturb.perturb` rounded ``ideal``'s sharp edges with
    in a record of ``group`` (``"level N"``): the level's fraction of the shortest sharp edge,
    for a convex solid with sharp edges; 0 for any other solid or group."""
    if not group.startswith("level "):
        return 0.0
    level = LEVELS.get(int(group.split()[1]))
    if level is None or level.rounding <= 0 or not ideal.is_convex or not _has_sharp_edges(ideal):
        return 0.0
    return float(level.rounding * sharp_edge_length(ideal))


def on_roundings(centres: np.ndarray, ideal: trimesh.Trimesh, radius: float) -> np.ndarray:
    """Which tip ``centres`` (n, 3) lie over a rounded edge or corner of ``ideal`` rounded
    with ``radius`` (see the module's ``roundings``): their nearest point on the solid shrunk
    by ``radius`` lies on two of its planes more than ``SHARP_DEG`` apart."""
    out = np.zeros(len(centres), dtype=bool)
    if radius <= 0 or len(centres) == 0:
        return out
    normals, offsets = true_planes(ideal)
    shrunk = offsets - radius
    q = nearest_points(np.asarray(centres, dtype=float), normals, shrunk)
    on = np.abs(q @ normals.T - shrunk) <= ON_PLANE * radius
    cos_sharp = np.cos(np.radians(SHARP_DEG))
    for i in np.flatnonzero(on.sum(axis=1) >= 2):
        n = normals[on[i]]
        out[i] = bool(((n @ n.T) < cos_sharp).any())
    return out


def _surface_normals(centres: np.ndarray, ideal: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """For each tip centre, the nearest point of ``ideal``'s surface and the outward normal
    of the triangle it lies on."""
    closest, _, triangle = trimesh.proximity.closest_point(ideal, centres)
    return np.asarray(closest, dtype=float), np.asarray(ideal.face_normals[triangle], dtype=float)


def _ideal_reading(contact: Contact, normal: np.ndarray, finger: Finger) -> dict[str, object]:
    """The fields of ``contact`` an ideal face of outward ``normal`` would give: the sensor
    of ``finger`` nearest to ``-normal`` (the head at the contact's orientation), its world
    direction and the sensors whose cones hold ``-normal`` (:meth:`Finger.fired`)."""
    turn = Orientation(*contact.orientation).rotation
    inward = turn.T @ -normal  # in the finger's frame
    best = int(np.argmax(finger.matrix @ inward))
    d = turn @ finger.matrix[best]
    return {
        "sensor": best,
        "sensors": finger.fired([inward]) or (best,),
        "direction": (float(d[0]), float(d[1]), float(d[2])),
    }


def _finger_of(record: ExplorationRecord) -> Finger:
    """The finger a record was explored with: the built-in layout it names, else its sensor
    directions with cones so narrow that only the nearest sensor is on."""
    if record.finger in BUILTIN_LAYOUTS:
        return builtin_finger(record.finger)
    return Finger(name=record.finger, directions=tuple(record.sensor_directions), cone_deg=1e-6)


def corrected(
    record: ExplorationRecord, ideal: trimesh.Trimesh, group: str, items: Collection[str]
) -> ExplorationRecord:
    """``record`` (explored on a perturbation of ``ideal`` in ``group``) with the ``items``
    of :data:`ITEMS` taken away (see the module)."""
    if not record.contacts:
        return record
    rho = record.tip_radius
    centres = np.asarray([c.centre for c in record.contacts], dtype=float)
    rounded = on_roundings(centres, ideal, rounding_radius(ideal, group))
    keep = ~rounded if "roundings" in items else np.ones(len(centres), dtype=bool)
    contacts = list(record.contacts)
    if "readings" in items or "centres" in items:
        closest, normals = _surface_normals(centres, ideal)
        finger = _finger_of(record) if record.sensor_directions else None
        for i in np.flatnonzero(~rounded):
            update: dict[str, object] = {}
            n = normals[i]
            if "readings" in items and finger is not None:
                update.update(_ideal_reading(contacts[i], n, finger))
            centre = centres[i]
            if "centres" in items:
                centre = centre - (float((centre - closest[i]) @ n) - rho) * n
                update["centre"] = (float(centre[0]), float(centre[1]), float(centre[2]))
            d = np.asarray(update.get("direction", contacts[i].direction), dtype=float)
            p = centre + rho * d
            update["point"] = (float(p[0]), float(p[1]), float(p[2]))
            contacts[i] = contacts[i].model_copy(update=update)
    kept = [c for c, k in zip(contacts, keep, strict=True) if k]
    return record.model_copy(update={"contacts": kept})
