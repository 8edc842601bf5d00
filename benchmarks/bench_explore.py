"""Exploration cost of the built-in stepper: touches per face and seconds per object.

Run: ``.venv/bin/python benchmarks/bench_explore.py`` (prints a table; never fails on time).
Faces are the object's distinct planes minus the one resting on the table (the table is the
support plane, known without touching); "touches" are sensor OFF→ON events.
"""

from __future__ import annotations

import statistics
import time

import numpy as np
import trimesh

from tactile_kb import solids
from tactile_kb.touch.stepper import StepperExplorer


def planes(mesh: trimesh.Trimesh) -> int:
    """Distinct face planes of ``mesh`` except the bottom one (z = 0, normal −z)."""
    seen: list[tuple[np.ndarray, float]] = []
    for n, tri in zip(mesh.face_normals, mesh.triangles, strict=True):
        d = float(n @ tri[0])
        if n[2] < -0.999 and abs(d) < 1e-9:
            continue
        if not any(float(n @ m) > 1 - 1e-6 and abs(d - e) < 1e-6 for m, e in seen):
            seen.append((n, d))
    return len(seen)


def objects() -> list[tuple[str, trimesh.Trimesh, str]]:
    out = [(name, mesh, "33") for name, mesh, _ in solids.fig5_objects()]
    out += [
        ("prism5", solids.prism(5, 0.04, 0.06), "33"),
        ("prism12", solids.prism(12, 0.04, 0.06), "33"),
        ("pyramid4", solids.pyramid(4, 0.05, 0.06), "33"),
        ("frustum6", solids.frustum(6, 0.05, 0.03, 0.05), "33"),
        ("rhombohedron", solids.rhombohedron(0.06), "33"),
        ("cylinder", solids.cylinder(0.03, 0.05), "33"),
        ("L", solids.l_shape(0.08, 0.06, 0.03, 0.04), "4"),
        ("T", solids.t_shape(0.09, 0.07, 0.03, 0.04), "4"),
        ("U", solids.u_shape(0.09, 0.07, 0.03, 0.04), "4"),
    ]
    return out


def main() -> None:
    explorer = StepperExplorer()
    explorer.explore(solids.box(0.05, 0.05, 0.05), finger="33", seed=0)  # warm-up
    head = f"{'object':14s} {'finger':>6s} {'faces':>5s} {'touches':>7s} {'t/face':>6s} {'contacts':>8s} {'layers':>6s} {'path m':>7s} {'seconds':>8s}"
    print(head)
    print("-" * len(head))
    per_face: list[float] = []
    hexa: list[float] = []
    for name, mesh, finger in objects():
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            rec = explorer.explore(mesh, finger=finger, seed=0)
            times.append(time.perf_counter() - t0)
        sec = statistics.median(times)
        faces = planes(mesh)
        ratio = rec.touches / faces
        per_face.append(ratio)
        if name.startswith(("CUBE", "PRAPA", "KOPA")):
            hexa.append(sec)
        print(
            f"{name:14s} {finger:>6s} {faces:5d} {rec.touches:7d} {ratio:6.2f} {len(rec.contacts):8d} "
            f"{len(rec.layers):6d} {rec.path_length:7.3f} {sec:8.3f}"
        )
    print()
    print(
        f"touches per face: median {statistics.median(per_face):.2f}, max {max(per_face):.2f} (goal <= 2)"
    )
    print(
        f"hexahedra: median {statistics.median(hexa):.3f} s, max {max(hexa):.3f} s per object (goal <= 0.5 s)"
    )


if __name__ == "__main__":
    main()
