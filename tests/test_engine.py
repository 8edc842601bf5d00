"""The engine against enumerated truth tables: full, partial, batch and lazy phased decisions."""

from __future__ import annotations

import itertools
import json
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kbtruth import bits, labels, rows, table

from tactile_kb import KnowledgeBase, compile_rules
from tactile_kb.errors import UsageError
from tactile_kb.kb import engine as engine_module
from tactile_kb.kb.engine import INCONSISTENT, TABLE_MAX_N, UNDECIDED, ternary_closure
from tactile_kb.kb.rulegen import generate_rules, rules_text
from tactile_kb.kb.rules import PAPER_EXAMPLE

BAR = "\u0304"


@pytest.fixture(scope="module")
def paper() -> KnowledgeBase:
    return compile_rules(PAPER_EXAMPLE)


@pytest.fixture(scope="module")
def parallelepipeds() -> KnowledgeBase:
    return compile_rules("parallelepipeds")


def _label_index(kb: KnowledgeBase, label: str) -> int:
    if label == INCONSISTENT:
        return -1
    ids = [k.id for k in kb.classes] + [kb.rules.otherwise_id]
    return ids.index(label)


@pytest.mark.parametrize("name", ["paper", "parallelepipeds"])
def test_every_full_assignment(name: str, request: pytest.FixtureRequest) -> None:
    kb: KnowledgeBase = request.getfixturevalue(name)
    expected = labels(kb.rules)
    for row in range(kb.s_size):
        d = kb.classify(bits(row, kb.n))
        assert _label_index(kb, d.label) == expected[row]
        assert d.certain
    assert (kb.classify_batch(rows(kb.n)) == expected).all()


def test_cube_decision(paper: KnowledgeBase) -> None:
    d = paper.classify(
        {"A": True, "B": False, "C": True, "D": True, "E": False, "F": True, "G": True}
    )
    assert (d.label, d.answer, d.bits) == ("cube", "OBJECT IS A CUBE", "1011011")
    assert d.matched == f"A·B{BAR}·C·D·E{BAR}·F·G"
    assert d.phase == "V"
    assert d.evaluated == ("A", "B", "C", "D", "E", "F", "G")
    assert d.explanation == (
        f"OBJECT IS A CUBE: 1011011 matches A·B{BAR}·C·D·E{BAR}·F·G (class 'cube', line 22), "
        "certain after phase V"
    )
    assert paper.classify(np.array([1, 0, 1, 1, 0, 1, 1], dtype=bool)) == d
    assert json.loads(json.dumps(d.to_dict()))["label"] == "cube"


def test_violation_names_the_connection_and_its_line(paper: KnowledgeBase) -> None:
    d = paper.classify("1010011")  # F without D breaks F -> D
    assert d.label == INCONSISTENT
    assert d.violated == ("line 13: F -> D",)
    assert "line 13: F -> D (D is false, F is true)" in d.explanation
    both = paper.classify("----11-")  # E and F together: F -> D and ~(D & E) conflict
    assert both.violated == ("line 13: F -> D", "line 14: ~(D & E)")


def test_otherwise_lists_nearest_classes_by_hamming_distance(
    parallelepipeds: KnowledgeBase,
) -> None:
    kb = parallelepipeds
    ok = labels(kb.rules)
    grid = rows(kb.n)
    for row in np.flatnonzero(ok == len(kb.classes))[:40]:
        d = kb.classify(bits(int(row), kb.n))
        assert d.label == "unknown"
        for label, dist in d.nearest:
            k = next(c for c in kb.classes if c.id == label)
            models = grid[table(k.text, kb.rules.ids) & (ok >= 0)]
            assert dist == int((models != grid[row]).sum(axis=1).min())
        dists = [dist for _, dist in d.nearest]
        assert dists == sorted(dists)


