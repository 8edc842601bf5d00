"""Grasp quality: two-contact force closure, the soft-finger Ferrari–Canny ε, the least force.

The contact model (the pincers' pads are soft): each contact pushes with a force inside its
friction cone (linearised by ``cone_edges`` unit forces on the cone's boundary, one of them
pointing straight up so holding against gravity is exact) and may twist about its normal by
torsional friction, modelled as two extra wrench primitives ``±ρ·n`` (a unit force acting at
the pad radius ρ, 5 mm by default). The grasp wrench set is the convex hull of these
primitives (total contact force ≤ 1 N); ε is the radius of the largest ball about the
origin inside it (torques divided by the object's size ``λ = √(tr I / m)``), and the least
force is its gauge at the gravity wrench. With hard point contacts (``soft=False``) two
contacts cannot resist a torque about the line joining them, so ε = 0.

Examples
--------
>>> import numpy as np
>>> points = np.array([[0.05, 0.0, 0.02], [-0.05, 0.0, 0.02]])
>>> normals = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
>>> force_closure(points, normals, mu=0.5)
True
>>> round(least_force(points, normals, com=(0.0, 0.0, 0.02), mass=0.2), 2)
4.39
>>> ferrari_canny(points, normals, com=(0.0, 0.0, 0.02), torque_scale=0.05, soft=False)
0.0
"""

from __future__ import annotations

import math

import numpy as np
import trimesh
from numpy.typing import ArrayLike
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from tactile_kb.errors import UsageError
from tactile_kb.geometry.polyhedron import Polyhedron
from tactile_kb.types import FloatArray

__all__ = [
    "DEFAULT_CONE_EDGES",
    "DEFAULT_MU",
    "DEFAULT_PAD_RADIUS",
    "GRAVITY",
    "ferrari_canny",
    "force_closure",
    "least_force",
    "torque_scale",
    "wrench_primitives",
]

DEFAULT_MU = 0.5
"""Coefficient of friction between the pads and the object (friction angle 26.6°)."""

DEFAULT_PAD_RADIUS = 0.005
"""ρ of the soft pads, metres: torsional friction is modelled as a unit force at this radius."""

DEFAULT_CONE_EDGES = 8
"""Unit forces on the boundary of each friction cone (its linearisation)."""

GRAVITY = 9.81
"""m/s²."""

_UP = np.array([0.0, 0.0, 1.0])


def _contacts(points: ArrayLike, normals: ArrayLike) -> tuple[FloatArray, FloatArray]:
    p = np.asarray(points, dtype=float)
    n = np.asarray(normals, dtype=float)
    if p.shape != n.shape or p.ndim != 2 or p.shape[1] != 3 or len(p) < 1:
        raise UsageError(f"points and normals must both be (k, 3) arrays, got {p.shape}, {n.shape}")
    lengths = np.linalg.norm(n, axis=1)
    if np.any(lengths < 1e-12) or not np.all(np.isfinite(p)):
        raise UsageError("contact normals must be non-zero and points finite")
    return p, n / lengths[:, None]


def force_closure(points: ArrayLike, normals: ArrayLike, *, mu: float = DEFAULT_MU) -> bool:
    """Nguyen's two-contact test: the line through both contacts lies in both friction cones.

    Parameters
    ----------
    points, normals
        (2, 3) contact points and the object's outward unit normals there.
    mu
        Coefficient of friction; the cones' half-angle is ``arctan mu``.

    Returns
    -------
    bool
        True when the angle between the line and each inward normal is at most ``arctan mu``.
    """
    p, n = _contacts(points, normals)
    if len(p) != 2:
        raise UsageError(f"the two-contact test needs exactly 2 contacts, got {len(p)}")
    line = p[1] - p[0]
    length = float(np.linalg.norm(line))
    if length < 1e-12:
        return False
    line /= length
    half = math.atan(mu) + 1e-9
    a0 = math.acos(float(np.clip(np.dot(line, -n[0]), -1.0, 1.0)))
    a1 = math.acos(float(np.clip(np.dot(-line, -n[1]), -1.0, 1.0)))
    return a0 <= half and a1 <= half


def _tangents(inward: FloatArray) -> tuple[FloatArray, FloatArray]:
    """A tangent basis whose first vector is the projection of "up" (x when the face is level)."""
    t1 = _UP - np.dot(_UP, inward) * inward
    if np.linalg.norm(t1) < 1e-6:
        t1 = np.array([1.0, 0.0, 0.0]) - inward[0] * inward
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(inward, t1)


