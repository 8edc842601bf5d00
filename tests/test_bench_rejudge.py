"""``benchmarks/bench_real.py --records DIR``, ``--rejudge DIR`` and ``--faces DIR`` (issue 10).

A saved exploration record holds everything the decision needs: classified again with the
same code, every answer is the one given when it was explored. An answer the index says was
different shows as changed, and a directory without an index, or with a file that is none, is
refused in one line. ``--faces`` matches each model's faces to the planes of the solid
explored: the matching is checked here on faces constructed from a box's planes, where every
extra, missing and tilted face is known.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import bench_real

from tactile_kb import solids


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


def test_rejudged_under_other_settings_the_answers_follow_them(
    saved: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--set``: with right angles allowed no tolerance at all (1e-6°, no σ widening), only
    the exact ideal cube's faces, fitted from exact tip centres, still meet at right angles:
    every record of a scan or under noise loses its "cube", the exact ideal one keeps it. The
    settings are printed under the versions line."""
    sets = ["--set", "features.tolerance_deg=0.000001", "--set", "features.sigmas=0"]
    bench_real.main(["--rejudge", str(saved), "--workers", "1", *sets])
    out = capsys.readouterr().out
    assert "settings: --set features.tolerance_deg=0.000001 --set features.sigmas=0" in out
    rows = _index(saved)
    assert all(r["got"] == r["label"] for r in rows)  # as explored, with the defaults
    exact_ideal = [r for r in rows if r["group"] == "ideal" and float(r["noise"]) == 0.0]
    assert len(exact_ideal) == 2  # under both rule files
    assert f"{len(rows) - len(exact_ideal)} answer(s) changed:" in out
    for r in rows:
        line = f"lost: [stepper {r['group']} {r['rules']} noise {float(r['noise']):g}]"
        assert (line in out) == (r not in exact_ideal), line


