"""A contour's motion blocked where no sensor fires, on a rough face, is tried again higher.

The boxes are built here (``tests/scanlike.py``) with ±1 mm of vertex jitter, a poor scan's:
the 5 mm tip sliding along a side meets bumps above its sensors' cones (25° about the equator)
and is blocked blindly. The truth is the box's four side planes x = ±a/2, y = ±b/2.
"""

from __future__ import annotations

import pytest
from scanlike import jittered
from test_servo_persist import A, B, C, sides_touched

from tactile_kb import settings, solids
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.servo import ServoParams
from tactile_kb.touch.stepper import StepperExplorer

BLIND_END = "met the object only where no sensor"


def layers(seed: int, rise: float | None = None) -> ExplorationRecord:
    """The contour layers of the jittered box (no side probes, no top), with ``servo.blind_rise``
    at ``rise`` (None: the default)."""
    mesh = jittered(solids.box(A, B, C), 0.001, seed=seed)
    chosen = {} if rise is None else {"servo": {"blind_rise": rise}}
    with settings.override(**chosen):
        return StepperExplorer(ServoParams(probe=False, top=False)).explore(mesh, seed=0)


@pytest.mark.parametrize("seed", [1, 2, 4])
def test_a_blind_block_on_a_rough_side_is_passed_higher(seed: int) -> None:
    rec = layers(seed)
    assert not any(BLIND_END in n for n in rec.notes)
    # the first layer goes round all four sides: each side's plane lies ρ from tip centres
    assert sides_touched(rec, 0) == {"+x", "-x", "+y", "-y"}
    # no tip centre of a layer lies more than the two tries' rise (1 ρ) above its first
    rho = rec.tip_radius
    for layer in {c.layer for c in rec.contacts if c.layer is not None}:
        zs = [c.centre[2] for c in rec.contacts if c.layer == layer]
        assert max(zs) - zs[0] <= rho + 1e-9


@pytest.mark.parametrize("seed", [1, 2, 4])
def test_without_the_rise_the_blind_block_ends_the_contour(seed: int) -> None:
    rec = layers(seed, rise=0.0)
    assert any(BLIND_END in n for n in rec.notes)
    assert sides_touched(rec, 0) != {"+x", "-x", "+y", "-y"}


def test_the_rise_is_bounded_by_the_setting() -> None:
    with pytest.raises(ValueError, match="blind_rise"):
        settings.Settings.model_validate({"servo": {"blind_rise": 1.5}})
