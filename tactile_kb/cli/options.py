"""Argument types and option groups shared by the subcommands."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import threading
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, TextIO

from tactile_kb.errors import PluginError, PluginUnavailableError, TactileKBError, UsageError

__all__ = [
    "BUG_HINT",
    "EXIT_FAILED",
    "EXIT_INTERNAL",
    "EXIT_OK",
    "EXIT_USAGE",
    "add_exploration_options",
    "add_object_inputs",
    "check_noise",
    "check_picture",
    "chosen_settings",
    "exit_code_of",
    "nonnegative",
    "notices",
    "object_failed",
    "object_inputs",
    "picture_paths",
    "positive",
    "progress",
    "seed",
]


EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERNAL = 0, 1, 2, 3
"""The exit codes: 0 success; 1 an input was read and failed (an invalid file, an object that
could not be classified, an output that could not be written); 2 the command line is wrong (an
unknown option, a bad value, a name or path that does not exist); 3 a bug in tactile_kb."""

BUG_HINT = (
    "this is a bug in tactile-kb; please report it with the command and its input files "
    "(TACTILE_KB_TRACEBACK=1 shows the traceback)"
)


def exit_code_of(error: BaseException) -> int:
    """The exit code an error gives (see :data:`EXIT_OK`)."""
    if isinstance(error, UsageError) or (
        isinstance(error, PluginError) and not isinstance(error, PluginUnavailableError)
    ):
        return EXIT_USAGE
    if isinstance(error, TactileKBError | MemoryError | RecursionError):
        return EXIT_FAILED
    return EXIT_INTERNAL


def error_kind(error: BaseException) -> str:
    """The ``kind`` of a JSON error object: the exception's class name, ``InternalError`` for
    an error that is a bug."""
    if exit_code_of(error) == EXIT_INTERNAL:
        return "InternalError"
    return type(error).__name__


def error_message(error: BaseException) -> str:
    """A one-line message for ``error``, whatever it is."""
    if isinstance(error, MemoryError):
        return "out of memory: the input is too large to process on this machine"
    if isinstance(error, RecursionError):
        return "the input is nested too deeply to process"
    text = " ".join(str(error).split()) or type(error).__name__
    if exit_code_of(error) == EXIT_INTERNAL:
        return f"internal error: {type(error).__name__}: {text} ({BUG_HINT})"
    return text


def object_failed(command: str, item: str, error: BaseException, as_json: bool) -> int:
    """Report that ``item`` failed in ``command`` (one line on stderr; a JSON error object on
    stdout with ``as_json``) and return the exit code this failure gives."""
    message = error_message(error)
    named = message if message.startswith(item) else f"{item}: {message}"  # named once
    print(
        f"tactile-kb {command}: error: {named}",
        file=sys.stderr,
        flush=True,
    )
    if as_json:
        obj = {"object": item, "error": {"kind": error_kind(error), "message": message}}
        print(json.dumps(obj, ensure_ascii=False), flush=True)
    return exit_code_of(error)


def nonnegative(text: str) -> float:
    """An argparse type: a finite number ≥ 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number ≥ 0, got {text!r}")
    return value


