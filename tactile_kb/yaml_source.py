"""Strict YAML sources that remember where every value came from.

PyYAML's ``safe_load`` drops duplicate keys silently, reads ``0777`` as octal and ``no``/``on``/
``off`` as booleans (YAML 1.1). Rule files and finger layouts are read here instead: the
document is *composed* into nodes that keep their start marks, duplicate keys are reported,
scalars follow a YAML 1.2-like core schema in which only ``true``/``false`` are booleans and a
number with a leading zero stays a string, and pydantic validation errors are mapped back to
``file:line:column: path: message``.

Examples
--------
>>> src = load_yaml("a: no\\nb: 0777\\nc: true\\nd: 12\\n", file="x.yaml")
>>> src.data
{'a': 'no', 'b': '0777', 'c': True, 'd': 12}
>>> src.locate(("b",))
(2, 4)
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from tactile_kb.errors import Problem, SourceError
from tactile_kb.files import MAX_YAML_BYTES, InputFileError, read_text

__all__ = ["MAX_DEPTH", "Source", "format_path", "load_yaml", "render_excerpt", "validate"]

PathT = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)

_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")
_INT = re.compile(r"^[-+]?(?:0|[1-9][0-9_]*)$|^0x[0-9a-fA-F]+$|^0o[0-7]+$")
_FLOAT = re.compile(
    r"^[-+]?(?:(?:0|[1-9][0-9]*)?\.[0-9]+|(?:0|[1-9][0-9]*)\.?)(?:[eE][-+]?[0-9]+)?$"
    r"|^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$"
)


# libyaml's parser when PyYAML was built with it (about 5x faster), else the pure-Python one;
# both give the same nodes and marks. Resolution stays in Python, so the schema below holds.
_BaseLoader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _Core12Loader(_BaseLoader):  # type: ignore[valid-type,misc]
    """A loader whose implicit resolvers follow the YAML 1.2 core schema (no yes/no/on/off)."""


class _Core12PyLoader(yaml.SafeLoader):
    """The same schema on the pure-Python parser, whose syntax messages are more specific."""


for _loader in (_Core12Loader, _Core12PyLoader):
    _loader.yaml_implicit_resolvers = {}
    for _tag, _rx, _first in [
        ("tag:yaml.org,2002:bool", _BOOL, list("tTfF")),
        ("tag:yaml.org,2002:null", _NULL, ["~", "n", "N", ""]),
        ("tag:yaml.org,2002:int", _INT, list("-+0123456789")),
        ("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789.")),
    ]:
        _loader.add_implicit_resolver(_tag, _rx, _first)


@dataclass(frozen=True)
class Source:
    """A composed YAML document: plain ``data`` plus the 1-based position of every value."""

    file: str
    text: str
    data: Any
    positions: dict[PathT, tuple[int, int]] = field(default_factory=dict)
    key_positions: dict[PathT, tuple[int, int]] = field(default_factory=dict)
    scalar_offsets: dict[PathT, int] = field(default_factory=dict)
    problems: tuple[Problem, ...] = ()
    """Structural problems (duplicate keys, unsupported keys) kept with ``keep_going=True``."""

    def locate(self, path: Iterable[str | int], *, key: bool = False) -> tuple[int, int]:
        """Line and column of the value at ``path`` (of its key with ``key=True``).

        A path that does not exist (a missing field) gives its nearest existing ancestor.
        """
        p = tuple(path)
        while True:
            if key and p in self.key_positions:
                return self.key_positions[p]
            if p in self.positions:
                return self.positions[p]
            if not p:
                return (1, 1)
            p = p[:-1]
            key = False

    def locate_in_scalar(self, path: Iterable[str | int], offset: int) -> tuple[int, int]:
        """Position of character ``offset`` (0-based) inside the one-line scalar at ``path``."""
        p = tuple(path)
        line, col = self.locate(p)
        return line, col + self.scalar_offsets.get(p, 0) + offset

    def problem(
        self,
        path: Iterable[str | int],
        message: str,
        *,
        severity: str = "error",
        key: bool = False,
        offset: int | None = None,
    ) -> Problem:
        """A :class:`Problem` located at ``path`` (or at ``offset`` inside its scalar)."""
        p = tuple(path)
        line, col = (
            self.locate_in_scalar(p, offset) if offset is not None else self.locate(p, key=key)
        )
        if severity == "warning":
            return Problem(self.file, line, col, format_path(p), message, "warning")
        return Problem(self.file, line, col, format_path(p), message)

    def excerpt(self, line: int, column: int, context: int = 1) -> str:
        """A numbered excerpt of the source around ``line`` with a caret under ``column``."""
        return render_excerpt(self.text, line, column, context)


def format_path(path: Iterable[str | int]) -> str:
    """``('phases', 0, 'propositions')`` → ``phases[0].propositions``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def render_excerpt(text: str, line: int, column: int, context: int = 1) -> str:
    """Numbered lines ``line-context .. line+context`` with a caret under ``column``."""
    lines = text.splitlines()
    if not 1 <= line <= len(lines):
        return ""
    lo, hi = max(1, line - context), min(len(lines), line + context)
    width = len(str(hi))
    out = []
    for n in range(lo, hi + 1):
        out.append(f"{n:>{width}} | {lines[n - 1]}")
        if n == line:
            out.append(f"{'':>{width}} | {' ' * max(0, column - 1)}^")
    return "\n".join(out)


