"""Rule files: propositions, connections, phases and classes, loaded and validated.

A rule file (``rules/*.yaml``, format in ``docs/rules.md``) declares the base of propositions
L = {L1 … Ln} with the feature that decides each, the logical connections between them (in the
paper's equality form ``B = ~C``, or as implications and exclusions), the phases of the choice
tree (paper Fig. 3), and the classes with the answer printed for each. :func:`load_rules` reads
one through :func:`tactile_kb.yaml_source.load_yaml` (duplicate keys and YAML 1.1 surprises are
reported there), validates its shape with pydantic and then its meaning, and raises one
:class:`~tactile_kb.errors.RuleFileError` that lists *every* problem as
``file:line:column: path: message``; expression problems point at the offending token inside
the expression.

Examples
--------
>>> rules = load_rules("parallelepipeds")
>>> rules.ids[:7]
('A', 'B', 'C', 'D', 'E', 'F', 'G')
>>> rules.proposition("E").text
'"Vertical" edges join at one point'
>>> [c.answer for c in rules.classes][:2]
['OBJECT IS A CUBE', 'OBJECT IS A RECTANGULAR PARALLELEPIPED']
>>> parse_rules("name: x\\npropositions: [{id: A, text: a}]\\nphases: [{id: I, propositions: [A]}]\\n"
...             "classes: [{id: a, answer: A, when: A & B}]\\notherwise: {id: u, answer: U}\\n",
...             file="x.yaml")
Traceback (most recent call last):
  ...
tactile_kb.errors.RuleFileError: x.yaml:4:40: classes[0].when: unknown proposition 'B'
"""

from __future__ import annotations

import difflib
import importlib.resources
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from functools import cached_property
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field
from pydantic_core import PydanticCustomError

from tactile_kb.errors import ExpressionError, Problem, RuleFileError, UsageError
from tactile_kb.kb.expr import RESERVED, Expr, is_identifier, parse_expr, variables
from tactile_kb.yaml_source import Source, format_path, load_yaml, validate

__all__ = [
    "PAPER_EXAMPLE",
    "Connection",
    "FeatureBinding",
    "Phase",
    "Proposition",
    "RuleClass",
    "RuleSet",
    "available_rule_sets",
    "load_rules",
    "parse_rules",
    "rules_directories",
]

PathT = tuple[str | int, ...]

_FEATURE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.:-]*$")
_SET_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]*$")
_SUFFIXES = (".yaml", ".yml")


# --------------------------------------------------------------------------- the result


@dataclass(frozen=True)
class FeatureBinding:
    """The feature extractor that decides a proposition, with its keyword parameters.

    ``line``/``column`` locate the feature's name in the file (to report an unknown name).
    """

    name: str
    params: dict[str, Any]
    line: int
    column: int


@dataclass(frozen=True)
class Proposition:
    """One basic proposition L_i: its id, its sentence, its phase and its feature."""

    id: str
    text: str
    phase: str
    feature: FeatureBinding | None
    line: int


@dataclass(frozen=True)
class Connection:
    """A logical connection between propositions (0-based ``index`` in the file).

    ``line``/``column`` locate the first character of the expression; ``path`` is its place in
    the YAML document (``('connections', 2)`` or ``('connections', 2, 'expr')``).
    """

    index: int
    text: str
    expr: Expr
    note: str
    line: int
    column: int
    path: PathT = ()


@dataclass(frozen=True)
class Phase:
    """A phase of the choice tree and the propositions evaluated in it, in order."""

    id: str
    title: str
    propositions: tuple[str, ...]
    line: int


@dataclass(frozen=True)
class RuleClass:
    """A class: its id, the answer printed for it, its name (``L: object is <name>``), and
    its definition ``expr`` (written as ``text``)."""

    id: str
    answer: str
    name: str
    text: str
    expr: Expr
    line: int
    path: PathT = ()
    report: tuple[str, ...] = ()
    """Measures the answer reports (``sides`` for the n of an n-gonal prism, …)."""


