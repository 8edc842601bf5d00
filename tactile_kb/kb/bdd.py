"""The binary decision diagrams behind r(L): one shared manager and the algorithms over it.

Each connection and class of a rule file becomes a BDD (dd, with CUDD where its wheel carries
it, the pure-Python ``dd.autoref`` otherwise). Counting is exact at any size, models are
enumerated in binary order, and :func:`isop` computes an irredundant sum of products
(Minato–Morreale) for printing.

Examples
--------
>>> from tactile_kb.kb.expr import parse_expr
>>> bdd = manager()
>>> bdd.declare("A", "B")
>>> u = expr_to_bdd(bdd, parse_expr("A -> B"))
>>> exact_count(bdd, u, ["A", "B"]), list(iter_minterms(bdd, u, ["A", "B"]))
(3, ['00', '01', '11'])
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from tactile_kb.kb.expr import Expr, fold
from tactile_kb.kb.notation import Cube, Sop

try:  # CUDD where the wheel carries it, the pure-Python implementation otherwise
    from dd import cudd as _dd
except ImportError:  # pragma: no cover - the PyPI wheel carries CUDD on this platform
    from dd import autoref as _dd

__all__ = [
    "BACKEND",
    "Node",
    "exact_count",
    "expr_to_bdd",
    "isop",
    "iter_minterms",
    "manager",
    "model_count",
]

BACKEND: str = _dd.__name__
"""The dd backend in use: ``dd.cudd`` or ``dd.autoref``."""

Node = Any  # a dd BDD function (dd is untyped)

_MANAGER: Any = None


def manager() -> Any:
    """The process-wide BDD manager every knowledge base shares.

    One manager, created on first use and never freed: CUDD asserts at deallocation that no
    node is still referenced, which the garbage collector cannot guarantee when it breaks a
    reference cycle (or at interpreter exit). A proposition id is the same BDD variable in
    every rule set; results never depend on the variable order. Dynamic reordering is off.
    """
    global _MANAGER
    if _MANAGER is None:
        bdd = _dd.BDD()
        bdd.configure(reordering=False)
        if BACKEND == "dd.cudd":
            ctypes.pythonapi.Py_IncRef(ctypes.py_object(bdd))  # immortal: see above
        _MANAGER = bdd
    return _MANAGER


def expr_to_bdd(bdd: Any, expr: Expr) -> Node:
    """Build the BDD of ``expr`` with operators (the ids must be declared in ``bdd``)."""
    return fold(
        expr,
        var=bdd.var,
        const=lambda v: bdd.true if v else bdd.false,
        not_=lambda a: ~a,
        and_=lambda a, b: a & b,
        or_=lambda a, b: a | b,
        implies=lambda a, b: ~a | b,
        equiv=lambda a, b: a.equiv(b),
        xor=lambda a, b: ~a.equiv(b),
    )


def model_count(bdd: Any, u: Node, nvars: int) -> float:
    """``bdd.count(u, nvars=nvars)``, with CUDD's garbage collection held off while it counts.

    CUDD 3.0.0's ``Cudd_CountMinterm`` keeps every partial count as a constant node in the
    manager's unique table (in a local table whose references it adjusts by hand). When those
    allocations trigger a garbage collection in the middle of a count, the manager is left
    inconsistent: a later cofactor hands back a dead node without reviving it, and the next
    collection aborts the process ("dead count != deleted"). Whether one fires depends on
    everything the process-wide manager has seen, so every count of a CUDD BDD goes through
    here. Collection resumes as soon as the count ends.
    """
    if BACKEND != "dd.cudd":
        return float(bdd.count(u, nvars=nvars))
    bdd.configure(garbage_collection=False)
    try:
        return float(bdd.count(u, nvars=nvars))
    finally:
        bdd.configure(garbage_collection=True)


def exact_count(bdd: Any, u: Node, names: Sequence[str]) -> int:
    """The exact number of assignments to ``names`` (a superset of u's support) satisfying u."""
    if u == bdd.false:
        return 0
    if len(names) <= 50:  # CUDD counts in doubles: exact below 2**53
        return round(model_count(bdd, u, len(names)))
    levels = sorted(bdd.level_of_var(v) for v in names)
    memo: dict[Node, int] = {}

    def below(u: Node, k: int) -> int:
        # models of u over levels[k:], u's support within them
        if u == bdd.false:
            return 0
        if u == bdd.true:
            return 1 << (len(levels) - k)
        level = u.level
        j = k
        while levels[j] != level:
            j += 1
        key = u
        if key not in memo:
            name = bdd.var_at_level(level)
            low, high = bdd.let({name: False}, u), bdd.let({name: True}, u)
            memo[key] = below(low, j + 1) + below(high, j + 1)
        return memo[key] << (j - k)

    return below(u, 0)


def iter_minterms(bdd: Any, u: Node, names: Sequence[str]) -> Iterator[str]:
    """The models of u over ``names`` (a superset of its support) as bit strings, in
    increasing binary order of the bit strings."""
    n = len(names)
    if u == bdd.false:
        return
    stack: list[tuple[int, Node, str]] = [(0, u, "")]
    while stack:
        k, f, prefix = stack.pop()
        if f == bdd.true:
            rest = n - k
            for x in range(1 << rest):
                yield prefix + (format(x, f"0{rest}b") if rest else "")
            continue
        name = names[k]
        high = bdd.let({name: True}, f)
        low = bdd.let({name: False}, f)
        if high != bdd.false:
            stack.append((k + 1, high, prefix + "1"))
        if low != bdd.false:
            stack.append((k + 1, low, prefix + "0"))


def isop(bdd: Any, lower: Node, upper: Node, index: Mapping[str, int]) -> Sop:
    """An irredundant sum of products f with ``lower ≤ f ≤ upper`` (Minato–Morreale).

    Cubes hold ``(index[name], value)`` literals. With ``lower == upper`` the result is an
    irredundant cover of that function: no cube and no literal can be dropped.
    """
    memo: dict[tuple[Node, Node], tuple[list[Cube], Node]] = {}

    def go(lo: Node, up: Node) -> tuple[list[Cube], Node]:
        if lo == bdd.false:
            return [], bdd.false
        if up == bdd.true:
            return [()], bdd.true
        key = (lo, up)
        if key in memo:
            return memo[key]
        level = min(lo.level, up.level)
        name = bdd.var_at_level(level)
        i = index[name]
        lo0, lo1 = bdd.let({name: False}, lo), bdd.let({name: True}, lo)
        up0, up1 = bdd.let({name: False}, up), bdd.let({name: True}, up)
        c0, f0 = go(lo0 & ~up1, up0)
        c1, f1 = go(lo1 & ~up0, up1)
        rest = (lo0 & ~f0) | (lo1 & ~f1)
        cs, fs = go(rest, up0 & up1)
        x = bdd.var(name)
        cubes = [((i, False), *c) for c in c0] + [((i, True), *c) for c in c1] + cs
        result = (cubes, (~x & f0) | (x & f1) | fs)
        memo[key] = result
        return result

    cubes, _ = go(lower, upper)
    return tuple(tuple(sorted(c)) for c in cubes)
