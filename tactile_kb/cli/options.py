"""Argument types and option groups shared by the subcommands."""

from __future__ import annotations

import argparse
import math

__all__ = ["add_exploration_options", "nonnegative"]


def nonnegative(text: str) -> float:
    """An argparse type: a finite number ≥ 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"must be a finite number ≥ 0, got {text!r}")
    return value


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
    p.add_argument("--seed", type=int, default=0, help="seed for noise and drop-outs (default: 0)")
