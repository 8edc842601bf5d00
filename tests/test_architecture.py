"""The import contract (``[tool.importlinter]`` in pyproject.toml) holds, and it has teeth.

``make test`` runs ``lint-imports`` on the package. Here the same contracts run on a copy of
the package into which a forbidden import is planted: the contract must then break, naming
the import.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(tree: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    return subprocess.run(
        [str(LINT), "--config", str(tree / "pyproject.toml"), "--no-cache"],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    shutil.copytree(
        ROOT / "tactile_kb",
        tmp_path / "tactile_kb",
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    return tmp_path


def _plant(tree: Path, module: str, line: str) -> None:
    path = tree / (module.replace(".", "/") + ".py")
    path.write_text(path.read_text(encoding="utf-8") + f"\n{line}\n", encoding="utf-8")


def test_the_package_keeps_its_contracts(tree: Path) -> None:
    out = _lint(tree)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "broken" not in out.stdout.lower().replace("0 broken", "")


@pytest.mark.parametrize(
    ("module", "line", "contract"),
    [
        # the knowledge base reaching into geometry
        ("tactile_kb.kb.expr", "import tactile_kb.geometry.model", "layered"),
        # the servo reaching into the knowledge base (touch and kb are independent)
        ("tactile_kb.touch.servo", "import tactile_kb.kb.engine", "layered"),
        # features reading the finger
        ("tactile_kb.features.builtin", "import tactile_kb.touch.finger", "never the finger"),
        # a cycle inside one stage
        ("tactile_kb.kb.notation", "import tactile_kb.kb.engine", "No import cycle"),
    ],
)
def test_a_forbidden_import_breaks_the_contract(
    tree: Path, module: str, line: str, contract: str
) -> None:
    _plant(tree, module, line)
    out = _lint(tree)
    assert out.returncode != 0
    broken = out.stdout[out.stdout.index("Broken contracts") :]
    assert contract in broken
    # named in full, or relative to its package in the cycle report (".notation -> .engine")
    assert module in broken or f".{module.rsplit('.', 1)[1]} -> " in broken
