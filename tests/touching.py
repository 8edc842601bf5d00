"""Touches built by hand for the geometry tests: contacts of the 33-sensor finger, each read
by the sensor nearest the surface's inward direction, and the record that holds them."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import builtin_finger

FINGER = builtin_finger("33")
RHO = FINGER.radius


def contact(step: int, centre: np.ndarray, normal: np.ndarray) -> Contact:
    """A touch with its tip centre at ``centre``, read by the sensor nearest ``−normal`` (the
    one that closes on a surface of outward ``normal``)."""
    k = int(np.argmax(FINGER.matrix @ -np.asarray(normal, dtype=float)))
    d = tuple(float(x) for x in FINGER.matrix[k])
    return Contact(
        step=step,
        centre=(float(centre[0]), float(centre[1]), float(centre[2])),
        sensors=(k,),
        sensor=k,
        direction=d,
        point=tuple(float(c + RHO * x) for c, x in zip(centre, d, strict=True)),
    )


def touched_record(
    name: str, contacts: Sequence[Contact], *, noise: float = 0.0
) -> ExplorationRecord:
    """The record of ``contacts`` touched with the 33-sensor finger, declaring ``noise``."""
    return ExplorationRecord(
        object=name,
        finger=FINGER.name,
        tip_radius=RHO,
        sensor_directions=[tuple(map(float, s)) for s in FINGER.matrix],
        contacts=list(contacts),
        noise=noise,
    )
