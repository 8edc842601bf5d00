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

__all__ = ["Source", "format_path", "load_yaml", "render_excerpt", "validate"]

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


def load_yaml(
    source: str | Path,
    *,
    file: str | None = None,
    error_cls: type[SourceError] = SourceError,
    keep_going: bool = False,
) -> Source:
    """Compose YAML from a path or from text and return a :class:`Source`.

    A ``Path`` is read from disk; a ``str`` is YAML text (name it with ``file``). Syntax errors
    raise ``error_cls``. Duplicate keys, merge keys and non-scalar keys raise ``error_cls``
    listing every one, or with ``keep_going=True`` are returned in :attr:`Source.problems` (the
    first occurrence of a duplicated key is kept) so that a caller can report them together
    with its own validation problems.
    """
    if isinstance(source, Path):
        name = file or str(source)
        try:
            text = source.read_text(encoding="utf-8")
        except OSError as exc:
            raise error_cls(
                [Problem(name, 0, 0, "", f"cannot read: {exc.strerror or exc}")]
            ) from None
        except UnicodeDecodeError as exc:
            raise error_cls([Problem(name, 0, 0, "", f"not UTF-8 text: {exc.reason}")]) from None
    else:
        name, text = file or "<string>", source
    try:
        try:
            node = yaml.compose(text, Loader=_Core12Loader)
        except yaml.MarkedYAMLError:
            node = yaml.compose(text, Loader=_Core12PyLoader)  # raises with the clearer message
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        msg = f"YAML syntax error: {exc.problem or exc.context}"
        raise error_cls(
            [Problem(name, line, col, "", msg)], render_excerpt(text, line, col)
        ) from None
    except yaml.YAMLError as exc:  # pragma: no cover - composer errors are all marked
        raise error_cls([Problem(name, 0, 0, "", f"YAML error: {exc}")]) from None
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
        if node.anchor if hasattr(node, "anchor") else False:  # pragma: no cover - defensive
            self._problem(node, path, "anchors and aliases are not supported")
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
