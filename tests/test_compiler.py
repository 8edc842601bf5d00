"""Compilation: r(L) as BDDs against enumerated truth tables; the classes' printed terms."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kbtruth import bits, r_table, rows, table

from tactile_kb import compile_rules
from tactile_kb.errors import RuleFileError, UsageError
from tactile_kb.kb.bdd import exact_count, isop, manager
from tactile_kb.kb.expr import parse_expr
from tactile_kb.kb.knowledge import EXACT_LIMIT
from tactile_kb.kb.rulegen import generate_rules, rules_text
from tactile_kb.kb.rules import PAPER_EXAMPLE, parse_rules

BAR = "\u0304"  # the combining macron, spelled out so that no editor can precompose it


def test_the_paper_cube_eq_3_to_5() -> None:
    """From the paper's base A–G with equality connections: r(L) = A·B̄·C·D·Ē·F·G."""
    kb = compile_rules(PAPER_EXAMPLE)
    cube = kb.classes[0]
    assert cube.paper == f"A·B{BAR}·C·D·E{BAR}·F·G"
    assert cube.ascii == "A & ~B & C & D & ~E & F & G"
    assert cube.bits == ("1011011",)
    assert cube.ints == (0b1011011,)
    assert cube.count == 1
    assert cube.proposition == "L: object is cube"
    assert cube.equation == f"L = A·B{BAR}·C·D·E{BAR}·F·G"
    assert (kb.n, kb.s_size) == (7, 128)
    assert kb.r_count == int(r_table(kb.rules).sum()) == 32
    assert [g.ids for g in kb.groups] == [("A",), ("B", "C"), ("D", "E", "F"), ("G",)]


def test_inputs_name_path_text(tmp_path: Path) -> None:
    path = tmp_path / "paper.yaml"
    path.write_text(PAPER_EXAMPLE, encoding="utf-8")
    assert compile_rules(path).r_count == 32
    assert compile_rules(str(path)).r_count == 32
    assert compile_rules(parse_rules(PAPER_EXAMPLE)).r_count == 32
    assert compile_rules("parallelepipeds").rules.name == "parallelepipeds"
    with pytest.raises(UsageError, match="no rule file"):
        compile_rules("no-such-rule-set")
    with pytest.raises(RuleFileError):
        compile_rules("name: x\npropositions: [\n")


# --------------------------------------------------------------------------- property tests

NAMES = [f"X{i}" for i in range(16)]


@st.composite
def rule_sets(draw: st.DrawFn, max_n: int = 16) -> str:
    n = draw(st.integers(1, max_n))
    ids = NAMES[:n]
    lit = st.tuples(st.sampled_from(ids), st.booleans()).map(lambda t: t[0] if t[1] else f"~{t[0]}")
    op = st.sampled_from([" -> ", " & ", " | ", " = ", " ^ "])
    binary = st.tuples(lit, op, lit).map("".join)
    ternary = st.tuples(lit, op, st.tuples(lit, op, lit).map("".join)).map(
        lambda t: f"{t[0]}{t[1]}({t[2]})"
    )
    conns = draw(st.lists(st.one_of(lit, binary, ternary), max_size=min(12, 2 * n)))
    classes = draw(st.lists(st.one_of(lit, binary, ternary), max_size=4))
    return rules_text(ids, conns, classes)


@settings(max_examples=40, deadline=None)
@given(rule_sets())
def test_bdd_counts_and_class_terms_match_truth_tables(text: str) -> None:
    rules = parse_rules(text)
    ok = r_table(rules)
    if not ok.any():
        with pytest.raises(RuleFileError, match=r"leave r\(L\) empty|can never hold"):
            compile_rules(rules)
        return
    kb = compile_rules(rules, check=False)
    n = kb.n
    assert kb.r_count == int(ok.sum())
    if n <= 12:
        assert list(kb.minterms()) == [bits(int(r), n) for r in np.flatnonzero(ok)]
    for k in kb.classes:
        truth = table(k.text, rules.ids) & ok
        assert k.count == int(truth.sum())
        assert (table(parse_expr(k.ascii), rules.ids) == truth).all(), k.ascii
        assert (table(parse_expr(k.paper), rules.ids) == truth).all(), k.paper
        if k.count <= 4096:
            assert set(k.ints) == set(np.flatnonzero(truth).tolist())


