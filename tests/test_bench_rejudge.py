"""``benchmarks/bench_real.py --records DIR`` and ``--rejudge DIR`` (issue 10).

A saved exploration record holds everything the decision needs: classified again with the
same code, every answer is the one given when it was explored. An answer the index says was
different shows as changed, and a directory without an index, or with a file that is none, is
refused in one line.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import bench_real


@pytest.fixture(scope="module")
def saved(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("records")
    args = ["--explorer", "stepper", "--no-real", "--family", "cube", "--levels", "1"]
    bench_real.main([*args, "--workers", "1", "--records", str(folder)])
    return folder


def _index(folder: Path) -> list[dict[str, str]]:
    with (folder / bench_real.INDEX).open(newline="") as f:
        return list(csv.DictReader(f))


def test_every_case_is_saved_and_named_in_the_index(saved: Path) -> None:
    rows = _index(saved)
    # the cube's ideal solid and its level-1 scan, under both rule files, exact and noisy
    assert len(rows) == 8
    assert {r["group"] for r in rows} == {"ideal", "level 1"}
    names = {
        bench_real.record_name(r["explorer"], r["group"], r["name"], r["rules"], float(r["noise"]))
        for r in rows
    }
    assert names == {p.name for p in saved.glob("*.json")}


def test_the_same_code_gives_every_answer_again(
    saved: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bench_real.main(["--rejudge", str(saved), "--workers", "1"])
    out = capsys.readouterr().out
    assert "0 answer(s) changed" in out
    assert "8 records classified again" in out


def test_an_answer_the_index_holds_otherwise_is_reported_changed(
    saved: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = _index(saved)
    k = next(i for i, r in enumerate(rows) if r["got"] == r["label"])  # one answered right
    rows[k]["got"] = "prism"  # as if it had been answered wrong when explored
    for p in saved.glob("*.json"):
        (tmp_path / p.name).write_bytes(p.read_bytes())
    with (tmp_path / bench_real.INDEX).open("w", newline="") as f:
        w = csv.DictWriter(f, bench_real.FIELDS)
        w.writeheader()
        w.writerows(rows)
    bench_real.main(["--rejudge", str(tmp_path), "--workers", "1"])
    out = capsys.readouterr().out
    assert "1 answer(s) changed:" in out
    assert f"gained: [stepper {rows[k]['group']} {rows[k]['rules']}" in out
    assert f"was prism, now {rows[k]['label']}" in out


def test_a_folder_without_an_index_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--rejudge", str(tmp_path)])
    assert str(err.value) == (
        f"{tmp_path / 'index.csv'}: no such file (save records with --records {tmp_path})"
    )


def test_a_file_that_is_no_index_is_refused_in_one_line(tmp_path: Path) -> None:
    (tmp_path / bench_real.INDEX).write_text("explorer,group,name\nstepper,ideal,cube\n")
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--rejudge", str(tmp_path)])
    assert str(err.value) == (
        f"{tmp_path / 'index.csv'}:1: not an index of --records (no column 'rules')"
    )
