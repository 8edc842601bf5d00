"""What a batch is given: mesh files, folders, globs and CSV/JSONL manifests, as
:class:`BatchItem` values, with the per-object options checked."""

from __future__ import annotations

import csv
import glob
import json
import os
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tactile_kb.errors import Problem, SourceError, UsageError

Row = dict[str, Any]
"""A result row: plain JSON-ready values."""
Task = dict[str, Any]
"""One task as sent to a worker: plain, picklable values."""

MANIFEST_SUFFIXES = (".csv", ".jsonl", ".ndjson")
"""Files read as manifests (a ``path`` column, optionally ``label`` and :data:`ROW_OPTIONS`)."""

ROW_OPTIONS = ("rules", "explorer", "finger", "noise", "seeds", "timeout")
"""The per-object options a manifest row may set (an empty cell keeps the batch's)."""


@dataclass(frozen=True)
class BatchItem:
    """One object of a batch: a mesh path, its expected label and per-object options."""

    path: str
    label: str | None = None
    options: Mapping[str, Any] = field(default_factory=dict)
    """Overrides of the batch options (:data:`ROW_OPTIONS`), already checked."""


def parse_seeds(text: str) -> tuple[int, ...]:
    """Seeds from ``"0-9"``, ``"3"`` or ``"0,2,5-7"`` (in the order given, without repeats).

    >>> parse_seeds("0-2,7,1")
    (0, 1, 2, 7)
    >>> parse_seeds("5-3")
    Traceback (most recent call last):
    ...
    tactile_kb.errors.UsageError: seeds '5-3': a range must go up (5-3)
    """
    seeds: list[int] = []
    for part in str(text).split(","):
        part = part.strip()
        lo_text, dash, hi_text = part.partition("-")
        try:
            lo = int(lo_text)
            hi = int(hi_text) if dash else lo
        except ValueError:
            raise UsageError(
                f"seeds {text!r}: expected whole numbers ≥ 0 like 0-9 or 0,3,5"
            ) from None
        if lo < 0:
            raise UsageError(f"seeds {text!r}: a seed must be ≥ 0")
        if hi < lo:
            raise UsageError(f"seeds {text!r}: a range must go up ({part})")
        if hi - lo >= 100_000:
            raise UsageError(f"seeds {text!r}: at most 100000 seeds")
        seeds.extend(s for s in range(lo, hi + 1) if s not in seeds)
    return tuple(seeds)


def _mesh_suffixes() -> tuple[str, ...]:
    from tactile_kb.objects import OBJECT_SUFFIXES

    return tuple(OBJECT_SUFFIXES)


def _walk(folder: Path, suffixes: tuple[str, ...]) -> Iterator[Path]:
    """Mesh files under ``folder``, recursively, in sorted order (symlinked folders not followed)."""
    for root, dirs, files in os.walk(folder):
        dirs.sort()
        for name in sorted(files):
            if Path(name).suffix.lower() in suffixes:
                yield Path(root) / name


def _check_option(name: str, value: Any) -> Any:
    """A per-row option value, checked; raises ValueError with a short reason."""
    if name in ("rules", "explorer", "finger"):
        return str(value)
    if name in ("noise", "timeout"):
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"not a number: {value!r}") from None
    if name == "noise":
        if not (number >= 0 and number != float("inf")):
            raise ValueError(f"must be a finite number ≥ 0, got {value!r}")
        return number
    if name == "timeout":
        if not (number > 0 and number != float("inf")):
            raise ValueError(f"must be a number > 0, got {value!r}")
        return number
    if name == "seeds":
        try:
            return parse_seeds(str(value))
        except UsageError as exc:
            raise ValueError(str(exc)) from None
    raise AssertionError(name)  # pragma: no cover


def _manifest_rows(path: Path) -> Iterator[tuple[int, Mapping[str, Any] | str]]:
    """(line, row) for each row of a manifest; a row that cannot be read is its reason."""
    with path.open(encoding="utf-8", newline="") as handle:
        if path.suffix.lower() == ".csv":
            reader = csv.DictReader(handle)
            for row in reader:
                yield reader.line_num, row
            return
        for number, line in enumerate(handle, start=1):
            if not line.strip():
                continue
            try:
                value = json.loads(line)
            except json.JSONDecodeError as exc:
                yield number, f"not a JSON object: {exc.msg}"
                continue
            yield number, value if isinstance(value, dict) else "not a JSON object"


