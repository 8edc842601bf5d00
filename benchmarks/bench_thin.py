"""Thin objects: tiles, flat boxes and bars lying on the table, ideal and scan-like.

Run: ``.venv/bin/python benchmarks/bench_thin.py [--instances N] [--workers N] [--levels 0,1,2,3]
[--family NAME]...``
(or ``python benchmarks/run.py thin``). It never fails; it prints, per family, perturbation
level (0: the ideal solid; 1-3: ``tactile_kb.perturb``'s scans) and mode (exact contacts, or
0.5 mm of contact-position noise), the share of objects given their true label, then every
wrong case.

The families, each in random sizes and turns about z, every instance scanned with its own
seed:

- ``tile``: square or oblong plates 18-30 cm across and 0.76-1.3 cm thick (the tip needs 7.5
  mm; a side lower than its diameter gives one height only; the thickness is under 6 % of
  the mean edge, or the corners lie within 3 % of the diameter of each other, where a square
  tile read as a cube or gave no model), ``parallelepipeds`` rules: a rectangular
  parallelepiped, never a cube;
- ``flat box``: 10-25 cm across and 2.5-4.5 cm thick (a cereal box lying down, a book),
  ``parallelepipeds`` rules;
- ``bar``: bars of equilateral-triangle or square section, 1.2-2 cm across and 20-40 cm long,
  lying on a face, ``polyhedra`` rules: a prism (a square one is a rectangular
  parallelepiped).
- ``slab``: square or oblong slabs 7-20 cm across and 1.2-2 cm thick (a phone, a sponge, a
  coaster, a paperback), ``parallelepipeds`` rules: their sides are a little higher than the
  tip's diameter, so a contour layer placed from the visual hint can run at the top's edge.

The true labels come from the construction, never from the code under test.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass

import numpy as np
import trimesh
from pool import map_jobs
from versions import versions_line

from tactile_kb import solids
from tactile_kb.perturb import perturb
from tactile_kb.pipeline import classify

NOISE = 0.0005

FAMILIES = ("tile", "flat box", "bar", "slab")
"""The families, in the order their random sizes are seeded (a new one goes last)."""

SIZES = {
    "tile": (0.18, 0.30, 0.0076, 0.013),
    "flat box": (0.10, 0.25, 0.025, 0.045),
    "slab": (0.07, 0.20, 0.012, 0.02),
}
"""Box families: the range of the longer side, then of the thickness (metres)."""


@dataclass(frozen=True)
class Job:
    family: str
    instance: int
    level: int
    noise: float


@dataclass(frozen=True)
class Outcome:
    job: Job
    name: str
    label: str
    got: str
    touches: int


def build(family: str, instance: int) -> tuple[trimesh.Trimesh, str, str, str]:
    """The object ``instance`` of ``family``: its mesh, rules, true label and description."""
    rng = np.random.default_rng(1000 * (1 + FAMILIES.index(family)) + instance)
    turn = float(rng.uniform(0.0, 360.0))
    if family in SIZES:
        lo, hi, t_lo, t_hi = SIZES[family]
        a = round(float(rng.uniform(lo, hi)), 4)
        b = a if instance % 2 == 0 else round(a * float(rng.uniform(0.5, 0.9)), 4)
        t = round(float(rng.uniform(t_lo, t_hi)), 4)
        mesh = solids.box(a, b, t)
        rules, label, desc = "parallelepipeds", "rectangular_parallelepiped", f"box({a}, {b}, {t})"
    else:
        sides = 3 if instance % 2 == 0 else 4
        width = round(float(rng.uniform(0.012, 0.02)), 4)
        length = round(float(rng.uniform(0.20, 0.40)), 4)
        r = width / (2 * math.sin(math.pi / sides))  # circumradius of a section of side width
        mesh = solids.prism(sides, r, length)
        # lying on a face along y: the prism's axis turned onto y, a side face down
        mesh.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
        low = mesh.facets_normal[np.argmin(mesh.facets_normal[:, 2])]
        mesh.apply_transform(trimesh.geometry.align_vectors(low, [0.0, 0.0, -1.0]))
        rules = "polyhedra"
        label = "prism" if sides == 3 else "rectangular_parallelepiped"
        desc = f"prism({sides}, side {width}, {length}) lying"
    mesh.apply_transform(trimesh.transformations.rotation_matrix(math.radians(turn), [0, 0, 1]))
    return mesh, rules, label, f"{desc} turned {turn:.1f}"


def run_job(job: Job) -> Outcome:
    mesh, rules, label, desc = build(job.family, job.instance)
    if job.level:
        mesh = perturb(mesh, job.level, seed=job.instance)
    try:
        result = classify(mesh, rules=rules, noise=job.noise, seed=0)
        got, touches = result.decision.label, result.record.touches
    except Exception as exc:  # a benchmark reports, never stops
        got, touches = f"error: {exc}", 0
    return Outcome(job, desc, label, got, touches)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=6, help="random objects per family")
    ap.add_argument("--workers", type=int, default=2, help="processes")
    ap.add_argument("--levels", default="0,1,2,3", help="perturbation levels (0: ideal)")
    ap.add_argument("--family", action="append", choices=FAMILIES, help="families (default: all)")
    args = ap.parse_args(argv if argv is not None else [])
    levels = [int(x) for x in args.levels.split(",")]
    families = tuple(args.family or FAMILIES)
    print(versions_line(), flush=True)
    todo = [
        Job(family, i, level, noise)
        for family in families
        for i in range(args.instances)
        for level in levels
        for noise in (0.0, NOISE)
    ]
    t0 = time.perf_counter()
    results = map_jobs(run_job, todo, args.workers)
    head = f"{'family':10s} {'level':>5s} {'exact':>7s} {'noisy':>7s}"
    print(head)
    print("-" * len(head))
    for family in families:
        for level in levels:
            cells = []
            for noisy in (False, True):
                rs = [
                    o
                    for o in results
                    if o.job.family == family
                    and o.job.level == level
                    and (o.job.noise > 0) == noisy
                ]
                cells.append(f"{sum(o.got == o.label for o in rs)}/{len(rs)}")
            print(f"{family:10s} {level:5d} {cells[0]:>7s} {cells[1]:>7s}")
    right = sum(o.got == o.label for o in results)
    print(f"\nall: {right}/{len(results)} right in {time.perf_counter() - t0:.0f} s")
    for o in results:
        if o.got != o.label:
            print(
                f"  [{o.job.family} level {o.job.level} noise {o.job.noise:g}] {o.name}: "
                f"want {o.label}, got {o.got} ({o.touches} touches)"
            )


if __name__ == "__main__":
    main(sys.argv[1:])
