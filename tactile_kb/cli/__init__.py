"""The ``tactile-kb`` command line.

Subcommands live in modules named for what they act on (``tactile_kb.cli.kb`` for rule files,
``tactile_kb.cli.explore`` for objects, ``tactile_kb.cli.grasp`` for grasps and pictures); each
exposes ``register(subparsers)`` and sets ``func(args) -> int`` on its parsers. This module turns
every error into one line on stderr and an exit code: 0 success, 1 failure (invalid input
file, an object that could not be classified), 2 usage error; never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from typing import NoReturn

from tactile_kb.errors import (
    PluginError,
    PluginUnavailableError,
    SourceError,
    TactileKBError,
    UsageError,
)

__all__ = ["main"]

COMMAND_MODULES = (
    "tactile_kb.cli.kb",
    "tactile_kb.cli.explore",
    "tactile_kb.cli.grasp",
    "tactile_kb.cli.batch",
)

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3


class _ArgumentError(Exception):
    pass


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line, raised instead of exiting."""

    def error(self, message: str) -> NoReturn:
        raise _ArgumentError(f"{self.prog}: {message}")


def build_parser() -> Parser:
    parser = Parser(
        prog="tactile-kb",
        description="Recognise a 3-D object by touch and say why.",
    )
    from tactile_kb import __version__

    parser.add_argument("--version", action="version", version=f"tactile-kb {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def report(error: TactileKBError) -> int:
    """Print ``error`` as one line per located problem; return its exit code."""
    if isinstance(error, SourceError):
        for problem in error.problems:
            print(problem, file=sys.stderr)
        has_errors = any(p.severity == "error" for p in error.problems)
        return EXIT_FAILED if has_errors else EXIT_OK
    if isinstance(error, UsageError) or (
        isinstance(error, PluginError) and not isinstance(error, PluginUnavailableError)
    ):  # a bad argument: an unknown name, a value out of range
        print(f"tactile-kb: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    print(f"tactile-kb: error: {error}", file=sys.stderr)
    return EXIT_FAILED


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        # A subcommand may take positionals after its options (`query RULES --json A=1 B=0`):
        # it names the list they join with ``set_defaults(interleaved="assignments")``.
        interleaved = getattr(args, "interleaved", None)
        if extra and interleaved and not any(e.startswith("-") for e in extra):
            getattr(args, interleaved).extend(extra)
        elif extra:
            parser.error(f"unrecognized arguments: {' '.join(extra)}")
    except _ArgumentError as exc:
        print(f"{exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        code: int = args.func(args)
    except TactileKBError as exc:
        return report(exc)
    except KeyboardInterrupt:
        print("tactile-kb: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except Exception as exc:  # the last line of defence: never a traceback
        print(f"tactile-kb: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
        return EXIT_INTERNAL
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
