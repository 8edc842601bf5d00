"""A contour that ends open does not end the layers: the planes above it are explored.

The solid is an inverted T standing on its bar (a held-out stable pose of
``benchmarks/bench_poses.py``): the bar 90.5 mm long and 30.7 mm high on the table, the stem
30.7 mm wide rising to 88.6 mm, both 37.3 mm deep, so that the stem's sides continue the bar's
long sides. The first plane lies at 35 % of the height, 2 mm above the bar's top: the tip slides
along the bar's top edge and runs into the stem's corner where no sensor faces it, so the
contour ends open. Before, that ended the layers: the stem was never touched and the answer
was a rectangular parallelepiped (the bar). The truth here is the mesh itself: every contact's
tip centre lies one tip radius from its surface, and the stem is where the mesh says."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.pipeline import classify
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import ServoParams
from tactile_kb.touch.stepper import StepperExplorer

RHO = builtin_finger("33").radius
BAR_HEIGHT = 0.0307
HEIGHT = 0.0886


def _inverted_t(turn: float) -> trimesh.Trimesh:
    t = solids.t_shape(0.0905, HEIGHT, BAR_HEIGHT, 0.0373)
    return solids.rotate_about_z(solids.rest_on_face(t, (0.0, 1.0, 0.0)), turn)


@pytest.mark.parametrize("turn", [173.0, 353.0])
def test_the_layers_go_on_above_a_contour_that_ended_open(turn: float) -> None:
    mesh = _inverted_t(turn)
    assert np.allclose(mesh.bounds[:, 2], [0.0, HEIGHT])
    result = classify(mesh, rules="parallelepipeds", seed=1, finger=builtin_finger("33"))
    record = result.record
    assert any("ended open at a blocked slide" in n for n in record.notes), record.notes
    assert any("blocked the slide" in n for n in record.notes), record.notes
    centres = np.asarray([c.centre for c in record.contacts])
    # every tip centre one tip radius outside the solid (trimesh: negative outside)
    depth = trimesh.proximity.signed_distance(mesh, centres)
    assert np.allclose(depth, -RHO, atol=1e-4)
    # contours on the stem: layer contacts higher than the tip reaches from the bar's top
    stem = [c for c in record.contacts if c.phase == "layers" and c.centre[2] > BAR_HEIGHT + RHO]
    assert len(stem) >= 4
    assert result.decision.label == "not_hexahedron"


def test_a_closed_first_contour_keeps_the_paper_s_layers() -> None:
    """A box's contours close: no new approach, the layers as the paper's cycle makes them."""
    result = classify(solids.box(0.06, 0.05, 0.04), rules="parallelepipeds", seed=1)
    assert result.decision.label == "rectangular_parallelepiped"
    assert not any("ended open" in n for n in result.record.notes)


def test_without_reapproach_the_blocked_contour_ends_the_layers() -> None:
    """``ServoParams(reapproach=False)``: the paper's rule, the layers end at the open contour
    and no layer contact lies above the bar."""
    mesh = _inverted_t(353.0)
    explorer = StepperExplorer(ServoParams(reapproach=False, probe=False, top=False))
    record = explorer.explore(mesh, finger="33", seed=1)
    assert any("blocked the slide" in n for n in record.notes)
    assert not any("ended open" in n for n in record.notes)
    assert all(c.centre[2] < BAR_HEIGHT + RHO for c in record.contacts)
    assert len(record.layers) == 1
    assert not record.layers[0].closed
