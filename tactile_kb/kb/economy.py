"""How many propositions a classification costs: the paper's "great economy" of phases, measured.

With a uniform prior over the classes' minterms (every member of r(L) that a class takes is
equally likely; the first class in file order takes a shared one; gaps weigh nothing), four
figures:

* ``lazy``: the expected number of propositions :meth:`~tactile_kb.kb.engine.Engine.decide`
  asks when it goes in phase order, skips what the connections force and stops as soon as one
  answer is left. Exact, for any n, by BDD quantification (see :func:`lazy_expectation`);
* ``optimal``: the expected number asked by the best decision tree (any proposition may come
  next; it must single out one answer, the ``otherwise`` answer of a gap included). Exact by
  dynamic programming over all 3ᵐ partial assignments of the m propositions the classes
  depend on (m ≤ :data:`TERNARY_MAX_N`), else by branch and bound over BDD states within
  :data:`MAX_WORK` restrictions (a work budget, not a time limit, so the printed line is the
  same on every machine). The problem is NP-complete in general (Hyafil & Rivest
  1976): when neither finishes (or there are more than :data:`MAX_CLASSES` classes),
  ``optimal`` is None and ``optimal_lower`` ≤ optimum ≤ ``optimal_upper`` bound it: the
  Huffman bound of the answers' weights (never below the entropy) and the cost of the
  better of two fixed orders (the phase order; the propositions most classes mention first);
* ``entropy``: the Shannon entropy of the class distribution, a lower bound on any tree
  (log2 K for K equally likely classes);
* ``test_all``: n, evaluating every proposition.

So ``entropy ≤ optimal ≤ lazy ≤ test_all``; s(L) is never enumerated beyond 2ᵐ rows.

Examples
--------
>>> from tactile_kb.kb.compiler import PAPER_EXAMPLE, compile_rules
>>> e = compile_rules(PAPER_EXAMPLE).economy()
>>> e.lazy, e.optimal, e.entropy, e.test_all
(5.0, 4.0, 0.0, 7)
"""

from __future__ import annotations

import heapq
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import TYPE_CHECKING, Any

import numpy as np

from tactile_kb.kb.bdd import model_count
from tactile_kb.kb.engine import ternary_closure
from tactile_kb.kb.expr import evaluate_columns, names
from tactile_kb.kb.expr import names as expr_names

if TYPE_CHECKING:
    from tactile_kb.kb.bdd import Node
    from tactile_kb.kb.knowledge import Group, Knowledge

__all__ = [
    "MAX_CLASSES",
    "MAX_SECONDS",
    "MAX_WORK",
    "TERNARY_MAX_N",
    "Economy",
    "economy",
    "huffman_bound",
    "lazy_expectation",
    "optimal_bdd",
    "optimal_ternary",
]

MAX_CLASSES = 20
"""The optimal tree is searched for at most this many classes."""
TERNARY_MAX_N = 12
"""The exact dynamic programme over 3ᵐ partial assignments runs for m ≤ this (≈ 0.1 s)."""
MAX_WORK = 120_000
"""Budget of BDD restrictions for the branch and bound above :data:`TERNARY_MAX_N`
(``polyhedra`` needs under 100 000, about 0.1 s; a 40-proposition file gives up in about 0.5 s)."""
MAX_SECONDS: float | None = None
"""An optional time limit of the branch and bound; None (the default) keeps results
deterministic."""