def wrench_primitives(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    torque_scale: float = 1.0,
) -> FloatArray:
    """The wrenches (force, torque / ``torque_scale``) one newton of contact force can exert.

    Parameters
    ----------
    points, normals
        (k, 3) contact points and outward unit normals of the object there.
    com
        The object's centre of mass: torques are taken about it.
    mu
        Coefficient of friction.
    soft
        Add the soft-finger torsion primitives ``±pad_radius · n`` at each contact.
    pad_radius
        Radius (m) at which the torsional friction of a soft pad acts.
    cone_edges
        Unit forces on each friction cone's boundary; the first is tilted straight up.
    torque_scale
        λ, metres: torques are divided by it so forces and torques compare.

    Returns
    -------
    numpy.ndarray
        (k · (cone_edges + 2·soft), 6) rows ``(fx, fy, fz, τx/λ, τy/λ, τz/λ)``.
    """
    p, n = _contacts(points, normals)
    c = np.asarray(com, dtype=float).reshape(3)
    if cone_edges < 3:
        raise UsageError(f"cone_edges must be at least 3, got {cone_edges}")
    if mu < 0 or torque_scale <= 0 or pad_radius < 0:
        raise UsageError("mu and pad_radius must be ≥ 0 and torque_scale > 0")
    rows = []
    angles = 2.0 * np.pi * np.arange(cone_edges) / cone_edges
    for point, normal in zip(p, n, strict=True):
        inward = -normal
        t1, t2 = _tangents(inward)
        forces = inward + mu * (np.cos(angles)[:, None] * t1 + np.sin(angles)[:, None] * t2)
        forces /= np.linalg.norm(forces, axis=1)[:, None]
        torques = np.cross(point - c, forces) / torque_scale
        rows.append(np.hstack([forces, torques]))
        if soft:
            twist = pad_radius * inward / torque_scale
            rows.append(np.array([[0, 0, 0, *twist], [0, 0, 0, *(-twist)]], dtype=float))
    return np.vstack(rows)


def ferrari_canny(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    torque_scale: float = 1.0,
) -> float:
    """Ferrari–Canny ε (L1): the largest ball about the origin inside the grasp wrench hull.

    The hull is that of :func:`wrench_primitives` (total contact force ≤ 1 N); ε is in
    newtons (torques divided by ``torque_scale``). 0 when the grasp cannot resist some wrench
    (two hard contacts never resist a torque about the line joining them).
    """
    w = wrench_primitives(
        points,
        normals,
        com,
        mu=mu,
        soft=soft,
        pad_radius=pad_radius,
        cone_edges=cone_edges,
        torque_scale=torque_scale,
    )
    if np.linalg.matrix_rank(w, tol=1e-9) < 6:
        return 0.0
    try:
        hull = ConvexHull(w)
    except QhullError:  # flat: the wrenches span fewer than six dimensions
        return 0.0
    distances = -hull.equations[:, -1]  # offsets b of n·x + b ≤ 0, n unit
    return float(max(0.0, distances.min()))


def least_force(
    points: ArrayLike,
    normals: ArrayLike,
    com: ArrayLike,
    mass: float,
    *,
    mu: float = DEFAULT_MU,
    soft: bool = True,
    pad_radius: float = DEFAULT_PAD_RADIUS,
    cone_edges: int = DEFAULT_CONE_EDGES,
    gravity: float = GRAVITY,
) -> float | None:
    """The least total contact force (N) that holds ``mass`` kg against gravity, or None.

    A linear programme over :func:`wrench_primitives`: non-negative amounts of each unit
    primitive whose wrenches cancel the weight ``(0, 0, −m g)`` acting at ``com``; the sum of
    the amounts is the total force (the twist primitives count as a force at the pad radius).
    None when no contact forces can hold the object (hard contacts off the centre of mass).
    """
    if mass <= 0:
        raise UsageError(f"mass must be > 0 kg, got {mass}")
    w = wrench_primitives(
        points, normals, com, mu=mu, soft=soft, pad_radius=pad_radius, cone_edges=cone_edges
    )
    weight = np.array([0.0, 0.0, -mass * gravity, 0.0, 0.0, 0.0])
    res = linprog(np.ones(len(w)), A_eq=w.T, b_eq=-weight, bounds=(0, None), method="highs")
    if res.status != 0:
        return None
    return float(res.fun)


def torque_scale(poly: Polyhedron) -> float:
    """λ = √(tr I / m) of a uniform solid polyhedron, metres (for a box a×b×c: √((a²+b²+c²)/6))."""
    return math.sqrt(_second_moment(poly) * 2.0)


def _mesh(poly: Polyhedron) -> trimesh.Trimesh:
    tris = [(f[0], f[k], f[k + 1]) for f in poly.faces for k in range(1, len(f) - 1)]
    return trimesh.Trimesh(vertices=poly.vertices, faces=np.asarray(tris), process=False)


def _second_moment(poly: Polyhedron) -> float:
    """E|x − c|² over the solid, m²."""
    mesh = _mesh(poly)
    inertia = np.asarray(mesh.moment_inertia, dtype=float)  # density 1, about the centre of mass
    volume = float(mesh.volume)
    if volume <= 0:
        raise UsageError("the polyhedron has no volume")
    return float(np.trace(inertia)) / (2.0 * volume)
