"""Cross-sections of the polyhedron, and layer contours of objects made of boxes (Fig. 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely.geometry

from tactile_kb import solids
from tactile_kb.errors import UsageError
from tactile_kb.geometry.polyhedron import polyhedron_from_planes
from tactile_kb.geometry.sections import (
    FAR_CORNER,
    contour_from_contacts,
    cross_section,
    distinct_planes,
    layer_sections,
    polygon_area,
)
from tactile_kb.record import Contact
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import layer_polygon, sample_layers


def test_cross_section_of_a_pyramid_scales_with_height() -> None:
    mesh = solids.pyramid(4, 0.05, 0.1)
    n = mesh.face_normals
    p = polyhedron_from_planes(n, np.einsum("ij,ij->i", n, mesh.triangles_center))
    base = abs(polygon_area(cross_section(p, 1e-9)))
    half = cross_section(p, 0.05)
    assert len(half) == 4
    assert polygon_area(half) > 0
    assert math.isclose(polygon_area(half), base / 4, rel_tol=1e-6)
    assert len(cross_section(p, 0.2)) == 0


@pytest.mark.parametrize(
    ("mesh", "planes"),
    [
        (solids.l_shape(0.1, 0.08, 0.03, 0.04), 6),
        (solids.t_shape(0.12, 0.1, 0.03, 0.05), 7),  # the bar's two lower sides are one plane
        (solids.u_shape(0.12, 0.1, 0.03, 0.04), 7),  # so are the arms' ends
    ],
)
@pytest.mark.parametrize("finger", ["4", "33"])
def test_layer_contours_equal_the_true_sections(mesh: object, planes: int, finger: str) -> None:
    import trimesh

    assert isinstance(mesh, trimesh.Trimesh)
    # sides as short as 2 cm keep their sensor's direction: turn them onto sensors (30° apart)
    turned = solids.rotate_about_z(mesh, 0.0 if finger == "4" else 30.0)
    rec = sample_layers(turned, builtin_finger(finger), [0.01, 0.025], noise=0.0002, seed=4)
    sections = layer_sections(rec)
    assert len(sections) == 2
    for s in sections:
        truth = layer_polygon(turned, s.z).simplify(1e-6)
        got = shapely.geometry.Polygon(s.contour)
        ring = np.asarray(truth.exterior.coords)[:-1]
        a, b = ring - np.roll(ring, 1, axis=0), np.roll(ring, -1, axis=0) - ring
        turn = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        assert len(s.contour) == int((np.abs(turn) > 1e-9).sum())  # corners, not collinear points
        assert got.symmetric_difference(truth).area < 0.03 * truth.area
        assert polygon_area(s.contour) > 0  # counter-clockwise
    assert len(distinct_planes(sections)) == planes


def test_contour_from_contacts_of_a_square_and_too_few_sides() -> None:
    rho = 0.005
    contacts = []
    for k, (n, p) in enumerate(
        [
            ((1, 0), (0.05, 0.0)),
            ((0, 1), (0.0, 0.05)),
            ((-1, 0), (-0.05, 0.0)),
            ((0, -1), (0.0, -0.05)),
        ]
    ):
        for t in (-0.02, 0.02):
            along = np.array([-n[1], n[0]]) * t
            point = np.array(p) + along
            centre = point + rho * np.array(n)
            contacts.append(
                Contact(
                    step=2 * k,
                    centre=(*centre, 0.01),
                    sensors=(k,),
                    direction=(-n[0], -n[1], 0.0),
                    point=(*point, 0.01),
                )
            )
    poly = contour_from_contacts(contacts, rho)
    assert sorted((round(x, 9), round(y, 9)) for x, y in poly) == [
        (-0.05, -0.05),
        (-0.05, 0.05),
        (0.05, -0.05),
        (0.05, 0.05),
    ]
    with pytest.raises(UsageError, match="at least three"):
        contour_from_contacts(contacts[:4], rho)


def _side_contacts(
    sides: list[tuple[tuple[float, float], tuple[float, float]]], rho: float, spread: float
) -> list[Contact]:
    """Two contacts on each side (unit outward normal, a point of the side), in order."""
    out = []
    for k, (n, p) in enumerate(sides):
        nn = np.asarray(n, dtype=float) / np.linalg.norm(n)
        for t in (-spread, spread):
            point = np.asarray(p) + np.array([-nn[1], nn[0]]) * t
            centre = point + rho * nn
            out.append(
                Contact(
                    step=len(out),
                    centre=(*centre, 0.01),
                    sensors=(k,),
                    direction=(-nn[0], -nn[1], 0.0),
                    point=(*point, 0.01),
                )
            )
    return out


def test_nearly_parallel_neighbours_do_not_meet_far_away() -> None:
    """A layer whose +y side was met at two spots: the right part at y = 50 mm, the left part
    a step out and turned 8°, with the part between unexplored. Their lines meet 150 mm to
    the left, far outside the touched region; the contour keeps to that region, running
    across from the one line's last contact to the other's first."""
    rho, tilt = 0.005, math.radians(8.0)
    sides = [
        ((1.0, 0.0), (0.05, 0.0)),
        ((0.0, 1.0), (0.03, 0.05)),  # +y, right part
        ((-math.sin(tilt), math.cos(tilt)), (-0.03, 0.05 + 0.12 * math.tan(tilt))),  # left part
        ((-1.0, 0.0), (-0.05, 0.0)),
        ((0.0, -1.0), (0.0, -0.05)),
    ]
    contacts = _side_contacts(sides, rho, 0.01)
    poly = np.asarray(contour_from_contacts(contacts, rho))
    points = np.asarray([c.point[:2] for c in contacts])
    lo, hi = points.min(axis=0), points.max(axis=0)
    slack = FAR_CORNER * float(np.linalg.norm(hi - lo))
    assert np.all(poly >= lo - slack - 1e-12)
    assert np.all(poly <= hi + slack + 1e-12)
    assert len(poly) == 6  # the far corner is two: the chord's ends
    # the chord's ends are the last contact on the right part and the first on the left one
    for end in (contacts[3].point[:2], contacts[4].point[:2]):
        assert np.min(np.linalg.norm(poly - np.asarray(end), axis=1)) < 1e-9


def test_a_shallow_roof_keeps_its_corner() -> None:
    """Two parts of the +y side turned ±4°, meeting above the middle: a corner near the
    touched region, kept."""
    rho, tilt = 0.005, math.radians(4.0)
    sides = [
        ((1.0, 0.0), (0.05, 0.0)),
        ((math.sin(tilt), math.cos(tilt)), (0.03, 0.05)),
        ((-math.sin(tilt), math.cos(tilt)), (-0.03, 0.05)),
        ((-1.0, 0.0), (-0.05, 0.0)),
        ((0.0, -1.0), (0.0, -0.05)),
    ]
    poly = np.asarray(contour_from_contacts(_side_contacts(sides, rho, 0.01), rho))
    assert len(poly) == 5
    apex = poly[np.argmax(poly[:, 1])]
    np.testing.assert_allclose(apex, [0.0, 0.05 + 0.03 * math.tan(tilt)], atol=1e-9)