def _read_manifest(path: Path) -> list[BatchItem]:
    """The items of a CSV or JSONL manifest; every problem is located (file:line)."""
    name = str(path)
    problems: list[Problem] = []
    items: list[BatchItem] = []
    known = ("path", "label", *ROW_OPTIONS)
    try:
        rows = list(_manifest_rows(path))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise SourceError([Problem(name, 0, 0, "", f"cannot read the manifest: {exc}")]) from None
    for line, row in rows:
        if isinstance(row, str):
            problems.append(Problem(name, line, 1, "", row))
            continue
        unknown = [k for k in row if k not in known]
        if unknown:
            problems.append(
                Problem(
                    name,
                    line,
                    1,
                    "",
                    f"unknown column {unknown[0]!r} (known: {', '.join(known)})",
                )
            )
            continue
        target = row.get("path")
        if target is None or not str(target).strip():
            problems.append(Problem(name, line, 1, "path", "no path given"))
            continue
        mesh = Path(str(target).strip())
        if not mesh.is_absolute():
            mesh = path.parent / mesh
        options: dict[str, Any] = {}
        for key in ROW_OPTIONS:
            value = row.get(key)
            if value is None or (isinstance(value, str) and not value.strip()):
                continue
            try:
                options[key] = _check_option(key, value)
            except (TypeError, ValueError) as exc:
                problems.append(Problem(name, line, 1, key, str(exc)))
                continue
            if key in ("rules", "finger") and not Path(options[key]).is_absolute():
                beside = path.parent / options[key]
                if beside.exists():  # a file named relative to the manifest
                    options[key] = str(beside)
        label = row.get("label")
        label_text = str(label).strip() if label is not None else ""
        items.append(BatchItem(str(mesh), label_text or None, options))
    if not rows:
        problems.append(Problem(name, 0, 0, "", "the manifest lists no objects"))
    if problems:
        raise SourceError(problems)
    return items


def expand_inputs(inputs: Iterable[str | Path | BatchItem]) -> list[BatchItem]:
    """The objects named by ``inputs``, in order, each once.

    Each input is a :class:`BatchItem`; a folder (searched recursively for the mesh formats
    :func:`~tactile_kb.objects.load_object` reads); a manifest (``.csv``, ``.jsonl``) with a
    ``path`` column, optionally ``label`` and the per-object options :data:`ROW_OPTIONS`, paths
    relative to the manifest's folder; a glob (``meshes/**/*.stl``); or a mesh file. A path
    that does not exist is kept: classifying it gives an error row, and the batch goes on.

    Raises
    ------
    UsageError
        A folder without mesh files, or a glob that matches nothing.
    SourceError
        A manifest with problems (each one located, ``file:line: column: message``).
    """
    suffixes = _mesh_suffixes()
    items: list[BatchItem] = []
    seen: set[tuple[str, str | None, str]] = set()

    def add(item: BatchItem) -> None:
        mark = (item.path, item.label, json.dumps(dict(item.options), sort_keys=True))
        if mark not in seen:
            seen.add(mark)
            items.append(item)

    for given in inputs:
        if isinstance(given, BatchItem):
            add(given)
            continue
        text = str(given)
        path = Path(text)
        if path.is_dir():
            found = list(_walk(path, suffixes))
            if not found:
                raise UsageError(f"{text}: no mesh files ({', '.join(suffixes)}) in this folder")
            for mesh in found:
                add(BatchItem(str(mesh)))
        elif path.is_file() and path.suffix.lower() in MANIFEST_SUFFIXES:
            for item in _read_manifest(path):
                add(item)
        elif not path.exists() and glob.has_magic(text):
            matches = sorted(glob.glob(text, recursive=True))
            files = [m for m in matches if Path(m).is_file()]
            if not files:
                raise UsageError(f"{text}: no file matches this pattern")
            for match in files:
                add(BatchItem(match))
        else:
            add(BatchItem(text))
    return items
