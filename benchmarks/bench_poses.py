"""Objects in their stable poses: every family, every resting pose gravity leaves it in.

Run: ``.venv/bin/python benchmarks/bench_poses.py [--turns N] [--family NAME ...] [--seed N]
[--explorer stepper|mujoco] [--shaft RADIUS] [--workers N] [--match TEXT] [--noisy-only]
[--set GROUP.FIELD=VALUE ...]``.
It never fails; it prints, per family and mode (exact contacts, 0.5 mm noise), the share of
right answers, the median touches per face, and the wall time per object with the share of
the motions' time spent with the head indexed away from the vertical; then every wrong case.

The families are those of ``bench_accuracy.py`` (one random instance each) plus an
icosahedron, an irregular tetrahedron, and L, T and U blocks (with the ``parallelepipeds``
rules: an L, T or U block is not a hexahedron). Each is tried in every stable
pose of ``trimesh.poses.compute_stable_poses`` with probability ≥ 2 % (a sphere, whose poses are
all less probable: its most probable one, said so in the output), under ``--turns`` random
turns about z (the issue's figures: ``--turns 3``, the default). Each family draws its instance,
poses' turns and noise from its own generator, seeded by ``--seed`` and the family's name: another
``--seed`` is another set of objects, the honest check that a change is not tuned to one set.
The true labels come from the construction (bench_accuracy's builders), never
from the code under test: a pose changes where an object lies, not what it is.

``--explorer mujoco`` runs the same instances (the same seeds draw the same objects, poses and
turns) in the MuJoCo plugin's world; ``--shaft RADIUS`` gives the 33-sensor finger a colliding
stem of that radius (metres), in either world; ``--set`` runs every case under changed settings
(as the command line's ``--set``), to measure a setting on the same cases. With MuJoCo the last column is the share of the
wall time spent simulating the head's turns.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
import zlib
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_accuracy import FAMILIES, NOISE, Family, faces_to_touch

from tactile_kb import settings, solids
from tactile_kb.errors import UsageError
from tactile_kb.pipeline import classify
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.stepper import StepperExplorer, StepperWorld

MIN_PROBABILITY = 0.02


class _Clock:
    """Seconds spent in motions, and the share of them with the head indexed; with MuJoCo,
    seconds spent simulating the head's turns."""

    motions = 0.0
    indexed = 0.0
    turning = 0.0


class _TimedWorld(StepperWorld):
    def _run(self, kind, start, direction, length):  # type: ignore[no-untyped-def]
        t = time.perf_counter()
        try:
            return super()._run(kind, start, direction, length)
        finally:
            dt = time.perf_counter() - t
            _Clock.motions += dt
            if not self.orientation.vertical:
                _Clock.indexed += dt


class _TimedExplorer(StepperExplorer):
    def make_world(self, mesh, finger, *, seed):  # type: ignore[no-untyped-def]
        del seed
        return _TimedWorld(mesh, finger)


def _mujoco_explorer():  # type: ignore[no-untyped-def]
    """The MuJoCo explorer, its motions timed as the stepper's (the plugin must be installed)."""
    from tactile_kb_mujoco.explorer import MujocoExplorer
    from tactile_kb_mujoco.world import MujocoWorld

    class TimedMujocoWorld(MujocoWorld):
        def _run(self, kind, p0, u, length, ref, *, press):  # type: ignore[no-untyped-def]
            t = time.perf_counter()
            try:
                return super()._run(kind, p0, u, length, ref, press=press)
            finally:
                dt = time.perf_counter() - t
                _Clock.motions += dt
                if not self.orientation.vertical:
                    _Clock.indexed += dt

        def _turn_head(self, p, q_from):  # type: ignore[no-untyped-def]
            t = time.perf_counter()
            try:
                return super()._turn_head(p, q_from)
            finally:
                _Clock.turning += time.perf_counter() - t

    class TimedMujocoExplorer(MujocoExplorer):
        def make_world(self, mesh, finger, *, seed):  # type: ignore[no-untyped-def]
            del seed
            return TimedMujocoWorld(mesh, finger)

    return TimedMujocoExplorer()


