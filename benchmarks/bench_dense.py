"""Dense meshes: exploration time and peak memory of ~1k- and ~200k-triangle meshes of one shape.

Run: ``.venv/bin/python benchmarks/bench_dense.py`` (prints a table; never fails on time).
Each exploration runs in a fresh process (the stepper, 33-sensor finger, seed 0) that reports
its own wall time, CPU time (``time.process_time``: steadier than the wall time on a shared
machine) and peak resident memory (``resource.getrusage``), so one run's memory does not hide
another's. Goal (issue 10): the 200k mesh in at most 10× the time of the 1k mesh of
the same shape, and under 1 GB.

* ``box``: a 8 × 6 × 5 cm box, its triangles split 4 ways 3 times (768) or 7 times (196 608);
* ``box, 0.3 mm jitter``: the same with every vertex moved by up to ±0.3 mm (a scan's noise);
* ``sphere``: UV spheres of radius 4 cm with 1 152 and 206 016 triangles.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import trimesh

# (label, shape, number of 4-way splits or UV count, jitter in metres)
CASES: list[tuple[str, str, int, float]] = [
    ("box", "box", 3, 0.0),
    ("box", "box", 7, 0.0),
    ("box, 0.3 mm jitter", "box", 3, 0.0003),
    ("box, 0.3 mm jitter", "box", 7, 0.0003),
    ("sphere", "sphere", 17, 0.0),
    ("sphere", "sphere", 232, 0.0),
]


def build(shape: str, level: int, jitter: float) -> trimesh.Trimesh:
    """The mesh of one case (deterministic)."""
    if shape == "box":
        mesh = trimesh.creation.box((0.08, 0.06, 0.05))
        for _ in range(level):
            mesh = mesh.subdivide()
    else:
        mesh = trimesh.creation.uv_sphere(radius=0.04, count=(level, level))
    if jitter:
        rng = np.random.default_rng(0)
        mesh.vertices = mesh.vertices + rng.uniform(-jitter, jitter, mesh.vertices.shape)
    return mesh


def run_one(shape: str, level: int, jitter: float) -> dict[str, float]:
    """Explore one case in this process; its figures."""
    import resource
    import time

    from tactile_kb.completion import model_completer
    from tactile_kb.touch.stepper import StepperExplorer

    mesh = build(shape, level, jitter)
    t0, c0 = time.perf_counter(), time.process_time()
    rec = StepperExplorer(completer=model_completer()).explore(mesh, seed=0)
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux
    return {
        "triangles": len(mesh.faces),
        "seconds": seconds,
        "cpu": cpu,
        "peak_mb": peak_kib / 1024.0,
        "touches": rec.touches,
        "closed": rec.ending == "closed",
    }


def main() -> int:
    rows = []
    for label, shape, level, jitter in CASES:
        out = subprocess.run(
            [sys.executable, __file__, "--one", shape, str(level), repr(jitter)],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        rows.append((label, json.loads(out.splitlines()[-1])))
    print(
        f"{'object':22} {'triangles':>9} {'seconds':>8} {'CPU s':>7} {'peak MB':>8} {'touches':>7}"
        "  closed"
    )
    for label, r in rows:
        print(
            f"{label:22} {r['triangles']:9d} {r['seconds']:8.2f} {r['cpu']:7.2f} "
            f"{r['peak_mb']:8.0f} {r['touches']:7d}  {'yes' if r['closed'] else 'no'}"
        )
    print()
    for k in range(0, len(rows), 2):
        (label, small), (_, big) = rows[k], rows[k + 1]
        ratio = big["seconds"] / small["seconds"]
        print(
            f"{label}: {big['triangles']} vs {small['triangles']} triangles: "
            f"{ratio:.1f}x the time (goal ≤ 10x; CPU {big['cpu'] / small['cpu']:.1f}x), "
            f"peak {big['peak_mb']:.0f} MB (goal < 1024 MB)"
        )
    return 0


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--one":
        print(json.dumps(run_one(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]))))
        sys.exit(0)
    sys.exit(main())
