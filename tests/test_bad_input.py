"""Every bad input of issue 12 ends in one located line and exit 1 or 2, in bounded time and
memory, and the other files of the run are still processed.

The cases that once ran without bound or crashed the interpreter (an alias bomb, a file nested
30 000 deep, /dev/zero, a named pipe) run the CLI in a subprocess with a time limit and an
address-space limit, so that a regression fails the test instead of taking pytest down.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tactile_kb.cli import main
from tactile_kb.errors import LayoutFileError, RecordError, RuleFileError, SourceError
from tactile_kb.files import InputFileError, atomic_write, read_text
from tactile_kb.kb.rules import load_rules, parse_rules
from tactile_kb.record import ExplorationRecord
from tactile_kb.solids import box
from tactile_kb.touch.finger import load_layout
from tactile_kb.yaml_source import MAX_DEPTH, load_yaml

RULES = Path(__file__).resolve().parents[1] / "rules" / "parallelepipeds.yaml"
MINI = """\
name: mini
propositions:
  - {id: A, text: a}
  - {id: B, text: b}
phases:
  - {id: I, propositions: [A, B]}
classes: [{id: c, answer: C, when: B}]
otherwise: {id: o, answer: O}
"""
BOMB = 'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{','.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8)
)
MEMORY_LIMIT = 3 * 1024**3


def _limits() -> None:  # pragma: no cover - runs in the child
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run_cli(*argv: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """``tactile-kb ARGV`` in a child limited to ``timeout`` seconds and 3 GiB."""
    return subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys; from tactile_kb.cli import main; sys.exit(main())",
            *argv,
        ],
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=_limits,
        check=False,
    )


@pytest.fixture
def good_rules(tmp_path: Path) -> Path:
    path = tmp_path / "good.yaml"
    path.write_text(MINI)
    return path


@pytest.fixture(scope="module")
def record_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from tactile_kb.touch.explorers import get_explorer

    path = tmp_path_factory.mktemp("rec") / "cube.json"
    get_explorer("stepper").explore(box(0.08, 0.08, 0.08), seed=0).save(path)
    return path


def _edit(line_no: int, old: str, new: str) -> tuple[str, int, int]:
    """The packaged rule file with ``old`` on line ``line_no`` replaced; the column of ``old``."""
    lines = RULES.read_text(encoding="utf-8").splitlines()
    column = lines[line_no - 1].index(old) + 1
    lines[line_no - 1] = lines[line_no - 1].replace(old, new, 1)
    return "\n".join(lines) + "\n", line_no, column


# --- the YAML loader -------------------------------------------------------------------------


def test_alias_bomb_is_refused_at_the_first_anchor_in_a_subprocess(
    tmp_path: Path, good_rules: Path
) -> None:
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text(BOMB)
    assert len(BOMB) < 600
    done = run_cli("validate", str(bomb), str(good_rules), timeout=60)
    assert done.returncode == 1
    about_bomb = [line for line in done.stderr.splitlines() if line.startswith(str(bomb))]
    assert about_bomb == [f"{bomb}:1:4: anchors (&a) are not supported"]
    assert done.stdout.startswith(f"{good_rules}: ok:")  # the next file is still checked


def test_alias_bomb_in_a_finger_file(tmp_path: Path) -> None:
    bomb = tmp_path / "finger.yaml"
    bomb.write_text(BOMB)
    stl = tmp_path / "cube.stl"
    box(0.06, 0.06, 0.06).export(stl)
    done = run_cli("classify", str(stl), "--finger", str(bomb), timeout=60)
    assert done.returncode == 1
    assert done.stderr.splitlines() == [f"{bomb}:1:4: anchors (&a) are not supported"]


def test_a_lone_alias_and_a_recursive_one_are_located() -> None:
    with pytest.raises(SourceError) as info:
        load_yaml("a: 1\nb: *x\n", file="t.yaml")
    assert str(info.value).startswith("t.yaml:2:4:")  # libyaml: an undefined alias
    with pytest.raises(SourceError, match=r"^t.yaml:1:4: anchors \(&a\) are not supported$"):
        load_yaml("a: &a [*a]\n", file="t.yaml")


@pytest.mark.parametrize(
    ("text", "where"),
    [
        ("[" * 30000 + "]" * 30000, "1:65"),
        ("- " * 500 + "x\n", "1:129"),
        ("".join(" " * i + f"k{i}:\n" for i in range(1000)) + " " * 1000 + "v\n", "65:65"),
    ],
    ids=["30000-deep-flow", "500-deep-block-list", "1000-deep-mapping"],
)
def test_deep_nesting_is_refused_before_composing(
    text: str, where: str, tmp_path: Path, good_rules: Path
) -> None:
    deep = tmp_path / "deep.yaml"
    deep.write_text(text)
    done = run_cli("validate", str(deep), str(good_rules), timeout=60)
    assert done.returncode == 1, done.stderr
    about_deep = [line for line in done.stderr.splitlines() if line.startswith(str(deep))]
    assert about_deep == [f"{deep}:{where}: nested more than {MAX_DEPTH} levels deep"]
    assert done.stdout.startswith(f"{good_rules}: ok:")


def test_depth_up_to_the_limit_is_accepted() -> None:
    text = "[" * MAX_DEPTH + "]" * MAX_DEPTH
    assert load_yaml(text).data is not None


@pytest.mark.parametrize(
    ("line_no", "old", "new", "where"),
    [
        (45, "one point'", "one point", (45, 11)),  # the quote left open
        (73, "[A]", "[A", (73, 19)),  # the [ left open
        (
            49,
            "{name: parallel_face_pairs, params: {count: 3}}",
            "{name: parallel_face_pairs, params: {count: 3}",
            (49, 14),
        ),
        (26, "description: >", "%bogus\ndescription: >", (26, 1)),  # a stray directive
    ],
    ids=["unclosed-quote", "unclosed-bracket", "unclosed-brace", "stray-directive"],
)
def test_syntax_errors_are_located_at_the_mistake(
    line_no: int, old: str, new: str, where: tuple[int, int]
) -> None:
    text, line, column = _edit(line_no, old, new)
    if old.startswith(("[", "{", "description")):
        assert (line, column) == where  # the construct itself starts there
    with pytest.raises(RuleFileError) as info:
        parse_rules(text, file="r.yaml")
    (problem,) = info.value.problems
    assert (problem.line, problem.column) == where
    assert "\n" not in str(info.value)


def test_an_unclosed_quote_at_the_end_of_the_file() -> None:
    with pytest.raises(SourceError, match=r"^t.yaml:2:4: YAML syntax error: this quoted"):
        load_yaml("a: 1\nb: 'abc\n", file="t.yaml")


def test_a_bad_feature_parameter_is_located_at_its_value(tmp_path: Path) -> None:
    text = MINI.replace(
        "{id: A, text: a}", "{id: A, text: a, feature: {name: face_count, params: {equals: -3}}}"
    )
    path = tmp_path / "p.yaml"
    path.write_text(text)
    line = text.splitlines()[2]
    column = line.index("-3") + 1
    for command in ("validate", "compile"):
        assert main([command, str(path)]) == 1
    from tactile_kb.pipeline import binding_problems

    (problem,) = [
        p for p in binding_problems(load_rules(path), missing="warning") if p.severity == "error"
    ]
    assert (problem.line, problem.column) == (3, column)
    assert problem.path == "propositions[0].feature.params.equals"


def test_non_utf8_is_located(tmp_path: Path) -> None:
    path = tmp_path / "latin1.yaml"
    path.write_bytes(b"name: x\ndescription: caf\xe9\n")
    with pytest.raises(RuleFileError) as info:
        load_rules(path)
    (problem,) = info.value.problems
    assert (problem.line, problem.column) == (2, 17)
    assert problem.message == "not UTF-8 text: byte 0xe9 cannot be decoded"


@pytest.mark.parametrize(("char", "code"), [("\x00", "U+0000"), ("\x07", "U+0007")])
def test_control_characters_give_one_line(
    char: str, code: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "ctl.yaml"
    path.write_text(f"name: x\ndescription: a{char}b\n")
    assert main(["validate", str(path)]) == 1
    err = capsys.readouterr().err
    assert err == f"{path}:2:15: control character {code} is not allowed in YAML\n"


# --- special files and sizes -----------------------------------------------------------------


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
@pytest.mark.parametrize("how", ["rules", "record", "finger"])
def test_dev_zero_is_refused(how: str, tmp_path: Path) -> None:
    stl = tmp_path / "cube.stl"
    box(0.06, 0.06, 0.06).export(stl)
    argv = {
        "rules": ["validate", "/dev/zero"],
        "record": ["classify", "--record", "/dev/zero"],
        "finger": ["classify", str(stl), "--finger", "/dev/zero"],
    }[how]
    done = run_cli(*argv, timeout=60)
    assert done.returncode == 1, done.stderr
    (line,) = done.stderr.splitlines()
    assert "/dev/zero" in line
    assert "not a regular file (a character device)" in line


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
@pytest.mark.parametrize("how", ["rules", "record", "finger"])
def test_a_named_pipe_is_refused_without_blocking(how: str, tmp_path: Path) -> None:
    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    stl = tmp_path / "cube.stl"
    box(0.06, 0.06, 0.06).export(stl)
    argv = {
        "rules": ["validate", str(fifo)],
        "record": ["classify", "--record", str(fifo)],
        "finger": ["classify", str(stl), "--finger", str(fifo)],
    }[how]
    done = run_cli(*argv, timeout=60)  # a blocking open would hit the timeout
    assert done.returncode == 1, done.stderr
    (line,) = done.stderr.splitlines()
    assert "not a regular file (a named pipe)" in line


def test_files_over_the_cap_are_refused_without_reading_them(tmp_path: Path) -> None:
    big = tmp_path / "big.yaml"
    with big.open("wb") as f:
        f.truncate(5 * 1024 * 1024)  # sparse: nothing is written, nothing should be read
    with pytest.raises(RuleFileError, match=r"file too large \(5 MiB; at most 4 MiB is read\)"):
        load_rules(big)
    with pytest.raises(InputFileError, match="file too large"):
        read_text(big, max_bytes=1000)


def test_a_deep_json_record_is_one_line_and_the_next_record_is_used(
    tmp_path: Path, record_file: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    assert main(["classify", "--record", str(deep), "--record", str(record_file)]) == 1
    captured = capsys.readouterr()
    assert captured.err == (
        f"tactile-kb classify: error: {deep}: not an exploration record (nested too deeply)\n"
    )
    name = ExplorationRecord.load(record_file).object
    assert captured.out == f"{name}- OBJECT IS A CUBE\n"
    with pytest.raises(RecordError, match="nested too deeply"):
        ExplorationRecord.from_json('{"contacts": ' + "[" * 100_000, file="x")


# --- the compiler ----------------------------------------------------------------------------


def test_compile_with_a_tautology_inside_a_class(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "t.yaml"
    path.write_text(MINI.replace("when: B", "when: B & (A | ~A)"))
    assert main(["validate", str(path)]) == 0
    assert main(["compile", str(path)]) == 0
    out = capsys.readouterr().out
    assert "optimal tree 1" in out  # one test (B) decides it


# --- one failing object never takes the others down -------------------------------------------


@pytest.mark.parametrize(
    "exc", [MemoryError(), RecursionError("maximum recursion depth exceeded"), ValueError("bug")]
)
def test_any_failure_of_one_object_is_that_objects_alone(
    exc: BaseException,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import tactile_kb.pipeline as pipeline

    paths = []
    for name in ("first", "second"):
        paths.append(tmp_path / f"{name}.stl")
        box(0.08, 0.08, 0.08).export(paths[-1])
    real = pipeline.classify

    def flaky(obj: object, **kw: object) -> pipeline.Classification:
        if str(obj).endswith("first.stl"):
            raise exc
        return real(obj, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(pipeline, "classify", flaky)
    code = main(["classify", *map(str, paths), "--json"])
    assert code == (3 if isinstance(exc, ValueError) else 1)
    captured = capsys.readouterr()
    first, second = (json.loads(line) for line in captured.out.splitlines())
    assert first["object"] == str(paths[0])
    assert first["error"]["kind"] == (
        "InternalError" if isinstance(exc, ValueError) else type(exc).__name__
    )
    assert second["answer"] == "OBJECT IS A CUBE"
    (line,) = captured.err.splitlines()
    assert line.startswith(f"tactile-kb classify: error: {paths[0]}: ")


# --- atomic writes ---------------------------------------------------------------------------


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "out.png"
    target.write_bytes(b"old picture")

    def half(f: object) -> None:
        f.write(b"half a pic")  # type: ignore[attr-defined]
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space"):
        atomic_write(target, half)
    assert target.read_bytes() == b"old picture"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.png"]


def test_a_symlink_planted_at_the_old_temporary_name_is_not_followed(
    tmp_path: Path, record_file: Path
) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "rec.json"
    (tmp_path / "rec.json.tmp").symlink_to(victim)
    ExplorationRecord.load(record_file).save(out)
    assert victim.read_text() == "precious"
    assert ExplorationRecord.load(out).touches > 0
    assert (tmp_path / "rec.json.tmp").is_symlink()  # left alone too


def test_a_picture_that_cannot_be_written_keeps_the_old_one(
    tmp_path: Path, record_file: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from matplotlib.figure import Figure

    out = tmp_path / "p.png"
    out.write_bytes(b"old")

    def full(self: Figure, *a: object, **kw: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full)
    assert main(["plot", str(record_file), "--out", str(out)]) == 1
    assert out.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.png"]


def test_a_read_only_folder_is_a_usage_error_before_any_work(
    tmp_path: Path,
    record_file: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    if os.geteuid() == 0:  # root writes anywhere: the folder answers as it would to a user
        access = os.access

        def user_access(path: object, mode: int, *a: object, **kw: object) -> bool:
            if Path(str(path)) == folder and mode & os.W_OK:
                return False
            return access(path, mode, *a, **kw)  # type: ignore[arg-type]

        monkeypatch.setattr(os, "access", user_access)
    try:
        assert main(["explore", "x.stl", "--out", str(folder / "r.json")]) == 2
        assert main(["plot", str(record_file), "--out", str(folder / "p.png")]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 2
        assert all("is not writable" in line for line in err)
    finally:
        folder.chmod(0o755)


# --- empty names -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["classify", "x.stl", "--plot", ""], "--plot '': give a picture file name"),
        (["classify", "x.stl", "--finger", ""], "no finger given (--finger '')"),
        (["grasp", "x.stl", "--plot", ""], "--plot '': give a picture file name"),
    ],
)
def test_empty_names_are_one_line_usage_errors(
    argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    (line,) = captured.err.splitlines()
    assert needle in line


# --- fuzzing ---------------------------------------------------------------------------------

_FRAGMENTS = [
    "name: x\n",
    "propositions:\n",
    "  - {id: A, text: a}\n",
    "  - id: B\n    text: b\n",
    "phases:\n  - {id: I, propositions: [A, B]}\n",
    "classes: [{id: c, answer: C, when: B & (A | ~A)}]\n",
    "classes:\n  - id: c\n    answer: C\n    when: A -> B\n",
    "connections:\n  - expr: A | B\n",
    "otherwise: {id: o, answer: O}\n",
    "&a ",
    "*a ",
    "[",
    "]",
    "{",
    "}",
    "'",
    '"',
    "%bogus\n",
    "\t",
    "\x00",
    "\xe9",
    "- ",
    ": ",
    "<<: ",
    "!!python/object ",
    "\n",
    "  ",
]


@settings(
    max_examples=150,
    deadline=2000,  # the resource bound: each file is loaded (or refused) within 2 s
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(st.lists(st.sampled_from(_FRAGMENTS), max_size=40), st.integers(1, 40))
def test_fuzzed_rule_files_load_or_give_located_problems(parts: list[str], repeat: int) -> None:
    from tactile_kb.kb.compiler import compile_rules

    text = "".join(parts) * (repeat if len(parts) < 4 else 1)
    error = _raised(lambda: compile_rules(parse_rules(text, file="fuzz.yaml")).economy())
    assert error is None or isinstance(error, RuleFileError)
    if isinstance(error, RuleFileError):
        assert error.problems
        assert all(p.file == "fuzz.yaml" and "\n" not in p.message for p in error.problems)


def _raised(fn: Callable[[], object]) -> BaseException | None:
    """The exception ``fn`` raised (any kind: the assertions judge it), or None."""
    try:
        fn()
    except Exception as exc:
        return exc
    return None


@settings(max_examples=100, deadline=2000)
@given(
    st.lists(
        st.sampled_from(
            [
                *_FRAGMENTS,
                "cone_deg: 30\n",
                "sensors:\n",
                "  - [0, 0, -1]\n",
                "radius: 0.005\n",
                "rings:\n  - {count: 4, elevation_deg: -45}\n",
            ]
        ),
        max_size=30,
    )
)
def test_fuzzed_finger_files_load_or_give_located_problems(parts: list[str]) -> None:
    error = _raised(lambda: load_layout("".join(parts), file="finger.yaml"))
    assert error is None or isinstance(error, LayoutFileError)
    if isinstance(error, LayoutFileError):
        assert error.problems
        assert all("\n" not in p.message for p in error.problems)


@settings(max_examples=100, deadline=2000)
@given(
    st.recursive(
        st.none() | st.booleans() | st.floats() | st.integers() | st.text(max_size=5),
        lambda children: (
            st.lists(children, max_size=4)
            | st.dictionaries(
                st.sampled_from(
                    [
                        "version",
                        "finger",
                        "tip_radius",
                        "contacts",
                        "path",
                        "step",
                        "centre",
                        "direction",
                        "point",
                        "sensors",
                        "layers",
                        "x",
                    ]
                ),
                children,
                max_size=5,
            )
        ),
        max_leaves=30,
    ),
    st.integers(0, 3000),
)
def test_fuzzed_records_load_or_give_one_line(data: object, depth: int) -> None:
    text = "[" * depth + json.dumps(data) + "]" * depth
    error = _raised(lambda: ExplorationRecord.from_json(text, file="r.json"))
    assert error is None or isinstance(error, RecordError)
    if error is not None:
        assert str(error).startswith("r.json")
        assert "\n" not in str(error)


def test_validate_goes_on_after_a_file_that_exhausts_memory(
    tmp_path: Path,
    good_rules: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import tactile_kb.cli.kb as kb_cli

    real = kb_cli._load

    def flaky(arg: str) -> object:
        if arg.endswith("huge.yaml"):
            raise MemoryError
        return real(arg)

    monkeypatch.setattr(kb_cli, "_load", flaky)
    huge = tmp_path / "huge.yaml"
    huge.write_text(MINI)
    assert main(["validate", str(huge), str(good_rules)]) == 1
    captured = capsys.readouterr()
    assert f"tactile-kb validate: error: {huge}: out of memory" in captured.err
    assert captured.out.startswith(f"{good_rules}: ok:")


_PART = st.tuples(
    st.sampled_from(["box", "tetra", "sheet", "soup"]),
    st.floats(0.0005, 0.12),  # size, metres
    st.tuples(*(st.floats(-0.08, 0.08) for _ in range(3))),  # offset
)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(_PART, min_size=1, max_size=5), st.integers(0, 2**16))
def test_fuzzed_meshes_of_parts_load_or_give_one_line(
    parts: list[tuple[str, float, tuple[float, float, float]]], seed: int
) -> None:
    # overlapping, touching and distant bodies, open sheets and loose triangles: every mesh
    # trimesh can hold either loads as one object or is refused in one line
    import numpy as np
    import trimesh

    from tactile_kb.errors import ObjectError
    from tactile_kb.objects import load_object

    rng = np.random.default_rng(seed)
    meshes = []
    for kind, size, offset in parts:
        if kind == "box":
            m = trimesh.creation.box((size, size * 0.7, size * 0.5))
        elif kind == "tetra":
            m = trimesh.Trimesh(
                rng.normal(size=(4, 3)) * size, [[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]]
            )
        elif kind == "sheet":
            m = trimesh.Trimesh([[0, 0, 0], [size, 0, 0], [0, size, 0]], [[0, 1, 2]])
        else:
            m = trimesh.Trimesh(rng.normal(size=(9, 3)) * size, np.arange(9).reshape(3, 3))
        m.apply_translation(offset)
        meshes.append(m)
    mesh = trimesh.util.concatenate(meshes)
    error = _raised(lambda: load_object(mesh, name="fuzz"))
    assert error is None or isinstance(error, ObjectError), repr(error)
    if error is not None:
        assert str(error).startswith("fuzz: ")
        assert "\n" not in str(error)
