"""Strict YAML sources: positions, duplicate keys, YAML 1.1 traps, pydantic error mapping."""

from __future__ import annotations

from pathlib import Path

import pytest
from pydantic import BaseModel, ConfigDict

from tactile_kb.errors import Problem, RuleFileError, SourceError
from tactile_kb.yaml_source import format_path, load_yaml, render_excerpt, validate


def test_yaml11_traps_stay_strings() -> None:
    src = load_yaml("a: no\nb: 0777\nc: on\nd: off\ne: yes\nf: true\ng: 12\nh: 1.5\ni: ~\n")
    assert src.data == {
        "a": "no",
        "b": "0777",
        "c": "on",
        "d": "off",
        "e": "yes",
        "f": True,
        "g": 12,
        "h": 1.5,
        "i": None,
    }


def test_quoted_scalars_are_strings() -> None:
    assert load_yaml("a: 'true'\nb: \"12\"\n").data == {"a": "true", "b": "12"}


def test_positions_are_one_based_and_nested() -> None:
    text = "top:\n  items:\n    - x: 1\n    - x: 2\n"
    src = load_yaml(text)
    assert src.locate(("top", "items", 1, "x")) == (4, 10)
    assert src.locate(("top", "items", 1, "x"), key=True) == (4, 7)
    # a missing path falls back to its nearest ancestor
    assert src.locate(("top", "items", 1, "missing")) == (4, 7)


def test_locate_in_quoted_scalar_counts_the_quote() -> None:
    src = load_yaml("e: 'A & ?'\n")
    assert src.locate_in_scalar(("e",), 4) == (1, 9)
    assert src.data["e"][4] == "?"


def test_duplicate_keys_are_all_reported() -> None:
    with pytest.raises(SourceError) as info:
        load_yaml("a: 1\nb: 2\na: 3\nb: 4\n", file="d.yaml")
    msgs = [str(p) for p in info.value.problems]
    assert msgs == [
        "d.yaml:3:1: a: duplicate key 'a' (first at line 1)",
        "d.yaml:4:1: b: duplicate key 'b' (first at line 2)",
    ]


def test_syntax_error_is_located_with_excerpt() -> None:
    with pytest.raises(RuleFileError) as info:
        load_yaml("a: [1, 2\nb: 3\n", file="s.yaml", error_cls=RuleFileError)
    (p,) = info.value.problems
    assert p.file == "s.yaml"
    assert (p.line, p.column) == (1, 4)  # the [ left open, not where parsing stopped
    assert "YAML syntax error" in p.message
    assert "^" in info.value.excerpt


def test_unreadable_file(tmp_path: Path) -> None:
    with pytest.raises(SourceError, match="cannot read"):
        load_yaml(tmp_path / "absent.yaml")


class _Item(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    name: str
    size: int


class _Doc(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    items: list[_Item]


def test_validate_maps_every_error_to_its_position() -> None:
    text = "items:\n  - name: a\n    size: big\n  - name: b\n    colour: red\n"
    src = load_yaml(text, file="v.yaml")
    with pytest.raises(SourceError) as info:
        validate(src, _Doc)
    got = [str(p) for p in info.value.problems]
    assert got == [
        "v.yaml:3:11: items[0].size: Input should be a valid integer",
        "v.yaml:4:5: items[1].size: field required",
        "v.yaml:5:5: items[1].colour: unknown field",
    ]


def test_validate_returns_the_model() -> None:
    doc = validate(load_yaml("items:\n  - {name: a, size: 3}\n"), _Doc)
    assert doc.items[0].size == 3


def test_format_path_and_excerpt() -> None:
    assert format_path(("phases", 0, "propositions")) == "phases[0].propositions"
    assert render_excerpt("one\ntwo\nthree\n", 2, 3) == "1 | one\n2 | two\n  |   ^\n3 | three"


def test_problem_str_forms() -> None:
    assert str(Problem("f.yaml", 0, 0, "", "cannot read")) == "f.yaml: cannot read"
    w = Problem("f.yaml", 3, 4, "classes[1]", "dead class", "warning")
    assert str(w) == "f.yaml:3:4: warning: classes[1]: dead class"


def test_keep_going_returns_structural_problems_with_the_data() -> None:
    src = load_yaml("a: 1\nb: 2\na: 3\n", file="k.yaml", keep_going=True)
    assert src.data == {"a": 1, "b": 2}
    assert [str(p) for p in src.problems] == ["k.yaml:3:1: a: duplicate key 'a' (first at line 1)"]