MAX_DEPTH = 64
"""The deepest nesting of lists and mappings a YAML source may have (rule files use 5)."""


def load_yaml(
    source: str | Path,
    *,
    file: str | None = None,
    error_cls: type[SourceError] = SourceError,
    keep_going: bool = False,
    max_bytes: int = MAX_YAML_BYTES,
) -> Source:
    """Compose YAML from a path or from text and return a :class:`Source`.

    A ``Path`` is read from disk (a regular file of at most ``max_bytes``); a ``str`` is YAML
    text (name it with ``file``). Syntax errors, anchors and aliases (``&a``, ``*a``: refused,
    so that an alias bomb cannot expand), nesting deeper than :data:`MAX_DEPTH` and text that
    is not UTF-8 raise ``error_cls`` with one located problem. Duplicate keys, merge keys and
    non-scalar keys raise ``error_cls`` listing every one, or with ``keep_going=True`` are
    returned in :attr:`Source.problems` (the first occurrence of a duplicated key is kept) so
    that a caller can report them together with its own validation problems.
    """
    if isinstance(source, Path):
        name = file or str(source)
        try:
            text = read_text(source, max_bytes=max_bytes)
        except InputFileError as exc:
            raise error_cls([Problem(name, exc.line, exc.column, "", exc.message)]) from None
    else:
        name, text = file or "<string>", source
        if len(text) > max_bytes:
            raise error_cls([Problem(name, 0, 0, "", f"text too large ({len(text)} characters)")])
    problem = _check_events(text, name)
    if problem is not None:
        raise error_cls([problem], render_excerpt(text, problem.line, problem.column))
    try:
        node = yaml.compose(text, Loader=_Core12Loader)
    except yaml.YAMLError as exc:  # pragma: no cover - the event pass found every syntax error
        raise error_cls([Problem(name, 0, 0, "", f"YAML error: {_one_line(str(exc))}")]) from None
    builder = _Builder(name)
    data = None if node is None else builder.build(node, ())
    if builder.problems and not keep_going:
        first = builder.problems[0]
        raise error_cls(builder.problems, render_excerpt(text, first.line, first.column))
    return Source(
        name,
        text,
        data,
        builder.positions,
        builder.key_positions,
        builder.offsets,
        tuple(builder.problems),
    )


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _line_col(text: str, index: int) -> tuple[int, int]:
    """1-based line and column of character ``index`` of ``text``."""
    before = text[:index]
    return before.count("\n") + 1, index - (before.rfind("\n") + 1) + 1


