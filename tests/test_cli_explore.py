"""``tactile-kb classify / explore / demo / plugins``: output, JSON keys, exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tactile_kb.cli import main
from tactile_kb.solids import box, tetrahedron


@pytest.fixture
def meshes(tmp_path: Path) -> dict[str, Path]:
    out = {}
    for name, mesh in (("cube", box(0.08, 0.08, 0.08)), ("tetra", tetrahedron(0.1))):
        path = tmp_path / f"{name}.stl"
        mesh.export(path)
        out[name] = path
    return out


def test_classify_prints_the_papers_answer(
    meshes: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["classify", str(meshes["cube"]), str(meshes["tetra"])]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out == [
        f"{meshes['cube']}- OBJECT IS A CUBE",
        f"{meshes['tetra']}- OBJECT IS NOT A HEXAHEDRON",
    ]


def test_classify_json_lines(meshes: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["classify", str(meshes["cube"]), "--json", "--noise", "0.0005", "--seed", "3"]) == 0
    )
    (line,) = capsys.readouterr().out.splitlines()
    row = json.loads(line)
    assert row["object"] == str(meshes["cube"])
    assert row["label"] == "cube"
    assert row["answer"] == "OBJECT IS A CUBE"
    assert len(row["bits"]) == len(row["propositions"])
    assert all(v in (True, False, None) for v in row["propositions"].values())
    assert row["contacts"] > 0
    assert row["planes"] == 6
    assert row["path_length"] > 0
    assert row["seconds"] > 0


def test_one_failure_does_not_stop_the_others(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "nope.stl"
    assert main(["classify", str(missing), str(meshes["cube"])]) == 1
    captured = capsys.readouterr()
    assert captured.out.splitlines() == [f"{meshes['cube']}- OBJECT IS A CUBE"]
    err = captured.err.splitlines()
    assert len(err) == 1
    assert str(missing) in err[0]


def test_explore_then_classify_the_record(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = tmp_path / "cube.json"
    assert main(["explore", str(meshes["cube"]), "--out", str(rec)]) == 0
    assert rec.exists()
    capsys.readouterr()
    assert main(["classify", "--record", str(rec), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["label"] == "cube"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["classify"], "at least one PATH"),
        (["classify", "x.stl", "--noise", "-1"], "--noise"),
        (["classify", "x.stl", "--seed", "abc"], "--seed"),
        (["classify", "x.stl", "--finger", "7"], "unknown finger"),
        (["classify", "x.stl", "--explorer", "nonesuch"], "unknown explorer 'nonesuch'"),
        (["classify", "x.stl", "--rules", "nonesuch"], "nonesuch"),
        (["explore", "x.stl", "--out", "/no/such/dir/r.json"], "does not exist"),
    ],
)
def test_usage_errors_are_one_line(
    argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(argv)
    err = capsys.readouterr().err
    assert code in (1, 2)
    assert len(err.strip().splitlines()) == 1
    assert needle in err
    assert "Traceback" not in err


def test_missing_plugin_prints_its_install_hint(
    meshes: dict[str, Path], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from tactile_kb.touch.explorers import explorer_registry

    monkeypatch.setattr(
        explorer_registry,
        "_loaded",
        {k: v for k, v in explorer_registry._loaded.items() if k != "mujoco"},
    )
    monkeypatch.setattr(
        explorer_registry,
        "_lazy",
        {**explorer_registry._lazy, "mujoco": "tk_absent_plugin:Explorer"},
    )
    assert main(["classify", str(meshes["cube"]), "--explorer", "mujoco"]) == 1
    err = capsys.readouterr().err
    assert "pip install -e ./explorers/mujoco" in err


def test_demo_prints_fig5(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["demo"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "OCTA- OBJECT IS NOT A HEXAHEDRON",
        "CUBE1- OBJECT IS A CUBE",
        "CUBE2- OBJECT IS A CUBE",
        "TETRA- OBJECT IS NOT A HEXAHEDRON",
        "PRAPAR- OBJECT IS A RECTANGULAR PARALLELEPIPED",
        "KOPAR- OBJECT IS A NONRECTANGULAR PARALLELEPIPED",
        "TETRA1- OBJECT IS NOT A HEXAHEDRON",
        "TETRA2- OBJECT IS NOT A HEXAHEDRON",
        "CUBE11- OBJECT IS A CUBE",
        "CUBE22- OBJECT IS A CUBE",
        "PRAPA1- OBJECT IS A RECTANGULAR PARALLELEPIPED",
        "KOPAR1- OBJECT IS A NONRECTANGULAR PARALLELEPIPED",
    ]


def test_plugins_lists_the_stepper(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    assert "stepper" in out
    assert "parallel_face_pairs" in out


@pytest.mark.parametrize(
    ("argv", "code", "needle"),
    [
        (["classify", "x.stl", "--seed", "-5"], 2, "--seed: must be ≥ 0"),
        (["classify", "x.stl", "--explorer", "nonesuch"], 2, "unknown explorer 'nonesuch'"),
        (["classify", "x.stl", "--plot", "/no/such/dir/p.png"], 2, "does not exist"),
        (["classify", "x.stl", "--plot", "p.gif"], 2, "must end in .png, .svg, .pdf"),
    ],
)
def test_bad_arguments_fail_before_any_exploration(
    argv: list[str], code: int, needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == code
    captured = capsys.readouterr()
    assert captured.out == ""
    assert len(captured.err.strip().splitlines()) == 1
    assert needle in captured.err


def test_explore_refuses_a_directory_or_device_and_leaves_it_alone(
    meshes: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import stat

    for out in (str(tmp_path), "/dev/null"):
        before = Path(out).stat().st_mode
        assert main(["explore", str(meshes["cube"]), "--out", out]) == 1
        err = capsys.readouterr().err
        assert err.strip().endswith("not a regular file; give a file name for the record")
        assert Path(out).stat().st_mode == before
    assert stat.S_ISCHR(Path("/dev/null").stat().st_mode)


def test_record_that_is_not_text_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "r.json"
    bad.write_bytes(b"\xff\xfe\x00garbage")
    assert main(["classify", "--record", str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"tactile-kb classify: error: {bad}:1:1: not UTF-8 text: byte 0xff cannot be decoded"
    ]


def test_pictures_of_objects_with_the_same_name_do_not_overwrite_each_other(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from tactile_kb.solids import box as make_box

    paths = []
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        paths.append(tmp_path / folder / "x.stl")
        make_box(0.08, 0.08, 0.08).export(paths[-1])
    plot = tmp_path / "pp.png"
    assert main(["classify", *map(str, paths), "--plot", str(plot)]) == 0
    assert sorted(p.name for p in tmp_path.glob("pp-*.png")) == ["pp-x-2.png", "pp-x.png"]


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith("tactile-kb ")


def _leaning_box(path: Path) -> Path:
    """A box whose two faces lean by 3°: square within the default 5°, not within 1°."""
    import math

    import numpy as np

    mesh = box(0.08, 0.06, 0.05)
    shear = np.eye(4)
    shear[0, 2] = math.tan(math.radians(3.0))
    mesh.apply_transform(shear)
    mesh.export(path)
    return path


def test_settings_from_the_command_line_change_the_answer(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lean = str(_leaning_box(tmp_path / "lean.stl"))
    assert main(["classify", lean]) == 0
    assert capsys.readouterr().out == f"{lean}- OBJECT IS A RECTANGULAR PARALLELEPIPED\n"
    strict = ["--set", "features.tolerance_deg=1", "--set", "features.sigmas=0"]
    assert main(["classify", lean, *strict]) == 0
    assert capsys.readouterr().out == f"{lean}- OBJECT IS A NONRECTANGULAR PARALLELEPIPED\n"
    toml = tmp_path / "strict.toml"
    toml.write_text("[features]\ntolerance_deg = 1.0\nsigmas = 0.0\n")
    assert main(["classify", lean, "--settings", str(toml)]) == 0
    assert "NONRECTANGULAR" in capsys.readouterr().out
    # --set comes after the file
    assert (
        main(["classify", lean, "--settings", str(toml), "--set", "features.tolerance_deg=5"]) == 0
    )
    assert "OBJECT IS A RECTANGULAR" in capsys.readouterr().out


def test_bad_settings_on_the_command_line_are_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    lean = str(_leaning_box(tmp_path / "lean.stl"))
    toml = tmp_path / "bad.toml"
    toml.write_text("[explore]\ncompletion_touches = -1\n")
    for extra, message in [
        (["--settings", str(toml)], f"{toml}:2: explore.completion_touches:"),
        (["--set", "explore.completion_touches"], "expected GROUP.FIELD=VALUE"),
        (["--set", "geometry.nope=1"], "--set geometry.nope=1: geometry.nope: Extra inputs"),
    ]:
        assert main(["classify", lean, *extra]) == 2
        captured = capsys.readouterr()
        assert captured.out == ""
        (line,) = captured.err.splitlines()
        assert line.startswith("tactile-kb classify: error: ")
        assert message in line


def test_probe_notes_are_cut_to_a_few_and_counted() -> None:
    from types import SimpleNamespace

    from tactile_kb.cli.options import PROBE_NOTES_SHOWN, notices

    probes = [f"a probe (the face {k}) found nothing (none)" for k in range(7)]
    notes = [
        "blind contact at (0, 0, 0)",
        *probes[:2],
        "the way to a probe is blocked",
        *probes[2:],
    ]
    notes.append("12 surface irregularities ridden over")
    shown = notices(SimpleNamespace(notes=notes))
    assert shown[:4] == notes[:4]  # the first PROBE_NOTES_SHOWN probe notes, in order
    assert PROBE_NOTES_SHOWN == 3
    assert shown[4] == "12 surface irregularities ridden over"
    assert shown[5].startswith("5 more probe note(s) like these; the record keeps them all")
    assert len(shown) == 6
    few = ["a probe (x) found nothing (none)", "other"]
    assert notices(SimpleNamespace(notes=few)) == few


def test_units_and_rest_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import trimesh

    mm = box(0.08, 0.06, 0.04)
    mm.apply_scale(1000.0)
    path = tmp_path / "box_mm.stl"
    mm.export(path)
    assert main(["classify", str(path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "80 m across" in err
    assert "--units mm" in err
    assert main(["classify", str(path), "--units", "mm"]) == 0
    assert capsys.readouterr().out.strip() == f"{path}- OBJECT IS A RECTANGULAR PARALLELEPIPED"
    # an explicit --set of the same setting wins over the shortcut
    assert main(["classify", str(path), "--units", "mm", "--set", "objects.units=m"]) == 1
    capsys.readouterr()
    # a slab standing on a corner: as given it is explored as it stands; --rest stable lays it
    # down on a broad face first, and says so
    slab = box(0.08, 0.06, 0.02)
    slab.apply_transform(trimesh.transformations.rotation_matrix(0.7, [1.0, 0.3, 0.0]))
    tilted = tmp_path / "slab.stl"
    slab.export(tilted)
    assert (
        main(["explore", str(tilted), "--rest", "stable", "--out", str(tmp_path / "r.json")]) == 0
    )
    err = capsys.readouterr().err
    assert "turned to rest in its most probable stable pose" in err
    record = json.loads((tmp_path / "r.json").read_text())
    assert max(c["point"][2] for c in record["contacts"]) == pytest.approx(0.02, abs=0.002)
    assert main(["classify", str(tilted), "--rest", "upright"]) == 2
    assert "--rest: invalid choice: 'upright'" in capsys.readouterr().err
