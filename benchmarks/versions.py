"""The versions a benchmark runs with, against those its published figures were measured with.

``benchmarks/constraints.txt`` pins every package of the environment the figures in
docs/benchmarks.md come from. The project itself sets lower bounds only, so a fresh
environment takes the newest releases, and the same code can give other figures there: of a
level-3 draw of ``bench_real.py``, 92 right answers in one fresh environment against 96 in
the one before it, with no change of the package. Every benchmark run through
``benchmarks/run.py``, and ``bench_real.py`` on its own, prints :func:`versions_line` first,
so a figure is read together with what it was measured with
(``tests/test_bench_versions.py``).
"""

from __future__ import annotations

import platform
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from packaging.requirements import InvalidRequirement, Requirement
from packaging.utils import canonicalize_name

CONSTRAINTS = Path(__file__).resolve().parent / "constraints.txt"

SHOWN = ("numpy", "scipy", "trimesh", "shapely", "rtree", "manifold3d", "sympy", "mujoco")
"""The packages whose versions the line always shows: those the geometry and the explorers
compute with."""


def pinned(path: Path = CONSTRAINTS) -> dict[str, str]:
    """The ``name==version`` lines of a constraints file, by canonical name (PEP 503, as pip
    compares them); comments, blank lines and anything not pinned exactly are skipped."""
    out: dict[str, str] = {}
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        try:
            req = Requirement(text)
        except InvalidRequirement:
            continue
        specs = list(req.specifier)
        if len(specs) == 1 and specs[0].operator == "==":
            out[canonicalize_name(req.name)] = specs[0].version
    return out


def installed(name: str) -> str | None:
    """The installed version of distribution ``name``, or None."""
    try:
        return version(name)
    except PackageNotFoundError:
        return None


def differing(path: Path = CONSTRAINTS) -> list[tuple[str, str, str]]:
    """``(name, installed, pinned)`` for every pinned package installed at another version
    (packages not installed are left out: the MuJoCo plugin's, before it is installed)."""
    out = []
    for name, want in sorted(pinned(path).items()):
        have = installed(name)
        if have is not None and have != want:
            out.append((name, have, want))
    return out


def versions_line(path: Path = CONSTRAINTS, *, most: int = 6) -> str:
    """One line: Python's and the :data:`SHOWN` packages' versions, then whether the
    environment is the pinned one (naming up to ``most`` packages that differ)."""
    shown = [f"python {platform.python_version()}"]
    shown += [f"{n} {v}" for n in SHOWN if (v := installed(n)) is not None]
    try:
        diff = differing(path)
    except OSError as exc:
        return f"versions: {', '.join(shown)} ({path.name} unreadable: {exc.strerror})"
    if not diff:
        return f"versions: {', '.join(shown)} (as pinned in benchmarks/{path.name})"
    named = ", ".join(f"{n} {have} (pinned {want})" for n, have, want in diff[:most])
    more = f" and {len(diff) - most} more" if len(diff) > most else ""
    verb = "differs" if len(diff) == 1 else "differ"
    return (
        f"versions: {', '.join(shown)}; {len(diff)} {verb} from benchmarks/{path.name}: "
        f"{named}{more}"
    )


if __name__ == "__main__":
    print(versions_line())
