"""Completion driven by the model: probe what the contour following left open.

Contour following in horizontal planes (:mod:`tactile_kb.touch.servo`) touches every face of an
ideal solid at two heights. On real objects it can stop early (a surface it cannot follow, a
side it never reached) and leave the enveloping polyhedron open, or leave a face with tip
centres at one height only (its normal then cannot be fitted). :class:`ModelCompleter` looks at
the model built from the record so far (:func:`tactile_kb.geometry.model.build_model`) and asks the
controller for one more touch at a time (a :class:`~tactile_kb.touch.servo.Probe`: approach along
the missing normal from outside the object), until

* the envelope is closed and every side face has tip centres at two heights, or every tip
  centre lies on one sphere (:func:`~tactile_kb.features.builtin.centres_on_sphere`: a ball,
  whose facets in the model are no faces to touch again) (ending ``"closed"``), or
* the budget (:class:`CompletionParams`: touches and path length spent by the completion)
  runs out (``"budget"``), or
* what stayed open cannot be reached: :attr:`CompletionParams.attempts` probes for it found
  nothing, were blocked on the way, or did not close it (``"unreachable"``).

A closed model can still be wrong: a face no touch found is cut off, and its neighbours'
planes meet in a corner where the object is not; a face known from one touch (a probe and its
short slide) has a plane that tilts by degrees. Probes that test the model (a second spot on
a face known from one: :func:`second_spot_probes`; where the contour's free path passed inside
it, where the visual hint reaches beyond it, and at corners that jut out from the touched
points: :func:`corner_probes`) are each tried once, within the same budget, and never hold
the completion open.

An item's second attempt learns from the first (:meth:`ModelCompleter._choose`): a face's
other height goes to the end farthest from the first attempt when that touched something
else; an open side is approached at the height, then in line with a point, where the object
surely is; a probe that found nothing moves halfway to the touches. With exact contacts the
same approach is never asked for twice (it would touch what it touched before).

The record says which happened (``record.ending``, ``record.unreachable`` and a note). The
controller computes no geometry: it carries out probes given as plain values; this module,
above it, computes them from the model.

Examples
--------
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.stepper import StepperExplorer
>>> rec = completing(StepperExplorer()).explore(box(0.06, 0.05, 0.04))
>>> rec.ending, rec.unreachable
('closed', [])
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from tactile_kb.errors import TactileKBError, UsageError
from tactile_kb.features.builtin import centres_on_sphere
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.geometry.planes import (
    SMOOTH_RHO,
    Face,
    nearest_points,
    rounded_edge_slack,
    rounding_zone,
    segment_distances,
    surface_detail,
)
from tactile_kb.geometry.polyhedron import Polyhedron
from tactile_kb.record import (
    APPROACH_LEVEL,
    APPROACH_SIDES,
    APPROACH_STRAIGHT,
    ExplorationRecord,
)
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.touch.explorers import Explorer, WorldExplorer
from tactile_kb.touch.servo import Ending, Probe
from tactile_kb.types import FloatArray

__all__ = [
    "CORNER_PROBES",
    "DEFAULT_COMPLETION",
    "CompletionParams",
    "ModelCompleter",
    "completing",
    "completion_probes",
    "corner_juts",
    "corner_probes",
    "model_completer",
    "second_spot_probes",
]

_SIDES = 8  # horizontal directions checked for a side never touched (every 45°)

RESOLVING_SENSORS = 8
"""A face touched along one line is probed off it (:func:`completion_probes`) only with a finger
of at least this many sensors: fewer (a tripod, the paper's 4-sensor equator) read a face's
normal no better than its neighbours', and a touch off the line then fits nothing new."""

_PATH = "the path passes inside the model"
_HINT = "the hint reaches beyond the model"
_CORNER = "a corner juts out"
_SPOT = "a face touched at one spot"
_ROUNDED = "a second height on a rounded edge"
_TESTS = (_PATH, _HINT, _CORNER, _SPOT, _ROUNDED)  # tests of the model, never holding it open
_OPEN = "open towards"

TOUCHED_OPEN = " (touched there; the planes touched do not close it)"
"""Added to an open direction the completion names unreachable when a probe that way touched
the object: the finger reached it there, and the planes still leave the envelope open (a star
prism's faces each leave its other points outside, so none bounds it, though every contour
closed round it)."""

PATH_PROBES = 4
"""At most this many probes per exploration where a contour's path passed inside the model, or
the hint box reaches past it (:func:`completion_probes`): tests of a corner or a part the
envelope may have wrong, each tried once, never items that hold the completion open."""

CORNER_PROBES = 3
"""At most this many corner checks per exploration (:func:`corner_probes`): each tests one
modelled corner that juts out from the touched points far more than the model's other corners
do, once; like the path's, they never hold the completion open."""

EDGE_EXPLAINED = 1.0
"""Tip radii (or 4 σ of the declared noise, when more): an edge touch whose surface point lies
further than this from every edge of the model touched an edge the model lacks; the corners
beyond it are tested (:func:`corner_probes`, :func:`_beyond_unexplained_edges`)."""

CORNER_OUTLIER = 1.5
"""A corner is checked when it juts out from the touched points more than this many times the
median of the model's corners (:func:`corner_probes`)."""

TOP_NZ = DEFAULTS.explore.top_nz
"""A face whose normal's z component is at least this is a top, probed from above when its tip
centres lie along one line (:func:`completion_probes`)."""


@dataclass(frozen=True)
class CompletionParams:
    """The budget and thresholds of the completion; ``None`` takes the current settings
    (``settings.current().explore``: ``completion_touches``, ``completion_path``,
    ``completion_attempts``) when the completion runs.

    Attributes
    ----------
    touches
        At most this many touches spent by the completion (or two per face of the model, when
        that is more; the path budget grows in proportion). Default 24.
    path
        At most this much tip-centre path (metres) spent by the completion, or
        ``explore.completion_path_sizes`` (4) times the touched extent per touch of the budget
        when that is more (each probe goes round the object; some touch nothing). Default 4 m.
    attempts
        Probes for one open item (a direction, a face) before it counts as unreachable (when
        they found nothing, or what they found did not close it). Default 2.
    height_gap
        Tip centres on a face lie at two heights when they span at least this much in z
        (metres); ``None``: half the tip radius.
    """

    touches: int | None = None
    path: float | None = None
    attempts: int | None = None
    height_gap: float | None = None

    def __post_init__(self) -> None:
        if (self.touches is not None and self.touches < 0) or (
            self.attempts is not None and self.attempts < 1
        ):
            raise UsageError("completion touches must be ≥ 0 and attempts ≥ 1")
        if self.path is not None and not (math.isfinite(self.path) and self.path >= 0):
            raise UsageError(f"completion path must be ≥ 0 metres, got {self.path}")
        if self.height_gap is not None and not (
            math.isfinite(self.height_gap) and self.height_gap > 0
        ):
            raise UsageError(f"completion height_gap must be > 0 metres, got {self.height_gap}")

    def budget(self) -> tuple[int, float, int]:
        """``(touches, path, attempts)``, the ``None`` ones from the current settings."""
        s = current().explore
        return (
            s.completion_touches if self.touches is None else self.touches,
            s.completion_path if self.path is None else self.path,
            s.completion_attempts if self.attempts is None else self.attempts,
        )


DEFAULT_COMPLETION = CompletionParams()
"""The completion's default budget: the current settings' (24 touches, 4 m of path)."""


def _name(v: FloatArray) -> str:
    return "(" + ", ".join(f"{round(float(x), 1) + 0.0:+.1f}" for x in v) + ")"


def completion_probes(model: ObjectModel, *, height_gap: float | None = None) -> list[Probe]:
    """The probes that would close ``model`` or give a face a second height, most urgent first.

    * Open: one probe per open direction (approached from that side at the middle of the
      touched heights; towards +z, from above), or, when the planes contradict each other
      and name no direction, one per horizontal side (every 45°) and the top that no face
      faces yet. Directions under the object (the table's side) are not probed. Planes
      that close only far from the touched points are then probed on the way to the far
      corner (:func:`_far_closure_probes`).
    * Closed: one probe per side face whose tip centres lie at one height, at the other end
      of the face's height range (faces lower than the tip's diameter are left as they are;
      on a scan touched without noise, a face that spans a plane only thanks to touches
      that may lie on the rounding of one of its edges is tested once, half way to the
      farther end, after the corner checks),
      and two from above beside a top whose tip centres lie along one line (a ridge); then
      tests of the model: a second spot on each face known from one spot
      (:func:`second_spot_probes`, after the path, hint and corner checks).
    """
    record = model.record
    rho = record.tip_radius
    gap = height_gap if height_gap is not None else 0.5 * rho
    centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
    probes: list[Probe] = _blind_probes(model)
    if len(centres) == 0:
        return probes
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    mid = 0.5 * (lo + hi)
    reach = float(np.linalg.norm(hi - lo)) + 4.0 * rho
    z_mid = max(float(mid[2]), rho + 0.001)
    if model.polyhedron is None:
        directions = [np.asarray(d, dtype=float) for d in model.open_directions]
        if not directions:  # contradictory planes: probe every side nothing faces yet
            normals = np.asarray([f.normal for f in model.faces], dtype=float).reshape(-1, 3)
            candidates = [
                np.array([math.cos(a), math.sin(a), 0.0])
                for a in np.arange(_SIDES) * 2 * math.pi / _SIDES
            ] + [np.array([0.0, 0.0, 1.0])]
            cos = math.cos(math.radians(50.0))
            directions = [d for d in candidates if not (normals @ d >= cos).any()]
        for d in directions:
            d = d / float(np.linalg.norm(d))
            if d[2] < -0.95:
                continue  # straight under the object: the table
            if d[2] > 0.9:
                target = np.array([mid[0], mid[1], hi[2]])
                probes.append(Probe(_v(target), (0.0, 0.0, 1.0), reach, f"{_OPEN} +z", middle=True))
            else:
                target = np.array([mid[0], mid[1], z_mid])
                probes.append(Probe(_v(target), _v(d), reach, f"{_OPEN} {_name(d)}", middle=True))
        probes += _far_closure_probes(model, rho)
        probes += _one_height_probes(model, centres, rho, gap)
        unique = {p.reason: p for p in reversed(probes)}  # the first of each direction
        return [p for p in probes if unique[p.reason] is p]
    poly = model.polyhedron
    probes += _bottom_probes(model, centres, rho, gap)
    top_touched = max(float(c.point[2]) for c in record.contacts)
    # a scan's surface (exact touches whose faces show detail) has rounded edges: a second
    # height touched on one (a probe at a face's end that met the rounding beside it) turns
    # the plane it lets the face span, and the face is tested half way there. Under declared
    # noise the faces' scatter cannot tell a scan's detail from the noise's chance (an ideal
    # box and cube touched with 0.5 mm of noise: 0.44 and 0.49 mm at the median; their
    # level-1 to level-3 scans: 0.38–0.60 mm)
    scan = record.noise <= 0 and surface_detail(model.faces) > SMOOTH_RHO * rho
    again: list[Probe] = []
    _, beside = rounded_edge_slack(poly, current().geometry.edge_rounding)
    reach_below, reach_above = _rounding_reach(poly, beside)
    for k, verts, face, n in _modelled_faces(model):
        if face.source == "contacts" and n[2] >= current().explore.top_nz:
            probes += _top_probes(face, poly.vertices[list(verts)], centres, rho)
            continue
        if face.source != "contacts" or abs(n[2]) > 0.9:
            continue  # tops and the table: not probed at another height
        own = centres[list(face.contacts)].reshape(-1, 3)
        zs = own[:, 2]
        rounded = False
        if scan and face.refined and len(zs) and float(zs.max() - zs.min()) >= gap:
            zone = rounding_zone(own, poly, k, rho, current().geometry.edge_rounding)
            flat = zs[~zone]
            if len(flat) and float(flat.max() - flat.min()) < gap:
                zs, rounded = flat, True
        if len(zs) and float(zs.max() - zs.min()) >= gap:
            if not face.refined and len(record.sensor_directions) >= RESOLVING_SENSORS:
                probes += _off_line_probes(face, n, poly.vertices[list(verts)], centres, rho)
            continue
        ring = poly.vertices[list(verts)]
        z0, z1 = float(ring[:, 2].min()), float(ring[:, 2].max())
        if z1 - z0 < 2.0 * rho:
            continue  # lower than the tip is wide: one height is all it can give
        margin = min(rho, 0.25 * (z1 - z0))
        # (half ρ more, and the tip centre's rise off a sloping face: clear of the rounding
        # zone, whose faces' widths move as the model grows, not on its border)
        below, above = (
            r + (0.5 + abs(float(n[2]))) * rho if r > 0 else 0.0
            for r in (float(reach_below[k]), float(reach_above[k]))
        )
        # the surface heights the tip can touch on this face, clear of its edges and of
        # their roundings (the tip centre stays 1.5 ρ above the table: scanned bottom edges
        # bulge)
        lo_z = max(z0 + max(margin, below), 1.5 * rho - rho * n[2])
        # no higher than the highest point touched: a side's outline above it comes from a
        # top not known yet (one touched along a line only tilts with its ridge)
        hi_z = min(z1 - max(margin, above), top_touched)
        if hi_z <= lo_z:
            continue
        have = float(zs.mean()) - rho * n[2] if len(zs) else 0.5 * (lo_z + hi_z)
        # the farther end first; the nearer one is the second attempt's (the model's outline
        # of a face touched along one line may reach where the object has another face)
        ends = [
            z for z in sorted((lo_z, hi_z), key=lambda e: -abs(e - have)) if abs(z - have) >= gap
        ]
        reason = f"the face facing {_name(n)} touched at one height"
        if rounded:
            # half way to the face's ends, clear of the rounding: a test of the plane that
            # the rounding's touches let the face span
            ends = [have + 0.5 * (z - have) for z in ends if 0.5 * abs(z - have) >= gap]
            reason = f"{_ROUNDED}: the face facing {_name(n)}"
        if not ends:
            continue  # the face is too low for two heights
        # such a face has a plane, turned or not: it is tested after the checks that find
        # what the model lacks (paths, corners)
        into = again if rounded else probes
        for z in ends:
            point = _section_point(ring, z)
            if point is not None:
                into.append(Probe(_v(point + rho * n), _v(n), 4.0 * rho, reason))
        if not face.refined and float(np.hypot(n[0], n[1])) > 1e-6 and face.contacts:
            # then, if that fails: its normal is the sensors' (quantised: a scanned face's
            # bump fires two sensors and gives their mean, tilted), and so is its outline;
            # approach level where its contacts are, at the other height
            flat = np.array([n[0], n[1], 0.0]) / float(np.hypot(n[0], n[1]))
            touched = centres[list(face.contacts)].mean(axis=0)
            for z in ends:
                target = touched.copy()
                target[2] = z + rho * n[2]
                into.append(Probe(_v(target), _v(flat), 4.0 * rho, reason + APPROACH_LEVEL))
    # a face left out as concave but touched at one height: its quantised normal may be what
    # made it look concave (an overhanging side read as vertical)
    probes += _one_height_probes(model, centres, rho, gap, concave=True)
    probes += _low_side_probes(model, centres, rho)
    probes += _beyond_model_probes(model, rho)
    probes += _free_path_probes(model, rho)
    probes += corner_probes(model)
    probes += again
    probes += second_spot_probes(model)
    return probes


def _rounding_reach(poly: Polyhedron, beside: FloatArray) -> tuple[FloatArray, FloatArray]:
    """How far up from its lowest point and down from its highest (z, metres) each face of
    ``poly`` may be rounded: the largest reach (``beside``, per edge:
    :func:`~tactile_kb.geometry.planes.rounded_edge_slack`) of its edges in its lower and its
    upper half, each times the face's slope across the edge; ``(below, above)``, (F,) each."""
    f_ = len(poly.faces)
    below, above = np.zeros(f_), np.zeros(f_)
    if len(poly.edges) == 0:
        return below, above
    ends = np.asarray(poly.edges, dtype=np.intp).reshape(-1, 2)
    a, b = poly.vertices[ends[:, 0]], poly.vertices[ends[:, 1]]
    d = (b - a) / np.maximum(np.linalg.norm(b - a, axis=1), 1e-12)[:, None]
    mid_z = 0.5 * (a[:, 2] + b[:, 2])
    face_mid = np.asarray(
        [
            0.5 * (float(poly.vertices[list(r), 2].min()) + float(poly.vertices[list(r), 2].max()))
            for r in poly.faces
        ]
    )
    for side in (0, 1):
        f = np.asarray(poly.edge_faces, dtype=np.intp).reshape(-1, 2)[:, side]
        reach = beside * np.abs(np.cross(poly.normals[f], d)[:, 2])  # the slope across
        upper = mid_z >= face_mid[f]
        np.maximum.at(above, f[upper], reach[upper])
        np.maximum.at(below, f[~upper], reach[~upper])
    return below, above


FAR_FACE_NZ = -0.5
"""A face whose normal's z component is below this (a deep undercut) is the last choice for a
probe towards a far closure (:func:`_far_closure_probes`): the finger meets it only indexed
upwards, near the table."""


def _far_closure_probes(model: ObjectModel, rho: float) -> list[Probe]:
    """Probes of the faces that meet far from the touched points, on the way there.

    Planes that close, but only far from where they were touched, leave the model open
    (:func:`~tactile_kb.geometry.polyhedron.polyhedron_from_planes`' ``bound``): a long end
    never explored, or a spike the contours never reached (an irregular tetrahedron's
    sharp corner on the table, beyond the lowest layer). A probe from that side at the
    middle of the touched heights meets the faces the model has, again. These probe a face
    through each far vertex (``model.open_points``) halfway there from the touched points,
    approached along its normal, the most upward-facing first: a touch on its plane carries
    the touched points towards the vertex (the model then closes within its bound, or the
    next such probe goes further); a touch elsewhere is a face the model lacked; nothing
    there, a face that ends sooner. The point probed must lie on the model's side of every
    other plane; the table is never probed."""
    if not model.open_points:
        return []
    record = model.record
    centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
    which = [k for k, s in enumerate(model.supporting) if s]
    normals = np.asarray([model.faces[k].normal for k in which], dtype=float).reshape(-1, 3)
    offsets = np.asarray([model.faces[k].offset for k in which], dtype=float)
    if len(centres) == 0 or len(normals) == 0:
        return []
    middle = centres.mean(axis=0)
    out: list[Probe] = []
    for d, v in zip(model.open_directions, model.open_points, strict=False):
        towards = np.asarray(d, dtype=float)
        far = np.asarray(v, dtype=float)
        size = float(np.linalg.norm(far - middle))
        tol = max(1e-4, 1e-3 * size)
        through = np.flatnonzero(np.abs(normals @ far - offsets) <= tol)
        halfway = 0.5 * (middle + far)
        order = sorted(
            (int(k) for k in through if normals[k, 2] > -0.95),
            key=lambda k: (normals[k, 2] < FAR_FACE_NZ, -normals[k, 2]),
        )
        for k in order:
            n = normals[k]
            spot = halfway + (offsets[k] - float(n @ halfway)) * n
            if float((normals @ spot - offsets).max()) > tol:
                continue  # beyond another plane: not on this face
            out.append(
                Probe(
                    _v(spot + rho * n),
                    _v(n),
                    4.0 * rho,
                    f"the planes close far towards {_name(towards)}",
                )
            )
            break
        # then straight along the open direction at the halfway point, from outside: a face
        # the model lacks (an undercut no contour met) cuts the open region on the way
        out.append(
            Probe(
                _v(halfway),
                _v(towards / float(np.linalg.norm(towards))),
                0.5 * size,
                f"the planes close far towards {_name(towards)}" + APPROACH_STRAIGHT,
            )
        )
    return out


def second_spot_probes(model: ObjectModel) -> list[Probe]:
    """Probes of the faces the model knows from one spot only, each at a second spot as far
    from the first as the face allows.

    A probe's touch and its short slide leave a few tip centres a few millimetres apart: a
    plane fitted through them (or the sensor's quantised normal, when they lie along one
    line) tilts by degrees under noise, and a plane that is wrong there moves the model's
    corners far from the object (an undercut face of a lying pyramid met once by an indexed
    probe). A face counts as touched at one spot when all its tip centres lie within
    ``explore.spot_rho`` × ρ of each other in its plane, or its plane is the sensor's (not
    fitted: the centres lie along a line, or are too few). It is probed again only when its
    normal's estimated uncertainty (``Face.normal_uncertainty_deg``) is at least
    ``explore.spot_deg``: exact touches fix a plane over one spot already, and a second
    probe of such a face, near an edge, only risks touching the edge.

    The second probe is aimed at the point of the face's polygon nearest its middle that
    lies ``spot_rho`` × ρ from the first touches, or else the one furthest from them (points
    sampled from its middle outwards to its corners and its edges' middles, clear of its
    edges by ρ/4, with the tip 1.5 ρ above the table; a sliver with no such point: its
    middle): the middle is the least likely to lie off the face when the model's outline of
    it is wrong (a neighbour's touch there only adds a neighbour's touch). It is approached
    along the face's normal (the head indexed when the face overhangs): its touch confirms
    the plane, or, landing elsewhere, corrects it. Faces with no such point at least ρ from
    the touches, the table and tops (touched from above along lines: :func:`_top_probes`) get
    none. Like the corner checks, these test the model and never hold the completion open;
    at most ``explore.spot_probes`` per exploration (:class:`ModelCompleter`).
    """
    poly = model.polyhedron
    record = model.record
    if poly is None or not record.contacts:
        return []
    rho = record.tip_radius
    spot = current().explore.spot_rho * rho
    centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
    top_nz = current().explore.top_nz
    out = []
    for _, verts, face, n in _modelled_faces(model):
        if face.source != "contacts" or not face.contacts or n[2] >= top_nz:
            continue
        pts = centres[list(face.contacts)]
        flat = pts - np.outer(pts @ n, n)  # the tip centres seen along the normal
        if face.normal_uncertainty_deg < current().explore.spot_deg or (
            face.refined
            and float(np.linalg.norm(flat[:, None, :] - flat[None, :, :], axis=2).max()) >= spot
        ):
            continue  # touched at two spots at least, and a plane fitted through them
        ring = poly.vertices[list(verts)]
        here = pts - rho * n  # the touched points on the face
        candidates = _inside_points(ring, 0.25 * rho)
        if len(candidates) == 0:  # a sliver (a plane through an edge's touches): its middle
            candidates = ring.mean(axis=0)[None, :]
        # the tip centre stays 1.5 ρ above the table
        candidates = candidates[candidates[:, 2] + rho * n[2] >= 1.5 * rho]
        if len(candidates) == 0:
            continue
        far = np.linalg.norm(candidates[:, None, :] - here[None, :, :], axis=2).min(axis=1)
        # the point nearest the middle (least likely off the face, should the model's outline
        # be wrong) a spot away from the touches; else the furthest
        apart = np.flatnonzero(far >= spot)
        best = int(apart[0]) if len(apart) else int(np.argmax(far))
        if float(far[best]) < rho:
            continue  # no second spot a tip radius away: the face is as known as it can be
        out.append(
            Probe(
                _v(candidates[best] + rho * n),
                _v(n),
                4.0 * rho,
                f"{_SPOT} at {_name(here.mean(axis=0) * 1000.0)} mm",
            )
        )
    return out


def _inside_points(ring: FloatArray, margin: float, steps: int = 4) -> FloatArray:
    """Points of the convex polygon ``ring`` at least about ``margin`` inside its edges: its
    middle, then the points 1/(``steps`` + 1), 2/(``steps`` + 1) … of the way from it to each
    corner and to each edge's middle (nearest the middle first), those within ``margin`` of
    an edge left out."""
    middle = ring.mean(axis=0)
    ends = np.vstack([ring, 0.5 * (ring + np.roll(ring, -1, axis=0))])
    t = np.arange(1, steps + 1)[:, None, None] / (steps + 1)
    pts = np.vstack([middle[None, :], (middle + t * (ends - middle)).reshape(-1, 3)])
    # distance of each point from each edge line (the polygon is convex and planar)
    a, b = ring, np.roll(ring, -1, axis=0)
    e = b - a
    length = np.linalg.norm(e, axis=1)
    keep = length > 1e-12
    a, e, length = a[keep], e[keep], length[keep]
    rel = pts[:, None, :] - a[None, :, :]
    along = (rel * e[None, :, :]).sum(axis=2) / length**2
    foot = a[None, :, :] + along[:, :, None] * e[None, :, :]
    inside = np.linalg.norm(pts[:, None, :] - foot, axis=2).min(axis=1) >= margin
    out: FloatArray = pts[inside]
    return out


def _beyond_model_probes(model: ObjectModel, rho: float) -> list[Probe]:
    """Probes from each side along x and y where the visual hint box (an axis-aligned box: its
    corners need not be the object's) reaches further than the model by more than 2 ρ.

    The controller records the hint box it was given (the object's visual extent, ``hint_lo_*``
    and ``hint_hi_*`` in ``record.params``). The contour layers lie at fixed fractions of its
    height: a part of the object lower than the first layer (an L-block's foot, standing on
    its end) or higher than the last is never touched, and the envelope of the rest stops
    short of the hint there. One probe from that side just above the table, aimed at the
    hint's middle, and one just under the model's top (1.5 ρ below its highest corner): they
    meet the part (a lid's handles, higher than the last layer), or the face the model has.
    A hint is an estimate (a scan's floating specks widen it): like the path's, these probes
    test the model and never hold the completion open.
    """
    params = model.record.params
    keys = [f"hint_{e}_{a}" for e in ("lo", "hi") for a in "xyz"]
    poly = model.polyhedron
    if poly is None or not all(k in params for k in keys):
        return []
    lo = np.array([params[k] for k in keys[:3]])
    hi = np.array([params[k] for k in keys[3:]])
    corners = np.array([[x, y] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])])
    mid = 0.5 * (lo + hi)
    reach = float(np.linalg.norm(hi[:2] - lo[:2])) + 4.0 * rho
    top = float(poly.vertices[:, 2].max())
    out = []
    for d in np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]):
        if float((corners @ d).max() - (poly.vertices[:, :2] @ d).max()) <= 2.0 * rho:
            continue
        towards = _name(np.append(d, 0.0))
        out.append(
            Probe(
                (float(mid[0]), float(mid[1]), 1.5 * rho),
                (float(d[0]), float(d[1]), 0.0),
                reach,
                f"{_HINT} towards {towards}",
                middle=True,
            )
        )
        # and just under the model's top: a part higher than the last layer (a lid's handles)
        out.append(
            Probe(
                (float(mid[0]), float(mid[1]), top - 1.5 * rho),
                (float(d[0]), float(d[1]), 0.0),
                reach,
                f"{_HINT} towards {towards}, under the top",
                middle=True,
            )
        )
    return out


