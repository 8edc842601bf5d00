"""Tests of tactile_kb.kb.expr: parsing, errors with columns, printing, evaluation, folding."""

from __future__ import annotations

import itertools

import pytest
import sympy
from hypothesis import given, settings
from hypothesis import strategies as st

from tactile_kb.errors import ExpressionError, UsageError
from tactile_kb.kb.expr import (
    And,
    Const,
    Equiv,
    Expr,
    Implies,
    Not,
    Or,
    Var,
    Xor,
    evaluate,
    fold,
    is_identifier,
    names,
    parse_expr,
    to_sympy,
    to_text,
    variables,
)

A, B, C, D = Var("A"), Var("B"), Var("C"), Var("D")
IDS = ("A", "B", "C", "D")


# --------------------------------------------------------------------------- trees


@pytest.mark.parametrize(
    ("text", "tree"),
    [
        ("A", A),
        ("  A  ", A),
        ("true", Const(True)),
        ("false", Const(False)),
        ("1", Const(True)),
        ("0", Const(False)),
        ("~A", Not(A)),
        ("~~A", Not(Not(A))),
        ("A & B & C", And((A, B, C))),
        ("A & (B & C)", And((A, And((B, C))))),
        ("A | B & C", Or((A, And((B, C))))),
        ("(A | B) & C", And((Or((A, B)), C))),
        ("A ^ B & C", Xor(A, And((B, C)))),
        ("A | B ^ C", Or((A, Xor(B, C)))),
        ("A ^ B ^ C", Xor(Xor(A, B), C)),
        ("A -> B -> C", Implies(A, Implies(B, C))),
        ("A | B -> C", Implies(Or((A, B)), C)),
        ("A -> B = C", Equiv(Implies(A, B), C)),
        ("B = ~C", Equiv(B, Not(C))),
        ("B <-> ~C", Equiv(B, Not(C))),
        ("~(D & E)", Not(And((D, Var("E"))))),
        ("~A & B", And((Not(A), B))),
        ("no & ~off", And((Var("no"), Not(Var("off"))))),
        ("_x1 | truth", Or((Var("_x1"), Var("truth")))),
    ],
)
def test_parse_precedence_and_associativity(text: str, tree: Expr) -> None:
    assert parse_expr(text) == tree


@pytest.mark.parametrize(
    ("spelling", "canonical"),
    [
        ("!A · B * C", "~A & B & C"),
        ("¬A ∧ B", "~A & B"),
        ("A + B ∨ C", "A | B | C"),
        ("A != B", "A ^ B"),
        ("A ⊕ B", "A ^ B"),
        ("A → B", "A -> B"),
        ("A ↔ B", "A = B"),
        ("A·B̄·C + D̄", "A & ~B & C | ~D"),
        ("B̄̄", "~~B"),
    ],
)
def test_operator_spellings(spelling: str, canonical: str) -> None:
    assert to_text(parse_expr(spelling)) == canonical
    assert parse_expr(spelling) == parse_expr(canonical)


def test_paper_notation_parses() -> None:
    precomposed = "A·B̄·C·D·\u0112·F·G"  # Ē as one code point
    assert parse_expr(precomposed) == parse_expr("A·B̄·C·D·E\u0304·F·G")
    cube = parse_expr(precomposed)
    assert cube == And(
        (A, Not(B), C, D, Not(Var("E")), Var("F"), Var("G")),
    )


def test_variable_positions_point_into_the_text() -> None:
    text = "alpha & (beta | ~gamma) -> alpha"
    found = [(v.name, v.pos) for v in variables(parse_expr(text))]
    assert found == [("alpha", 0), ("beta", 9), ("gamma", 17), ("alpha", 27)]
    for name, pos in found:
        assert text[pos : pos + len(name)] == name
    assert names(parse_expr(text)) == {"alpha", "beta", "gamma"}


def test_positions_are_not_compared() -> None:
    assert Var("A", 3) == Var("A", 7)
    assert hash(Var("A", 3)) == hash(Var("A", 7))


def test_nary_nodes_need_two_operands() -> None:
    with pytest.raises(UsageError):
        And((A,))
    with pytest.raises(UsageError):
        Or(())


@pytest.mark.parametrize(
    ("word", "ok"),
    [("A", True), ("no", True), ("_1", True), ("a_b9", True), ("true", False), ("1A", False)],
)
def test_is_identifier(word: str, ok: bool) -> None:
    assert is_identifier(word) is ok


def test_is_identifier_rejects_other_characters() -> None:
    assert not is_identifier("")
    assert not is_identifier("A-B")
    assert not is_identifier("Ä")