def test_rectangular_box_is_one_bit_from_the_cube(parallelepipeds: KnowledgeBase) -> None:
    d = parallelepipeds.classify("101101011")
    assert d.label == "rectangular_parallelepiped"
    assert d.matched == f"A·B{BAR}·C·D·E{BAR}·F·G{BAR}·H·J"


@pytest.mark.parametrize("name", ["paper", "parallelepipeds"])
def test_partial_assignments_are_certain_iff_all_completions_agree(
    name: str, request: pytest.FixtureRequest
) -> None:
    kb: KnowledgeBase = request.getfixturevalue(name)
    expected = labels(kb.rules)
    rng = np.random.default_rng(5)
    for _ in range(60):
        pattern = "".join(rng.choice(list("01--")) for _ in range(kb.n))
        rows_ok = [
            r
            for r in range(kb.s_size)
            if all(p == "-" or p == b for p, b in zip(pattern, bits(r, kb.n), strict=True))
        ]
        answers = {int(expected[r]) for r in rows_ok} - {-1}
        d = kb.classify(pattern)
        if not answers:
            assert d.label == INCONSISTENT
        elif len(answers) == 1:
            assert d.certain
            assert _label_index(kb, d.label) == answers.pop()
        else:
            assert not d.certain
            assert d.label == UNDECIDED


def _providers(kb: KnowledgeBase, row: str, calls: list[str]) -> dict[str, Any]:
    def make(name: str, value: bool) -> Any:
        def provide() -> bool:
            calls.append(name)
            return value

        return provide

    return {name: make(name, ch == "1") for name, ch in zip(kb.ids, row, strict=True)}


@pytest.mark.parametrize("name", ["paper", "parallelepipeds"])
def test_decide_agrees_with_classify_and_is_lazy(name: str, request: pytest.FixtureRequest) -> None:
    kb: KnowledgeBase = request.getfixturevalue(name)
    for row in kb.minterms():
        calls: list[str] = []
        d = kb.decide(_providers(kb, row, calls))
        assert d.label == kb.classify(row).label
        assert d.certain
        assert tuple(calls) == d.evaluated
        order = kb.engine.order
        assert list(calls) == sorted(calls, key=order.index)
        assert not set(calls) & set(d.implied)
        assert d.phase == (kb.rules.proposition(calls[-1]).phase if calls else None)


def test_decide_on_the_cube_skips_what_the_connections_force(paper: KnowledgeBase) -> None:
    calls: list[str] = []
    d = paper.decide(_providers(paper, "1011011", calls))
    assert calls == ["A", "B", "D", "F", "G"]
    assert d.implied == ("C", "E")
    assert d.phase == "V"
    no_contact: list[str] = []
    assert paper.decide(_providers(paper, "0011011", no_contact)).label == "unknown"
    assert no_contact == ["A"]


def test_decide_errors(paper: KnowledgeBase) -> None:
    with pytest.raises(UsageError, match="no provider for proposition 'A'"):
        paper.decide({})
    with pytest.raises(UsageError, match="returned 'yes', not a bool"):
        paper.decide({"A": lambda: "yes"})


