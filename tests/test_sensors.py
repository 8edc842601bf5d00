"""FaultySensors: one wrapper adds encoder noise, drop-outs and false fires to any world."""

from __future__ import annotations

import numpy as np
import pytest

from tactile_kb.errors import UsageError
from tactile_kb.solids import box
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.sensors import FaultySensors
from tactile_kb.touch.stepper import StepperExplorer, StepperWorld
from tactile_kb.touch.world import World

START, EAST = (-0.15, 0.0, 0.05), (1.0, 0.0, 0.0)
FACE_X = -0.04 - 0.005  # the cube's face at x = −0.04, minus the tip radius


def _world() -> StepperWorld:
    return StepperWorld(box(0.08, 0.08, 0.08), builtin_finger("4"))


def test_it_is_a_world_and_without_faults_it_changes_nothing() -> None:
    ideal, wrapped = _world(), FaultySensors(_world(), seed=3)
    assert isinstance(wrapped, World)
    assert wrapped.move(START, EAST, 0.3) == ideal.move(START, EAST, 0.3)
    assert wrapped.sense((FACE_X, 0.0, 0.05)) == ideal.sense((FACE_X, 0.0, 0.05))


def test_noise_moves_only_the_measurement_and_is_seeded() -> None:
    a = FaultySensors(_world(), noise=0.001, seed=5).move(START, EAST, 0.3)
    b = FaultySensors(_world(), noise=0.001, seed=5).move(START, EAST, 0.3)
    c = FaultySensors(_world(), noise=0.001, seed=6).move(START, EAST, 0.3)
    assert a == b
    assert a.measured != c.measured
    assert a.end[0] == pytest.approx(FACE_X, abs=1e-6)
    assert a.measured != a.end
    assert np.linalg.norm(np.subtract(a.measured, a.end)) < 0.01


def test_a_dropout_loses_the_touch_and_reading_at_rest_recovers_it() -> None:
    dead = FaultySensors(_world(), dropout=1.0, seed=0)
    m = dead.move(START, EAST, 0.3)
    assert (m.event, m.fired, m.closed) == ("blocked", (), ())
    assert m.end[0] == pytest.approx(FACE_X, abs=1e-6)  # stopped at the face, blind
    assert dead.sense(m.end) == _world().sense(m.end) != ()


def test_a_false_fire_stops_the_finger_before_the_face() -> None:
    ghost = FaultySensors(_world(), false_fire=1.0, seed=0)
    g = ghost.move(START, EAST, 0.3)
    assert g.event == "touch"
    assert g.end[0] < FACE_X - 1e-6
    assert g.distance == pytest.approx(float(np.linalg.norm(np.subtract(g.end, START))))
    assert g.closed  # a sensor that was off reports on


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"noise": -1.0}, "noise"),
        ({"noise": float("inf")}, "noise"),
        ({"dropout": 1.5}, "dropout"),
        ({"false_fire": -0.1}, "false_fire"),
    ],
)
def test_rates_out_of_range_are_refused(kwargs: dict[str, float], message: str) -> None:
    with pytest.raises(UsageError, match=message):
        FaultySensors(_world(), **kwargs)


def test_explorers_pass_their_faults_to_the_wrapper() -> None:
    cube = box(0.06, 0.06, 0.06)
    clean = StepperExplorer().explore(cube, seed=0)
    lossy = StepperExplorer(dropout=0.05).explore(cube, seed=0)
    again = StepperExplorer(dropout=0.05).explore(cube, seed=0)
    assert not any("lost" in n for n in clean.notes)
    assert any("lost" in n for n in lossy.notes)
    assert lossy == again
