"""Benchmark: contacts → merged planes → polyhedron → every feature.

Run ``.venv/bin/python benchmarks/bench_geometry.py [--repeat N]``; it prints, for each stage, the
median and (in brackets) the fastest of N runs (default 200) on 500-contact records (33-sensor
finger, quantised, 0.5 mm noise) of a box, a hexagonal pyramid and a cylinder (curved: many
small faces), and Qhull alone on 200 planes for reference. On a shared machine the fastest run
is the steadier figure; the target of the issue is the total, record → all features, < 5 ms.

Stages:

* *read contacts*: the record's pydantic contacts into numpy arrays (``contact_arrays``);
* *merge planes*: ``merge_planes(record)``, reading included;
* *polyhedron, as build_model*: ``polyhedron_from_planes`` of the merged planes with the
  interior point the model passes (the centre of the touched points);
* *polyhedron, Chebyshev LP*: the same without an interior point (a linear programme finds it);
* *build_model*: the whole model (planes, supporting faces, polyhedron, layers);
* *features, fresh model*: every built-in feature plus the face-angle table, the parallelism
  table and a cross-section, on a model that has computed nothing yet;
* *features, again*: the same on a model that has (shared derived values are reused);
* *total*: record → model → every feature.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import statistics
import sys
import time
from collections.abc import Callable
from functools import partial

import numpy as np
import trimesh
from scipy.spatial import HalfspaceIntersection

from tactile_kb import solids
from tactile_kb.errors import GeometryError
from tactile_kb.features.builtin import BUILTIN_FEATURES, face_angles, parallelism_table, section_at
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.geometry.planes import contact_arrays, merge_planes
from tactile_kb.geometry.polyhedron import polyhedron_from_planes
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record


def _times_ms(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """(median, fastest) wall time of ``fn`` in milliseconds, after one warm-up call."""
    fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * statistics.median(times), 1e3 * min(times)


def _features(model: ObjectModel) -> None:
    for name, feat in BUILTIN_FEATURES.items():
        params = {"equals": 6} if name == "face_count" else {}
        with contextlib.suppress(GeometryError):  # a feature needing a closed model
            feat.fn(model, **params)
    if model.polyhedron is not None:
        face_angles(model)
        parallelism_table(model)
        section_at(model, 0.01)


def _fresh_features(model: ObjectModel) -> None:
    _features(dataclasses.replace(model))  # a copy without the derived values


def _chain(rec: ExplorationRecord) -> None:
    _features(build_model(rec))


def _objects() -> list[tuple[str, trimesh.Trimesh]]:
    return [
        ("box", solids.rotate_about_z(solids.box(0.12, 0.08, 0.06), 17.0)),
        ("hex. pyramid", solids.rotate_about_z(solids.pyramid(6, 0.07, 0.06), 17.0)),
        ("cylinder", solids.rotate_about_z(solids.cylinder(0.04, 0.06), 17.0)),
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=200, help="timed runs per stage")
    args = parser.parse_args(argv or [])
    finger = builtin_finger("33")
    objects = _objects()
    rows: dict[str, list[str]] = {}
    for _, mesh in objects:
        rec = sample_record(mesh, finger, total=500, seed=1)
        model = build_model(rec)
        faces = merge_planes(rec)
        n = np.asarray([f.normal for f in faces])
        d = np.asarray([f.offset for f in faces])
        centres = contact_arrays(rec.contacts)[0]
        touched = np.vstack(
            [
                centres[list(f.contacts)] - rec.tip_radius * f.normal_array
                for f in faces
                if f.contacts
            ]
        )
        centre = touched.mean(axis=0)
        radius = float(np.linalg.norm(touched - centre, axis=1).max())
        kept = [i for i, s in enumerate(model.supporting) if s]
        rows.setdefault("contacts", []).append(f"{len(rec.contacts):>15d}")
        rows.setdefault("planes (with the table)", []).append(f"{len(faces):>15d}")
        poly = model.polyhedron
        rows.setdefault("polyhedron faces", []).append(
            f"{len(poly.faces) if poly is not None else 0:>15d}"
        )
        stages: list[tuple[str, Callable[[], object]]] = [
            ("read contacts", partial(contact_arrays, rec.contacts)),
            ("merge planes", partial(merge_planes, rec)),
            (
                "polyhedron, as build_model",
                partial(
                    polyhedron_from_planes,
                    n[kept],
                    d[kept],
                    bound=(centre, 3.0 * radius),
                    interior=centre,
                ),
            ),
            ("polyhedron, Chebyshev LP", partial(polyhedron_from_planes, n[kept], d[kept])),
            ("build_model", partial(build_model, rec)),
            ("features, fresh model", partial(_fresh_features, model)),
            ("features, again", partial(_features, model)),
            ("total: record → all features", partial(_chain, rec)),
        ]
        for label, fn in stages:
            med, best = _times_ms(fn, args.repeat)
            rows.setdefault(label + " (ms)", []).append(f"{med:7.2f} ({best:5.2f})")
    print(f"median (fastest) of {args.repeat} runs, 33-sensor finger, 0.5 mm noise")
    print(f"{'stage':34s} " + "  ".join(f"{name:>15s}" for name, _ in objects))
    for label, values in rows.items():
        print(f"{label:34s} " + "  ".join(values))
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(200, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    hs = np.hstack([normals, -np.ones((200, 1))])
    med, best = _times_ms(lambda: HalfspaceIntersection(hs, np.zeros(3)), args.repeat)
    print(f"{'Qhull alone, 200 planes (ms)':34s} {med:7.2f} ({best:5.2f})")


if __name__ == "__main__":
    main(sys.argv[1:])
