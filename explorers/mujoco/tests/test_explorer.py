"""The plugin: found through its entry point, keeps the explorer contract, agrees with the stepper."""

from __future__ import annotations

from importlib.metadata import entry_points

import pytest
from tactile_kb_mujoco import MujocoExplorer
from tactile_kb_mujoco.compare import compare_object

from tactile_kb import solids
from tactile_kb.record import ExplorationRecord
from tactile_kb.testing import explorer_checks
from tactile_kb.touch.explorers import available_explorers, get_explorer

ANGLE_TOL_DEG = 0.01
"""Matched planes of the two explorers differ by less than this angle..."""
OFFSET_TOL = 1e-5
"""... and by less than this offset (metres)."""


def test_registered_through_the_entry_point():
    (ep,) = [ep for ep in entry_points(group="tactile_kb.explorers") if ep.name == "mujoco"]
    assert ep.value == "tactile_kb_mujoco:MujocoExplorer"
    assert ep.dist is not None
    assert ep.dist.name == "tactile-kb-mujoco"
    assert "mujoco" in available_explorers()
    explorer = get_explorer("mujoco")
    assert isinstance(explorer, MujocoExplorer)
    assert explorer.name == "mujoco"


@pytest.mark.parametrize(("name", "check"), explorer_checks())
def test_contract(name, check):
    check(MujocoExplorer())


def test_record_is_the_shared_type():
    rec = MujocoExplorer().explore(solids.box(0.05, 0.04, 0.03), finger="4", seed=0)
    assert type(rec) is ExplorationRecord
    assert rec.explorer == "mujoco"
    assert ExplorationRecord.from_json(rec.to_json()) == rec


CASES = [(name, mesh, "33") for name, mesh, _ in solids.fig5_objects()] + [
    ("L", solids.l_shape(0.1, 0.08, 0.03, 0.04), "4"),
    ("T", solids.t_shape(0.12, 0.08, 0.03, 0.04), "4"),
    ("U", solids.u_shape(0.1, 0.08, 0.025, 0.03), "4"),
]
EXPECTED = {name: label for name, _, label in solids.fig5_objects()}
CORNERS = {"L": 6, "T": 8, "U": 8}  # the cross-section polygons, by construction


@pytest.mark.parametrize(("name", "mesh", "finger"), CASES, ids=[c[0] for c in CASES])
def test_both_explorers_agree(name, mesh, finger):
    rules = "parallelepipeds" if name in EXPECTED else "polyhedra"
    row = compare_object(name, mesh, finger=finger, seed=0, rules=rules)
    stepper, mujoco = row.runs
    assert (stepper.explorer, mujoco.explorer) == ("stepper", "mujoco")
    assert (mujoco.label, mujoco.answer) == (stepper.label, stepper.answer)
    if name in EXPECTED:
        assert mujoco.label == EXPECTED[name]
    else:
        assert mujoco.label == "composed_of_boxes"
        assert mujoco.corners == stepper.corners
        assert set(mujoco.corners) == {CORNERS[name]}
    assert row.planes[0] == row.planes[1]
    assert row.agreement.unmatched == 0
    assert row.max_angle_deg < ANGLE_TOL_DEG
    assert row.max_offset < OFFSET_TOL
    assert len(mujoco.record.contacts) == len(stepper.record.contacts)
    assert mujoco.record.path_length == pytest.approx(stepper.record.path_length, rel=0.01)


def test_command_line_classifies_with_mujoco(tmp_path, capsys):
    from tactile_kb.cli import main

    path = tmp_path / "cube.stl"
    solids.box(0.06, 0.06, 0.06).export(path)
    assert main(["classify", str(path), "--explorer", "mujoco"]) == 0
    assert "OBJECT IS A CUBE" in capsys.readouterr().out
