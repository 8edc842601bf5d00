"""Openings the layers pass by: a tunnel whose rim lies just over the tip, a slot between layers.

* A U block standing on the ends of its arms has a tunnel under its base. When a layer's tip
  centre lies less than ρ under the tunnel's ceiling, the tip is too tall for the mouth: its
  upper half meets the rim, the face followed comes back a step on, and the slide rides over
  the mouth as over a dent. The finger then looks under that rim one tip radius lower
  (``Controller._under_edge``), enters the mouth and touches its side wall.
* A U block lying on the side of an arm has its gap facing sideways, between the arms. With
  layers 0.35 of the height apart, the gap (the width of the base less two arms) can lie
  wholly between two layers. Where a contour first touches a side face, the finger rises
  along it towards the next layer (``Controller._rise``); a face falling away on the way up is
  a rim, and the finger enters over it and touches what lies behind.

The truth is the construction: a point the finger touched inside a concave opening lies well
inside the solid's convex hull (``trimesh.proximity.signed_distance``), where no point of a
convex solid's surface lies; and the class (a U block is not a hexahedron). Each case is also
run with the mechanism switched off, to show that it is what finds the opening.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.pipeline import classify
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import Controller, ServoParams
from tactile_kb.touch.stepper import StepperExplorer

RHO = builtin_finger("33").radius


def _depth(mesh: trimesh.Trimesh, record: ExplorationRecord) -> float:
    """How far inside ``mesh``'s convex hull the deepest contact point lies, metres."""
    points = np.array([c.point for c in record.contacts])
    inside = trimesh.proximity.signed_distance(mesh.convex_hull, points)
    return float(np.max(inside))


# The tunnel: a U block 0.1 m across its arms (0.0406 m wide, 0.064 m long), on their ends; the
# tunnel under its base is 0.1 − 2 × 0.0406 = 18.8 mm wide and 0.064 − 0.0406 = 23.4 mm high.
TUNNEL = 0.064 - 0.0406
# The slot: a U block 0.09 m across its arms (0.037 m wide), on the outer side of one; the gap
# between the arms lies from 0.037 to 0.053 m above the table.
SLOT = (0.037, 0.09 - 0.037)
# Layers 0.35 of the height apart, as by default: the first one's tip centre 1 mm under the
# tunnel's ceiling (too tall for the mouth); the slot block's at 0.0315 and 0.063 m, so that no
# layer's tip (centre between 0.042 and 0.048 m) fits in the slot.
TUNNEL_LAYERS = ServoParams(z_first=TUNNEL - 0.001, z_step=0.35 * 0.064)
SLOT_LAYERS = ServoParams(z_first=0.35 * 0.09, z_step=0.35 * 0.09)


def _tunnel_block() -> tuple[trimesh.Trimesh, ServoParams]:
    block = solids.rest_on_face(solids.u_shape(0.1, 0.064, 0.0406, 0.05), (0.0, 1.0, 0.0))
    return block, TUNNEL_LAYERS


def _slot_block() -> tuple[trimesh.Trimesh, ServoParams]:
    block = solids.rest_on_face(solids.u_shape(0.09, 0.07, 0.037, 0.05), (-1.0, 0.0, 0.0))
    return block, SLOT_LAYERS


def test_the_constructions_place_the_openings_where_the_layers_miss_them() -> None:
    tunnel, params = _tunnel_block()
    assert tunnel.extents[2] == pytest.approx(0.064)
    assert params.z_first is not None
    assert TUNNEL - RHO < params.z_first < TUNNEL  # the tip is too tall for the mouth
    slot, params = _slot_block()
    assert slot.extents[2] == pytest.approx(0.09)
    assert params.z_first is not None
    assert params.z_step is not None
    lo, hi = SLOT
    assert hi - lo > 2 * RHO  # the tip fits in the gap...
    for z in (params.z_first, params.z_first + params.z_step):  # ...but no layer's tip does
        assert not (lo + RHO <= z <= hi - RHO)


@pytest.mark.parametrize("turn", [0.0, 37.0, 128.0])
@pytest.mark.parametrize(
    "build",
    [_tunnel_block, _slot_block],
    ids=["a tunnel under a rim just over the tip", "a slot between two layers"],
)
def test_the_opening_is_found(
    build: Callable[[], tuple[trimesh.Trimesh, ServoParams]], turn: float
) -> None:
    block, params = build()
    block = solids.rotate_about_z(block, turn)
    result = classify(block, explorer=StepperExplorer(params))
    assert result.decision.label == "not_hexahedron"
    assert _depth(block, result.record) > 2 * RHO / 5
    assert any("opening(s) found" in n for n in result.record.notes)


@pytest.mark.parametrize(
    ("build", "mechanism"), [(_tunnel_block, "_under_edge"), (_slot_block, "_rise")]
)
def test_without_the_look_the_opening_is_missed(
    build: Callable[[], tuple[trimesh.Trimesh, ServoParams]],
    mechanism: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    block, params = build()
    monkeypatch.setattr(Controller, mechanism, lambda self, *args: None)
    result = classify(block, explorer=StepperExplorer(params))
    assert result.decision.label == "rectangular_parallelepiped"
    assert _depth(block, result.record) < RHO / 5


@pytest.mark.parametrize(
    "mesh",
    [
        solids.box(0.08, 0.06, 0.05),
        solids.prism(6, 0.04, 0.07),
        solids.parallelepiped(0.1, 0.07, 0.06, angle_deg=75.0),
    ],
    ids=["box", "hexagonal prism", "oblique parallelepiped"],
)
def test_whole_faces_show_no_opening(mesh: trimesh.Trimesh) -> None:
    mesh = solids.rotate_about_z(mesh, 23.0)
    record = classify(mesh, rules="polyhedra").record
    assert not any("opening" in n for n in record.notes)
    assert _depth(mesh, record) < RHO / 5