def _free_path_probes(model: ObjectModel, rho: float, *, most: int = 4) -> list[Probe]:
    """Probes where the finger passed through what the model says is the object.

    The tip centre moved freely along the contour layers' paths: the object lies at least ρ
    from every point of them (a touch stops the motion there, a slide keeps ρ). Where the path comes
    nearer than that to the model's convex envelope, by more than a quarter of ρ (and 3σ of
    noise), the envelope reaches where the object does not: a corner the contour went round
    is cut by a face no touch found (a lying frustum's small end). One probe at the deepest
    such point of each stretch, approached along the direction from the envelope to it; at
    most ``most``, deepest first. None for a non-convex model, whose envelope spans its
    hollows.
    """
    poly = model.polyhedron
    paths = [np.asarray(layer.path, dtype=float).reshape(-1, 3) for layer in model.record.layers]
    paths = [p for p in paths if len(p) >= 2]
    if poly is None or not model.convex or not paths:
        return []
    tol = 0.25 * rho + 3.0 * model.record.noise
    # the contour paths' segments sampled every quarter ρ
    a = np.vstack([p[:-1] for p in paths])
    b = np.vstack([p[1:] for p in paths])
    steps = np.maximum(1, np.ceil(np.linalg.norm(b - a, axis=1) / (0.25 * rho))).astype(int)
    t = np.concatenate([np.arange(k) / k for k in steps])
    seg = np.repeat(np.arange(len(a)), steps)
    x = np.vstack([a[seg] + t[:, None] * (b[seg] - a[seg]), b[-1:]])
    # a point further than ρ − tol from some face's plane is at least that far from the
    # envelope; the others' exact distance from its nearest point
    near = np.flatnonzero((x @ poly.normals.T - poly.offsets).max(axis=1) < rho - tol)
    if len(near) == 0:
        return []
    q = nearest_points(x[near], poly.normals, poly.offsets)
    gap = x[near] - q
    dist = np.linalg.norm(gap, axis=1)
    deep = dist < rho - tol
    if deep.any() and len(poly.edges):
        # a path round a rounded edge passes nearer its sharp edge by up to the rounding's
        # slack, where its nearest point lies on the rounding (beside the edge)
        inside, beside = rounded_edge_slack(poly, current().geometry.edge_rounding)
        ends = np.asarray(poly.edges, dtype=np.intp).reshape(-1, 2)
        which = np.flatnonzero(deep)
        on = segment_distances(q[which], poly.vertices[ends[:, 0]], poly.vertices[ends[:, 1]])
        slack = np.where(on <= beside[None, :], inside[None, :], 0.0).max(axis=1)
        deep[which] = dist[which] < rho - tol - slack
    if not deep.any():
        return []
    pts, qs, ds = x[near][deep], q[deep], dist[deep]
    out: list[Probe] = []
    taken: list[FloatArray] = []
    for i in np.argsort(ds):
        c = pts[i]
        if any(float(np.linalg.norm(c - p)) < 4.0 * rho for p in taken):
            continue
        if ds[i] > 1e-9:
            n = (c - qs[i]) / ds[i]
        else:  # on the envelope's surface: the nearest face's normal
            n = poly.normals[int(np.argmax(poly.normals @ c - poly.offsets))]
        taken.append(c)
        out.append(
            Probe(
                _v(c),
                _v(n),
                4.0 * rho,
                f"{_PATH} at {_name(c * 1000.0)} mm",
            )
        )
        if len(out) >= most:
            break
    return out


