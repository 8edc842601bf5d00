"""Economy figures against brute force over explicit sets of minterms."""

from __future__ import annotations

import math
import random
from functools import cache

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kbtruth import labels, rows

from tactile_kb import KnowledgeBase, compile_rules
from tactile_kb.kb import economy as economy_module
from tactile_kb.kb.economy import huffman_bound, lazy_expectation
from tactile_kb.kb.rulegen import generate_rules, rules_text
from tactile_kb.kb.rules import PAPER_EXAMPLE


def _brute(kb: KnowledgeBase, order: list[str] | None = None) -> tuple[float, float, float]:
    """(lazy, optimal, entropy) by enumeration: rows of r(L), class rows weigh 1; ``lazy``
    asks in ``order`` (default: the phase order)."""
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

    order_ = [kb.ids.index(name) for name in (order or kb.engine.order)]
    asked_total = 0
    for r in weighted:
        s = frozenset(live)
        for x in order_:
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


@pytest.mark.parametrize("ternary_max_n", [12, 0])
@settings(max_examples=30, deadline=None)
@given(small_rule_sets())
def test_economy_matches_brute_force(ternary_max_n: int, text: str) -> None:
    """Both exact methods: the ternary programme and (with it switched off) the branch and
    bound over BDD states."""
    kb = compile_rules(text, check=False)
    if kb.r_count == 0 or any(kb.count(m) == 0 for m in kb.model_bdds):
        return
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(economy_module, "TERNARY_MAX_N", ternary_max_n)
        e = kb.economy()
    lazy, optimal, entropy = _brute(kb)
    assert e.lazy == pytest.approx(lazy)
    assert e.optimal == pytest.approx(optimal)
    assert e.optimal_lower == e.optimal_upper == e.optimal
    assert e.entropy == pytest.approx(entropy, abs=1e-12)
    assert e.entropy <= e.optimal + 1e-9 <= e.lazy + 2e-9 <= kb.n + 3e-9


@settings(max_examples=30, deadline=None)
@given(small_rule_sets(), st.randoms(use_true_random=False))
def test_lazy_in_any_order_matches_brute_force(text: str, rnd: random.Random) -> None:
    kb = compile_rules(text, check=False)
    if kb.r_count == 0 or any(kb.count(m) == 0 for m in kb.model_bdds):
        return
    order = list(kb.ids)
    rnd.shuffle(order)
    assert lazy_expectation(kb, order) == pytest.approx(_brute(kb, order)[0])


def _optimal_code(weights: list[int]) -> float:
    """The least expected depth of a prefix code, by trying every full binary tree shape:
    split the symbols (sorted by weight) into two sets, recursively."""

    @cache
    def best(items: tuple[int, ...]) -> float:
        if len(items) <= 1:
            return 0.0
        out = math.inf
        for mask in range(1, (1 << len(items)) - 1):
            left = tuple(w for j, w in enumerate(items) if mask >> j & 1)
            right = tuple(w for j, w in enumerate(items) if not mask >> j & 1)
            out = min(out, sum(items) + best(left) + best(right))
        return out

    return best(tuple(sorted(weights))) / sum(weights)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 20), min_size=1, max_size=6).filter(lambda ws: sum(ws) > 0))
def test_huffman_bound_is_the_optimal_prefix_code(weights: list[int]) -> None:
    bound = huffman_bound([float(w) for w in weights])
    assert bound == pytest.approx(_optimal_code(weights))
    p = np.array([w for w in weights if w]) / sum(weights)
    assert bound >= float(-(p * np.log2(p)).sum()) - 1e-12
    assert bound >= (1.0 if len(weights) > 1 else 0.0)


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


