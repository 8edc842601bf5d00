"""Run a benchmark's jobs on ``workers`` processes (forked), or in this one for 1."""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Sequence
from typing import TypeVar

J = TypeVar("J")
R = TypeVar("R")


def map_jobs(run: Callable[[J], R], jobs: Sequence[J], workers: int) -> list[R]:
    """``[run(j) for j in jobs]``, on ``workers`` forked processes when more than one, in order."""
    if workers > 1:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            return pool.map(run, jobs, chunksize=1)
    return [run(j) for j in jobs]
