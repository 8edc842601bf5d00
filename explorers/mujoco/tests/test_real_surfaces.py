"""The shared controller's riding and completion in the physics world: imperfect surfaces."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from tactile_kb_mujoco import MujocoExplorer

from tactile_kb import solids
from tactile_kb.model import build_model
from tactile_kb.pipeline import classify


def jittered(mesh: trimesh.Trimesh, amplitude: float, seed: int) -> trimesh.Trimesh:
    """Subdivided to 4 mm edges, every vertex moved by up to ±``amplitude`` per axis."""
    v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge=0.004)
    rng = np.random.default_rng(seed)
    return trimesh.Trimesh(v + rng.uniform(-amplitude, amplitude, v.shape), f)


def mug() -> trimesh.Trimesh:
    """A revolved mug (8 cm across, 9 cm tall, 6 mm walls) with a ring handle."""
    profile = np.array(
        [[0.0, 0.0], [0.04, 0.0], [0.04, 0.09], [0.034, 0.09], [0.034, 0.006], [0.0, 0.006]]
    )
    body = trimesh.creation.revolve(profile, sections=48)
    handle = trimesh.creation.torus(
        major_radius=0.025, minor_radius=0.006, major_sections=32, minor_sections=12
    )
    handle.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    handle.apply_translation((0.052, 0.0, 0.045))
    out: trimesh.Trimesh = trimesh.boolean.union([body, handle])
    return out


def test_a_jittered_box_is_explored_to_a_closed_model():
    rec = MujocoExplorer().explore(jittered(solids.box(0.08, 0.06, 0.05), 0.0005, 1), seed=0)
    assert rec.ending == "closed", rec.notes
    assert build_model(rec).polyhedron is not None
    assert any(n.endswith("surface irregularities ridden over") for n in rec.notes)


def test_the_mug_is_classified_as_the_stepper_classifies_it():
    mesh = mug()
    assert mesh.is_watertight
    answers = {}
    for explorer in ("stepper", "mujoco"):
        result = classify(mesh, rules="polyhedra", explorer=explorer, seed=0)
        answers[explorer] = result.decision.label
        assert result.record.touches > 5  # not the one touch of 0.1
        assert result.record.ending in ("closed", "unreachable", "budget")
    assert answers["mujoco"] == answers["stepper"] == "curved"


@pytest.mark.parametrize("explorer", ["stepper", "mujoco"])
def test_an_open_ending_is_never_silent(explorer, tmp_path, capsys):
    from tactile_kb.cli import main

    path = tmp_path / "box.stl"
    solids.box(0.05, 0.04, 0.03).export(path)
    args = ["explore", str(path), "--finger", "4", "--explorer", explorer]
    assert main([*args, "--out", str(tmp_path / "r.json")]) == 0
    err = capsys.readouterr().err
    assert "still open: open towards +z" in err