@dataclass(frozen=True)
class RuleSet:
    """A loaded, validated rule file. ``propositions`` are in declared order."""

    name: str
    description: str
    file: str
    propositions: tuple[Proposition, ...]
    connections: tuple[Connection, ...]
    phases: tuple[Phase, ...]
    classes: tuple[RuleClass, ...]
    otherwise_id: str
    otherwise_answer: str
    source: Source = field(compare=False, repr=False)

    @cached_property
    def ids(self) -> tuple[str, ...]:
        """The proposition ids in declared order (the order of bit strings)."""
        return tuple(p.id for p in self.propositions)

    @cached_property
    def _by_id(self) -> dict[str, Proposition]:
        return {p.id: p for p in self.propositions}

    def proposition(self, id: str) -> Proposition:
        """The proposition with this id (:class:`UsageError` naming the known ids if none)."""
        try:
            return self._by_id[id]
        except KeyError:
            known = ", ".join(self.ids)
            raise UsageError(
                f"rule set {self.name!r} has no proposition {id!r}; its propositions: {known}"
            ) from None

    def rule_class(self, id: str) -> RuleClass:
        """The class with this id (:class:`UsageError` naming the known classes if none)."""
        for c in self.classes:
            if c.id == id:
                return c
        known = ", ".join(c.id for c in self.classes)
        raise UsageError(f"rule set {self.name!r} has no class {id!r}; its classes: {known}")

    def locate(self, path: Iterable[str | int], offset: int | None = None) -> tuple[int, int]:
        """Line and column of the value at ``path`` in the file, or of character ``offset``
        inside that (string) value — also in multi-line and block scalars."""
        p = tuple(path)
        return self.source.locate(p) if offset is None else _scalar_position(self.source, p, offset)

    def problem(
        self,
        path: Iterable[str | int],
        message: str,
        *,
        severity: str = "error",
        offset: int | None = None,
    ) -> Problem:
        """A :class:`~tactile_kb.errors.Problem` at ``path`` (at ``offset`` inside it)."""
        p = tuple(path)
        line, col = self.locate(p, offset)
        if severity == "warning":
            return Problem(self.file, line, col, format_path(p), message, "warning")
        return Problem(self.file, line, col, format_path(p), message)


# --------------------------------------------------------------------------- the schema


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, int | float):
        return f"the number {value!r}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    return repr(value)


def _fail(kind: str, message: str) -> PydanticCustomError:
    # pydantic formats ``{name}`` placeholders from a context; with none the text is kept as is
    return PydanticCustomError(kind, message.replace("{", "(").replace("}", ")"))


def _check_id(value: Any) -> Any:
    if not isinstance(value, str):
        raise _fail("id_type", f"an id must be a string, not {_kind(value)} (quote it)")
    if value in RESERVED:
        raise _fail("id_reserved", f"{value!r} is a constant and cannot be an id")
    if not is_identifier(value):
        raise _fail(
            "id_pattern",
            f"{value!r} is not an id: use a letter or an identifier ([A-Za-z_][A-Za-z0-9_]*)",
        )
    return value


def _check_feature_name(value: Any) -> Any:
    if not isinstance(value, str):
        raise _fail("feature_name_type", f"a feature name must be a string, not {_kind(value)}")
    if not _FEATURE_NAME.match(value):
        raise _fail("feature_name_pattern", f"{value!r} is not a feature name")
    return value


def _check_set_name(value: Any) -> Any:
    if isinstance(value, str) and not _SET_NAME.match(value):
        raise _fail("set_name", f"{value!r} is not a rule-set name ([A-Za-z0-9_.-]+)")
    return value


def _expression_text(value: Any) -> Any:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int) and value in (0, 1):
        return str(value)
    if not isinstance(value, str):
        raise _fail("expr_type", f"an expression must be a string, not {_kind(value)}")
    return value


def _feature_shape(value: Any) -> Any:
    if value is None or isinstance(value, dict):
        return value
    if isinstance(value, str):
        return {"name": value}
    raise _fail(
        "feature_shape",
        f"a feature is a name or a mapping with a name and params, not {_kind(value)}",
    )


