"""tactile_kb.batch: inputs, local workers, faults, resume, Dask, summaries.

Ground truth: the objects are built here (tactile_kb.solids) with the label their construction
gives them (a box with equal sides is a cube, a three-sided pyramid a tetrahedron); the
summary is checked against counts enumerated from those labels.
"""

from __future__ import annotations

import json
import os
import signal
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tactile_kb.batch import (
    BatchItem,
    BatchSummary,
    classify_many,
    expand_inputs,
    parse_seeds,
    read_results,
    run_batch,
)
from tactile_kb.errors import SourceError, UsageError
from tactile_kb.solids import box, prism, sphere, tetrahedron

# name → (mesh, label under the polyhedra rules, known from the construction)
SOLIDS = {
    "cube": (box(0.06, 0.06, 0.06), "cube"),
    "brick": (box(0.10, 0.06, 0.04), "rectangular_parallelepiped"),
    "tetra": (tetrahedron(0.08), "tetrahedron"),
    "prism5": (prism(5, 0.04, 0.05), "prism"),
}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four solids in a folder tree, with a corrupt file between them and a non-mesh file."""
    root = tmp_path_factory.mktemp("dataset")
    (root / "a").mkdir()
    (root / "b" / "deep").mkdir(parents=True)
    SOLIDS["cube"][0].export(root / "a" / "cube.stl")
    SOLIDS["brick"][0].export(root / "a" / "brick.stl")
    SOLIDS["tetra"][0].export(root / "b" / "deep" / "tetra.stl")
    SOLIDS["prism5"][0].export(root / "b" / "prism5.stl")
    (root / "b" / "corrupt.stl").write_bytes(b"solid nothing\nfacet oops\n")
    (root / "b" / "notes.txt").write_text("not a mesh\n")
    return root


def _manifest(root: Path, name: str = "labels.csv", corrupt: bool = True) -> Path:
    rows = ["path,label"]
    for sub, stem in (("a", "cube"), ("a", "brick"), ("b", "corrupt"), ("b/deep", "tetra")):
        if stem == "corrupt" and not corrupt:
            continue
        label = SOLIDS[stem][1] if stem in SOLIDS else "cube"
        rows.append(f"{sub}/{stem}.stl,{label}")
    rows.append(f"b/prism5.stl,{SOLIDS['prism5'][1]}")
    path = root / name
    path.write_text("\n".join(rows) + "\n")
    return path


def _by_index(rows: Iterator[dict[str, Any]] | list[dict[str, Any]]) -> dict[int, dict[str, Any]]:
    out: dict[int, dict[str, Any]] = {}
    for row in rows:
        assert row["index"] not in out, f"index {row['index']} twice"
        out[row["index"]] = row
    return out


# --- inputs -------------------------------------------------------------------------------------


def test_parse_seeds() -> None:
    assert parse_seeds("0-9") == tuple(range(10))
    assert parse_seeds("4") == (4,)
    assert parse_seeds("3, 0-1,3") == (3, 0, 1)
    for bad in ("", "a", "-1", "2-1", "1-x"):
        with pytest.raises(UsageError, match="seeds"):
            parse_seeds(bad)


def test_folder_glob_and_manifest_expansion(dataset: Path) -> None:
    meshes = sorted(str(p) for p in dataset.rglob("*.stl"))
    assert sorted(i.path for i in expand_inputs([dataset])) == meshes  # notes.txt left out
    items = expand_inputs([str(dataset / "b" / "**" / "*.stl")])
    assert [Path(i.path).name for i in items] == ["corrupt.stl", "tetra.stl", "prism5.stl"]
    manifest = _manifest(dataset)
    items = expand_inputs([manifest])
    assert [(Path(i.path).name, i.label) for i in items] == [
        ("cube.stl", "cube"),
        ("brick.stl", "rectangular_parallelepiped"),
        ("corrupt.stl", "cube"),
        ("tetra.stl", "tetrahedron"),
        ("prism5.stl", "prism"),
    ]
    assert all(Path(i.path).is_file() for i in items)  # relative to the manifest's folder
    # The same object named twice is one object; a missing file is kept (its row is an error).
    twice = expand_inputs([dataset / "a" / "cube.stl", str(dataset / "a" / "cube.stl"), "nope.stl"])
    assert [i.path for i in twice] == [str(dataset / "a" / "cube.stl"), "nope.stl"]


def test_jsonl_manifest_with_row_options(tmp_path: Path) -> None:
    (tmp_path / "m.jsonl").write_text(
        '{"path": "x.stl", "label": "cube", "noise": 0.001, "seeds": "1-2", "finger": "4"}\n'
        "\n"
        '{"path": "y.stl", "timeout": "2.5"}\n'
    )
    first, second = expand_inputs([tmp_path / "m.jsonl"])
    assert first == BatchItem(
        str(tmp_path / "x.stl"), "cube", {"finger": "4", "noise": 0.001, "seeds": (1, 2)}
    )
    assert second == BatchItem(str(tmp_path / "y.stl"), None, {"timeout": 2.5})


def test_manifest_problems_are_located(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("path,label,noise\n,cube,\nok.stl,cube,-1\nok2.stl,,x\n")
    with pytest.raises(SourceError) as info:
        expand_inputs([bad])
    assert [str(p) for p in info.value.problems] == [
        f"{bad}:2:1: path: no path given",
        f"{bad}:3:1: noise: must be a finite number ≥ 0, got '-1'",
        f"{bad}:4:1: noise: not a number: 'x'",
    ]
    typo = tmp_path / "typo.jsonl"
    typo.write_text('{"path": "a.stl", "lable": "cube"}\n[1]\n')
    with pytest.raises(SourceError) as info:
        expand_inputs([typo])
    assert [str(p) for p in info.value.problems] == [
        f"{typo}:1:1: unknown column 'lable' (known: path, label, rules, explorer, finger, "
        "noise, seeds, timeout)",
        f"{typo}:2:1: not a JSON object",
    ]


def test_empty_folder_and_unmatched_glob_are_refused(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="no mesh files"):
        expand_inputs([tmp_path])
    with pytest.raises(UsageError, match="no file matches"):
        expand_inputs([str(tmp_path / "*.stl")])


# --- local workers ------------------------------------------------------------------------------


def test_batch_with_labels_corrupt_file_and_missing_path(dataset: Path, tmp_path: Path) -> None:
    manifest = _manifest(dataset)
    with manifest.open("a") as handle:
        handle.write("a/missing.stl,cube\n")
    out = tmp_path / "results.jsonl"
    seen: list[dict[str, Any]] = []
    summary = run_batch(
        [manifest], out, rules="polyhedra", seeds=(0, 1), workers=2, on_row=seen.append
    )
    rows = list(read_results(out))
    assert [r["index"] for r in rows] == list(range(12))  # sorted, each (object, seed) once
    assert sorted(r["index"] for r in seen) == list(range(12))  # streamed as they finished
    assert [(Path(r["object"]).stem, r["seed"]) for r in rows] == [
        (stem, seed)
        for stem in ("cube", "brick", "corrupt", "tetra", "prism5", "missing")
        for seed in (0, 1)
    ]
    for row in rows:
        stem = Path(row["object"]).stem
        if stem in SOLIDS:
            assert row["label"] == SOLIDS[stem][1] == row["expected"]
            assert row["correct"] is True
            assert {"answer", "bits", "propositions", "explanation", "measures"} <= set(row)
            assert row["options"] == {
                "rules": "polyhedra",
                "explorer": "stepper",
                "finger": "33",
                "noise": 0.0,
            }
        else:
            assert row["correct"] is False
            assert row["error"]["kind"] == "ObjectError"
            assert row["error"]["message"].startswith(row["object"])
            assert "answer" not in row
    missing = rows[-1]["error"]["message"]
    assert missing == f"{dataset / 'a' / 'missing.stl'}: no such file"
    assert summary.rows == 12
    assert summary.errors == Counter({"ObjectError": 4})
    assert summary.accuracy() == {
        "cube": (2, 6),  # the corrupt file and the missing one were labelled cube
        "prism": (2, 2),
        "rectangular_parallelepiped": (2, 2),
        "tetrahedron": (2, 2),
    }
    assert summary.confusion[("cube", "error")] == 4
    lines = summary.lines()
    assert lines[0] == "12 results: 8 answered, 4 failed"
    assert "  ObjectError       4" in lines
    assert lines[-1].split() == ["all", "8", "of", "12", "66.7", "%"]


def test_same_seeds_same_answers_on_one_or_two_workers(dataset: Path) -> None:
    inputs = [dataset / "a", dataset / "b" / "prism5.stl"]
    options: dict[str, Any] = {"rules": "polyhedra", "seeds": (3, 7), "noise": 0.0005}
    one = _by_index(classify_many(inputs, workers=1, **options))
    two = _by_index(classify_many(inputs, workers=2, **options))
    assert sorted(one) == sorted(two) == list(range(6))
    keys = ("object", "seed", "answer", "label", "bits", "contacts", "planes", "measures", "key")
    for index in one:
        assert {k: one[index][k] for k in keys} == {k: two[index][k] for k in keys}
    # With noise, the seeds explore differently: the rows are not copies of each other.
    assert one[0]["path_length"] != one[1]["path_length"]


def kill_once_then_classify(task: dict[str, Any]) -> dict[str, Any]:
    """Batch work for the fault test, run in the worker: the first time it meets prism5.stl
    with seed 0 it kills its own process (SIGKILL, as the OOM killer would), leaving a marker
    beside the mesh; then, and for every other task, it classifies as the batch does."""
    from tactile_kb.batch import run_task

    marker = Path(task["object"] + ".killed")
    if task["object"].endswith("prism5.stl") and task["seed"] == 0 and not marker.exists():
        marker.touch()
        os.kill(os.getpid(), signal.SIGKILL)
    return run_task(task)


def test_a_killed_worker_is_an_error_row_and_resume_redoes_it(
    dataset: Path, tmp_path: Path
) -> None:
    # a copy of the objects, so that the kill's marker stays out of the shared folder
    (tmp_path / "a").mkdir()
    for name in ("a/brick.stl", "a/cube.stl", "b/prism5.stl"):
        (tmp_path / "a" / Path(name).name).write_bytes((dataset / name).read_bytes())
    out = tmp_path / "r.jsonl"
    work = f"{__name__}:kill_once_then_classify"
    inputs = [tmp_path / "a"]  # brick, cube, prism5; seeds 0 and 1: six tasks
    summary = run_batch(inputs, out, rules="polyhedra", seeds=(0, 1), workers=2, _work=work)
    assert (tmp_path / "a" / "prism5.stl.killed").exists()
    rows = list(read_results(out))
    assert len(rows) == 6
    lost = [r for r in rows if "error" in r]
    assert [(r["error"]["kind"], r["object"][-10:], r["seed"]) for r in lost] == [
        ("WorkerLost", "prism5.stl", 0)
    ]
    assert "the worker process ended while classifying it" in lost[0]["error"]["message"]
    assert "killed by signal 9" in lost[0]["error"]["message"]
    assert summary.errors == Counter({"WorkerLost": 1})
    # Resume: the lost task is run again, the others are not; every task is there once.
    again: list[dict[str, Any]] = []
    summary = run_batch(
        inputs,
        out,
        resume=True,
        rules="polyhedra",
        seeds=(0, 1),
        workers=2,
        on_row=again.append,
        _work=work,
    )
    assert [r["index"] for r in again] == [lost[0]["index"]]
    rows = list(read_results(out))
    assert [r["index"] for r in rows] == list(range(6))
    assert not any("error" in r for r in rows)
    assert summary.rows == 6
    assert not summary.errors


def test_resume_after_a_kill_mid_line(dataset: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.jsonl"
    inputs = [dataset / "a"]  # brick.stl, cube.stl
    run_batch(inputs, out, rules="polyhedra", seeds=(0, 1), workers=2)
    lines = out.read_bytes().splitlines(keepends=True)
    # A batch killed after two rows and halfway through writing a third:
    out.write_bytes(lines[3] + lines[0] + lines[2][: len(lines[2]) // 2])
    ran: list[dict[str, Any]] = []
    run_batch(
        inputs, out, resume=True, rules="polyhedra", seeds=(0, 1), workers=2, on_row=ran.append
    )
    assert sorted(r["index"] for r in ran) == [1, 2]
    rows = list(read_results(out))
    assert [(r["index"], r["label"]) for r in rows] == [
        (0, "rectangular_parallelepiped"),
        (1, "rectangular_parallelepiped"),
        (2, "cube"),
        (3, "cube"),
    ]
    again = run_batch(inputs, out, resume=True, rules="polyhedra", seeds=(0, 1), workers=1)
    assert again.rows == 4  # nothing left to do, the summary covers the whole file


def test_a_changed_file_is_classified_again_on_resume(tmp_path: Path) -> None:
    mesh = tmp_path / "obj.stl"
    box(0.06, 0.06, 0.06).export(mesh)
    out = tmp_path / "r.jsonl"
    run_batch([mesh], out, workers=1)
    box(0.10, 0.06, 0.04).export(mesh)  # same name, other content
    ran: list[dict[str, Any]] = []
    run_batch([mesh], out, resume=True, workers=1, on_row=ran.append)
    assert [r["label"] for r in ran] == ["rectangular_parallelepiped"]
    labels = [r["label"] for r in read_results(out)]
    assert labels == ["rectangular_parallelepiped", "cube"]  # the old row is kept after


def test_timeout_stops_one_object_and_the_batch_goes_on(tmp_path: Path) -> None:
    sphere(0.05).export(tmp_path / "ball.stl")  # about a second to classify
    box(0.06, 0.06, 0.06).export(tmp_path / "cube.stl")
    (tmp_path / "m.csv").write_text("path,timeout\nball.stl,0.3\ncube.stl,\n")
    rows = _by_index(classify_many([tmp_path / "m.csv"], workers=1, timeout=60))
    assert rows[0]["error"] == {
        "kind": "Timeout",
        "message": f"{tmp_path / 'ball.stl'}: not classified within 0.3 s (the worker was stopped)",
    }
    assert 0.3 <= rows[0]["task_seconds"] < 5
    assert rows[1]["label"] == "cube"


def test_unwritable_output_is_refused_before_any_work(dataset: Path, tmp_path: Path) -> None:
    ran: list[dict[str, Any]] = []
    blocker = tmp_path / "file"
    blocker.write_text("")
    for out, message in (
        (tmp_path / "no" / "r.jsonl", "does not exist"),
        (tmp_path, "is a directory"),
        (blocker / "r.jsonl", "does not exist"),
    ):
        with pytest.raises(UsageError, match=message):
            run_batch([dataset / "a"], out, on_row=ran.append)
    existing = tmp_path / "old.jsonl"
    existing.write_text('{"key": "x"}\n')
    with pytest.raises(UsageError, match="add --resume"):
        run_batch([dataset / "a"], existing, on_row=ran.append)
    assert not ran
    assert existing.read_text() == '{"key": "x"}\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "old.jsonl"]


def test_parquet_results(dataset: Path, tmp_path: Path) -> None:
    pytest.importorskip("pyarrow")  # the parquet extra, installed by `make test`
    out = tmp_path / "r.parquet"
    run_batch([_manifest(dataset)], out, rules="polyhedra", workers=2)
    rows = list(read_results(out))
    assert [r["index"] for r in rows] == list(range(5))
    stream = list(read_results(tmp_path / "r.parquet.jsonl"))  # beside it, in finishing order
    assert rows == sorted(stream, key=lambda r: r["index"])
    assert rows[2]["error"]["kind"] == "ObjectError"
    assert rows[3]["propositions"]["A"] is True


def test_summary_report_files(tmp_path: Path) -> None:
    summary = BatchSummary()
    for expected, label in [("cube", "cube")] * 3 + [("cube", "prism"), ("prism", "prism")]:
        summary.add(
            {"label": label, "answer": f"OBJECT IS A {label.upper()}", "expected": expected}
        )
    summary.add({"error": {"kind": "Timeout", "message": "x"}, "expected": "prism"})
    assert summary.classes() == (["cube", "prism"], ["cube", "prism", "error"])
    assert summary.accuracy() == {"cube": (3, 4), "prism": (1, 2)}
    summary.write_report(tmp_path / "report.md")
    text = (tmp_path / "report.md").read_text()
    assert "![confusion matrix](report-confusion.png)" in text
    assert (tmp_path / "report-confusion.png").read_bytes()[:4] == b"\x89PNG"
    (tmp_path / "web").mkdir()
    summary.write_report(tmp_path / "web" / "report.html")
    page = (tmp_path / "web" / "report.html").read_text()
    assert 'src="data:image/png;base64,' in page
    assert "  cube         3      1      0" in page
    assert [p.name for p in (tmp_path / "web").iterdir()] == ["report.html"]  # embedded


# --- Dask ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    distributed = pytest.importorskip("distributed")  # the dask extra, installed by `make test`
    with (
        distributed.LocalCluster(
            host="127.0.0.1",
            n_workers=2,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
        ) as cluster,
        distributed.Client(cluster) as c,
    ):
        yield c


def test_dask_gives_the_local_answers(dataset: Path, client: Any) -> None:
    manifest = _manifest(dataset, "dask.csv")
    options: dict[str, Any] = {"rules": "polyhedra", "seeds": (2,), "noise": 0.0005}
    local = _by_index(classify_many([manifest], workers=2, **options))
    dask = _by_index(classify_many([manifest], client=client, in_flight=2, **options))
    shipped = _by_index(classify_many([manifest], client=client, ship=True, **options))
    assert sorted(dask) == sorted(shipped) == sorted(local) == list(range(5))
    for index, row in local.items():
        for other in (dask[index], shipped[index]):
            assert other["object"] == row["object"]
            assert other.get("bits") == row.get("bits")
            assert other.get("correct") == row.get("correct")
            assert other.get("error") == row.get("error")
    assert {r["worker"] for r in dask.values()}.isdisjoint(r["worker"] for r in local.values())


def test_dask_timeout_and_resume_to_a_file(tmp_path: Path, client: Any) -> None:
    sphere(0.05).export(tmp_path / "ball.stl")
    box(0.06, 0.06, 0.06).export(tmp_path / "cube.stl")
    out = tmp_path / "r.jsonl"
    (tmp_path / "m.csv").write_text("path,timeout,label\nball.stl,0.3,curved\ncube.stl,,cube\n")
    summary = run_batch([tmp_path / "m.csv"], out, client=client, rules="polyhedra")
    rows = list(read_results(out))
    assert rows[0]["error"]["kind"] == "Timeout"
    assert rows[1]["label"] == "cube"
    assert summary.accuracy() == {"cube": (1, 1), "curved": (0, 1)}
    ran: list[dict[str, Any]] = []
    run_batch(
        [tmp_path / "m.csv"], out, resume=True, client=client, on_row=ran.append, rules="polyhedra"
    )
    assert ran == []
    assert [json.loads(line)["index"] for line in out.read_text().splitlines()] == [0, 1]


def test_problems_raise_at_the_call_and_overwrite_waits_for_them(
    dataset: Path, tmp_path: Path
) -> None:
    with pytest.raises(UsageError, match="nope"):
        classify_many([dataset / "a"], rules="nope")  # raised before any row is asked for
    with pytest.raises(UsageError, match="workers must be ≥ 1"):
        classify_many([dataset / "a"], workers=0)
    out = tmp_path / "r.jsonl"
    out.write_text('{"key": "x"}\n')
    with pytest.raises(UsageError, match="no file matches"):
        run_batch([str(tmp_path / "nothing-*.stl")], out, overwrite=True)
    assert out.read_text() == '{"key": "x"}\n'  # the old results are kept


def test_a_dask_worker_killed_mid_batch_loses_nothing(dataset: Path, client: Any) -> None:
    """Dask moves the tasks of a dead worker to the other one: every row is an answer."""
    killed: list[str] = []

    def kill_first_worker(row: dict[str, Any]) -> None:
        if not killed:
            killed.append(row["worker"])
            os.kill(int(row["worker"].rsplit(":", 1)[1]), signal.SIGKILL)

    rows = []
    for row in classify_many(
        [dataset / "a", dataset / "b" / "prism5.stl"],
        rules="polyhedra",
        seeds=(0, 1),
        client=client,
        in_flight=6,
    ):
        kill_first_worker(row)
        rows.append(row)
    assert sorted(r["index"] for r in rows) == list(range(6))
    assert not any("error" in r for r in rows)
    client.wait_for_workers(2, timeout=60)  # the nanny restarts it for the tests after
