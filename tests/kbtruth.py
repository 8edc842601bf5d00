"""Ground truth for the knowledge-base tests: truth tables enumerated with numpy.

Independent of the BDD compiler: every expression is evaluated on all 2ⁿ rows by
``tactile_kb.kb.expr.fold`` with numpy operations.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tactile_kb.kb.expr import Expr, fold, parse_expr
from tactile_kb.kb.rules import RuleSet


def rows(n: int) -> np.ndarray[Any, Any]:
    """All 2ⁿ assignments, row r = the bits of r with the first proposition most significant."""
    r = np.arange(1 << n, dtype=np.int64)
    return ((r[:, None] >> np.arange(n - 1, -1, -1)) & 1).astype(bool)


def table(expr: Expr | str, ids: tuple[str, ...]) -> np.ndarray[Any, Any]:
    """The truth table of ``expr`` over ``ids`` (length 2ⁿ)."""
    if isinstance(expr, str):
        expr = parse_expr(expr)
    grid = rows(len(ids))
    cols = {name: grid[:, i] for i, name in enumerate(ids)}
    size = grid.shape[0]
    out = fold(
        expr,
        var=lambda name: cols[name],
        const=lambda v: np.full(size, v),
        not_=lambda a: ~a,
        and_=lambda a, b: a & b,
        or_=lambda a, b: a | b,
    )
    return np.broadcast_to(out, (size,)).copy()


def r_table(rules: RuleSet) -> np.ndarray[Any, Any]:
    """The truth table of r(L): every connection holds."""
    ok = np.ones(1 << len(rules.ids), dtype=bool)
    for c in rules.connections:
        ok &= table(c.expr, rules.ids)
    return ok


def labels(rules: RuleSet) -> np.ndarray[Any, Any]:
    """The expected answer index of every row: first class in file order, K otherwise, -1
    when a connection is broken."""
    K = len(rules.classes)
    out = np.full(1 << len(rules.ids), K, dtype=np.int64)
    for i in range(K - 1, -1, -1):
        out[table(rules.classes[i].expr, rules.ids)] = i
    out[~r_table(rules)] = -1
    return out


def bits(row: int, n: int) -> str:
    return format(row, f"0{n}b") if n else ""
