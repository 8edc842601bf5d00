"""Sensor faults for any world: encoder noise, drop-outs and false fires.

A world (:class:`~tactile_kb.touch.world.World`) answers ideally: the true tip position, the
sensors that really close. :class:`FaultySensors` wraps any world and passes its motions
through imperfect hardware, the same way whichever world is inside, so the analytic stepper
and the MuJoCo simulation get the same faults from the same seed:

* ``false_fire``: the probability, per motion, that a sensor that is OFF fires spuriously
  somewhere before the motion's real end; the finger then stops there, as at a touch.
* ``dropout``: the probability that the signal of a sensor that closes is lost: the finger
  stops without a sensor change (``"blocked"``) when every closing sensor is lost. Reading
  the sensors at rest (:meth:`~tactile_kb.touch.world.World.sense`) is never faulty, which is
  how the controller recovers.
* ``noise``: σ (metres) of the Gaussian noise on the measured tip position of every motion
  (:attr:`~tactile_kb.touch.world.Motion.measured`); the true position is kept for the next
  motion.

The random draws come in that order for every motion, from one generator seeded with
``seed``.

Examples
--------
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.touch.stepper import StepperWorld
>>> ideal = StepperWorld(box(0.04, 0.04, 0.04), builtin_finger("4"))
>>> faulty = FaultySensors(ideal, dropout=1.0, seed=0)
>>> ideal.move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.2).event
'touch'
>>> faulty.move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.2).event  # the signal is lost
'blocked'
"""

from __future__ import annotations

import copy
import math

import numpy as np

from tactile_kb.errors import ExplorationError, UsageError
from tactile_kb.touch.finger import VERTICAL, Finger, Orientation
from tactile_kb.touch.world import Box, Motion, OrientableWorld, Vec3, Workspace, World

__all__ = ["FaultySensors", "check_fault_rates"]


def check_fault_rates(*, noise: float, dropout: float, false_fire: float) -> None:
    """Raise :class:`UsageError` naming the first rate out of range."""
    if not (math.isfinite(noise) and noise >= 0):
        raise UsageError(f"noise must be a finite σ ≥ 0 metres, got {noise}")
    for name, p in (("dropout", dropout), ("false_fire", false_fire)):
        if not 0 <= p <= 1:
            raise UsageError(f"{name} must be a probability in [0, 1], got {p}")


class FaultySensors:
    """A :class:`~tactile_kb.touch.world.World` reading another world through faulty sensors.

    Parameters
    ----------
    world
        The ideal world.
    noise
        σ of the Gaussian noise on each motion's measured end position, metres.
    dropout
        Probability that a closing sensor's signal is lost.
    false_fire
        Probability per motion that a sensor fires spuriously before the motion's end.
    seed
        Seed of the random generator; the same seed and the same motions give the same faults.
    """

    def __init__(
        self,
        world: World,
        *,
        noise: float = 0.0,
        dropout: float = 0.0,
        false_fire: float = 0.0,
        seed: int | None = None,
    ) -> None:
        check_fault_rates(noise=noise, dropout=dropout, false_fire=false_fire)
        self.world = world
        self.noise = float(noise)
        self.dropout = float(dropout)
        self.false_fire = float(false_fire)
        self._rng = np.random.default_rng(seed)

    @property
    def orientation(self) -> Orientation:
        """The head's pose in the wrapped world (vertical when it cannot index)."""
        inner = getattr(self.world, "orientation", VERTICAL)
        return inner if isinstance(inner, Orientation) else VERTICAL

    def oriented(self, orientation: Orientation, at: Vec3 | None = None) -> FaultySensors:
        """The wrapped world with the head indexed to ``orientation`` (see
        :class:`~tactile_kb.touch.world.OrientableWorld`), read through the same faulty sensors
        (one random generator for both)."""
        if not isinstance(self.world, OrientableWorld):
            raise ExplorationError(
                f"the world {type(self.world).__name__} cannot index the finger's head"
            )
        out = copy.copy(self)
        out.world = self.world.oriented(orientation, at)
        return out

    @property
    def finger(self) -> Finger:
        """The finger of the wrapped world."""
        return self.world.finger

    @property
    def workspace(self) -> Workspace:
        """The workspace of the wrapped world."""
        return self.world.workspace

    @property
    def hint(self) -> Box:
        """The object hint of the wrapped world."""
        return self.world.hint

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        """The sensors at rest: read without faults (a reading can be repeated)."""
        return self.world.sense(centre)

    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        """The wrapped world's move, through the faulty sensors."""
        return self._through(self.world.move(start, direction, length))

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        """The wrapped world's slide, through the faulty sensors."""
        return self._through(self.world.slide(start, direction, length, sensor))

    def _through(self, m: Motion) -> Motion:
        rng = self._rng
        end, stop, event = m.end, m.distance, m.event
        fired, closed, opened = m.fired, m.closed, m.opened
        if self.false_fire > 0 and rng.random() < self.false_fire and stop > 0:
            off = [i for i in range(len(self.finger.directions)) if i not in m.fired_start]
            if off:
                k = int(rng.choice(off))
                stop = float(rng.uniform(0.0, stop))
                end = _along(m.start, m.direction, stop)
                fired = tuple(sorted(set(self.world.sense(end)) | {k}))
                event = "touch"
                closed = tuple(sorted(set(fired) - set(m.fired_start)))
                opened = tuple(sorted(set(m.fired_start) - set(fired)))
        if event == "touch" and self.dropout > 0:
            lost = {s for s in closed if rng.random() < self.dropout}
            if lost:
                fired = tuple(s for s in fired if s not in lost)
                closed = tuple(s for s in closed if s not in lost)
                if not closed:
                    event = "blocked"
        measured = end
        if self.noise > 0:
            e = np.asarray(end, dtype=float) + rng.normal(0.0, self.noise, 3)
            measured = (float(e[0]), float(e[1]), float(e[2]))
        return Motion(
            kind=m.kind,
            start=m.start,
            end=end,
            direction=m.direction,
            distance=float(stop),
            event=event,
            fired_start=m.fired_start,
            fired=fired,
            closed=closed,
            opened=opened,
            measured=measured,
        )


def _along(start: Vec3, direction: Vec3, t: float) -> Vec3:
    return (start[0] + t * direction[0], start[1] + t * direction[1], start[2] + t * direction[2])
