"""``benchmarks/constraints.txt`` and ``benchmarks/versions.py``: the environment the published
benchmark figures were measured with, and the line every benchmark prints about its own."""

from __future__ import annotations

import sys
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import versions  # noqa: E402


def _requirements() -> list[Requirement]:
    core = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    plugin = tomllib.loads(
        (ROOT / "explorers" / "mujoco" / "pyproject.toml").read_text(encoding="utf-8")
    )["project"]
    names = [*core["dependencies"], *plugin["dependencies"]]
    for extra in ("dev", "dask", "parquet"):
        names += core["optional-dependencies"][extra]
    reqs = [Requirement(n) for n in names]
    return [r for r in reqs if not r.name.startswith("tactile-kb")]


@pytest.mark.parametrize("req", _requirements(), ids=lambda r: r.name)
def test_every_dependency_is_pinned_within_the_project_s_bounds(req: Requirement) -> None:
    pins = versions.pinned()
    name = canonicalize_name(req.name)
    assert name in pins, f"benchmarks/constraints.txt does not pin {req.name}"
    assert req.specifier.contains(pins[name], prereleases=True), (
        f"{req.name}=={pins[name]} is outside the project's {req}"
    )


def test_a_pin_of_another_version_is_named(tmp_path: Path) -> None:
    pins = tmp_path / "constraints.txt"
    have = version("numpy")
    pins.write_text(
        f"# comment\nnumpy==0.0.1\nscipy=={version('scipy')}\nnot-installed-here==1.0\n"
        "trimesh>=4  # a bound, not a pin\n"
    )
    assert versions.pinned(pins) == {
        "numpy": "0.0.1",
        "scipy": version("scipy"),
        "not-installed-here": "1.0",
    }
    # numpy differs; scipy matches; a package not installed is no difference
    assert versions.differing(pins) == [("numpy", have, "0.0.1")]
    line = versions.versions_line(pins)
    assert line.startswith("versions: python ")
    assert f"numpy {have}" in line
    assert f"1 differs from benchmarks/constraints.txt: numpy {have} (pinned 0.0.1)" in line


def test_the_pinned_environment_says_so(tmp_path: Path) -> None:
    pins = tmp_path / "constraints.txt"
    pins.write_text(f"numpy=={version('numpy')}\nSciPy=={version('scipy')}\n")
    assert versions.pinned(pins) == {"numpy": version("numpy"), "scipy": version("scipy")}
    assert versions.differing(pins) == []
    assert versions.versions_line(pins).endswith("(as pinned in benchmarks/constraints.txt)")


def test_an_unreadable_file_is_named(tmp_path: Path) -> None:
    line = versions.versions_line(tmp_path / "missing.txt")
    assert "missing.txt unreadable" in line
