"""Persistent contour following: a slide blocked without a sensor change is re-acquired.

The objects are boxes built here whose faces carry a scan's vertex jitter or smooth bumps
(``tests/scanlike.py``), so the truth is known: the four side planes x = ±a/2, y = ±b/2. The
paper's rules alone (and the riding of version 0.2) end the contour at the first blocked slide
on each of them; the persistent servo goes round all four sides in every layer.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest
import trimesh
from scanlike import bumped, jittered

from tactile_kb import settings, solids
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import Finger
from tactile_kb.touch.servo import Controller, ServoParams
from tactile_kb.touch.stepper import StepperExplorer, StepperWorld
from tactile_kb.touch.world import Box, Motion, Vec3, Workspace

A, B, C = 0.08, 0.06, 0.05
RHO = 0.005  # the 33-sensor finger's tip radius
SIDES = {"+x": (0, A / 2), "-x": (0, -A / 2), "+y": (1, B / 2), "-y": (1, -B / 2)}


def rough(kind: str, seed: int) -> trimesh.Trimesh:
    """The A × B × C box with ±0.3 mm of vertex jitter, or with twelve 0.8 mm bumps."""
    box = solids.box(A, B, C)
    if kind == "jitter":
        return jittered(box, 0.0003, seed=seed)
    return bumped(jittered(box, 0.0001, seed=seed), 0.0008, bumps=12, seed=seed)


def sides_touched(rec: ExplorationRecord, layer: int) -> set[str]:
    """The box sides whose planes lie a tip radius (within 2.5 mm) from a tip centre of
    ``layer``'s contacts: which sides the contour went along."""
    hit = set()
    for c in rec.contacts:
        if c.layer != layer:
            continue
        for name, (axis, at) in SIDES.items():
            if abs(abs(c.centre[axis] - at) - RHO) < 0.0025 and abs(c.centre[1 - axis]) < (
                B / 2 if axis == 0 else A / 2
            ):
                hit.add(name)
    return hit


def layers_only() -> StepperExplorer:
    return StepperExplorer(ServoParams(probe=False, top=False))


@pytest.fixture(autouse=True)
def persisting() -> Iterator[None]:
    """Re-acquisition on (``servo.persist_tries``, off by default until the face fitting reads
    rough contours as flat faces), over the world's straight slides (``world.comply_deg`` 0:
    the analytic world's compliant slide rides over these boxes' irregularities by itself,
    see tests/test_stepper_comply.py; here the servo's own persistence is what is tested)."""
    with settings.override(servo={"persist_tries": 3}, world={"comply_deg": 0.0}):
        yield


@pytest.mark.parametrize(("kind", "seed"), [("jitter", 0), ("jitter", 2), ("bumps", 1)])
def test_the_contour_goes_round_every_side_of_a_rough_box(kind: str, seed: int) -> None:
    rec = layers_only().explore(rough(kind, seed), seed=0)
    assert len(rec.layers) >= 2
    assert all(layer.closed for layer in rec.layers), rec.notes
    assert not [n for n in rec.notes if n.startswith("contour stopped")]
    for layer in rec.layers:
        assert sides_touched(rec, layer.index) == set(SIDES), (layer.index, rec.notes)
    # the irregularities are slid over, not touched: at most two touches a side and layer
    touches = sum(1 for c in rec.contacts if c.kind == "touch" and c.phase == "layers")
    assert touches <= 2 * len(SIDES) * len(rec.layers) + 1


def test_a_blocked_slide_is_re_acquired_and_noted() -> None:
    mesh = rough("bumps", 0)
    rec = layers_only().explore(mesh, seed=0)
    assert any(n.endswith("followed by re-acquiring the surface") for n in rec.notes), rec.notes
    # the paper's rules alone end the same contour there
    paper = StepperExplorer(ServoParams(comply=False, probe=False, top=False)).explore(mesh)
    assert not paper.layers[0].closed
    assert any("blocked the slide without a sensor change" in n for n in paper.notes)


def test_ripples_of_a_scanned_face_are_slides_not_touches() -> None:
    rec = layers_only().explore(rough("jitter", 1), seed=0)
    assert any(n.endswith("followed as the same surface") for n in rec.notes), rec.notes
    kinds = [c.kind for c in rec.contacts if c.phase == "layers"]
    assert kinds.count("slide") > 4 * kinds.count("touch")


@dataclass
class Sticky:
    """A world whose surfaces never let the tip slide: every slide is blocked at once (no
    sensor change), and a move meeting the object is blocked too, after its first touch."""

    inner: StepperWorld
    moves: int = 0

    @property
    def finger(self) -> Finger:
        return self.inner.finger

    @property
    def workspace(self) -> Workspace:
        return self.inner.workspace

    @property
    def hint(self) -> Box:
        return self.inner.hint

    def sense(self, centre: Vec3) -> tuple[int, ...]:
        return self.inner.sense(centre)

    def move(self, start: Vec3, direction: Vec3, length: float) -> Motion:
        m = self.inner.move(start, direction, length)
        self.moves += 1
        return m

    def slide(self, start: Vec3, direction: Vec3, length: float, sensor: int) -> Motion:
        fired = self.inner.sense(start)
        return Motion(
            kind="slide",
            start=start,
            end=start,
            direction=direction,
            distance=0.0,
            event="blocked",
            fired_start=fired,
            fired=fired,
            closed=(),
            opened=(),
            measured=start,
        )


def test_re_acquiring_is_bounded_where_no_slide_ever_goes_on() -> None:
    from tactile_kb.touch.finger import builtin_finger

    world = Sticky(StepperWorld(solids.box(A, B, C), builtin_finger("33")))
    params = ServoParams(probe=False, top=False, max_layer_motions=300, max_layers=3)
    controller = Controller(world, params)
    marks = list(controller.run())
    assert marks[-1] == "complete"
    rec = controller.record(complete=True)
    # each layer ends within its motion budget (plus the z increment), whatever it met
    assert len(rec.layers) <= 3
    assert controller.motions <= 3 * (300 + 10) + 20
    assert all(np.isfinite(np.asarray(p)).all() for p in rec.path)


def test_no_persist_tries_ends_the_contour_at_the_blocked_slide() -> None:
    with settings.override(servo={"persist_tries": 0}):
        rec = layers_only().explore(rough("bumps", 0), seed=0)
    assert not all(layer.closed for layer in rec.layers)
    assert any("blocked the slide without a sensor change" in n for n in rec.notes), rec.notes
    assert not any(n.endswith("followed by re-acquiring the surface") for n in rec.notes)
