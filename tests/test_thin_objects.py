"""Thin objects: a plate is a rectangular parallelepiped, a bar lying on the table a prism.

A plate's edges along its thickness are shorter than ``features.rel_tol`` (6 %) of its mean
edge, the length below which an edge counts as a corner that noisy planes split
(``features.builtin._split_corners``). Taken for corners, they left only the square faces'
edges, all equal: a 20 × 20 × 0.8 cm tile was answered "OBJECT IS A CUBE" by both rule files.
Its top and bottom corners also lie within 3 % of its diameter (``geometry.merge_fraction``),
and a larger or noisier tile had them merged, leaving no polyhedron. Such an edge runs
between faces that face away from each other, and the faces of one corner never do
(``geometry.polyhedron.opposed``). A bar's end, 12 mm across and 40 cm long, has its corners
within that distance too, whatever its faces; merged into no polyhedron, they are merged again
within half the distance (``polyhedron.MERGE_RETRIES``). The truth here is the objects' own
dimensions (edges of 200, 200 and 8 mm are not equal; a bar's corners, faces and volume), and
an octahedron, whose corners four faces share, keeps its split corners joined.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.features import builtin
from tactile_kb.geometry.polyhedron import (
    Polyhedron,
    collapse_short_edges,
    opposed_edges,
    polyhedron_from_planes,
)
from tactile_kb.pipeline import classify


def turned(mesh: trimesh.Trimesh, degrees: float) -> trimesh.Trimesh:
    out = mesh.copy()
    out.apply_transform(trimesh.transformations.rotation_matrix(np.radians(degrees), [0, 0, 1]))
    return out


@pytest.mark.parametrize("rules", ["parallelepipeds", "polyhedra"])
@pytest.mark.parametrize(
    ("side", "thick", "turn", "noise"),
    [(0.20, 0.008, 0.0, 0.0), (0.22, 0.008, 33.0, 0.0005), (0.24, 0.0085, 71.0, 0.0)],
)
def test_a_thin_square_plate_is_no_cube(
    rules: str, side: float, thick: float, turn: float, noise: float
) -> None:
    assert thick < 0.06 * (2 * side + thick) / 3  # under rel_tol of the mean edge
    result = classify(turned(solids.box(side, side, thick), turn), rules=rules, noise=noise, seed=0)
    assert result.decision.label == "rectangular_parallelepiped"
    assert not builtin.equal_edges(result.model)


def test_a_cube_stays_a_cube() -> None:
    # the same exploration of a solid whose edges are equal
    result = classify(turned(solids.box(0.08, 0.08, 0.08), 33.0), noise=0.0005, seed=0)
    assert result.decision.label == "cube"


PLATE_N = np.vstack([np.eye(3), -np.eye(3)])


def plate_planes(side: float, thick: float) -> np.ndarray:
    """The offsets of a side × side × thick plate's planes (normals ``PLATE_N``), centred."""
    return np.array([side / 2, side / 2, thick / 2] * 2)


def split_octahedron(tilt_deg: float) -> Polyhedron:
    """A 12 cm octahedron (faces n·x = 5 cm, n = (±1, ±1, ±1)/√3) with one face turned
    ``tilt_deg`` about z, so that its corners split into short edges; nothing merged."""
    s = 1 / np.sqrt(3)
    n = np.array([[a, b, c] for a in (s, -s) for b in (s, -s) for c in (s, -s)])
    t = np.radians(tilt_deg)
    turn = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    n[0] = turn @ n[0]
    return polyhedron_from_planes(n, np.full(8, 0.05), tol=0.0)