def corner_juts(model: ObjectModel) -> FloatArray:
    """How far (m) each vertex of the model's polyhedron lies outside the convex hull of the
    touched points (the contacts' surface points ``r1``); zeros without a polyhedron.

    A corner of the envelope is where the planes of touched faces meet: no touch found it.
    Where it lies far outside what was touched, a face nobody touched may cut it off.
    """
    poly = model.polyhedron
    if poly is None:
        return np.zeros(0)
    pts = np.asarray([c.point for c in model.record.contacts], dtype=float).reshape(-1, 3)
    verts = np.asarray(poly.vertices, dtype=float)
    if len(pts) == 0:
        return np.zeros(len(verts))
    hull = _touched_hull(model)
    if hull is None:  # the touched points lie in a plane: their distances
        return np.asarray(
            np.linalg.norm(verts[:, None, :] - pts[None, :, :], axis=2).min(axis=1), dtype=float
        )
    from trimesh.triangles import closest_point

    tris = pts[hull.simplices]
    out = np.zeros(len(verts))
    outside = np.flatnonzero(
        (verts @ hull.equations[:, :3].T + hull.equations[:, 3]).max(axis=1) > 0
    )
    if len(outside):  # the nearest point of every hull triangle to every corner outside it
        q = np.repeat(verts[outside], len(tris), axis=0)
        foot = closest_point(np.tile(tris, (len(outside), 1, 1)), q)  # type: ignore[no-untyped-call]
        dist = np.linalg.norm(foot - q, axis=1).reshape(len(outside), len(tris))
        out[outside] = dist.min(axis=1)
    return out