def positive(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = nonnegative(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def add_object_inputs(p: argparse.ArgumentParser, what: str) -> None:
    """``PATH...`` mesh files and ``--record RECORD.json`` (repeatable) to ``what``."""
    p.add_argument(
        "paths",
        nargs="*",
        metavar="PATH",
        help="mesh files (STL, OBJ, PLY, OFF, glTF), metres unless --units",
    )
    p.add_argument(
        "--record",
        action="append",
        default=[],
        metavar="RECORD.json",
        help=f"{what} a saved exploration record instead (repeatable)",
    )


def object_inputs(args: argparse.Namespace) -> list[tuple[str, bool]]:
    """The objects of a command, ``(path, is_record)``: the mesh files, then the records.

    Raises :class:`UsageError` when there are none.
    """
    items = [(p, False) for p in args.paths] + [(r, True) for r in args.record]
    if not items:
        raise UsageError(f"{args.command} needs at least one PATH or --record RECORD.json")
    return items


def add_exploration_options(p: argparse.ArgumentParser, *, with_seed: bool = True) -> None:
    """``--explorer``, ``--finger``, ``--noise`` and (with ``with_seed``) ``--seed``, as every
    exploring command has them."""
    p.add_argument("--explorer", default="stepper", help="explorer plugin (default: stepper)")
    p.add_argument(
        "--finger", default="33", help="finger layout: 4, 33 or a YAML file (default: 33)"
    )
    p.add_argument(
        "--noise",
        type=nonnegative,
        default=0.0,
        metavar="SIGMA_METRES",
        help="σ of the contact-position noise, metres (default: 0)",
    )
    if with_seed:
        p.add_argument(
            "--seed", type=seed, default=0, help="seed for noise and drop-outs (default: 0)"
        )
    p.add_argument(
        "--units",
        choices=("m", "cm", "mm", "in"),
        help="the length unit of the mesh files (default: m; the setting objects.units)",
    )
    p.add_argument(
        "--rest",
        choices=("as-given", "stable"),
        help="as-given: the mesh's own orientation, its lowest point on the table (default); "
        "stable: turned to the pose it most probably rests in when dropped (objects.rest)",
    )
    p.add_argument(
        "--settings",
        metavar="FILE.toml",
        help="tolerances and budgets from a TOML file, one [group] table each (docs/settings.md)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="GROUP.FIELD=VALUE",
        help="change one setting, e.g. explore.completion_touches=40 (repeatable; after --settings)",
    )


def chosen_settings(args: argparse.Namespace) -> Any:
    """The settings a command runs with: the defaults, then ``--settings FILE``, then
    ``--units`` and ``--rest``, then each ``--set``; ``None`` when none of them was given."""
    from tactile_kb import settings

    path, sets = getattr(args, "settings", None), list(getattr(args, "set", None) or [])
    # the shortcuts first, so that an explicit --set of the same field wins
    shortcuts = [
        f"objects.{field}={value}"
        for field in ("units", "rest")
        if (value := getattr(args, field, None)) is not None
    ]
    sets = shortcuts + sets
    if path is None and not sets:
        return None
    chosen = settings.load(path) if path is not None else settings.DEFAULTS
    return chosen.assigned(sets) if sets else chosen


def seed(text: str) -> int:
    """An argparse type: a seed, a whole number ≥ 0."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be ≥ 0, got {text!r}")
    return value


PICTURE_SUFFIXES = (".png", ".svg", ".pdf")
MAX_PIXELS = 20000
"""The largest picture side, in pixels, the command line draws."""


def check_picture(
    path: str, flag: str, size: tuple[float, float] | None = None, dpi: float = 100.0
) -> None:
    """Refuse, before any work is done, a picture path or size that cannot be written."""
    p = Path(path)
    if not path:
        raise UsageError(f"{flag} '': give a picture file name ending in .png, .svg or .pdf")
    if p.suffix.lower() not in PICTURE_SUFFIXES:
        raise UsageError(f"{flag} {path}: the file must end in {', '.join(PICTURE_SUFFIXES)}")
    if not p.parent.is_dir():
        raise UsageError(f"{flag} {path}: directory {str(p.parent)!r} does not exist")
    if p.is_dir():
        raise UsageError(f"{flag} {path}: is a directory")
    if p.exists() and not p.is_file():
        raise UsageError(f"{flag} {path}: exists and is not a regular file")
    if not os.access(p.parent, os.W_OK):
        raise UsageError(f"{flag} {path}: directory {str(p.parent)!r} is not writable")
    if size is not None and max(size) * dpi > MAX_PIXELS:
        raise UsageError(
            f"--size {size[0]:g}x{size[1]:g} at --dpi {dpi:g} is over {MAX_PIXELS} pixels a side"
        )


def picture_paths(base: str, items: Sequence[str]) -> list[Path]:
    """One picture path per item: ``base`` itself for one item, else ``base-<item stem>``,
    numbered where two items share a stem, so that no picture overwrites another."""
    path = Path(base)
    if len(items) == 1:
        return [path]
    out: list[Path] = []
    used: set[str] = set()
    for index, item in enumerate(items):
        stem = Path(item).stem or f"object{index + 1}"
        name = f"{path.stem}-{stem}"
        if name in used:
            name = f"{name}-{index + 1}"
        used.add(name)
        out.append(path.with_name(name + path.suffix))
    return out


def check_noise(noise: float, finger: Any) -> None:
    """Refuse, before any work, a σ no contact sensor could have (≥ the tip radius). A σ large
    enough to change answers is allowed; each exploration says so in its notes."""
    from tactile_kb.touch.explorers import noise_problem

    refused, _warning = noise_problem(noise, finger.radius)
    if refused:
        raise UsageError(f"--noise {noise:g}: {refused}")


PROBE_NOTES_SHOWN = 3
"""At most this many of the completion's probe notes are printed; the rest are counted."""


def notices(record: Any) -> list[str]:
    """What a person should be told about an exploration: its notes, with the completion's
    probe notes (one per probe, dozens on a curved object) cut to :data:`PROBE_NOTES_SHOWN`
    and a count; the record keeps them all."""
    out: list[str] = []
    shown = hidden = 0
    for note in record.notes:
        if note.startswith(("a probe ", "the way to a probe ")):
            if shown >= PROBE_NOTES_SHOWN:
                hidden += 1
                continue
            shown += 1
        out.append(note)
    if hidden:
        out.append(
            f"{hidden} more probe note(s) like these; the record keeps them all "
            "(tactile-kb explore … --out RECORD.json)"
        )
    return out


PHASE_WORDS = {
    "first-contact": "approaching",
    "layers": "following the contour",
    "probe": "probing the sides",
    "top": "exploring the top",
    "complete": "completing the model",
}
"""How the progress line names the servo cycle's phases."""


@contextlib.contextmanager
def progress(item: str, *, stream: TextIO | None = None) -> Iterator[None]:
    """Show ``item``, the exploration's phase and touches so far, and the time spent, on a
    terminal while the block runs.

    Nothing is shown when ``stream`` (default stderr) is not a terminal, nor for work that
    ends within half a second; the line is erased when the work ends.
    """
    out = sys.stderr if stream is None else stream
    if not (hasattr(out, "isatty") and out.isatty()):
        yield
        return
    from tqdm import tqdm

    from tactile_kb.touch.watch import watching

    done = threading.Event()
    state = {"phase": "", "touches": 0}

    def watch(phase: str, touches: int, motions: int) -> None:
        state["phase"], state["touches"] = phase, touches

    def show() -> None:
        if done.wait(0.5):
            return
        with tqdm(
            total=None,
            desc=f"working on {item}",
            bar_format="{desc} … {elapsed}{postfix}",
            file=out,
            leave=False,
        ) as bar:
            while not done.wait(0.25):
                if state["phase"]:
                    phase = PHASE_WORDS.get(str(state["phase"]), str(state["phase"]))
                    bar.set_postfix_str(f"{phase}, {state['touches']} touches", refresh=False)
                bar.refresh()

    thread = threading.Thread(target=show, daemon=True)
    thread.start()
    try:
        with watching(watch):
            yield
    finally:
        done.set()
        thread.join()
