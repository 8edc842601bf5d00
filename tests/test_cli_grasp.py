"""``tactile-kb grasp / plot / tree``: output, JSON keys, pictures, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from tactile_kb.cli import main
from tactile_kb.solids import box, tetrahedron, u_shape

KEYS = {
    "object",
    "points",
    "normals",
    "angle_deg",
    "com_offset",
    "width",
    "quality",
    "quality_measure",
    "force_closure",
    "reason",
}


@pytest.fixture
def meshes(tmp_path: Path) -> dict[str, Path]:
    out = {}
    for name, mesh in (
        ("box", box(0.10, 0.06, 0.04)),
        ("tetra", tetrahedron(0.1)),
        ("u", u_shape(0.12, 0.08, 0.03, 0.04)),
    ):
        path = tmp_path / f"{name}.stl"
        mesh.export(path)
        out[name] = path
    return out


def _size(path: Path) -> tuple[int, int]:
    with Image.open(path) as im:
        return im.size


def test_grasp_json_lines_and_exit_code(
    meshes: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["grasp", str(meshes["box"]), str(meshes["tetra"]), "--json"])
    assert code == 1  # the tetrahedron has no grasp
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert len(rows) == 2
    for row in rows:
        assert set(row) >= KEYS
    good, bad = rows
    assert good["reason"] is None
    assert good["force_closure"] is True
    assert good["width"] == pytest.approx(0.06, abs=1e-4)
    assert good["com_offset"] < 0.001
    assert np.allclose(np.mean(good["points"], axis=0), [0.0, 0.0, 0.02], atol=1e-3)
    assert bad["points"] is None
    assert bad["reason"].startswith("no pair of parallel faces")


def test_grasp_text_and_plot(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "g.png"
    args = ["grasp", str(meshes["box"]), "--plot", str(out), "--size", "4x3", "--dpi", "50"]
    assert main(args) == 0
    (line,) = capsys.readouterr().out.splitlines()
    assert line.startswith(f"{meshes['box']}- GRASP faces")
    assert "opening 60.0 mm" in line
    assert _size(out) == (200, 150)


def test_grasp_on_a_saved_record(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "box.json"
    assert main(["explore", str(meshes["box"]), "--out", str(record)]) == 0
    capsys.readouterr()
    assert main(["grasp", "--record", str(record), "--json", "--max-opening", "0.05"]) == 1
    row = json.loads(capsys.readouterr().out)
    assert row["reason"].startswith("every parallel pair is wider than the pincers")


def test_plot_a_record(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    record = tmp_path / "box.json"
    assert main(["explore", str(meshes["box"]), "--out", str(record)]) == 0
    png, svg = tmp_path / "p.png", tmp_path / "p.svg"
    assert main(["plot", str(record), "--out", str(png), "--mesh", str(meshes["box"])]) == 0
    assert _size(png) == (640, 480)
    assert main(["plot", str(record), "--out", str(svg), "--no-grasp"]) == 0
    assert "<svg" in svg.read_text()


def test_tree(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "t.png"
    assert main(["tree", "parallelepipeds", "--out", str(out), "--bits", "101101111"]) == 0
    assert capsys.readouterr().out.strip().endswith("OBJECT IS A CUBE")
    assert _size(out) == (960, 640)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["grasp"], "at least one PATH"),
        (["grasp", "x.stl", "--plot", "x.gif"], "must end in"),
        (["tree", "parallelepipeds", "--out", "t.png", "--bits", "10"], "9 characters"),
        (["plot", "r.json", "--out", "r.bmp"], "must end in"),
        (["grasp", "x.stl", "--size", "big"], "WIDTHxHEIGHT"),
        (["grasp", "x.stl", "--mu", "-1"], "≥ 0"),
    ],
)
def test_usage_errors_exit_2_with_one_line(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err
    assert len(err.splitlines()) == 1


def test_unreadable_object_and_record_exit_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "missing.stl"
    assert main(["grasp", str(missing)]) == 1
    assert str(missing) in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    assert main(["plot", str(bad), "--out", str(tmp_path / "x.png")]) == 1
    err = capsys.readouterr().err.strip()
    assert "bad.json" in err
    assert len(err.splitlines()) == 1


def test_grasp_a_box_union_with_the_four_sensor_finger(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "u.png"
    args = ["grasp", str(meshes["u"]), "--finger", "4", "--json", "--plot", str(out), "--dpi", "40"]
    assert main(args) == 0
    row = json.loads(capsys.readouterr().out)
    assert set(row) >= KEYS
    assert row["basis"] == "sections"
    assert "not touched" in row["notes"][0]
    assert row["force_closure"] is True
    # across the base of the U (3 cm), on the line through its centre of mass (x = 0)
    assert row["width"] == pytest.approx(0.03, abs=1e-4)
    assert [p[0] for p in row["points"]] == pytest.approx([0.0, 0.0], abs=1e-4)
    assert _size(out) == (256, 192)
    assert main(["grasp", str(meshes["u"]), "--finger", "4"]) == 0
    line = capsys.readouterr().out.strip()
    assert "of the layer contour" in line
    assert "top not touched" in line


@pytest.mark.parametrize("option", ["--mu", "--dpi", "--mass", "--max-opening"])
def test_quantities_that_must_be_positive(option: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["grasp", "x.stl", option, "0"]) == 2
    assert (
        capsys.readouterr().err.strip()
        == f"tactile-kb grasp: argument {option}: must be > 0, got '0'"
    )
