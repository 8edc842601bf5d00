"""Two-level minimisation of small Boolean functions: Quine–McCluskey prime implicants, then a
prime-implicant table reduced by row and column dominance.

This is the algorithm of sympy's ``SOPform`` (``_simplified_pairs`` and ``_rem_redundancy`` in
``sympy/logic/boolalg.py``, sympy 1.14, BSD-3-Clause), restated over plain lists so that the
commands that compile a rule file (``validate``, ``query``, ``compile``) need not import sympy,
whose import alone costs about half a second. Given the same minterms in the same order it
chooses the same implicants, so the printed r(L) strings are the ones sympy gives;
``tests/test_minimise.py`` checks that against ``SOPform`` on enumerated functions.

A term is a list of ``0``, ``1`` or :data:`DASH` (the variable does not occur) per variable.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

__all__ = ["DASH", "minimal_sop"]

DASH = 3
"""The value of a variable that a term does not mention (sympy's convention)."""


def _differ_in_one(a: Sequence[int], b: Sequence[int]) -> int:
    """The one position where ``a`` and ``b`` differ, or -1 if they differ in none or more."""
    index = -1
    for x, v in enumerate(a):
        if v != b[x]:
            if index != -1:
                return -1
            index = x
    return index


def _prime_implicants(terms: list[list[int]]) -> list[list[int]]:
    """Merge terms that differ in one variable, round after round (the Quine–McCluskey step)."""
    if not terms:
        return []
    merged: list[list[int]] = []
    used = [False] * len(terms)
    by_ones: defaultdict[int, list[int]] = defaultdict(list)
    for n, term in enumerate(terms):
        by_ones[sum(1 for t in term if t == 1)].append(n)
    for k in range(len(terms[0])):
        for i in by_ones[k]:
            for j in by_ones[k + 1]:
                index = _differ_in_one(terms[i], terms[j])
                if index != -1:
                    used[i] = used[j] = True
                    term = terms[i][:]
                    term[index] = DASH
                    if term not in merged:
                        merged.append(term)
    if merged:
        merged = _prime_implicants(merged)
    merged.extend(t for t, u in zip(terms, used, strict=True) if not u)
    return merged


def _covers(prime: Sequence[int], minterm: Sequence[int]) -> bool:
    return all(p in (DASH, m) for p, m in zip(prime, minterm, strict=True))


def _column(table: list[list[int]], c: int, seen: dict[int, list[int]]) -> list[int]:
    if c not in seen:
        seen[c] = [row[c] for row in table]
    return seen[c]


def _select(primes: list[list[int]], minterms: list[list[int]]) -> list[list[int]]:
    """Reduce the prime-implicant table by dominance; break ties by the widest cover."""
    if not minterms:
        return []
    nrows, ncols = len(minterms), len(primes)
    table = [[int(_covers(p, m)) for p in primes] for m in minterms]
    colcount = [sum(table[r][c] for r in range(nrows)) for c in range(ncols)]
    rowcount = [sum(row) for row in table]

    changed = True
    while changed:
        changed = False
        # A minterm whose covering primes include another minterm's is implied by it: drop it.
        for r in range(nrows):
            if not rowcount[r]:
                continue
            row = table[r]
            for r2 in range(nrows):
                if r != r2 and rowcount[r] and rowcount[r] <= rowcount[r2]:
                    row2 = table[r2]
                    if all(row2[c] >= row[c] for c in range(ncols)):
                        rowcount[r2] = 0
                        changed = True
                        for c in range(ncols):
                            if row2[c]:
                                row2[c] = 0
                                colcount[c] -= 1
        # A prime covering a subset of what another covers is not needed: drop it.
        columns: dict[int, list[int]] = {}  # each column as first read in this round
        for c in range(ncols):
            if not colcount[c]:
                continue
            col = _column(table, c, columns)
            for c2 in range(ncols):
                if c != c2 and colcount[c2] and colcount[c] >= colcount[c2]:
                    col2 = _column(table, c2, columns)
                    if all(col[r] >= col2[r] for r in range(nrows)):
                        colcount[c2] = 0
                        changed = True
                        for r in range(nrows):
                            if col2[r] and table[r][c2]:
                                table[r][c2] = 0
                                rowcount[r] -= 1
        if not changed:
            # No dominance left (a cyclic core): keep the prime covering most minterms.
            best, most = -1, 0
            for c in range(ncols):
                if colcount[c] > most:
                    best, most = c, colcount[c]
            if best != -1 and most > 1:
                for c in range(ncols):
                    if c == best:
                        continue
                    for r, hit in enumerate(columns[best]):
                        if hit and table[r][c]:
                            table[r][c] = 0
                            changed = True
                            rowcount[r] -= 1
                            colcount[c] -= 1
    return [primes[c] for c in range(ncols) if colcount[c]]


def minimal_sop(minterms: Sequence[Sequence[int]]) -> list[list[int]]:
    """The terms of a minimal sum of products covering exactly ``minterms`` (rows of 0/1).

    An empty list is the constant false; a single all-:data:`DASH` term is the constant true.

    >>> minimal_sop([[0, 0, 1], [0, 1, 1], [1, 1, 1]])
    [[0, 3, 1], [3, 1, 1]]
    """
    rows = [list(m) for m in minterms]
    return _select(_prime_implicants([r[:] for r in rows]), rows)
