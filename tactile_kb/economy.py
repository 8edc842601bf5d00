"""How many propositions a classification costs: the paper's "great economy" of phases, measured.

With a uniform prior over the classes' minterms (every member of r(L) that a class takes is
equally likely; the first class in file order takes a shared one), four figures:

* ``lazy``: the expected number of propositions :meth:`~tactile_kb.engine.Engine.decide`
  asks when it goes in phase order, skips what the connections force and stops as soon as one
  answer is left;
* ``optimal``: the expected number asked by the best decision tree (any proposition may come
  next), by exact dynamic programming over the states the tests reach (None beyond
  :data:`MAX_CLASSES` classes or :data:`MAX_WORK` BDD operations; the problem is NP-complete
  in general, Hyafil & Rivest 1976);
* ``entropy``: the Shannon entropy of the class distribution, a lower bound on any tree
  (log2 K for K equally likely classes);
* ``test_all``: n, evaluating every proposition.

So ``entropy ≤ optimal ≤ lazy ≤ test_all``. Both expectations are computed exactly on BDDs
(states are the restricted class functions), never by enumerating s(L).

Examples
--------
>>> from tactile_kb.compiler import PAPER_EXAMPLE, compile_rules
>>> e = compile_rules(PAPER_EXAMPLE).economy()
>>> e.lazy, e.optimal, e.entropy, e.test_all
(5.0, 4.0, 0.0, 7)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tactile_kb.compiler import KnowledgeBase, Node

__all__ = ["MAX_CLASSES", "MAX_WORK", "Economy", "economy"]

MAX_CLASSES = 20
"""The optimal tree is computed for at most this many classes."""
MAX_WORK = 400_000
"""Budget of BDD restrictions for each of the two dynamic programmes."""


@dataclass(frozen=True)
class Economy:
    """Expected numbers of propositions evaluated per classification (see the module)."""

    classes: int
    n: int
    lazy: float | None
    optimal: float | None
    entropy: float
    log2_classes: float
    test_all: int
    note: str = ""

    @property
    def line(self) -> str:
        """The economy line printed by ``tactile-kb compile``."""

        def fmt(x: float | None) -> str:
            return "not computed" if x is None else f"{x:.4g}"

        lazy = (
            "phase-order average not computed"
            if self.lazy is None
            else f"{fmt(self.lazy)} propositions evaluated on average in phase order"
        )
        text = (
            f"economy: {lazy}; "
            f"optimal tree {fmt(self.optimal)}, entropy bound {self.entropy:.4g} "
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
            "entropy": self.entropy,
            "log2_classes": self.log2_classes,
            "test_all": self.test_all,
            "note": self.note,
        }


class _Budget(Exception):
    pass


class _Solver:
    def __init__(self, kb: KnowledgeBase) -> None:
        self.kb = kb
        self.bdd = kb.bdd
        self.K = len(kb.classes)
        self.work = 0
        self.counts: dict[Node, float] = {}

    def weight(self, state: Sequence[Node]) -> float:
        total = 0.0
        for f in state[: self.K]:
            if f not in self.counts:
                self.counts[f] = float(self.bdd.count(f, nvars=self.kb.n))
            total += self.counts[f]
        return total

    def entropy(self, state: Sequence[Node]) -> float:
        self.weight(state)
        ws = [self.counts[f] for f in state[: self.K]]
        total = sum(ws)
        if total == 0:
            return 0.0
        return max(0.0, -sum(w / total * math.log2(w / total) for w in ws if w > 0))

    def alive(self, state: Sequence[Node]) -> int:
        return sum(f != self.bdd.false for f in state)

    def split(self, state: tuple[Node, ...], name: str) -> tuple[tuple[Node, ...], ...]:
        self.work += 2 * len(state)
        if self.work > MAX_WORK:
            raise _Budget
        let = self.bdd.let
        return (
            tuple(let({name: False}, f) for f in state),
            tuple(let({name: True}, f) for f in state),
        )

    def union(self, state: Sequence[Node]) -> Node:
        u = self.bdd.false
        for f in state:
            u |= f
        return u

    def lazy(self, order: Sequence[str], state: tuple[Node, ...]) -> float:
        memo: dict[tuple[int, tuple[Node, ...]], float] = {}
        bdd = self.bdd

        def go(k: int, s: tuple[Node, ...]) -> float:
            if self.alive(s) <= 1 or self.weight(s) == 0:
                return 0.0
            key = (k, s)
            if key in memo:
                return memo[key]
            u = self.union(s)
            while True:  # skip what the connections force, as decide() does
                x = bdd.var(order[k])
                if u & x == bdd.false or u & ~x == bdd.false:
                    k += 1
                    continue
                break
            s0, s1 = self.split(s, order[k])
            w0, w1 = self.weight(s0), self.weight(s1)
            value = 1.0 + (w0 * go(k + 1, s0) + w1 * go(k + 1, s1)) / (w0 + w1)
            memo[key] = value
            return value

        return go(0, state)

    def optimal(self, state: tuple[Node, ...]) -> float:
        """Exact expected cost of the best tree: depth-first branch and bound over states,
        children ordered by their entropy bound, with exact values and lower bounds memoised."""
        exact: dict[tuple[Node, ...], float] = {}
        lower: dict[tuple[Node, ...], float] = {}
        bdd = self.bdd

        def go(s: tuple[Node, ...], ub: float) -> float:
            # the cost of s if it is below ub; otherwise a lower bound that is >= ub
            if self.alive(s) <= 1 or self.weight(s) == 0:
                return 0.0
            if s in exact:
                return exact[s]
            lb = max(lower.get(s, 0.0), self.entropy(s))
            if lb >= ub:
                return lb
            names: set[str] = set()
            for f in s:
                names |= bdd.support(f)
            options = []
            for name in sorted(names, key=self.kb.index.__getitem__):
                s0, s1 = self.split(s, name)
                if s0 == s or s1 == s:
                    continue
                w0, w1 = self.weight(s0), self.weight(s1)
                if w0 + w1 == 0:
                    continue
                b0 = max(lower.get(s0, 0.0), self.entropy(s0))
                b1 = max(lower.get(s1, 0.0), self.entropy(s1))
                bound = 1.0 + (w0 * b0 + w1 * b1) / (w0 + w1)
                options.append((bound, name, s0, s1, w0, w1, b1))
            options.sort(key=lambda o: o[0])
            best = math.inf
            for bound, _, s0, s1, w0, w1, b1 in options:
                limit = min(ub, best)
                if bound >= limit - 1e-12:
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
                cost = 1.0 + (w0 * c0 + w1 * c1) / w
                best = min(best, cost)
            if best < ub:
                exact[s] = best
                return best
            bound_s = max(lb, ub)
            lower[s] = bound_s
            return bound_s

        return go(state, math.inf)


def economy(kb: KnowledgeBase) -> Economy:
    """The economy figures of a compiled rule set (see the module docstring)."""
    K = len(kb.classes)
    weights = [float(kb.count(f)) for f in kb.owned_bdds]
    total = sum(weights)
    entropy = 0.0
    if total > 0:
        entropy = -sum(w / total * math.log2(w / total) for w in weights if w > 0)
        entropy = max(0.0, entropy)
    state = (*kb.owned_bdds, kb.gap_bdd)
    notes = []
    solver = _Solver(kb)
    lazy: float | None
    try:
        lazy = solver.lazy(kb.engine.order, state)
    except _Budget:
        lazy = None
        notes.append(f"lazy: over {MAX_WORK} BDD operations")
    optimal: float | None = None
    if K > MAX_CLASSES:
        notes.append(f"optimal tree: more than {MAX_CLASSES} classes")
    else:
        solver = _Solver(kb)
        try:
            optimal = solver.optimal(state)
        except _Budget:
            notes.append(f"optimal tree: over {MAX_WORK} BDD operations")
    return Economy(
        classes=K,
        n=kb.n,
        lazy=lazy,
        optimal=optimal,
        entropy=entropy,
        log2_classes=math.log2(K) if K else 0.0,
        test_all=kb.n,
        note="; ".join(notes),
    )
