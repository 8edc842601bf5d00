"""Static checks: each problem kind with its exact file:line:column."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kbtruth import r_table, table

from tactile_kb.errors import Problem, RuleFileError
from tactile_kb.kb.analysis import smallest_conflict
from tactile_kb.kb.compiler import compile_rules
from tactile_kb.kb.expr import evaluate, parse_expr
from tactile_kb.kb.rulegen import rules_text
from tactile_kb.kb.rules import parse_rules

IDS = ["A", "B", "C", "D"]


def _errors(text: str) -> list[Problem]:
    with pytest.raises(RuleFileError) as info:
        compile_rules(text)
    return info.value.problems


def _line_of(text: str, needle: str) -> tuple[int, int]:
    """1-based line and column of the first occurrence of ``needle``."""
    for number, line in enumerate(text.splitlines(), 1):
        if needle in line:
            return number, line.index(needle) + 1
    raise AssertionError(needle)


def test_unsatisfiable_names_the_smallest_conflict() -> None:
    """A deletion pass from the front would keep 4 connections; the smallest set has 2."""
    conns = ["A", "A -> B", "B -> C", "~C", "~A"]
    text = rules_text(IDS, conns, ["D"])
    (problem,) = _errors(text)
    first_line, first_col = _line_of(text, "'A'")
    last_line, _ = _line_of(text, "'~A'")
    assert (problem.line, problem.column) == (first_line, first_col + 1)
    assert problem.path == "connections[0]"
    assert problem.severity == "error"
    assert problem.message == (
        f"conflicting connections leave r(L) empty: line {first_line} (A), line {last_line} (~A)"
    )


def test_a_connection_that_never_holds() -> None:
    text = rules_text(IDS, ["A & ~A"], ["D"])
    (problem,) = _errors(text)
    assert (problem.line, problem.column) == (_line_of(text, "A & ~A")[0], 6)
    assert "can never hold" in problem.message
    (constant,) = _errors(rules_text(IDS, ["0"], ["D"]))
    assert "can never hold" in constant.message


def test_dead_class_is_an_error_at_its_condition() -> None:
    text = rules_text(IDS, ["A -> B"], ["A & ~B", "C & ~C", "D"])
    problems = _errors(text)
    errors = [p for p in problems if p.severity == "error"]
    assert len(errors) == 2
    line, col = _line_of(text, "A & ~B")
    assert (errors[0].line, errors[0].column) == (line, col)
    assert errors[0].path == "classes[0].when"
    assert errors[0].message == (
        f"class 'c0' is dead: no member of r(L) satisfies it; "
        f"it contradicts line {_line_of(text, 'A -> B')[0]} (A -> B)"
    )
    assert "its condition can never hold" in errors[1].message
    # the warnings of the same file are listed too
    assert any(p.severity == "warning" for p in problems)


def test_overlap_gives_a_witness_minterm() -> None:
    text = rules_text(IDS, [], ["A & B", "B & C"])
    kb = compile_rules(text)
    (overlap,) = [p for p in kb.problems if "overlaps" in p.message]
    assert overlap.severity == "warning"
    assert (overlap.line, overlap.column) == _line_of(text, "B & C")
    witness = overlap.message.split("both take ")[1].split(" ")[0]
    values = dict(zip(IDS, (ch == "1" for ch in witness), strict=True))
    assert evaluate(parse_expr("A & B & C"), values)
    assert "and 1 more" in overlap.message  # ABC·D and ABC·D̄


def test_gap_count_matches_enumeration() -> None:
    text = rules_text(IDS, ["A -> B"], ["A & C", "~B & D"])
    kb = compile_rules(text)
    (gap,) = [p for p in kb.problems if "gap" in p.message]
    rules = parse_rules(text)
    covered = table("A & C", rules.ids) | table("~B & D", rules.ids)
    expected = int((r_table(rules) & ~covered).sum())
    assert f"a gap: {expected} of the {kb.r_count} members" in gap.message
    assert gap.path == "otherwise"
    assert gap.line == _line_of(text, "otherwise")[0]


def test_no_gap_no_overlap_when_classes_partition() -> None:
    kb = compile_rules(rules_text(["A", "B"], [], ["A", "~A & B", "~A & ~B"]))
    assert kb.problems == ()


def test_redundant_connections() -> None:
    conns = ["A -> B", "B -> C", "A -> C", "A -> B", "C | ~C"]
    text = rules_text(IDS, conns, ["A", "~A"])
    kb = compile_rules(text)
    redundant = [p for p in kb.problems if "redundant" in p.message]
    lines = [line for line, col in (_line_of(text, f"'{c}'") for c in conns)]
    got = {p.path: p.message for p in redundant}
    assert set(got) == {"connections[2]", "connections[3]", "connections[4]"}
    assert got["connections[4]"] == "redundant: it always holds"
    assert got["connections[3]"] == f"redundant: already implied by line {lines[0]} (A -> B)"
    assert got["connections[2]"] == (
        f"redundant: already implied by line {lines[0]} (A -> B), line {lines[1]} (B -> C)"
    )


@settings(max_examples=30, deadline=None)
@given(
    st.lists(
        st.tuples(st.sampled_from(IDS), st.sampled_from(["", "~"]), st.sampled_from(IDS)).map(
            lambda t: f"{t[1]}{t[0]} -> {t[2]}" if t[0] != t[2] else f"{t[1]}{t[0]}"
        ),
        min_size=1,
        max_size=7,
    )
)
def test_smallest_conflict_is_unsat_and_minimum(conns: list[str]) -> None:
    exprs = [parse_expr(c) for c in conns]
    ids = tuple(IDS)

    def sat(subset: tuple[int, ...]) -> bool:
        ok = np.ones(16, dtype=bool)
        for k in subset:
            ok &= table(exprs[k], ids)
        return bool(ok.any())

    core = smallest_conflict(exprs)
    if sat(tuple(range(len(exprs)))):
        assert core == []
        return
    assert not sat(tuple(core))
    for size in range(1, len(core)):
        assert all(sat(s) for s in itertools.combinations(range(len(exprs)), size))
