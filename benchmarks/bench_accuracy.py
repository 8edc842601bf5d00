"""End-to-end accuracy: every object family explored by the stepper and classified, exact and noisy.

Run: ``.venv/bin/python benchmarks/bench_accuracy.py [--instances N] [--seeds N] [--workers N]
[--family NAME ...]`` (or ``python benchmarks/run.py accuracy`` for the defaults). It never
fails; it prints, per family and mode (exact positions, or 0.5 mm contact-position noise), the
share of objects given their true label, the touches per face, the seconds per object, and
then every misclassified case with what it would take to rebuild it.

The families: the twelve objects of the paper's Fig. 5 with the ``parallelepipeds`` rules (their
true labels are the paper's); and, with the ``polyhedra`` rules, cubes, boxes, nonrectangular
parallelepipeds, rhombohedra, tetrahedra, octahedra, prisms (n = 3…8), pyramids (n = 3…6),
frusta (n = 3…6), cylinders and spheres, each in random sizes (2–30 cm), random turns about z
and, where the family has several kinds of faces, a random face to rest on among those the
object can rest on stably and the finger can feel (no face overhanging by more than 20°: the
33-sensor finger feels contact directions up to about 20° above its equator). The true labels
come from the construction (a square prism is a parallelepiped; a three-sided pyramid is a
tetrahedron), never from the code under test.

"Faces" are the object's distinct planes except the one resting on the table; "touches" are
sensor OFF→ON events (the table itself is known without touching).
"""

from __future__ import annotations

import argparse
import itertools
import math
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely.geometry
import trimesh
from pool import map_jobs

from tactile_kb import solids
from tactile_kb.pipeline import classify
from tactile_kb.touch.synthetic import mesh_planes

NOISE = 0.0005
MAX_OVERHANG_DEG = 20.0

Builder = Callable[[np.random.Generator], tuple[trimesh.Trimesh, str, str]]


@dataclass(frozen=True)
class Family:
    name: str
    rules: str
    build: Builder


def _size(rng: np.random.Generator, lo: float = 0.02, hi: float = 0.30) -> float:
    """A log-uniform length in [lo, hi] metres (rounded to 0.1 mm)."""
    return round(float(math.exp(rng.uniform(math.log(lo), math.log(hi)))), 4)


def faces_to_touch(mesh: trimesh.Trimesh) -> int:
    """Distinct planes except the bottom one (z = 0, normal −z)."""
    return sum(1 for n, d in mesh_planes(mesh) if not (n[2] < -0.999 and abs(d) < 1e-9))


def overhang_deg(mesh: trimesh.Trimesh) -> float:
    """The largest angle (degrees) by which a face other than the base looks below the horizon."""
    worst = 0.0
    for n, d in mesh_planes(mesh):
        if n[2] < -0.999 and abs(d) < 1e-9:
            continue
        worst = max(worst, math.degrees(math.asin(max(0.0, -float(n[2])))))
    return worst


def _stable(mesh: trimesh.Trimesh) -> bool:
    """The centre of mass lies over the resting face (inside it, away from its edges)."""
    base = mesh.vertices[np.abs(mesh.vertices[:, 2]) < 1e-9][:, :2]
    if len(base) < 3:
        return False
    hull = shapely.geometry.MultiPoint([tuple(p) for p in base]).convex_hull
    com = mesh.center_mass[:2]
    return bool(hull.buffer(-1e-4).contains(shapely.geometry.Point(*com)))


def rest_randomly(mesh: trimesh.Trimesh, rng: np.random.Generator) -> tuple[trimesh.Trimesh, int]:
    """``mesh`` resting on a random face it can rest on stably and the finger can feel it in."""
    normals = [n for n, _ in mesh_planes(mesh)]
    order = rng.permutation(len(normals))
    for k in order:
        turned = solids.rest_on_face(mesh, normals[k])
        if _stable(turned) and overhang_deg(turned) <= MAX_OVERHANG_DEG:
            return turned, int(k)
    return mesh, -1


def _turn(mesh: trimesh.Trimesh, rng: np.random.Generator) -> tuple[trimesh.Trimesh, float]:
    angle = round(float(rng.uniform(0.0, 360.0)), 1)
    return solids.rotate_about_z(mesh, angle), angle


def _distinct(rng: np.random.Generator, k: int, ratio: float = 1.25) -> list[float]:
    """``k`` sizes whose pairwise ratios are at least ``ratio`` (so edges count as unequal)."""
    while True:
        xs = sorted(_size(rng) for _ in range(k))
        if all(b / a >= ratio for a, b in itertools.pairwise(xs)):
            return [float(x) for x in rng.permutation(xs)]