def _touched_hull(model: ObjectModel) -> ConvexHull | None:
    """The convex hull of the touched points (the contacts' ``r1``), or None when they span
    no volume."""
    pts = np.asarray([c.point for c in model.record.contacts], dtype=float).reshape(-1, 3)
    if len(pts) < 4:
        return None
    try:
        return ConvexHull(pts)
    except (QhullError, ValueError):
        return None


def _ray_into(hull: ConvexHull, start: FloatArray, direction: FloatArray) -> float | None:
    """How far from ``start`` along ``direction`` the line enters the convex ``hull`` (0 when
    it starts inside), or None when it misses it."""
    a, b = hull.equations[:, :3], hull.equations[:, 3]
    side = a @ start + b  # ≤ 0 inside each plane
    rate = a @ direction
    enter, leave = 0.0, math.inf
    for s_k, r_k in zip(side, rate, strict=True):
        if abs(r_k) < 1e-12:
            if s_k > 0:
                return None
            continue
        t = -s_k / r_k
        if r_k < 0:
            enter = max(enter, t)
        else:
            leave = min(leave, t)
    return enter if enter <= leave else None


def corner_probes(model: ObjectModel) -> list[Probe]:
    """Probes that test the model's corners that jut out from the touched points, furthest
    first.

    A closed envelope can still be wrong: a face no touch found is cut off the model, and the
    planes of its neighbours meet in a corner where the object is not (a lying pyramid's
    undercut side, a face above the top layer). Such a corner lies further outside the convex
    hull of the touched points (:func:`corner_juts`) than the model's other corners, which the
    contour layers' spacing keeps alike. A corner is tested when it juts out more than

    * :data:`CORNER_OUTLIER` × the median of the model's corners,
    * 2 ρ + 3 σ (a corner within the tip's size of the touches is as good as touched; σ the
      declared noise), and 5 % of the model's diameter (a smaller cut changes no feature);

    and no face the model left out as concave, with a plane its tip centres fitted, cuts it off
    (the hollow of an L-block is known already; an unrefined concave face has the sensor's
    quantised normal, which may be what made it look concave). The probe approaches along the
    corner's outward direction (the mean of its faces' normals), aimed at it from outside, and
    may go on past it until the line enters the touched hull, plus 2 ρ (when that line misses
    the hull, it aims from the corner at the hull's middle instead). A touch at the corner
    confirms it (and puts it in the touched hull); a touch deeper in is a face the model lacks,
    which the next model has. Corners whose direction points down are left to the probes near
    the table (:func:`_bottom_probes`); corners on the table get level probes
    (:func:`_table_corner_probes`) when no side of the model overhangs.
    """
    poly = model.polyhedron
    record = model.record
    if poly is None or not record.contacts:
        return []
    rho, sigma = record.tip_radius, record.noise
    juts = corner_juts(model)
    hull = _touched_hull(model)
    if len(juts) < 4 or hull is None:
        return []
    middle = np.asarray(hull.points, dtype=float).mean(axis=0)
    size = float(np.linalg.norm(np.ptp(poly.vertices, axis=0)))
    limit = max(2.0 * rho + 3.0 * sigma, 0.05 * size, CORNER_OUTLIER * float(np.median(juts)))
    tol = 0.25 * rho + 3.0 * sigma
    # concave faces whose plane the tip centres fitted (an unrefined one has the sensor's
    # quantised normal, which may be what made it look concave)
    concave = [
        f
        for f, keep in zip(model.faces, model.supporting, strict=False)
        if not keep and f.source == "contacts" and f.refined
    ]
    table = {
        k
        for k in range(len(poly.faces))
        if k < len(model.face_of)
        and model.face_of[k] >= 0
        and model.faces[model.face_of[k]].source == "table"
    }
    # corners beyond an edge the touches found inside a face of the model: tested whether
    # or not they jut out more than the others
    beyond = _beyond_unexplained_edges(model)
    past_hint = _past_the_hint(model)
    beyond |= past_hint
    floor = max(2.0 * rho + 3.0 * sigma, 0.05 * size)
    out: list[Probe] = []
    for i in np.argsort(-juts):
        jut = float(juts[i])
        if jut <= (floor if int(i) in beyond else limit):
            if jut <= floor:
                break
            continue
        v = np.asarray(poly.vertices[i], dtype=float)
        if any(float(f.normal_array @ v) - f.offset > tol for f in concave):
            continue
        around = [k for k, verts in enumerate(poly.faces) if int(i) in verts]
        normals = poly.normals[[k for k in around if k not in table]]
        if len(normals) == 0:
            continue
        n = normals.sum(axis=0)
        if float(np.linalg.norm(n)) < 1e-9:
            continue
        n = n / float(np.linalg.norm(n))
        if len(around) > len(normals) or n[2] < -0.2:
            continue  # on the table or under the object: see below, and the bottom probes
        depth = _ray_into(hull, v, -n)
        if depth is None:  # the line misses what was touched: aim at its middle instead
            n = v - middle
            n = n / float(np.linalg.norm(n))
            depth = _ray_into(hull, v, -n)
            if depth is None or n[2] < -0.2:
                continue
        target = v + rho * n
        out.append(
            Probe(_v(target), _v(n), depth + 2.0 * rho, f"{_CORNER} at {_name(v * 1000.0)} mm")
        )
    for p in _table_corner_probes(model, hull, table, past_hint):
        if not any(float(f.normal_array @ np.asarray(p.target)) - f.offset > tol for f in concave):
            out.append(p)
    return out


