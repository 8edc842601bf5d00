"""Real and scan-like objects: the vendored real meshes and perturbed ideal solids, explored and
classified.

Run: ``.venv/bin/python benchmarks/bench_real.py [--instances N] [--seeds N] [--levels 1,2,3]
[--workers N] [--explorer NAME ...] [--family NAME ...] [--no-real] [--draw N] [--log FILE]
[--set GROUP.FIELD=VALUE ...] [--settings FILE.toml]`` (or
``python benchmarks/run.py real``). It never fails; it prints, per group (real objects; ideal
solids; perturbed solids per level) and explorer:

* right answers (%) over both rule files, with and without 0.5 mm contact-position noise;
* "needs a closed model" endings (the exploration did not close the envelope);
* the median touches per face on boxes (cubes and rectangular parallelepipeds);
* the median seconds per object, and the median ratio of an object's seconds to those of the
  same ideal solid (same rules, noise and explorer).

The real objects are ``tests/data/real`` (labels from its ``manifest.csv``); the perturbed
solids are every family of ``bench_accuracy`` (one random instance each by default) made
scan-like by :func:`tactile_kb.perturb.perturb` at levels 1–3. Level 3 cuts holes and adds
floating specks; an explorer that refuses such a mesh shows as an error. The ``mujoco``
explorer is measured when its plugin is installed.

The default run takes one perturbation seed (764 classifications with both explorers, about
20 minutes at 2 workers on a quiet 2-core machine). The issue's full figures take two:
``--seeds 2`` (1,292 classifications, about twice as long). ``--log FILE`` writes every outcome
to a CSV file as it comes (the jobs run in a shuffled order, so an interrupted run's log is a
fair sample), and ``--summarize FILE`` prints the figures of such a file. ``--reverse`` runs
the shuffled jobs from the last one back: a second process started beside a first one (each
with its own ``--log``) meets it half-way, and the two logs together hold every outcome.

``--records DIR`` also saves every exploration record there (``DIR/index.csv`` names them);
``--rejudge DIR`` classifies those records again with the code as it is now, without
exploring, and prints every answer that changed (in seconds for a whole draw). That is the
final answer exactly for a change of what follows the exploration, and a first screen for a
change of the model, which the completion also consults: the exploration itself would then
change where its probes do, and only a full run tells.

``--set GROUP.FIELD=VALUE`` (repeatable) and ``--settings FILE.toml`` run, rejudge or match
faces under other tolerances and budgets, as the command line's options of the same names do
(docs/settings.md): ``--rejudge DIR --set geometry.edge_rounding=0.13`` screens a threshold
over a whole draw's saved explorations in seconds. The settings changed are printed under the
versions line.

``--faces DIR`` (with the run's ``--draw``, ``--instances`` and ``--seeds``) makes the solids
again and matches each saved model's faces to their planes: per group, how many models have
every face right, extra faces (a split of one face, or an edge's face between two), missing or
tilted ones (5° or more), a concave or an open model, and how far the faces' normals are off
in units of the uncertainty the model gives them (``z``: each plane's nearest face's tilt over
that face's ``normal_uncertainty_deg``, median and 90th percentile; errors as uncertain as
the model says, equal in every direction, give about 1.2 and 2.1, the Rayleigh
distribution's; larger, the model is surer of its faces than they are right, and every
tolerance widened by those uncertainties is too narrow); then each wrong answer's model. It
says why an answer is wrong before anyone opens a record.

``--truth ITEMS`` (with ``--rejudge`` or ``--faces`` and the run's ``--draw``, ``--instances``
and ``--seeds``) first puts the solids' truth into the records (``benchmarks/truth.py``):
``roundings`` drops the touches of rounded edges, ``readings`` gives the other touches the
sensors an ideal face fires, ``centres`` puts their tip centres ρ from the ideal surface. What
an item gains is what a perfect cure of that imperfection could gain.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import hashlib
import multiprocessing
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_accuracy import FAMILIES, NOISE, faces_to_touch
from truth import corrected, parse_items, true_planes
from versions import versions_line

from tactile_kb import settings as tk_settings
from tactile_kb.cli.options import chosen_settings as cli_settings
from tactile_kb.errors import UsageError
from tactile_kb.objects import load_object
from tactile_kb.perturb import perturb
from tactile_kb.pipeline import classify, classify_record
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.explorers import available_explorers

REAL = Path(__file__).resolve().parent.parent / "tests" / "data" / "real"
POLY_TO_PARALLELEPIPEDS = {
    "cube": "cube",
    "rectangular_parallelepiped": "rectangular_parallelepiped",
    "nonrectangular_parallelepiped": "nonrectangular_parallelepiped",
}
BOXES = {"cube", "rectangular_parallelepiped"}


@dataclass(frozen=True)
class Job:
    group: str
    name: str
    mesh: trimesh.Trimesh
    ideal: trimesh.Trimesh | None
    rules: str
    label: str
    noise: float
    explorer: str
    faces: int
    records: Path | None = None
    settings: tk_settings.Settings | None = None


@dataclass(frozen=True)
class Outcome:
    """One classification, as the summary and the ``--log`` file hold it."""

    explorer: str
    group: str
    name: str
    rules: str
    noise: float
    label: str
    faces: int
    got: str
    touches: int
    seconds: float

    @property
    def right(self) -> bool:
        return self.got == self.label

    @property
    def open_model(self) -> bool:
        return "needs a closed model" in self.got


FIELDS = list(Outcome.__dataclass_fields__)


def _label_for(rules: str, poly_label: str, mesh: trimesh.Trimesh) -> str | None:
    """The true label under ``rules`` of an object whose polyhedra label is ``poly_label``."""
    if rules == "polyhedra":
        return poly_label
    if poly_label in POLY_TO_PARALLELEPIPEDS:
        return POLY_TO_PARALLELEPIPEDS[poly_label]
    if poly_label == "curved":
        return "not_hexahedron"
    return "other_hexahedron" if faces_to_touch(mesh) + 1 == 6 else "not_hexahedron"


def _using(chosen: tk_settings.Settings | None) -> contextlib.AbstractContextManager[object]:
    """``chosen`` (``--set``, ``--settings``) in force inside the block; the defaults when None.
    Each worker process enters it for each case: nothing relies on what a fork inherits."""
    return tk_settings.use(chosen) if chosen is not None else contextlib.nullcontext()


def chosen_settings(args: argparse.Namespace) -> tk_settings.Settings | None:
    """The settings of ``--settings FILE`` then each ``--set``, as the command line chooses
    them (:func:`tactile_kb.cli.options.chosen_settings`); None when neither was given. A bad
    file or assignment is refused in one line naming it."""
    try:
        chosen: tk_settings.Settings | None = cli_settings(args)
    except UsageError as exc:
        raise SystemExit(str(exc)) from None
    return chosen


def record_name(explorer: str, group: str, name: str, rules: str, noise: float) -> str:
    """The file name of a case's saved record (``--records``): a digest of what makes the case."""
    key = f"{explorer}|{group}|{name}|{rules}|{noise!r}"
    return hashlib.sha1(key.encode()).hexdigest()[:16] + ".json"


