"""A few touches of a face turned between two sensors (issue 10, scan-like objects).

A face whose normal lies about halfway between two neighbouring sensors fires either; a bump
decides which. The contour layers leave most of its touches with one sensor, and a few at
its end, in two short rows, with the other: their centres span a plane of their own, which
tilts by degrees under 0.5 mm of noise. Ground truth is the geometry built here: the face's
plane, the sensors of the 33-sensor finger, and a fold whose far side the same sensor faces.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_kb.geometry.planes import merge_planes
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import builtin_finger

F33 = builtin_finger("33")
RHO = F33.radius
SENSORS = np.asarray(F33.directions, dtype=float)
NOISE = 0.0005
TURN = 14.0  # degrees: the face's normal lies 14° from sensor 24's and 16° from sensor 25's


def _outward(turn_deg: float) -> np.ndarray:
    """The outward normal of a vertical face facing −y, turned ``turn_deg`` towards +x."""
    a = math.radians(turn_deg)
    return np.array([math.sin(a), -math.cos(a), 0.0])


def _along(n: np.ndarray) -> np.ndarray:
    """The horizontal direction along the vertical face of outward normal ``n``."""
    return np.array([-n[1], n[0], 0.0])


def _touches(
    points: list[np.ndarray], normal: np.ndarray, sensor: int, rng: np.random.Generator, start: int
) -> list[Contact]:
    """Touches of the surface points (outward ``normal``) that closed ``sensor``, their tip
    centres ρ out with 0.5 mm of noise."""
    out = []
    d = SENSORS[sensor]
    for k, p in enumerate(points):
        c = p + RHO * normal + rng.normal(0.0, NOISE, 3)
        out.append(
            Contact(
                step=start + k,
                centre=(float(c[0]), float(c[1]), float(c[2])),
                sensors=(sensor,),
                sensor=sensor,
                direction=(float(d[0]), float(d[1]), float(d[2])),
                point=tuple(float(v) for v in c + RHO * d),
                kind="slide",
            )
        )
    return out


def _record(fold_deg: float, seed: int) -> tuple[ExplorationRecord, int]:
    """A vertical face touched in three contour layers by sensor 24, and at its end, past
    those touches, in two short rows at two heights by sensor 25 (a bump there): on the same
    plane (``fold_deg`` 0), or past a vertical fold 2 mm beyond the layers' touches, turned
    ``fold_deg`` further (sensor 25 faces that side too)."""
    rng = np.random.default_rng(seed)
    n = _outward(TURN)
    h = _along(n)
    base = np.array([0.0, -0.05, 0.0])
    z = np.array([0.0, 0.0, 1.0])
    rows = [base + t * h + s * z for s in (0.02, 0.04, 0.06) for t in np.linspace(-0.05, 0.04, 14)]
    contacts = _touches(rows, n, 24, rng, 0)
    edge = base + 0.042 * h
    n2 = _outward(TURN + fold_deg)
    h2 = _along(n2)
    few = [edge + t * h2 + 0.02 * z for t in (0.006, 0.010, 0.014)]
    few += [edge + t * h2 + 0.06 * z for t in (0.008, 0.011)]
    contacts += _touches(few, n2, 25, rng, len(contacts))
    record = ExplorationRecord(
        finger="33",
        tip_radius=RHO,
        sensor_directions=[tuple(d) for d in F33.directions],
        noise=NOISE,
        contacts=contacts,
    )
    return record, len(rows)


@pytest.mark.parametrize("seed", range(6))
def test_a_few_touches_of_the_neighbouring_sensor_stay_on_their_face(seed: int) -> None:
    record, _ = _record(0.0, seed)
    faces = [f for f in merge_planes(record) if f.source == "contacts"]
    assert len(faces) == 1
    assert faces[0].n_contacts == len(record.contacts)
    angle = math.degrees(math.acos(min(1.0, float(faces[0].normal_array @ _outward(TURN)))))
    assert angle < 1.5


@pytest.mark.parametrize("seed", [0, 1])
def test_a_few_touches_past_a_fold_are_another_face(seed: int) -> None:
    # the same sensor faces the far side of a 30° fold that begins 2 mm past the rows: its
    # centres lie 3–7 mm inside the face's plane
    record, rows = _record(30.0, seed)
    faces = [f for f in merge_planes(record) if f.source == "contacts"]
    assert len(faces) == 2
    assert sorted(f.n_contacts for f in faces) == [len(record.contacts) - rows, rows]
