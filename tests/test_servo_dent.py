"""Whether a search cycle met the face it left again, beyond a dent (``Controller._dent``).

The contact a search cycle finds is the face followed when its tip centre lies within two
``bump`` of the line the tip centres followed on that face. That line was the chord of the last
slide alone; on a rough scan a slide of a few millimetres turns with the bumps, and sixteen
millimetres on its line is millimetres off the face. The line of the whole run of the surface
(its contacts since the touch that began it) judges too, once they span ``RUN_SPAN_RHO`` ρ.
The truth here is the face's line, built by hand: tip centres on y = 0.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import pytest
from test_servo import ScriptedWorld

from tactile_kb.record import Contact
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import RUN_SPAN_RHO, Controller, ServoParams, _Segment

FINGER = builtin_finger("33")
Z = 0.03
CHORD_DEG = 15.0  # the last slide's chord, turned by a bump


def _controller(run: list[float]) -> Controller:
    """A controller whose record holds a touch and slides at x = ``run`` (metres) on y = 0,
    then the contact a search cycle just made (a placeholder: ``_dent`` gets its position)."""
    c = Controller(ScriptedWorld(deque(), finger=FINGER), ServoParams())
    r0 = (0.0, 1.0, 0.0)
    for k, x in enumerate(run):
        c.contacts.append(
            Contact(
                step=k,
                centre=(x, 0.0, Z),
                sensors=(0,),
                direction=r0,
                point=(x, c.rho, Z),
                kind="touch" if k == 0 else "slide",
            )
        )
    c.contacts.append(c.contacts[-1].model_copy(update={"kind": "touch"}))
    return c


def _chord(start_x: float) -> _Segment:
    """The last slide: from (start_x, 0), its chord turned by CHORD_DEG towards +y."""
    a = math.radians(CHORD_DEG)
    return _Segment(
        group=frozenset({0}),
        start=np.array([start_x, 0.0, Z]),
        direction=np.array([math.cos(a), math.sin(a), 0.0]),
        length=0.004,
        r0=np.array([0.0, 1.0, 0.0]),
    )


def _offset_from_chord(seg: _Segment, p: np.ndarray) -> float:
    d = p[:2] - seg.start[:2]
    u = seg.direction[:2]
    return abs(float(d[0] * u[1] - d[1] * u[0]))


def _dent(c: Controller, seg: _Segment, y: float) -> bool:
    f = c._follow((0,))  # the same sensor before and after: the angle test passes
    pos = np.array([0.036, y, Z])
    return c._dent(seg, f, f, pos)


RUN = [0.0, 0.004, 0.008, 0.012, 0.016]  # 16 mm of tip centres on the face


@pytest.mark.parametrize("y", [0.0, 0.001, -0.002])
def test_the_run_line_finds_the_face_again_beyond_a_turned_chord(y: float) -> None:
    c = _controller(RUN)
    seg = _chord(RUN[-1])
    pos = np.array([0.036, y, Z])
    assert _offset_from_chord(seg, pos) > 2.0 * c.bump  # the chord's line alone misses it
    assert abs(y) <= 2.0 * c.bump  # the face's line does not
    assert _dent(c, seg, y)


@pytest.mark.parametrize("y", [0.004, -0.004])
def test_a_contact_off_both_lines_is_a_new_surface(y: float) -> None:
    c = _controller(RUN)
    seg = _chord(RUN[-1])
    assert abs(y) > 2.0 * c.bump
    if _offset_from_chord(seg, np.array([0.036, y, Z])) > 2.0 * c.bump:
        assert not _dent(c, seg, y)
    else:  # on the chord's line: the chord's rule holds as before
        assert _dent(c, seg, y)


def test_a_short_run_leaves_the_chord_to_judge() -> None:
    c = _controller([0.0, 0.002, 0.004])
    assert RUN_SPAN_RHO * c.rho > 0.004  # the run spans less than RUN_SPAN_RHO ρ
    seg = _chord(0.004)
    assert c._run_line() is None
    assert not _dent(c, seg, 0.0)


def test_the_run_begins_at_the_surfaces_touch() -> None:
    # an earlier surface's contacts, far off this face's line, before its touch: left out
    c = _controller(RUN)
    old = Contact(
        step=-1,
        centre=(-0.05, 0.03, Z),
        sensors=(0,),
        direction=(1.0, 0.0, 0.0),
        point=(-0.045, 0.03, Z),
        kind="touch",
    )
    c.contacts.insert(0, old)
    line = c._run_line()
    assert line is not None
    mean, along = line
    assert abs(float(mean[1])) < 1e-12
    assert abs(abs(float(along[0])) - 1.0) < 1e-12
