"""The servo logic against a scripted world: no geometry, only sensor events."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
import pytest

from tactile_kb.errors import ExplorationError, UsageError
from tactile_kb.touch.finger import Finger, builtin_finger
from tactile_kb.touch.servo import Controller, ServoParams
from tactile_kb.touch.world import Box, Event, Motion, Vec3, Workspace


@dataclass
class Call:
    kind: str
    start: Vec3
    direction: Vec3
    length: float
    sensor: int | None


@dataclass
class ScriptedWorld:
    """A world that answers each motion from a script of (event, distance, fired after)."""

    script: deque[tuple[Event, float, tuple[int, ...]]]
    finger: Finger = field(default_factory=lambda: builtin_finger("4"))
    workspace: Workspace = field(
        default_factory=lambda: Workspace(lo=(-0.5, -0.5, 0.005), hi=(0.5, 0.5, 0.5))
    )
    hint: Box = field(default_factory=lambda: Box(lo=(-0.05, -0.05, 0.0), hi=(0.05, 0.05, 0.1)))
    calls: list[Call] = field(default_factory=list)
    fired_now: tuple[int, ...] = ()

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        return self.fired_now

    def _answer(
        self, kind: str, start: Vec3, direction: Vec3, length: float, sensor: int | None
    ) -> Motion:
        self.calls.append(Call(kind, start, direction, length, sensor))
        if not self.script:
            raise AssertionError(f"unscripted {kind} from {start} along {direction}")
        event, dist, fired = self.script.popleft()
        dist = min(dist, length)
        end = tuple(float(s + dist * d) for s, d in zip(start, direction, strict=True))
        before = self.fired_now
        self.fired_now = fired
        return Motion(
            kind="slide" if kind == "slide" else "move",
            start=start,
            end=end,  # type: ignore[arg-type]
            direction=direction,
            distance=dist,
            event=event,
            fired_start=before,
            fired=fired,
            closed=tuple(sorted(set(fired) - set(before))),
            opened=tuple(sorted(set(before) - set(fired))),
            measured=end,  # type: ignore[arg-type]
        )

    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        return self._answer("move", start, direction, length, None)

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        return self._answer("slide", start, direction, length, sensor)


P = ServoParams(comply=False)  # the paper's rules, motion by motion (riding is tested below)


def _dir(call: Call) -> tuple[float, ...]:
    return tuple(round(v, 9) + 0.0 for v in call.direction)


def run(world: ScriptedWorld, params: ServoParams = P) -> Controller:
    c = Controller(world, params)
    for _ in c.run():
        pass
    return c


def test_l1_l2_l3_cycle_and_the_small_dimension_decision() -> None:
    world = ScriptedWorld(
        deque(
            [
                ("touch", 0.02, (0,)),  # approach along +x: sensor 0 (+x) closes
                ("release", 0.05, ()),  # slide along the face until contact is lost
                ("none", 1.0, ()),  # l1
                ("none", 1.0, ()),  # l2
                ("none", 1.0, ()),  # l3
            ]
        )
    )
    c = run(world)
    kinds = [(k.kind, _dir(k), k.length, k.sensor) for k in world.calls]
    assert kinds[0][:2] == ("move", (1.0, 0.0, 0.0))
    # sensor 0 (+x) touched a face with outward normal -x: the tangent with the object on the
    # left is -y
    assert kinds[1][0] == "slide"
    assert kinds[1][1] == (0.0, -1.0, 0.0)
    assert kinds[1][3] == 0
    assert kinds[2] == ("move", (0.0, -1.0, 0.0), P.l1, None)  # continue l1
    assert kinds[3] == ("move", (1.0, 0.0, 0.0), P.l2, None)  # search l2 towards the object
    assert kinds[4] == ("move", (0.0, 1.0, 0.0), P.l3, None)  # then l3, orthogonal to l2
    assert len(world.calls) == 5  # blocks C, D: no further cycle; the 4-finger has no pole
    assert any("smaller than l2" in n for n in c.notes)
    rec = c.record(complete=True)
    assert [x.kind for x in rec.contacts] == ["touch", "slide"]
    assert rec.layers[0].closed is False


def test_contact_during_the_cycle_stops_it_and_is_followed() -> None:
    world = ScriptedWorld(
        deque(
            [
                ("touch", 0.02, (0,)),
                ("release", 0.05, ()),
                ("none", 1.0, ()),  # l1
                ("touch", 0.004, (3,)),  # during l2 sensor 3 (-y) closes
                ("release", 0.03, ()),  # followed along its own tangent
                ("none", 1.0, ()),
                ("none", 1.0, ()),
                ("none", 1.0, ()),
            ]
        )
    )
    run(world)
    call = world.calls[4]
    assert call.kind == "slide"  # not l3: the cycle stopped
    assert call.sensor == 3
    # sensor 3 points -y: outward normal +y, object on the left: move -x
    assert _dir(call) == (-1.0, 0.0, 0.0)


def test_the_last_sensor_that_closed_is_followed() -> None:
    world = ScriptedWorld(
        deque(
            [
                ("touch", 0.02, (0,)),
                ("touch", 0.03, (0, 1)),  # a concave corner: sensor 1 closes, 0 still ON
                ("release", 0.01, (1,)),  # sensor 0 opens: not the followed one, keep going
                ("release", 0.04, ()),  # now the followed sensor opens: cycle
                ("none", 1.0, ()),
                ("none", 1.0, ()),
                ("none", 1.0, ()),
            ]
        )
    )
    c = run(world)
    assert [k.sensor for k in world.calls[1:4]] == [0, 1, 1]
    assert world.calls[4].kind == "move"
    # sensor 1 points +y: outward normal -y, object on the left: +x
    assert _dir(world.calls[2]) == (1.0, 0.0, 0.0)
    kinds = [(x.kind, x.sensor) for x in c.contacts]
    assert kinds[:4] == [("touch", 0), ("slide", 0), ("touch", 1), ("slide", 1)]


def _follow0(c: Controller) -> object:
    return c._follow((0,))


def test_z_increment_keeps_contact_and_explores_the_next_plane() -> None:
    world = ScriptedWorld(deque([("none", 1.0, (0,))]), fired_now=(0,))
    c = Controller(world, P)
    pos = np.array([-0.055, 0.0, 0.03])
    nxt = c._z_increment(pos, c._follow((0,)))
    assert nxt is not None
    assert world.calls[0].direction == (0.0, 0.0, 1.0)
    assert world.calls[0].length == pytest.approx(c.z_step)
    assert nxt[0][2] == pytest.approx(0.03 + c.z_step)
    assert c.contacts[-1].kind == "slide"  # contact kept: no new touch


def test_z_increments_end_when_contact_is_not_kept() -> None:
    world = ScriptedWorld(
        deque([("release", 0.0, ()), ("none", 1.0, ()), ("none", 1.0, ())]), fired_now=(0,)
    )
    c = Controller(world, P)
    assert c._z_increment(np.array([-0.055, 0.0, 0.03]), c._follow((0,))) is None
    assert [k.kind for k in world.calls] == ["move", "move", "move"]
    assert _dir(world.calls[2]) == (1.0, 0.0, 0.0)  # the search goes towards the object
    assert any("contact not kept" in n for n in c.notes)


def test_z_increment_regains_a_face_sloping_inwards() -> None:
    world = ScriptedWorld(
        deque([("release", 0.0, ()), ("none", 1.0, ()), ("touch", 0.004, (0,))]), fired_now=(0,)
    )
    c = Controller(world, P)
    nxt = c._z_increment(np.array([-0.055, 0.0, 0.03]), c._follow((0,)))
    assert nxt is not None
    assert c.contacts[-1].kind == "touch"


def test_overlapping_cones_give_the_mean_direction() -> None:
    world = ScriptedWorld(deque(), finger=builtin_finger("33"))
    c = Controller(world, P)
    f = c._follow((21, 22))  # two equator sensors 30 degrees apart
    assert np.allclose(f.r0, [np.cos(np.radians(15)), np.sin(np.radians(15)), 0.0])


def test_never_touching_is_an_exploration_error() -> None:
    world = ScriptedWorld(deque([("none", 1.0, ())] * 50))
    c = Controller(world, P)
    with pytest.raises(ExplorationError, match="never touched"):
        list(c.run())


def test_motion_budget_ends_the_exploration_with_a_note() -> None:
    # a world that keeps closing and opening the same sensor forever
    steps: list[tuple[Event, float, tuple[int, ...]]] = [("touch", 0.02, (0,))]
    steps += [("release", 0.001, ()), ("touch", 0.001, (0,))] * 200
    script = deque(steps)
    world = ScriptedWorld(script)
    c = Controller(world, ServoParams(max_motions=30, comply=False))
    marks = list(c.run())
    assert marks[-1] == "complete"
    assert c.motions == 30
    assert any("budget" in n for n in c.notes)


@pytest.mark.parametrize(
    "kwargs",
    [{"l1": 0.0}, {"l2": -1.0}, {"z_step": 0.0}, {"max_motions": 0}, {"l3": float("nan")}],
)
def test_bad_parameters(kwargs: dict[str, float]) -> None:
    with pytest.raises(UsageError):
        ServoParams(**kwargs)  # type: ignore[arg-type]


def test_a_touch_that_rolls_off_at_once_is_an_edge_and_is_dropped() -> None:
    world = ScriptedWorld(
        deque(
            [
                ("touch", 0.02, (0,)),  # the approach meets a vertical edge
                ("release", 0.001, ()),  # its slide rolls off within edge_slide: an edge
                ("none", 1.0, ()),  # l1
                ("touch", 0.004, (3,)),  # l2 meets a face
                ("release", 0.03, ()),  # which slides like a surface
                ("none", 1.0, ()),
                ("none", 1.0, ()),
                ("none", 1.0, ()),
            ]
        )
    )
    c = run(world)
    assert [(x.kind, x.sensor) for x in c.contacts] == [("touch", 3), ("slide", 3)]
    assert c.record(complete=True).touches == 1


def test_edge_touches_in_a_row_are_a_curved_surface_and_are_kept() -> None:
    steps: list[tuple[Event, float, tuple[int, ...]]] = [("touch", 0.02, (0,))]
    for sensor in (3, 2):
        steps += [("release", 0.001, ()), ("none", 1.0, ()), ("touch", 0.004, (sensor,))]
    steps += [("release", 0.001, ()), ("none", 1.0, ()), ("none", 1.0, ()), ("none", 1.0, ())]
    c = run(ScriptedWorld(deque(steps)))
    assert [(x.kind, x.sensor) for x in c.contacts] == [("touch", 0), ("touch", 3), ("touch", 2)]


def test_z_increment_steps_round_an_overhanging_face() -> None:
    world = ScriptedWorld(
        deque(
            [
                ("blocked", 0.0, (0,)),  # going up: the face overhangs
                ("none", 1.0, ()),  # step away from it
                ("none", 1.0, ()),  # up
                ("touch", 0.01, (0,)),  # back towards the middle of the layer: touched
            ]
        ),
        fired_now=(0,),
    )
    c = Controller(world, P)
    pos = np.array([-0.055, 0.0, 0.03])
    nxt = c._z_increment(pos, c._follow((0,)), np.array([0.0, 0.0, 0.03]))
    assert nxt is not None
    dirs = [_dir(k) for k in world.calls]
    assert dirs[0] == (0.0, 0.0, 1.0)
    assert dirs[1] == (-1.0, 0.0, 0.0)  # away from the face (sensor 0 points +x)
    assert world.calls[1].length > 0.6 * c.z_step  # clears an overhang of 31°
    assert dirs[2] == (0.0, 0.0, 1.0)
    assert world.calls[2].length == pytest.approx(c.z_step)
    assert dirs[3] == (1.0, 0.0, 0.0)  # towards the middle
    assert nxt[0][2] == pytest.approx(0.03 + c.z_step)
    assert c.contacts[-1].kind == "touch"


def test_new_parameters_are_checked() -> None:
    for kwargs in (
        {"spacing": 0.0},
        {"edge_slide": -1.0},
        {"top_spread": 1.0},
        {"top_outer": 0.4},  # inside the first diamond
        {"top_outer": 1.0},
    ):
        with pytest.raises(UsageError):
            ServoParams(**kwargs)  # type: ignore[arg-type]


@dataclass
class DroppingWorld(ScriptedWorld):
    """A scripted world whose motion number ``drop`` loses its closing signal (a drop-out):
    the motion reports ``"blocked"`` with no sensor closed, while the sensors read at rest
    tell the truth."""

    drop: int = -1

    def _answer(
        self, kind: str, start: Vec3, direction: Vec3, length: float, sensor: int | None
    ) -> Motion:
        m = super()._answer(kind, start, direction, length, sensor)
        if len(self.calls) - 1 != self.drop:
            return m
        return Motion(
            kind=m.kind,
            start=m.start,
            end=m.end,
            direction=m.direction,
            distance=m.distance,
            event="blocked",
            fired_start=m.fired_start,
            fired=m.fired_start,
            closed=(),
            opened=(),
            measured=m.measured,
        )


def test_a_lost_closing_signal_is_recovered_by_reading_the_sensors_at_rest() -> None:
    script: list[tuple[Event, float, tuple[int, ...]]] = [
        ("touch", 0.02, (0,)),
        ("release", 0.05, ()),
        ("none", 1.0, ()),  # l1
        ("touch", 0.004, (3,)),  # during l2 sensor 3 (-y) closes, but its signal is lost
        ("release", 0.03, ()),
        ("none", 1.0, ()),
        ("none", 1.0, ()),
        ("none", 1.0, ()),
    ]
    world = DroppingWorld(deque(script), drop=3)
    c = run(world)
    call = world.calls[4]
    assert call.kind == "slide"  # the cycle stopped at the contact and follows sensor 3
    assert call.sensor == 3
    assert _dir(call) == (-1.0, 0.0, 0.0)
    rec = c.record(complete=True)
    touch = [x for x in rec.contacts if x.kind == "touch"][1]
    assert touch.sensor == 3
    assert touch.sensors == (3,)
    assert "1 lost sensor signal(s) recovered by reading the sensors at rest" in rec.notes
    # without the drop-out the same motions are made and nothing is noted
    plain = ScriptedWorld(deque(script))
    c2 = run(plain)
    assert [(k.kind, k.sensor) for k in plain.calls] == [(k.kind, k.sensor) for k in world.calls]
    assert not any("lost sensor" in n for n in c2.record(complete=True).notes)


def test_a_cycle_that_only_meets_the_object_blindly_infers_no_size() -> None:
    # The 4-sensor finger's sensors point along ±x, ±y with 46° cones; a square pyramid's faces
    # face the diagonals, 29° up: 52° from every sensor, so the finger meets them blindly.
    from tactile_kb.solids import pyramid
    from tactile_kb.touch.explorers import get_explorer

    record = get_explorer("stepper").explore(pyramid(4, 0.04, 0.05), finger="4")
    assert record.touches == 0
    assert any("met the object only where no sensor of finger '4' fires" in n for n in record.notes)
    assert not any("smaller than l2" in n for n in record.notes)
