"""Which sensor changes during a slide are ripples of the surface followed.

A sensor closing while the followed one stays ON is a ripple when it lies within
``servo.ripple_deg`` of the sensor followed. Three looser rules were measured and left out
(docs/benchmarks.md, thirty-ninth round): a neighbour of the normal the followed group reads
took the contact turning round a sloped side's edge for a ripple, and the contour then ended at
a blocked slide (``tests/test_rough_top.py``'s frustum). The cases here pin the rule on the
33-sensor layout; the angles are computed from the layout's own directions.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
from test_servo import ScriptedWorld

from tactile_kb.settings import current
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import Controller, ServoParams, _Follow
from tactile_kb.touch.world import Motion

FINGER = builtin_finger("33")
DIRS = FINGER.matrix


def _deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(
        math.acos(float(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b), -1, 1)))
    )


def _sensor(azimuth_deg: float, elevation_deg: float) -> int:
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    want = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    k = int(np.argmax(DIRS @ want))
    assert _deg(DIRS[k], want) < 1e-6
    return k


def _case() -> tuple[tuple[int, int], int, int, int, int]:
    """The pair, its sensor followed, its other sensor, the sensor 30° under that other one
    and an equator sensor turned 45° from the pair's direction (a corner)."""
    a60, a90 = _sensor(60.0, 0.0), _sensor(90.0, 0.0)  # a face whose normal points 75° round
    pair = (a60, a90)
    followed = Controller(ScriptedWorld(deque(), finger=FINGER), ServoParams())._follow(pair).sensor
    other = a90 if followed == a60 else a60
    below = _sensor(60.0 if other == a60 else 90.0, -30.0)
    turned = _sensor(120.0 if other == a90 else 30.0, 0.0)
    return pair, followed, other, below, turned


PAIR, FOLLOWED, OTHER, BELOW, TURNED = _case()


def _slide_closing(group: tuple[int, ...], closing: int) -> tuple[Controller, Motion, _Follow]:
    c = Controller(ScriptedWorld(deque(), finger=FINGER), ServoParams())
    f = c._follow(group)
    fired = tuple(sorted({*group, closing}))
    m = Motion(
        kind="slide",
        start=(0.0, 0.0, 0.03),
        end=(0.0, 0.004, 0.03),
        direction=(0.0, 1.0, 0.0),
        distance=0.004,
        event="touch",
        fired_start=tuple(sorted(group)),
        fired=fired,
        closed=(closing,),
        opened=(),
        measured=(0.0, 0.004, 0.03),
    )
    return c, m, f


def test_the_layout_gives_the_case_its_angles() -> None:
    limit = current().servo.ripple_deg
    mean = DIRS[list(PAIR)].sum(axis=0)
    assert _deg(DIRS[BELOW], DIRS[FOLLOWED]) > limit  # 41.4° from the sensor followed
    assert _deg(DIRS[BELOW], DIRS[OTHER]) < limit  # 30°: the pair's other sensor's neighbour
    assert _deg(DIRS[BELOW], mean) <= limit  # 33.2° from the normal the pair reads
    assert _deg(DIRS[TURNED], mean) > limit  # 45°


def test_a_face_turned_from_the_pair_is_a_new_touch() -> None:
    c, m, f = _slide_closing(PAIR, TURNED)
    assert not c._ripple(m, f)


def test_followed_alone_the_sensor_below_its_neighbour_is_a_new_touch() -> None:
    # one sensor reads the normal as its own direction: 41.4° from BELOW, more than ripple_deg
    c, m, f = _slide_closing((FOLLOWED,), BELOW)
    assert not c._ripple(m, f)


def test_a_neighbour_of_the_sensor_followed_stays_a_ripple() -> None:
    # two sensors of the ring 30° down, at 60° and 90° round, the first followed; the sensor of
    # the ring 60° down at 45° round is 31.6° from it and 35.3° from the pair's normal
    lower = (_sensor(60.0, -30.0), _sensor(90.0, -30.0))
    between = _sensor(45.0, -60.0)
    c, m, f = _slide_closing(lower, between)
    limit = current().servo.ripple_deg
    assert f.sensor == lower[0]
    assert _deg(DIRS[between], DIRS[f.sensor]) <= limit
    assert _deg(DIRS[between], DIRS[list(lower)].sum(axis=0)) > limit
    assert c._ripple(m, f)


def test_a_contact_turning_round_towards_the_next_face_is_a_new_touch() -> None:
    # a sloped side read by a sensor of the ring 30° down and the equator sensor above it, both
    # 150° round, the lower one followed: at the edge to the next side the contact turns round,
    # and the equator sensor at 120° closes. It lies 33.3° from the pair's normal but 30° round
    # from it, further than the pair's own sensors (which do not turn round at all), and 41.4°
    # from the sensor followed: a new touch, as a straight slide meeting a new face is.
    side = (_sensor(150.0, -30.0), _sensor(150.0, 0.0))
    round_ = _sensor(120.0, 0.0)
    c, m, f = _slide_closing(side, round_)
    limit = current().servo.ripple_deg
    assert f.sensor == side[0]
    assert _deg(DIRS[round_], DIRS[f.sensor]) > limit
    assert _deg(DIRS[round_], DIRS[list(side)].sum(axis=0)) <= limit
    assert not c._ripple(m, f)