def _beyond_unexplained_edges(model: ObjectModel) -> set[int]:
    """The model's corners beyond an edge that the touches found and the model lacks.

    A touch the model sets apart as an edge's (``options["edge_contacts"]``: its sensor turned
    between two faces' normals) whose surface point lies further than ``EDGE_EXPLAINED`` ρ
    (or 4 σ of the declared noise) from every edge of the model's polyhedron touched an edge
    inside one of the model's faces: a face nobody touched begins there (a disc standing on a
    narrow side of its octagon, whose contour layer passed just above the top of a vertical
    side; the model runs that side on to the top and closes as a box). The corners of the
    faces it lies on that lie the way its sensor tilts out of the face (towards the face not
    found) are returned; :func:`corner_probes` tests them however the model's other corners
    jut out (all a model's corners jut out alike when a whole band of faces is missing)."""
    poly = model.polyhedron
    record = model.record
    edge = model.options.get("edge_contacts", ())
    if poly is None or not edge or not isinstance(edge, tuple):
        return set()
    rho, sigma = record.tip_radius, record.noise
    tol = max(EDGE_EXPLAINED * rho, 4.0 * sigma)
    verts = np.asarray(poly.vertices, dtype=float)
    ends = np.asarray(poly.edges, dtype=int).reshape(-1, 2)
    a, b = verts[ends[:, 0]], verts[ends[:, 1]]
    # a touch on a rounded edge lies up to the rounding's reach beside the sharp edge
    _, beside = rounded_edge_slack(poly, current().geometry.edge_rounding)
    out: set[int] = set()
    for i in edge:
        if not isinstance(i, int) or not 0 <= i < len(record.contacts):
            continue
        c = record.contacts[i]
        p = np.asarray(c.point, dtype=float)
        if float((segment_distances(p[None, :], a, b)[0] - beside).min()) <= tol:
            continue  # an edge of the model (rounded or not): explained
        outward = -np.asarray(c.direction, dtype=float)
        for k, ring in enumerate(poly.faces):
            n = poly.normals[k]
            if abs(float(n @ p) - float(poly.offsets[k])) > tol:
                continue
            tilt = outward - float(outward @ n) * n  # towards the face not found
            if float(np.linalg.norm(tilt)) < math.sin(math.radians(5.0)):
                continue
            out.update(int(j) for j in ring if float((verts[int(j)] - p) @ tilt) > 0.0)
    return out


def _past_the_hint(model: ObjectModel) -> set[int]:
    """The model's corners further than 2 ρ + 3 σ from the visual hint box (``hint_lo_*``,
    ``hint_hi_*`` in ``record.params``: the object's visual extent, grown by the tip).

    The object lies inside its hint: a corner that far outside it is where the planes of
    touched faces run on past a face nobody touched (a lying frustum's small end, its sides
    meeting in an apex 2 cm past the object's end). :func:`corner_probes` tests them however
    the other corners jut out, and on the table also when a side overhangs."""
    poly = model.polyhedron
    params = model.record.params
    keys = [f"hint_{e}_{a}" for e in ("lo", "hi") for a in "xyz"]
    if poly is None or not all(k in params for k in keys):
        return set()
    lo = np.array([params[k] for k in keys[:3]])
    hi = np.array([params[k] for k in keys[3:]])
    margin = 2.0 * model.record.tip_radius + 3.0 * model.record.noise
    verts = np.asarray(poly.vertices, dtype=float)
    # the distance from the box (a corner past a box's corner lies out along two axes)
    outside = np.linalg.norm(np.maximum(lo - verts, 0.0) + np.maximum(verts - hi, 0.0), axis=1)
    return {int(i) for i in np.flatnonzero(outside > margin)}


def _table_corner_probes(
    model: ObjectModel, hull: ConvexHull, table: set[int], past_hint: set[int] | None = None
) -> list[Probe]:
    """Level probes of the model's corners on the table that jut out sideways beyond
    everything touched: further than 2 ρ + 3 σ, 5 % of the model's diameter and
    :data:`CORNER_OUTLIER` × the median of the table corners outside the convex hull of the
    touched points seen from above.

    Seen from above, the table corners of a lying prism or pyramid lie under its touched
    sides (inside that outline); a corner far outside it is where the planes of touched
    sides run on past a face nobody touched (a lying frustum's overhanging end).

    Asked only of a model none of whose sides overhangs (turns down by more than
    ``explore.overhang_deg``): then the object lies inside the model, and a table corner far
    from every touch can only be cut off by a face not found yet; and of the corners in
    ``past_hint`` (:func:`_past_the_hint`), which no face of the object reaches, in any case. A side that overhangs
    puts the model's table corners where its plane, known from a touch or two, meets the
    table; a level probe there meets the undercut's edge, whose touches fit no face (the
    lying hexagonal pyramids of the stable-pose benchmark), so those corners are left to
    :func:`_bottom_probes` and :func:`second_spot_probes`.
    """
    poly = model.polyhedron
    assert poly is not None
    rho, sigma = model.record.tip_radius, model.record.noise
    pts = np.asarray([c.point for c in model.record.contacts], dtype=float)[:, :2]
    try:
        outline = ConvexHull(pts)
    except (QhullError, ValueError):
        return []
    verts = np.asarray(poly.vertices, dtype=float)
    size = float(np.linalg.norm(np.ptp(verts, axis=0)))
    limit = max(2.0 * rho + 3.0 * sigma, 0.05 * size)
    out = (verts[:, :2] @ outline.equations[:, :2].T + outline.equations[:, 2]).max(axis=1)
    around = [[k for k, face in enumerate(poly.faces) if i in face] for i in range(len(verts))]
    on_table = [i for i in range(len(verts)) if any(k in table for k in around[i])]
    sides = [k for k in range(len(poly.faces)) if k not in table]
    overhang = math.sin(math.radians(current().explore.overhang_deg))
    past = past_hint or set()
    if not on_table:
        return []
    if float(poly.normals[sides, 2].min()) < -overhang:
        on_table = [i for i in on_table if i in past]  # an overhang: only what no face reaches
        if not on_table:
            return []
        limit = math.inf
    else:
        # the table corners of a model whose sides were all touched lie alike outside that
        # outline (the layers' spacing): an outlier among them is tested
        limit = max(limit, CORNER_OUTLIER * float(np.median(out[on_table])))
    probes = []
    for i in sorted(on_table, key=lambda j: -float(out[j])):
        if float(out[i]) <= limit and i not in past:
            continue
        sides = [k for k in around[i] if k not in table]
        if not sides:
            continue
        n = poly.normals[sides].sum(axis=0)
        probe = _table_corner_probe(verts[i], n, hull, rho)
        if probe is not None:
            probes.append(probe)
    return probes


