"""A contour's motion blocked where no sensor fires, on a rough face, is tried again higher.

The boxes are built here (``tests/scanlike.py``) with ±1 mm of vertex jitter, a poor scan's:
the 5 mm tip sliding along a side meets bumps above its sensors' cones (25° about the equator)
and is blocked blindly. The truth is the box's four side planes x = ±a/2, y = ±b/2. A box
with an overhanging block on one side (built here too) blocks the re-acquisition of a blocked
slide blindly (``servo.persist_tries`` on); the block's outer face is the truth there.
"""

from __future__ import annotations

import pytest
import trimesh
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


def overhung_box(h: float = 0.004, gap: float = 0.0027) -> trimesh.Trimesh:
    """The A × B × C box with a block 1 cm wide standing ``h`` out of its -y side, centred at
    x = 0, from ``gap`` above the first layer's height (19.3 mm, where the first contact of
    these explorations is made) to the top: the contour sliding along -y meets the block's
    lower edge with the upper half of the tip, where no sensor faces."""
    box = trimesh.creation.box((A, B, C))
    box.apply_translation((0.0, 0.0, C / 2))
    bottom = 0.0193 + gap
    block = trimesh.creation.box((0.01, 2.0 * h, C - bottom))
    block.apply_translation((0.0, -B / 2, bottom + (C - bottom) / 2))
    return trimesh.boolean.union([box, block], engine="manifold")


def first_layer_on_block(rec: ExplorationRecord, h: float = 0.004) -> list[tuple[float, ...]]:
    """The first layer's tip centres ρ (within 1 mm) from the block's outer face y = -B/2 - h,
    beside it (|x| < 5 mm)."""
    rho = rec.tip_radius
    return [
        c.centre
        for c in rec.contacts
        if c.layer == 0 and abs(c.centre[1] + B / 2 + h + rho) < 0.001 and abs(c.centre[0]) < 0.005
    ]


def test_a_re_acquisition_blocked_blind_is_passed_higher() -> None:
    # persistence on: the slide along -y is blocked by the overhang without a sensor change,
    # the ride and the re-acquisition's step along the side are blocked blind too, and the
    # step is tried again higher (Controller._over_blind): it touches the block and the
    # contour goes on round it and the box
    mesh = overhung_box()
    with settings.override(servo={"persist_tries": 3}):
        rec = StepperExplorer(ServoParams(probe=False, top=False)).explore(mesh, seed=0)
    assert rec.layers[0].closed, rec.notes
    assert any(n.endswith("followed by re-acquiring the surface") for n in rec.notes)
    assert first_layer_on_block(rec)
    assert sides_touched(rec, 0) == {"+x", "-x", "+y", "-y"}
    # without the rise the re-acquisition meets a wall: the contour ends at the overhang
    with settings.override(servo={"persist_tries": 3, "blind_rise": 0.0}):
        flat = StepperExplorer(ServoParams(probe=False, top=False)).explore(mesh, seed=0)
    assert not flat.layers[0].closed
    assert any("blocked the slide without a sensor change" in n for n in flat.notes)
    assert not first_layer_on_block(flat)
