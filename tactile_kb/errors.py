"""The exception hierarchy of tactile_kb.

Every error the library raises on purpose derives from :class:`TactileKBError`; the CLI turns
each into one line and an exit code, never a traceback::

    TactileKBError
    ├── SourceError                 located problems in a YAML file (file:line:column: path: message)
    │   ├── RuleFileError           a rule file (rules/*.yaml)
    │   └── LayoutFileError         a custom finger layout
    ├── ExpressionError             a malformed rule expression (carries the column of the bad token)
    ├── UsageError                  a bad argument to the API or the CLI (CLI exit 2)
    ├── ObjectError                 an object that cannot be explored (unreadable, empty, open, too large)
    ├── ExplorationError            exploration could not proceed (the finger never touches, ...)
    ├── GeometryError               the touched planes give no model
    │   └── OpenModelError          the planes do not bound a region (names the open directions)
    ├── RecordError                 an exploration record that cannot be loaded
    ├── OutputError                 an output file (a picture, a report) that cannot be written
    └── PluginError                 a plugin (explorer, feature extractor) is unknown or broken
        └── PluginUnavailableError  a plugin is known but cannot load; carries its install hint
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

__all__ = [
    "ExplorationError",
    "ExpressionError",
    "GeometryError",
    "LayoutFileError",
    "ObjectError",
    "OpenModelError",
    "OutputError",
    "PluginError",
    "PluginUnavailableError",
    "Problem",
    "RecordError",
    "RuleFileError",
    "SourceError",
    "TactileKBError",
    "UsageError",
]


class TactileKBError(Exception):
    """Base of every error tactile_kb raises on purpose."""


@dataclass(frozen=True)
class Problem:
    """One located problem in a source file.

    ``line`` and ``column`` are 1-based; 0 means "unknown" (the whole file).
    """

    file: str
    line: int
    column: int
    path: str
    message: str
    severity: Literal["error", "warning"] = "error"

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}" if self.line else self.file
        what = f"{self.path}: {self.message}" if self.path else self.message
        tag = "" if self.severity == "error" else "warning: "
        return f"{where}: {tag}{what}"


class SourceError(TactileKBError):
    """Problems found in a YAML source; ``problems`` lists every one, in file order."""

    def __init__(self, problems: list[Problem], excerpt: str = "") -> None:
        self.problems = sorted(problems, key=lambda p: (p.file, p.line, p.column))
        self.excerpt = excerpt
        super().__init__("\n".join(str(p) for p in self.problems))


class RuleFileError(SourceError):
    """A rule file failed to load, validate or compile."""


class LayoutFileError(SourceError):
    """A finger-layout file failed to load or validate."""


class ExpressionError(TactileKBError):
    """A malformed expression; ``column`` is the 1-based column of the bad token in ``text``."""

    def __init__(self, text: str, column: int, message: str) -> None:
        self.text = text
        self.column = column
        self.message = message
        super().__init__(f"column {column}: {message}")


class UsageError(TactileKBError):
    """A bad argument to the API or the CLI."""


class ObjectError(TactileKBError):
    """An object that cannot be explored: unreadable file, empty or open mesh, too large."""


class ExplorationError(TactileKBError):
    """Exploration could not proceed (for example, the finger never touches the object)."""


class GeometryError(TactileKBError):
    """The touched planes give no model."""


class OpenModelError(GeometryError):
    """The planes do not bound a region; ``open_directions`` are unit vectors left unexplored.
    When the planes do close, but only far from where they were touched, ``far_points`` are
    the far vertices, one per open direction (otherwise empty)."""

    def __init__(
        self,
        message: str,
        open_directions: list[tuple[float, float, float]],
        far_points: list[tuple[float, float, float]] | None = None,
    ) -> None:
        self.open_directions = open_directions
        self.far_points = far_points or []
        super().__init__(message)


class RecordError(TactileKBError):
    """An exploration record that cannot be loaded."""


class OutputError(TactileKBError):
    """An output file (a picture, a report) that cannot be written; nothing is left half-written."""


class PluginError(TactileKBError):
    """A plugin (explorer or feature extractor) that is unknown or broken."""


class PluginUnavailableError(PluginError):
    """A known plugin that cannot load; ``hint`` says how to install it."""

    def __init__(self, name: str, hint: str, reason: str = "") -> None:
        self.name = name
        self.hint = hint
        self.reason = reason
        why = f" ({reason})" if reason else ""
        super().__init__(f"{name!r} cannot load{why}; install it with: {hint}")
