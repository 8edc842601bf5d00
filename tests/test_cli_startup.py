"""What the quick commands import: ``--help`` and ``--version`` none of the heavy libraries,
``validate``, ``query`` and ``compile`` neither sympy nor any geometry, plotting or explorer plugin.

Each runs in a fresh interpreter: the rest of the suite imports everything into this one.
(Times are printed by ``benchmarks/bench_startup.py``, never checked here.)
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GEOMETRY_AND_PLOTS = ("trimesh", "scipy", "matplotlib", "tactile_kb_mujoco", "tactile_kb.plot")
PROBE = """
import contextlib, io, json, sys
from tactile_kb.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    try:
        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def imported_by(*argv: str) -> tuple[int, set[str]]:
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *argv], capture_output=True, text=True, check=True
    )
    info = json.loads(done.stdout)
    return info["code"], {m.split(".")[0] for m in info["modules"]} | set(info["modules"])


@pytest.mark.parametrize("argv", [["--version"], ["--help"], ["validate", "--help"]])
def test_help_and_version_import_nothing_heavy(argv: list[str]) -> None:
    code, modules = imported_by(*argv)
    assert code == 0
    heavy = {"sympy", "dd", "networkx", "pysat", "numpy", *GEOMETRY_AND_PLOTS}
    assert modules & heavy == set()


@pytest.mark.parametrize(
    "argv",
    [
        ["validate", str(ROOT / "rules" / "parallelepipeds.yaml")],
        ["query", "parallelepipeds", "--bits", "101101111"],
        ["compile", "parallelepipeds"],
    ],
)
def test_rule_file_commands_import_no_sympy_geometry_plots_or_plugins(argv: list[str]) -> None:
    code, modules = imported_by(*argv)
    assert code == 0
    # the classes' sums of products are minimised by kb.minimise, not by sympy's SOPform
    assert modules & {"sympy", *GEOMETRY_AND_PLOTS} == set()
    assert "tactile_kb.touch.explorers" not in modules
    if argv[0] in ("validate", "compile"):  # the bindings are checked, without the geometry
        assert "tactile_kb.features.builtin" in modules


class _Terminal:
    def __init__(self, tty: bool) -> None:
        self.tty = tty
        self.text = ""

    def isatty(self) -> bool:
        return self.tty

    def write(self, text: str) -> int:
        self.text += text
        return len(text)

    def flush(self) -> None:
        pass


@pytest.mark.parametrize("tty", [True, False])
def test_slow_work_shows_progress_on_a_terminal_only(tty: bool) -> None:
    import time

    from tactile_kb.cli.options import progress
    from tactile_kb.touch.watch import current_watcher

    stream = _Terminal(tty)
    with progress("sphere.stl", stream=stream):  # type: ignore[arg-type]
        watcher = current_watcher()
        assert (watcher is not None) is tty  # nobody watches when nothing is shown
        if watcher is not None:
            watcher("layers", 7, 20)
        time.sleep(1.0)
    assert ("working on sphere.stl" in stream.text) is tty
    assert ("following the contour, 7 touches" in stream.text) is tty
    assert current_watcher() is None  # the watcher ends with the block
    quick = _Terminal(True)
    with progress("cube.stl", stream=quick):  # type: ignore[arg-type]
        pass
    assert quick.text == ""  # work that ends at once shows nothing
