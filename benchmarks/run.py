"""Run every benchmark and print its figures: ``make bench`` (or ``python benchmarks/run.py``).

Each ``benchmarks/bench_*.py`` prints its own figures when run as a script; none fails on time.
Each runs in a process of its own, as it would alone. Name some to run only those:
``python benchmarks/run.py kb geometry``.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

from versions import versions_line

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    wanted = set(argv)
    known = {p.stem.removeprefix("bench_"): p for p in sorted(HERE.glob("bench_*.py"))}
    unknown = sorted(wanted - set(known))
    if unknown:
        print(f"unknown benchmark(s): {', '.join(unknown)} (known: {', '.join(known)})")
        return 2
    print(versions_line(), flush=True)
    failed = 0
    for name, script in known.items():
        if wanted and name not in wanted:
            continue
        print(f"== {name} ({script.name})", flush=True)
        t0 = time.perf_counter()
        code = subprocess.run([sys.executable, str(script)], check=False).returncode
        failed += code != 0
        print(
            f"   [{time.perf_counter() - t0:.1f} s{'' if code == 0 else f', exit {code}'}]\n",
            flush=True,
        )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
