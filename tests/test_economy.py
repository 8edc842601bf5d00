"""Economy figures against brute force over explicit sets of minterms."""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kbtruth import labels, rows

from tactile_kb import economy as economy_module
from tactile_kb.compiler import PAPER_EXAMPLE, KnowledgeBase, compile_rules
from tactile_kb.rulegen import generate_rules, rules_text


def _brute(kb: KnowledgeBase) -> tuple[float, float, float]:
    """(lazy, optimal, entropy) by enumeration: rows of r(L), class rows weigh 1."""
    lab = labels(kb.rules)
    grid = rows(kb.n)
    K = len(kb.classes)
    live = [int(r) for r in np.flatnonzero(lab >= 0)]
    weighted = [r for r in live if lab[r] < K]
    if not weighted:
        return 0.0, 0.0, 0.0

    def done(s: frozenset[int]) -> bool:
        return len({int(lab[r]) for r in s}) <= 1 or not any(lab[r] < K for r in s)

    def weight(s: frozenset[int]) -> int:
        return sum(1 for r in s if lab[r] < K)

    @cache
    def best(s: frozenset[int]) -> float:
        if done(s):
            return 0.0
        out = math.inf
        for x in range(kb.n):
            s0 = frozenset(r for r in s if not grid[r, x])
            s1 = s - s0
            if not s0 or not s1:
                continue
            w0, w1 = weight(s0), weight(s1)
            out = min(out, 1 + (w0 * best(s0) + w1 * best(s1)) / (w0 + w1))
        return out

    order = [kb.ids.index(name) for name in kb.engine.order]
    asked_total = 0
    for r in weighted:
        s = frozenset(live)
        for x in order:
            if done(s):
                break
            values = {bool(grid[q, x]) for q in s}
            if len(values) > 1:
                asked_total += 1
            s = frozenset(q for q in s if grid[q, x] == grid[r, x])
    counts = np.bincount(lab[weighted], minlength=K)
    p = counts[counts > 0] / len(weighted)
    entropy = float(-(p * np.log2(p)).sum())
    return asked_total / len(weighted), best(frozenset(live)), entropy


@st.composite
def small_rule_sets(draw: st.DrawFn) -> str:
    n = draw(st.integers(2, 6))
    ids = [f"V{i}" for i in range(n)]
    lit = st.tuples(st.sampled_from(ids), st.booleans()).map(lambda t: ("" if t[1] else "~") + t[0])
    term = st.lists(lit, min_size=1, max_size=3).map(" & ".join)
    conn = st.tuples(lit, st.sampled_from([" -> ", " | ", " = "]), lit).map("".join)
    connections = draw(st.lists(conn, max_size=3))
    classes = draw(st.lists(term, min_size=1, max_size=4))
    order = draw(st.permutations(ids))
    cut = draw(st.integers(1, n))
    phases = [list(order[:cut]), list(order[cut:])] if cut < n else [list(order)]
    return rules_text(ids, connections, classes, phases=phases)


@settings(max_examples=40, deadline=None)
@given(small_rule_sets())
def test_economy_matches_brute_force(text: str) -> None:
    kb = compile_rules(text, check=False)
    if kb.r_count == 0 or any(kb.count(m) == 0 for m in kb.model_bdds):
        return
    e = kb.economy()
    lazy, optimal, entropy = _brute(kb)
    assert e.lazy == pytest.approx(lazy)
    assert e.optimal == pytest.approx(optimal)
    assert e.entropy == pytest.approx(entropy, abs=1e-12)
    assert e.entropy <= e.optimal + 1e-9 <= e.lazy + 2e-9 <= kb.n + 3e-9


def test_lazy_is_the_average_of_decide() -> None:
    kb = compile_rules("parallelepipeds")
    owned = [kb.owned_bdds[i] for i in range(len(kb.classes))]
    total = asked = 0
    for row in kb.minterms():
        values = dict(zip(kb.ids, (ch == "1" for ch in row), strict=True))
        if all(kb.bdd.let(values, f) == kb.bdd.false for f in owned):
            continue  # gaps weigh nothing
        d = kb.decide({name: (lambda v=v: v) for name, v in values.items()})
        total += 1
        asked += len(d.evaluated)
    assert kb.economy().lazy == pytest.approx(asked / total)


def test_paper_example_figures() -> None:
    e = compile_rules(PAPER_EXAMPLE).economy()
    # one class, one minterm: A, B (C forced), D (E forced), F, G are asked in phase order;
    # the best tree asks A, C, F, G (F forces D)
    assert (e.lazy, e.optimal, e.entropy, e.test_all) == (5.0, 4.0, 0.0, 7)
    assert e.line == (
        "economy: 5 propositions evaluated on average in phase order; optimal tree 4, "
        "entropy bound 0 (log2 1 classes = 0), test-all 7"
    )


def test_equally_likely_classes_reach_log2_k() -> None:
    ids = ["A", "B", "C"]
    classes = [f"{'' if a else '~'}A & {'' if b else '~'}B" for a in (1, 0) for b in (1, 0)]
    e = compile_rules(rules_text(ids, [], classes)).economy()
    assert e.entropy == e.log2_classes == 2.0
    assert e.optimal == 2.0
    assert e.lazy == 2.0


def test_budget_and_class_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    kb = compile_rules(generate_rules(12, 6, 5, seed=2), check=False)
    monkeypatch.setattr(economy_module, "MAX_WORK", 10)
    e = kb.economy()
    assert e.lazy is None
    assert e.optimal is None
    assert "over 10 BDD operations" in e.note
    assert "not computed" in e.line
    monkeypatch.setattr(economy_module, "MAX_CLASSES", 3)
    monkeypatch.setattr(economy_module, "MAX_WORK", 400_000)
    e = kb.economy()
    assert e.optimal is None
    assert "more than 3 classes" in e.note
    assert e.to_dict()["classes"] == 5
