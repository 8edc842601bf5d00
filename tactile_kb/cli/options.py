"""Argument types and option groups shared by the subcommands."""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from pathlib import Path

from tactile_kb.errors import UsageError

__all__ = [
    "add_exploration_options",
    "add_object_inputs",
    "check_picture",
    "error_line",
    "nonnegative",
    "object_inputs",
    "picture_paths",
    "positive",
    "seed",
]


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
    p.add_argument("paths", nargs="*", metavar="PATH", help="mesh files (STL, OBJ, PLY), metres")
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


def add_exploration_options(p: argparse.ArgumentParser) -> None:
    """``--explorer``, ``--finger``, ``--noise`` and ``--seed``, as every exploring command has them."""
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
    p.add_argument("--seed", type=seed, default=0, help="seed for noise and drop-outs (default: 0)")


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
    if p.suffix.lower() not in PICTURE_SUFFIXES:
        raise UsageError(f"{flag} {path}: the file must end in {', '.join(PICTURE_SUFFIXES)}")
    if not p.parent.is_dir():
        raise UsageError(f"{flag} {path}: directory {str(p.parent)!r} does not exist")
    if p.is_dir():
        raise UsageError(f"{flag} {path}: is a directory")
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


def error_line(item: str, error: Exception) -> str:
    """The one line for an object that failed, naming it once."""
    message = str(error)
    return f"tactile-kb: error: {message if message.startswith(item) else f'{item}: {message}'}"
