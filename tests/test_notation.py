"""Printing sums of products: paper notation, ASCII, bit strings, integers."""

from __future__ import annotations

import itertools

import numpy as np
import sympy
from hypothesis import given
from hypothesis import strategies as st
from kbtruth import rows, table

from tactile_kb.kb.expr import parse_expr
from tactile_kb.kb.notation import (
    MACRON,
    Cube,
    Factored,
    ascii_text,
    bit_strings,
    cube_bits,
    cube_ints,
    flat_cubes,
    normalize,
    paper,
    sop_from_sympy,
    to_sympy,
)

IDS = ("A", "B", "C", "D", "E")


def test_the_paper_cube() -> None:
    cube: Cube = ((0, True), (1, False), (2, True), (3, True), (4, False))
    assert paper(((cube,),), IDS) == "A·B" + MACRON + "·C·D·E" + MACRON
    assert paper(((cube,),), IDS) == "A·B̄·C·D·Ē"
    assert ascii_text(((cube,),), IDS) == "A & ~B & C & D & ~E"
    assert bit_strings(((cube,),), 5) == ("10110",)
    assert cube_ints(cube, 5) == (0b10110,)


def test_constants() -> None:
    assert paper((), IDS) == "1"
    assert paper(((),), IDS) == "0"
    assert ascii_text(((),), IDS) == "0"
    assert bit_strings((((),),), 3) == ("---",)
    assert bit_strings(((),), 3) == ()
    assert normalize((((((0, True),),)), (((0, False),),))) is None


def test_single_cube_factors_merge_and_distribute() -> None:
    factors: Factored = ((((0, True),),), (((1, True),), ((2, False),)))
    assert paper(factors, IDS) == "A·B + A·C̄"
    assert ascii_text(factors, IDS) == "(A & B) | (A & ~C)"


def test_two_sums_stay_factored() -> None:
    factors: Factored = (
        (((0, True),),),
        (((1, True),), ((2, True),)),
        (((3, True),), ((4, False),)),
    )
    assert paper(factors, IDS) == "A·(B + C)·(D + Ē)"
    assert ascii_text(factors, IDS) == "A & (B | C) & (D | ~E)"
    assert bit_strings(factors, 5) == ("11-1-", "11--0", "1-11-", "1-1-0")


def test_sympy_round_trip() -> None:
    a, b, c = sympy.symbols("A B C")
    sop = sop_from_sympy(sympy.Or(sympy.And(a, sympy.Not(b)), c), {a: 0, b: 1, c: 2})
    assert sop == (((0, True), (1, False)), ((2, True),))
    assert sop_from_sympy(sympy.true, {}) == ((),)
    assert sop_from_sympy(sympy.false, {}) == ()
    expr = to_sympy((sop,), sympy.symbols("A B C"))
    assert sympy.simplify_logic(expr ^ ((a & ~b) | c)) is sympy.false


cubes = st.dictionaries(st.integers(0, 4), st.booleans(), max_size=5).map(
    lambda d: tuple(sorted(d.items()))
)
factors_st = st.lists(st.lists(cubes, min_size=1, max_size=3).map(tuple), max_size=3).map(tuple)


@given(factors_st)
def test_every_form_denotes_the_same_function(factors: Factored) -> None:
    """ascii (parsed back), paper (parsed back), bit strings and sympy agree by enumeration."""
    grid = rows(5)
    truth = np.ones(len(grid), dtype=bool)
    for sop in factors:
        hit = np.zeros(len(grid), dtype=bool)
        for cube in sop:
            ok = np.ones(len(grid), dtype=bool)
            for i, v in cube:
                ok &= grid[:, i] == v
            hit |= ok
        truth &= hit
    assert (table(parse_expr(ascii_text(factors, IDS)), IDS) == truth).all()
    assert (table(parse_expr(paper(factors, IDS)), IDS) == truth).all()
    from_bits = np.zeros(len(grid), dtype=bool)
    for b in bit_strings(factors, 5):
        ok = np.ones(len(grid), dtype=bool)
        for i, ch in enumerate(b):
            if ch != "-":
                ok &= grid[:, i] == (ch == "1")
        from_bits |= ok
    assert (from_bits == truth).all()
    ints = {x for c in flat_cubes(factors) for x in cube_ints(c, 5)}
    assert ints == set(np.flatnonzero(truth).tolist())
    syms = sympy.symbols(IDS)
    expr = to_sympy(factors, syms)
    for row in itertools.islice(range(32), 0, 32, 3):
        env = dict(zip(syms, grid[row].tolist(), strict=True))
        assert bool(expr.subs(env)) == truth[row]


def test_cube_bits() -> None:
    assert cube_bits(((1, True), (3, False)), 5) == "-1-0-"
