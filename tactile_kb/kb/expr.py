"""Boolean expressions over proposition ids: the language of connections and class definitions.

Syntax (operators from the tightest to the loosest binding)::

    ~ ! ¬        not            ~C        (also a macron over an id: C̄ or Ē)
    & · * ∧      and            A & ~B    A·B̄
    ^ != ⊕       xor            D ^ E
    | + ∨        or             D | E     D + E
    -> →         implies        F -> D    (right-associative: a -> b -> c = a -> (b -> c))
    <-> = ↔      equivalence    B = ~C    (the paper's equality form; not chainable)

Ids are ``[A-Za-z_][A-Za-z0-9_]*``; ``0 1 true false`` are the constants; parentheses group.
:func:`parse_expr` raises :class:`~tactile_kb.errors.ExpressionError` with the 1-based column
of the bad token. :func:`to_text` prints the canonical ASCII form, and
``parse_expr(to_text(e)) == e`` for every tree ``e`` (``Var.pos`` is not compared).
The paper's notation printed by the compiler (``A·B̄·C + D``) parses back too.

Examples
--------
>>> e = parse_expr("B = ~C")
>>> e
Equiv(left=Var(name='B'), right=Not(operand=Var(name='C')))
>>> sorted(names(e)), evaluate(e, {"B": True, "C": False})
(['B', 'C'], True)
>>> to_text(parse_expr("A·B̄·C + ¬(D -> E)"))
'A & ~B & C | ~(D -> E)'
>>> parse_expr("A & (B | )")
Traceback (most recent call last):
  ...
tactile_kb.errors.ExpressionError: column 10: expected an id, a constant, '~' or '(' but found ')'
"""

from __future__ import annotations

import unicodedata
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from tactile_kb.errors import ExpressionError, UsageError

__all__ = [
    "ID_PATTERN",
    "RESERVED",
    "And",
    "Const",
    "Equiv",
    "Expr",
    "Implies",
    "Not",
    "Or",
    "Var",
    "Xor",
    "evaluate",
    "evaluate_columns",
    "fold",
    "is_identifier",
    "names",
    "parse_expr",
    "to_sympy",
    "to_text",
    "variables",
]

T = TypeVar("T")

#: The pattern a proposition id must match.
ID_PATTERN = r"^[A-Za-z_][A-Za-z0-9_]*$"
#: Words that read as constants and so cannot be ids.
RESERVED = frozenset({"true", "false"})
#: A combining macron (U+0304) after an id negates it: ``B̄`` is ``~B``.
MACRON = "\u0304"
MAX_DEPTH = 64


# --------------------------------------------------------------------------- the tree


@dataclass(frozen=True)
class Var:
    """A proposition id; ``pos`` is its 0-based offset in the parsed text (not compared)."""

    name: str
    pos: int = field(default=0, compare=False, repr=False)


@dataclass(frozen=True)
class Const:
    """The constant true or false."""

    value: bool


@dataclass(frozen=True)
class Not:
    """Negation."""

    operand: Expr


@dataclass(frozen=True)
class And:
    """Conjunction of two or more operands."""

    args: tuple[Expr, ...]

    def __post_init__(self) -> None:
        if len(self.args) < 2:
            raise UsageError("And needs at least two operands")


@dataclass(frozen=True)
class Or:
    """Disjunction of two or more operands."""

    args: tuple[Expr, ...]

    def __post_init__(self) -> None:
        if len(self.args) < 2:
            raise UsageError("Or needs at least two operands")


@dataclass(frozen=True)
class Implies:
    """``left -> right``."""

    left: Expr
    right: Expr


@dataclass(frozen=True)
class Equiv:
    """``left = right`` (the paper's equality form)."""

    left: Expr
    right: Expr


@dataclass(frozen=True)
class Xor:
    """``left ^ right`` (exclusive or)."""

    left: Expr
    right: Expr


Expr = Var | Const | Not | And | Or | Implies | Equiv | Xor


def is_identifier(text: str) -> bool:
    """Whether ``text`` is a valid proposition id (matches :data:`ID_PATTERN`, not reserved)."""
    if not text or text in RESERVED or not _is_id_start(text[0]):
        return False
    return all(_is_id_char(ch) for ch in text[1:])


def _is_id_start(ch: str) -> bool:
    return ch == "_" or ("a" <= ch <= "z") or ("A" <= ch <= "Z")


def _is_id_char(ch: str) -> bool:
    return _is_id_start(ch) or "0" <= ch <= "9"


# --------------------------------------------------------------------------- tokens

_NOT, _AND, _XOR, _OR, _IMPLIES, _EQUIV = "not", "and", "xor", "or", "implies", "equiv"
_LPAR, _RPAR, _ID, _CONST, _MACRON, _END = "(", ")", "id", "const", "macron", "end"

