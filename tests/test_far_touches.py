"""One or two touches far outside the other faces' polyhedron are a face, not an edge's touch.

A 27 cm box lying on a side, scanned at level 3: its contour ran out of motions before the
far end, and a face fitted to a rounded corner's touches (sensor-quantised, cutting deep into
the box) closed the others' planes short of that end. One probe then met the end as two
contacts whose sensors read a normal 29° off the end's (a rough scan), 35 mm further than ρ
outside the others' polyhedron. :func:`~tactile_kb.geometry.planes.edge_faces` took them for
an edge's touches (a tip outside a polyhedron does not penetrate it) and the model stayed
open. A tip on an edge of that polyhedron, sharp or rounded, has its centre within ρ of it;
:func:`tactile_kb.geometry.model._far_from_edges` keeps the touches when every centre lies
further than :data:`~tactile_kb.geometry.model.FAR_TOUCH_RHO` tip radii beyond that.

The truth is the construction: a box's planes, touches placed on its faces and edges here.
"""

from __future__ import annotations

import math

import numpy as np

from tactile_kb.geometry.model import _far_from_edges
from tactile_kb.geometry.planes import Face, edge_faces
from tactile_kb.settings import current
from tactile_kb.touch.finger import builtin_finger

RHO = builtin_finger("33").radius
L, W, H = 0.135, 0.025, 0.065  # half-length, half-width, height of the box lying along x
CONE = 13.0  # degrees: the 33-sensor finger's quantisation, as an unrefined face's uncertainty


def _face(
    normal: np.ndarray, points: list[np.ndarray], centres: list[np.ndarray], *, refined: bool
) -> Face:
    """A face of touches at ``points`` (on its plane), their tip centres appended to ``centres``."""
    n = normal / np.linalg.norm(normal)
    start = len(centres)
    centres.extend(p + RHO * n for p in points)
    return Face(
        tuple(float(x) for x in n),  # type: ignore[arg-type]
        float(n @ points[0]),
        len(points),
        0.0,
        0.5 if refined else CONE,
        tuple(range(start, len(centres))),
        refined,
    )


def _box_without_its_far_end() -> tuple[list[Face], list[np.ndarray]]:
    """The box's sides ±y, +x end and top, each touched on a grid of six (refined); the table;
    a corner face of three touches at the −x, −y corner whose plane cuts 45 mm into the box."""
    centres: list[np.ndarray] = []
    faces: list[Face] = []
    grid = [(u, v) for u in (-0.6, 0.0, 0.6) for v in (0.3, 0.7)]
    sides = {
        (0.0, 1.0, 0.0): [(u * L, W, v * H) for u, v in grid],
        (0.0, -1.0, 0.0): [(u * L, -W, v * H) for u, v in grid],
        (1.0, 0.0, 0.0): [(L, u * W, v * H) for u, v in grid],
        (0.0, 0.0, 1.0): [(u * L, (v - 0.5) * W, H) for u, v in grid],
    }
    for normal, points in sides.items():
        faces.append(_face(np.array(normal), [np.array(p) for p in points], centres, refined=True))
    faces.append(Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table"))
    corner = np.array([-0.8, -0.6, 0.0])
    through = np.array([-L + 0.045, -W, 0.0])  # its plane meets the −y side 45 mm in
    d = corner @ through
    spots = []
    for z in (0.02, 0.03, 0.04):  # three touches on its plane, inside the box's outline
        p = through + np.array([0.0, 0.0, z])
        spots.append(p + (d - corner @ p) * corner)
    faces.append(_face(corner, spots, centres, refined=False))
    return faces, centres


def _judged(read: np.ndarray, points: list[np.ndarray]) -> tuple[bool, bool]:
    """The box without its far end, and a face of touches at ``points`` each reading the
    normal ``read``: whether ``edge_faces`` takes it for an edge's touches, and whether
    ``_far_from_edges`` drops it then."""
    faces, centres = _box_without_its_far_end()
    k = len(faces)
    faces.append(_face(read, points, centres, refined=False))
    c = np.asarray(centres)
    rounding = current().geometry.edge_rounding
    edge = k in edge_faces(tuple(faces), c, RHO, rounding=rounding)
    return edge, _far_from_edges(tuple(faces), [k], c, RHO, 0.0, rounding) == [k]


def test_two_touches_of_the_far_end_are_a_face() -> None:
    # the −x end met twice, the sensors reading a normal 29° off the end's: the tips lie
    # outside the others' polyhedron, penetrating nothing, an edge's by the edge test alone
    read = np.array([-math.cos(math.radians(29.0)), -math.sin(math.radians(29.0)), 0.0])
    end = [np.array([-L, 0.010, 0.030]), np.array([-L, 0.014, 0.030])]
    assert _judged(read, end) == (True, False)


def test_two_touches_of_an_edge_stay_an_edges() -> None:
    # the edge between the +y side and the top, touched twice reading their bisector: the
    # tip centres ρ from the edge
    bisector = np.array([0.0, 1.0, 1.0]) / math.sqrt(2.0)
    edge = [np.array([x, W, H]) for x in (0.02, 0.05)]
    assert _judged(bisector, edge) == (True, True)