def _check_events(text: str, name: str) -> Problem | None:
    """The first syntax error, anchor, alias or too-deep nesting of ``text``, located.

    The event stream is read without building anything (libyaml's parser keeps its own
    stack), so an alias bomb or a file nested 30 000 deep costs no more than its size.
    """
    depth = 0
    try:
        for event in yaml.parse(text, Loader=_Core12Loader):
            if isinstance(event, yaml.AliasEvent):
                line, col = _mark(event.start_mark)
                return Problem(name, line, col, "", f"aliases (*{event.anchor}) are not supported")
            if isinstance(event, yaml.NodeEvent) and event.anchor is not None:
                line, col = _mark(event.start_mark)
                return Problem(name, line, col, "", f"anchors (&{event.anchor}) are not supported")
            if isinstance(event, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_DEPTH:
                    line, col = _mark(event.start_mark)
                    return Problem(name, line, col, "", f"nested more than {MAX_DEPTH} levels deep")
            elif isinstance(event, yaml.CollectionEndEvent):
                depth -= 1
    except yaml.reader.ReaderError as exc:
        line, col = _line_col(text, exc.position)
        what = f"U+{exc.character:04X}" if isinstance(exc.character, int) else repr(exc.character)
        return Problem(name, line, col, "", f"control character {what} is not allowed in YAML")
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        if "nesting depth" in str(exc.problem) and mark is not None and 0 < mark.index < len(text):
            # PyYAML ≥ 6.0.4 refuses nesting over 1000 while it scans ahead, before the events
            # reach MAX_DEPTH: the text up to that point holds the first level too deep
            found = _check_events(text[: mark.index], name)
            if found is not None and found.message.startswith("nested more than"):
                return found
        return _syntax_problem(text, name, exc)
    return None


def _mark(mark: Any) -> tuple[int, int]:
    return (mark.line + 1, mark.column + 1) if mark is not None else (0, 0)


def _syntax_problem(text: str, name: str, exc: yaml.MarkedYAMLError) -> Problem:
    """One located problem for a YAML syntax error, at the construct that was left open.

    libyaml reports where parsing stopped; for an unclosed ``[``, ``{`` or quote, or an unknown
    directive, that is far from the mistake, so the construct's own start is given instead.
    """
    context = exc.context or ""
    problem = exc.problem or context
    # The pure-Python parser's message names the token it found; take it where both agree.
    try:
        for _ in yaml.parse(text, Loader=_Core12PyLoader):
            pass
    except yaml.MarkedYAMLError as py_exc:
        if _mark(py_exc.problem_mark) == _mark(exc.problem_mark) and py_exc.problem:
            problem = py_exc.problem
    except yaml.YAMLError:  # pragma: no cover - both parsers read the same characters
        pass
    at = _mark(exc.problem_mark)
    where = f"line {at[0]}, column {at[1]}"
    if context.startswith("while parsing a flow") and exc.context_mark is not None:
        opener = "[" if "sequence" in context else "{"
        line, col = _mark(exc.context_mark)
        return Problem(
            name,
            line,
            col,
            "",
            f"YAML syntax error: this {opener} is not closed ({problem} at {where})",
        )
    if context.startswith("while scanning a quoted scalar") and exc.context_mark is not None:
        line, col = _mark(exc.context_mark)
        return Problem(
            name, line, col, "", f"YAML syntax error: this quoted string is not closed ({problem})"
        )
    if context.startswith("while scanning a directive") and exc.context_mark is not None:
        line, col = _mark(exc.context_mark)
        return Problem(
            name, line, col, "", f"YAML syntax error: {problem} (a line starting with %)"
        )
    opened = _open_quote_before(text, at)
    if opened is not None:
        line, col = opened
        return Problem(
            name,
            line,
            col,
            "",
            f"YAML syntax error: this quoted string runs on to line {at[0]}; "
            "is its closing quote missing?",
        )
    return Problem(name, at[0], at[1], "", f"YAML syntax error: {problem}")


def _open_quote_before(text: str, at: tuple[int, int]) -> tuple[int, int] | None:
    """The start of a quoted scalar spanning several lines that ends just before ``at``.

    A quote left open swallows the lines after it up to the next quote character, and the
    parser stops there: the quote that was opened is the mistake.
    """
    last: Any = None
    try:
        for token in yaml.scan(text, Loader=_Core12PyLoader):
            if _mark(token.start_mark) >= at:
                break
            last = token
    except yaml.YAMLError:
        pass
    if (
        isinstance(last, yaml.ScalarToken)
        and last.style in ("'", '"')
        and last.end_mark.line > last.start_mark.line
        and last.end_mark.line + 1 == at[0]
    ):
        return _mark(last.start_mark)
    return None


class _Builder:
    def __init__(self, file: str) -> None:
        self.file = file
        self.positions: dict[PathT, tuple[int, int]] = {}
        self.key_positions: dict[PathT, tuple[int, int]] = {}
        self.offsets: dict[PathT, int] = {}
        self.problems: list[Problem] = []

    def _where(self, node: yaml.Node) -> tuple[int, int]:
        return node.start_mark.line + 1, node.start_mark.column + 1

    def _problem(self, node: yaml.Node, path: PathT, message: str) -> None:
        line, col = self._where(node)
        self.problems.append(Problem(self.file, line, col, format_path(path), message))

    def build(self, node: yaml.Node, path: PathT) -> Any:
        self.positions[path] = self._where(node)
        if isinstance(node, yaml.MappingNode):
            out: dict[str, Any] = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    self._problem(key_node, path, "a key must be a plain scalar")
                    continue
                key = str(key_node.value)
                if key == "<<":
                    self._problem(key_node, path, "merge keys (<<) are not supported")
                    continue
                if key in out:
                    first = self.key_positions[(*path, key)]
                    self._problem(
                        key_node, (*path, key), f"duplicate key {key!r} (first at line {first[0]})"
                    )
                    continue
                self.key_positions[(*path, key)] = self._where(key_node)
                out[key] = self.build(value_node, (*path, key))
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, (*path, i)) for i, item in enumerate(node.value)]
        assert isinstance(node, yaml.ScalarNode)
        if node.style in ("'", '"'):
            self.offsets[path] = 1
        return _scalar(node)


