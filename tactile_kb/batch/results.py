"""The results file: rows streamed as fsynced JSON lines, read back, resumed, and sorted
atomically at the end (JSON lines or Parquet)."""

from __future__ import annotations

import importlib
import io
import json
import os
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from tactile_kb.batch.inputs import Row
from tactile_kb.batch.summary import BatchSummary
from tactile_kb.errors import PluginUnavailableError, UsageError

TRANSIENT_ERRORS = frozenset({"WorkerLost"})
"""Error kinds that ``resume`` runs again: the worker was lost (killed, crashed), which says
nothing about the object. Every other row, errors included, counts as done."""


def stream_path(out: Path) -> Path:
    """Where rows are streamed: the results file itself, or ``NAME.parquet.jsonl`` beside it."""
    return out.with_name(out.name + ".jsonl") if out.suffix.lower() == ".parquet" else out


def _scan(path: Path) -> Iterator[tuple[int, int, Row]]:
    """(offset, length, row) for each complete, readable line of a results file."""
    offset = 0
    with path.open("rb") as handle:
        for raw in handle:
            length = len(raw)
            if raw.endswith(b"\n"):
                try:
                    row = json.loads(raw)
                except (json.JSONDecodeError, UnicodeDecodeError):
                    row = None
                if isinstance(row, dict) and isinstance(row.get("key"), str):
                    yield offset, length, row
            offset += length


def read_results(path: str | Path) -> Iterator[Row]:
    """The rows of a results file (JSONL, or Parquet through pyarrow), in file order.

    A line cut short by a kill and lines that are not rows are passed over. In Parquet, the
    nested values (propositions, measures, errors, ...) are JSON text; they are decoded here.
    """
    p = Path(path)
    if p.suffix.lower() == ".parquet":
        table = _pyarrow().read_table(p)
        nested = set(json.loads((table.schema.metadata or {}).get(_JSON_COLUMNS, b"[]")))
        for row in table.to_pylist():
            yield {
                k: json.loads(v) if k in nested and v is not None else v
                for k, v in row.items()
                if v is not None
            }
        return
    for _, _, row in _scan(p):
        yield row


def _pyarrow() -> Any:
    try:
        pq = importlib.import_module("pyarrow.parquet")
    except ImportError:
        raise PluginUnavailableError(
            "parquet", "pip install 'tactile-kb[parquet]'", "pyarrow is not installed"
        ) from None
    return pq


def prepare_stream(path: Path) -> set[str]:
    """The keys already done in ``path``; a last line cut short by a kill is cut off."""
    if not path.exists():
        return set()
    done: dict[str, bool] = {}
    for _, _, row in _scan(path):
        error = row.get("error")
        kind = error.get("kind") if isinstance(error, dict) else None
        done[row["key"]] = kind not in TRANSIENT_ERRORS
    size = path.stat().st_size
    if size:
        with path.open("r+b") as handle:
            handle.seek(size - 1)
            if handle.read(1) != b"\n":  # an unfinished last line: drop it, its task is redone
                handle.seek(0)
                handle.truncate(handle.read().rfind(b"\n") + 1)
                handle.flush()
                os.fsync(handle.fileno())
    return {key for key, ok in done.items() if ok}


def _plain(value: Any) -> Any:
    """A JSON-ready stand-in for a value json cannot write (a numpy scalar or array)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if hasattr(value, "item"):
        return value.item()
    return str(value)


def _line(row: Row) -> bytes:
    """One results line: the row as JSON, newline-terminated."""
    return (json.dumps(row, ensure_ascii=False, default=_plain) + "\n").encode("utf-8")


class Appender:
    """Appends whole lines, each flushed and synced, so that a kill leaves at most a torn last line."""

    def __init__(self, path: Path) -> None:
        self._fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def write(self, row: Row) -> None:
        data = _line(row)
        view = memoryview(data)
        while view:
            written = os.write(self._fd, view)
            view = view[written:]
        os.fsync(self._fd)

    def close(self) -> None:
        os.close(self._fd)


def check_output(out: str | Path, *, resume: bool = False, overwrite: bool = False) -> Path:
    """Refuse, before any work, a results path that cannot be written; return it.

    Raises :class:`UsageError` when the folder is missing or read-only, the path is a folder,
    or results already exist there and neither ``resume`` nor ``overwrite`` is given.
    """
    p = Path(out)
    if p.is_dir():
        raise UsageError(f"--out {out}: is a directory")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"--out {out}: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"--out {out}: directory {str(parent)!r} is not writable")
    stream = stream_path(p)
    for target in {p, stream}:
        if target.exists() and not os.access(target, os.W_OK):
            raise UsageError(f"--out {out}: {target} is not writable")
    if p.suffix.lower() == ".parquet":
        _pyarrow()
    existing = stream.exists() and stream.stat().st_size > 0
    if existing and not resume and not overwrite:
        raise UsageError(
            f"--out {out}: results already there; add --resume to continue them or "
            "--overwrite to start again"
        )
    return p


def finish_stream(
    stream: Path, out: Path, index_of: Mapping[str, int], summary: BatchSummary
) -> None:
    """Write the results sorted by index, each (object, seed) once (its last row), atomically."""
    last: dict[str, tuple[int, int, int]] = {}
    for offset, length, row in _scan(stream):
        index = index_of.get(row["key"], len(index_of) + int(row.get("index", 0)))
        last[row["key"]] = (index, offset, length)
    order = sorted(last.values())
    fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    try:
        with os.fdopen(fd, "wb") as dst, stream.open("rb") as src:
            rows = _sorted_rows(src, order, index_of)
            if out.suffix.lower() == ".parquet":
                _write_parquet(dst, rows, summary)
            else:
                for row in rows:
                    summary.add(row)
                    dst.write(_line(row))
            dst.flush()
            os.fsync(dst.fileno())
        os.replace(tmp, out)  # for Parquet the stream beside it stays: --resume reads it
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _sorted_rows(
    src: io.BufferedReader, order: Sequence[tuple[int, int, int]], index_of: Mapping[str, int]
) -> Iterator[Row]:
    for _, offset, length in order:
        src.seek(offset)
        row: Row = json.loads(src.read(length))
        if row["key"] in index_of:
            row["index"] = index_of[row["key"]]
        yield row


_JSON_COLUMNS = b"tactile_kb.json_columns"
"""Parquet schema metadata: the columns that hold JSON text (nested values)."""


def _write_parquet(dst: Any, rows: Iterator[Row], summary: BatchSummary) -> None:
    """Rows in Parquet: scalars as columns, nested values (dicts, lists) as JSON text.

    The columns holding JSON are listed in the schema metadata, for :func:`read_results`.
    The table is built in memory (one column set for all rows); the JSONL stream is the
    flat-memory path.
    """
    pq = _pyarrow()
    pa: Any = importlib.import_module("pyarrow")

    names: list[str] = []
    nested: set[str] = set()
    buffered: list[Row] = []
    for row in rows:
        summary.add(row)
        for k, v in row.items():
            if k not in names:
                names.append(k)
            if isinstance(v, dict | list):
                nested.add(k)
        buffered.append(row)

    def cell(name: str, value: Any) -> Any:
        if value is None or name not in nested:
            return value
        return json.dumps(value, ensure_ascii=False, default=_plain)

    table = pa.Table.from_pylist([{n: cell(n, r.get(n)) for n in names} for r in buffered])
    table = table.replace_schema_metadata({_JSON_COLUMNS: json.dumps(sorted(nested))})
    pq.write_table(table, dst)
