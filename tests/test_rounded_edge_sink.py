"""A tip on a well rounded edge sinks below the grown planes of the edge's faces (issue 10).

A scanned box's edges are rounded with a radius up to about a tenth of an edge. A tip of
radius ρ resting on a rounding of radius r, half way round a 90° edge, has its centre
(ρ + r)(1 − cos 45°) below the planes of both faces moved out by ρ: 3.8 mm for ρ = 5 mm and
r = 8 mm, more than the half tip radius within which a centre used to count as lying against
a face. Such touches read a normal between the two faces' and made a narrow face of their
own, which cut the box's edge off (a level-2 rhombohedron read "other polyhedron").

The truth is the construction: a 10 cm cube's planes, its sides touched on grids, and a row
of touches on an edge rounded with radius r, their centres computed from the rounding's
axis. A chamfer cut deeper than such a rounding reaches stays a face, and so do touches sunk
below one face alone.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_kb.geometry.planes import Face, edge_faces
from tactile_kb.touch.finger import builtin_finger

RHO = builtin_finger("33").radius
S = 0.10  # the cube's side
CONE = 13.0  # degrees: the 33-sensor finger's quantisation, as an unrefined face's uncertainty
# outward normals and offsets: +x, −x, +y, −y, top, table
NORMALS = np.array(
    [[1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0], [0, -1.0, 0], [0, 0, 1.0], [0, 0, -1.0]]
)
OFFSETS = np.array([S / 2, S / 2, S / 2, S / 2, S, 0.0])


def _sides() -> tuple[list[Face], list[np.ndarray]]:
    """Each face but the table touched on a 3 × 2 grid of its own (refined), and the table."""
    faces: list[Face] = []
    centres: list[np.ndarray] = []
    for k, (n, d) in enumerate(zip(NORMALS, OFFSETS, strict=True)):
        if k == 5:
            faces.append(Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table"))
            continue
        u = np.roll(n, 1)  # two directions in the face
        v = np.cross(n, u)
        middle = n * d + (np.array([0.0, 0.0, S / 2]) if k < 4 else 0.0)
        start = len(centres)
        for a in (-0.3, 0.0, 0.3):
            for b in (-0.2, 0.2):
                p = middle + S * (a * u + b * v)
                assert abs(float(n @ p) - d) < 1e-12  # on the face
                centres.append(p + RHO * n)
        nt = tuple(float(x) for x in n)
        faces.append(Face(nt, float(d), 6, 0.0, 0.5, tuple(range(start, len(centres))), True))  # type: ignore[arg-type]
    return faces, centres


def _row(
    faces: list[Face], centres: list[np.ndarray], tips: list[np.ndarray], normal: np.ndarray
) -> tuple[list[Face], np.ndarray]:
    """``faces`` and an unrefined face of tip centres ``tips``, each read with ``normal``."""
    start = len(centres)
    all_centres = np.asarray([*centres, *tips])
    nt = tuple(float(x) for x in normal)
    row = Face(
        nt,
        float(normal @ tips[0]) - RHO,
        len(tips),
        0.0,
        CONE,
        tuple(range(start, len(all_centres))),
        False,
    )  # type: ignore[arg-type]
    return [*faces, row], all_centres


@pytest.mark.parametrize("radius", [0.002, 0.005, 0.008])
def test_touches_half_way_round_a_rounded_edge_are_the_edges(radius: float) -> None:
    faces, centres = _sides()
    # the edge between the top and the +x side, rounded with this radius: its axis lies r
    # inside both faces; the tips rest on it half way round, reading the bisector
    m = (NORMALS[0] + NORMALS[4]) / math.sqrt(2.0)
    axis = np.array([S / 2 - radius, 0.0, S - radius])
    tips = [axis + np.array([0.0, y, 0.0]) + (RHO + radius) * m for y in (-0.01, 0.0, 0.01)]
    sink = (RHO + radius) * (1.0 - math.cos(math.radians(45.0)))
    for c in tips:  # below both faces' planes moved out by ρ, by the sink
        assert float(NORMALS[0] @ c) - OFFSETS[0] == pytest.approx(RHO - sink)
        assert float(NORMALS[4] @ c) - OFFSETS[4] == pytest.approx(RHO - sink)
    faces, c = _row(faces, centres, tips, m)
    assert edge_faces(faces, c, RHO) == [len(faces) - 1]


def test_a_chamfer_deeper_than_any_rounding_stays_a_face() -> None:
    faces, centres = _sides()
    # a chamfer cutting the same edge with legs of 30 mm: a face of the object, its middle
    # 21 mm inside the edge, beyond what a rounding of a tenth of the faces' width reaches
    # (the width of a square face is measured across a diagonal: 14 mm)
    m = (NORMALS[0] + NORMALS[4]) / math.sqrt(2.0)
    middle = np.array([S / 2 - 0.015, 0.0, S - 0.015])
    tips = [middle + np.array([0.0, y, 0.0]) + RHO * m for y in (-0.01, 0.0, 0.01)]
    faces, c = _row(faces, centres, tips, m)
    assert edge_faces(faces, c, RHO) == []


def test_a_side_of_an_octagon_touched_near_its_end_stays_a_side() -> None:
    """At an octagonal prism's 45° edges a rounding sinks a tip by (ρ + r)(1 − cos 22.5°),
    0.7 mm: two touches of a side 4 mm from its end, 4 mm below the grown plane of the
    neighbouring side (extended) and within a wide top's reach, are that side's."""
    faces: list[Face] = []
    centres: list[np.ndarray] = []
    apothem, height = 0.04, 0.04
    for k in range(1, 8):  # seven of the octagon's eight sides, each touched on a grid
        a = math.radians(45.0 * k)
        n = np.array([math.cos(a), math.sin(a), 0.0])
        along = np.array([-math.sin(a), math.cos(a), 0.0])
        start = len(centres)
        for u in (-0.008, 0.0, 0.008):
            for z in (0.012, 0.028):
                centres.append(apothem * n + u * along + np.array([0.0, 0.0, z]) + RHO * n)
        faces.append(Face(tuple(n), apothem, 6, 0.0, 0.5, tuple(range(start, len(centres))), True))  # type: ignore[arg-type]
    start = len(centres)
    for x, y in ((0.0, 0.0), (0.02, 0.01), (-0.02, 0.01)):
        centres.append(np.array([x, y, height + RHO]))
    faces.append(
        Face((0.0, 0.0, 1.0), height, 3, 0.0, 0.5, tuple(range(start, len(centres))), True)
    )  # type: ignore[arg-type]
    faces.append(Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table"))
    # the eighth side (normal +x): half its width is apothem·tan 22.5°; touched 4 mm from
    # its end, 4 mm below its neighbour's grown plane, near the top
    half = apothem * math.tan(math.radians(22.5))
    side = np.array([1.0, 0.0, 0.0])
    tips = [np.array([apothem + RHO, half - 0.004, z]) for z in (0.034, 0.036)]
    neighbour = np.array([math.cos(math.radians(45.0)), math.sin(math.radians(45.0)), 0.0])
    for t in tips:  # 4.3 mm below the neighbour's grown plane: deeper than ρ/2, and than
        # the 0.7 mm a rounding at a 45° edge sinks a tip, 9–11 mm below the top's
        assert apothem + RHO - float(neighbour @ t) == pytest.approx(0.0043, abs=1e-4)
    faces, c = _row(faces, centres, tips, side)
    assert edge_faces(faces, c, RHO) == []


def test_touches_sunk_below_one_face_alone_are_no_edges() -> None:
    """A rounding sinks a tip below the planes of both its edge's faces; three touches 3 mm
    below the top's grown plane in its middle, far below every other face's, lie on no
    rounded edge (a dimple, or a face of its own), and their face stays."""
    faces, centres = _sides()
    tilted = np.array([math.sin(math.radians(20.0)), 0.0, math.cos(math.radians(20.0))])
    tips = [np.array([0.0, y, S + RHO - 0.003]) for y in (-0.01, 0.0, 0.01)]
    faces, c = _row(faces, centres, tips, tilted)
    assert edge_faces(faces, c, RHO) == []
