"""The built-in analytic explorer: a spherical tip moving straight among the triangles of a mesh.

:class:`StepperWorld` implements :class:`tactile_kb.touch.world.World` exactly, without time steps.
The set of tip-centre positions at which the tip of radius ρ touches (or penetrates) a
triangle mesh is the union of simple convex primitives: for each triangle the slab
``|(p − v0)·n| ≤ ρ`` over the triangle, for each edge a cylinder of radius ρ between its ends,
for each vertex a ball of radius ρ. A straight motion ``p(t) = a + t·u`` meets each primitive
in one interval of ``t``, found in closed form (a linear condition per triangle side, a
quadratic for a cylinder or a ball). Where those intervals start and end are the only places
where the fired set can change, so the world evaluates the sensors between consecutive ends
and reports the first change:

* contact intervals use the radius ρ + :data:`~tactile_kb.touch.world.CONTACT_TOL` (a sensor fires
  at a contact within that tolerance);
* blocking intervals use ρ − 1e-9 m: the tip stops where it would penetrate.

A slide follows the horizontal tangent of the surface under the followed sensor; for a plane
surface the tip stays at constant distance from it, so the same interval algebra gives where
the face ends (a ``"release"`` at a convex edge) or where another face closes a sensor (a
``"touch"`` at a concave corner). With ``world.comply_deg`` > 0 (0 by default) the slide is
compliant (:meth:`StepperWorld._comply`): small irregularities of a scanned surface (a bump,
a dip, a crease between its triangles, turning the surface at most ``world.comply_deg`` from
where the slide began) are ridden over; a real edge ends it where the straight slide ends.

The world is ideal: it reports true positions and the sensors that really close. Encoder
noise, drop-outs and false fires are added by :class:`tactile_kb.touch.sensors.FaultySensors`,
the same for every world (:class:`StepperExplorer` wraps its world in it).

Examples
--------
>>> import trimesh
>>> from tactile_kb.touch.finger import builtin_finger
>>> cube = trimesh.creation.box((0.1, 0.1, 0.1))
>>> _ = cube.apply_translation((0.0, 0.0, 0.05))
>>> world = StepperWorld(cube, builtin_finger("4"))
>>> m = world.move((-0.2, 0.0, 0.03), (1.0, 0.0, 0.0), 0.3)
>>> m.event, m.closed, round(m.end[0], 6)
('touch', (0,), -0.055)
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
import trimesh
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from tactile_kb.errors import ExplorationError, UsageError
from tactile_kb.settings import DEFAULTS, current
from tactile_kb.touch.explorers import WorldExplorer
from tactile_kb.touch.finger import VERTICAL, Finger, Orientation
from tactile_kb.touch.world import (
    Box,
    Event,
    Motion,
    MotionKind,
    Vec3,
    Workspace,
    default_workspace,
)
from tactile_kb.types import FloatArray

__all__ = [
    "SAME_CONTACT_DEG",
    "StepperExplorer",
    "StepperWorld",
]

_NUDGE = 1e-8  # how far past a change the motion stops, so the new state holds at the end
_EPS_T = 1e-12
_BATCH = 48  # sensor states evaluated together along a motion
_DENSE_STRIDE = 8  # on a dense mesh, sensor states are first sampled every 8th gap
_CONTACT_CACHE = 64  # single-point contact sets kept (see StepperWorld._contacts)
_MAX_PIECES = 200  # straight pieces of one compliant slide (see StepperWorld._comply)
_SIDE = 0.5  # a surface whose normal's horizontal part is below this (more than 60° from
# vertical) is a top: a compliant slide on it lifts and presses along its normal, not across

DENSE_FACES = 4000
"""Meshes with more triangles than this are searched through k-d trees: a motion meets only the
triangles, edges and vertices near its segment (a 200k-triangle scan costs about what a
few-thousand-triangle one does, instead of 50 times more)."""

SAME_CONTACT_DEG = DEFAULTS.world.same_contact_deg
"""Degrees: a contact on a triangle's side this close in direction to a contact inside a face
is the same contact (see :meth:`StepperWorld._touching`)."""


def _pack(tri: FloatArray, normals: FloatArray, sides: FloatArray | None = None) -> FloatArray:
    """(K, 33) rows of what :func:`_closest_packed` reads about the triangles ``tri`` (K, 3, 3)
    with unit ``normals`` (K, 3): the corners v0, v1, v2, the normal, the inward side normals
    ``n × (v[k+1] − v[k])`` (``sides`` (K, 3, 3) when given), the sides ``v[k+1] − v[k]``
    and their squared lengths."""
    pk = np.empty((len(tri), 33))
    pk[:, 0:9] = tri.reshape(-1, 9)
    pk[:, 9:12] = normals
    for k in range(3):
        j = (k + 1) % 3
        side = np.subtract(pk[:, 3 * j : 3 * j + 3], pk[:, 3 * k : 3 * k + 3])
        pk[:, 21 + 3 * k : 24 + 3 * k] = side
        pk[:, 12 + 3 * k : 15 + 3 * k] = np.cross(normals, side) if sides is None else sides[:, k]
        pk[:, 30 + k] = np.einsum("ij,ij->i", side, side)
    return pk


def _closest(
    tri: FloatArray, normals: FloatArray, sides: FloatArray, points: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The closest point of each triangle (K, 3, 3) to the matching point (K, 3), and whether
    it lies inside the triangle (not on a side).

    ``normals`` (K, 3) are the triangles' unit normals and ``sides`` (K, 3, 3) their inward side
    normals ``n × (v[k+1] − v[k])``. The closest point is the projection onto the triangle's
    plane when it falls inside the triangle, else the nearest point of its three sides (the
    same points as ``trimesh.triangles.closest_point``, which does not say which case it was).
    """
    return _closest_packed(_pack(tri, normals, sides), points)


