"""A top touched along two lines across it (issue 10, scan-like objects).

The top of a box is touched from above along one line, then, by the completion, along a
second line near its far side. The two clusters of tip centres lie at the face's two ends
along the direction in which their sensors differ; the bend a quadratic fits through them
rests on each cluster's few millimetres (a bump's flank there bends as much) extrapolated
over the gap. Ground truth is the geometry built here: the top is a plane, its centres raised
by a millimetre-high bump's flank under one cluster.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_features import _top_face, _turned_direction

from tactile_kb import solids
from tactile_kb.features.builtin import get_feature, spread_bend
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

FINGER = builtin_finger("33")
RHO = FINGER.radius
HEIGHT = 0.07


def _two_lines(bump: float, seed: int) -> ExplorationRecord:
    """A 12 × 12 × 7 cm box whose top's touches lie on two lines across it, 8 cm apart along
    x (at x = −4 cm, running along y over 4 cm, and at x = +4 cm over 2 cm), the first on the
    flank of a bump of height ``bump`` that rises towards +x; the second line's first touch
    closed a sensor tilted 18° along x (a bump under it). 0.1 mm of noise, declared."""
    rng = np.random.default_rng(seed)
    rec = sample_record(solids.box(0.12, 0.12, HEIGHT), FINGER, per_face=13, quantise=True)
    model, fi = _top_face(rec)
    top = model.faces[model.face_of[fi]]
    a = [(-0.04 - 0.001 * k, -0.02 + 0.005 * k) for k in range(8)]
    b = [(0.04 + 0.0005 * k, 0.01 + 0.005 * k) for k in range(5)]
    contacts = list(rec.contacts)
    for n, (i, (x, y)) in enumerate(zip(top.contacts, a + b, strict=True)):
        lift = bump * (x + 0.047) / 0.007 if n < len(a) else 0.0
        c = np.array([x, y, HEIGHT + RHO + lift]) + rng.normal(0.0, 0.0001, 3)
        d = np.array([0.0, 0.0, -1.0])
        if n == len(a):
            d = _turned_direction(d, 18.0)
        contacts[i] = contacts[i].model_copy(
            update={
                "centre": tuple(float(v) for v in c),
                "direction": tuple(float(v) for v in d),
                "point": tuple(float(v) for v in c + RHO * d),
            }
        )
    return rec.model_copy(update={"contacts": contacts, "noise": 0.0001})


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_lines_across_a_top_measure_no_bend(seed: int) -> None:
    rec = _two_lines(0.001, seed)
    model, fi = _top_face(rec)
    found = spread_bend(model, fi)
    assert found is not None
    assert math.isinf(found[1])  # the centres cannot tell: weak evidence at most
    assert not get_feature("surface_curved").fn(model)
