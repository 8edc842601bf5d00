"""Output a program can rely on: every ``--json`` output validates against its published JSON
Schema, failed objects have JSON lines too, and one exit-code rule holds everywhere."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from tactile_kb.cli import main
from tactile_kb.record import ExplorationRecord
from tactile_kb.schemas import schema, schema_names
from tactile_kb.solids import box, prism


def validate(name: str, instance: Any) -> None:
    jsonschema.validate(instance, schema(name), cls=jsonschema.Draft202012Validator)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("json")
    out = {"cube": d / "cube.stl", "prism": d / "prism.stl", "missing": d / "missing.stl"}
    box(0.08, 0.08, 0.08).export(out["cube"])
    prism(6, 0.04, 0.05).export(out["prism"])
    return out


def test_the_schemas_are_valid_json_schemas() -> None:
    assert schema_names() == ["classify", "compile", "grasp", "query"]
    for name in schema_names():
        jsonschema.Draft202012Validator.check_schema(schema(name))


def test_classify_lines_have_touches_contacts_report_and_measures(
    files: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["classify", str(files["prism"]), str(files["missing"]), "--rules", "polyhedra"]
    assert main([*argv, "--json"]) == 1
    ok, failed = (json.loads(line) for line in capsys.readouterr().out.splitlines())
    for row in (ok, failed):
        validate("classify", row)
    assert ok["answer"] == "OBJECT IS A PRISM"
    assert ok["report"] == "OBJECT IS A PRISM (sides = 6)"
    assert ok["reported"] == {"sides": 6}
    assert ok["measures"]["faces"] == 8
    assert 0 < ok["touches"] < ok["contacts"]
    assert failed["object"] == str(files["missing"])
    assert failed["error"]["kind"] == "ObjectError"
    assert str(files["missing"]) in failed["error"]["message"]
    # the text output says the same: the report, and the failure on stderr
    assert main(argv) == 1
    captured = capsys.readouterr()
    assert captured.out == f"{files['prism']}- OBJECT IS A PRISM (sides = 6)\n"
    assert captured.err.startswith(f"tactile-kb classify: error: {files['missing']}")


def test_explore_counts_touches_and_contacts_like_the_json(
    files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rec.json"
    assert main(["explore", str(files["cube"]), str(files["prism"]), "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2
    for line, stem in zip(lines, ("cube", "prism"), strict=True):
        record = ExplorationRecord.load(tmp_path / f"rec-{stem}.json")
        assert f"{record.touches} touches, {len(record.contacts)} contacts" in line
    assert main(["classify", "--record", str(tmp_path / "rec-cube.json"), "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    record = ExplorationRecord.load(tmp_path / "rec-cube.json")
    assert (row["touches"], row["contacts"]) == (record.touches, len(record.contacts))


def test_explore_errors_name_the_command_and_the_others_go_on(
    files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.json"
    assert main(["explore", str(files["missing"]), str(files["cube"]), "--out", str(out)]) == 1
    captured = capsys.readouterr()
    assert captured.err.startswith(f"tactile-kb explore: error: {files['missing']}")
    assert captured.out.startswith(f"{files['cube']}: ")
    assert (tmp_path / "r-cube.json").is_file()


def test_grasp_lines_validate(files: dict[str, Path], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["grasp", str(files["cube"]), str(files["missing"]), "--json"]) == 1
    ok, failed = (json.loads(line) for line in capsys.readouterr().out.splitlines())
    validate("grasp", ok)
    validate("grasp", failed)
    assert ok["touches"] > 0
    assert ok["contacts"] >= ok["touches"]
    assert failed["error"]["kind"] == "ObjectError"


def test_compile_json_and_format_json_agree_and_validate(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["compile", "parallelepipeds", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(["compile", "parallelepipeds", "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out) == first
    validate("compile", first)


@pytest.mark.parametrize(
    "argv",
    [
        ["--bits", "---------"],
        ["--bits=---------"],
        ["--bits", "1-1101-11"],
        ["A=1", "B=0"],
    ],
)
def test_query_json_validates_and_bits_may_start_with_a_dash(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["query", "parallelepipeds", *argv, "--json"]) == 0
    validate("query", json.loads(capsys.readouterr().out))


def test_query_contradicting_the_connections_exits_1(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["query", "parallelepipeds", "A=1", "B=1", "C=1", "--json"]) == 1
    captured = capsys.readouterr()
    decision = json.loads(captured.out)
    validate("query", decision)
    assert decision["label"] == "inconsistent"
    assert captured.err == (
        "tactile-kb query: error: the values contradict the connections: "
        "line 61: B = A & ~C; line 63: C = A & ~B\n"
    )


# --- one exit-code rule ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["validate", "no-such-rules"],
        ["compile", "no-such-rules"],
        ["query", "no-such-rules", "A=1"],
        ["tree", "no-such-rules", "--out", "t.png"],
        ["classify", "x.stl", "--rules", "no-such-rules"],
    ],
)
def test_a_rule_name_that_names_nothing_is_exit_2_everywhere(
    argv: list[str],
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"tactile-kb {argv[0]}: error: no rule file 'no-such-rules'")


def test_a_picture_that_cannot_be_written_is_exit_1_everywhere(
    files: dict[str, Path],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    from matplotlib.figure import Figure

    from tactile_kb.touch.explorers import get_explorer

    record = tmp_path / "r.json"
    get_explorer("stepper").explore(box(0.08, 0.08, 0.08), seed=0).save(record)

    def full(self: Figure, *a: object, **kw: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full)
    png = str(tmp_path / "p.png")
    for argv in (
        ["plot", str(record), "--out", png],
        ["tree", "parallelepipeds", "--out", png],
        ["classify", "--record", str(record), "--plot", png],
        ["grasp", "--record", str(record), "--plot", png],
    ):
        assert main(argv) == 1, argv
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1
        assert err[0].endswith("cannot write the picture: No space left on device"), err


MINI = """\
name: mini
propositions:
  - {id: A, text: a, feature: contact}
  - {id: B, text: b, feature: surface_plane}