def _connection_shape(value: Any) -> Any:
    return value if isinstance(value, dict) else {"expr": value}


def _none_is_empty(value: Any) -> Any:
    return [] if value is None else value


Id = Annotated[str, BeforeValidator(_check_id)]
Text = Annotated[str, Field(min_length=1)]
ExprText = Annotated[str, BeforeValidator(_expression_text)]
_STRICT = ConfigDict(extra="forbid", strict=True)


class _FeatureModel(BaseModel):
    model_config = _STRICT
    name: Annotated[str, BeforeValidator(_check_feature_name)]
    params: dict[str, Any] = Field(default_factory=dict)


class _PropositionModel(BaseModel):
    model_config = _STRICT
    id: Id
    text: Text
    feature: Annotated[_FeatureModel | None, BeforeValidator(_feature_shape)] = None


class _ConnectionModel(BaseModel):
    model_config = _STRICT
    expr: ExprText
    note: str = ""


class _PhaseModel(BaseModel):
    model_config = _STRICT
    id: Id
    title: str = ""
    propositions: list[Id]


class _ClassModel(BaseModel):
    model_config = _STRICT
    id: Id
    answer: Text
    name: Text | None = None
    when: ExprText
    report: list[Id] = []


class _OtherwiseModel(BaseModel):
    model_config = _STRICT
    id: Id
    answer: Text


class _RuleFileModel(BaseModel):
    model_config = _STRICT
    name: Annotated[str, BeforeValidator(_check_set_name)]
    description: str = ""
    propositions: list[_PropositionModel]
    connections: Annotated[
        list[Annotated[_ConnectionModel, BeforeValidator(_connection_shape)]],
        BeforeValidator(_none_is_empty),
    ] = Field(default_factory=list)
    phases: list[_PhaseModel]
    classes: list[_ClassModel]
    otherwise: _OtherwiseModel


# --------------------------------------------------------------------------- loading


def parse_rules(text: str, file: str = "<string>") -> RuleSet:
    """Load a rule set from YAML ``text`` (``file`` names it in messages).

    Raises
    ------
    RuleFileError
        Listing every problem found, each located at ``file:line:column``; ``excerpt`` shows
        the source around the first one.
    """
    return _build(load_yaml(text, file=file, error_cls=RuleFileError, keep_going=True))


def load_rules(name_or_path: str | Path) -> RuleSet:
    """Load a rule set by packaged name (``"parallelepipeds"``) or from a file.

    A ``Path`` is always a file. A string is a packaged rule set when one has that name (with
    or without ``.yaml``), else a file path.

    Raises
    ------
    RuleFileError
        The file has problems (every one is listed) or cannot be read.
    UsageError
        The string is neither a packaged rule set nor an existing file; the message names the
        packaged rule sets.
    """
    if isinstance(name_or_path, Path):
        return _build(load_yaml(name_or_path, error_cls=RuleFileError, keep_going=True))
    text = str(name_or_path)
    looks_like_name = "/" not in text and "\\" not in text
    if looks_like_name:
        stem = text[: -len(s)] if (s := _suffix(text)) else text
        packaged = _packaged().get(stem)
        if packaged is not None and (not _suffix(text) or not Path(text).is_file()):
            return _load_traversable(packaged)
    path = Path(text)
    if text and path.exists():  # a directory or device is refused by load_yaml, located
        return _build(load_yaml(path, error_cls=RuleFileError, keep_going=True))
    known = ", ".join(available_rule_sets()) or "(none found)"
    raise UsageError(
        f"no rule file {text!r} and no packaged rule set of that name; packaged rule sets: {known}"
    )


def rules_directories() -> list[Traversable]:
    """Where packaged rule sets are looked for: the installed ``tactile_kb/kb/rules`` first,
    then the source checkout's top-level ``rules/``."""
    dirs: list[Traversable] = []
    try:
        installed = importlib.resources.files("tactile_kb") / "rules"
        if installed.is_dir():
            dirs.append(installed)
    except (ModuleNotFoundError, OSError):  # pragma: no cover - tactile_kb is importable here
        pass
    checkout = Path(__file__).resolve().parents[2] / "rules"
    if checkout.is_dir() and not any(str(d) == str(checkout) for d in dirs):
        dirs.append(checkout)
    return dirs