@pytest.mark.parametrize(("side", "thick"), [(0.22, 0.006), (0.30, 0.008), (0.5, 0.003)])
def test_a_plate_thinner_than_the_merge_distance_keeps_its_corners(
    side: float, thick: float
) -> None:
    # the vertices closer than 3 % of the diameter are merged, but a plate's top corner and
    # the bottom corner below it lie on planes facing away from each other
    assert thick < 0.03 * side * np.sqrt(2)
    p = polyhedron_from_planes(PLATE_N, plate_planes(side, thick))
    truth = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * [
        side / 2,
        side / 2,
        thick / 2,
    ]
    assert len(p.faces) == 6
    assert np.allclose(np.sort(p.vertices, axis=0), np.sort(truth, axis=0))
    short = p.edge_lengths() < 2 * thick
    assert short.sum() == 4
    assert np.isclose(p.edge_lengths()[short], thick).all()
    assert opposed_edges(p)[short].all()
    # noisy planes' σ make its thickness "short", and it is not collapsed either
    q = collapse_short_edges(p, np.full(6, 0.003), np.full(6, 0.05))
    assert len(q.vertices) == 8


def test_a_split_corner_is_still_one_corner() -> None:
    split = split_octahedron(2.0)
    short = split.edge_lengths() < 0.003
    assert short.sum() == 2  # the two corners of the turned face beside others split
    assert not opposed_edges(split)[short].any()
    # merged at the default distance: the octahedron's 6 corners, 12 edges
    s = 1 / np.sqrt(3)
    n = np.array([[a, b, c] for a in (s, -s) for b in (s, -s) for c in (s, -s)])
    n[0] = split.normals[list(split.plane_index).index(0)]
    merged = polyhedron_from_planes(n, np.full(8, 0.05))
    assert (len(merged.vertices), len(merged.edges)) == (6, 12)


def lying(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """``mesh`` turned a quarter about x: a standing cylinder lies along y."""
    out = mesh.copy()
    out.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    return out


def test_a_long_thin_bar_keeps_its_end_faces() -> None:
    # a bar of equilateral section (12 mm sides) lying along y, 40 cm long: the corners of
    # its end lie within 3 % of its diameter, merged they left no end face (Euler's formula
    # failed); merged within half that, the bar's 6 corners are its own
    a, length = 0.012, 0.40
    h = a * np.sqrt(3) / 2
    n = np.array(
        [[0, 0, -1], [np.sqrt(3) / 2, 0, 0.5], [-np.sqrt(3) / 2, 0, 0.5], [0, 1, 0], [0, -1, 0]]
    )
    # each slanted side passes through a base corner (±a/2, y, 0) and the ridge (0, y, h)
    d = np.array([0.0, np.sqrt(3) / 4 * a, np.sqrt(3) / 4 * a, length / 2, length / 2])
    p = polyhedron_from_planes(n, d)
    truth = np.array(
        [[x, y, 0.0] for x in (-a / 2, a / 2) for y in (-length / 2, length / 2)]
        + [[0.0, y, h] for y in (-length / 2, length / 2)]
    )
    assert (len(p.vertices), len(p.edges), len(p.faces)) == (6, 9, 5)
    assert np.allclose(np.sort(p.vertices, axis=0), np.sort(truth, axis=0))


@pytest.mark.parametrize("turn", [0.0, 40.0, 77.0])
def test_a_lying_triangular_bar_is_a_three_sided_prism(turn: float) -> None:
    a, length = 0.012, 0.40
    h = a * np.sqrt(3) / 2
    corners = [[x, y, 0.0] for x in (-a / 2, a / 2) for y in (-length / 2, length / 2)]
    corners += [[0.0, y, h] for y in (-length / 2, length / 2)]
    bar = turned(trimesh.convex.convex_hull(np.array(corners)), turn)
    result = classify(bar, rules="polyhedra")
    assert result.decision.label == "prism"
    assert result.measures["sides"] == 3
    assert result.measures["volume"] == pytest.approx(a * h / 2 * length, rel=0.01)


def test_a_lying_rod_is_curved() -> None:
    # 8 mm across, the tip 10 mm: its end's facets merged into no polyhedron before
    rod = lying(solids.cylinder(0.004, 0.30))
    assert classify(rod, rules="polyhedra").decision.label == "curved"