@dataclass(frozen=True)
class Economy:
    """Expected numbers of propositions evaluated per classification (see the module).

    ``optimal`` is None when the optimum was not solved; ``optimal_lower`` and
    ``optimal_upper`` always bound it (both equal ``optimal`` when it was). ``method`` says
    how: ``"ternary"``, ``"branch and bound"`` or ``"bounds"``.
    """

    classes: int
    n: int
    lazy: float
    optimal: float | None
    entropy: float
    log2_classes: float
    test_all: int
    optimal_lower: float
    optimal_upper: float
    method: str
    note: str = ""

    @property
    def line(self) -> str:
        """The economy line printed by ``tactile-kb compile``."""
        if self.optimal is not None:
            tree = f"optimal tree {self.optimal:.4g}"
        else:
            tree = (
                f"optimal tree not solved, between {self.optimal_lower:.4g} (lower bound) "
                f"and {self.optimal_upper:.4g} (a fixed-order tree)"
            )
        text = (
            f"economy: {self.lazy:.4g} propositions evaluated on average in phase order; "
            f"{tree}, entropy bound {self.entropy:.4g} "
            f"(log2 {self.classes} classes = {self.log2_classes:.4g}), test-all {self.test_all}"
        )
        return f"{text} ({self.note})" if self.note else text

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary."""
        return {
            "classes": self.classes,
            "n": self.n,
            "lazy": self.lazy,
            "optimal": self.optimal,
            "optimal_lower": self.optimal_lower,
            "optimal_upper": self.optimal_upper,
            "method": self.method,
            "entropy": self.entropy,
            "log2_classes": self.log2_classes,
            "test_all": self.test_all,
            "note": self.note,
        }


# --------------------------------------------------------------------------- bounds


def huffman_bound(weights: Sequence[float]) -> float:
    """The least expected depth of a binary code for symbols of these weights (normalised).

    Every answer alive in a state needs a leaf of the decision tree; keeping, for each answer,
    only its shallowest leaf gives a prefix code, so the tree costs at least the Huffman code
    of the answers' weights (zero-weight answers such as a gap included). This bound is never
    below the entropy and is at least 1 whenever two answers are alive.

    Examples
    --------
    >>> huffman_bound([1, 1, 1, 1]), huffman_bound([3, 1]), huffman_bound([5, 0])
    (2.0, 1.0, 1.0)
    """
    total = float(sum(weights))
    if len(weights) <= 1 or total <= 0:
        return 0.0
    heap = [float(w) for w in weights]
    heapq.heapify(heap)
    cost = 0.0
    while len(heap) > 1:
        merged = heapq.heappop(heap) + heapq.heappop(heap)
        cost += merged
        heapq.heappush(heap, merged)
    return cost / total


def _entropy(weights: Sequence[float]) -> float:
    total = float(sum(weights))
    if total <= 0:
        return 0.0
    h = -sum(w / total * math.log2(w / total) for w in weights if w > 0)
    return max(0.0, h)


# --------------------------------------------------------------------------- the phase order


def lazy_expectation(kb: Knowledge, order: Sequence[str] | None = None) -> float:
    """The exact expected number of propositions ``decide`` asks in ``order`` (default: the
    phase order), under the uniform prior over the classes' minterms.

    For a weighted minterm x, the proposition at position k is asked iff (a) the values of
    the earlier propositions leave more than one answer possible and (b) the connections do
    not force it. Both are functions of the prefix p = x[order[:k]] only:

    * (a) fails iff, for some class i, every completion of p in r(L) belongs to class i:
      ``D_k = ∨ᵢ ∀ order[k:] (¬r ∨ Oᵢ)``;
    * (b) holds iff p extends in r(L) with both values of ``order[k]``:
      ``F_k = E|order[k]=1 ∧ E|order[k]=0`` with ``E = ∃ order[k+1:] r``.

    So the expectation is ``Σ_k |W ∧ ¬D_k ∧ F_k| / |W|`` (W the weighted minterms), n BDD
    counts after K·n single-variable quantifications: no enumeration of prefixes.
    """
    bdd = kb.bdd
    order = tuple(order if order is not None else kb.order)
    weighted: Node = bdd.false
    for owned in kb.owned_bdds:
        weighted |= owned
    total = kb.count(weighted)
    if total == 0:
        return 0.0
    alone = [~kb.r | owned for owned in kb.owned_bdds if owned != bdd.false]
    rest = kb.r  # ∃ order[k+1:] r during step k
    asked = 0
    for name in reversed(order):
        free = bdd.let({name: True}, rest) & bdd.let({name: False}, rest)
        alone = [bdd.forall([name], u) for u in alone]
        decided = bdd.false
        for u in alone:
            decided |= u
        asked += kb.count(weighted & ~decided & free)
        rest = bdd.exist([name], rest)
    return float(Fraction(asked, total))


# --------------------------------------------------------------------------- optimal tree


def _touched(kb: Knowledge) -> list[Group]:
    """The groups some class mentions; the others only scale every class's weight."""
    support: set[str] = set()
    for c in kb.class_bdds:
        support |= kb.bdd.support(c)
    return [g for g in kb.groups if support & set(g.ids)]