@pytest.mark.parametrize(
    ("given", "message"),
    [
        (["--set", "geometry.nosuch=1"], "--set geometry.nosuch=1: geometry.nosuch: Extra inputs"),
        (
            ["--set", "geometry.edge_rounding=-1"],
            "--set geometry.edge_rounding=-1: geometry.edge_rounding: Input should be greater",
        ),
        (["--set", "edge_rounding"], "--set 'edge_rounding': expected GROUP.FIELD=VALUE"),
    ],
)
def test_a_bad_setting_is_refused_in_one_line(saved: Path, given: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--rejudge", str(saved), *given])
    assert str(err.value).startswith(message)
    assert "\n" not in str(err.value)


def test_a_missing_settings_file_is_refused_in_one_line(saved: Path, tmp_path: Path) -> None:
    missing = tmp_path / "none.toml"
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--rejudge", str(saved), "--settings", str(missing)])
    assert str(err.value).startswith(f"{missing}: cannot read the settings file")


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


def _box_planes() -> tuple[np.ndarray, np.ndarray]:
    normals, offsets = bench_real.true_planes(solids.box(0.08, 0.06, 0.05))
    order = np.lexsort(normals.T)  # a fixed order, whatever trimesh's
    return normals[order], offsets[order]


def test_the_planes_of_a_box_are_its_six_faces() -> None:
    normals, offsets = _box_planes()
    assert len(normals) == 6
    # the box stands on the table (z = 0) centred over the origin: offsets a/2, b/2, 0 and c
    got = sorted(zip(map(tuple, np.round(normals, 9) + 0.0), np.round(offsets, 9), strict=True))
    assert got == sorted(
        [
            ((1.0, 0.0, 0.0), 0.04),
            ((-1.0, 0.0, 0.0), 0.04),
            ((0.0, 1.0, 0.0), 0.03),
            ((0.0, -1.0, 0.0), 0.03),
            ((0.0, 0.0, 1.0), 0.05),
            ((0.0, 0.0, -1.0), 0.0),
        ]
    )


def _turned(n: np.ndarray, deg: float) -> np.ndarray:
    """``n`` turned by ``deg`` towards +z (or +x for a vertical normal)."""
    other = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    t = other - (other @ n) * n
    t /= np.linalg.norm(t)
    a = np.radians(deg)
    return np.cos(a) * n + np.sin(a) * t


def test_extra_missing_and_tilted_faces_are_told_apart() -> None:
    planes = _box_planes()
    normals, offsets = planes
    exact = bench_real.check_faces(planes, planes, convex=True, closed=True)
    assert (exact.extra, exact.missing, exact.tilt_deg, exact.kinds) == (0, 0, 0.0, "faces right")
    px = int(np.argmax(normals[:, 0]))
    py = int(np.argmax(normals[:, 1]))
    split = _turned(normals[px], 3.0)  # a second face of +x, 3° off: a split
    edge = (normals[px] + normals[py]) / np.sqrt(2.0)  # between +x and +y: the edge's face
    faces = (np.vstack([normals, split, edge]), np.concatenate([offsets, [0.04, 0.0495]]))
    c = bench_real.check_faces(faces, planes, convex=True, closed=True)
    assert (c.faces, c.extra, c.split, c.edge, c.missing) == (8, 2, 1, 1, 0)
    assert c.tilt_deg == pytest.approx(0.0, abs=1e-9)
    assert c.kinds == "extra"
    # the +y face tilted by 6° and the +x face not touched at all
    tilted = normals.copy()
    tilted[py] = _turned(normals[py], 6.0)
    keep = np.arange(6) != px
    c = bench_real.check_faces((tilted[keep], offsets[keep]), planes, convex=False, closed=False)
    assert (c.extra, c.missing) == (0, 1)
    assert c.tilt_deg == pytest.approx(6.0, abs=1e-6)
    assert c.kinds == "missing tilted concave open"


def test_the_tilts_are_measured_in_the_faces_uncertainties() -> None:
    """``z``: each plane's nearest face's tilt over that face's uncertainty. The +y face
    tilted by 6° with an uncertainty of 2° is 3 of them off; the others, exact, 0. An extra
    face (a split) does not count, and an uncertainty below the floor counts as the floor."""
    planes = _box_planes()
    normals, offsets = planes
    px = int(np.argmax(normals[:, 0]))
    py = int(np.argmax(normals[:, 1]))
    tilted = normals.copy()
    tilted[py] = _turned(normals[py], 6.0)
    split = _turned(normals[px], 3.0)
    faces = (np.vstack([tilted, split]), np.concatenate([offsets, [0.04]]))
    unc = np.full(7, 1.0)
    unc[py] = 2.0
    unc[px] = 1e-9  # an exact face: the floor
    c = bench_real.check_faces(faces, planes, convex=True, closed=True, uncertainty=unc)
    assert len(c.z) == 6  # one per plane, the split left out
    assert sorted(c.z)[-1] == pytest.approx(3.0, abs=1e-6)
    assert sorted(c.z)[:-1] == pytest.approx([0.0] * 5, abs=1e-6)
    # a face 0.5° off with an uncertainty of 1e-9°: counted against the floor, 0.1°
    slight = normals.copy()
    slight[px] = _turned(normals[px], 0.5)
    c = bench_real.check_faces(
        (slight, offsets), planes, convex=True, closed=True, uncertainty=unc[:6]
    )
    assert max(c.z) == pytest.approx(0.5 / bench_real.Z_FLOOR_DEG, abs=1e-6)
    assert bench_real.check_faces(planes, planes, convex=True, closed=True).z == ()


def test_parallel_planes_are_matched_by_their_offsets() -> None:
    # two tops 2 cm apart (an L block's): each model face finds its own, none is extra
    n = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    planes = (n, np.array([0.03, 0.05]))
    c = bench_real.check_faces((n, np.array([0.0502, 0.0299])), planes, convex=True, closed=True)
    assert (c.extra, c.missing) == (0, 0)


def _table_rows(out: str) -> dict[str, list[str]]:
    """The two group rows of ``--faces``'s table (after its header and rule), by group."""
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("group "))
    return {line.split()[0]: line.split()[1:] for line in lines[head + 2 : head + 4]}