def _classify(mesh: trimesh.Trimesh, job: Job) -> tuple[str, int, float]:
    t0 = time.perf_counter()
    try:
        with _using(job.settings):
            r = classify(mesh, rules=job.rules, explorer=job.explorer, noise=job.noise, seed=0)
        got, touches = r.decision.label, r.record.touches
        if job.records is not None:
            r.record.save(
                job.records / record_name(job.explorer, job.group, job.name, job.rules, job.noise)
            )
    except Exception as exc:  # a benchmark reports failures, it does not stop on them
        got, touches = f"error: {type(exc).__name__}: {exc}"[:200], 0
    return got, touches, time.perf_counter() - t0


def run_job(job: Job) -> Outcome:
    got, touches, seconds = _classify(job.mesh, job)
    return Outcome(
        job.explorer,
        job.group,
        job.name,
        job.rules,
        job.noise,
        job.label,
        job.faces,
        got,
        touches,
        seconds,
    )


def _key(o: Outcome) -> tuple[str, str, str, float]:
    """The same ideal solid, rules, explorer and noise (perturbation seeds aside)."""
    return (o.name.rsplit(" seed ", 1)[0], o.rules, o.explorer, o.noise)


def jobs(
    instances: int,
    seeds: int,
    levels: list[int],
    explorers: list[str],
    families: set[str] | None = None,
    real: bool = True,
    draw: int = 0,
) -> list[Job]:
    out: list[Job] = []
    with (REAL / "manifest.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    for explorer in explorers:
        for noise in (0.0, NOISE) if real else ():
            for row in rows:
                mesh = load_object(REAL / row["path"])
                out.append(
                    Job(
                        "real",
                        row["path"],
                        mesh,
                        None,
                        row["rules"],
                        row["label"],
                        noise,
                        explorer,
                        faces_to_touch(mesh),
                    )
                )
        for k, fam in enumerate(FAMILIES):
            if families is not None and fam.name not in families:
                continue
            # draw 0 is the set every earlier figure was measured on; another is held out
            rng = np.random.default_rng(2000 + k if not draw else [draw, 2000 + k])
            for _ in range(instances):
                ideal, poly_label, desc = fam.build(rng)
                for rules in ("polyhedra", "parallelepipeds"):
                    label = _label_for(rules, poly_label, ideal)
                    for noise in (0.0, NOISE):
                        out.append(
                            Job(
                                "ideal",
                                f"{fam.name}: {desc}",
                                ideal,
                                None,
                                rules,
                                label,
                                noise,
                                explorer,
                                faces_to_touch(ideal),
                            )
                        )
                for level in levels:
                    for seed in range(seeds):
                        scan = perturb(ideal, level, seed=seed)
                        for rules in ("polyhedra", "parallelepipeds"):
                            label = _label_for(rules, poly_label, ideal)
                            for noise in (0.0, NOISE):
                                out.append(
                                    Job(
                                        f"level {level}",
                                        f"{fam.name}: {desc} seed {seed}",
                                        scan,
                                        ideal,
                                        rules,
                                        label,
                                        noise,
                                        explorer,
                                        faces_to_touch(ideal),
                                    )
                                )
    return out


def summary(results: list[Outcome]) -> None:
    """Print the figures per explorer and group, then the wrong answers."""
    ideal = {_key(o): o.seconds for o in results if o.group == "ideal"}
    head = (
        f"{'explorer':9s} {'group':8s} {'right':>9s} {'acc %':>6s} {'open':>5s} "
        f"{'t/face box':>10s} {'s/obj':>6s} {'× ideal':>7s}"
    )
    print(head)
    print("-" * len(head))
    for explorer in dict.fromkeys(o.explorer for o in results):
        for group in dict.fromkeys(o.group for o in results):
            rs = [o for o in results if o.group == group and o.explorer == explorer]
            if not rs:
                continue
            right = sum(o.right for o in rs)
            opened = sum(o.open_model for o in rs)
            boxes = [o.touches / o.faces for o in rs if o.label in BOXES and o.faces]
            tpf = f"{statistics.median(boxes):10.2f}" if boxes else f"{'-':>10s}"
            secs = statistics.median(o.seconds for o in rs)
            ratios = [o.seconds / ideal[_key(o)] for o in rs if _key(o) in ideal]
            ratio = f"{statistics.median(ratios):7.2f}" if ratios else f"{'-':>7s}"
            print(
                f"{explorer:9s} {group:8s} {right:4d}/{len(rs):<4d} {100 * right / len(rs):6.1f} "
                f"{opened:5d} {tpf} {secs:6.2f} {ratio}"
            )
    wrong = [o for o in results if not o.right]
    if wrong:
        print(f"\nwrong ({len(wrong)}):")
        for o in wrong:
            noise = "noisy" if o.noise else "exact"
            print(
                f"  [{o.explorer} {o.group} {o.rules} {noise}] {o.name}: want {o.label}, got {o.got}"
            )


def read_log(path: Path) -> list[Outcome]:
    """The outcomes a ``--log`` file holds (a complete or an interrupted run)."""
    with path.open(newline="") as f:
        return [
            Outcome(
                r["explorer"],
                r["group"],
                r["name"],
                r["rules"],
                float(r["noise"]),
                r["label"],
                int(r["faces"]),
                r["got"],
                int(r["touches"]),
                float(r["seconds"]),
            )
            for r in csv.DictReader(f)
        ]


INDEX = "index.csv"
"""The list of a ``--records`` directory's records: one row per case, its outcome's fields."""


def _record(
    folder: Path, row: dict[str, str], solid: trimesh.Trimesh | None, truth: tuple[str, ...]
) -> ExplorationRecord:
    """The record of ``row`` saved in ``folder``, with ``truth`` (:mod:`truth`) put in from
    ``solid`` when both are given."""
    record = ExplorationRecord.load(
        folder
        / record_name(row["explorer"], row["group"], row["name"], row["rules"], float(row["noise"]))
    )
    if truth and solid is not None:
        record = corrected(record, solid, row["group"], truth)
    return record


RejudgeJob = tuple[
    Path, dict[str, str], tk_settings.Settings | None, trimesh.Trimesh | None, tuple[str, ...]
]


def _rejudge_one(job: RejudgeJob) -> tuple[dict[str, str], str]:
    folder, row, chosen, solid, truth = job
    try:
        with _using(chosen):
            record = _record(folder, row, solid, truth)
            got = classify_record(record, rules=row["rules"]).decision.label
    except Exception as exc:  # a benchmark reports failures, it does not stop on them
        got = f"error: {type(exc).__name__}: {exc}"[:200]
    return row, got


def read_index(folder: Path) -> list[dict[str, str]]:
    """The rows of a ``--records`` directory's index, those of failed cases left out (they
    saved no record); one line naming the file when there is none or it is no such index."""
    index = folder / INDEX
    if not index.is_file():
        raise SystemExit(f"{index}: no such file (save records with --records {folder})")
    with index.open(newline="") as f:
        reader = csv.DictReader(f)
        missing = [
            k
            for k in ("explorer", "group", "name", "rules", "noise", "label", "got")
            if k not in (reader.fieldnames or ())
        ]
        if missing:
            raise SystemExit(f"{index}:1: not an index of --records (no column {missing[0]!r})")
        return [r for r in reader if not r["got"].startswith("error")]


def rejudge(
    folder: Path,
    workers: int,
    chosen: tk_settings.Settings | None = None,
    truth: tuple[str, ...] = (),
    solids: dict[tuple[str, str, str, str, float], trimesh.Trimesh] | None = None,
) -> None:
    """Classify the records saved with ``--records`` again (under ``chosen`` settings, when
    given; with ``truth`` put in from the ``solids`` explored, keyed by :func:`_case`);
    print what changed, per group."""
    rows = read_index(folder)
    t0 = time.perf_counter()
    solids = solids or {}
    todo: list[RejudgeJob] = [(folder, r, chosen, solids.get(_case(r)), truth) for r in rows]
    if truth:
        alone = sum(_case(r) not in solids for r in rows)
        print(f"truth: {', '.join(truth)} put into {len(rows) - alone} records", end="")
        print(f" ({alone} with no solid to take it from, as they are)" if alone else "")
    if workers > 1:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            done = list(pool.imap_unordered(_rejudge_one, todo, 4))
    else:
        done = [_rejudge_one(t) for t in todo]
    groups: dict[tuple[str, str], list[int]] = {}
    changed = []
    for row, got in done:
        was, now = row["got"] == row["label"], got == row["label"]
        tally = groups.setdefault((row["explorer"], row["group"]), [0, 0, 0])
        tally[0] += was
        tally[1] += now
        tally[2] += 1
        if got != row["got"]:
            tag = "gained" if now else "lost" if was else "changed"
            changed.append(
                f"  {tag}: [{row['explorer']} {row['group']} {row['rules']} noise "
                f"{float(row['noise']):g}] {row['name']}: want {row['label']}, "
                f"was {row['got']}, now {got}"
            )
    for (explorer, group), (was, now, n) in sorted(groups.items()):
        print(f"{explorer:8s} {group:8s} right {was}/{n} when explored, {now}/{n} now")
    print(f"{len(changed)} answer(s) changed" + (":" if changed else ""))
    for line in sorted(changed):
        print(line)
    print(f"{len(done)} records classified again in {time.perf_counter() - t0:.1f} s")


TILTED_DEG = 5.0
"""``--faces``: a model face this far (degrees) or further from its plane of the object is
tilted."""
SPLIT_DEG = 8.0
"""``--faces``: a second model face of one plane of the object within this angle of it is a
split of that face; further, and between two of the object's planes, an edge's face."""


@dataclass(frozen=True)
class FaceCheck:
    """A model's faces against the planes of the solid it was explored on (``--faces``)."""

    planes: int
    faces: int
    split: int
    edge: int
    missing: int
    tilt_deg: float
    convex: bool
    closed: bool
    z: tuple[float, ...] = ()
    """Per plane met, its nearest face's tilt over that face's normal uncertainty (at least
    :data:`Z_FLOOR_DEG`)."""

    @property
    def kinds(self) -> str:
        out = [
            name
            for name, flag in (
                ("extra", self.extra),
                ("missing", self.missing),
                ("tilted", self.tilt_deg >= TILTED_DEG),
                ("concave", not self.convex),
                ("open", not self.closed),
            )
            if flag
        ]
        return " ".join(out) or "faces right"

    @property
    def extra(self) -> int:
        """Faces beyond one per plane: the splits and the edges' faces."""
        return self.split + self.edge


Z_FLOOR_DEG = 0.1
"""``--faces``: a face's normal uncertainty counts as at least this (degrees) in ``z``: an
exact record's faces fit their planes to rounding, and a tilt of a millionth of a degree over
that is no miscalibration any tolerance (5° and more) would feel."""

OFFSET_DEG = 1000.0
"""``--faces``: degrees a metre of offset counts as when matching a model face to a plane
(1 mm as 1°): parallel planes of a composed solid (an L block's two tops) are told apart."""


def check_faces(
    faces: tuple[np.ndarray, np.ndarray],
    planes: tuple[np.ndarray, np.ndarray],
    *,
    convex: bool,
    closed: bool,
    uncertainty: np.ndarray | None = None,
) -> FaceCheck:
    """Match each model face (rows of unit normals and offsets, ``faces``) to the nearest
    plane of the object (``planes``): by angle, a metre of offset counting as
    :data:`OFFSET_DEG`. A plane met by more than one face has extra faces (a split within
    :data:`SPLIT_DEG` of it, else an edge's face, turned towards a neighbour), one met by
    none is missing, and the tilt is the largest angle between a plane and the nearest of its
    faces. With ``uncertainty`` (degrees, per face), each plane's nearest face's tilt over
    its uncertainty (at least :data:`Z_FLOOR_DEG`) is ``z``."""
    (fn, fd), (pn, pd) = faces, planes
    ang = np.degrees(np.arccos(np.clip(fn @ pn.T, -1.0, 1.0))).reshape(len(fn), len(pn))
    cost = ang + OFFSET_DEG * np.abs(fd[:, None] - pd[None, :])
    nearest = cost.argmin(axis=1) if len(fn) else np.zeros(0, dtype=int)
    angle = ang[np.arange(len(fn)), nearest]
    split = edge = 0
    tilt = 0.0
    z = []
    met = set(nearest.tolist())
    for k in sorted(met):
        idx = np.flatnonzero(nearest == k)
        idx = idx[np.argsort(angle[idx])]  # the plane's nearest face first
        if uncertainty is not None:
            z.append(float(angle[idx[0]] / max(float(uncertainty[idx[0]]), Z_FLOOR_DEG)))
        mine = angle[idx]
        tilt = max(tilt, float(mine[0]))
        split += int((mine[1:] < SPLIT_DEG).sum())
        edge += int((mine[1:] >= SPLIT_DEG).sum())
    return FaceCheck(
        planes=len(pn),
        faces=len(fn),
        split=split,
        edge=edge,
        missing=len(pn) - len(met),
        tilt_deg=tilt,
        convex=convex,
        closed=closed,
        z=tuple(z),
    )


def _faces_one(
    job: tuple[Path, dict[str, str], trimesh.Trimesh, tk_settings.Settings | None, tuple[str, ...]],
) -> tuple[dict[str, str], FaceCheck | str]:
    folder, row, solid, chosen, truth = job
    try:
        with _using(chosen):
            model = classify_record(_record(folder, row, solid, truth), rules=row["rules"]).model
    except Exception as exc:  # a benchmark reports failures, it does not stop on them
        return row, f"{type(exc).__name__}: {exc}"[:200]
    kept = [f for f in model.faces if f.source != "assumed"]
    normals = np.asarray([f.normal for f in kept], dtype=float).reshape(-1, 3)
    offsets = np.asarray([f.offset for f in kept], dtype=float)
    return row, check_faces(
        (normals, offsets),
        true_planes(solid),
        convex=model.convex,
        closed=model.polyhedron is not None,
        uncertainty=np.asarray([f.normal_uncertainty_deg for f in kept], dtype=float),
    )


def _z_columns(checks: list[FaceCheck]) -> str:
    """The ``z50`` and ``z90`` columns: the median and 90th percentile of the checks' ``z``."""
    z = [v for c in checks for v in c.z]
    if not z:
        return f"{'-':>5s} {'-':>5s}"
    z50, z90 = np.percentile(z, [50, 90])
    return f"{z50:5.1f} {z90:5.1f}"


def _case(row: dict[str, str]) -> tuple[str, str, str, str, float]:
    """The key of a case: explorer, group, name, rules and noise."""
    return (row["explorer"], row["group"], row["name"], row["rules"], float(row["noise"]))


def solids_of(
    folder: Path, rows: list[dict[str, str]], draw: int, instances: int, seeds: int
) -> dict[tuple[str, str, str, str, float], trimesh.Trimesh]:
    """The ideal solid of each case of ``rows`` (the real objects have none), made again from
    ``draw``, ``instances`` and ``seeds``, which must be those of the run that saved them in
    ``folder``; one line naming the index when a case is not one of them."""
    levels = sorted({int(r["group"].split()[1]) for r in rows if r["group"].startswith("level ")})
    families = {r["name"].split(":", 1)[0] for r in rows if r["group"] != "real"}
    explorers = sorted({r["explorer"] for r in rows})
    made = jobs(instances, seeds, levels, explorers, families, False, draw)
    solids = {
        (j.explorer, j.group, j.name, j.rules, j.noise): j.ideal if j.ideal is not None else j.mesh
        for j in made
    }
    for r in rows:
        if r["group"] != "real" and _case(r) not in solids:
            raise SystemExit(
                f"{folder / INDEX}: {r['group']} {r['name']!r} is not a case of --draw {draw} "
                f"--instances {instances} --seeds {seeds} (give the run's)"
            )
    return solids


def faces_report(
    folder: Path,
    draw: int,
    instances: int,
    seeds: int,
    workers: int,
    chosen: tk_settings.Settings | None = None,
    truth: tuple[str, ...] = (),
) -> None:
    """Compare the model of every record in ``folder`` (saved with ``--records``) with the
    solid it was explored on: per group, the cases whose model has extra, missing or tilted
    faces, is concave or open; then every wrong answer's model. The solids are made again
    from ``draw``, ``instances`` and ``seeds``, which must be those of the run. With
    ``truth``, the records get it first (:mod:`truth`)."""
    rows = read_index(folder)
    solids = solids_of(folder, rows, draw, instances, seeds)
    # a curved solid's tessellation is no set of faces to find
    curved = {r["name"] for r in rows if r["rules"] == "polyhedra" and r["label"] == "curved"}
    todo = [
        (folder, r, solids[_case(r)], chosen, truth)
        for r in rows
        if r["group"] != "real" and r["name"] not in curved
    ]
    if workers > 1:
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            done = list(pool.imap(_faces_one, todo, 4))
    else:
        done = [_faces_one(t) for t in todo]
    groups: dict[str, list[tuple[dict[str, str], FaceCheck]]] = {}
    unread = []
    for row, check in done:
        if isinstance(check, FaceCheck):
            groups.setdefault(row["group"], []).append((row, check))
        else:
            unread.append(f"  [{row['group']}] {row['name']}: {check}")
    head = (
        f"{'group':8s} {'cases':>5s} {'faces right':>11s} {'extra':>5s} {'split':>5s} "
        f"{'edge':>5s} {'missing':>7s} {'tilted':>6s} {'concave':>7s} {'open':>4s} "
        f"{'z50':>5s} {'z90':>5s}"
    )
    print(head)
    print("-" * len(head))
    for group, cs in sorted(groups.items()):
        checks = [c for _, c in cs]
        print(
            f"{group:8s} {len(cs):5d} {sum(c.kinds == 'faces right' for c in checks):11d} "
            f"{sum(c.extra > 0 for c in checks):5d} {sum(c.split > 0 for c in checks):5d} "
            f"{sum(c.edge > 0 for c in checks):5d} {sum(c.missing > 0 for c in checks):7d} "
            f"{sum(c.tilt_deg >= TILTED_DEG for c in checks):6d} "
            f"{sum(not c.convex for c in checks):7d} {sum(not c.closed for c in checks):4d} "
            f"{_z_columns(checks)}"
        )
    wrong = [(r, c) for cs in groups.values() for r, c in cs if r["got"] != r["label"]]
    if wrong:
        print(f"\nwrong ({len(wrong)}), the model against the solid:")
    for r, c in sorted(wrong, key=lambda rc: (rc[0]["group"], rc[0]["name"])):
        print(
            f"  [{r['explorer']} {r['group']} {r['rules']} noise {float(r['noise']):g}] "
            f"{r['name']}: got {r['got']}; {c.faces} faces for {c.planes} planes, "
            f"{c.extra} extra ({c.split} split, {c.edge} edge), {c.missing} missing, "
            f"tilt {c.tilt_deg:.1f}°: {c.kinds}"
        )
    if unread:
        print(f"\n{len(unread)} record(s) could not be modelled:")
        print("\n".join(unread))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=1, help="random objects per family")
    ap.add_argument("--seeds", type=int, default=1, help="perturbation seeds per object (full: 2)")
    ap.add_argument("--levels", default="1,2,3", help="perturbation levels")
    ap.add_argument("--workers", type=int, default=2, help="processes")
    ap.add_argument("--explorer", action="append", default=[], help="explorers (default: all)")
    ap.add_argument("--family", action="append", default=[], help="families (default: all)")
    ap.add_argument("--no-real", action="store_true", help="leave out the vendored real objects")
    ap.add_argument("--log", type=Path, help="write each outcome to this CSV file as it comes")
    ap.add_argument("--summarize", type=Path, help="print the figures of a --log file and stop")
    ap.add_argument(
        "--draw",
        type=int,
        default=0,
        help="which random objects to perturb (0: the set of the earlier figures; any other "
        "number: another set, to check that a change is not tuned to one)",
    )
    ap.add_argument(
        "--reverse",
        action="store_true",
        help="run the shuffled jobs from the last one back (a second process that meets a "
        "first one half-way; --summarize the two logs concatenated)",
    )
    ap.add_argument(
        "--records",
        type=Path,
        help="also save every exploration record in this directory (with an index.csv)",
    )
    ap.add_argument(
        "--rejudge",
        type=Path,
        help="classify the records saved with --records in this directory again, print "
        "what changed, and stop",
    )
    ap.add_argument(
        "--faces",
        type=Path,
        help="compare the models of the records saved with --records in this directory "
        "with the solids explored (made again from --draw, --instances and --seeds, which "
        "must be the run's): extra, missing and tilted faces, per group and per wrong answer",
    )
    ap.add_argument(
        "--truth",
        metavar="ITEMS",
        help="with --rejudge or --faces: first put the solid's truth into each record, "
        "comma-separated from roundings (drop the touches of rounded edges), readings (the "
        "sensors an ideal face fires) and centres (tip centres ρ from the ideal surface); the "
        "solids are made again from --draw, --instances and --seeds, which must be the run's",
    )
    ap.add_argument(
        "--settings",
        type=Path,
        metavar="FILE.toml",
        help="tolerances and budgets from a TOML file, one [group] table each (docs/settings.md)",
    )
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="GROUP.FIELD=VALUE",
        help="change one setting, e.g. geometry.edge_rounding=0.13 (repeatable; after --settings)",
    )
    args = ap.parse_args(argv if argv is not None else [])
    chosen = chosen_settings(args)
    truth = parse_items(args.truth) if args.truth is not None else ()
    if truth and not (args.rejudge or args.faces):
        raise SystemExit(f"--truth {args.truth}: give --rejudge DIR or --faces DIR with it")
    if not args.summarize:  # a log's figures were measured with what wrote it
        print(versions_line(), flush=True)
        if chosen is not None:
            given = ([f"--settings {args.settings}"] if args.settings else []) + [
                f"--set {a}" for a in args.set
            ]
            print("settings: " + " ".join(given), flush=True)
    if args.faces:
        faces_report(args.faces, args.draw, args.instances, args.seeds, args.workers, chosen, truth)
        return
    if args.summarize:
        summary(read_log(args.summarize))
        return
    if args.rejudge:
        solids = (
            solids_of(args.rejudge, read_index(args.rejudge), args.draw, args.instances, args.seeds)
            if truth
            else None
        )
        rejudge(args.rejudge, args.workers, chosen, truth, solids)
        return
    known = available_explorers()
    explorers = args.explorer or [e for e in ("stepper", "mujoco") if e in known]
    levels = [int(v) for v in args.levels.split(",") if v]
    todo = jobs(
        args.instances,
        args.seeds,
        levels,
        explorers,
        set(args.family) or None,
        not args.no_real,
        args.draw,
    )
    # In a shuffled order, an interrupted run's log is a fair sample of the whole.
    order = np.random.default_rng(0).permutation(len(todo))
    todo = [dataclasses.replace(todo[int(k)], settings=chosen) for k in order]
    if args.reverse:
        todo.reverse()
    index_file = index = None
    if args.records:
        args.records.mkdir(parents=True, exist_ok=True)
        todo = [dataclasses.replace(j, records=args.records) for j in todo]
        index_file = (args.records / INDEX).open("w", newline="")
        index = csv.DictWriter(index_file, FIELDS)
        index.writeheader()
    t0 = time.perf_counter()
    results: list[Outcome] = []
    log = args.log.open("w", newline="") if args.log else None
    writer = csv.DictWriter(log, FIELDS) if log else None
    if writer:
        writer.writeheader()

    def progress(o: Outcome) -> None:
        results.append(o)
        if log and writer:
            writer.writerow({f: getattr(o, f) for f in FIELDS})
            log.flush()
        if index_file and index:
            index.writerow({f: getattr(o, f) for f in FIELDS})
            index_file.flush()
        print(
            f"[{len(results)}/{len(todo)}] {o.seconds:6.2f} s  {o.explorer} {o.group} {o.rules} "
            f"noise {o.noise:g} {o.name}: {o.got[:60]}",
            file=sys.stderr,
            flush=True,
        )

    try:
        if args.workers > 1:
            with multiprocessing.get_context("fork").Pool(args.workers) as pool:
                for o in pool.imap_unordered(run_job, todo, chunksize=1):
                    progress(o)
        else:
            for j in todo:
                progress(run_job(j))
    finally:
        if log:
            log.close()
        if index_file:
            index_file.close()
    summary(results)
    print(f"{len(results)} classifications in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
