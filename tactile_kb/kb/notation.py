"""Printing sums of products in the paper's notation, in ASCII, as bit strings and integers.

A reduced disjunction is held as a *product of sums of products*: a tuple of factors, each a
tuple of cubes, each cube a tuple of ``(index, value)`` literals sorted by the proposition's
index in the declared order. Independent groups of propositions stay separate factors, so a
class over forty propositions prints as a few short sums instead of thousands of flat terms.

The paper writes a negated proposition with a bar over it and joins literals with a dot
(``A·B̄·C·D·Ē·F·G``, eq. 3); here the bar is a combining macron (U+0304) after the id. ASCII
uses the rule files' expression syntax, so ``parse_expr`` reads it back. Bit strings follow
the declared order, ``1`` true, ``0`` false, ``-`` free; integers read the bit string with the
first proposition as the most significant bit.

Examples
--------
>>> ids = ("A", "B", "C")
>>> sop = ((((0, True), (1, False)),), (((2, True),), ((1, True),)))
>>> paper(sop, ids)
'A·B̄·C'
>>> ascii_text(sop, ids)
'A & ~B & C'
>>> bit_strings(sop, 3)
('101',)
>>> paper(((((0, True),), ((1, False),)),), ids)
'A + B̄'
>>> ascii_text(((((0, True), (2, False)), ((1, False),)),), ids)
'(A & ~C) | ~B'
>>> bit_strings(((((0, True),), ((1, False),)),), 3)
('1--', '-0-')
>>> cube_ints(((0, True),), 3)
(4, 5, 6, 7)
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:  # sympy is imported where it is used: printing needs none of it
    import sympy

__all__ = [
    "MACRON",
    "Cube",
    "Factored",
    "Sop",
    "ascii_text",
    "bit_strings",
    "cube_bits",
    "cube_ints",
    "cube_text",
    "flat_cubes",
    "literal_text",
    "normalize",
    "paper",
    "sop_from_sympy",
    "sop_from_terms",
    "to_sympy",
]

MACRON = "\u0304"
"""The combining macron written after a negated id: ``B̄`` is ``"B" + MACRON``."""

Cube = tuple[tuple[int, bool], ...]
"""A conjunction of literals: ``(index, value)`` pairs sorted by index; ``()`` is true."""
Sop = tuple[Cube, ...]
"""A disjunction of cubes; ``()`` is false."""
Factored = tuple[Sop, ...]
"""A conjunction of sums of products; ``()`` is true."""

Style = Literal["paper", "ascii"]


def literal_text(name: str, value: bool, style: Style = "paper") -> str:
    """One literal: ``B`` or ``B̄`` (paper), ``B`` or ``~B`` (ascii)."""
    if value:
        return name
    return name + MACRON if style == "paper" else "~" + name


def cube_text(cube: Cube, ids: Sequence[str], style: Style = "paper") -> str:
    """A cube as ``A·B̄·C`` (paper) or ``A & ~B & C`` (ascii); the empty cube is ``1``."""
    if not cube:
        return "1"
    sep = "·" if style == "paper" else " & "
    return sep.join(literal_text(ids[i], v, style) for i, v in cube)


def _sop_text(sop: Sop, ids: Sequence[str], style: Style) -> str:
    if not sop:
        return "0"
    if style == "paper":
        return " + ".join(cube_text(c, ids, style) for c in sop)
    if len(sop) == 1:
        return cube_text(sop[0], ids, style)
    return " | ".join(
        f"({cube_text(c, ids, style)})" if len(c) > 1 else cube_text(c, ids, style) for c in sop
    )


def _merge(a: Cube, b: Cube) -> Cube | None:
    """The conjunction of two cubes, or ``None`` if they contradict."""
    out = dict(a)
    for i, v in b:
        if out.get(i, v) != v:
            return None
        out[i] = v
    return tuple(sorted(out.items()))


def normalize(factors: Factored) -> tuple[Cube, tuple[Sop, ...]] | None:
    """Split a product into its common cube and its sums of more than one term.

    Returns ``None`` for false (an empty factor, or contradictory single-cube factors). When at
    most one sum remains, the common cube is distributed into it, so the result is a flat sum
    of products: ``((), (sop,))``.
    """
    common: Cube = ()
    sums: list[Sop] = []
    for sop in factors:
        if not sop:
            return None
        if len(sop) == 1:
            merged = _merge(common, sop[0])
            if merged is None:
                return None
            common = merged
        else:
            sums.append(sop)
    if len(sums) == 1:
        flat = tuple(m for c in sums[0] if (m := _merge(common, c)) is not None)
        return ((), (flat,)) if flat else None
    return common, tuple(sums)


def _text(factors: Factored, ids: Sequence[str], style: Style) -> str:
    norm = normalize(factors)
    if norm is None:
        return "0"
    common, sums = norm
    if not sums:
        return cube_text(common, ids, style)
    if len(sums) == 1 and not common:
        return _sop_text(sums[0], ids, style)
    sep = "·" if style == "paper" else " & "
    parts = [cube_text(common, ids, style)] if common else []
    parts += [f"({_sop_text(s, ids, style)})" for s in sums]
    return sep.join(parts)


def paper(factors: Factored, ids: Sequence[str]) -> str:
    """The paper's notation: ``A·B̄·C + A·D``; independent sums as ``A·(B + C̄)·(D + E)``."""
    return _text(factors, ids, "paper")


