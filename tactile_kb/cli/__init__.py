"""The ``tactile-kb`` command line.

Subcommands live in modules named for what they act on (``tactile_kb.cli.kb`` for rule files,
``tactile_kb.cli.explore`` for objects, ``tactile_kb.cli.grasp`` for grasps and pictures); each
exposes ``register(subparsers)`` and sets ``func(args) -> int`` on its parsers. This module turns
every error into one line on stderr and an exit code, never a traceback:

* 0: success;
* 1: an input was read and failed (an invalid rule file, layout or record; an object that could
  not be explored or classified; an output that could not be written). The other inputs of the
  run are still processed;
* 2: the command line is wrong: an unknown option, a bad value, a rule set, explorer or finger
  name that names nothing, an output path in a missing or read-only directory. Found before
  any object is processed;
* 3: a bug in tactile-kb (an error no input should cause); the line says how to report it.

With several inputs, the largest code of any of them is the exit code.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from tactile_kb.cli.options import chosen_settings, error_message
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

_DASHED_VALUES = ("--bits",)
"""Options whose value may start with a dash (``--bits ---------``: every value unknown)."""


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


def report(error: TactileKBError, prog: str = "tactile-kb") -> int:
    """Print ``error`` as one line per located problem; return its exit code."""
    if isinstance(error, SourceError):
        for problem in error.problems:
            print(problem, file=sys.stderr)
        has_errors = any(p.severity == "error" for p in error.problems)
        return EXIT_FAILED if has_errors else EXIT_OK
    if isinstance(error, UsageError) or (
        isinstance(error, PluginError) and not isinstance(error, PluginUnavailableError)
    ):  # a bad argument: an unknown name, a value out of range
        print(f"{prog}: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    print(f"{prog}: error: {error}", file=sys.stderr)
    return EXIT_FAILED


def _join_dashed_values(argv: Sequence[str]) -> list[str]:
    """``["--bits", "---"]`` → ``["--bits=---"]``, so that argparse does not take a value made
    of dashes for an option."""
    out: list[str] = []
    items = list(argv)
    i = 0
    while i < len(items):
        item = items[i]
        if item in _DASHED_VALUES and i + 1 < len(items) and items[i + 1].startswith("-"):
            value = items[i + 1]
            if value and set(value) <= set("01-") and value != "--":
                out.append(f"{item}={value}")
                i += 2
                continue
        out.append(item)
        i += 1
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    parser = build_parser()
    argv = _join_dashed_values(sys.argv[1:] if argv is None else argv)
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
    prog = f"tactile-kb {args.command}"
    try:
        with warnings.catch_warnings():
            # the mesh library's numeric warnings on a messy mesh (the mass properties of a
            # body with no volume) are nothing a user can act on; the notes say what was
            # done to the mesh
            warnings.filterwarnings("ignore", category=RuntimeWarning, module="trimesh")
            chosen = chosen_settings(args)
            if chosen is None:
                code: int = args.func(args)
            else:
                from tactile_kb.settings import use

                with use(chosen):
                    code = args.func(args)
    except TactileKBError as exc:
        return report(exc, prog)
    except KeyboardInterrupt:
        print("tactile-kb: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return EXIT_OK
    except (MemoryError, RecursionError) as exc:  # an input too large or too deep
        print(f"{prog}: error: {error_message(exc)}", file=sys.stderr)
        return EXIT_FAILED
    except Exception as exc:  # the last line of defence: never a traceback
        if os.environ.get("TACTILE_KB_TRACEBACK"):
            raise
        print(f"{prog}: {error_message(exc)}", file=sys.stderr)
        return EXIT_INTERNAL
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
