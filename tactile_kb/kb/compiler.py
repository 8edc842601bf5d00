"""Compile a rule file into its r(L) models: BDDs for the connections, printed class terms.

The paper (eq. 2) forms s(L), the disjunction of all 2ⁿ conjunctions of the base L; the
connections empty some of them, and the rest is the reduced disjunction r(L). Here each
connection becomes a binary decision diagram (dd, with CUDD when its wheel has it), r(L) is
their conjunction, and propositions fall into independent *groups* (the connected components
of the graph in which a connection joins the ids it mentions) whose BDDs stay separate: |r(L)|
is the product of the groups' exact counts and s(L) is never enumerated.

Each class's reduced disjunction is ``class ∧ r(L)``; it is printed as a sum of products,
minimal (sympy ``SOPform``) when the function has few variables, irredundant
(Minato–Morreale ISOP computed on the BDD) otherwise, with independent groups kept as separate
factors. The paper's cube, from its base A–G with equality connections::

    r(L) = A·B̄·C·D·Ē·F·G            L: object is cube            L = A·B̄·C·D·Ē·F·G

Examples
--------
>>> kb = compile_rules(PAPER_EXAMPLE)
>>> kb.s_size, kb.r_count
(128, 32)
>>> kb.classes[0].paper, kb.classes[0].bits
('A·B̄·C·D·Ē·F·G', ('1011011',))
>>> kb.classes[0].equation
'L = A·B̄·C·D·Ē·F·G'
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import networkx as nx

from tactile_kb.errors import Problem, RuleFileError
from tactile_kb.kb.analysis import analyse, conflicts
from tactile_kb.kb.base import KnowledgeBase
from tactile_kb.kb.bdd import Node, exact_count, expr_to_bdd, manager
from tactile_kb.kb.engine import FAST_MAX_N
from tactile_kb.kb.expr import names
from tactile_kb.kb.knowledge import CompiledClass, Group, Knowledge
from tactile_kb.kb.notation import (
    Factored,
    ascii_text,
    bit_strings,
    cube_ints,
    flat_cubes,
    paper,
)
from tactile_kb.kb.rules import PAPER_EXAMPLE, RuleSet, load_rules, parse_rules

__all__ = ["MAX_INTS", "PAPER_EXAMPLE", "compile_rules"]

MAX_INTS = 1 << 16
"""A class lists the integers of its models only when it has at most this many."""


def _groups(rules: RuleSet, bdd: Any, conns: Sequence[Node]) -> tuple[Group, ...]:
    """Independent groups: connected components of the graph joining the ids a connection names
    (networkx, which dd imports anyway; scipy stays out of the rule-file commands)."""
    ids = rules.ids
    index = {name: i for i, name in enumerate(ids)}
    members = [[index[v] for v in names(c.expr)] for c in rules.connections]
    graph = nx.Graph()
    graph.add_nodes_from(range(len(ids)))
    graph.add_edges_from((m[0], j) for m in members for j in m[1:])
    # number the components by their first proposition, in declared order
    components = sorted((sorted(c) for c in nx.connected_components(graph)), key=lambda c: c[0])
    group_of = {i: g for g, positions in enumerate(components) for i in positions}
    positions_of = dict(enumerate(components))
    conn_of: dict[int, list[int]] = {}
    for c, m in zip(rules.connections, members, strict=True):
        conn_of.setdefault(group_of[m[0]] if m else -1, []).append(c.index)
    groups: list[Group] = []
    for g, positions in sorted(positions_of.items()):
        u = bdd.true
        for k in conn_of.get(g, []):
            u &= conns[k]
        names_g = tuple(ids[i] for i in positions)
        groups.append(
            Group(
                len(groups),
                names_g,
                tuple(positions),
                tuple(conn_of.get(g, [])),
                u,
                exact_count(bdd, u, names_g),
            )
        )
    # a constant connection (no ids) joins no group: false empties r(L), true changes nothing
    for k in conn_of.get(-1, []):
        if conns[k] == bdd.false:
            groups.append(Group(len(groups), (), (), (k,), bdd.false, 0))
    return tuple(groups)


def _factors(kb: Knowledge, k: int) -> tuple[Factored, int]:
    """The class's reduced disjunction as a product of sums of products, and its count."""
    bdd = kb.bdd
    c = kb.class_bdds[k]
    support = bdd.support(c)
    touched = [g for g in kb.groups if any(v in support for v in g.ids)]
    block = c
    for g in touched:
        block &= g.bdd
    block_names = [v for g in touched for v in g.ids]
    untouched = [g for g in kb.groups if g not in touched]
    count = exact_count(bdd, block, block_names) * math.prod(g.count for g in untouched)
    if block == bdd.false:
        return ((),), 0
    parts: list[Node] = []
    if len(touched) > 1:
        product = bdd.true
        for g in touched:
            others = {v for v in block_names if v not in g.ids}
            part = bdd.exist(others, block)
            parts.append(part)
            product &= part
        if product != block:
            parts = [block]
    else:
        parts = [block]
    factors = [kb.sop(p) for p in parts]
    factors += [kb.sop(g.bdd) for g in untouched if g.bdd != bdd.true]
    return tuple(factors), count