def _scalar(node: yaml.ScalarNode) -> Any:
    value: str = node.value
    tag = node.tag
    if node.style in ("'", '"', "|", ">") or tag == "tag:yaml.org,2002:str":
        return value
    if tag == "tag:yaml.org,2002:bool":
        return value.lower() == "true"
    if tag == "tag:yaml.org,2002:null":
        return None
    if tag == "tag:yaml.org,2002:int":
        v = value.replace("_", "")
        if v.startswith("0o"):
            return int(v[2:], 8)
        return int(v, 16) if v.startswith("0x") else int(v)
    if tag == "tag:yaml.org,2002:float":
        low = value.lower()
        if low.endswith("inf"):
            return float("-inf") if low.startswith("-") else float("inf")
        return float("nan") if low.endswith("nan") else float(value)
    return value


def validate(source: Source, model: type[M], *, error_cls: type[SourceError] = SourceError) -> M:
    """Validate ``source.data`` with a pydantic model; raise ``error_cls`` with every located error."""
    try:
        return model.model_validate(source.data)
    except ValidationError as exc:
        problems = []
        for err in exc.errors(include_url=False):
            loc = tuple(p for p in err["loc"] if isinstance(p, str | int))
            # pydantic adds tags of union members / validators to loc; keep the real path
            path: list[str | int] = []
            node: Any = source.data
            for part in loc:
                in_dict = isinstance(node, dict) and isinstance(part, str) and part in node
                in_list = isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node)
                if in_dict or in_list:
                    path.append(part)
                    node = node[part]
                elif err["type"] in ("extra_forbidden", "missing"):
                    path.append(part)
                    break
            is_key = err["type"] == "extra_forbidden"
            msg = err["msg"]
            if err["type"] == "extra_forbidden":
                msg = "unknown field"
            elif err["type"] == "missing":
                msg = "field required"
            problems.append(source.problem(path, msg, key=is_key))
        first = min(problems, key=lambda p: (p.line, p.column))
        raise error_cls(problems, source.excerpt(first.line, first.column)) from None
