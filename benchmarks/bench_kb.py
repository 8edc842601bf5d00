"""Knowledge-base benchmark: compile, analyse, print, classify. Prints figures; never fails.

Run: ``.venv/bin/python benchmarks/bench_kb.py``. Targets (issue #2): the paper's base
compiles in < 50 ms; 40 propositions, 30 connections, 20 classes compile with every analysis
and every class's printed expression in < 1 s; batch classification ≥ 10 M/s on the
7-proposition base; one classify() with its explanation ≤ 20 µs.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

import tactile_kb.analysis
import tactile_kb.economy
import tactile_kb.engine  # noqa: F401 - imported up front: the figures exclude module imports
from tactile_kb.compiler import BACKEND, PAPER_EXAMPLE, compile_rules
from tactile_kb.rulegen import generate_rules
from tactile_kb.rules import parse_rules


def _best(fn: Callable[[], object], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    print(f"BDD backend: {BACKEND}")
    paper = parse_rules(PAPER_EXAMPLE)
    t = time.perf_counter()
    compile_rules(paper)
    cold = time.perf_counter() - t
    warm = _best(lambda: compile_rules(paper), 20)
    print(
        f"paper base A–G (7 propositions): compile {warm * 1e3:.1f} ms "
        f"(first call in the process, creating the CUDD manager: {cold * 1e3:.1f} ms; target < 50 ms)"
    )
    packaged = _best(lambda: compile_rules("parallelepipeds"), 10)
    print(
        f"rules/parallelepipeds.yaml (9 propositions, 6 classes): compile {packaged * 1e3:.1f} ms"
    )

    text = generate_rules(40, 30, 20, seed=0)
    big = parse_rules(text)
    kb = compile_rules(big)
    size = _best(lambda: compile_rules(big), 3)
    terms = sum(len(k.bits) for k in kb.classes)
    print(
        f"generated 40 propositions, 30 connections, 20 classes: compile + analyses + printed "
        f"expressions {size * 1e3:.0f} ms (target < 1 s); |r(L)| = {kb.r_count}, "
        f"{len(kb.groups)} groups, {len(kb.problems)} warnings, {terms} flat terms"
    )

    kb7 = compile_rules(paper)
    rng = np.random.default_rng(0)
    batch = rng.random((10_000_000, kb7.n)) < 0.5
    kb7.classify_batch(batch[:10])  # build the table
    rate_time = _best(lambda: kb7.classify_batch(batch), 3)
    print(
        f"batch classification, 7 propositions: {len(batch) / rate_time / 1e6:.1f} M "
        f"assignments/s (target ≥ 10 M/s)"
    )
    big_batch = rng.random((1_000_000, 40)) < 0.5
    big_time = _best(lambda: kb.classify_batch(big_batch), 2)
    print(
        f"batch classification, 40 propositions (column-wise numpy): "
        f"{len(big_batch) / big_time / 1e6:.2f} M assignments/s"
    )

    rows = [format(r, "07b") for r in range(128)]
    fresh = compile_rules(paper)
    t = time.perf_counter()
    for r in rows:
        fresh.classify(r)
    first = (time.perf_counter() - t) / len(rows)
    loops = 20
    t = time.perf_counter()
    for _ in range(loops):
        for r in rows:
            fresh.classify(r)
    again = (time.perf_counter() - t) / (loops * len(rows))
    mapping = {name: bool(i % 2) for i, name in enumerate(fresh.ids)}
    t = time.perf_counter()
    for _ in range(2000):
        fresh.classify(mapping)
    as_map = (time.perf_counter() - t) / 2000
    print(
        f"single classify() with explanation: {again * 1e6:.1f} µs (bit string), "
        f"{as_map * 1e6:.1f} µs (mapping) once cached; first call per assignment "
        f"{first * 1e6:.0f} µs (target ≤ 20 µs)"
    )
    t = time.perf_counter()
    e = kb7.economy()
    print(f"{e.line}  [{(time.perf_counter() - t) * 1e3:.0f} ms]")
    pk = compile_rules("parallelepipeds")
    t = time.perf_counter()
    e = pk.economy()
    print(f"parallelepipeds {e.line}  [{(time.perf_counter() - t) * 1e3:.0f} ms]")


if __name__ == "__main__":
    main()