def test_the_models_of_saved_records_are_checked_against_their_solids(
    saved: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bench_real.main(["--faces", str(saved), "--workers", "1"])
    out = capsys.readouterr().out
    assert out.startswith("versions: python ")  # the environment first, then the table
    rows = _table_rows(out)
    # the ideal cube, explored under both rule files with exact and noisy contacts: four
    # models, every one with the cube's six planes, none extra, missing, tilted, concave
    assert rows["ideal"][:9] == ["4", "4", "0", "0", "0", "0", "0", "0", "0"]
    assert rows["level"][:2] == ["1", "4"]  # "level 1": the level-1 scans, four cases
    # the tilts in units of the faces' uncertainties: median and 90th percentile, numbers
    z50, z90 = (float(v) for v in rows["ideal"][9:])
    assert 0.0 <= z50 <= z90


def test_records_of_another_draw_are_refused_in_one_line(saved: Path) -> None:
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--faces", str(saved), "--draw", "5"])
    msg = str(err.value)
    assert msg.startswith(f"{saved / 'index.csv'}: ")
    assert "is not a case of --draw 5 --instances 1 --seeds 1 (give the run's)" in msg
    assert "\n" not in msg


def test_a_record_that_cannot_be_read_is_named_not_fatal(
    saved: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for p in saved.iterdir():
        (tmp_path / p.name).write_bytes(p.read_bytes())
    row = next(r for r in _index(saved) if r["group"] == "ideal")
    name = bench_real.record_name(
        row["explorer"], row["group"], row["name"], row["rules"], float(row["noise"])
    )
    (tmp_path / name).write_text("{not json")
    bench_real.main(["--faces", str(tmp_path), "--workers", "1"])
    out = capsys.readouterr().out
    assert "1 record(s) could not be modelled:" in out
    assert f"  [ideal] {row['name']}: RecordError: " in out
    rows = _table_rows(out)
    assert rows["ideal"][:2] == ["3", "3"]  # the other three ideal models, every face right


def test_the_solids_truth_is_put_into_the_records_rejudged(
    saved: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bench_real.main(["--rejudge", str(saved), "--workers", "1", "--truth", "centres,readings"])
    out = capsys.readouterr().out
    assert "truth: readings, centres put into 8 records\n" in out
    # the ideal cube's touches read and lie as an ideal face's: every answer stays right
    assert "stepper  ideal    right 4/4 when explored, 4/4 now" in out
    assert "stepper  level 1  right " in out
    assert "8 records classified again" in out


def test_the_faces_are_matched_with_the_truth_put_in(
    saved: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bench_real.main(["--faces", str(saved), "--workers", "1", "--truth", "roundings"])
    rows = _table_rows(capsys.readouterr().out)
    assert rows["ideal"][:9] == ["4", "4", "0", "0", "0", "0", "0", "0", "0"]
    assert rows["level"][:2] == ["1", "4"]


@pytest.mark.parametrize(
    ("given", "message"),
    [
        (["--truth", "readings"], "--truth readings: give --rejudge DIR or --faces DIR with it"),
        (["--truth", "bumps"], "--truth bumps: no item 'bumps' (choose from roundings, readings"),
    ],
)
def test_a_bad_truth_is_refused_in_one_line(given: list[str], message: str) -> None:
    with pytest.raises(SystemExit) as err:
        bench_real.main(given)
    assert str(err.value).startswith(message)
    assert "\n" not in str(err.value)


def test_truth_from_another_draw_is_refused_in_one_line(saved: Path) -> None:
    with pytest.raises(SystemExit) as err:
        bench_real.main(["--rejudge", str(saved), "--draw", "5", "--truth", "readings"])
    msg = str(err.value)
    assert msg.startswith(f"{saved / 'index.csv'}: ")
    assert "is not a case of --draw 5 --instances 1 --seeds 1 (give the run's)" in msg