# Longest first, so that '<->' wins over '<' and '!=' over '!'.
_OPERATORS: tuple[tuple[str, str], ...] = (
    ("<->", _EQUIV),
    ("->", _IMPLIES),
    ("!=", _XOR),
    ("=", _EQUIV),
    ("↔", _EQUIV),
    ("→", _IMPLIES),
    ("~", _NOT),
    ("!", _NOT),
    ("¬", _NOT),
    ("&", _AND),
    ("·", _AND),
    ("*", _AND),
    ("∧", _AND),
    ("^", _XOR),
    ("⊕", _XOR),
    ("|", _OR),
    ("+", _OR),
    ("∨", _OR),
    ("(", _LPAR),
    (")", _RPAR),
    (MACRON, _MACRON),
)


@dataclass(frozen=True)
class _Token:
    kind: str
    text: str
    pos: int  # 0-based


def _precomposed() -> dict[str, str]:
    """Letters with a macron as one code point (``Ē``) → their ASCII letter."""
    out = {}
    for base in "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz":
        composed = unicodedata.normalize("NFC", base + MACRON)
        if len(composed) == 1:
            out[composed] = base
    return out


_PRECOMPOSED = _precomposed()


def _tokenize(text: str) -> Iterator[_Token]:
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch.isspace():
            i += 1
            continue
        if ch in _PRECOMPOSED:  # 'Ē' is the one-letter id E with a macron
            yield _Token(_ID, _PRECOMPOSED[ch], i)
            yield _Token(_MACRON, MACRON, i)
            i += 1
            continue
        if _is_id_start(ch):
            j = i + 1
            while j < n and _is_id_char(text[j]):
                j += 1
            word = text[i:j]
            yield _Token(_CONST if word in RESERVED else _ID, word, i)
            i = j
            continue
        if "0" <= ch <= "9":
            j = i + 1
            while j < n and _is_id_char(text[j]):
                j += 1
            word = text[i:j]
            if word not in ("0", "1"):
                raise ExpressionError(
                    text, i + 1, f"{word!r} is neither a constant (0, 1) nor an id"
                )
            yield _Token(_CONST, word, i)
            i = j
            continue
        for op, kind in _OPERATORS:
            if text.startswith(op, i):
                yield _Token(kind, op, i)
                i += len(op)
                break
        else:
            raise ExpressionError(text, i + 1, f"unexpected character {ch!r}")
    yield _Token(_END, "", n)


# --------------------------------------------------------------------------- parser


