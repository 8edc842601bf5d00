"""Honest answers: what the run could not do well is said, on stderr and in the JSON notes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import trimesh

from tactile_kb.cli import main
from tactile_kb.errors import UsageError
from tactile_kb.solids import box
from tactile_kb.touch.explorers import get_explorer, noise_problem
from tactile_kb.touch.finger import builtin_finger, coverage, layout_warnings, load_layout

TRIPOD = """\
name: tripod
cone_deg: 70
sensors:
  - {elevation: -20, azimuth: 0}
  - {elevation: -20, azimuth: 120}
  - {elevation: -20, azimuth: 240}
"""


@pytest.fixture
def cube(tmp_path: Path) -> Path:
    path = tmp_path / "cube.stl"
    box(0.06, 0.06, 0.06).export(path)
    return path


def test_coverage_of_the_tripod_is_complete_but_not_adequate() -> None:
    tripod = load_layout(TRIPOD)
    report = coverage(tripod, samples=8000)
    assert report.complete  # every direction fires a sensor ...
    assert not report.adequate  # ... but up to 70° away from it
    assert report.max_error_deg > 60
    (problem,) = report.problems
    assert "from the sensor that reports it" in problem
    assert coverage(builtin_finger("33"), samples=8000).adequate
    assert layout_warnings(builtin_finger("33")) == []


def test_a_custom_layout_that_cannot_resolve_faces_is_warned_about(
    cube: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    finger = tmp_path / "tripod.yaml"
    finger.write_text(TRIPOD)
    assert main(["classify", str(cube), "--finger", str(finger), "--json"]) == 0
    captured = capsys.readouterr()
    row = json.loads(captured.out)
    assert any("finger 'tripod'" in note for note in row["notes"])
    assert f"tactile-kb classify: note: {cube}: finger 'tripod'" in captured.err


@pytest.mark.parametrize("sigma", ["0.5", "1e308", "0.005"])
def test_a_non_physical_noise_is_refused_naming_the_option(
    sigma: str, cube: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["classify", str(cube), "--noise", sigma]) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"tactile-kb classify: error: --noise {float(sigma):g}: ")
    assert "less than the tip radius (5 mm)" in line
    with pytest.raises(UsageError, match="tip radius"):
        get_explorer("stepper").explore(box(0.06, 0.06, 0.06), noise=float(sigma))


def test_a_large_noise_is_noted(cube: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert noise_problem(0.001, 0.005) == ("", "")
    assert main(["classify", str(cube), "--noise", "0.0015", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    assert any("large against the 5 mm tip" in note for note in row["notes"])


def test_noise_large_against_a_small_object_is_noted() -> None:
    record = get_explorer("stepper").explore(box(0.03, 0.03, 0.03), noise=0.001, seed=0)
    assert any("large against the object (30 mm" in note for note in record.notes)


def test_a_mesh_moved_onto_the_table_is_noted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    floating = tmp_path / "floating.stl"
    trimesh.creation.box((0.06, 0.06, 0.06)).export(floating)  # centred: z from -3 to 3 cm
    assert main(["classify", str(floating)]) == 0
    captured = capsys.readouterr()
    assert captured.out.endswith("OBJECT IS A CUBE\n")
    assert "the mesh was moved +30 mm along z so that it rests on the table" in captured.err
    resting = get_explorer("stepper").explore(box(0.06, 0.06, 0.06), seed=0)
    assert not any("moved" in note for note in resting.notes)
