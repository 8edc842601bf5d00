"""``tactile-kb validate | compile | query``: output, exit codes, one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tactile_kb.cli import main
from tactile_kb.kb.rulegen import rules_text
from tactile_kb.kb.rules import PAPER_EXAMPLE

BAR = "\u0304"


@pytest.fixture
def paper_file(tmp_path: Path) -> Path:
    path = tmp_path / "paper.yaml"
    path.write_text(PAPER_EXAMPLE, encoding="utf-8")
    return path


def test_validate_ok_with_warnings_exits_0(
    paper_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["validate", str(paper_file), "parallelepipeds"]) == 0
    out, err = capsys.readouterr()
    assert f"{paper_file}: ok: 7 propositions, 1 classes, |r(L)| = 32, 8 warnings" in out
    lines = err.splitlines()
    assert lines[:7] == [
        f"{paper_file}:{4 + i}:5: warning: propositions[{i}]: no feature decides proposition "
        f"'{name}', so objects cannot be classified with this file (add feature: NAME)"
        for i, name in enumerate("ABCDEFG")
    ]
    assert lines[7] == (
        f"{paper_file}:26:3: warning: otherwise: a gap: 31 of the 32 members of r(L) "
        "satisfy no class (for example 0010000); they get the answer OBJECT IS NOT RECOGNISED"
    )


def test_validate_lists_every_error_and_exits_1(
    tmp_path: Path, paper_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(rules_text(["A", "B"], ["A -> B"], ["A & ~B", "A & B & (C"]), "utf-8")
    dead = tmp_path / "dead.yaml"
    dead.write_text(rules_text(["A", "B"], ["A -> B"], ["A & ~B", "B"]), "utf-8")
    assert main(["validate", str(bad), str(dead), str(paper_file)]) == 1
    out, err = capsys.readouterr()
    errors = [line for line in err.splitlines() if ": warning: " not in line]
    assert errors[0] == f"{bad}:12:46: classes[1].when: unbalanced '(': it is never closed"
    assert errors[1].startswith(f"{dead}:11:38: classes[0].when: class 'c0' is dead: ")
    assert len(errors) == 2
    assert f"{paper_file}: ok" in out
    assert "Traceback" not in err


def test_validate_missing_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # a path that names nothing is a usage error (docs/cli.md), as in compile and query
    assert main(["validate", str(tmp_path / "nope.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "no rule file" in err


def test_compile_text(paper_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", str(paper_file)]) == 0
    out = capsys.readouterr().out
    assert "s(L): 2^7 = 128 conjunctions" in out
    assert "r(L): 32 members left by 3 connections" in out
    assert f"  r(L) = A·B{BAR}·C·D·E{BAR}·F·G\n" in out
    assert "  ascii: A & ~B & C & D & ~E & F & G\n" in out
    assert "  bits:  1011011\n" in out
    assert "  L: object is cube\n" in out
    assert f"  L = A·B{BAR}·C·D·E{BAR}·F·G\n" in out
    assert "warning: otherwise: a gap" in out
    assert out.rstrip().splitlines()[-1].startswith("economy: 5 propositions evaluated")


def test_compile_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", "parallelepipeds", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["n"] == 9
    assert data["classes"][0]["bits"] == ["101101111"]
    assert set(data["economy"]) >= {"lazy", "optimal", "entropy", "test_all"}


def test_compile_error_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(rules_text(["A"], ["A", "~A"], ["A"]), "utf-8")
    assert main(["compile", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err == (
        f"{bad}:5:6: connections[0]: conflicting connections leave r(L) empty: "
        "line 5 (A), line 6 (~A)\n"
    )


def test_query_bits_and_assignments(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["query", "parallelepipeds", "--bits", "101101111"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == "OBJECT IS A CUBE"
    assert "certain: yes, after phase VII" in out
    assert main(["query", "parallelepipeds", "A=0"]) == 0
    assert capsys.readouterr().out.splitlines()[0] == "THE FINGER FOUND NO OBJECT"
    assert main(["query", "parallelepipeds", "A=1", "B=true", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["label"] == "not_hexahedron"
    assert data["certain"] is True


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["A:1"], "bad assignment 'A:1': write ID=1 or ID=0"),
        (["Z=1"], "unknown proposition 'Z'"),
        (["A=1", "A=0"], "proposition 'A' is assigned twice"),
        (["--bits", "101"], "bit string '101' has 3 characters"),
        (["A=1", "--bits", "101101111"], "not both"),
        ([], "give ID=0|1 assignments or --bits"),
    ],
)
def test_query_usage_errors_exit_2_with_one_line(
    argv: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["query", "parallelepipeds", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert message in err


def test_unknown_rule_set_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", "no-such-rules"]) == 2
    assert "no rule file 'no-such-rules'" in capsys.readouterr().err


def test_validate_checks_feature_bindings_with_the_logic(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (
        "name: b\n"
        "propositions:\n"
        "  - id: A\n"
        "    text: contact\n"
        "    feature: contact\n"
        "  - id: B\n"
        "    text: six faces\n"
        "    feature: {name: face_count, params: {sides: 6}}\n"
        "  - id: C\n"
        "    text: unbound\n"
        "connections:\n"
        "  - A & ~A\n"
        "phases:\n"
        "  - id: I\n"
        "    propositions: [A, B, C]\n"
        "classes:\n"
        "  - id: x\n"
        "    answer: X\n"
        "    when: A\n"
        "otherwise:\n"
        "  id: none\n"
        "  answer: NONE\n"
    )
    path = tmp_path / "b.yaml"
    path.write_text(text)
    assert main(["validate", str(path)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert (
        err[0]
        == f"{path}:8:42: propositions[1].feature.params.sides: feature 'face_count' has no parameter 'sides' (parameters: equals, max, min)"
    )
    assert err[1].startswith(
        f"{path}:9:5: warning: propositions[2]: no feature decides proposition 'C'"
    )
    assert any(line.startswith(f"{path}:12:5: connections[0]") for line in err[2:])


def test_query_takes_assignments_after_its_options(capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["query", "parallelepipeds", "--json", "A=1", "B=0", "C=1", "D=0", "E=1", "H=0"]) == 0
    )
    assert json.loads(capsys.readouterr().out)["label"] == "not_hexahedron"
    assert main(["query", "parallelepipeds", "A=1", "--bogus"]) == 2
    assert capsys.readouterr().err.strip() == "tactile-kb: unrecognized arguments: --bogus"
