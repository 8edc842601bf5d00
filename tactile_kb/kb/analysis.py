"""Static checks of a compiled rule set, each a BDD operation, reported at file lines.

========================  =====================================  ========
check                     condition (u = r(L), cᵢ = class i)     severity
========================  =====================================  ========
conflicting connections   u = ⊥; names a smallest conflicting    error
                          set (python-sat OptUx)
dead class                cᵢ ∧ u = ⊥                             error
overlapping classes       cᵢ ∧ cⱼ ∧ u ≠ ⊥ (a witness minterm)    warning
gap                       u ∧ ¬(c₁ ∨ … ∨ c_K) ≠ ⊥ (count, example) warning
redundant connection      the others already imply it            warning
========================  =====================================  ========

Examples
--------
>>> from tactile_kb.kb.compiler import compile_rules
>>> from tactile_kb.kb.rules import PAPER_EXAMPLE
>>> text = PAPER_EXAMPLE.replace("  - ~(D & E)", "  - ~(D & E)\\n  - F -> ~E")
>>> kb = compile_rules(text)
>>> for p in kb.problems:
...     print(p)
<string>:15:5: warning: connections[3]: redundant: already implied by line 13 (F -> D), line 14 (~(D & E))
<string>:27:3: warning: otherwise: a gap: 31 of the 32 members of r(L) satisfy no class (for example 0010000); they get the answer OBJECT IS NOT RECOGNISED
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pysat.examples.optux import OptUx
from pysat.formula import WCNF, IDPool

from tactile_kb.errors import Problem
from tactile_kb.kb.bdd import Node, iter_minterms
from tactile_kb.kb.expr import Expr, fold
from tactile_kb.kb.knowledge import Knowledge
from tactile_kb.kb.rules import Connection, RuleSet
from tactile_kb.yaml_source import format_path

__all__ = ["analyse", "conflicts", "minimal_conflict", "smallest_conflict"]


def _at_connection(rules: RuleSet, c: Connection, message: str, severity: str = "error") -> Problem:
    path = format_path(c.path) if c.path else f"connections[{c.index}]"
    if severity == "warning":
        return Problem(rules.file, c.line, c.column, path, message, "warning")
    return Problem(rules.file, c.line, c.column, path, message)


def _cite(rules: RuleSet, indices: Sequence[int]) -> str:
    return ", ".join(
        f"line {rules.connections[k].line} ({rules.connections[k].text})" for k in indices
    )


# --------------------------------------------------------------------------- conflicts


def _tseitin(expr: Expr, pool: IDPool, clauses: list[list[int]]) -> int:
    """A literal equivalent to ``expr`` under the definitional ``clauses`` appended."""

    def fresh() -> int:
        return int(pool.id(("t", len(pool.obj2id))))

    def const(v: bool) -> int:
        t = fresh()
        clauses.append([t] if v else [-t])
        return t

    def and_(a: int, b: int) -> int:
        t = fresh()
        clauses.extend([[-t, a], [-t, b], [t, -a, -b]])
        return t

    def or_(a: int, b: int) -> int:
        t = fresh()
        clauses.extend([[t, -a], [t, -b], [-t, a, b]])
        return t

    def equiv(a: int, b: int) -> int:
        t = fresh()
        clauses.extend([[-t, -a, b], [-t, a, -b], [t, a, b], [t, -a, -b]])
        return t

    lit: int = fold(
        expr,
        var=lambda name: int(pool.id(("v", name))),
        const=const,
        not_=lambda a: -a,
        and_=and_,
        or_=or_,
        implies=lambda a, b: or_(-a, b),
        equiv=equiv,
        xor=lambda a, b: -equiv(a, b),
    )
    return lit


def smallest_conflict(exprs: Sequence[Expr]) -> list[int]:
    """Indices of a smallest subset of ``exprs`` whose conjunction is unsatisfiable.

    Each expression is encoded (Tseitin) behind a selector; python-sat's OptUx finds a
    minimum-size unsatisfiable core over the selectors. ``[]`` if the set is satisfiable.
    """
    pool = IDPool()
    hard: list[list[int]] = []
    selectors = []
    for k, e in enumerate(exprs):
        lit = _tseitin(e, pool, hard)
        s = int(pool.id(("s", k)))
        hard.append([-s, lit])
        selectors.append(s)
    wcnf = WCNF()
    for clause in hard:
        wcnf.append(clause)
    for s in selectors:
        wcnf.append([s], weight=1)
    from pysat.solvers import Solver

    with Solver(name="g3", bootstrap_with=hard) as solver:
        if solver.solve(assumptions=selectors):
            return []
    with OptUx(wcnf) as optux:
        core = optux.compute()
    return sorted(int(i) - 1 for i in core)


def minimal_conflict(bdd: Any, base: Node, parts: Sequence[Node]) -> list[int]:
    """Deletion-based minimal subset of ``parts`` whose conjunction with ``base`` is ⊥."""
    keep = list(range(len(parts)))
    for k in list(keep):
        trial = base
        for j in keep:
            if j != k:
                trial &= parts[j]
        if trial == bdd.false:
            keep.remove(k)
    return keep


def conflicts(kb: Knowledge) -> list[Problem]:
    """Errors for connections that leave r(L) empty, naming a smallest conflicting set."""
    rules, bdd = kb.rules, kb.bdd
    problems = []
    for g in kb.groups:
        if g.bdd != bdd.false:
            continue
        members = list(g.connections)
        core = [members[i] for i in smallest_conflict([rules.connections[k].expr for k in members])]
        first = rules.connections[core[0]]
        if len(core) == 1:
            msg = f"connection {first.text!r} can never hold: r(L) is empty"
        else:
            msg = f"conflicting connections leave r(L) empty: {_cite(rules, core)}"
        problems.append(_at_connection(rules, first, msg))
    return problems


# --------------------------------------------------------------------------- the other checks


def _class_problem(kb: Knowledge, k: int, message: str, severity: str) -> Problem:
    rc = kb.rules.classes[k]
    path = rc.path or ("classes", k, "when")
    return kb.rules.source.problem(path, message, severity=severity, offset=0)


def _dead(kb: Knowledge, k: int) -> Problem:
    bdd, rules = kb.bdd, kb.rules
    rc = rules.classes[k]
    c = kb.class_bdds[k]
    if c == bdd.false:
        why = "its condition can never hold"
    else:
        core = minimal_conflict(bdd, c, kb.connection_bdds)
        why = f"it contradicts {_cite(rules, core)}"
    return _class_problem(
        kb, k, f"class {rc.id!r} is dead: no member of r(L) satisfies it; {why}", "error"
    )


def _redundant(kb: Knowledge) -> list[Problem]:
    bdd, rules = kb.bdd, kb.rules
    problems = []
    for g in kb.groups:
        active = list(g.connections)
        for k in reversed(g.connections):  # the later of two equivalent connections goes
            conn = kb.connection_bdds[k]
            others = [j for j in active if j != k]
            rest = bdd.true
            for j in others:
                rest &= kb.connection_bdds[j]
            if rest & ~conn != bdd.false:
                continue
            active.remove(k)
            c = rules.connections[k]
            if conn == bdd.true:
                msg = "redundant: it always holds"
            else:
                parts = [kb.connection_bdds[j] for j in others]
                needed = minimal_conflict(bdd, ~conn, parts)
                msg = f"redundant: already implied by {_cite(rules, [others[i] for i in needed])}"
            problems.append(_at_connection(rules, c, msg, "warning"))
    return problems


def analyse(kb: Knowledge) -> list[Problem]:
    """Dead classes (errors), overlapping classes, gaps and redundant connections (warnings).

    Run after :func:`conflicts` found r(L) non-empty; :func:`~tactile_kb.kb.compiler.compile_rules`
    runs both.
    """
    bdd, rules = kb.bdd, kb.rules
    problems = conflicts(kb)
    if problems:
        return problems
    models = kb.model_bdds
    for k, m in enumerate(models):
        if m == bdd.false:
            problems.append(_dead(kb, k))
    for j in range(len(models)):
        for i in range(j):
            both = models[i] & models[j]
            if both == bdd.false:
                continue
            witness = next(iter_minterms(bdd, both, kb.ids))
            first, second = rules.classes[i], rules.classes[j]
            count = kb.count(both)
            others = "" if count == 1 else f" and {count - 1} more"
            msg = (
                f"class {second.id!r} overlaps class {first.id!r} (line {first.line}): both take "
                f"{witness}{others}; {first.id!r}, first in the file, wins"
            )
            problems.append(_class_problem(kb, j, msg, "warning"))
    if kb.gap_bdd != bdd.false:
        example = next(iter_minterms(bdd, kb.gap_bdd, kb.ids))
        count = kb.count(kb.gap_bdd)
        msg = (
            f"a gap: {count} of the {kb.r_count} members of r(L) satisfy no class "
            f"(for example {example}); they get the answer {rules.otherwise_answer}"
        )
        problems.append(rules.source.problem(("otherwise",), msg, severity="warning"))
    problems.extend(_redundant(kb))
    return problems