def available_rule_sets() -> list[str]:
    """Names of the packaged rule sets, sorted."""
    return sorted(_packaged())


def _suffix(text: str) -> str:
    return next((s for s in _SUFFIXES if text.endswith(s)), "")


def _packaged() -> dict[str, Traversable]:
    found: dict[str, Traversable] = {}
    for directory in rules_directories():
        for entry in sorted(directory.iterdir(), key=lambda e: e.name):
            suffix = _suffix(entry.name)
            stem = entry.name[: -len(suffix)] if suffix else ""
            if stem and not stem.startswith(".") and entry.is_file():
                found.setdefault(stem, entry)
    return found


def _load_traversable(entry: Traversable) -> RuleSet:
    if isinstance(entry, Path):
        return _build(load_yaml(entry, error_cls=RuleFileError, keep_going=True))
    text = entry.read_text(encoding="utf-8")  # pragma: no cover - zipped installs only
    return parse_rules(text, file=str(entry))  # pragma: no cover


def _build(src: Source) -> RuleSet:
    if not isinstance(src.data, dict):
        what = "empty" if src.data is None else f"{_kind(src.data)}, not a mapping"
        msg = f"the rule file is {what}: it needs name, propositions, phases, classes, otherwise"
        raise RuleFileError([Problem(src.file, 1, 1, "", msg)], src.excerpt(1, 1))
    problems: list[Problem] = list(src.problems)  # duplicate keys, reported with the rest
    model: _RuleFileModel | None = None
    try:
        model = validate(src, _RuleFileModel, error_cls=RuleFileError)
    except RuleFileError as exc:
        problems.extend(exc.problems)
    checker = _Checker(src)
    checker.run()
    seen = {(p.line, p.column, p.message) for p in problems}
    for p in checker.problems:
        if (p.line, p.column, p.message) not in seen:
            seen.add((p.line, p.column, p.message))
            problems.append(p)
    if problems or model is None:
        first = min(problems, key=lambda p: (p.line, p.column))
        raise RuleFileError(problems, src.excerpt(first.line, first.column))
    return _rule_set(src, model, checker)


# --------------------------------------------------------------------------- semantic checks


def _items(data: Any, key: str) -> Iterator[tuple[int, dict[str, Any]]]:
    seq = data.get(key) if isinstance(data, dict) else None
    if isinstance(seq, list):
        for i, item in enumerate(seq):
            if isinstance(item, dict):
                yield i, item


def _valid_id(value: Any) -> str | None:
    return value if isinstance(value, str) and is_identifier(value) else None


def _suggest(name: str, known: Iterable[str]) -> str:
    ids = sorted(known)
    same_letters = [k for k in ids if k.lower() == name.lower()]
    close = same_letters or difflib.get_close_matches(name, ids, n=1, cutoff=0.6)
    return f"; did you mean {close[0]!r}?" if close else ""