def _closest_packed(pk: FloatArray, points: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """:func:`_closest` of the triangles packed by :func:`_pack` (one gather per query)."""
    normals = pk[:, 9:12]
    proj = points - np.einsum("ij,ij->i", points - pk[:, 0:3], normals)[:, None] * normals
    corners = pk[:, 0:9].reshape(-1, 3, 3)
    sides = pk[:, 21:30].reshape(-1, 3)
    # each (triangle, side) pair as a row (3K, 3)
    g = np.einsum(
        "ij,ij->i", pk[:, 12:21].reshape(-1, 3), (proj[:, None, :] - corners).reshape(-1, 3)
    )
    g3 = (g >= 0.0).reshape(-1, 3)
    inside = g3[:, 0] & g3[:, 1] & g3[:, 2]
    pa = (points[:, None, :] - corners).reshape(-1, 3)
    t = np.clip(np.einsum("ij,ij->i", pa, sides) / pk[:, 30:33].reshape(-1), 0, 1)
    q = (corners.reshape(-1, 3) + t[:, None] * sides).reshape(-1, 3, 3)
    dq = (points[:, None, :] - q).reshape(-1, 3)
    d = np.einsum("ij,ij->i", dq, dq).reshape(-1, 3)
    # the nearest side, the first of equals
    c1 = d[:, 1] < d[:, 0]
    edge_q = np.where(c1[:, None], q[:, 1], q[:, 0])
    c2 = d[:, 2] < np.where(c1, d[:, 1], d[:, 0])
    edge_q = np.where(c2[:, None], q[:, 2], edge_q)
    out: FloatArray = np.where(inside[:, None], proj, edge_q)
    return out, inside


def _sq(x: FloatArray) -> FloatArray:
    """Squared lengths of the rows of ``x`` (K, 3), summed in the order ``np.linalg.norm`` sums."""
    out: FloatArray = x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1] + x[:, 2] * x[:, 2]
    return out


def _norms(x: FloatArray) -> FloatArray:
    """Lengths of the rows of ``x`` (K, 3), as ``np.linalg.norm(x, axis=1)``."""
    out: FloatArray = np.sqrt(_sq(x))
    return out


