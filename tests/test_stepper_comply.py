"""The analytic world's compliant slide: small irregularities are ridden over, real edges end it.

The objects are built here, so the truth is known: a box whose +x face (x = A/2) carries one
smooth bump or dip of a few tenths of a millimetre (far smaller than the 5 mm tip), and a
prism whose side turns by a few degrees (ridden over) or by a real edge's angle (not). A slide
along the face at constant z must reach the face's real end (the convex edge at y = B/2) and
stop there exactly as a straight slide on the ideal box stops; with ``world.comply_deg`` 0 (the
straight slides of the paper's world) it stops at the irregularity.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest
import trimesh
from shapely.geometry import Polygon

from tactile_kb import settings, solids
from tactile_kb.errors import UsageError
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.stepper import StepperWorld
from tactile_kb.touch.world import Motion

A, B, C = 0.08, 0.06, 0.05
RHO = 0.005  # the 33-sensor finger's tip radius
Z = 0.025  # the slide's height
FINGER = builtin_finger("33")


def bumped_box(height: float, *, at: float = 0.0, width: float = 0.003) -> trimesh.Trimesh:
    """The A × B × C box with a smooth bump (``height`` > 0) or dip (< 0) on its +x face,
    centred at (A/2, ``at``, Z): the biweight ``height`` (1 − (r/R)²)² within R = 2 ``width``
    (slopes up to 0.77 ``height`` / R); every other vertex stays on the box."""
    box = solids.box(A, B, C)
    v, f = trimesh.remesh.subdivide_to_size(box.vertices, box.faces, max_edge=0.001)
    v = np.array(v, dtype=float)
    on = np.abs(v[:, 0] - A / 2) < 1e-12
    x2 = ((v[:, 1] - at) ** 2 + (v[:, 2] - Z) ** 2) / (2.0 * width) ** 2
    inner = on & (x2 < 1.0)
    v[inner, 0] += height * (1.0 - x2[inner]) ** 2
    return trimesh.Trimesh(v, f, process=False)


def creased_prism(turn_deg: float) -> trimesh.Trimesh:
    """A vertical prism whose side x = A/2 (for y < 0) turns outward-convex by ``turn_deg`` at
    y = 0 (for y > 0 it recedes along a line turned by that angle), up to y = B/2."""
    t = math.radians(turn_deg)
    end = (A / 2 - (B / 2) * math.tan(t), B / 2)
    outline = [(-A / 2, -B / 2), (A / 2, -B / 2), (A / 2, 0.0), end, (-A / 2, B / 2)]
    return trimesh.creation.extrude_polygon(Polygon(outline), C)


@pytest.fixture(autouse=True)
def compliant() -> Iterator[None]:
    """The compliant slide on (``world.comply_deg``, 0 by default: straight slides)."""
    with settings.override(world={"comply_deg": 12.0}):
        yield


def _slide(mesh: trimesh.Trimesh, y0: float = -0.02) -> Motion:
    """A slide along +y from the tip pressed on the +x face at (A/2 + ρ, y0, Z)."""
    world = StepperWorld(mesh, FINGER)
    start = (A / 2 + RHO, y0, Z)
    sensor = FINGER.nearest((-1.0, 0.0, 0.0))
    assert sensor is not None
    assert sensor in world.sense(start)
    return world.slide(start, (0.0, 1.0, 0.0), 0.2, sensor)


def _straight(mesh: trimesh.Trimesh, y0: float = -0.02) -> Motion:
    with settings.override(world={"comply_deg": 0.0}):
        return _slide(mesh, y0)


def test_the_ideal_box_slides_exactly_as_straight() -> None:
    box = solids.box(A, B, C)
    assert _slide(box) == _straight(box)
    m = _slide(box)
    assert m.event == "release"
    assert m.end[1] == pytest.approx(B / 2, abs=1e-4)  # the convex edge, no further round it


@pytest.mark.parametrize(
    ("height", "width"), [(0.0003, 0.003), (-0.0003, 0.003), (0.0008, 0.008), (-0.0008, 0.008)]
)
def test_a_bump_or_dip_smaller_than_the_tip_is_ridden_over(height: float, width: float) -> None:
    # slopes up to 2.2°: no neighbouring sensor (30° away, 25° cones) closes on them
    ideal = _straight(solids.box(A, B, C))
    rough = bumped_box(height, width=width)
    straight = _straight(rough)
    assert straight.end[1] < 0.0  # the paper's straight slide stops at the irregularity
    assert straight.event in ("blocked", "release")
    m = _slide(rough)
    # the compliant one reaches the real edge and stops there as on the ideal box
    assert m.event == ideal.event == "release"
    assert m.end[1] == pytest.approx(ideal.end[1], abs=2e-4)
    assert m.end[0] == pytest.approx(ideal.end[0], abs=2e-4)
    assert m.end[2] == pytest.approx(Z, abs=1e-9)  # at constant z
    assert m.fired_start == ideal.fired_start
    assert m.distance >= ideal.distance - 2e-4  # the length of the path
    assert m.direction == pytest.approx((0.0, 1.0, 0.0), abs=1e-6)


def test_a_sensor_closing_on_a_steeper_bump_ends_the_slide_there() -> None:
    # 1.2 mm within 6 mm turns the surface by up to 9°: the neighbouring sensor closes while
    # the followed one stays pressed; the world reports it (the servo decides it is a ripple)
    m = _slide(bumped_box(0.0012))
    assert m.event == "touch"
    assert set(m.fired) > set(m.fired_start)
    assert -0.02 < m.end[1] < 0.0
    assert m.end[0] > A / 2 + RHO  # on the bump's flank, riding up it


def test_a_bump_higher_than_the_ride_is_not_ridden_over() -> None:
    # 4 mm high within 6 mm: its flank turns the surface by far more than comply_deg
    m = _slide(bumped_box(0.004))
    assert m.end[1] < 0.0
    assert m.event in ("blocked", "touch", "release")


def test_a_gentle_crease_is_ridden_over_and_a_real_edge_is_not() -> None:
    gentle = _slide(creased_prism(3.0))
    assert gentle.event == "release"
    assert gentle.end[1] == pytest.approx(B / 2, abs=3e-4)  # on to the real end of the side
    assert _straight(creased_prism(3.0)).end[1] == pytest.approx(0.0, abs=1e-3)
    for turn in (20.0, 45.0):  # real edges: the slide ends where the straight one ends
        prism = creased_prism(turn)
        m = _slide(prism)
        assert m == _straight(prism), turn
        assert m.event == "release"
        assert m.end[1] == pytest.approx(0.0, abs=1e-3)


def test_comply_deg_bounds_what_is_ridden_over() -> None:
    prism = creased_prism(3.0)
    with settings.override(world={"comply_deg": 2.0}):
        m = _slide(prism)
    assert m == _straight(prism)


def test_a_slide_not_in_contact_and_a_missing_sensor_are_reported() -> None:
    world = StepperWorld(bumped_box(0.0003), FINGER)
    free = world.slide((A / 2 + 2 * RHO, 0.0, Z), (0.0, 1.0, 0.0), 0.05, 0)
    assert (free.event, free.distance, free.opened) == ("release", 0.0, (0,))
    with pytest.raises(UsageError, match="no sensor 99"):
        world.slide((A / 2 + RHO, 0.0, Z), (0.0, 1.0, 0.0), 0.05, 99)


@pytest.mark.parametrize(
    ("field", "value"),
    [("comply_deg", 90.0), ("comply_deg", -1.0), ("comply_step", 0.0), ("comply_depth", 1.5)],
)
def test_the_compliance_settings_are_checked(field: str, value: float) -> None:
    with pytest.raises(UsageError, match=f"world.{field}"):
        settings.current().replaced(world={field: value})
