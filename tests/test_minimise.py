"""The sympy-free minimiser chooses exactly the implicants sympy's ``SOPform`` chooses.

Ground truth: every Boolean function of up to 3 variables, and seeded random functions of 4–7
variables with their minterms in random orders, each compared with ``SOPform`` on the same
rows; plus the covering property checked by enumeration.
"""

from __future__ import annotations

import itertools
import random

import pytest
import sympy
from sympy.logic import SOPform

from tactile_kb.kb.minimise import DASH, minimal_sop
from tactile_kb.kb.notation import sop_from_sympy, sop_from_terms


def _rows(n: int, mask: int) -> list[list[int]]:
    return [
        list(bits) for k, bits in enumerate(itertools.product((0, 1), repeat=n)) if mask >> k & 1
    ]


def _same_as_sympy(rows: list[list[int]], n: int) -> None:
    syms = sympy.symbols(f"x0:{n}")
    want = sop_from_sympy(SOPform(syms, rows), {s: i for i, s in enumerate(syms)}) if rows else ()
    got = sop_from_terms(minimal_sop(rows), range(n))
    assert got == want, rows


def _covers_exactly(terms: list[list[int]], rows: list[list[int]], n: int) -> None:
    on = {tuple(r) for r in rows}
    for bits in itertools.product((0, 1), repeat=n):
        hit = any(all(t in (DASH, b) for t, b in zip(term, bits, strict=True)) for term in terms)
        assert hit == (bits in on)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_every_function_of_few_variables(n: int) -> None:
    for mask in range(1, 2 ** (2**n)):
        rows = _rows(n, mask)
        _same_as_sympy(rows, n)
        _covers_exactly(minimal_sop(rows), rows, n)


@pytest.mark.parametrize("n", [4, 5, 6, 7])
def test_random_functions_in_random_row_orders(n: int) -> None:
    rng = random.Random(n)
    for _ in range(40):
        rows = _rows(n, rng.getrandbits(2**n) or 1)
        rng.shuffle(rows)
        _same_as_sympy(rows, n)
        _covers_exactly(minimal_sop(rows), rows, n)


def test_constants() -> None:
    assert minimal_sop([]) == []
    assert minimal_sop([[0], [1]]) == [[DASH]]