def test_unsolved_optimum_is_bracketed(monkeypatch: pytest.MonkeyPatch) -> None:
    """Over its budget the branch and bound gives up; the bounds still hold the optimum."""
    kb = compile_rules(generate_rules(12, 6, 5, seed=2), check=False)
    exact = kb.economy()
    assert exact.method == "ternary"
    _, optimal, _ = _brute(kb)
    assert exact.optimal == pytest.approx(optimal)
    monkeypatch.setattr(economy_module, "TERNARY_MAX_N", 0)
    monkeypatch.setattr(economy_module, "MAX_WORK", 10)
    e = kb.economy()
    assert (e.optimal, e.method) == (None, "bounds")
    assert e.lazy == exact.lazy
    assert e.entropy - 1e-12 <= e.optimal_lower <= optimal <= e.optimal_upper <= e.lazy + 1e-12
    assert "over its budget of 10 BDD restrictions" in e.note
    assert (
        f"optimal tree not solved, between {e.optimal_lower:.4g} (lower bound) and "
        f"{e.optimal_upper:.4g} (a fixed-order tree)" in e.line
    )
    assert e.to_dict()["optimal_lower"] == e.optimal_lower
    monkeypatch.setattr(economy_module, "MAX_WORK", 10**9)
    monkeypatch.setattr(economy_module, "MAX_SECONDS", 0.0)
    assert kb.economy().optimal is None
    monkeypatch.setattr(economy_module, "MAX_SECONDS", 60.0)
    solved = kb.economy()
    assert solved.method == "branch and bound"
    assert solved.optimal == pytest.approx(optimal)


def test_class_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    kb = compile_rules(generate_rules(12, 6, 5, seed=2), check=False)
    monkeypatch.setattr(economy_module, "MAX_CLASSES", 3)
    e = kb.economy()
    assert e.optimal is None
    assert "more than 3 classes" in e.note
    assert e.optimal_upper == e.lazy
    assert e.to_dict()["classes"] == 5


def _lazy_by_prefixes(kb: KnowledgeBase, order: list[str]) -> float:
    """The phase-order expectation by enumerating all 2ⁿ rows with numpy: the proposition
    at position k is asked for a weighted row iff the live rows sharing its prefix carry
    more than one label and take both values at position k."""
    n, K = kb.n, len(kb.classes)
    lab = labels(kb.rules)
    grid = rows(n)[:, [kb.ids.index(v) for v in order]]
    keys = grid.astype(np.int64) @ (1 << np.arange(n - 1, -1, -1, dtype=np.int64))
    live = lab >= 0
    lab, keys = lab[live], keys[live]
    asked = 0
    for k in range(n):
        _, inv = np.unique(keys >> (n - k), return_inverse=True)
        bit = (keys >> (n - k - 1)) & 1
        spread = []
        for column in (lab, bit):
            lo = np.full(inv.max() + 1, np.iinfo(np.int64).max)
            hi = np.full(inv.max() + 1, np.iinfo(np.int64).min)
            np.minimum.at(lo, inv, column)
            np.maximum.at(hi, inv, column)
            spread.append(lo[inv] != hi[inv])
        asked += int(((lab < K) & spread[0] & spread[1]).sum())
    return asked / int((lab < K).sum())


@pytest.mark.parametrize("seed", [0, 1])
def test_lazy_on_sixteen_propositions_matches_enumeration(seed: int) -> None:
    kb = compile_rules(generate_rules(16, 10, 8, seed=seed), check=False)
    order = list(kb.engine.order)
    assert kb.economy().lazy == pytest.approx(_lazy_by_prefixes(kb, order))
    random.Random(seed).shuffle(order)
    assert lazy_expectation(kb, order) == pytest.approx(_lazy_by_prefixes(kb, order))


def test_forty_propositions_bracketed() -> None:
    """The benchmark's file: the phase-order figure is exact (no budget, no enumeration)
    and the optimum, out of the exact searches' reach, is bracketed."""
    kb = compile_rules(generate_rules(40, 30, 20, seed=0))
    e = kb.economy()
    assert e.optimal is None
    assert e.method == "bounds"
    assert e.entropy <= e.optimal_lower <= e.optimal_upper <= e.lazy <= kb.n
    assert "not computed" not in e.line


def test_lower_bound_met_means_optimal() -> None:
    # two classes told apart by one proposition: the phase order asks exactly it
    kb = compile_rules(rules_text(["A", "B"], [], ["A", "~A"]))
    e = kb.economy()
    assert (e.lazy, e.optimal, e.method) == (1.0, 1.0, "lower bound met")
