"""A layer's contour is closed once it has gone round the object, and only then.

The paper closes a layer when its first surface is touched a second time. On a cylinder's or a
sphere's facets the contour rides back onto its first surface without a new touch there (each
loss of contact is found again beyond a dent, a slide contact), and went round until the
layer's motion budget ran out; on a rough side a touch a few millimetres from where the layer
began can be a bump of the first surface, and closed the layer there. The truth here is the tip
centres' polar angle about the solid's vertical axis, which a contour going round the object
once sweeps through 360°.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scanlike import jittered

from tactile_kb import solids
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.servo import ServoParams
from tactile_kb.touch.stepper import StepperExplorer


def layers(mesh: trimesh.Trimesh) -> ExplorationRecord:
    """The contour layers alone (no side probes, no top, no completion)."""
    return StepperExplorer(ServoParams(probe=False, top=False)).explore(mesh, seed=0)


def swept(rec: ExplorationRecord, index: int, axis: np.ndarray) -> float:
    """Degrees the tip centres of layer ``index`` turn about the vertical line through
    ``axis`` (x, y), from the layer's first contact to its last."""
    pts = np.array([c.centre[:2] for c in rec.contacts if c.layer == index]) - axis
    angles = np.unwrap(np.arctan2(pts[:, 1], pts[:, 0]))
    return float(np.degrees(angles[-1] - angles[0]))


@pytest.mark.parametrize(
    "solid",
    [solids.cylinder(0.0845, 0.1731), solids.sphere(0.0777)],
    ids=["cylinder", "sphere"],
)
def test_a_round_solid_closes_every_layer_within_its_budget(solid: trimesh.Trimesh) -> None:
    rec = layers(solid)
    assert not [n for n in rec.notes if "budget" in n], rec.notes
    assert len(rec.layers) >= 2
    axis = solid.bounds.mean(axis=0)[:2]
    for layer in rec.layers:
        assert layer.closed
        # round at least once, and not the four times the motion budget allowed
        assert 330.0 <= swept(rec, layer.index, axis) <= 3 * 360.0 + 30.0


def test_a_touch_on_the_first_surface_still_closes_a_cylinder_layer_once_round() -> None:
    solid = solids.cylinder(0.03, 0.08)  # facets 3 mm wide: the search cycle's touches close
    rec = layers(solid)
    axis = solid.bounds.mean(axis=0)[:2]
    assert len(rec.layers) >= 2
    for layer in rec.layers:
        assert layer.closed
        assert 330.0 <= swept(rec, layer.index, axis) <= 390.0


def test_no_layer_of_a_rough_side_closes_before_it_went_round() -> None:
    # ±1 mm of jitter: a touch on its first side closed layer 0 when it had gone 21° round
    solid = solids.box(0.08, 0.06, 0.05)
    rec = layers(jittered(solid, 0.001, seed=3))
    axis = solid.bounds.mean(axis=0)[:2]
    closed = [layer for layer in rec.layers if layer.closed]
    assert closed
    for layer in closed:
        # three quarters round at least (a layer started mid-side meets that side again)
        assert abs(swept(rec, layer.index, axis)) >= 270.0, (layer.index, rec.notes)