def _compile_class(kb: Knowledge, k: int) -> CompiledClass:
    rc = kb.rules.classes[k]
    factors, count = _factors(kb, k)
    text_paper = paper(factors, kb.ids)
    ints: tuple[int, ...] = ()
    if count <= MAX_INTS:
        found: set[int] = set()
        for cube in flat_cubes(factors):
            found.update(cube_ints(cube, kb.n))
        ints = tuple(sorted(found))
    return CompiledClass(
        index=k,
        id=rc.id,
        answer=rc.answer,
        name=rc.name,
        text=rc.text,
        line=rc.line,
        count=count,
        factors=factors,
        paper=text_paper,
        ascii=ascii_text(factors, kb.ids),
        ids=kb.ids,
        bits=bit_strings(factors, kb.n),
        ints=ints,
        proposition=f"L: object is {rc.name}",
        equation=f"L = {text_paper}",
    )


def compile_rules(rules: RuleSet | str | Path, *, check: bool = True) -> KnowledgeBase:
    """Compile a rule set (or a packaged name, a path, YAML text) into a :class:`KnowledgeBase`.

    A ``str`` containing a newline is YAML text; another ``str`` is a packaged rule-set name or
    a file path (see :func:`tactile_kb.kb.rules.load_rules`).

    With ``check`` (the default) the static analysis runs: connections that leave r(L) empty
    (naming the smallest conflicting set) and dead classes raise :class:`RuleFileError` (with
    every warning too); overlaps, gaps and redundant connections become ``problems``.

    Raises
    ------
    RuleFileError
        The file does not load, or the analysis finds an error.
    """
    if isinstance(rules, str) and "\n" in rules:
        rules = parse_rules(rules)
    elif not isinstance(rules, RuleSet):
        rules = load_rules(rules)
    bdd = manager()
    bdd.declare(*rules.ids)
    conns = tuple(expr_to_bdd(bdd, c.expr) for c in rules.connections)
    groups = _groups(rules, bdd, conns)
    class_bdds = tuple(expr_to_bdd(bdd, k.expr) for k in rules.classes)
    kb = KnowledgeBase(rules, bdd, conns, groups, class_bdds)
    problems: list[Problem] = []
    if check:
        problems = conflicts(kb)
        if problems:
            raise RuleFileError(problems, _excerpt(rules, problems))
    kb.classes = tuple(_compile_class(kb, k) for k in range(len(rules.classes)))
    if check:
        problems = analyse(kb)
        if any(p.severity == "error" for p in problems):
            raise RuleFileError(problems, _excerpt(rules, problems))
        kb.problems = tuple(sorted(problems, key=lambda p: (p.line, p.column)))
    if kb.n <= FAST_MAX_N:
        _ = kb.engine  # small bases: precompute the answer sets, so classify() is fast at once
    return kb


def _excerpt(rules: RuleSet, problems: Sequence[Problem]) -> str:
    errors = [p for p in problems if p.severity == "error"] or list(problems)
    first = min(errors, key=lambda p: (p.line, p.column))
    return rules.source.excerpt(first.line, first.column)
