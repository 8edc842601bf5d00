"""Side by side: the analytic ``stepper`` and the ``mujoco`` explorer on the same objects.

For the paper's Fig. 5 objects (33-sensor finger) and the L, T and U box unions (4-sensor
finger), both explorers run with the same seed; each record goes through the same chain
(model → features → rules) and the two models' planes are matched one to one. Prints, per
object and explorer: the answer, the number of planes, contacts, touches, path length and
seconds; then the planes' agreement (largest angle and offset between matched planes), and the
MuJoCo world's cost per physics step and per probe.

Run (after ``pip install -e ./explorers/mujoco``)::

    .venv/bin/python benchmarks/bench_mujoco.py            # every object
    .venv/bin/python benchmarks/bench_mujoco.py CUBE1 L    # some of them
"""

from __future__ import annotations

import sys
import time

import numpy as np
import trimesh
from tactile_kb_mujoco.compare import SideBySide, compare_object
from tactile_kb_mujoco.world import MujocoWorld

from tactile_kb import solids
from tactile_kb.touch.finger import builtin_finger


def objects() -> list[tuple[str, trimesh.Trimesh, str]]:
    """The benchmark set: ``(name, mesh, finger layout)``."""
    fig5 = [(name, mesh, "33") for name, mesh, _ in solids.fig5_objects()]
    unions = [
        ("L", solids.l_shape(0.1, 0.08, 0.03, 0.04), "4"),
        ("T", solids.t_shape(0.12, 0.08, 0.03, 0.04), "4"),
        ("U", solids.u_shape(0.1, 0.08, 0.025, 0.03), "4"),
    ]
    return fig5 + unions


def _row(r: SideBySide) -> list[str]:
    out = []
    for run in r.runs:
        rec = run.record
        out.append(
            f"{r.name:7s} {r.finger:>2s} {run.explorer:8s} {run.answer[:50]:50s} "
            f"{len(run.model.faces):6d} {len(rec.contacts):8d} {rec.touches:7d} "
            f"{rec.path_length:8.3f} {run.seconds:7.3f}"
        )
    return out


def _world_costs() -> tuple[float, float]:
    """Microseconds per MuJoCo physics step (with its probe) and per probe alone."""
    world = MujocoWorld(solids.box(0.08, 0.08, 0.08), builtin_finger("33"))
    t0 = time.perf_counter()
    n = 2000
    for _ in range(n):
        world.sense((0.0, 0.0, 0.09))
    probe_us = (time.perf_counter() - t0) / n * 1e6
    world.move((-0.15, 0.0, 0.04), (1.0, 0.0, 0.0), 0.3)  # warm up
    steps0 = world.steps
    t0 = time.perf_counter()
    for _ in range(10):
        world.move((-0.15, 0.0, 0.04), (1.0, 0.0, 0.0), 0.3)
    step_us = (time.perf_counter() - t0) / max(1, world.steps - steps0) * 1e6
    return step_us, probe_us


def main(argv: list[str] | None = None) -> int:
    """Print the side-by-side table for the objects named in ``argv`` (default: all)."""
    wanted = set(argv if argv is not None else sys.argv[1:])
    chosen = [o for o in objects() if not wanted or o[0] in wanted]
    head = (
        f"{'object':7s} {'f':>2s} {'explorer':8s} {'answer':50s} "
        f"{'planes':>6s} {'contacts':>8s} {'touches':>7s} {'path m':>8s} {'seconds':>7s}"
    )
    print(head)
    print("-" * len(head))
    rows = []
    for name, mesh, finger in chosen:
        # the box unions are named by the polyhedra rules (the paper's base has no class for them)
        rules = "polyhedra" if finger == "4" else "parallelepipeds"
        r = compare_object(name, mesh, finger=finger, seed=0, rules=rules)
        rows.append(r)
        print("\n".join(_row(r)), flush=True)
    print()
    print(
        f"{'object':7s} {'same answer':>11s} {'same planes':>11s} {'max angle °':>12s} {'max offset µm':>14s}"
    )
    for r in rows:
        same_planes = r.planes[0] == r.planes[1] and r.agreement.unmatched == 0
        print(
            f"{r.name:7s} {r.same_answer!s:>11s} {same_planes!s:>11s} "
            f"{r.max_angle_deg:12.5f} {r.max_offset * 1e6:14.3f}"
        )
    t_step = np.array([r.runs[0].seconds for r in rows])
    t_mj = np.array([r.runs[1].seconds for r in rows])
    print()
    print(
        f"seconds per object: stepper median {np.median(t_step):.3f} (max {t_step.max():.3f}), "
        f"mujoco median {np.median(t_mj):.3f} (max {t_mj.max():.3f})"
    )
    print(
        f"all answers equal: {all(r.same_answer for r in rows)}; "
        f"largest plane disagreement: {max(r.max_angle_deg for r in rows):.5f}° and "
        f"{max(r.max_offset for r in rows) * 1e6:.3f} µm"
    )
    step_us, probe_us = _world_costs()
    print(
        f"mujoco world: {step_us:.1f} µs per physics step (with its probe), {probe_us:.1f} µs per probe"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
