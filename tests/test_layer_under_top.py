"""A layer that grazes a step's top: the finger contours under it (issue 11).

A T block standing on its crossbar has a step: the crossbar's top, ``width`` above the table,
with the stem rising from its middle. When the first layer's tip centre lies less than ρ over
that top, the tip's lowest point dips into it by a fraction of a millimetre, and the sensors
that close point almost straight down. Following them traces the top's edges at the layer's
height, not the crossbar's sides, and the model stays open along the crossbar. The finger
lowers that layer to ρ/2 under the top, where its equator meets the crossbar's sides
(``Controller._top_met``, ``Controller._lower_under_top``).

The truth is the construction: the crossbar's height, the layer's height above it, and the
class (a T block is not a hexahedron).
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.errors import GeometryError
from tactile_kb.features.builtin import face_count
from tactile_kb.geometry.model import build_model
from tactile_kb.pipeline import classify
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import Controller, ServoParams
from tactile_kb.touch.stepper import StepperExplorer

RHO = builtin_finger("33").radius
BAR = 0.0344  # the crossbar's width: its top's height above the table, standing on it
GRAZE = 0.0001  # how far the first layer's tip dips into the crossbar's top
LAYERS = ServoParams(z_first=BAR + RHO - GRAZE)


def _standing_t(turn: float) -> trimesh.Trimesh:
    t = solids.t_shape(0.1163, 0.1073, BAR, 0.041)  # the crossbar along x, from y = 0 to BAR
    return solids.rotate_about_z(solids.rest_on_face(t, (0.0, 1.0, 0.0)), turn)


def test_the_construction_grazes_the_top() -> None:
    t = _standing_t(0.0)
    assert t.extents[2] == pytest.approx(0.1073)  # the stem rises from the crossbar
    lowest = t.vertices[:, 2] < BAR + 1e-9
    # the crossbar is a box 0.1163 × BAR × 0.041 on the table
    assert sorted(np.ptp(t.vertices[lowest], axis=0).round(4).tolist()) == [0.0344, 0.041, 0.1163]
    assert LAYERS.z_first is not None
    assert LAYERS.z_first - RHO == pytest.approx(BAR - GRAZE)  # the tip dips 0.1 mm into it


@pytest.mark.parametrize("turn", [0.0, 107.6, 227.1])
def test_the_layer_is_lowered_under_the_top(turn: float) -> None:
    t = _standing_t(turn)
    result = classify(t, explorer=StepperExplorer(LAYERS))
    assert result.decision.label == "not_hexahedron"
    # the crossbar's sides were touched by the equator, under its top
    sides = [
        c
        for c in result.record.contacts
        if abs(c.direction[2]) < 0.05 and c.centre[2] < BAR - RHO / 4
    ]
    assert len(sides) >= 4
    assert any("just under the tip" in n for n in result.record.notes)


def test_without_lowering_the_crossbar_stays_open(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(Controller, "_top_met", lambda self, *args: False)
    t = _standing_t(227.1)
    result = classify(t, explorer=StepperExplorer(LAYERS))
    # the crossbar's sides were never touched: the touched planes do not close, and the
    # classification closes them only by assumed faces where the touches reached
    assert build_model(result.record).polyhedron is None
    assert result.model.assumed_reach
    assert result.record.ending != "closed"
    with pytest.raises(GeometryError, match="needs a closed model"):
        face_count(build_model(result.record))
