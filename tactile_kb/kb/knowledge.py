"""A compiled rule set as plain data: r(L) as factored BDDs and the classes' printed terms.

:class:`Knowledge` is what compiling returns; it imports nothing that uses it. The engine,
the analyses, the economy and the choice tree are functions over it, and
:class:`~tactile_kb.kb.base.KnowledgeBase` is the facade that joins them.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

from tactile_kb.errors import Problem, UsageError
from tactile_kb.kb.bdd import Node, exact_count, isop, iter_minterms
from tactile_kb.kb.minimise import minimal_sop
from tactile_kb.kb.notation import Factored, Sop, sop_from_terms, to_sympy
from tactile_kb.kb.rules import RuleSet

if TYPE_CHECKING:
    import sympy

__all__ = ["EXACT_LIMIT", "EXACT_MAX_MINTERMS", "CompiledClass", "Group", "Knowledge"]

EXACT_LIMIT = 10
"""Functions of at most this many variables (and :data:`EXACT_MAX_MINTERMS` models) get an
exact minimal sum of products; larger ones an irredundant one."""
EXACT_MAX_MINTERMS = 96


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


class Knowledge:
    """A compiled rule set as data: r(L) as factored BDDs and the classes' terms.

    Built by :func:`tactile_kb.kb.compiler.compile_rules` (as its facade
    :class:`~tactile_kb.kb.base.KnowledgeBase`); classifying, deciding, the economy and the
    analyses are functions over it. ``n`` propositions in declared order ``ids``;
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
        self.order: tuple[str, ...] = tuple(n for ph in rules.phases for n in ph.propositions)
        """The propositions in phase order (the order the paper's choice tree asks them)."""
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
            f"<{type(self).__name__} {self.rules.name!r}: n={self.n}, |r(L)|={self.r_count}, "
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
                rows = [[int(m[v]) for v in support] for m in bdd.pick_iter(f, care_vars=support)]
                sop = sop_from_terms(minimal_sop(rows), [self.index[v] for v in support])
            else:
                sop = isop(bdd, f, f, self.index)
        self._sop_cache[f] = sop
        return sop

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
