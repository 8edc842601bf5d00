"""Benchmark: contacts → merged planes → polyhedron → every feature.

Run ``.venv/bin/python benchmarks/bench_geometry.py``; it prints the median time of each
stage over repeated runs for a 500-contact record of a box (33-sensor finger, quantised, 0.5 mm
noise) and of a hexagonal pyramid, and Qhull alone on 200 planes for reference.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable
from functools import partial

import numpy as np
from scipy.spatial import HalfspaceIntersection

from tactile_kb import solids
from tactile_kb.features import BUILTIN_FEATURES, face_angles, parallelism_table, section_at
from tactile_kb.finger import builtin_finger
from tactile_kb.model import build_model
from tactile_kb.planes import merge_planes
from tactile_kb.polyhedron import polyhedron_from_planes
from tactile_kb.record import ExplorationRecord
from tactile_kb.synthetic import sample_record


def _median_ms(fn: Callable[[], object], repeat: int = 50) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times)


def _features(model: object) -> None:
    for name, feat in BUILTIN_FEATURES.items():
        params = {"equals": 6} if name == "face_count" else {}
        feat.fn(model, **params)
    face_angles(model)  # type: ignore[arg-type]
    parallelism_table(model)  # type: ignore[arg-type]
    section_at(model, 0.01)  # type: ignore[arg-type]


def _chain(rec: ExplorationRecord) -> None:
    _features(build_model(rec))


def main() -> None:
    finger = builtin_finger("33")
    print("stage (median of 50 runs)                 box      hex. pyramid")
    rows: dict[str, list[float]] = {}
    for mesh in (
        solids.rotate_about_z(solids.box(0.12, 0.08, 0.06), 17.0),
        solids.rotate_about_z(solids.pyramid(6, 0.07, 0.06), 17.0),
    ):
        n_faces = len(mesh.facets) + (len(mesh.faces) - sum(len(f) for f in mesh.facets)) - 1
        rec = sample_record(mesh, finger, total=500, seed=1)
        faces = merge_planes(rec)
        n = np.asarray([f.normal for f in faces])
        d = np.asarray([f.offset for f in faces])
        model = build_model(rec)
        rows.setdefault("faces touched", []).append(n_faces)
        rows.setdefault("contacts", []).append(len(rec.contacts))
        rows.setdefault("merge planes (ms)", []).append(_median_ms(partial(merge_planes, rec)))
        rows.setdefault("polyhedron from planes (ms)", []).append(
            _median_ms(partial(polyhedron_from_planes, n, d))
        )
        rows.setdefault("build_model, whole chain (ms)", []).append(
            _median_ms(partial(build_model, rec))
        )
        rows.setdefault("every feature + values (ms)", []).append(
            _median_ms(partial(_features, model))
        )
        rows.setdefault("total: record → all features (ms)", []).append(
            _median_ms(partial(_chain, rec))
        )
    for label, values in rows.items():
        print(f"{label:40s} " + "  ".join(f"{v:8.2f}" for v in values))
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    hs = np.hstack([normals, -np.ones((200, 1))])
    print(
        f"{'Qhull alone, 200 planes (ms)':40s} {_median_ms(lambda: HalfspaceIntersection(hs, np.zeros(3))):8.2f}"
    )


if __name__ == "__main__":
    main()
