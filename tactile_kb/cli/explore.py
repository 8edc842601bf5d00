"""Subcommands of ``tactile-kb`` (being built; see tactile_kb/cli/__init__.py)."""

from __future__ import annotations

import argparse
from typing import Any


def register(sub: argparse._SubParsersAction[Any]) -> None:
    """Add this module's subcommands to ``sub``."""