def _table_corner_probe(v: FloatArray, n: FloatArray, hull: ConvexHull, rho: float) -> Probe | None:
    """A level probe of a modelled corner ``v`` on the table that juts out (``n``: its side
    faces' mean normal): the tip centre 1.5 ρ above the table, approaching horizontally
    along ``n`` as far in as the touched points' middle, plus 2 ρ.

    A face nobody touched that cuts such a corner (a lying frustum's overhanging end) faces
    outwards and down: the head is indexed so that the tip points inwards and up (as for a
    blind contact, :func:`_blind_probes`), and a sensor facing the face fires. Its one touch
    is then confirmed elsewhere (:func:`second_spot_probes`).
    """
    n = n / max(float(np.linalg.norm(n)), 1e-12)
    flat = np.array([n[0], n[1], 0.0])
    if float(np.linalg.norm(flat)) < 0.3:
        return None  # a corner facing up or down: no level approach reaches it
    flat = flat / float(np.linalg.norm(flat))
    z = 1.5 * rho
    start = np.array([v[0], v[1], z])
    # as far in as the touched points' middle (the tip stops at whatever it meets)
    middle = np.asarray(hull.points, dtype=float).mean(axis=0)
    depth = float((v - middle)[:2] @ flat[:2])
    if depth <= 0.0:
        return None
    return Probe(
        _v(start + rho * flat),
        _v(flat),
        depth + 2.0 * rho,
        f"{_CORNER} at {_name(v * 1000.0)} mm",
        facing=_v((np.array([0.0, 0.0, 1.0]) - flat) / math.sqrt(2.0)),
    )


def _modelled_faces(model: ObjectModel) -> Iterator[tuple[int, list[int], Face, FloatArray]]:
    """Each polyhedron face the model maps to a face: its index in the polyhedron, its
    vertices, the model's face and that face's unit normal."""
    poly = model.polyhedron
    assert poly is not None
    for k, verts in enumerate(poly.faces):
        found = _modelled_face(model, k)
        if found is not None:
            yield k, list(verts), *found


def _modelled_face(model: ObjectModel, k: int) -> tuple[Face, FloatArray] | None:
    """The model face behind polyhedron face ``k`` and its unit normal, or None when the model
    maps no face to it."""
    index = model.face_of[k] if k < len(model.face_of) else -1
    if index < 0:
        return None
    face = model.faces[index]
    return face, np.asarray(face.normal, dtype=float)


def _low_side_probes(model: ObjectModel, centres: FloatArray, rho: float) -> list[Probe]:
    """Probes from above at the top edge of each side face touched only in its lower half.

    The layers end when the contact is lost after a z increment (a step up the object, as
    from an L-block's foot to its leg); the model then extends the foot's end face up to the
    top. A touch from above, 2 ρ inside the face's top edge, meets the top there (a box) or a
    lower step (the foot's top: a concave face).
    """
    poly = model.polyhedron
    assert poly is not None
    out = []
    for _, verts, face, n in _modelled_faces(model):
        if face.source != "contacts" or abs(n[2]) > 0.3 or not face.contacts:
            continue
        ring = poly.vertices[list(verts)]
        z0, z1 = float(ring[:, 2].min()), float(ring[:, 2].max())
        touched = float(centres[list(face.contacts), 2].max())
        if z1 - z0 < 4.0 * rho or touched - z0 > 0.5 * (z1 - z0):
            continue
        edge = ring[ring[:, 2] >= z1 - 0.25 * rho]
        inwards = -np.array([n[0], n[1], 0.0]) / max(float(np.linalg.norm(n[:2])), 1e-9)
        point = edge.mean(axis=0) + 2.0 * rho * inwards
        out.append(
            Probe(
                (float(point[0]), float(point[1]), z1 + rho),
                (0.0, 0.0, 1.0),
                z1 - z0,
                f"the face facing {_name(n)} touched only low: its top probed from above",
            )
        )
    return out


def _one_height_probes(
    model: ObjectModel, centres: FloatArray, rho: float, gap: float, *, concave: bool = False
) -> list[Probe]:
    """For an open model (or, with ``concave``, for the faces a closed one left out as
    concave): a probe at another height for each side face whose tip centres lie at one
    height.

    Such a face's normal is the sensor's, quantised (an overhanging side felt by the
    vertical finger's equator reads as vertical), so the planes may close far from the object
    or not at all; a second height fits its slope. The other height is 2 ρ (or a quarter of
    the touched height) below the face's contacts, or above them when that is too near the
    table, never above the highest point touched.
    """
    top = max(float(c.point[2]) for c in model.record.contacts)
    delta = max(2.0 * rho, 0.25 * top)
    out = []
    for k, face in enumerate(model.faces):
        n = np.asarray(face.normal, dtype=float)
        if face.source != "contacts" or abs(n[2]) > 0.9 or not face.contacts:
            continue
        if concave and (k >= len(model.supporting) or model.supporting[k]):
            continue
        pts = centres[list(face.contacts)]
        if float(np.ptp(pts[:, 2])) >= gap:
            continue
        z0 = float(pts[:, 2].mean())
        lowest = 1.5 * rho
        z = z0 - delta if z0 - delta >= lowest else z0 + delta
        if z > top or z < lowest:
            continue
        target = pts.mean(axis=0)
        target[2] = z
        out.append(
            Probe(
                _v(target),
                _v(n),
                4.0 * rho + delta,
                f"the face facing {_name(n)} touched at one height",
            )
        )
    return out


def _distance_to(poly: Polyhedron, point: FloatArray) -> float:
    """Distance (m) from ``point`` to the convex polyhedron ``poly`` (negative inside: minus
    the distance to the nearest face's plane)."""
    s = poly.normals @ point - poly.offsets
    if float(s.max()) <= 0.0:
        return float(s.max())
    best = math.inf
    for k, verts in enumerate(poly.faces):
        if s[k] <= 0.0:
            continue  # a face turned away from the point is never the nearest
        ring = poly.vertices[list(verts)]
        n = poly.normals[k]
        foot = point - s[k] * n
        edges = np.roll(ring, -1, axis=0) - ring
        if (
            np.einsum("ij,ij->i", np.cross(edges, foot - ring), np.broadcast_to(n, ring.shape)) >= 0
        ).all():
            best = min(best, float(s[k]))
            continue
        t = np.clip(np.einsum("ij,ij->i", point - ring, edges) / (edges * edges).sum(axis=1), 0, 1)
        closest = ring + t[:, None] * edges
        best = min(best, float(np.linalg.norm(closest - point, axis=1).min()))
    return best


def _blind_probes(model: ObjectModel) -> list[Probe]:
    """Probes at the blind contacts the model does not explain, the head indexed so that the
    tip points along the blocked motion and up.

    A motion blocked with no sensor closed met the object where no sensor faces: an overhang
    above the tip (a lying prism's lower side, a pyramid on a lateral face). The model explains
    it when its surface lies one tip radius from the tip centre there; otherwise the probe
    approaches the same point along the same direction, the head indexed towards the motion
    tilted upwards (:meth:`~tactile_kb.touch.finger.Finger.index_towards`), so that a sensor
    faces what blocked it. Blind contacts closer than 2 ρ to one already listed give no probe.
    """
    record = model.record
    if not record.blind:
        return []
    rho = record.tip_radius
    tol = 0.25 * rho + 3.0 * record.noise
    poly = model.polyhedron
    faces = [f for f in model.faces if f.source == "contacts"]
    out: list[Probe] = []
    listed: list[FloatArray] = []
    for point, direction in record.blind:
        c = np.asarray(point, dtype=float)
        d = np.asarray(direction, dtype=float)
        h = np.array([d[0], d[1], 0.0])
        if float(np.linalg.norm(h)) < 0.5:
            continue  # blocked going up or down: no horizontal approach reaches it
        h /= float(np.linalg.norm(h))
        if any(float(np.linalg.norm(c - q)) < 2.0 * rho for q in listed):
            continue
        if poly is not None:
            explained = abs(_distance_to(poly, c) - rho) <= tol
        else:
            explained = any(
                abs(float(f.normal_array @ c) - f.offset - rho) <= tol
                and float(f.normal_array @ h) < -0.1
                for f in faces
            )
        if explained:
            continue
        listed.append(c)
        out.append(
            Probe(
                _v(c),
                _v(-h),
                4.0 * rho,
                f"a blind contact at {_name(c * 1000.0)} mm",
                facing=_v((h + np.array([0.0, 0.0, 1.0])) / math.sqrt(2.0)),
            )
        )
    return out