class _Checker:
    """The checks pydantic cannot make, run on the raw data so that they are reported even
    when parts of the file have the wrong shape."""

    def __init__(self, src: Source) -> None:
        self.src = src
        self.data = src.data
        self.problems: list[Problem] = []
        self.exprs: dict[PathT, Expr] = {}
        self.phase_of: dict[str, str] = {}
        self.known: set[str] | None = None

    def add(self, path: PathT, message: str, offset: int | None = None) -> None:
        if offset is None:
            line, col = self.src.locate(path)
        else:
            line, col = _scalar_position(self.src, path, offset)
        self.problems.append(Problem(self.src.file, line, col, format_path(path), message))

    def run(self) -> None:
        if not isinstance(self.data, dict):  # pragma: no cover - _build rejects it first
            return
        self.propositions()
        self.phases()
        self.expressions()
        self.classes()

    def _unique(self, key: str, what: str) -> dict[str, int]:
        first: dict[str, int] = {}
        for i, item in _items(self.data, key):
            ident = _valid_id(item.get("id"))
            if ident is None:
                continue
            if ident in first:
                line = self.src.locate((key, first[ident], "id"))[0]
                self.add((key, i, "id"), f"duplicate {what} id {ident!r} (first at line {line})")
            else:
                first[ident] = i
        return first

    def propositions(self) -> None:
        props = self.data.get("propositions")
        if isinstance(props, list):
            if not props:
                self.add(("propositions",), "a rule file needs at least one proposition")
            self.known = set(self._unique("propositions", "proposition"))

    def phases(self) -> None:
        phases = self.data.get("phases")
        if not isinstance(phases, list):
            return
        self._unique("phases", "phase")
        where: dict[str, tuple[str, int]] = {}
        complete = all(isinstance(item, dict) for item in phases)
        for j, phase in _items(self.data, "phases"):
            pid = _valid_id(phase.get("id")) or f"#{j + 1}"
            listed = phase.get("propositions")
            if not isinstance(listed, list):
                complete = False  # pydantic reports it; "in no phase" would only be noise
                continue
            if not listed:
                self.add(("phases", j, "propositions"), f"phase {pid!r} names no proposition")
            for k, name in enumerate(listed):
                if _valid_id(name) is None:
                    continue
                path: PathT = ("phases", j, "propositions", k)
                if self.known is not None and name not in self.known:
                    hint = _suggest(name, self.known)
                    self.add(path, f"unknown proposition {name!r}{hint}")
                elif name in where:
                    other, line = where[name]
                    again = "again" if other == pid else f"also in phase {other!r}"
                    self.add(path, f"proposition {name!r} is {again} (line {line})")
                else:
                    where[name] = (pid, self.src.locate(path)[0])
                    self.phase_of[name] = pid
        if self.known is None or not complete:
            return
        for i, prop in _items(self.data, "propositions"):
            ident = _valid_id(prop.get("id"))
            if ident is not None and ident not in where:
                self.add(("propositions", i, "id"), f"proposition {ident!r} is in no phase")

    def _expression(self, path: PathT, text: Any) -> None:
        if isinstance(text, bool) or (isinstance(text, int) and text in (0, 1)):
            text = _expression_text(text)
        if not isinstance(text, str):
            return
        try:
            expr = parse_expr(text)
        except ExpressionError as exc:
            self.add(path, exc.message, offset=exc.column - 1)
            return
        self.exprs[path] = expr
        if self.known is None:
            return
        for var in variables(expr):
            if var.name not in self.known:
                hint = _suggest(var.name, self.known)
                self.add(path, f"unknown proposition {var.name!r}{hint}", offset=var.pos)

    def expressions(self) -> None:
        conns = self.data.get("connections")
        if isinstance(conns, list):
            for i, item in enumerate(conns):
                if isinstance(item, dict):
                    self._expression(("connections", i, "expr"), item.get("expr"))
                else:
                    self._expression(("connections", i), item)
        for i, item in _items(self.data, "classes"):
            self._expression(("classes", i, "when"), item.get("when"))

    def classes(self) -> None:
        first = self._unique("classes", "class")
        otherwise = self.data.get("otherwise")
        other = _valid_id(otherwise.get("id")) if isinstance(otherwise, dict) else None
        if other is not None and other in first:
            line = self.src.locate(("otherwise", "id"))[0]
            self.add(
                ("classes", first[other], "id"),
                f"class id {other!r} is also the otherwise id (line {line})",
            )


