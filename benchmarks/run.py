"""Run every benchmark and print its figures: ``make bench`` (or ``python benchmarks/run.py``).

Each ``benchmarks/bench_*.py`` has a ``main()`` that prints its own figures; none fails on time.
Name some to run only those: ``python benchmarks/run.py kb geometry``.
"""

from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    wanted = set(argv)
    scripts = sorted(HERE.glob("bench_*.py"))
    for script in scripts:
        name = script.stem.removeprefix("bench_")
        if wanted and name not in wanted:
            continue
        spec = importlib.util.spec_from_file_location(script.stem, script)
        assert spec is not None
        assert spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        print(f"== {name} ({script.name})", flush=True)
        t0 = time.perf_counter()
        module.main()
        print(f"   [{time.perf_counter() - t0:.1f} s]\n", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
