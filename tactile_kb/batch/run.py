"""A batch run to a results file: resume, stream, sort, summarise (:func:`run_batch`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from tactile_kb.batch.inputs import BatchItem, Row, Task
from tactile_kb.batch.many import classify_many
from tactile_kb.batch.results import (
    Appender,
    check_output,
    finish_stream,
    prepare_stream,
    stream_path,
)
from tactile_kb.batch.summary import BatchSummary


def run_batch(
    inputs: Iterable[str | Path | BatchItem],
    out: str | Path,
    *,
    resume: bool = False,
    overwrite: bool = False,
    on_row: Callable[[Row], None] | None = None,
    on_skip: Callable[[Task], None] | None = None,
    **options: Any,
) -> BatchSummary:
    """Classify ``inputs`` into the results file ``out`` and return the summary of all of it.

    Rows are appended to ``out`` (JSONL; for ``*.parquet``, to ``out + ".jsonl"`` beside it) as
    they finish, each line whole and synced to disk. At the end the file is rewritten, atomically,
    sorted by index with each (object, seed) once. With ``resume``, the tasks whose key is
    already there (except those whose worker was lost) are skipped; a last line cut short by a
    kill is dropped and its task redone. ``options`` go to :func:`classify_many`.
    """
    path = check_output(out, resume=resume, overwrite=overwrite)
    stream = stream_path(path)
    done = prepare_stream(stream) if resume else set()
    index_of: dict[str, int] = {}
    rows = classify_many(  # checks the inputs and options: nothing is touched before
        inputs,
        skip=done.__contains__,
        _on_skip=on_skip,
        _index_of=index_of,
        **options,
    )
    if overwrite and not resume:
        stream.unlink(missing_ok=True)
    appender: Appender | None = None
    try:
        for row in rows:
            if appender is None:
                appender = Appender(stream)
            appender.write(row)
            if on_row is not None:
                on_row(row)
    finally:
        rows.close()
        if appender is not None:
            appender.close()
    summary = BatchSummary()
    if stream.exists():
        finish_stream(stream, path, index_of, summary)
    return summary
