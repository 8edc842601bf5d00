"""The way out from under an overhang that closes the way up and the way out sideways.

The object is a hat built here from boxes: a stem, a brim over it and a lip hanging from the
brim's rim. A finger that went in under the brim (below the lip, then up beside the stem)
can leave neither upwards (the brim) nor sideways (the lip); the one way out is the way it
came, and the controller finds it from the tip's own trail.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import trimesh

from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import Controller, ServoParams, _Follow
from tactile_kb.touch.stepper import StepperWorld

RHO = 0.005  # the 33-sensor finger's tip radius
BRIM_LOW = 0.040  # the brim's underside
LIP_LOW = 0.025  # the lip's lower end
LIP_IN = 0.045  # the lip's inner face: |x| or |y| = 45 mm


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> trimesh.Trimesh:
    lo_, hi_ = np.asarray(lo), np.asarray(hi)
    b = trimesh.creation.box(hi_ - lo_)
    b.apply_translation((lo_ + hi_) / 2.0)
    return b


def hat() -> trimesh.Trimesh:
    parts = [
        _box((-0.010, -0.010, 0.0), (0.010, 0.010, BRIM_LOW)),  # the stem
        _box((-0.050, -0.050, BRIM_LOW), (0.050, 0.050, 0.050)),  # the brim
        _box((-0.050, -0.050, LIP_LOW), (-LIP_IN, 0.050, BRIM_LOW)),  # the lip, all round
        _box((LIP_IN, -0.050, LIP_LOW), (0.050, 0.050, BRIM_LOW)),
        _box((-0.050, -0.050, LIP_LOW), (0.050, -LIP_IN, BRIM_LOW)),
        _box((-0.050, LIP_IN, LIP_LOW), (0.050, 0.050, BRIM_LOW)),
    ]
    return trimesh.util.concatenate(parts)


def under_the_brim() -> Controller:
    """A controller whose finger went in below the lip and up beside the stem."""
    c = Controller(StepperWorld(hat(), builtin_finger("33")), ServoParams())
    way_in = [(-0.09, 0.0, 0.015), (-0.025, 0.0, 0.015), (-0.025, 0.0, 0.030)]
    for a, b in itertools.pairwise(way_in):
        d = np.subtract(b, a)
        m = c._move(a, d / np.linalg.norm(d), float(np.linalg.norm(d)))
        assert m.event == "none"
    return c


def test_the_way_out_is_the_way_in() -> None:
    c = under_the_brim()
    goal = np.array([0.09, 0.0, 0.080])
    assert c._go_round(goal, "a test")
    assert c._last_pos == pytest.approx(tuple(goal))
    trail = np.asarray(c._trail)
    # it went back down below the lip and out beyond it before rising
    low_out = (trail[:, 2] < LIP_LOW - RHO) & (trail[:, 0] < -(0.050 + RHO))
    assert low_out[3:].any()
    # and no point of its way lies inside the hat's parts (a tip radius from every surface)
    world = c.world
    assert all(world.distance(tuple(p)) >= RHO - 1e-6 for p in trail)


def test_without_a_way_in_the_probe_is_given_up_and_said() -> None:
    c = under_the_brim()
    while len(c._trail) > 1:  # as if the finger had been put there: no way back is known
        c._trail.popleft()
    assert not c._go_round(np.array([0.09, 0.0, 0.080]), "a test")
    assert any("the way to a probe (a test) is blocked" in n for n in c.notes)


def test_no_free_way_up_from_any_point_moves_nothing() -> None:
    c = under_the_brim()
    motions = c.motions
    assert c._retrace_up(0.080) is not None  # the way in is known: out and up
    c = under_the_brim()
    while len(c._trail) > 2:  # the last leg only: from beside the stem up, under the brim
        c._trail.popleft()
    assert c._retrace_up(0.080) is None
    assert c.motions == motions


def test_pinched_between_a_ceiling_and_a_floor_the_way_out_is_sideways() -> None:
    # a C-shaped block: a floor and a ceiling joined at the back, the slot between them 0.5 mm
    # higher than the tip's diameter. The finger touched the ceiling from below; leaving it
    # straight down meets the floor at once, and the turn towards +z that follows a blocked
    # step is then no direction at all: the finger leaves sideways, out of the slot's mouth
    floor_top, ceiling_low = 0.020, 0.020 + 2 * RHO + 0.0005
    c_block = trimesh.util.concatenate(
        [
            _box((-0.05, -0.05, 0.0), (0.05, 0.05, floor_top)),
            _box((-0.05, -0.05, ceiling_low), (0.05, 0.05, 0.04)),
            _box((0.03, -0.05, floor_top), (0.05, 0.05, ceiling_low)),
        ]
    )
    c = Controller(StepperWorld(c_block, builtin_finger("33")), ServoParams())
    start = np.array([-0.09, 0.0, floor_top + RHO + 0.0002])
    m = c._move(start, np.array([1.0, 0.0, 0.0]), 0.07)  # into the slot
    assert m.event == "none"
    # the ceiling 0.3 mm over the tip, touched by a sensor facing up (a head indexed upwards)
    c._record(m, _Follow(0, (0,), np.array([0.0, 0.0, 1.0])), "touch")
    goal = np.array([0.09, 0.0, 0.080])
    assert c._go_round(goal, "a test")
    assert c._last_pos == pytest.approx(tuple(goal))
    trail = np.asarray(c._trail)
    assert trail[:, 0].min() < -0.05 - RHO + 1e-6  # out of the slot's mouth, at x < -50 mm
    assert all(c.world.distance(tuple(p)) >= RHO - 1e-6 for p in trail)
