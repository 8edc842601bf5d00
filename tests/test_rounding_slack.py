"""Rounded edges in the completion's tests of the model: a path that went round a rounded edge,
and a face's second height, clear of a rounding (ground truth: boxes built here, their
planes, the arcs a tip centre follows round a rounding, and the rounding's extent)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_kb import completion, settings, solids
from tactile_kb.completion import completion_probes
from tactile_kb.geometry.model import build_model
from tactile_kb.geometry.planes import rounded_edge_slack, rounding_zone, segment_distances
from tactile_kb.geometry.polyhedron import polyhedron_from_planes
from tactile_kb.record import ExplorationRecord, Layer
from tactile_kb.settings import current
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

RHO = 0.005  # the 33-sensor finger's tip radius
A, B, C = 0.10, 0.08, 0.09  # the box: x from −A/2 to A/2, y from −B/2 to B/2, z from 0 to C
# its faces' widths (across their longest direction): ±x 0.08 (B × C), ±y 0.09 (A × C),
# top 0.08 (A × B); a rounding is at most edge_rounding (0.1) times the narrower face's
CAP_SIDES = 0.1 * min(B, C)  # the vertical edge of +x and +y: 8 mm
CAP_TOP_X = 0.1 * min(B, B)  # the top edge of +x (the top is 0.08 wide): 8 mm


def _box_planes() -> tuple[np.ndarray, np.ndarray]:
    normals = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float
    )
    offsets = np.array([A / 2, A / 2, B / 2, B / 2, C, 0.0])
    return normals, offsets


def _edge(poly_faces: tuple[tuple[int, int], ...], f: int, g: int) -> int:
    return next(e for e, pair in enumerate(poly_faces) if set(pair) == {f, g})


def test_the_slack_of_a_box_edge_is_that_of_its_largest_rounding() -> None:
    normals, offsets = _box_planes()
    poly = polyhedron_from_planes(normals, offsets)
    inside, beside = rounded_edge_slack(poly, 0.1)
    at = {int(j): k for k, j in enumerate(poly.plane_index)}  # plane → face of poly
    e = _edge(poly.edge_faces, at[0], at[2])  # the vertical edge of +x and +y
    # a right angle: the arc ρ + r from the axis passes r(√2 − 1) nearer the sharp edge, and
    # the rounding meets its faces r from it
    assert inside[e] == pytest.approx(CAP_SIDES * (math.sqrt(2.0) - 1.0), rel=1e-6)
    assert beside[e] == pytest.approx(CAP_SIDES, rel=1e-6)
    e = _edge(poly.edge_faces, at[0], at[4])  # the top edge of +x
    assert beside[e] == pytest.approx(CAP_TOP_X, rel=1e-6)
    none = rounded_edge_slack(poly, 0.0)
    assert not none[0].any()
    assert not none[1].any()


def test_an_acute_edge_has_no_slack() -> None:
    """A wedge's 45° edges (normals 135° apart): a spike's wide faces must not explain away
    what lies by its tip."""
    s = math.sqrt(0.5)
    normals = np.array([[0, 0, -1], [s, 0, s], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], dtype=float)
    offsets = np.array([0.0, s * 0.05, 0.0, 0.04, 0.04])  # the slope x + z ≤ 0.05, x ≥ 0
    poly = polyhedron_from_planes(normals, offsets)
    inside, beside = rounded_edge_slack(poly, 0.1)
    at = {int(j): k for k, j in enumerate(poly.plane_index)}
    e = _edge(poly.edge_faces, at[0], at[1])  # table and slope: 45°
    assert inside[e] == 0.0
    assert beside[e] == 0.0
    e = _edge(poly.edge_faces, at[1], at[2])  # slope and back: 45° too
    assert inside[e] == 0.0
    assert beside[e] == 0.0
    e = _edge(poly.edge_faces, at[0], at[2])  # table and back: a right angle
    assert inside[e] > 0.0
    assert beside[e] > 0.0


def test_segment_distances() -> None:
    a = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    b = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    pts = np.array([[0.5, 2.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.5]])
    d = segment_distances(pts, a, b)
    assert d == pytest.approx(np.array([[2.0, math.hypot(0.5, 2.0)], [1.0, 2.0], [0.5, 0.0]]))


def _sampled_box() -> ExplorationRecord:
    return sample_record(
        solids.box(A, B, C), builtin_finger("33"), per_face=8, quantise=False, noise=0.0, seed=5
    )


def _arc(r: float, *, z: float = 0.045) -> list[tuple[float, float, float]]:
    """The tip centre's way round the vertical edge (+x, +y) rounded with radius ``r``: ρ off
    face +x for 2 cm, ρ + r from the rounding's axis round it (every 5°), ρ off face +y for
    2 cm."""
    axis = np.array([A / 2 - r, B / 2 - r])
    out = [(A / 2 + RHO, B / 2 - r - 0.02, z)]
    for a in np.radians(np.arange(0.0, 91.0, 5.0)):
        p = axis + (RHO + r) * np.array([math.cos(a), math.sin(a)])
        out.append((float(p[0]), float(p[1]), z))
    out.append((A / 2 - r - 0.02, B / 2 + RHO, z))
    return out


def _with_path(rec: ExplorationRecord, path: list[tuple[float, float, float]]) -> ExplorationRecord:
    return rec.model_copy(update={"layers": [Layer(index=0, z=path[0][2], path=path)]})


@pytest.mark.parametrize("r", [0.004, 0.006, 0.008])
def test_a_path_round_a_rounded_edge_is_no_missing_face(r: float) -> None:
    """A contour that went round a rounded vertical edge passes up to r(√2 − 1) nearer the
    model's sharp edge than ρ (2.5 mm for r = 6 mm, more than the test's ρ/4): the rounding
    explains it, up to the largest rounding the edge's faces allow (8 mm), and no probe goes
    there."""
    model = build_model(_with_path(_sampled_box(), _arc(r)))
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 6
    assert completion._free_path_probes(model, RHO) == []
    # the same path, the rounding allowance off: every such dip was a probe
    with settings.override(geometry={"edge_rounding": 0.0}):
        deep = RHO - r * (math.sqrt(2.0) - 1.0) < RHO - 0.25 * RHO
        assert bool(completion._free_path_probes(model, RHO)) == deep


def test_a_path_past_a_cut_corner_is_still_probed() -> None:
    """A corner cut off by a face no touch found (a 45° chamfer with 15 mm legs): the path
    along it, ρ off it, runs inside the model, far deeper than any rounding, and is probed."""
    leg = 0.015
    n = np.array([1.0, 1.0]) / math.sqrt(2.0)
    along = np.array([-n[1], n[0]])
    middle = np.array([A / 2, B / 2]) - leg / math.sqrt(2.0) * n  # of the chamfer
    path = [
        (float(x), float(y), 0.045)
        for x, y in (middle + RHO * n + t * along for t in np.linspace(-0.01, 0.01, 11))
    ]
    model = build_model(_with_path(_sampled_box(), path))
    probes = completion._free_path_probes(model, RHO)
    assert probes, "the cut corner is tested"
    target = np.asarray(probes[0].target)[:2]
    assert float(n @ (target - middle)) == pytest.approx(RHO, abs=1e-6)  # on the path


def _one_height(rec: ExplorationRecord, z: float) -> ExplorationRecord:
    """The box's record with every side's contacts moved to tip-centre height ``z`` (the
    sides are vertical: still exact touches of them)."""
    out = []
    for c in rec.contacts:
        if abs(c.direction[2]) < 0.5:
            cx, cy, _ = c.centre
            px, py, _ = c.point
            c = c.model_copy(update={"centre": (cx, cy, z), "point": (px, py, z)})
        out.append(c)
    return rec.model_copy(update={"contacts": out})


def test_a_sides_second_height_is_asked_clear_of_the_roundings_of_its_edges() -> None:
    """A side touched at one height (3 cm) is probed at another, but not where a rounding of
    its top or bottom edge as large as its faces allow could reach (8 mm from the top and
    from the table, and half ρ clear): there the tip touches the flat side of a scanned box,
    not the rounding, whose touch would only tilt the side's plane and call for another
    test."""
    model = build_model(_one_height(_sampled_box(), 0.03))
    poly = model.polyhedron
    assert poly is not None
    probes = [p for p in completion_probes(model) if "touched at one height" in p.reason]
    sides = {tuple(np.round(p.normal, 3)) for p in probes}
    assert len(sides) == 4  # each side
    reach = 0.1 * min(A, B, C) + 0.5 * RHO  # every face of this box is 8 cm wide or more
    for p in probes:
        target = np.asarray(p.target)  # the tip centre, ρ off the side
        assert abs(target[2] - 0.03) >= 0.5 * RHO  # another height
        assert reach - 1e-9 <= target[2] <= C - reach + 1e-9
        k = int(np.argmax(poly.normals @ np.asarray(p.normal)))
        zone = rounding_zone(target[None, :], poly, k, RHO, current().geometry.edge_rounding)
        assert not zone.any()
