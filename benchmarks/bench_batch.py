"""Batches: objects per minute on local workers and a Dask LocalCluster; driver memory.

Run: ``.venv/bin/python benchmarks/bench_batch.py [--objects 200] [--tiny 10000] [--no-dask]``
(or ``python benchmarks/run.py batch``). It never fails; it prints:

1. Objects per minute over ``--objects`` generated polyhedra (cubes, boxes, prisms, pyramids,
   tetrahedra, octahedra in random sizes and turns; ``polyhedra`` rules, 33-sensor finger), for
   - the baseline: the same files classified one by one with ``classify()`` in one process;
   - ``run_batch`` with 1 and 2 local workers (start-up, hashing, the synced JSONL stream and
     the sorted rewrite included); goal: ≥ 1.7× the baseline at 2 workers, ≤ 10 % slower at 1;
   - ``run_batch`` on a 2-worker Dask ``LocalCluster`` (cluster start-up reported apart).
   Every run must give the same answers as the baseline; a difference is printed.
2. The driver's resident memory while ``--tiny`` tiny files stream through ``run_batch`` with 2
   local workers. STAND-IN WORK: to measure the batch machinery (inputs, hashing, tasks,
   inter-process transport, synced stream, final sort) over 10,000 objects in minutes, each
   worker runs ``stand_in`` below, which reads the file and returns a row shaped and sized like a
   real one, instead of exploring (a tiny cube takes about 0.2 s to explore: 10,000 would take
   15 minutes on 2 cores and measure the same driver).
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from tactile_kb import solids
from tactile_kb.batch import BatchItem, run_batch
from tactile_kb.pipeline import classify, knowledge_base

RULES = "polyhedra"


def _size(rng: np.random.Generator, lo: float = 0.03, hi: float = 0.15) -> float:
    return round(float(math.exp(rng.uniform(math.log(lo), math.log(hi)))), 4)


def _objects(rng: np.random.Generator) -> list[Callable[[], tuple[trimesh.Trimesh, str]]]:
    def cube() -> tuple[trimesh.Trimesh, str]:
        a = _size(rng)
        return solids.box(a, a, a), "cube"

    def brick() -> tuple[trimesh.Trimesh, str]:
        a = _size(rng)
        return solids.box(a, a * 0.6, a * 1.4), "rectangular_parallelepiped"

    def prism() -> tuple[trimesh.Trimesh, str]:
        n = int(rng.integers(5, 8))
        return solids.prism(n, _size(rng, 0.03, 0.08), _size(rng, 0.04, 0.12)), "prism"

    def pyramid() -> tuple[trimesh.Trimesh, str]:
        n = int(rng.integers(4, 7))
        return solids.pyramid(n, _size(rng, 0.04, 0.08), _size(rng, 0.04, 0.10)), "pyramid"

    def tetra() -> tuple[trimesh.Trimesh, str]:
        return solids.tetrahedron(_size(rng, 0.05, 0.15)), "tetrahedron"

    return [cube, brick, prism, pyramid, tetra]


def make_dataset(folder: Path, count: int, seed: int = 7) -> list[BatchItem]:
    rng = np.random.default_rng(seed)
    builders = _objects(rng)
    items = []
    for i in range(count):
        mesh, label = builders[i % len(builders)]()
        angle = float(rng.uniform(0, 90))
        mesh = solids.rotate_about_z(mesh, angle)
        path = folder / f"obj{i:04d}.stl"
        mesh.export(path)
        items.append(BatchItem(str(path), label))
    return items


def stand_in(task: dict[str, Any]) -> dict[str, Any]:
    """STAND-IN for classification (see the module docstring): read, hash, return a row."""
    from tactile_kb.batch import finish_row

    started = time.perf_counter()
    data = Path(task["object"]).read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    row = {
        "answer": "OBJECT IS A CUBE",
        "label": "cube",
        "bits": "10110111110011-",
        "propositions": dict.fromkeys("ABCDEFGHJKMNQRS", True),
        "touches": 9,
        "contacts": 140,
        "planes": 6,
        "path_length": 0.79,
        "seconds": 0.0,
        "phase": "VIII",
        "contacts_per_phase": dict.fromkeys(("I", "II", "III", "IV", "V", "VI", "VII", "VIII"), 9),
        "explanation": "stand-in " + digest * 4,
        "reported": {},
        "measures": {"edges": 12, "faces": 6, "height": 0.06, "sides": 4, "vertices": 8},
    }
    return finish_row(task, row, started)


def _rss_mib() -> float:
    with open("/proc/self/statm") as handle:
        pages = int(handle.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def _peak_mib() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _per_minute(n: int, seconds: float) -> float:
    return 60.0 * n / seconds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=200)
    parser.add_argument("--tiny", type=int, default=10_000)
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args()
    print(f"cores: {os.cpu_count()}; load average now: {os.getloadavg()[0]:.1f}")

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "objects").mkdir()
        items = make_dataset(root / "objects", args.objects)
        kb = knowledge_base(RULES)

        # Baseline: today's classify(), one object after another, in this process. It runs
        # before and after the batches; their mean is the baseline, so that a change in the
        # machine's other load during the run weighs on both sides alike.
        cpu: dict[str, tuple[float, float, float]] = {}  # name → (driver, workers, busiest)

        def baseline_run() -> tuple[float, float, list[str]]:
            t0, c0 = time.perf_counter(), time.process_time()
            labels = [classify(item.path, rules=kb).decision.label for item in items]
            return time.perf_counter() - t0, time.process_time() - c0, labels

        before, base_cpu, baseline = baseline_run()
        right = sum(b == item.label for b, item in zip(baseline, items, strict=True))
        print(
            f"\n{args.objects} objects, baseline (classify() one by one, one process): "
            f"{before:.1f} s, {_per_minute(args.objects, before):.0f} objects/min, "
            f"{base_cpu:.1f} s of CPU ({right}/{args.objects} labels right)"
        )
        results: dict[str, float] = {}

        def timed(name: str, **options: Any) -> float:
            out = root / f"{name}.jsonl"
            t, c = time.perf_counter(), time.process_time()
            rows: list[dict[str, Any]] = []
            run_batch(items, out, rules=RULES, on_row=rows.append, **options)
            seconds, driver = time.perf_counter() - t, time.process_time() - c
            labels = {r["index"]: r.get("label") for r in rows}
            differ = sum(labels[i] != b for i, b in enumerate(baseline))
            per_worker: dict[str, float] = {}
            for r in rows:
                per_worker[r["worker"]] = per_worker.get(r["worker"], 0.0) + r["cpu_seconds"]
            cpu[name] = (driver, sum(per_worker.values()), max(per_worker.values()))
            print(
                f"  {name:<22} {seconds:6.1f} s {_per_minute(args.objects, seconds):6.0f} "
                f"objects/min; CPU: driver {driver:.1f} s, workers {cpu[name][1]:.1f} s"
                + (f"  ({differ} answers differ!)" if differ else "  (same answers)")
            )
            return seconds

        results["local, 1 worker"] = timed("local, 1 worker", workers=1)
        results["local, 2 workers"] = timed("local, 2 workers", workers=2)
        if not args.no_dask:
            try:
                import distributed
            except ImportError:
                print("  Dask: not installed (pip install 'tactile-kb[dask]')")
            else:
                t = time.perf_counter()
                with (
                    distributed.LocalCluster(
                        host="127.0.0.1",
                        n_workers=2,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                    ) as cluster,
                    distributed.Client(cluster) as client,
                ):
                    print(f"  (Dask LocalCluster start-up: {time.perf_counter() - t:.1f} s)")
                    results["Dask, 2 workers"] = timed("Dask, 2 workers", client=client)
        after, after_cpu, again = baseline_run()
        base_s = (before + after) / 2
        base_cpu = (base_cpu + after_cpu) / 2
        print(
            f"  baseline again: {after:.1f} s ({'same' if again == baseline else 'other'} "
            f"answers); mean baseline {base_s:.1f} s, "
            f"{_per_minute(args.objects, base_s):.0f} objects/min"
        )
        for name, seconds in results.items():
            print(f"  {name:<22} ×{base_s / seconds:.2f} vs the mean baseline")
        one, two = results["local, 1 worker"], results["local, 2 workers"]
        print(
            f"  speedup at 2 local workers: {base_s / two:.2f}× (goal ≥ 1.7×); "
            f"overhead at 1 worker: {100 * (one - base_s) / base_s:+.1f} % (goal ≤ 10 %)"
        )
        if "Dask, 2 workers" in results:
            dask = results["Dask, 2 workers"]
            print(f"  Dask speedup at 2 workers: {base_s / dask:.2f}×")
        # CPU times do not depend on what else the machine runs: the work a batch adds, and
        # the wall time it would take with a core per worker (its busiest worker, the driver
        # running alongside), against the baseline's CPU time.
        print(f"  from CPU times (load-independent; baseline {base_cpu:.1f} s of CPU):")
        for name, (driver, workers, busiest) in cpu.items():
            print(
                f"    {name:<22} CPU overhead {100 * (driver + workers - base_cpu) / base_cpu:+.1f} %"
                f" (driver {driver:.1f} s); with a free core per worker: "
                f"×{base_cpu / max(busiest, driver):.2f}"
            )

        # Driver memory over many tiny objects (stand-in work, see the docstring).
        tiny = root / "tiny"
        tiny.mkdir()
        data = trimesh.exchange.stl.export_stl(solids.box(0.03, 0.03, 0.03))
        for i in range(args.tiny):
            (tiny / f"t{i:05d}.stl").write_bytes(data)
        samples: dict[int, float] = {}
        count = 0

        def sample(row: dict[str, Any]) -> None:
            nonlocal count
            count += 1
            if count in (100, 1_000) or count % 2_500 == 0:
                samples[count] = _rss_mib()

        t = time.perf_counter()
        summary = run_batch(
            [tiny], root / "tiny.jsonl", workers=2, on_row=sample, _work="bench_batch:stand_in"
        )
        seconds = time.perf_counter() - t
        print(
            f"\n{args.tiny} tiny objects through run_batch, 2 workers, STAND-IN work "
            f"(no exploration): {seconds:.1f} s, {args.tiny / seconds:.0f} objects/s "
            f"({summary.rows} rows, {sum(summary.errors.values())} errors)"
        )
        print(
            "  driver resident memory after N rows: "
            + ", ".join(f"{n}: {mib:.0f} MiB" for n, mib in sorted(samples.items()))
        )
        print(
            f"  after the sorted rewrite: {_rss_mib():.0f} MiB; peak of the driver: "
            f"{_peak_mib():.0f} MiB"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