@pytest.mark.parametrize(
    ("assignment", "message"),
    [
        ("101", "bit string '101' has 3 characters; the rule set has 7 propositions"),
        ("10110x1", "'x' is not 0, 1 or -"),
        ({"Z": True}, "unknown proposition 'Z'"),
        ({"A": 2}, "proposition 'A': 2 is not true/false/0/1"),
        (np.zeros(3, dtype=bool), r"must have shape \(7,\)"),
        (np.full(7, 2), "must hold booleans"),
        (12, "not int"),
    ],
)
def test_bad_assignments(paper: KnowledgeBase, assignment: Any, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        paper.classify(assignment)


def test_bad_batches(paper: KnowledgeBase) -> None:
    with pytest.raises(UsageError, match=r"shape \(m, 7\)"):
        paper.classify_batch(np.zeros((3, 6), dtype=bool))
    with pytest.raises(UsageError, match="booleans"):
        paper.classify_batch(np.full((2, 7), 3))
    cube = np.array([[1, 0, 1, 1, 0, 1, 1]] * 2, dtype=np.int8)
    assert (paper.classify_batch(cube) == 0).all()


@settings(max_examples=12, deadline=None)
@given(st.sampled_from([5, 8, 9, 12, 16, 17, 20, 23, 30]), st.integers(0, 10**6))
def test_batch_matches_per_row_truth(n: int, seed: int) -> None:
    """One packed byte, two, three, and the column-wise path above TABLE_MAX_N."""
    kb = compile_rules(generate_rules(n, n // 2, 4, seed=seed, group_size=6), check=False)
    rng = np.random.default_rng(seed)
    batch = rng.random((300, n)) < 0.5
    got = kb.classify_batch(batch)
    K = len(kb.classes)
    for row, answer in zip(batch, got, strict=True):
        values = dict(zip(kb.ids, row.tolist(), strict=True))
        from tactile_kb.kb.expr import evaluate

        if not all(evaluate(c.expr, values) for c in kb.rules.connections):
            assert answer == -1
            continue
        first = next((i for i, k in enumerate(kb.rules.classes) if evaluate(k.expr, values)), K)
        assert answer == first
    assert n <= TABLE_MAX_N or kb.engine._table is None


def test_overlap_goes_to_the_first_class() -> None:
    kb = compile_rules(rules_text(["A", "B"], [], ["A", "B"]))
    assert kb.classify("11").label == "c0"
    assert kb.classify("01").label == "c1"
    assert list(kb.classify_batch(np.array(list(itertools.product([0, 1], repeat=2))))) == [
        2,
        1,
        0,
        0,
    ]


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 6), st.integers(0, 10**6))
def test_ternary_closure_reduces_over_completions(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    values = rng.integers(0, 1 << 20, 1 << n)
    summed = ternary_closure(values, n, np.add)
    ored = ternary_closure(values, n, np.bitwise_or)
    assert summed.shape == (3**n,)
    for pattern in itertools.product("012", repeat=n):
        text = "".join(pattern)
        rows_ = [
            r
            for r in range(1 << n)
            if all(p == "2" or p == b for p, b in zip(text, bits(r, n), strict=True))
        ]
        t = int(text, 3) if n else 0
        assert summed[t] == values[rows_].sum()
        assert ored[t] == np.bitwise_or.reduce(values[rows_])


def _bdd_only(kb: KnowledgeBase, monkeypatch: pytest.MonkeyPatch) -> KnowledgeBase:
    """The same rule set compiled with the precomputed answer sets switched off."""
    monkeypatch.setattr(engine_module, "FAST_MAX_N", -1)
    slow = compile_rules(kb.rules)
    assert slow.engine._answer_sets is None
    assert kb.engine._answer_sets is not None
    return slow


@pytest.mark.parametrize("name", ["paper", "parallelepipeds"])
def test_fast_path_gives_the_bdd_path_decisions(
    name: str, request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every partial assignment (a sample for the 9-proposition base) gets the very same
    Decision, explanation included, from the answer sets as from the BDDs."""
    kb: KnowledgeBase = request.getfixturevalue(name)
    slow = _bdd_only(kb, monkeypatch)
    patterns = ["".join(p) for p in itertools.product("01-", repeat=kb.n)]
    if len(patterns) > 3000:
        rng = np.random.default_rng(7)
        patterns = [patterns[i] for i in rng.choice(len(patterns), 3000, replace=False)]
    for pattern in patterns:
        assert kb.classify(pattern) == slow.classify(pattern), pattern
    for row in kb.minterms():
        assert kb.decide(_providers(kb, row, [])) == slow.decide(_providers(slow, row, []))
    known = {"A": True, "C": True}
    for v in kb.ids:
        assert kb.engine.forced(known, v) == slow.engine.forced(known, v)
        assert kb.engine.possible({v: False}) == slow.engine.possible({v: False})
