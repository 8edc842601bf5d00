"""Counting in the process-wide CUDD manager never aborts the process.

CUDD 3.0.0's minterm count stores its partial counts as constant nodes of the shared unique
table; a garbage collection that fires in the middle of a count corrupted the manager's
dead-node bookkeeping, and a later collection aborted the interpreter ("dead count !=
deleted"). It took a process that had already done a lot of work, so a single test passed and
the whole suite died at random. The script below is the smallest workload found that fires
such a collection: the benchmark's 40-proposition file compiled and its economy computed
twelve times in one process (before the fix the eighth run aborted, exit code -6). It runs
in a subprocess because the failure kills the interpreter.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

from tactile_kb.kb.bdd import BACKEND

SCRIPT = """
import json
from tactile_kb.kb.compiler import compile_rules
from tactile_kb.kb.rulegen import generate_rules

runs = []
for _ in range(12):
    kb = compile_rules(generate_rules(40, 30, 20, seed=0))
    e = kb.economy()
    runs.append([kb.r_count, [k.count for k in kb.classes], e.lazy, e.optimal_lower,
                 e.optimal_upper, e.method])
    del kb, e  # each run starts from a manager holding only dead nodes of the last one
print(json.dumps(runs))
"""


def test_repeated_compiles_and_economies_in_one_manager() -> None:
    env = {**os.environ, "PYTHONHASHSEED": "0", "PYTHONFAULTHANDLER": "1"}
    run = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, timeout=900
    )
    assert run.returncode == 0, (BACKEND, run.returncode, run.stderr[-3000:])
    runs = json.loads(run.stdout)
    assert len(runs) == 12
    assert all(r == runs[0] for r in runs)  # the shared manager changes no figure
    r_count, class_counts, lazy, lower, upper, method = runs[0]
    assert all(0 < c <= r_count for c in class_counts)
    assert lower <= upper <= lazy
    assert method == "bounds"
