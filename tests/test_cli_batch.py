"""``tactile-kb batch``: inputs, summary, report, exit codes, kills and --resume, Dask."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tactile_kb.cli import main
from tactile_kb.solids import box, prism, tetrahedron

LABELS = {"cube": "cube", "brick": "rectangular_parallelepiped", "tetra": "tetrahedron"}


@pytest.fixture(scope="module")
def objects(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("objects")
    (root / "sub").mkdir()
    box(0.06, 0.06, 0.06).export(root / "cube.stl")
    box(0.10, 0.06, 0.04).export(root / "sub" / "brick.stl")
    tetrahedron(0.08).export(root / "sub" / "tetra.stl")
    (root / "labels.csv").write_text(
        "path,label\ncube.stl,cube\nsub/brick.stl,rectangular_parallelepiped\n"
        "sub/tetra.stl,tetrahedron\nsub/gone.stl,cube\n"
    )
    return root


def _rows(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_batch_manifest_summary_and_report(
    objects: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out, report = tmp_path / "r.jsonl", tmp_path / "report.md"
    code = main(
        [
            "batch",
            str(objects / "labels.csv"),
            "--out",
            str(out),
            "--rules",
            "polyhedra",
            "--workers",
            "2",
            "--seeds",
            "0-1",
            "--report",
            str(report),
        ]
    )
    captured = capsys.readouterr()
    assert code == 1  # one object could not be classified
    gone = objects / "sub" / "gone.stl"
    # No progress bar when stderr is not a terminal: only the error lines.
    assert sorted(captured.err.splitlines()) == [
        f"tactile-kb: error: {gone}: no such file (seed {seed}, ObjectError)" for seed in (0, 1)
    ]
    lines = captured.out.splitlines()
    assert lines[0] == "8 results: 6 answered, 2 failed"
    assert lines[-2:] == [f"results: {out}", f"report: {report}"]
    assert lines[-3].split() == ["all", "6", "of", "8", "75.0", "%"]
    rows = _rows(out)
    assert [(Path(r["object"]).stem, r["seed"]) for r in rows] == [
        (stem, seed) for stem in ("cube", "brick", "tetra", "gone") for seed in (0, 1)
    ]
    assert all(r.get("label") == LABELS.get(Path(r["object"]).stem) for r in rows[:6])
    assert "![confusion matrix](report-confusion.png)" in report.read_text()
    assert (tmp_path / "report-confusion.png").stat().st_size > 1000


def test_batch_folder_and_glob(
    objects: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    code = main(
        ["batch", str(objects / "sub"), str(objects / "*.stl"), "--out", str(out), "--workers", "1"]
    )
    assert code == 0
    assert [Path(r["object"]).name for r in _rows(out)] == ["brick.stl", "tetra.stl", "cube.stl"]
    assert [" ".join(x.split()) for x in capsys.readouterr().out.splitlines()[:5]] == [
        "3 results: 3 answered, 0 failed",
        "answers:",
        "OBJECT IS A CUBE 1",
        "OBJECT IS A RECTANGULAR PARALLELEPIPED 1",
        "OBJECT IS NOT A HEXAHEDRON 1",
    ]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--out", "{tmp}/missing/r.jsonl"], "--out {tmp}/missing/r.jsonl: directory "),
        (["--out", "{tmp}"], "--out {tmp}: is a directory"),
        (["--out", "{tmp}/r.jsonl", "--report", "{tmp}/r.pdf"], "--report {tmp}/r.pdf: the file"),
        (["--out", "{tmp}/r.jsonl", "--ship"], "--ship sends meshes to Dask workers"),
        (["--out", "{tmp}/r.jsonl", "--workers", "0"], "argument --workers: must be ≥ 1"),
        (["--out", "{tmp}/r.jsonl", "--seeds", "3-1"], "a range must go up"),
        (["--out", "{tmp}/r.jsonl", "--timeout", "0"], "argument --timeout: must be > 0"),
        (["--out", "{tmp}/r.jsonl", "--rules", "nope"], "nope"),
        (["--out", "{tmp}/r.jsonl", "--finger", "7"], "unknown finger '7'"),
    ],
)
def test_bad_arguments_are_refused_before_any_work(
    objects: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    argv: list[str],
    message: str,
) -> None:
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(["batch", str(objects / "cube.stl"), *args]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1
    assert message.replace("{tmp}", str(tmp_path)) in err
    assert list(tmp_path.iterdir()) == []


def test_existing_results_need_resume_or_overwrite(
    objects: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.jsonl"
    out.write_text("precious\n")
    assert main(["batch", str(objects / "cube.stl"), "--out", str(out)]) == 2
    assert "add --resume to continue them or --overwrite" in capsys.readouterr().err
    assert out.read_text() == "precious\n"
    assert main(["batch", str(objects / "cube.stl"), "--out", str(out), "--overwrite"]) == 0
    assert [r["label"] for r in _rows(out)] == ["cube"]


def test_a_bad_manifest_is_located(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    manifest = tmp_path / "m.csv"
    manifest.write_text("path,label,seeds\na.stl,cube,0-2\nb.stl,cube,two\n")
    assert main(["batch", str(manifest), "--out", str(tmp_path / "r.jsonl")]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [
        f"{manifest}:3:1: seeds: seeds 'two': expected whole numbers ≥ 0 like 0-9 or 0,3,5"
    ]
    assert not (tmp_path / "r.jsonl").exists()


def _wait_for_lines(path: Path, count: int, proc: subprocess.Popen[bytes]) -> list[str]:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if path.exists():
            lines = [x for x in path.read_text().splitlines() if x.endswith("}")]
            if len(lines) >= count:
                return lines
        assert proc.poll() is None, "the batch ended before it could be killed"
        time.sleep(0.05)
    raise AssertionError(f"fewer than {count} rows after 120 s")


def test_kill_a_worker_then_the_batch_then_resume(tmp_path: Path) -> None:
    """Every (object, seed) ends up exactly once, answered, after two kills and a resume."""
    expected = {}
    for i in range(3):
        box(0.05 + 0.01 * i, 0.06, 0.06).export(tmp_path / f"box{i}.stl")
        expected[f"box{i}"] = "cube" if i == 1 else "rectangular_parallelepiped"
        prism(5 + i % 2, 0.04, 0.05).export(tmp_path / f"prism{i}.stl")
        expected[f"prism{i}"] = "prism"
    out = tmp_path / "r.jsonl"
    argv = ["batch", str(tmp_path), "--out", str(out), "--rules", "polyhedra", "--workers", "2"]
    run = "import sys; from tactile_kb.cli import main; sys.exit(main(sys.argv[1:]))"
    cmd = [sys.executable, "-c", run, *argv, "--seeds", "0-1"]
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        first = _wait_for_lines(out, 2, proc)
        os.kill(int(json.loads(first[-1])["worker"].rsplit(":", 1)[1]), signal.SIGKILL)
        _wait_for_lines(out, 5, proc)
    finally:
        with contextlib.suppress(ProcessLookupError):  # the driver, fork server and workers
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    with out.open("ab") as handle:  # as if killed while writing a line
        handle.write(b'{"index": 3, "seed": 1, "object": "')
    written = len(out.read_text().splitlines()) - 1
    assert 5 <= written < 12

    code = main([*argv, "--seeds", "0-1", "--resume"])
    rows = _rows(out)
    assert code == 0
    assert [r["index"] for r in rows] == list(range(12))
    assert Counter((r["object"], r["seed"]) for r in rows) == Counter(
        {
            (str(tmp_path / f"{kind}{i}.stl"), s): 1
            for kind in ("box", "prism")
            for i in range(3)
            for s in (0, 1)
        }
    )
    assert not any("error" in r for r in rows)
    assert all(r["label"] == expected[Path(r["object"]).stem] for r in rows)


@pytest.fixture(scope="module")
def scheduler() -> Iterator[str]:
    distributed = pytest.importorskip("distributed")  # the dask extra, installed by `make test`
    with distributed.LocalCluster(
        host="127.0.0.1",
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
    ) as cluster:
        yield cluster.scheduler_address


def test_batch_on_a_dask_scheduler_with_ship(
    objects: Path, tmp_path: Path, scheduler: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r.parquet"
    pytest.importorskip("pyarrow")
    argv = ["batch", str(objects / "labels.csv"), "--out", str(out), "--scheduler", scheduler]
    assert main([*argv, "--ship", "--rules", "polyhedra"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "4 results: 3 answered, 1 failed"
    from tactile_kb.batch import read_results

    rows = list(read_results(out))
    assert [r.get("label") for r in rows] == [*LABELS.values(), None]
    assert rows[3]["error"]["kind"] == "ObjectError"
    assert all(r["correct"] == (i < 3) for i, r in enumerate(rows))


def test_settings_reach_the_workers_and_key_the_rows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import math

    import numpy as np

    lean = box(0.08, 0.06, 0.05)
    shear = np.eye(4)
    shear[0, 2] = math.tan(math.radians(3.0))  # square within 5°, not within 1°
    lean.apply_transform(shear)
    lean.export(tmp_path / "lean.stl")
    out = tmp_path / "r.jsonl"
    args = ["batch", str(tmp_path / "lean.stl"), "--out", str(out), "--workers", "2"]
    assert main(args) == 0
    strict = ["--set", "features.tolerance_deg=1", "--set", "features.sigmas=0"]
    assert main([*args, "--resume", *strict]) == 0  # other settings: not the same task
    capsys.readouterr()
    labels = sorted(r["label"] for r in _rows(out))
    assert labels == ["nonrectangular_parallelepiped", "rectangular_parallelepiped"]
    assert main([*args, "--resume", *strict]) == 0  # now done: nothing more
    assert len(_rows(out)) == 2