def icosahedron(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    r = round(float(rng.uniform(0.02, 0.12)), 4)
    m = trimesh.creation.icosahedron()
    m.apply_scale(r)
    return m, "other_polyhedron", f"icosahedron(circumradius {r})"


def irregular_tetrahedron(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    while True:
        pts = rng.uniform(-0.06, 0.06, size=(4, 3))
        m = trimesh.convex.convex_hull(pts)
        if m.volume > 2e-5 and min(m.area_faces) > 4e-4:
            return m, "tetrahedron", f"hull of {np.round(pts, 4).tolist()}"


def _blocks(name: str) -> Family:
    def build(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
        a, b = (round(float(rng.uniform(0.06, 0.12)), 4) for _ in range(2))
        w, h = round(float(rng.uniform(0.02, 0.04)), 4), round(float(rng.uniform(0.02, 0.06)), 4)
        maker = {"L": solids.l_shape, "T": solids.t_shape, "U": solids.u_shape}[name]
        return maker(a, b, w, h), "not_hexahedron", f"{name}-block({a}, {b}, {w}, {h})"

    return Family(f"{name}_block", "parallelepipeds", build)


ALL = [
    *FAMILIES,
    Family("icosahedron", "polyhedra", icosahedron),
    Family("irregular_tetrahedron", "polyhedra", irregular_tetrahedron),
    *(_blocks(n) for n in "LTU"),
]


def stable_poses(mesh: trimesh.Trimesh) -> list[tuple[trimesh.Trimesh, float]]:
    """``mesh`` in each stable pose of probability ≥ 2 % (or its most probable one), resting on
    z = 0, centred, most probable first (``tactile_kb.solids.stable_poses``)."""
    return solids.stable_poses(mesh, min_probability=MIN_PROBABILITY)


def _job(job: dict) -> dict:  # type: ignore[type-arg]
    """Classify one posed object (in a worker process with ``--workers``); its outcome."""
    finger = builtin_finger("33")
    if job["shaft"] is not None:
        finger = finger.model_copy(update={"shaft_radius": job["shaft"]})
    _Clock.motions = _Clock.indexed = _Clock.turning = 0.0
    m = job["mesh"]
    t = time.perf_counter()
    ending = ""
    try:
        with settings.use(settings.DEFAULTS.assigned(job["set"])):
            r = classify(
                m,
                rules=job["rules"],
                noise=job["noise"],
                seed=1,
                finger=finger,
                explorer=_TimedExplorer() if job["explorer"] == "stepper" else _mujoco_explorer(),
            )
            got, touches, ending = r.decision.label, r.record.touches, r.record.ending
    except Exception as exc:  # a benchmark reports, it does not stop
        got, touches = f"error: {type(exc).__name__}: {exc}"[:160], 0
    return {
        "got": got,
        "touches": touches,
        "ending": ending,
        "seconds": time.perf_counter() - t,
        "faces": faces_to_touch(m),
        "motions": _Clock.motions,
        "indexed": _Clock.indexed,
        "turning": _Clock.turning,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--turns", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--family", nargs="*", default=None)
    ap.add_argument("--exact-only", action="store_true")
    ap.add_argument("--noisy-only", action="store_true")
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="GROUP.FIELD=VALUE",
        help="run every case with this setting changed (repeatable; as the command line's --set)",
    )
    ap.add_argument(
        "--match",
        action="append",
        default=[],
        help="run only the cases whose description (as the wrong list prints it, e.g. "
        "'frustum4 pose 3') contains this text; the instances, poses and turns are drawn as in "
        "a full run, so a case reproduces (repeatable)",
    )
    ap.add_argument("--explorer", choices=("stepper", "mujoco"), default="stepper")
    ap.add_argument("--shaft", type=float, default=None, help="stem radius, metres (none)")
    ap.add_argument(
        "--workers", type=int, default=1, help="processes (the same instances, in parallel)"
    )
    args = ap.parse_args()
    if args.exact_only and args.noisy_only:
        ap.error("--exact-only and --noisy-only exclude each other")
    try:
        settings.DEFAULTS.assigned(args.set)
    except UsageError as exc:  # located to the argument
        ap.error(str(exc))
    print(f"explorer {args.explorer}, finger 33, stem radius {args.shaft or 'none'}")
    families = [f for f in ALL if not args.family or f.name in args.family]
    modes = [0.0] if args.exact_only else [NOISE] if args.noisy_only else [0.0, NOISE]
    # every instance, pose and turn is drawn first from the family's own generator (seeded by
    # --seed and the family's name), so that --workers, --family, --exact-only and --match
    # change only which cases run and where, never what a case is
    groups: list[tuple[Family, float, int, list[dict]]] = []  # type: ignore[type-arg]
    for fam in families:
        rng = np.random.default_rng([args.seed, zlib.crc32(fam.name.encode())])
        mesh, label, what = fam.build(rng)
        poses = stable_poses(mesh)
        if poses and max(p for _, p in poses) < MIN_PROBABILITY:
            print(f"  ({fam.name}: no pose reaches {MIN_PROBABILITY:.0%}; its most probable one)")
        turns = rng.uniform(0.0, 360.0, size=(2, len(poses), args.turns))
        for m, noise in enumerate([0.0, NOISE]):
            if noise not in modes:
                continue
            jobs = []
            for k, (posed, p) in enumerate(poses):
                for t in range(args.turns):
                    ang = float(turns[m, k, t])
                    jobs.append(
                        {
                            "mesh": solids.rotate_about_z(posed, ang),
                            "rules": fam.rules,
                            "noise": noise,
                            "explorer": args.explorer,
                            "shaft": args.shaft,
                            "set": args.set,
                            "what": f"{fam.name} pose {k} (p={p:.2f}) turned {ang:.0f}° "
                            f"noise {noise * 1000:g} mm",
                            "label": label,
                            "desc": what,
                        }
                    )
            groups.append((fam, noise, len(poses), jobs))
    if args.match:
        groups = [
            (fam, noise, n, [j for j in jobs if any(m in j["what"] for m in args.match)])
            for fam, noise, n, jobs in groups
        ]
        groups = [g for g in groups if g[3]]
    everything = [job for _, _, _, jobs in groups for job in jobs]
    if args.workers > 1:
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(args.workers) as pool:
            outcomes = list(pool.map(_job, everything, chunksize=1))
    else:
        outcomes = [_job(job) for job in everything]
    totals = {m: [0, 0] for m in modes}
    every_per_face: dict[float, list[float]] = {m: [] for m in modes}
    wrong: list[str] = []
    print(
        f"{'family':24s} {'mode':6s} {'poses':>5s} {'right':>7s} {'touch/face':>10s} "
        f"{'s/object':>8s} {'indexed':>7s} {'turning':>7s}"
    )
    at = 0
    for fam, noise, n_poses, jobs in groups:
        outs = outcomes[at : at + len(jobs)]
        at += len(jobs)
        right = sum(o["got"] == j["label"] for o, j in zip(outs, jobs, strict=True))
        for o, j in zip(outs, jobs, strict=True):
            if o["got"] != j["label"]:
                wrong.append(
                    f"{j['what']}: {o['got']} (want {j['label']}); {j['desc']}; "
                    f"{o['ending'] or 'no ending'} after {o['touches']} touches"
                )
        per_face = [o["touches"] / max(1, o["faces"]) for o in outs]
        secs = [o["seconds"] for o in outs]
        motions = sum(o["motions"] for o in outs)
        share = sum(o["indexed"] for o in outs) / motions if motions else 0.0
        turning = (
            f"{sum(o['turning'] for o in outs) / sum(secs):7.0%}"
            if args.explorer == "mujoco" and secs
            else "      -"
        )
        every_per_face[noise] += per_face
        totals[noise][0] += right
        totals[noise][1] += len(jobs)
        mode = "exact" if noise == 0 else f"{noise * 1000:g}mm"
        print(
            f"{fam.name:24s} {mode:6s} {n_poses:5d} {right:3d}/{len(jobs):<3d} "
            f"{statistics.median(per_face) if per_face else math.nan:10.2f} "
            f"{statistics.mean(secs) if secs else math.nan:8.2f} {share:7.0%} {turning}",
            flush=True,
        )
    for noise, (right, runs) in totals.items():
        mode = "exact contacts" if noise == 0 else f"{noise * 1000:g} mm noise"
        print(f"right answers, {mode}: {right}/{runs} = {right / max(1, runs):.1%}")
    for noise, per in every_per_face.items():
        mode = "exact contacts" if noise == 0 else f"{noise * 1000:g} mm noise"
        median = statistics.median(per) if per else math.nan
        print(f"median touches per face, {mode}: {median:.2f} (of {len(per)} objects)")
    if wrong:
        print("wrong:")
        for w in wrong:
            print("  " + w)


if __name__ == "__main__":
    main()