def test_minterm_iterator_is_lazy_over_s_l() -> None:
    """n = 60: |s(L)| = 2**60 is never enumerated; |r(L)| is exact past the 2**53 of doubles."""
    ids = [f"P{i:02d}" for i in range(60)]
    chain = [f"P{i:02d} -> P{i + 1:02d}" for i in range(59)]
    kb = compile_rules(rules_text(ids, chain, ["P00"]), check=False)
    assert kb.r_count == 61  # monotone chains: the first true position, or none
    free = compile_rules(rules_text(ids, ["P00 -> P01"], ["P00"]), check=False)
    assert free.r_count == 3 * 2**58
    first = next(free.minterms())
    assert first == "0" * 60
    assert free.classes[0].count == 2**58
    assert free.classes[0].ints == ()  # too many to list


def test_exact_count_above_fifty_variables() -> None:
    bdd = manager()
    names = [f"Q{i:02d}" for i in range(70)]
    bdd.declare(*names)
    u = bdd.var("Q00") | bdd.var("Q69")
    assert exact_count(bdd, u, names) == 3 * 2**68
    assert exact_count(bdd, bdd.false, names) == 0
    assert exact_count(bdd, bdd.true, names) == 2**70


def test_isop_is_an_irredundant_cover() -> None:
    """Above EXACT_LIMIT variables the printed terms come from ISOP: equal to the function,
    and neither a cube nor a literal can be dropped."""
    n = EXACT_LIMIT + 2
    ids = tuple(f"Y{i:02d}" for i in range(n))
    conns = [f"Y{i:02d} | Y{(i + 1) % n:02d} -> Y{(i + 3) % n:02d}" for i in range(n)]
    kb = compile_rules(rules_text(list(ids), conns, ["Y00 | Y05"]), check=False)
    k = kb.classes[0]
    truth = table("Y00 | Y05", ids) & r_table(kb.rules)
    assert len(kb.bdd.support(kb.model_bdds[0])) > EXACT_LIMIT
    (sop,) = k.factors
    grid = rows(n)

    def cover(cubes: list[tuple[tuple[int, bool], ...]]) -> np.ndarray:
        out = np.zeros(len(grid), dtype=bool)
        for cube in cubes:
            hit = np.ones(len(grid), dtype=bool)
            for i, v in cube:
                hit &= grid[:, i] == v
            out |= hit
        return out

    assert (cover(list(sop)) == truth).all()
    for j in range(len(sop)):
        assert not (cover(list(sop[:j] + sop[j + 1 :])) == truth).all()
        for lit in sop[j]:
            wider = tuple(x for x in sop[j] if x != lit)
            assert not (cover([*sop[:j], wider, *sop[j + 1 :]]) == truth).all()


def test_isop_between_bounds() -> None:
    bdd = manager()
    bdd.declare("Z0", "Z1", "Z2")
    z0, z1, z2 = bdd.var("Z0"), bdd.var("Z1"), bdd.var("Z2")
    lower, upper = z0 & z1 & z2, z0
    sop = isop(bdd, lower, upper, {"Z0": 0, "Z1": 1, "Z2": 2})
    assert sop == (((0, True),),)


def test_independent_groups_stay_factored() -> None:
    ids = ["A", "B", "C", "D", "E"]
    kb = compile_rules(rules_text(ids, ["A | B", "C | D"], ["E"]), check=False)
    k = kb.classes[0]
    assert k.paper == "E·(A + B)·(C + D)"
    assert k.ascii == "E & (A | B) & (C | D)"
    assert k.count == 9
    assert len(k.bits) == 4


def test_classes_minterms_and_unknown_class() -> None:
    kb = compile_rules(PAPER_EXAMPLE)
    assert list(kb.class_minterms("cube")) == ["1011011"]
    with pytest.raises(UsageError, match="no class 'sphere'"):
        kb.class_minterms("sphere")


def test_generated_rule_file_compiles() -> None:
    kb = compile_rules(generate_rules(40, 30, 20, seed=3))
    assert kb.n == 40
    assert len(kb.classes) == 20
    assert all(k.count > 0 for k in kb.classes)
    assert kb.s_size == 2**40


def test_to_dict_is_json_ready() -> None:
    import json

    data = compile_rules("parallelepipeds").to_dict()
    assert json.loads(json.dumps(data))["classes"][0]["id"] == "cube"


@pytest.mark.parametrize(
    "module", ["compiler", "bdd", "notation", "engine", "analysis", "economy", "rulegen"]
)
def test_module_examples(module: str) -> None:
    mod = importlib.import_module(f"tactile_kb.kb.{module}")
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