def _unique_edges(faces: NDArray[np.int64], nv: int) -> NDArray[np.int64]:
    """The undirected edges of ``faces`` (F, 3), once each, as (E, 2) sorted vertex pairs."""
    ends = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    keys = np.minimum(ends[:, 0], ends[:, 1]) * nv + np.maximum(ends[:, 0], ends[:, 1])
    keys.sort()
    keys = keys[np.concatenate(([True], keys[1:] != keys[:-1]))]
    out: NDArray[np.int64] = np.column_stack([keys // nv, keys % nv])
    return out


@dataclass(frozen=True)
class _Prims:
    """The radius-independent terms of :meth:`StepperWorld._intervals` for one line: vertices
    (``vb`` = w·u, ``vww`` = |w|²), edges (the cylinder's quadratic without its radius, the
    slab of the edge's length) and triangles (the plane's offset and rate, and the interval
    inside the three sides)."""

    vb: FloatArray
    vww: FloatArray
    aa: FloatArray
    bb: FloatArray
    wpwp: FloatArray
    par: NDArray[np.bool_]
    safe_a: FloatArray
    slo: FloatArray
    shi: FloatArray
    s0: FloatArray
    movn: NDArray[np.bool_]
    safe_sd: FloatArray
    side_lo: FloatArray
    side_hi: FloatArray


def _v3(a: Sequence[float] | FloatArray) -> Vec3:
    return (float(a[0]), float(a[1]), float(a[2]))


class StepperWorld:
    """A :class:`~tactile_kb.touch.world.World` in which the object is a triangle mesh and the tip a sphere.

    Parameters
    ----------
    mesh
        The object, metres, resting on z = 0 (not modified; the world keeps its own arrays).
    finger
        The finger layout; its ``radius`` is ρ.
    workspace
        Where the tip centre may go; default :func:`default_workspace` of the mesh bounds.
    hint_margin
        How much the :attr:`hint` box exceeds the object's bounds (metres).
    orientation
        The head's pose (:class:`~tactile_kb.touch.finger.Orientation`); :meth:`oriented` gives
        the same world with the head indexed to another pose. The sensors turn with the head;
        the finger's shaft (when it has a ``shaft_radius``) is a cylinder of that radius along
        the head's axis from the tip, modelled as a chain of balls ``0.75 × radius`` apart,
        and blocks a motion where it would enter the object or the table.
    """

    def __init__(
        self,
        mesh: trimesh.Trimesh,
        finger: Finger,
        *,
        workspace: Workspace | None = None,
        hint_margin: float = 0.005,
        orientation: Orientation = VERTICAL,
    ) -> None:
        self._finger = finger
        self._rho = float(finger.radius)
        self._orientation = orientation
        self._dirs = finger.directions_at(orientation)
        self._axis = np.asarray(orientation.axis, dtype=float)
        self._cos = finger.cos_cone
        v = np.array(mesh.vertices, dtype=float)
        f = np.array(mesh.faces, dtype=np.int64)
        tri = v[f]  # (F, 3, 3)
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        lengths = _norms(normals)
        keep = lengths > 1e-18
        tri, normals, lengths = tri[keep], normals[keep], lengths[keep]
        self._n = normals / lengths[:, None]
        # bounding spheres of the triangles: a conservative pre-filter for closest points
        self._tc = (tri[:, 0] + tri[:, 1] + tri[:, 2]) / 3.0
        rel = tri - self._tc[:, None, :]
        self._tr = np.sqrt(
            np.maximum(np.maximum(_sq(rel[:, 0]), _sq(rel[:, 1])), _sq(rel[:, 2]))
        )  # the furthest corner
        self._tr_max = float(self._tr.max()) if len(self._tr) else 0.0
        self._tree = cKDTree(self._tc)
        # rows read in one gather, filled when a triangle is first met (a dense mesh's
        # exploration meets a fraction of them): (F, 8) for _may_touch, (F, 33) for the rest
        self._tri = tri
        self._pre = np.empty((len(tri), 8))
        self._pk = np.empty((len(tri), 33))
        self._filled = np.zeros(len(tri), dtype=bool)
        edges = _unique_edges(f, len(v))
        self._e0 = v[edges[:, 0]]
        evec = v[edges[:, 1]] - self._e0
        self._elen = _norms(evec)
        ok = self._elen > 1e-15
        self._e0, evec, self._elen = self._e0[ok], evec[ok], self._elen[ok]
        self._edir = evec / self._elen[:, None]
        self._verts = v[np.flatnonzero(np.bincount(f.ravel(), minlength=len(v)))]
        self._dense = len(self._n) > DENSE_FACES
        if self._dense:  # primitives near a segment, found through their centres (the union
            # of balls does not depend on how a tree is built, so these are built fast)
            self._etree = cKDTree(
                self._e0 + 0.5 * self._elen[:, None] * self._edir,
                balanced_tree=False,
                compact_nodes=False,
            )
            self._er_max = float(0.5 * self._elen.max()) if len(self._elen) else 0.0
            self._vtree = cKDTree(self._verts, balanced_tree=False, compact_nodes=False)
        else:
            self._fill(np.arange(len(tri)))
        self._near: tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]] | None = None
        self._ccache: dict[tuple[bytes, float, float], FloatArray] = {}
        self._pcache: list[
            tuple[
                tuple[bytes, bytes],
                tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]] | None,
                _Prims,
            ]
        ] = []
        bounds = np.array(mesh.bounds, dtype=float)
        self._bounds = bounds
        self._workspace = workspace or default_workspace(bounds, self._rho)
        self._hint = Box(lo=_v3(bounds[0] - hint_margin), hi=_v3(bounds[1] + hint_margin))

    def _fill(self, ti: NDArray[np.intp]) -> None:
        """Fill the packed rows of the triangles ``ti`` that are not filled yet."""
        todo = ti[~self._filled[ti]]
        if len(todo) == 0:
            return
        todo = np.unique(todo)
        tri, n, tc = self._tri[todo], self._n[todo], self._tc[todo]
        flat = np.abs(np.einsum("ijk,ik->ij", tri - tc[:, None, :], n)).max(axis=1) + 1e-12
        self._pre[todo] = np.column_stack([tc, n, self._tr[todo], flat])
        self._pk[todo] = _pack(tri, n)
        self._filled[todo] = True

    # protocol attributes ------------------------------------------------------------------------
    @property
    def finger(self) -> Finger:
        """The finger layout."""
        return self._finger

    @property
    def workspace(self) -> Workspace:
        """Where the tip centre may go."""
        return self._workspace

    @property
    def hint(self) -> Box:
        """The object's bounds plus ``hint_margin``: the visual estimate."""
        return self._hint

    @property
    def orientation(self) -> Orientation:
        """The head's pose."""
        return self._orientation

    def oriented(self, orientation: Orientation, at: Vec3 | None = None) -> StepperWorld:
        """The same world with the head indexed to ``orientation``.

        With ``at`` (the tip centre where the head turns), a pose whose shaft would be inside
        the object or the table there raises :class:`~tactile_kb.errors.ExplorationError`.
        """
        out = copy.copy(self)
        out._pcache = []
        out._orientation = orientation
        out._dirs = self._finger.directions_at(orientation)
        out._axis = np.asarray(orientation.axis, dtype=float)
        if at is not None and out.shaft_collides(at):
            raise ExplorationError(
                f"the head at tilt {orientation.tilt_deg:g}°, turn {orientation.turn_deg:g}° "
                f"collides with the object or the table at {tuple(round(c, 4) for c in at)}: "
                "index the head elsewhere"
            )
        return out

    def shaft_collides(self, centre: Vec3) -> bool:
        """Whether the shaft enters the object or the table with the tip centre at ``centre``."""
        a = np.asarray(centre, dtype=float)
        return self._shaft_block(a, np.array([1.0, 0.0, 0.0]), 0.0, inside=True) <= 0.0

    def _shaft_balls(self, a: FloatArray, u: FloatArray, reach: float) -> FloatArray:
        """Offsets along the axis of the shaft's balls that can meet the object during the
        motion a + t·u, 0 ≤ t ≤ reach (the others stay clear of the mesh's bounding box)."""
        rs = float(self._finger.shaft_radius or 0.0)
        rho = self._rho
        s = np.arange(max(rho - rs, 0.0), self._finger.shaft_length + 1e-12, 0.75 * rs)
        lo = self._bounds[0] - rs - 1e-9
        hi = self._bounds[1] + rs + 1e-9
        starts = a[None, :] + s[:, None] * self._axis[None, :]
        t0 = np.zeros(len(s))
        t1 = np.full(len(s), float(reach))
        for k in range(3):  # slab test of each ball's swept segment against the box
            if abs(u[k]) < 1e-15:
                out = (starts[:, k] < lo[k]) | (starts[:, k] > hi[k])
                t1 = np.where(out, -1.0, t1)
                continue
            ta = (lo[k] - starts[:, k]) / u[k]
            tb = (hi[k] - starts[:, k]) / u[k]
            t0 = np.maximum(t0, np.minimum(ta, tb))
            t1 = np.minimum(t1, np.maximum(ta, tb))
        out_s: FloatArray = s[t0 <= t1]
        return out_s

    def _shaft_block(
        self, a: FloatArray, u: FloatArray, limit: float, *, inside: bool = False
    ) -> float:
        """Where along the motion the shaft would enter the object or the table (``inf``:
        nowhere); with ``inside``, 0 when it is in them at the start."""
        rs = self._finger.shaft_radius
        if rs is None:
            return math.inf
        best = math.inf
        w = self._axis
        tol = current().world.block_tol
        # the table: the lowest ball's bottom stays above z = 0
        low = float(a[2]) + min(0.0, float(w[2]) * self._finger.shaft_length) - rs
        if float(w[2]) < -1e-12:
            if low < -tol:
                return 0.0
            if u[2] < -1e-15:
                best = min(best, low / -float(u[2]))
        saved = self._near
        try:
            for s in self._shaft_balls(a, u, limit):
                c = a + s * w
                if self._dense:
                    self._near = self._near_segment(c, u, limit, rs)
                lo, hi = self._intervals(c, u, rs - tol)
                if inside:
                    if ((lo < 0.0) & (hi > 0.0)).any():
                        return 0.0
                    continue
                real = (hi - lo > _EPS_T) & (hi > _EPS_T) & (lo > -1e-10) & (lo <= limit)
                if real.any():
                    best = min(best, float(max(0.0, lo[real].min())))
        finally:
            self._near = saved
        return best

    # sensing ------------------------------------------------------------------------------------
    def _touching(self, pts: FloatArray) -> tuple[NDArray[np.intp], FloatArray]:
        """The contacts of the tip centres ``pts`` (P, 3): point indices and unit directions.

        One direction per triangle within ρ + CONTACT_TOL, towards its closest point, except
        a closest point on a triangle's side whose direction repeats (within
        :data:`SAME_CONTACT_DEG`) that of a contact inside a face: the contact shell's
        tolerance would otherwise let the neighbouring triangle of the same plane turn the
        direction by up to 0.25° and make a sensor at the edge of its cone flicker.
        """
        r = self._rho + current().world.contact_tol
        found = self._tree.query_ball_point(pts, r + self._tr_max + 1e-9, return_sorted=False)
        pi = np.repeat(np.arange(len(pts)), [len(f) for f in found])
        ti = np.fromiter(itertools.chain.from_iterable(found), dtype=np.intp, count=len(pi))
        if len(pi):  # a lower bound of the distance: only triangles that can touch go on
            pi, ti = self._may_touch(pts, pi, ti, r + 1e-9)
        if len(pi) == 0:
            return pi, np.zeros((0, 3))
        q, inside = _closest_packed(self._pk[ti], pts[pi])
        d = q - pts[pi]
        dist = np.linalg.norm(d, axis=1)
        ok = (dist <= r) & (dist > 1e-12)
        pi, inside = pi[ok], inside[ok]
        u = d[ok] / dist[ok, None]
        side = np.flatnonzero(~inside)
        face = np.flatnonzero(inside)
        if len(side) and len(face):
            same = pi[side][:, None] == pi[face][None, :]
            close = u[side] @ u[face].T >= math.cos(math.radians(current().world.same_contact_deg))
            keep = np.ones(len(pi), dtype=bool)
            keep[side[(same & close).any(axis=1)]] = False
            pi, u = pi[keep], u[keep]
        return pi, u

    def _may_touch(
        self, pts: FloatArray, pi: NDArray[np.intp], ti: NDArray[np.intp], r: float
    ) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """The pairs (point ``pi``, triangle ``ti``) whose distance can be ≤ ``r``, in order.

        Triangle ``t`` lies in the disc of radius ``tr`` about its centroid ``tc`` in the
        plane of normal ``n``, thickened by ``flat`` (how far its corners are from that plane
        in floating point). With ``s`` the point's height over that plane and ``l`` its
        distance from ``tc`` along it, the distance is at least
        ``hypot(max(|s| − flat, 0), max(l − tr, 0))``: a pair further than ``r`` by that
        bound cannot touch, whatever the exact closest point (a conservative test that keeps
        the order of the pairs).
        """
        self._fill(ti)
        pre = self._pre[ti]  # (k, 8): tc, n, tr, flat
        dv = pts[pi] - pre[:, 0:3]
        s = np.abs(np.einsum("ij,ij->i", dv, pre[:, 3:6]))
        d2 = np.einsum("ij,ij->i", dv, dv)
        h = np.maximum(s - pre[:, 7], 0.0)
        lat = np.maximum(np.sqrt(np.maximum(d2 - s * s, 0.0)) - pre[:, 6], 0.0)
        near = h * h + lat * lat <= r * r
        return pi[near], ti[near]

    def _contacts(self, p: FloatArray) -> FloatArray:
        """Unit directions from ``p`` to the surface within ρ + CONTACT_TOL, (k, 3).

        A motion starts where the last one ended and asks there again: the last few answers
        are kept (read-only), by the exact coordinates and the tolerances that decide them.
        """
        pt = np.asarray(p, dtype=float).reshape(1, 3)
        world = current().world
        key = (pt.tobytes(), world.contact_tol, world.same_contact_deg)
        hit = self._ccache.get(key)
        if hit is not None:
            return hit
        out = self._touching(pt)[1]
        out.flags.writeable = False
        if len(self._ccache) >= _CONTACT_CACHE:
            del self._ccache[next(iter(self._ccache))]
        self._ccache[key] = out
        return out

    def _fired(self, p: FloatArray) -> tuple[int, ...]:
        d = self._contacts(p)
        if len(d) == 0:
            return ()
        cos = d @ self._dirs.T
        return tuple(int(i) for i in np.flatnonzero((cos >= self._cos - 1e-12).any(axis=0)))

    def _fired_many(self, pts: FloatArray) -> NDArray[np.bool_]:
        """(P, S) bool: sensor ``s`` is ON with the tip centre at ``pts[p]`` (as :meth:`_fired`)."""
        out = np.zeros((len(pts), len(self._dirs)), dtype=bool)
        pi, u = self._touching(pts)
        if len(pi):
            np.logical_or.at(out, pi, u @ self._dirs.T >= self._cos - 1e-12)
        return out

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        """Sensors ON with the tip centre at ``centre``."""
        return self._fired(np.asarray(centre, dtype=float))

    def distance(self, centre: Vec3) -> float:
        """Distance from ``centre`` to the mesh surface (for tests and diagnostics)."""
        p = np.asarray(centre, dtype=float)
        self._fill(np.arange(len(self._pk)))
        q, _ = _closest_packed(self._pk, np.tile(p, (len(self._pk), 1)))
        return float(np.linalg.norm(q - p, axis=1).min())

    # interval algebra ---------------------------------------------------------------------------
    def _near_segment(
        self, a: FloatArray, u: FloatArray, length: float, r: float
    ) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """Indices of the triangles, edges and vertices that can come within ``r`` of the
        segment a + t·u, 0 ≤ t ≤ ``length`` (a superset: k-d tree balls along the segment)."""
        n = max(1, min(256, math.ceil(length / max(r, 1e-6))))
        step = length / n
        pts = a[None, :] + np.linspace(0.0, length, n + 1)[:, None] * u[None, :]
        pad = r + 0.5 * step + 1e-9

        def near(tree: cKDTree, radius: float) -> NDArray[np.intp]:
            # the union of the balls' indices, in increasing order (a mask, not a sort)
            found = tree.query_ball_point(pts, radius, return_sorted=False)
            mask = np.zeros(tree.n, dtype=bool)
            mask[np.fromiter(itertools.chain.from_iterable(found), dtype=np.intp)] = True
            out: NDArray[np.intp] = np.flatnonzero(mask)
            return out

        return (
            near(self._tree, pad + self._tr_max),
            near(self._etree, pad + self._er_max),
            near(self._vtree, pad),
        )

    def _primitives(self, a: FloatArray, u: FloatArray) -> _Prims:
        """The parts of :meth:`_intervals` that do not depend on the radius, for the line
        a + t·u and the current candidates (kept for the few radii one motion asks about)."""
        key = (a.tobytes(), u.tobytes())
        for k, near, prims in self._pcache:
            if k == key and near is self._near:
                return prims
        pk, e0, edir, elen, verts = self._pk, self._e0, self._edir, self._elen, self._verts
        if self._near is not None:
            ti, ei, vi = self._near
            self._fill(ti)
            pk, e0, edir, elen, verts = pk[ti], e0[ei], edir[ei], elen[ei], verts[vi]
        # vertices: |a - v + t u|^2 = r^2
        w = a - verts
        vb = w @ u
        vww = np.einsum("ij,ij->i", w, w)
        # edges: infinite cylinder clipped by the slab 0 <= s <= len
        w = a - e0
        we = np.einsum("ij,ij->i", w, edir)
        ue = edir @ u
        wp = w - we[:, None] * edir
        up = u - ue[:, None] * edir
        aa = np.einsum("ij,ij->i", up, up)
        bb = np.einsum("ij,ij->i", wp, up)
        wpwp = np.einsum("ij,ij->i", wp, wp)
        par = aa < 1e-14
        safe_a = np.where(par, 1.0, aa)
        moving = np.abs(ue) > 1e-14
        safe_ue = np.where(moving, ue, 1.0)
        s1 = -we / safe_ue
        s2 = (elen - we) / safe_ue
        within = (we >= 0) & (we <= elen)
        slo = np.where(moving, np.minimum(s1, s2), np.where(within, -np.inf, np.inf))
        shi = np.where(moving, np.maximum(s1, s2), np.where(within, np.inf, -np.inf))
        # triangles: the plane's slab, and the projection inside the three sides
        n = pk[:, 9:12]
        s0 = np.einsum("ij,ij->i", a - pk[:, 0:3], n)
        sd = n @ u
        movn = np.abs(sd) > 1e-14
        safe_sd = np.where(movn, sd, 1.0)
        # the three sides of every triangle as rows (3K, 3): g0 + t gd >= 0 inside
        side_n = pk[:, 12:21].reshape(-1, 3)
        g0 = np.einsum("ij,ij->i", (a - pk[:, 0:9].reshape(-1, 3, 3)).reshape(-1, 3), side_n)
        gd = side_n @ u
        mv = np.abs(gd) > 1e-14
        root = -g0 / np.where(mv, gd, 1.0)
        lo3 = np.where(mv & (gd > 0), root, -np.inf).reshape(-1, 3)
        hi3 = np.where(mv & (gd < 0), root, np.inf).reshape(-1, 3)
        bad3 = (~mv & (g0 < 0)).reshape(-1, 3)
        side_lo = np.maximum(np.maximum(lo3[:, 0], lo3[:, 1]), lo3[:, 2])
        side_hi = np.minimum(np.minimum(hi3[:, 0], hi3[:, 1]), hi3[:, 2])
        bad = bad3[:, 0] | bad3[:, 1] | bad3[:, 2]
        keep = ~bad  # a line outside a side, parallel to it, never meets the triangle
        prims = _Prims(
            vb=vb,
            vww=vww,
            aa=aa,
            bb=bb,
            wpwp=wpwp,
            par=par,
            safe_a=safe_a,
            slo=slo,
            shi=shi,
            s0=s0[keep],
            movn=movn[keep],
            safe_sd=safe_sd[keep],
            side_lo=side_lo[keep],
            side_hi=side_hi[keep],
        )
        if len(self._pcache) >= 4:
            del self._pcache[0]
        self._pcache.append((key, self._near, prims))
        return prims

    def _intervals(self, a: FloatArray, u: FloatArray, r: float) -> tuple[FloatArray, FloatArray]:
        """Entry and exit parameters of the line a + t·u in the primitives of radius r (only
        the primitives near the current motion's segment on a dense mesh; triangles the line
        cannot meet at any radius are left out)."""
        p = self._primitives(a, u)
        rr = r * r
        # vertices
        disc = p.vb * p.vb - (p.vww - rr)
        ok = disc > 0
        sq = np.sqrt(np.where(ok, disc, 0.0))
        vlo = np.where(ok, -p.vb - sq, np.inf)
        vhi = np.where(ok, -p.vb + sq, -np.inf)
        # edges
        cc = p.wpwp - rr
        disc = p.bb * p.bb - p.aa * cc
        okc = (disc > 0) & ~p.par
        sq = np.sqrt(np.where(okc, disc, 0.0))
        lo = np.where(okc, (-p.bb - sq) / p.safe_a, np.inf)
        hi = np.where(okc, (-p.bb + sq) / p.safe_a, -np.inf)
        inside_par = p.par & (cc < 0)
        elo = np.maximum(np.where(inside_par, -np.inf, lo), p.slo)
        ehi = np.minimum(np.where(inside_par, np.inf, hi), p.shi)
        # triangles: |s(t)| <= r and the projection inside the triangle
        t1 = (-r - p.s0) / p.safe_sd
        t2 = (r - p.s0) / p.safe_sd
        inside = np.abs(p.s0) < r
        lo = np.where(p.movn, np.minimum(t1, t2), np.where(inside, -np.inf, np.inf))
        hi = np.where(p.movn, np.maximum(t1, t2), np.where(inside, np.inf, -np.inf))
        tlo = np.maximum(lo, p.side_lo)
        thi = np.minimum(hi, p.side_hi)
        return np.concatenate([vlo, elo, tlo]), np.concatenate([vhi, ehi, thi])

    def _block_at(self, a: FloatArray, u: FloatArray, limit: float) -> float:
        """Where along the segment the tip would start to penetrate (``inf`` if nowhere)."""
        lo, hi = self._intervals(a, u, self._rho - current().world.block_tol)
        real = (hi - lo > _EPS_T) & (hi > _EPS_T) & (lo > -1e-10) & (lo <= limit)
        if not real.any():
            return math.inf
        return float(max(0.0, lo[real].min()))

    # motions ------------------------------------------------------------------------------------
    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        """A rigid straight motion (see :meth:`tactile_kb.touch.world.World.move`)."""
        return self._run("move", start, direction, length)

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        """A compliant motion along the surface under ``sensor`` (see the protocol)."""
        a = np.asarray(start, dtype=float)
        if not 0 <= sensor < len(self._dirs):
            raise UsageError(f"slide: no sensor {sensor} on finger {self._finger.name!r}")
        cmd = np.asarray(direction, dtype=float)
        contacts = self._contacts(a)
        cos = contacts @ self._dirs[sensor] if len(contacts) else np.zeros(0)
        if len(contacts) == 0 or cos.max() < self._cos - 1e-12:
            fired = self._fired(a)
            return Motion(
                kind="slide",
                start=_v3(a),
                end=_v3(a),
                direction=_v3(cmd),
                distance=0.0,
                event="release",
                fired_start=fired,
                fired=fired,
                closed=(),
                opened=(sensor,),
                measured=_v3(a),
            )
        n = -contacts[int(np.argmax(cos))]
        t = np.array([-n[1], n[0], 0.0])
        norm = float(np.linalg.norm(t))
        if norm < 1e-9:  # a horizontal surface: any horizontal direction is tangent
            t = np.array([cmd[0], cmd[1], 0.0])
            norm = float(np.linalg.norm(t))
            if norm < 1e-12:
                raise UsageError("slide: the commanded direction has no horizontal component")
            t /= norm
        else:
            t /= norm
            if float(t @ cmd) < 0:
                t = -t
        m = self._run("slide", _v3(a), _v3(t), length)
        if current().world.comply_deg <= 0.0:
            return m
        return self._comply(m, n, sensor, float(length))

    def _comply(self, first: Motion, n0: FloatArray, sensor: int, length: float) -> Motion:
        """The compliant slide that began with the straight slide ``first`` along the surface of
        outward normal ``n0`` under ``sensor``.

        A finger under force control rides over irregularities smaller than its tip: its centre
        follows the surface offset by ρ while the followed sensor stays pressed. Where a
        straight piece stops without a sensor change (``"blocked"`` by a bump or a crease of
        a scan's triangles) the tip turns to the tangent of the contact that blocks it; where
        it loses the surface (the followed sensor opens: a dip, or a crease turning away) it
        lifts off by ``comply_depth`` ρ, steps on by ``comply_step`` ρ and presses back (a
        ride, :meth:`_ride_on`). Either is taken only when the surface met there turns at most
        :attr:`~tactile_kb.settings.WorldSettings.comply_deg` from ``n0`` and, after a ride,
        the followed sensor fires again. On a side (a normal within 60° of horizontal) the
        tip stays at constant z; on a top it lifts and presses along the normal and a bump
        turns the slide up its slope. Otherwise the slide ends as the straight piece
        ended: at a real edge, a real corner or a wall the surface turns further (past a
        convex edge the surface a ride finds has turned by at least asin(comply_step)), so a
        polyhedron's slides end exactly where straight slides end.

        The motion's ``distance`` is the length of the path, its ``direction`` the last
        piece's; a ride that finds the sensors changed (a neighbouring sensor closed or
        opened while the followed one stays ON) ends the motion there with that event.
        """
        cos_max = math.cos(math.radians(current().world.comply_deg))
        fired0 = first.fired_start
        start = np.asarray(first.start, dtype=float)
        m = first
        travelled = first.distance
        stalls = 0
        for _ in range(_MAX_PIECES):
            if travelled >= length - 1e-12 or m.event not in ("blocked", "release"):
                break
            if m.event == "release" and sensor in m.fired:
                break  # another surface's sensor opened: the servo decides
            here = np.asarray(m.end, dtype=float)
            u = np.asarray(m.direction, dtype=float)
            if m.event == "blocked":
                turned = self._conform(here, u, n0, cos_max)
                if turned is None:
                    break
                # off the surface by a few block_tol (far inside the contact band): the piece
                # starts clear of the triangles it is tangent to, not on their boundary
                t, nb = turned
                pos, hop = here + 4.0 * current().world.block_tol * nb, 0.0
            else:
                ridden = self._ride_on(here, u, n0, sensor, cos_max)
                if ridden is None:
                    break
                pos, t, hop, fired = ridden
                if fired != fired0 or travelled + hop >= length - 1e-12:
                    # the sensors changed where the surface was regained, or the ride went
                    # the whole length
                    return self._joined(start, pos, u, travelled + hop, fired0, fired)
            nxt = self._run("slide", _v3(pos), _v3(t), length - travelled - hop)
            stalls = stalls + 1 if hop + nxt.distance < 1e-9 else 0
            if stalls >= 4:  # turning on the spot: the surface does not let the tip on
                break
            m = nxt
            travelled += hop + nxt.distance
        if m is first:
            return first
        return Motion(
            kind="slide",
            start=first.start,
            end=m.end,
            direction=m.direction,
            distance=float(travelled),
            event=m.event,
            fired_start=fired0,
            fired=m.fired,
            closed=tuple(sorted(set(m.fired) - set(fired0))),
            opened=tuple(sorted(set(fired0) - set(m.fired))),
            measured=m.end,
        )

    def _joined(
        self,
        start: FloatArray,
        end: FloatArray,
        direction: FloatArray,
        distance: float,
        fired0: tuple[int, ...],
        fired: tuple[int, ...],
    ) -> Motion:
        """A compliant slide that ended after a ride, where its sensors changed (``fired0`` →
        ``fired``) or its length was travelled."""
        closed = tuple(sorted(set(fired) - set(fired0)))
        opened = tuple(sorted(set(fired0) - set(fired)))
        return Motion(
            kind="slide",
            start=_v3(start),
            end=_v3(end),
            direction=_v3(direction),
            distance=float(distance),
            event="touch" if closed else "release" if opened else "none",
            fired_start=fired0,
            fired=fired,
            closed=closed,
            opened=opened,
            measured=_v3(end),
        )

    @staticmethod
    def _tangent_of(n: FloatArray, u: FloatArray, side: bool) -> FloatArray | None:
        """The tangent of a surface of outward normal ``n`` a slide along ``u`` turns to: the
        horizontal ẑ × n on a side, in ``u``'s sense; on a top, ``u`` projected on the surface."""
        t = np.array([-n[1], n[0], 0.0]) if side else u - float(u @ n) * n
        norm = float(np.linalg.norm(t))
        if norm < 1e-6:
            return None
        t /= norm
        return t if float(t @ u) >= 0.0 else -t

    def _conform(
        self, here: FloatArray, u: FloatArray, n0: FloatArray, cos_max: float
    ) -> tuple[FloatArray, FloatArray] | None:
        """The direction a slide blocked at ``here`` while moving along ``u`` turns to: of the
        tangents of the contacts there, the one nearest ``u`` that enters none of them (the
        motion re-projected on the surfaces that block it), when the surface it follows turns
        at most ``comply_deg`` from ``n0``; with that surface's normal. Else None."""
        normals = self._normals_at(here)
        if len(normals) == 0 or float((normals @ u).min()) >= 0.0:
            return None  # nothing at the tip blocks it (the shaft does): no turn helps
        side = float(np.hypot(n0[0], n0[1])) >= _SIDE
        best: tuple[FloatArray, FloatArray] | None = None
        best_cos = -math.inf
        for n in normals:
            t = self._tangent_of(n, u, side)
            if t is None or float(n @ n0) < cos_max:
                continue
            if float((normals @ t).min()) < -1e-9:
                continue  # it would enter another of the surfaces at the tip
            c = float(t @ u)
            if c > best_cos:
                best, best_cos = (t, n), c
        return best

    def _normals_at(self, p: FloatArray) -> FloatArray:
        """Unit outward normals (k, 3) of the surface at every triangle within ρ +
        CONTACT_TOL of ``p`` (towards ``p`` from the triangle's closest point; the contacts
        :meth:`_touching` merges are kept apart, since any of them may block a motion)."""
        r = self._rho + current().world.contact_tol
        pt = np.asarray(p, dtype=float).reshape(1, 3)
        ti = np.asarray(self._tree.query_ball_point(pt[0], r + self._tr_max + 1e-9), dtype=np.intp)
        if len(ti) == 0:
            return np.zeros((0, 3))
        self._fill(ti)
        q, _ = _closest_packed(self._pk[ti], np.repeat(pt, len(ti), axis=0))
        d = pt - q
        dist = _norms(d)
        ok = (dist <= r) & (dist > 1e-12)
        out: FloatArray = d[ok] / dist[ok, None]
        return out

    def _ride_on(
        self, here: FloatArray, u: FloatArray, n0: FloatArray, sensor: int, cos_max: float
    ) -> tuple[FloatArray, FloatArray, float, tuple[int, ...]] | None:
        """Ride over a dip where a slide along ``u`` lost the surface at ``here``: lift off
        (horizontally from a side, along ``n0`` from a top) by ``comply_depth`` ρ, step on by ``comply_step`` ρ, press back up to
        twice as far. Returns (where the surface was regained, the tangent there, the step's
        length, the sensors ON there), or None when the followed ``sensor`` does not fire
        there or the surface there turns more than ``comply_deg`` from ``n0``."""
        world = current().world
        side = float(np.hypot(n0[0], n0[1])) >= _SIDE
        out = np.array([n0[0], n0[1], 0.0]) if side else n0.copy()
        out /= float(np.linalg.norm(out))
        depth = world.comply_depth * self._rho
        step = world.comply_step * self._rho
        pos = here
        for direction, reach in ((out, depth), (u, step)):
            done = 0.0
            while done < reach - 1e-12:  # through losses of contact; anything else: no ride
                leg = self._run("move", _v3(pos), _v3(direction), reach - done)
                pos = np.asarray(leg.end, dtype=float)
                done += leg.distance
                if leg.event == "none":
                    break
                if leg.event != "release" or leg.distance <= 0.0:
                    return None
        press = self._run("move", _v3(pos), _v3(-out), 2.0 * depth)
        if press.event != "touch" or sensor not in press.fired:
            return None
        end = np.asarray(press.end, dtype=float)
        contacts = self._contacts(end)
        if len(contacts) == 0:
            return None
        nq = -contacts[int(np.argmax(contacts @ self._dirs[sensor]))]
        if float(nq @ n0) < cos_max:
            return None
        t = self._tangent_of(nq, u, side)
        if t is None:
            return None
        return end, t, float((end - here) @ u), press.fired

    def _changes(
        self, a: FloatArray, u: FloatArray, marks: FloatArray, fired0: tuple[int, ...]
    ) -> Iterator[int]:
        """Indices ``i`` of the gaps ``marks[i]..marks[i+1]`` whose middle state differs from
        ``fired0``, in order (the sensors are evaluated in batches)."""
        ref = np.zeros(len(self._dirs), dtype=bool)
        ref[list(fired0)] = True
        width = np.diff(marks)
        gaps = np.flatnonzero(width > 0)

        def differ(idx: NDArray[np.intp]) -> NDArray[np.intp]:
            mid = 0.5 * (marks[idx] + marks[idx + 1])
            states = self._fired_many(a[None, :] + mid[:, None] * u[None, :])
            hit: NDArray[np.intp] = idx[(states != ref[None, :]).any(axis=1)]
            return hit

        stride = _DENSE_STRIDE if self._dense and len(gaps) > 2 * _DENSE_STRIDE else 1
        if stride == 1:
            for k in range(0, len(gaps), _BATCH):
                yield from (int(i) for i in differ(gaps[k : k + _BATCH]))
            return
        # a dense mesh: every triangle crossed adds gaps where nothing changes (coplanar
        # neighbours); sample every stride-th gap, and look at every gap only before a change
        done = 0  # gaps[:done] are settled
        coarse = np.arange(stride - 1, len(gaps), stride)
        for k in range(0, len(coarse), _BATCH):
            hits = differ(gaps[coarse[k : k + _BATCH]])
            if len(hits) == 0:
                done = int(coarse[min(k + _BATCH, len(coarse)) - 1]) + 1
                continue
            first = int(np.searchsorted(gaps, hits[0]))
            for j in range(done, first + 1, _BATCH):
                yield from (int(i) for i in differ(gaps[j : min(j + _BATCH, first + 1)]))
            done = first + 1
        for j in range(done, len(gaps), _BATCH):
            yield from (int(i) for i in differ(gaps[j : j + _BATCH]))

    def _run(self, kind: MotionKind, start: Vec3, direction: Vec3, length: float) -> Motion:
        a = np.asarray(start, dtype=float)
        u = np.asarray(direction, dtype=float)
        nu = float(np.linalg.norm(u))
        if not math.isfinite(nu) or nu < 1e-12:
            raise UsageError(f"{kind}: direction {direction} is not a direction")
        if not math.isfinite(length) or length < 0:
            raise UsageError(f"{kind}: length {length} must be a finite number ≥ 0")
        u = u / nu
        fired0 = self._fired(a)
        room = self._workspace.room(_v3(a), _v3(u))
        reach = min(float(length), room)
        self._pcache.clear()
        if self._dense:
            self._near = self._near_segment(a, u, reach, self._rho + current().world.contact_tol)
        try:
            return self._run_near(kind, a, u, length, fired0, room, reach)
        finally:
            self._near = None
            self._pcache.clear()

    def _run_near(
        self,
        kind: MotionKind,
        a: FloatArray,
        u: FloatArray,
        length: float,
        fired0: tuple[int, ...],
        room: float,
        reach: float,
    ) -> Motion:
        t_block = min(self._block_at(a, u, reach), self._shaft_block(a, u, reach))
        end_t = min(reach, t_block)
        if t_block <= reach:
            end_t = max(0.0, t_block - 1e-10)
        lo, hi = self._intervals(a, u, self._rho + current().world.contact_tol)
        ends = np.concatenate([lo, hi])
        cand = np.unique(ends[(ends > _EPS_T) & (ends < end_t)])
        marks = np.array([0.0, *cand.tolist(), end_t])
        event: Event = "none"
        stop = end_t
        fired = fired0
        for i in self._changes(a, u, marks, fired0):
            t0, t1 = float(marks[i]), float(marks[i + 1])
            state = self._fired(a + 0.5 * (t0 + t1) * u)
            if state != fired0:
                stop = t0 + min(_NUDGE, 0.5 * (t1 - t0))
                if set(state) - set(fired0):
                    # a touch: stop half-way into the contact shell, so that the contact holds
                    # robustly for the next motion (a grazing approach enters it very slowly)
                    mlo, mhi = self._intervals(a, u, self._rho + 0.5 * current().world.contact_tol)
                    ok = (mhi - mlo > _EPS_T) & (mlo >= t0 - 1e-12) & (mlo <= end_t)
                    if ok.any():
                        deeper = max(stop, float(mlo[ok].min()))
                        if set(self._fired(a + deeper * u)) >= set(state):
                            stop = deeper
                fired = self._fired(a + stop * u)
                if fired == fired0:  # the change is thinner than the nudge: take the middle
                    stop = 0.5 * (t0 + t1)
                    fired = state
                event = "touch" if set(fired) - set(fired0) else "release"
                break
        else:
            fired = self._fired(a + end_t * u)
            if fired != fired0:
                event = "touch" if set(fired) - set(fired0) else "release"
            elif t_block <= reach:
                event = "blocked"
            elif room < length:
                event = "limit"
        closed = tuple(sorted(set(fired) - set(fired0)))
        opened = tuple(sorted(set(fired0) - set(fired)))
        end = a + stop * u
        return Motion(
            kind=kind,
            start=_v3(a),
            end=_v3(end),
            direction=_v3(u),
            distance=float(stop),
            event=event,
            fired_start=fired0,
            fired=fired,
            closed=closed,
            opened=opened,
            measured=_v3(end),
        )


class StepperExplorer(WorldExplorer):
    """The built-in explorer: the shared servo controller driving a :class:`StepperWorld`.

    Parameters
    ----------
    params
        Servo parameters (:class:`tactile_kb.touch.servo.ServoParams`); defaults suit 2–30 cm objects.
    dropout, false_fire
        Sensor fault probabilities (see :class:`tactile_kb.touch.sensors.FaultySensors`).
    completer
        Makes the completer of one exploration (see
        :class:`~tactile_kb.touch.explorers.WorldExplorer`).
    """

    name = "stepper"

    def make_world(
        self, mesh: trimesh.Trimesh, finger: Finger, *, seed: int | None
    ) -> StepperWorld:
        """The analytic world of ``mesh`` sensed with ``finger`` (ideal; faults are added by
        :class:`~tactile_kb.touch.sensors.FaultySensors`)."""
        del seed  # the analytic world draws no random numbers
        return StepperWorld(mesh, finger)