def _bottom_probes(model: ObjectModel, centres: FloatArray, rho: float, gap: float) -> list[Probe]:
    """Probes near the table of the sloping faces the model extends down to the table.

    The model closes the envelope with the table, as if the object rested on a face there.
    A face that is not vertical and meets the table in the model was touched higher up only;
    the object may turn under it (a prism lying on a side, an icosahedron on a vertex): one
    probe at the lowest height the tip reaches on it, approached along its normal (the head
    indexed when the face overhangs). A touch there confirms it; a touch elsewhere is a face
    not seen yet and reshapes the model. Asked only when the exploration met the object blind
    (``record.blind``, a contact no sensor felt): the sign of a surface turning under.
    """
    poly = model.polyhedron
    record = model.record
    if poly is None or not record.blind:
        return []  # nothing met the finger where no sensor faced: no sign of an undercut
    table = [
        k
        for k in range(len(poly.faces))
        if k < len(model.face_of)
        and model.face_of[k] >= 0
        and model.faces[model.face_of[k]].source == "table"
    ]
    if not table:
        return []
    beside = {b for a, b in poly.edge_faces if a in table} | {
        a for a, b in poly.edge_faces if b in table
    }
    points = np.asarray([c.point for c in record.contacts], dtype=float).reshape(-1, 3)
    out = []
    for k in sorted(beside - set(table)):
        found = _modelled_face(model, k)
        if found is None:
            continue
        face, n = found
        if face.source != "contacts" or abs(n[2]) < math.sin(math.radians(3.0)) or n[2] > 0.9:
            continue  # vertical faces meet the table as the layers saw them; tops do not
        if -math.sin(math.radians(20.0)) <= n[2] < 0.0:
            continue  # felt by the vertical finger down to its lowest layer (an octahedron)
        ring = poly.vertices[list(poly.faces[k])]
        z0, z1 = float(ring[:, 2].min()), float(ring[:, 2].max())
        low = max(z0 + 0.5 * rho, 1.5 * rho - rho * float(n[2]))  # the tip stays off the table
        if low >= z1 - 0.5 * rho:
            continue
        touched = points[list(face.contacts), 2] if face.contacts else np.zeros(0)
        if len(touched) and float(touched.min()) <= low + max(2.0 * rho, gap):
            continue  # touched near the table already
        point = _section_point(ring, low)
        out_h = np.array([n[0], n[1], 0.0])
        if point is None or float(np.linalg.norm(out_h)) < 1e-6:
            continue
        out_h /= float(np.linalg.norm(out_h))
        # approached horizontally with the tip pointing inwards: what is there (the face, or
        # a face turning under it) faces the tip's front hemisphere either way
        out.append(
            Probe(
                _v(point + rho * n),
                _v(out_h),
                float(np.ptp(poly.vertices[:, 0]) + np.ptp(poly.vertices[:, 1])),
                f"the face facing {_name(n)} not touched near the table",
                facing=_v(-out_h),
            )
        )
    return out


def _off_line_probes(
    face: Face, n: FloatArray, ring: FloatArray, centres: FloatArray, rho: float
) -> list[Probe]:
    """A probe off the line of a side face's tip centres, when they lie along one line.

    Probes that touch a face slide a little: two of them, at two heights, leave the face's
    centres along one line, which fits any plane through it, so the face keeps its sensor's
    quantised normal (and four such faces meeting at an apex split it). One more touch
    across the line fits the plane: halfway from the line to the face's far side, approached
    along the face's normal. None when the face is narrower than the tip across the line.
    """
    pts = centres[list(face.contacts)]
    if len(pts) < 2:
        return []
    mid = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - mid, full_matrices=False)
    across = np.cross(n, vt[0])
    length = float(np.linalg.norm(across))
    if length < 1e-9:
        return []
    across /= length
    surface = mid - rho * n
    side = (ring - surface) @ across
    far = float(side.max()) if side.max() >= -side.min() else float(side.min())
    if abs(far) < 2.0 * rho:
        return []
    point = surface + 0.5 * far * across
    return [
        Probe(
            _v(point + rho * n),
            _v(n),
            4.0 * rho,
            f"the face facing {_name(n)} touched along one line",
        )
    ]


def _top_probes(face: Face, ring: FloatArray, centres: FloatArray, rho: float) -> list[Probe]:
    """Probes from above beside a top whose tip centres lie along one line.

    A touch from above that lands on a ridge (a gabled carton's seal) slides along it, and the
    line of tip centres fits any plane through the ridge: the top is not known until it is
    touched off that line. Two probes, one each side of the line, halfway to the face's
    border; none when the centres already span the face (more than ρ / 2 across the line).
    """
    pts = centres[list(face.contacts), :2] if face.contacts else np.zeros((0, 2))
    if len(pts) < 2:
        return []
    mid = pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(pts - mid, full_matrices=False)
    if len(sv) > 1 and sv[1] / math.sqrt(len(pts)) >= 0.5 * rho:
        return []
    across = np.array([-vt[0, 1], vt[0, 0]])
    half = float(np.abs((ring[:, :2] - mid) @ across).max())
    if half < rho:
        return []
    n = np.asarray(face.normal, dtype=float)
    top = float(ring[:, 2].max()) + rho
    reach = float(np.ptp(ring[:, 2])) + 4.0 * rho
    out = []
    for sign, side in APPROACH_SIDES.items():
        xy = mid + sign * 0.5 * half * across
        out.append(
            Probe(
                (float(xy[0]), float(xy[1]), top),
                (0.0, 0.0, 1.0),
                reach,
                f"the top facing {_name(n)} touched along one line" + side,
            )
        )
    return out


def _section_point(ring: FloatArray, z: float) -> FloatArray | None:
    """The middle of the face polygon ``ring`` at height ``z`` (mean of its edges' crossings)."""
    pts = []
    for a, b in zip(ring, np.roll(ring, -1, axis=0), strict=True):
        if (a[2] - z) * (b[2] - z) <= 0 and abs(b[2] - a[2]) > 1e-12:
            t = (z - a[2]) / (b[2] - a[2])
            pts.append(a + t * (b - a))
    if not pts:
        return None
    point: FloatArray = np.mean(pts, axis=0)
    return point


def _over_the_rim(record: ExplorationRecord, probe: Probe) -> Probe:
    """The probe from above moved over the highest touched point, 1.5 ρ inwards: when the
    middle of the object is a cavity (a mug), its top is a rim next to the highest contact."""
    centres = np.asarray([c.centre for c in record.contacts], dtype=float)
    top = centres[int(np.argmax(centres[:, 2]))]
    mid = np.asarray(probe.target, dtype=float)
    inwards = np.array([mid[0] - top[0], mid[1] - top[1], 0.0])
    length = float(np.linalg.norm(inwards))
    if length < 1e-9:
        return probe
    point = top + inwards / length * min(length, 1.5 * record.tip_radius)
    return Probe(_v(point), probe.normal, probe.reach, probe.reason, middle=False)


def _at_the_far_touches(record: ExplorationRecord, probe: Probe) -> Probe:
    """``probe`` (towards an open side) again, at the height of the touch that reached
    furthest that way: the first, at the middle of the touched heights, met what was there
    already (the face above an L-block's foot, concave), and the part still open lies at
    the height where the touches went furthest. When the first was at that height already,
    the second approaches in line with a point touched on a face facing the other way (the
    middle of the hint box may be empty: the notch of an L-block lying on its arms)."""
    d = np.asarray(probe.normal, dtype=float)
    centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
    far = centres[int(np.argmax(centres @ d))]
    if abs(float(far[2]) - probe.target[2]) >= record.tip_radius:
        return Probe(
            (probe.target[0], probe.target[1], float(far[2])),
            probe.normal,
            probe.reach,
            probe.reason,
            middle=True,
        )
    # behind a point touched on a face facing the other way the object is solid: the one
    # nearest the middle of those points
    points = np.asarray([c.point for c in record.contacts], dtype=float).reshape(-1, 3)
    normals = -np.asarray([c.direction for c in record.contacts], dtype=float).reshape(-1, 3)
    back = points[normals @ d <= -math.cos(math.radians(45.0))]
    if not len(back):
        return probe
    point = back[int(np.argmin(np.linalg.norm(back - back.mean(axis=0), axis=1)))]
    return Probe(_v(point), probe.normal, probe.reach, probe.reason)


def _nearer_the_touches(record: ExplorationRecord, probe: Probe) -> Probe:
    """``probe`` (approached sideways) again, aimed halfway to the nearest tip centre that
    touched a surface facing about the same way (within 45°).

    A probe placed from the model at a face's other height, or near the table, found nothing:
    the model's face there extends beyond the object (its normal is the sensor's, quantised,
    or a face the model lacks cuts it off). The same probe again would find nothing again;
    halfway to where that face was touched it lies on the object if the face reaches there.
    """
    n = np.asarray(probe.normal, dtype=float)
    centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
    normals = -np.asarray([c.direction for c in record.contacts], dtype=float).reshape(-1, 3)
    near = normals @ n >= math.cos(math.radians(45.0))
    if not near.any():
        return probe
    target = np.asarray(probe.target, dtype=float)
    pool = centres[near]
    nearest = pool[int(np.argmin(np.linalg.norm(pool - target, axis=1)))]
    moved = 0.5 * (target + nearest)
    return Probe(_v(moved), probe.normal, probe.reach, probe.reason, facing=probe.facing)


def _v(a: FloatArray) -> tuple[float, float, float]:
    return (float(a[0]), float(a[1]), float(a[2]))


_BUILD_ERRORS = (TactileKBError, np.linalg.LinAlgError, ValueError)
"""What building the model of a record so far may raise: the completion then ends."""

_MODEL_INPUTS = {"contacts", "layers", "noise", "tip_radius", "sensor_directions"}
"""The fields of a record :func:`~tactile_kb.geometry.model.build_model` reads."""