def ascii_text(factors: Factored, ids: Sequence[str]) -> str:
    """The rule-file expression syntax: ``(A & ~B) | C``; ``parse_expr`` reads it back."""
    return _text(factors, ids, "ascii")


def cube_bits(cube: Cube, n: int) -> str:
    """A cube as a bit string of length ``n``: ``1``, ``0``, ``-`` (free)."""
    out = ["-"] * n
    for i, v in cube:
        out[i] = "1" if v else "0"
    return "".join(out)


def flat_cubes(factors: Factored) -> Iterator[Cube]:
    """The cubes of the product multiplied out (one per choice of a cube in each factor)."""
    norm = normalize(factors)
    if norm is None:
        return
    common, sums = norm
    for choice in itertools.product(*sums):
        cube: Cube | None = common
        for c in choice:
            cube = _merge(cube, c) if cube is not None else None
        if cube is not None:
            yield cube


def bit_strings(factors: Factored, n: int) -> tuple[str, ...]:
    """The bit strings of the multiplied-out cubes, in the order the factors give them."""
    return tuple(cube_bits(c, n) for c in flat_cubes(factors))


def cube_ints(cube: Cube, n: int) -> tuple[int, ...]:
    """The integers of a cube's minterms (first proposition = most significant bit), sorted."""
    base = 0
    free: list[int] = []
    fixed = dict(cube)
    for i in range(n):
        weight = 1 << (n - 1 - i)
        if i not in fixed:
            free.append(weight)
        elif fixed[i]:
            base |= weight
    out = [base]
    for w in free:
        out += [x | w for x in out]
    return tuple(sorted(out))


def sop_from_terms(terms: Iterable[Sequence[int]], positions: Sequence[int]) -> Sop:
    """Terms of 0/1/``DASH`` over ``positions`` (proposition indices) as a :data:`Sop`.

    >>> sop_from_terms([[1, 3], [0, 0]], [4, 2])
    (((2, False), (4, False)), ((4, True),))
    """
    sop = [
        tuple(sorted((p, bool(v)) for p, v in zip(positions, term, strict=True) if v in (0, 1)))
        for term in terms
    ]
    return tuple(sorted(sop, key=_cube_order))


def sop_from_sympy(expr: Any, index: Mapping[sympy.Symbol, int]) -> Sop:
    """A sympy sum of products (``Or`` of ``And`` of literals, or a constant) as a :data:`Sop`."""
    import sympy

    if expr is sympy.true:
        return ((),)
    if expr is sympy.false:
        return ()
    terms: Iterable[Any] = expr.args if isinstance(expr, sympy.Or) else (expr,)
    sop: list[Cube] = []
    for term in terms:
        lits: Iterable[Any] = term.args if isinstance(term, sympy.And) else (term,)
        cube: dict[int, bool] = {}
        for lit in lits:
            if isinstance(lit, sympy.Not):
                cube[index[lit.args[0]]] = False
            elif isinstance(lit, sympy.Symbol):
                cube[index[lit]] = True
            else:
                raise TypeError(f"not a sum of products: {expr}")
        sop.append(tuple(sorted(cube.items())))
    return tuple(sorted(sop, key=_cube_order))


def _cube_order(cube: Cube) -> tuple[tuple[int, int], ...]:
    # positive literals before negative ones at the same index, earlier indices first
    return tuple((i, 0 if v else 1) for i, v in cube)


def to_sympy(factors: Factored, symbols: Sequence[sympy.Symbol]) -> Any:
    """The product of sums of products as a sympy Boolean (``symbols`` in declared order)."""
    import sympy

    def cube(c: Cube) -> Any:
        return sympy.And(*[symbols[i] if v else sympy.Not(symbols[i]) for i, v in c])

    norm = normalize(factors)
    if norm is None:
        return sympy.false
    common, sums = norm
    return sympy.And(cube(common), *[sympy.Or(*[cube(c) for c in s]) for s in sums])
