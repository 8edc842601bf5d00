"""Classify many objects: on every local core or on a Dask cluster, streamed, resumable.

:func:`expand_inputs` turns what a user names (mesh files, folders, globs, CSV/JSONL manifests)
into :class:`BatchItem` values; :func:`classify_many` classifies them, one task per object and
seed, and yields one result row (a plain dict) per task as it finishes; :func:`run_batch` writes
the rows to a results file as they come, resumes a run that was cut short, sorts the file at the
end and returns a :class:`BatchSummary` (answers per class, errors per kind, the confusion matrix
when the objects carry expected labels).

A result row holds the keys of ``tactile-kb classify --json``
(:meth:`~tactile_kb.pipeline.Classification.summary`), or, for an object that failed,
``{"object": …, "error": {"kind": …, "message": …}}``; and in both cases ``index`` (the stable
position of the (object, seed) pair in the inputs), ``seed``, ``key`` (what ``--resume`` matches:
the path, the file's content hash and the options), ``options``, ``expected`` and ``correct``
(with a label), ``task_seconds``, ``cpu_seconds`` and ``worker``.

Execution
---------
* Local workers (the default) are processes of the standard library's ``multiprocessing``, each
  running one task at a time with the next one waiting in its pipe, so that a task that crashes or kills its process, or runs past its
  timeout (the process is killed), becomes an error row of kind ``WorkerLost`` or ``Timeout``
  and a fresh process takes the tasks queued behind it. Tasks in flight: twice the workers.
* A ``dask.distributed.Client`` runs the tasks on its cluster with a bounded number of futures
  in flight. Workers read meshes by path (a shared filesystem) unless ``ship=True`` sends the
  bytes with each task.

The answers depend on the seeds only, never on the number of workers or the order they finish in.

Modules: :mod:`~tactile_kb.batch.inputs` (what is given), :mod:`~tactile_kb.batch.tasks` (one
task and its row), :mod:`~tactile_kb.batch.local` and :mod:`~tactile_kb.batch.cluster` (where
tasks run), :mod:`~tactile_kb.batch.many` (:func:`classify_many`),
:mod:`~tactile_kb.batch.results` (the results file), :mod:`~tactile_kb.batch.summary` and
:mod:`~tactile_kb.batch.run` (:func:`run_batch`).

Examples
--------
>>> import pathlib, tempfile
>>> from tactile_kb.solids import box
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> _ = box(0.08, 0.08, 0.08).export(folder / "cube.stl")
>>> [(row["object"][-8:], row["seed"], row["label"]) for row in classify_many([folder], workers=1)]
[('cube.stl', 0, 'cube')]
"""

from __future__ import annotations

from tactile_kb.batch.inputs import (
    MANIFEST_SUFFIXES,
    ROW_OPTIONS,
    BatchItem,
    expand_inputs,
    parse_seeds,
)
from tactile_kb.batch.many import classify_many
from tactile_kb.batch.results import TRANSIENT_ERRORS, check_output, read_results
from tactile_kb.batch.run import run_batch
from tactile_kb.batch.summary import BatchSummary
from tactile_kb.batch.tasks import error_summary, finish_row, run_task

__all__ = [
    "MANIFEST_SUFFIXES",
    "ROW_OPTIONS",
    "TRANSIENT_ERRORS",
    "BatchItem",
    "BatchSummary",
    "check_output",
    "classify_many",
    "error_summary",
    "expand_inputs",
    "finish_row",
    "parse_seeds",
    "read_results",
    "run_batch",
    "run_task",
]
