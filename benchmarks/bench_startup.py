"""Startup of the ``tactile-kb`` command as a person feels it, and what each command imports.

Each command runs in a fresh interpreter (as the console script does), five times; the
median wall time is printed with the heavy libraries the command imported. ``--help``,
``--version`` import none of trimesh, scipy, sympy, matplotlib or an explorer plugin;
``validate``, ``query`` and ``compile`` none but dd, networkx and pysat (the BDDs, the groups
and the conflict analysis).
Run: ``python benchmarks/bench_startup.py``.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("trimesh", "scipy", "sympy", "matplotlib", "tactile_kb_mujoco", "dd", "networkx", "pysat")
COMMANDS = [
    ["--version"],
    ["--help"],
    ["validate", str(ROOT / "rules" / "parallelepipeds.yaml")],
    ["query", "parallelepipeds", "--bits", "101101111"],
    ["compile", "parallelepipeds"],
    ["plugins"],
]
PROBE = """
import contextlib, io, json, sys
from tactile_kb.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
print(json.dumps({"code": code, "heavy": [m for m in HEAVY if m in sys.modules]}))
"""


def run(argv: list[str]) -> tuple[float, dict[str, object]]:
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", f"HEAVY = {HEAVY!r}\n{PROBE}", *argv],
        capture_output=True,
        text=True,
        check=True,
    )
    return time.perf_counter() - t0, json.loads(done.stdout)


def main() -> None:
    baseline = statistics.median(run_python() for _ in range(5))
    print(f"python -c pass: {baseline * 1000:.0f} ms (the interpreter alone)")
    print(f"{'command':45} {'median':>8} {'min':>8}  heavy imports")
    for argv in COMMANDS:
        times, info = [], {}
        for _ in range(5):
            seconds, info = run(argv)
            times.append(seconds)
        label = " ".join(a if len(a) < 30 else Path(a).name for a in argv)
        heavy = ", ".join(info["heavy"]) or "none"  # type: ignore[arg-type]
        print(
            f"tactile-kb {label:34} {statistics.median(times) * 1000:6.0f} ms "
            f"{min(times) * 1000:6.0f} ms  {heavy}"
        )


def run_python() -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "pass"], check=True)
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