phases:
  - {id: I, propositions: [A, B]}
classes: [{id: c, answer: C, when: A & B}]
otherwise: {id: o, answer: O}
"""


@pytest.mark.parametrize(
    ("old", "new", "needle"),
    [
        ("feature: surface_plane", "feature: no_such_feature", "no_such_feature"),
        (
            "feature: surface_plane",
            "feature: {name: face_count, params: {equals: x}}",
            "must be a number",
        ),
        ("when: A & B}", "when: A & B, report: [no_such_measure]}", "unknown measure"),
    ],
    ids=["unknown-feature", "bad-parameter", "unknown-measure"],
)
def test_compile_refuses_what_validate_refuses(
    old: str, new: str, needle: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "r.yaml"
    path.write_text(MINI.replace(old, new))
    assert main(["validate", str(path)]) == 1
    validate_err = capsys.readouterr().err
    assert main(["compile", str(path)]) == 1
    compile_err = capsys.readouterr().err
    assert needle in compile_err
    assert [line for line in validate_err.splitlines() if needle in line] == [
        line for line in compile_err.splitlines() if needle in line
    ]


def test_what_stayed_unreachable_is_named_in_the_json(
    files: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the 4-sensor finger has no sensor that can face a top in any pose of its head: the cube's
    # top stays open, and both the JSON line and the saved record name it rather than guess it
    assert main(["classify", str(files["cube"]), "--finger", "4", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    validate("classify", row)
    assert row["ending"] == "unreachable"
    assert row["unreachable"] == ["open towards +z"]
    assert row["budget"] == ""  # no budget ran out
    out = tmp_path / "rec.json"
    assert main(["explore", str(files["cube"]), "--finger", "4", "--out", str(out)]) == 0
    capsys.readouterr()
    record = ExplorationRecord.load(out)
    assert (record.ending, record.unreachable) == ("unreachable", ["open towards +z"])
    # an exploration that closes its model names nothing
    assert main(["classify", str(files["cube"]), "--json"]) == 0
    row = json.loads(capsys.readouterr().out)
    validate("classify", row)
    assert (row["ending"], row["unreachable"]) == ("closed", [])
