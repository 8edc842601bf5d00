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

import ctypes
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from tactile_kb.errors import Problem, RuleFileError, UsageError
from tactile_kb.expr import Expr, fold
from tactile_kb.notation import (
    Cube,
    Factored,
    Sop,
    ascii_text,
    bit_strings,
    cube_ints,
    flat_cubes,
    paper,
    sop_from_sympy,
    to_sympy,
)
from tactile_kb.rules import RuleSet, load_rules, parse_rules

if TYPE_CHECKING:
    import sympy

    from tactile_kb.economy import Economy
    from tactile_kb.engine import Decision, Engine

try:  # CUDD where the wheel carries it, the pure-Python implementation otherwise
    from dd import cudd as _dd
except ImportError:  # pragma: no cover - the PyPI wheel carries CUDD on this platform
    from dd import autoref as _dd

__all__ = [
    "BACKEND",
    "EXACT_LIMIT",
    "MAX_INTS",
    "PAPER_EXAMPLE",
    "CompiledClass",
    "Group",
    "KnowledgeBase",
    "compile_rules",
    "exact_count",
    "expr_to_bdd",
    "isop",
    "iter_minterms",
    "manager",
]

BACKEND: str = _dd.__name__
"""The dd backend in use: ``dd.cudd`` or ``dd.autoref``."""

EXACT_LIMIT = 10
"""Functions of at most this many variables (and :data:`EXACT_MAX_MINTERMS` models) get an
exact minimal sum of products; larger ones an irredundant one."""
EXACT_MAX_MINTERMS = 96
MAX_INTS = 1 << 16
"""A class lists the integers of its models only when it has at most this many."""

Node = Any  # a dd BDD function (dd is untyped)

PAPER_EXAMPLE = """\
name: paper-example
description: The paper's base A–G, its phases I–V and its cube (eq. 3–5).
propositions:
  - {id: A, text: There is contact between the object and the finger}
  - {id: B, text: Surface is curved}
  - {id: C, text: Surface is plane}
  - {id: D, text: Vertical edges are parallel}
  - {id: E, text: '"Vertical" edges join at one point'}
  - {id: F, text: Three pairs of parallel faces exist}
  - {id: G, text: Distances between neighbouring vertices are equal}
connections:
  - B = ~C
  - F -> D
  - ~(D & E)
phases:
  - {id: I, propositions: [A]}
  - {id: II, propositions: [B, C]}
  - {id: III, propositions: [D, E]}
  - {id: IV, propositions: [F]}
  - {id: V, propositions: [G]}
classes:
  - id: cube
    answer: OBJECT IS A CUBE
    when: A & ~B & C & D & ~E & F & G
otherwise:
  id: unknown
  answer: OBJECT IS NOT RECOGNISED
"""
"""The paper's base A–G as a rule file (the cube only); used by examples and tests."""


# --------------------------------------------------------------------------- BDD helpers

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


def exact_count(bdd: Any, u: Node, names: Sequence[str]) -> int:
    """The exact number of assignments to ``names`` (a superset of u's support) satisfying u."""
    if u == bdd.false:
        return 0
    if len(names) <= 50:  # CUDD counts in doubles: exact below 2**53
        total: float = bdd.count(u, nvars=len(names))
        return round(total)
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


# --------------------------------------------------------------------------- results


@dataclass(frozen=True, eq=False)
class Group:
    """Propositions tied together by connections (a connected component), with its BDD."""

    index: int
    ids: tuple[str, ...]
    positions: tuple[int, ...]
    connections: tuple[int, ...]
    bdd: Node
    count: int