# --------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("text", "column", "message"),
    [
        ("", 1, "empty expression"),
        ("   ", 4, "empty expression"),
        ("A & $", 5, "unexpected character '$'"),
        ("A &", 4, "missing operand after '&'"),
        ("~", 2, "missing operand after '~'"),
        ("A & | B", 5, "expected an id, a constant, '~' or '(' but found '|'"),
        ("(A & B", 1, "unbalanced '(': it is never closed"),
        ("A & (B | (C)", 5, "unbalanced '(': it is never closed"),
        ("A & B)", 6, "unbalanced ')': no '(' to close"),
        ("(A B)", 4, "expected an operator or ')' but found 'B'"),
        ("A B", 3, "expected an operator but found 'B'"),
        ("A = B = C", 7, "chained '=' is ambiguous"),
        ("A <-> B = C", 9, "chained '=' is ambiguous"),
        ("A & 2", 5, "'2' is neither a constant (0, 1) nor an id"),
        ("A & 10", 5, "'10' is neither a constant"),
        ("\u0304A", 1, "a combining macron must follow an id"),
        ("A < B", 3, "unexpected character '<'"),
        ("A - B", 3, "unexpected character '-'"),
        ("()", 2, "expected an id, a constant, '~' or '(' but found ')'"),
    ],
)
def test_errors_carry_the_column_of_the_bad_token(text: str, column: int, message: str) -> None:
    with pytest.raises(ExpressionError) as info:
        parse_expr(text)
    assert info.value.column == column
    assert info.value.text == text
    assert message in info.value.message
    assert str(info.value).startswith(f"column {column}: ")


def test_too_deep_nesting_is_an_error_not_a_crash() -> None:
    with pytest.raises(ExpressionError, match="nested deeper"):
        parse_expr("(" * 500 + "A" + ")" * 500)
    with pytest.raises(ExpressionError, match="nested deeper"):
        parse_expr("A -> " * 500 + "B")
    with pytest.raises(ExpressionError, match="nested deeper"):
        parse_expr("~" * 500 + "A")


def test_non_string_is_a_usage_error() -> None:
    with pytest.raises(UsageError):
        parse_expr(5)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- evaluation


def test_evaluate_truth_tables() -> None:
    # the truth tables written out by hand, independent of the implementation
    table = {
        "A & B": [0, 0, 0, 1],
        "A | B": [0, 1, 1, 1],
        "A ^ B": [0, 1, 1, 0],
        "A -> B": [1, 1, 0, 1],
        "A = B": [1, 0, 0, 1],
        "~A | B": [1, 1, 0, 1],
    }
    rows = [(False, False), (False, True), (True, False), (True, True)]
    for text, expected in table.items():
        got = [int(evaluate(parse_expr(text), {"A": a, "B": b})) for a, b in rows]
        assert got == expected, text


def test_evaluate_needs_every_value() -> None:
    with pytest.raises(UsageError, match="no value for proposition 'B'"):
        evaluate(parse_expr("A & B"), {"A": True})


def test_to_sympy_names_a_missing_symbol() -> None:
    with pytest.raises(UsageError, match="'B'"):
        to_sympy(parse_expr("A & B"), {"A": sympy.Symbol("A")})


def test_to_sympy_constants() -> None:
    assert to_sympy(Const(True), {}) is sympy.true
    assert to_sympy(Const(False), {}) is sympy.false


def test_fold_counts_nodes_and_derives_missing_operators() -> None:
    e = parse_expr("(A -> B) = (C ^ ~D)")
    leaves = fold(e, var=lambda n: 1, const=lambda v: 1, not_=lambda a: a, and_=int.__add__,
                  or_=int.__add__)  # fmt: skip
    # implies → or(not a, b), equiv → or(and(a,b), and(¬a,¬b)), xor → or(and(a,¬b), and(¬a,b)):
    # each operand value is used twice in = and in ^, once in ->: 2·(1 + 1) + 2·(2·1 + 2·1)
    assert leaves == 12


# --------------------------------------------------------------------------- properties

_leaves = st.one_of(st.sampled_from(IDS).map(Var), st.booleans().map(Const))


def _extend(children: st.SearchStrategy[Expr]) -> st.SearchStrategy[Expr]:
    nary = st.lists(children, min_size=2, max_size=3).map(tuple)
    pair = st.tuples(children, children)
    return st.one_of(
        children.map(Not),
        nary.map(And),
        nary.map(Or),
        pair.map(lambda t: Implies(*t)),
        pair.map(lambda t: Equiv(*t)),
        pair.map(lambda t: Xor(*t)),
    )


trees = st.recursive(_leaves, _extend, max_leaves=14)


@settings(max_examples=300, deadline=None)
@given(trees)
def test_to_text_then_parse_is_the_identity(tree: Expr) -> None:
    text = to_text(tree)
    assert parse_expr(text) == tree
    assert to_text(parse_expr(text)) == text


@settings(max_examples=120, deadline=None)
@given(trees)
def test_evaluate_and_fold_agree_with_sympy_on_every_assignment(tree: Expr) -> None:
    symbols = {n: sympy.Symbol(n) for n in IDS}
    sym = to_sympy(tree, symbols)
    for bits in itertools.product([False, True], repeat=len(IDS)):
        values = dict(zip(IDS, bits, strict=True))
        truth = bool(sym.xreplace({symbols[n]: sympy.true if v else sympy.false
                                   for n, v in values.items()}))  # fmt: skip
        assert evaluate(tree, values) is truth
        folded = fold(
            tree,
            var=values.__getitem__,
            const=bool,
            not_=lambda a: not a,
            and_=lambda a, b: a and b,
            or_=lambda a, b: a or b,
        )
        assert folded is truth


@settings(max_examples=100, deadline=None)
@given(trees)
def test_paper_spellings_parse_to_the_same_function(tree: Expr) -> None:
    paper = (
        to_text(tree)
        .replace("<->", "↔")
        .replace("->", "→")
        .replace("&", "·")
        .replace("|", "+")
        .replace("~", "¬")
        .replace("^", "!=")
    )
    assert parse_expr(paper) == tree