class ModelCompleter:
    """A :class:`~tactile_kb.touch.servo.Completer`: probes from the model of the record so far.

    Parameters
    ----------
    params
        The budget and thresholds (default :data:`DEFAULT_COMPLETION`).
    """

    def __init__(self, params: CompletionParams | None = None) -> None:
        self.params = params or DEFAULT_COMPLETION
        self._start: tuple[int, float] | None = None
        self._tried: Counter[str] = Counter()
        self._path_probes = 0
        self._corner_probes = 0
        self._spot_probes = 0
        self.probes = 0
        self._last: tuple[str, ObjectModel] | None = None
        self._asked: dict[str, list[Probe]] = {}
        self._touched: set[str] = set()  # open directions a probe touched the object in

    def _budget(self, record: ExplorationRecord, model: ObjectModel) -> tuple[int, float]:
        """The completion's touch and path budgets for ``record``."""
        max_touches, max_path, _ = self.params.budget()
        # many-faced objects get two touches a face (an icosahedron: 40)
        faces = sum(1 for f in model.faces if f.source == "contacts")
        budget = max(max_touches, 2 * faces) if max_touches else 0
        scale = budget / max_touches if max_touches else 1.0
        # a probe goes round the object: large objects get path in proportion to their size
        centres = np.asarray([c.centre for c in record.contacts], dtype=float).reshape(-1, 3)
        size = float(np.linalg.norm(np.ptp(centres, axis=0))) if len(centres) else 0.0
        sizes = current().explore.completion_path_sizes
        return budget, max(max_path * scale, sizes * size * budget)

    def _spent(self, record: ExplorationRecord, model: ObjectModel) -> bool:
        """True when the completion's budget is spent (checked only with nothing open)."""
        assert self._start is not None
        budget, allowed = self._budget(record, model)
        return (
            record.touches - self._start[0] >= budget
            or record.path_length - self._start[1] >= allowed
        )

    def next_probe(
        self, record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe | Ending:
        """The next probe for ``record``, or how the completion ended."""
        if self._start is None:
            self._start = (record.touches, record.path_length)
        if last is not None and last[1] and last[0].reason.startswith(_OPEN):
            self._touched.add(last[0].reason)
        try:
            model = self._model(record)
        except _BUILD_ERRORS as exc:
            text = f"the model cannot be built after {record.touches} touches: {exc}"
            return Ending("unreachable", text, (str(exc),))
        if model.polyhedron is not None and centres_on_sphere(model):
            return Ending(
                "closed",
                f"the model is closed and every tip centre lies on one sphere: a ball, whose "
                f"facets are no faces to touch at two heights ({record.touches} touches, "
                f"{record.touches - self._start[0]} of them by the completion)",
            )
        wanted, open_items = self._open(model)
        attempts = self.params.budget()[2]
        todo = [p for p in wanted if self._tried[p.reason] < attempts]
        probe: Probe | None = None
        while todo:
            probe = self._choose(todo, record, last)
            if record.noise > 0 or not self._asked_before(probe, record.tip_radius):
                break
            # with exact contacts the same approach again would touch what it touched
            # before: it counts as tried, and the next attempt (another end, another item)
            # goes instead (under noise it is another sample of the same spot)
            self._tried[probe.reason] += 1
            probe = None
            todo = [p for p in wanted if self._tried[p.reason] < attempts]
        touches = record.touches - self._start[0]
        path = record.path_length - self._start[1]
        if not open_items and (not wanted or self._spent(record, model)):
            return Ending(
                "closed",
                f"the model is closed and every side face has tip centres at two heights "
                f"({record.touches} touches, {touches} of them by the completion)",
            )
        if probe is None:
            what = (
                "the model stayed open"
                if model.polyhedron is None
                else "the model is closed but not every face was touched at two heights"
            )
            items = [f"{i}{TOUCHED_OPEN}" if i in self._touched else i for i in open_items]
            return Ending(
                "unreachable",
                f"{what} after {record.touches} touches; unreachable: " + "; ".join(items),
                tuple(items),
            )
        budget, allowed = self._budget(record, model)
        if touches >= budget or path >= allowed:
            return Ending(
                "budget",
                f"the completion budget ran out ({touches} of {budget} touches, "
                f"{path:.2f} of {allowed:.3g} m of path; {record.touches} touches in "
                "all): still open: " + "; ".join(open_items),
                tuple(open_items),
                f"the completion's budget of {budget} touches"
                if touches >= budget
                else f"the completion's budget of {allowed:.3g} m of path",
            )
        self.probes += 1
        self._tried[probe.reason] += 1
        self._asked.setdefault(probe.reason, []).append(probe)
        if probe.reason.startswith(_CORNER):
            self._corner_probes += 1
        elif probe.reason.startswith(_SPOT):
            self._spot_probes += 1
        elif probe.reason.startswith(_TESTS):
            self._path_probes += 1
        return probe

    def _open(self, model: ObjectModel) -> tuple[list[Probe], list[str]]:
        """The probes ``model`` asks for (those :meth:`_allowed`), and the items that hold the
        completion open, each once (probes at two heights or ends share their item)."""
        wanted = [
            p
            for p in completion_probes(model, height_gap=self.params.height_gap)
            if self._allowed(p)
        ]
        open_items = list(
            dict.fromkeys(p.reason for p in wanted if not p.reason.startswith(_TESTS))
        )
        if model.polyhedron is None and not wanted:
            open_items = [model.open_reason or "the model is open"]
        return wanted, open_items

    def still_open(self, record: ExplorationRecord) -> tuple[str, ...]:
        """What holds the completion open after ``record``, each item once, as an ending's
        ``unreachable`` names it; () when nothing does or the model cannot be built. The
        controller asks when its motion budget ends the exploration before the completion
        does (:meth:`tactile_kb.touch.servo.Controller._complete`)."""
        try:
            model = self._model(record)
        except _BUILD_ERRORS:
            return ()
        if model.polyhedron is not None and centres_on_sphere(model):
            return ()
        return tuple(self._open(model)[1])

    def _choose(
        self, todo: list[Probe], record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe:
        """The first of ``todo``, moved for its second attempt by what the first met."""
        probe = todo[0]
        tried = self._tried[probe.reason]
        ends = [p for p in todo if p.reason == probe.reason]
        if len(ends) > 1 and last is not None and last[0].reason == probe.reason and last[1]:
            # a face's other height, again: the last attempt touched, but not this face there
            # (the model's outline reached into another face); the end of the face farthest
            # from where the attempts so far went
            before = self._asked.get(probe.reason, [])
            return max(
                ends,
                key=lambda p: min((math.dist(p.target, q.target) for q in before), default=0.0),
            )
        if probe.reason == f"{_OPEN} +z" and tried:
            return _over_the_rim(record, probe)
        if probe.reason.startswith(_OPEN) and tried:
            return _at_the_far_touches(record, probe)
        if tried and last is not None and not last[1] and abs(probe.normal[2]) < 0.9:
            return _nearer_the_touches(record, probe)
        return probe

    def _asked_before(self, probe: Probe, rho: float) -> bool:
        """Whether an earlier attempt for the same item approached the same point the same
        way (within a tenth of the tip radius and a degree)."""
        for p in self._asked.get(probe.reason, []):
            near = math.dist(p.target, probe.target) < 0.1 * rho
            same = float(np.dot(p.normal, probe.normal)) > math.cos(math.radians(1.0))
            if near and same and p.facing == probe.facing:
                return True
        return False

    def _model(self, record: ExplorationRecord) -> ObjectModel:
        """``build_model(record)``; the last model again (with ``record``) when a probe
        added nothing the model is built from (it touched nothing)."""
        key = record.model_dump_json(include=_MODEL_INPUTS)
        if self._last is not None and self._last[0] == key:
            return dataclasses.replace(self._last[1], record=record)
        model = build_model(record, rounded=False)
        self._last = (key, model)
        return model

    def _allowed(self, p: Probe) -> bool:
        """Whether ``p`` may be asked for: what holds the completion open always; a test of
        the model once, while its kind's allowance (:data:`PATH_PROBES`,
        :data:`CORNER_PROBES`) lasts."""
        if not p.reason.startswith(_TESTS):
            return True
        if self._tried[p.reason]:
            return False
        if p.reason.startswith(_CORNER):
            return self._corner_probes < CORNER_PROBES
        if p.reason.startswith(_SPOT):
            return self._spot_probes < current().explore.spot_probes
        return self._path_probes < PATH_PROBES


def model_completer(params: CompletionParams | None = None) -> Callable[[], ModelCompleter]:
    """A factory of :class:`ModelCompleter` (one per exploration), for ``WorldExplorer(completer=…)``."""

    def make() -> ModelCompleter:
        return ModelCompleter(params)

    return make


def completing(explorer: Explorer, params: CompletionParams | None = None) -> Explorer:
    """``explorer`` with the model-driven completion: a copy of a
    :class:`~tactile_kb.touch.explorers.WorldExplorer` that has no completer of its own gets
    :func:`model_completer`; any other explorer is returned as it is.

    The touch stage knows nothing of models, so the completion is attached here, above both
    stages; :func:`tactile_kb.classify` and the command line explore through this.
    """
    if isinstance(explorer, WorldExplorer) and explorer.completer is None:
        explorer = copy.copy(explorer)
        explorer.completer = model_completer(params)
    return explorer