def _rule_set(src: Source, model: _RuleFileModel, checker: _Checker) -> RuleSet:
    propositions = []
    for i, p in enumerate(model.propositions):
        binding = None
        if p.feature is not None:
            raw = src.data["propositions"][i]["feature"]
            fpath: PathT = ("propositions", i, "feature")
            fline, fcol = src.locate((*fpath, "name") if isinstance(raw, dict) else fpath)
            binding = FeatureBinding(p.feature.name, dict(p.feature.params), fline, fcol)
        line = src.locate(("propositions", i, "id"))[0]
        propositions.append(Proposition(p.id, p.text, checker.phase_of[p.id], binding, line))
    connections = []
    for i, c in enumerate(model.connections):
        raw = src.data["connections"][i]
        path: PathT = ("connections", i, "expr") if isinstance(raw, dict) else ("connections", i)
        line, col = _scalar_position(src, path, 0)
        connections.append(Connection(i, c.expr, checker.exprs[path], c.note, line, col, path))
    phases = tuple(
        Phase(ph.id, ph.title, tuple(ph.propositions), src.locate(("phases", j, "id"))[0])
        for j, ph in enumerate(model.phases)
    )
    classes = []
    for i, k in enumerate(model.classes):
        path = ("classes", i, "when")
        name = k.name if k.name is not None else k.id.replace("_", " ")
        line = src.locate(("classes", i, "id"))[0]
        classes.append(
            RuleClass(
                k.id, k.answer, name, k.when, checker.exprs[path], line, path, tuple(k.report)
            )
        )
    return RuleSet(
        name=model.name,
        description=model.description,
        file=src.file,
        propositions=tuple(propositions),
        connections=tuple(connections),
        phases=phases,
        classes=tuple(classes),
        otherwise_id=model.otherwise.id,
        otherwise_answer=model.otherwise.answer,
        source=src,
    )


# --------------------------------------------------------------------------- positions


def _scalar_position(src: Source, path: PathT, offset: int) -> tuple[int, int]:
    """Line and column of character ``offset`` of the string scalar at ``path``.

    Walks the raw text from the scalar's start mark alongside the loaded value, so that folded
    line breaks, indentation, block scalars (``|``, ``>``) and quote escapes are accounted for.
    """
    value = _value_at(src.data, path)
    line, col = src.locate(path)
    if not isinstance(value, str):
        return line, col
    raw = src.text
    starts = [0]
    for k, ch in enumerate(raw):
        if ch == "\n":
            starts.append(k + 1)
    if line < 1 or line > len(starts):
        return line, col
    p = starts[line - 1] + col - 1
    n = len(raw)
    quote = raw[p] if p < n and raw[p] in "'\"" else ""
    if quote:
        p += 1
    indent = -1  # in a block scalar, the indentation removed from each line
    if not quote and p < n and raw[p] in "|>":
        nl = raw.find("\n", p)
        p = n if nl < 0 else nl + 1
        q = _skip_blanks(raw, p, newlines=False)
        indent, p = q - p, q

    for ch in value[: max(0, min(offset, len(value)))]:
        if p >= n:
            break
        if raw[p] == ch:
            p += 1
            if ch == "\n" and indent >= 0:
                p = min(_skip_blanks(raw, p, newlines=False), p + indent)
        elif raw[p] in " \t\r\n":
            p = _skip_blanks(raw, p, newlines=True)
            if ch not in " \n" and p < n and raw[p] == ch:
                p += 1
        elif (quote == "'" and ch == "'" and raw.startswith("''", p)) or (
            quote == '"' and raw[p] == "\\"
        ):
            p += 2
        else:
            p += 1
    if offset < len(value) and not value[offset].isspace() and p < n and raw[p] in " \t\r\n":
        p = _skip_blanks(raw, p, newlines=True)
    p = min(p, n)
    out_line = raw.count("\n", 0, p) + 1
    return out_line, p - starts[out_line - 1] + 1


def _skip_blanks(raw: str, p: int, *, newlines: bool) -> int:
    blanks = " \t\r\n" if newlines else " \t"
    while p < len(raw) and raw[p] in blanks:
        p += 1
    return p


def _value_at(data: Any, path: PathT) -> Any:
    node = data
    for part in path:
        in_dict = isinstance(node, dict) and isinstance(part, str) and part in node
        in_list = isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node)
        if in_dict or in_list:
            node = node[part]
        else:
            return None
    return node


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