def _describe(tok: _Token) -> str:
    return "the end of the expression" if tok.kind == _END else repr(tok.text)


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.tokens = list(_tokenize(text))
        self.i = 0
        self.depth = 0

    @property
    def tok(self) -> _Token:
        return self.tokens[self.i]

    def take(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def error(self, tok: _Token, message: str) -> ExpressionError:
        return ExpressionError(self.text, tok.pos + 1, message)

    def parse(self) -> Expr:
        if self.tok.kind == _END:
            raise self.error(self.tok, "empty expression")
        expr = self.equiv()
        tok = self.tok
        if tok.kind == _RPAR:
            raise self.error(tok, "unbalanced ')': no '(' to close")
        if tok.kind != _END:
            raise self.error(tok, f"expected an operator but found {_describe(tok)}")
        return expr

    def equiv(self) -> Expr:
        left = self.implies()
        if self.tok.kind != _EQUIV:
            return left
        self.take()
        right = self.implies()
        if self.tok.kind == _EQUIV:
            raise self.error(self.tok, f"chained {self.tok.text!r} is ambiguous: add parentheses")
        return Equiv(left, right)

    def implies(self) -> Expr:
        left = self.or_()
        if self.tok.kind != _IMPLIES:
            return left
        self.take()
        self.enter()
        right = self.implies()
        self.depth -= 1
        return Implies(left, right)

    def or_(self) -> Expr:
        args = [self.xor()]
        while self.tok.kind == _OR:
            self.take()
            args.append(self.xor())
        return args[0] if len(args) == 1 else Or(tuple(args))

    def xor(self) -> Expr:
        left = self.and_()
        while self.tok.kind == _XOR:
            self.take()
            left = Xor(left, self.and_())
        return left

    def and_(self) -> Expr:
        args = [self.unary()]
        while self.tok.kind == _AND:
            self.take()
            args.append(self.unary())
        return args[0] if len(args) == 1 else And(tuple(args))

    def unary(self) -> Expr:
        if self.tok.kind == _NOT:
            self.take()
            self.enter()
            operand = self.unary()
            self.depth -= 1
            return Not(operand)
        return self.atom()

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise self.error(self.tok, f"expression nested deeper than {MAX_DEPTH} levels")

    def atom(self) -> Expr:
        tok = self.take()
        if tok.kind == _ID:
            var: Expr = Var(tok.text, tok.pos)
            while self.tok.kind == _MACRON:
                self.take()
                var = Not(var)
            return var
        if tok.kind == _CONST:
            return Const(tok.text in ("1", "true"))
        if tok.kind == _LPAR:
            self.enter()
            inner = self.equiv()
            self.depth -= 1
            if self.tok.kind != _RPAR:
                if self.tok.kind == _END:
                    raise self.error(tok, "unbalanced '(': it is never closed")
                raise self.error(
                    self.tok, f"expected an operator or ')' but found {_describe(self.tok)}"
                )
            self.take()
            return inner
        if tok.kind == _MACRON:
            raise self.error(tok, "a combining macron must follow an id")
        what = "an id, a constant, '~' or '('"
        if tok.kind == _END:
            prev = self.tokens[self.i - 2] if self.i >= 2 else None
            after = f" after {prev.text!r}" if prev is not None else ""
            raise self.error(tok, f"missing operand{after}: expected {what}")
        raise self.error(tok, f"expected {what} but found {_describe(tok)}")


def parse_expr(text: str) -> Expr:
    """Parse ``text`` into an expression tree.

    Raises
    ------
    ExpressionError
        With the 1-based ``column`` of the offending token: an unexpected character, an
        unbalanced parenthesis, a missing operand, trailing input, or a chained ``=``.
    """
    if not isinstance(text, str):
        raise UsageError(f"an expression must be a string, not {type(text).__name__}")
    return _Parser(text).parse()


# --------------------------------------------------------------------------- evaluation


def fold(
    expr: Expr,
    *,
    var: Callable[[str], T],
    const: Callable[[bool], T],
    not_: Callable[[T], T],
    and_: Callable[[T, T], T],
    or_: Callable[[T, T], T],
    implies: Callable[[T, T], T] | None = None,
    equiv: Callable[[T, T], T] | None = None,
    xor: Callable[[T, T], T] | None = None,
) -> T:
    """Evaluate ``expr`` bottom-up with the given operations.

    ``and_`` and ``or_`` are binary and applied left to right over n-ary nodes. Missing
    ``implies``/``equiv``/``xor`` are derived: ``a -> b = ~a | b``, ``a = b = (a & b) | (~a &
    ~b)``, ``a ^ b = (a & ~b) | (~a & b)``.

    Examples
    --------
    >>> fold(parse_expr("A -> B"), var=lambda n: {"A": 1, "B": 0}[n], const=int,
    ...      not_=lambda a: 1 - a, and_=min, or_=max)
    0
    """
    imp = implies or (lambda a, b: or_(not_(a), b))
    eqv = equiv or (lambda a, b: or_(and_(a, b), and_(not_(a), not_(b))))
    xr = xor or (lambda a, b: or_(and_(a, not_(b)), and_(not_(a), b)))

    def go(e: Expr) -> T:
        if isinstance(e, Var):
            return var(e.name)
        if isinstance(e, Const):
            return const(e.value)
        if isinstance(e, Not):
            return not_(go(e.operand))
        if isinstance(e, And | Or):
            op = and_ if isinstance(e, And) else or_
            acc = go(e.args[0])
            for arg in e.args[1:]:
                acc = op(acc, go(arg))
            return acc
        if isinstance(e, Implies):
            return imp(go(e.left), go(e.right))
        if isinstance(e, Equiv):
            return eqv(go(e.left), go(e.right))
        return xr(go(e.left), go(e.right))

    return go(expr)


def variables(expr: Expr) -> Iterator[Var]:
    """Every :class:`Var` occurrence in ``expr``, left to right (with its ``pos``)."""
    if isinstance(expr, Var):
        yield expr
    elif isinstance(expr, Not):
        yield from variables(expr.operand)
    elif isinstance(expr, And | Or):
        for arg in expr.args:
            yield from variables(arg)
    elif isinstance(expr, Implies | Equiv | Xor):
        yield from variables(expr.left)
        yield from variables(expr.right)


def names(expr: Expr) -> frozenset[str]:
    """The ids ``expr`` mentions."""
    return frozenset(v.name for v in variables(expr))


def evaluate_columns(expr: Expr, columns: Mapping[str, Any], size: int) -> np.ndarray[Any, Any]:
    """``expr`` over many assignments at once: ``columns[id]`` is a boolean array of ``size``.

    Examples
    --------
    >>> import numpy as np
    >>> a, b = np.array([0, 0, 1, 1], bool), np.array([0, 1, 0, 1], bool)
    >>> evaluate_columns(parse_expr("A -> B"), {"A": a, "B": b}, 4).tolist()
    [True, True, False, True]
    """
    out = fold(
        expr,
        var=lambda name: columns[name],
        const=lambda v: np.full(size, v, dtype=bool),
        not_=np.logical_not,
        and_=np.logical_and,
        or_=np.logical_or,
        implies=lambda a, b: np.logical_or(np.logical_not(a), b),
        equiv=np.equal,
        xor=np.logical_xor,
    )
    return np.broadcast_to(out, (size,))


def evaluate(expr: Expr, values: Mapping[str, bool]) -> bool:
    """The truth value of ``expr`` under ``values`` (every id it mentions must have one)."""

    def var(name: str) -> bool:
        try:
            return bool(values[name])
        except KeyError:
            raise UsageError(f"no value for proposition {name!r}") from None

    def go(e: Expr) -> bool:
        if isinstance(e, Var):
            return var(e.name)
        if isinstance(e, Const):
            return e.value
        if isinstance(e, Not):
            return not go(e.operand)
        if isinstance(e, And):
            return all(go(a) for a in e.args)
        if isinstance(e, Or):
            return any(go(a) for a in e.args)
        if isinstance(e, Implies):
            return (not go(e.left)) or go(e.right)
        if isinstance(e, Equiv):
            return go(e.left) == go(e.right)
        return go(e.left) != go(e.right)

    return go(expr)


def to_sympy(expr: Expr, symbols: Mapping[str, Any]) -> Any:
    """The sympy Boolean for ``expr``, with ``symbols[name]`` for each id.

    Examples
    --------
    >>> import sympy
    >>> a, b = sympy.symbols("A B")
    >>> to_sympy(parse_expr("A -> ~B"), {"A": a, "B": b})
    Implies(A, ~B)
    """
    import sympy

    def var(name: str) -> Any:
        try:
            return symbols[name]
        except KeyError:
            raise UsageError(f"no sympy symbol for proposition {name!r}") from None

    def go(e: Expr) -> Any:
        if isinstance(e, Var):
            return var(e.name)
        if isinstance(e, Const):
            return sympy.true if e.value else sympy.false
        if isinstance(e, Not):
            return sympy.Not(go(e.operand))
        if isinstance(e, And):
            return sympy.And(*(go(a) for a in e.args))
        if isinstance(e, Or):
            return sympy.Or(*(go(a) for a in e.args))
        if isinstance(e, Implies):
            return sympy.Implies(go(e.left), go(e.right))
        if isinstance(e, Equiv):
            return sympy.Equivalent(go(e.left), go(e.right))
        return sympy.Xor(go(e.left), go(e.right))

    return go(expr)


# --------------------------------------------------------------------------- printing

_PREC: dict[type, int] = {Equiv: 1, Implies: 2, Or: 3, Xor: 4, And: 5, Not: 6, Var: 7, Const: 7}
_SYMBOL: dict[type, str] = {Equiv: "=", Implies: "->", Or: "|", Xor: "^", And: "&"}


def to_text(expr: Expr) -> str:
    """The canonical ASCII text of ``expr``; ``parse_expr(to_text(e)) == e``.

    Operators ``~ & ^ | -> =`` with one space around binary ones; parentheses only where the
    tree needs them.

    Examples
    --------
    >>> to_text(And((Var("A"), Or((Var("B"), Not(Var("C")))))))
    'A & (B | ~C)'
    >>> to_text(Implies(Implies(Var("A"), Var("B")), Var("C")))
    '(A -> B) -> C'
    """
    if isinstance(expr, Var):
        return expr.name
    if isinstance(expr, Const):
        return "1" if expr.value else "0"
    if isinstance(expr, Not):
        inner = expr.operand
        text = to_text(inner)
        return f"~({text})" if _PREC[type(inner)] < _PREC[Not] else f"~{text}"
    if isinstance(expr, And | Or):
        sym = _SYMBOL[type(expr)]
        return f" {sym} ".join(_wrap(a, expr, same_ok=False) for a in expr.args)
    sym = _SYMBOL[type(expr)]
    left_ok = isinstance(expr, Xor)  # xor is left-associative
    right_ok = isinstance(expr, Implies)  # implication is right-associative
    left = _wrap(expr.left, expr, same_ok=left_ok)
    right = _wrap(expr.right, expr, same_ok=right_ok)
    return f"{left} {sym} {right}"


def _wrap(child: Expr, parent: Expr, *, same_ok: bool) -> str:
    text = to_text(child)
    pc, pp = _PREC[type(child)], _PREC[type(parent)]
    if pc < pp or (pc == pp and not same_ok):
        return f"({text})"
    return text