def cube(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    a = _size(rng)
    m, ang = _turn(solids.box(a, a, a), rng)
    return m, "cube", f"box({a}, {a}, {a}) turned {ang}"


def box(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    a, b, c = _distinct(rng, 3)
    m, face = rest_randomly(solids.box(a, b, c), rng)
    m, ang = _turn(m, rng)
    return m, "rectangular_parallelepiped", f"box({a}, {b}, {c}) on face {face} turned {ang}"


def oblique(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    a, b, c = (_size(rng, 0.03) for _ in range(3))
    angle = round(float(rng.choice([-1, 1]) * rng.uniform(15.0, 30.0) + 90.0), 1)
    shear = round(float(rng.uniform(0.0, 10.0)), 1)
    azim = round(float(rng.uniform(0.0, 360.0)), 1)
    base = solids.parallelepiped(a, b, c, angle_deg=angle, shear_deg=shear, shear_azimuth_deg=azim)
    m, face = rest_randomly(base, rng)
    m, ang = _turn(m, rng)
    what = f"parallelepiped({a}, {b}, {c}, angle_deg={angle}, shear_deg={shear}, shear_azimuth_deg={azim})"
    return m, "nonrectangular_parallelepiped", f"{what} on face {face} turned {ang}"


def rhombohedron(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    e = _size(rng, 0.03)
    angle = round(float(rng.uniform(72.0, 80.0)), 1)
    m, face = rest_randomly(solids.rhombohedron(e, angle), rng)
    m, ang = _turn(m, rng)
    return (
        m,
        "nonrectangular_parallelepiped",
        f"rhombohedron({e}, {angle}) on face {face} turned {ang}",
    )


def tetrahedron(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    e = _size(rng, 0.03)
    m, ang = _turn(solids.tetrahedron(e), rng)
    return m, "tetrahedron", f"tetrahedron({e}) turned {ang}"


def octahedron(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    e = _size(rng, 0.025, 0.30)
    m, ang = _turn(solids.octahedron(e), rng)
    return m, "octahedron", f"octahedron({e}) turned {ang}"


def prism(n: int) -> Builder:
    def build(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
        while True:
            r, h = _size(rng, 0.012, 0.15), _size(rng)
            side = 2 * r * math.sin(math.pi / n)
            if n != 4 or not 0.8 <= h / side <= 1.25:  # a square prism: a box, not a cube
                break
        m, ang = _turn(solids.prism(n, r, h), rng)
        label = "rectangular_parallelepiped" if n == 4 else "prism"
        return m, label, f"prism({n}, {r}, {h}) turned {ang}"

    return build


def pyramid(n: int) -> Builder:
    def build(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
        r = _size(rng, 0.012, 0.15)
        h = round(min(0.30, max(0.02, r * float(rng.uniform(0.7, 2.5)))), 4)
        m, ang = _turn(solids.pyramid(n, r, h), rng)
        label = "tetrahedron" if n == 3 else "pyramid"  # four triangles: a tetrahedron
        return m, label, f"pyramid({n}, {r}, {h}) turned {ang}"

    return build


def frustum(n: int) -> Builder:
    def build(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
        r = _size(rng, 0.015, 0.15)
        rt = round(r * float(rng.uniform(0.35, 0.7)), 4)
        h = round(min(0.30, max(0.02, r * float(rng.uniform(0.5, 2.0)))), 4)
        m, ang = _turn(solids.frustum(n, r, rt, h), rng)
        return m, "frustum", f"frustum({n}, {r}, {rt}, {h}) turned {ang}"

    return build


def cylinder(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    r, h = _size(rng, 0.01, 0.15), _size(rng)
    return solids.cylinder(r, h), "curved", f"cylinder({r}, {h})"


def sphere(rng: np.random.Generator) -> tuple[trimesh.Trimesh, str, str]:
    r = _size(rng, 0.01, 0.15)
    return solids.sphere(r), "curved", f"sphere({r})"


FAMILIES: list[Family] = [
    Family("cube", "polyhedra", cube),
    Family("box", "polyhedra", box),
    Family("nonrect_parallelepiped", "polyhedra", oblique),
    Family("rhombohedron", "polyhedra", rhombohedron),
    Family("tetrahedron", "polyhedra", tetrahedron),
    Family("octahedron", "polyhedra", octahedron),
    *(Family(f"prism{n}", "polyhedra", prism(n)) for n in range(3, 9)),
    *(Family(f"pyramid{n}", "polyhedra", pyramid(n)) for n in range(3, 7)),
    *(Family(f"frustum{n}", "polyhedra", frustum(n)) for n in range(3, 7)),
    Family("cylinder", "polyhedra", cylinder),
    Family("sphere", "polyhedra", sphere),
]


@dataclass(frozen=True)
class Job:
    family: str
    rules: str
    desc: str
    mesh: trimesh.Trimesh
    label: str
    noise: float
    seed: int


@dataclass(frozen=True)
class Outcome:
    job: Job
    got: str
    bits: str
    touches: int
    faces: int
    seconds: float

    @property
    def right(self) -> bool:
        return self.got == self.job.label


def run_job(job: Job) -> Outcome:
    t0 = time.perf_counter()
    try:
        r = classify(job.mesh, rules=job.rules, noise=job.noise, seed=job.seed)
        got, bits, touches = r.decision.label, r.decision.bits, r.record.touches
    except Exception as exc:  # a benchmark reports failures, it does not stop on them
        got, bits, touches = f"error: {type(exc).__name__}: {exc}"[:160], "", 0
    seconds = time.perf_counter() - t0
    return Outcome(job, got, bits, touches, faces_to_touch(job.mesh), seconds)


def jobs(instances: int, seeds: int, wanted: set[str]) -> list[Job]:
    out: list[Job] = []
    if not wanted or "fig5" in wanted:
        for name, mesh, label in solids.fig5_objects():
            out.append(Job("fig5", "parallelepipeds", name, mesh, label, 0.0, 0))
            out += [
                Job("fig5", "parallelepipeds", name, mesh, label, NOISE, s) for s in range(seeds)
            ]
    for k, fam in enumerate(FAMILIES):
        if wanted and fam.name not in wanted:
            continue
        rng = np.random.default_rng(1000 + k)
        for _ in range(instances):
            mesh, label, desc = fam.build(rng)
            out.append(Job(fam.name, fam.rules, desc, mesh, label, 0.0, 0))
            out += [Job(fam.name, fam.rules, desc, mesh, label, NOISE, s) for s in range(seeds)]
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=5, help="random objects per family")
    ap.add_argument("--seeds", type=int, default=2, help="noise seeds per object")
    ap.add_argument("--workers", type=int, default=2, help="processes")
    ap.add_argument("--family", action="append", default=[], help="only these families")
    args = ap.parse_args(argv if argv is not None else [])
    todo = jobs(args.instances, args.seeds, set(args.family))
    t0 = time.perf_counter()
    results = map_jobs(run_job, todo, args.workers)
    wall = time.perf_counter() - t0
    head = f"{'family':24s} {'mode':6s} {'right':>9s} {'acc %':>6s} {'t/face':>6s} {'s/obj':>6s} {'max s':>6s}"
    print(head)
    print("-" * len(head))
    fams = list(dict.fromkeys(o.job.family for o in results))
    total = {"exact": [0, 0], "noisy": [0, 0]}
    for fam in fams:
        for mode, noisy in (("exact", False), ("noisy", True)):
            rs = [o for o in results if o.job.family == fam and (o.job.noise > 0) == noisy]
            if not rs:
                continue
            right = sum(o.right for o in rs)
            total[mode][0] += right
            total[mode][1] += len(rs)
            curved = rs[0].job.label == "curved"
            tpf = "-" if curved else f"{statistics.mean(o.touches / o.faces for o in rs):6.2f}"
            secs = [o.seconds for o in rs]
            print(
                f"{fam:24s} {mode:6s} {right:4d}/{len(rs):<4d} {100 * right / len(rs):6.1f} "
                f"{tpf:>6s} {statistics.median(secs):6.3f} {max(secs):6.3f}"
            )
    print()
    for mode, (right, n) in total.items():
        if n:
            print(f"all families, {mode}: {right}/{n} right ({100 * right / n:.1f} %)")
    hexa = [
        o
        for o in results
        if o.job.label in ("cube", "rectangular_parallelepiped", "nonrectangular_parallelepiped")
        and o.faces == 5
    ]
    if hexa:
        ratios = [o.touches / o.faces for o in hexa]
        print(
            f"hexahedra: touches per face mean {statistics.mean(ratios):.2f}, "
            f"max {max(ratios):.2f} "
            f"(goal <= 2); seconds per object median {statistics.median(o.seconds for o in hexa):.3f}, "
            f"max {max(o.seconds for o in hexa):.3f} (goal <= 0.5)"
        )
    poly = [o for o in results if o.job.label != "curved"]
    if poly:
        ratios = [o.touches / o.faces for o in poly]
        print(
            f"all polyhedra: touches per face mean {statistics.mean(ratios):.2f}, "
            f"max {max(ratios):.2f}"
        )
    print(f"{len(results)} classifications in {wall:.1f} s wall time on {args.workers} process(es)")
    wrong = [o for o in results if not o.right]
    if wrong:
        print(f"\nmisclassified ({len(wrong)}):")
        for o in wrong:
            j = o.job
            print(
                f"  {j.family}: {j.desc} noise={j.noise} seed={j.seed}: want {j.label}, got "
                f"{o.got} {o.bits}"
            )


if __name__ == "__main__":
    main(sys.argv[1:])