def optimal_ternary(kb: Knowledge) -> float:
    """The optimal tree's expected cost by dynamic programming over every partial assignment
    of the propositions the classes depend on (3ᵐ patterns, m of them).

    The cost of a set of minterms depends on the set only; a pattern's set is its
    completions in r(L). A pattern is a leaf when at most one answer is possible or nothing
    it holds has weight; otherwise its cost is the least, over its unknown propositions that
    both values leave possible, of ``1 + (w₀·c₀ + w₁·c₁) / w``. Patterns are solved in order
    of their number of unknowns, vectorised with numpy.
    """
    K = len(kb.classes)
    groups = _touched(kb)
    names = [v for g in groups for v in g.ids]
    m = len(names)
    size = 1 << m
    ints = np.arange(size, dtype=np.int64)
    cols = {v: ((ints >> (m - 1 - i)) & 1).astype(bool) for i, v in enumerate(names)}
    # A class may mention a proposition outside the support of its function (``B & (A | ~A)``
    # depends on B only): its value there changes nothing, so any constant column will do.
    absent = np.zeros(size, dtype=bool)
    for cls in kb.rules.classes:
        for v in expr_names(cls.expr):
            cols.setdefault(v, absent)

    def evaluate(expr: Any) -> np.ndarray[Any, Any]:
        return evaluate_columns(expr, cols, size)

    ok = np.ones(size, dtype=bool)
    for g in groups:
        for k in g.connections:
            ok &= evaluate(kb.rules.connections[k].expr)
    label = np.full(size, K, dtype=np.int64)
    for i in range(K - 1, -1, -1):  # the first class in file order takes a shared minterm
        label[evaluate(kb.rules.classes[i].expr)] = i
    masks = np.where(ok, np.left_shift(np.int64(1), label), 0).astype(np.int64)
    weights = (ok & (label < K)).astype(np.float64)
    answers = ternary_closure(masks, m, np.bitwise_or)
    weight = ternary_closure(weights, m, np.add)
    total = 3**m
    pattern = np.arange(total, dtype=np.int64)
    powers = [3 ** (m - 1 - i) for i in range(m)]
    unknown = np.zeros((m, total), dtype=bool)
    for i, p in enumerate(powers):
        unknown[i] = (pattern // p) % 3 == 2
    leaf = (answers & (answers - 1) == 0) | (weight == 0)
    level = unknown.sum(axis=0)
    cost = np.zeros(total, dtype=np.float64)
    inner = np.flatnonzero(~leaf)
    inner = inner[np.argsort(level[inner], kind="stable")]
    bounds = np.searchsorted(level[inner], np.arange(m + 2))
    for u in range(1, m + 1):
        todo = inner[bounds[u] : bounds[u + 1]]
        if not todo.size:
            continue
        best = np.full(todo.size, np.inf)
        for i, p in enumerate(powers):
            sel = unknown[i, todo]
            sub = todo[sel]
            i0, i1 = sub - 2 * p, sub - p
            cand = 1.0 + (weight[i0] * cost[i0] + weight[i1] * cost[i1]) / weight[sub]
            cand[(answers[i0] == 0) | (answers[i1] == 0)] = np.inf
            best[sel] = np.minimum(best[sel], cand)
        cost[todo] = best
    return float(cost[total - 1])


class _Budget(Exception):
    pass


def optimal_bdd(
    kb: Knowledge,
    upper: float,
    max_work: int | None = None,
    max_seconds: float | None = None,
) -> float | None:
    """The optimal tree's expected cost by depth-first branch and bound over BDD states.

    A state is the tuple of the answers' functions restricted by the values seen (the
    propositions of groups no class mentions quantified away: they scale every weight
    alike); children are tried in order of their Huffman bounds, exact values and lower
    bounds are memoised, and ``upper`` (the cost of a known tree, such as the phase
    order's) prunes from the start. Returns None when more than ``max_work`` BDD
    restrictions or ``max_seconds`` (defaults :data:`MAX_WORK`, :data:`MAX_SECONDS`) would
    be needed.
    """
    budget = MAX_WORK if max_work is None else max_work
    limit = MAX_SECONDS if max_seconds is None else max_seconds
    deadline = math.inf if limit is None else time.perf_counter() + limit
    bdd = kb.bdd
    false = bdd.false
    groups = _touched(kb)
    names = [v for g in groups for v in g.ids]
    others = [v for v in kb.ids if v not in set(names)]
    nvars = len(names)
    K = len(kb.classes)

    def project(f: Node) -> Node:
        return bdd.exist(others, f) if others else f

    root = tuple(project(f) for f in (*kb.owned_bdds, kb.gap_bdd))
    counts: dict[Node, float] = {false: 0.0}
    info: dict[tuple[Node, ...], tuple[float, float]] = {}
    work = 0

    def analyse(s: tuple[Node, ...]) -> tuple[float, float]:
        """(weight, lower bound); a leaf has bound -1."""
        hit = info.get(s)
        if hit is not None:
            return hit
        ws = []
        for f in s[:K]:
            w = counts.get(f)
            if w is None:
                w = counts[f] = model_count(bdd, f, nvars)
            ws.append(w)
        alive = [w for w, f in zip(ws, s, strict=False) if f != false]
        if s[K] != false:
            alive.append(0.0)
        total = sum(ws)
        result = (total, -1.0 if len(alive) <= 1 or total == 0 else huffman_bound(alive))
        info[s] = result
        return result

    exact: dict[tuple[Node, ...], float] = {}
    lower: dict[tuple[Node, ...], float] = {}

    def bound(s: tuple[Node, ...]) -> float:
        if s in exact:
            return exact[s]
        return max(lower.get(s, 0.0), analyse(s)[1], 0.0)

    def go(s: tuple[Node, ...], ub: float) -> float:
        # the cost of s if it is below ub; otherwise a lower bound that is >= ub
        nonlocal work
        if analyse(s)[1] < 0:
            return 0.0
        if s in exact:
            return exact[s]
        lb = bound(s)
        if lb >= ub:
            return lb
        support: set[str] = set()
        for f in s:
            if f != false:
                support |= bdd.support(f)
        options = []
        for name in sorted(support):
            work += 2 * len(s)
            if work > budget or (work & 1023 < 2 * len(s) and time.perf_counter() > deadline):
                raise _Budget
            s0 = tuple(f if f == false else bdd.let({name: False}, f) for f in s)
            s1 = tuple(f if f == false else bdd.let({name: True}, f) for f in s)
            if s0 == s or s1 == s:
                continue
            w0, w1 = analyse(s0)[0], analyse(s1)[0]
            b0, b1 = bound(s0), bound(s1)
            options.append((1.0 + (w0 * b0 + w1 * b1) / (w0 + w1), name, s0, s1, w0, w1, b1))
        options.sort(key=lambda o: (o[0], o[1]))
        best = math.inf
        for first, _, s0, s1, w0, w1, b1 in options:
            limit = min(ub, best)
            if first >= limit - 1e-12:
                break
            w = w0 + w1
            c0 = 0.0
            if w0 > 0:
                c0 = go(s0, ((limit - 1.0) * w - w1 * b1) / w0)
                if 1.0 + (w0 * c0 + w1 * b1) / w >= limit - 1e-12:
                    continue
            c1 = 0.0
            if w1 > 0:
                c1 = go(s1, ((limit - 1.0) * w - w0 * c0) / w1)
            best = min(best, 1.0 + (w0 * c0 + w1 * c1) / w)
        if best < ub:
            exact[s] = best
            return best
        lower[s] = max(lb, ub)
        return lower[s]

    try:
        value = go(root, upper + 1e-9 * max(1.0, upper))
    except _Budget:
        return None
    return min(value, upper)


def _class_order(kb: Knowledge) -> list[str]:
    """The phase order with the propositions most classes mention first (stable): another
    fixed order whose lazy cost bounds the optimum from above."""
    mentions: dict[str, int] = dict.fromkeys(kb.ids, 0)
    for rc in kb.rules.classes:
        for name in names(rc.expr):
            mentions[name] += 1
    return sorted(kb.order, key=lambda v: -mentions[v])


def economy(kb: Knowledge) -> Economy:
    """The economy figures of a compiled rule set (see the module docstring)."""
    K = len(kb.classes)
    weights = [float(kb.count(f)) for f in kb.owned_bdds]
    entropy = _entropy(weights)
    lazy = lazy_expectation(kb)
    alive = [w for w in weights if w > 0]
    if kb.gap_bdd != kb.bdd.false:
        alive.append(0.0)
    lower = max(entropy, huffman_bound(alive)) if sum(weights) > 0 else 0.0
    upper = lazy
    optimal: float | None = None
    method = "bounds"
    note = ""
    if K > MAX_CLASSES:
        note = f"optimal tree: more than {MAX_CLASSES} classes"
    elif lower >= lazy - 1e-12:
        optimal, method = lazy, "lower bound met"  # the phase order is optimal
    elif sum(len(g.ids) for g in _touched(kb)) <= TERNARY_MAX_N:
        optimal, method = optimal_ternary(kb), "ternary"
    else:
        upper = min(upper, lazy_expectation(kb, _class_order(kb)))
        optimal = optimal_bdd(kb, upper)
        method = "branch and bound"
        if optimal is None:
            method = "bounds"
            note = f"optimal tree: exact search over its budget of {MAX_WORK} BDD restrictions" + (
                f" or {MAX_SECONDS} s" if MAX_SECONDS is not None else ""
            )
    if optimal is not None:
        lower = upper = optimal
    return Economy(
        classes=K,
        n=kb.n,
        lazy=lazy,
        optimal=optimal,
        entropy=entropy,
        log2_classes=math.log2(K) if K else 0.0,
        test_all=kb.n,
        optimal_lower=lower,
        optimal_upper=upper,
        method=method,
        note=note,
    )