@dataclass(frozen=True, eq=False)
class CompiledClass:
    """One class of a compiled rule set: its reduced disjunction ``class ∧ r(L)``.

    ``paper``/``ascii`` print it as a sum of products (independent groups as separate
    parenthesised factors), ``bits`` are its cubes multiplied out (``-`` free), ``ints`` the
    integers of its models (empty when there are more than :data:`MAX_INTS`), ``count`` the
    exact number of its models, ``proposition`` and ``equation`` the paper's eq. 4 and 5.
    """

    index: int
    id: str
    answer: str
    name: str
    text: str
    line: int
    count: int
    factors: Factored
    paper: str
    ascii: str
    ids: tuple[str, ...] = field(repr=False)
    """The propositions in declared order (the indices of :attr:`factors`)."""
    bits: tuple[str, ...]
    ints: tuple[int, ...]
    proposition: str
    equation: str

    @cached_property
    def expr(self) -> Any:
        """The reduced disjunction as a sympy Boolean (sympy is imported on first use)."""
        import sympy

        return to_sympy(self.factors, tuple(sympy.Symbol(name) for name in self.ids))

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary."""
        return {
            "id": self.id,
            "answer": self.answer,
            "name": self.name,
            "when": self.text,
            "line": self.line,
            "count": self.count,
            "paper": self.paper,
            "ascii": self.ascii,
            "bits": list(self.bits),
            "ints": list(self.ints),
            "proposition": self.proposition,
            "equation": self.equation,
        }


class KnowledgeBase:
    """A compiled rule set: r(L) as factored BDDs, the classes' terms, the engine.

    Build it with :func:`compile_rules`. ``n`` propositions in declared order ``ids``;
    ``s_size`` is 2ⁿ; ``r_count`` the exact |r(L)|; ``classes`` the compiled classes in file
    order; ``problems`` the analysis warnings (errors raise :class:`RuleFileError`).
    """

    def __init__(
        self,
        rules: RuleSet,
        bdd: Any,
        connections: tuple[Node, ...],
        groups: tuple[Group, ...],
        class_bdds: tuple[Node, ...],
    ) -> None:
        self.rules = rules
        self.bdd = bdd
        self.ids: tuple[str, ...] = rules.ids
        self.n = len(self.ids)
        self.index: dict[str, int] = {name: i for i, name in enumerate(self.ids)}
        self.s_size = 1 << self.n
        self.connection_bdds = connections
        self.groups = groups
        self.group_of: dict[str, Group] = {name: g for g in groups for name in g.ids}
        self.r = bdd.true
        for g in groups:
            self.r &= g.bdd
        self.r_count = math.prod(g.count for g in groups)
        self.class_bdds = class_bdds
        self.model_bdds = tuple(c & self.r for c in class_bdds)
        taken = bdd.false
        owned = []
        for m in self.model_bdds:  # the first class in file order takes an overlap
            owned.append(m & ~taken)
            taken |= m
        self.owned_bdds: tuple[Node, ...] = tuple(owned)
        self.gap_bdd: Node = self.r & ~taken
        self.classes: tuple[CompiledClass, ...] = ()
        self.problems: tuple[Problem, ...] = ()
        self._sop_cache: dict[Node, Sop] = {}

    def __repr__(self) -> str:
        return (
            f"<KnowledgeBase {self.rules.name!r}: n={self.n}, |r(L)|={self.r_count}, "
            f"{len(self.classes)} classes>"
        )

    @cached_property
    def symbols(self) -> tuple[sympy.Symbol, ...]:
        """One sympy symbol per proposition, in declared order (sympy is imported here)."""
        import sympy

        return tuple(sympy.Symbol(name) for name in self.ids)

    # ----------------------------------------------------------------- models

    def count(self, u: Node) -> int:
        """The exact number of assignments to all n propositions that satisfy ``u``."""
        return exact_count(self.bdd, u, self.ids)

    def minterms(self) -> Iterator[str]:
        """The members of r(L) as bit strings in declared order, in increasing binary order."""
        return iter_minterms(self.bdd, self.r, self.ids)

    def class_minterms(self, label: str) -> Iterator[str]:
        """The models of one class's reduced disjunction (``class ∧ r(L)``)."""
        for k in self.classes:
            if k.id == label:
                return iter_minterms(self.bdd, self.model_bdds[k.index], self.ids)
        known = ", ".join(k.id for k in self.classes)
        raise UsageError(f"no class {label!r}; the classes are: {known}")

    def sop(self, f: Node, exact_limit: int = EXACT_LIMIT) -> Sop:
        """A sum of products of ``f``: minimal for few variables, irredundant otherwise."""
        cached = self._sop_cache.get(f)
        if cached is not None:
            return cached
        bdd = self.bdd
        if f == bdd.false:
            sop: Sop = ()
        elif f == bdd.true:
            sop = ((),)
        else:
            support = sorted(bdd.support(f), key=self.index.__getitem__)
            small = len(support) <= exact_limit
            if small and exact_count(bdd, f, support) <= EXACT_MAX_MINTERMS:
                syms = [self.symbols[self.index[v]] for v in support]
                rows = [[int(m[v]) for v in support] for m in bdd.pick_iter(f, care_vars=support)]
                from sympy.logic import SOPform  # exact minimisation of a small function

                expr = SOPform(syms, rows)
                sop = sop_from_sympy(expr, {s: self.index[s.name] for s in syms})
            else:
                sop = isop(bdd, f, f, self.index)
        self._sop_cache[f] = sop
        return sop

    # ----------------------------------------------------------------- engine

    @cached_property
    def engine(self) -> Engine:
        """The classification engine (built on first use)."""
        from tactile_kb.engine import Engine

        return Engine(self)

    def classify(self, assignment: Any) -> Decision:
        """Classify a full or partial assignment: a mapping id → bool, a bit string
        (``'1011011'``, ``-`` unknown) or a numpy bool array of shape (n,)."""
        return self.engine.classify(assignment)

    def classify_batch(self, assignments: Any) -> np.ndarray[Any, np.dtype[np.int16]]:
        """Class indices of an (m, n) bool array: ``len(classes)`` = otherwise, -1 = violates."""
        return self.engine.classify_batch(assignments)

    def decide(self, providers: Mapping[str, Any]) -> Decision:
        """Evaluate propositions lazily in phase order until one answer is left."""
        return self.engine.decide(providers)

    def economy(self) -> Economy:
        """Expected propositions evaluated (lazy phase order, optimal tree) and the bounds."""
        from tactile_kb.economy import economy

        return economy(self)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready summary: sizes, classes, warnings."""
        return {
            "name": self.rules.name,
            "file": self.rules.file,
            "propositions": list(self.ids),
            "n": self.n,
            "s_size": self.s_size,
            "r_count": self.r_count,
            "groups": [list(g.ids) for g in self.groups],
            "classes": [k.to_dict() for k in self.classes],
            "otherwise": {"id": self.rules.otherwise_id, "answer": self.rules.otherwise_answer},
            "warnings": [str(p) for p in self.problems],
        }


# --------------------------------------------------------------------------- compilation


def _groups(rules: RuleSet, bdd: Any, conns: Sequence[Node]) -> tuple[Group, ...]:
    from tactile_kb.expr import names

    ids = rules.ids
    parent = list(range(len(ids)))
    index = {name: i for i, name in enumerate(ids)}

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for c in rules.connections:
        members = [index[v] for v in names(c.expr)]
        for j in members[1:]:
            a, b = find(members[0]), find(j)
            if a != b:
                parent[max(a, b)] = min(a, b)
    roots: dict[int, list[int]] = {}
    for i in range(len(ids)):
        roots.setdefault(find(i), []).append(i)
    conn_of: dict[int, list[int]] = {}
    for c in rules.connections:
        members = [index[v] for v in names(c.expr)]
        root = find(members[0]) if members else -1
        conn_of.setdefault(root, []).append(c.index)
    groups: list[Group] = []
    for root, positions in sorted(roots.items()):
        u = bdd.true
        for k in conn_of.get(root, []):
            u &= conns[k]
        names_g = tuple(ids[i] for i in positions)
        groups.append(
            Group(
                len(groups),
                names_g,
                tuple(positions),
                tuple(conn_of.get(root, [])),
                u,
                exact_count(bdd, u, names_g),
            )
        )
    # a constant connection (no ids) joins no group: false empties r(L), true changes nothing
    for k in conn_of.get(-1, []):
        if conns[k] == bdd.false:
            g = Group(len(groups), (), (), (k,), bdd.false, 0)
            groups.append(g)
    return tuple(groups)


def _factors(kb: KnowledgeBase, k: int) -> tuple[Factored, int]:
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


def _compile_class(kb: KnowledgeBase, k: int) -> CompiledClass:
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
    a file path (see :func:`tactile_kb.rules.load_rules`).

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
        from tactile_kb.analysis import conflicts

        problems = conflicts(kb)
        if problems:
            raise RuleFileError(problems, _excerpt(rules, problems))
    kb.classes = tuple(_compile_class(kb, k) for k in range(len(rules.classes)))
    if check:
        from tactile_kb.analysis import analyse

        problems = analyse(kb)
        if any(p.severity == "error" for p in problems):
            raise RuleFileError(problems, _excerpt(rules, problems))
        kb.problems = tuple(sorted(problems, key=lambda p: (p.line, p.column)))
    from tactile_kb.engine import FAST_MAX_N

    if kb.n <= FAST_MAX_N:
        _ = kb.engine  # small bases: precompute the answer sets, so classify() is fast at once
    return kb


def _excerpt(rules: RuleSet, problems: Sequence[Problem]) -> str:
    errors = [p for p in problems if p.severity == "error"] or list(problems)
    first = min(errors, key=lambda p: (p.line, p.column))
    return rules.source.excerpt(first.line, first.column)
