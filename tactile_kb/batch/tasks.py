"""One task of a batch (an object and a seed) and the row it gives: the resume key, the
classification run in a worker, and the error row of a task that failed."""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import socket
import tempfile
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from tactile_kb.batch.inputs import BatchItem, Row, Task
from tactile_kb.settings import DEFAULTS, current, use

DEFAULT_WORK = "tactile_kb.batch.tasks:run_task"
"""What a worker runs for a task (``module:function``; benchmarks put a stand-in there)."""


def _file_digest(path: str) -> tuple[str, bytes | None]:
    """The sha256 of a file's bytes (``"missing"`` when it cannot be read), and the bytes."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            data = handle.read()
    except OSError:
        return "missing", None
    digest.update(data)
    return digest.hexdigest(), data


def _option_digest(value: str) -> str | None:
    """The content hash of a rule or finger file named by ``value``; None for a built-in name."""
    path = Path(value)
    if path.is_file():
        return _file_digest(value)[0]
    return None


def make_tasks(
    items: Sequence[BatchItem],
    defaults: Mapping[str, Any],
    *,
    ship: bool,
    skip: Callable[[str], bool],
    on_skip: Callable[[Task], None] | None,
    index_of: dict[str, int] | None,
) -> Iterator[Task]:
    """One task per (object, seed), lazily: each file is read (hashed) only when its turn comes."""
    option_hashes: dict[str, str | None] = {}
    changed = current().changes()  # the caller's settings travel with each task
    index = 0
    for item in items:
        opts = {**defaults, **item.options}
        seeds: tuple[int, ...] = tuple(opts.pop("seeds"))
        timeout = opts.pop("timeout")
        digest, data = _file_digest(item.path)
        for name in ("rules", "finger"):
            value = str(opts[name])
            if value not in option_hashes:
                option_hashes[value] = _option_digest(value)
        for seed in seeds:
            keyed = {
                "path": item.path,
                "sha256": digest,
                "seed": seed,
                "options": opts,
                "files": {n: option_hashes[str(opts[n])] for n in ("rules", "finger")},
            }
            if changed:  # the defaults keep the keys they had
                keyed["settings"] = changed
            key = hashlib.sha256(json.dumps(keyed, sort_keys=True).encode()).hexdigest()[:32]
            task: Task = {
                "index": index,
                "object": item.path,
                "seed": seed,
                "key": key,
                "expected": item.label,
                "options": dict(opts),
                "timeout": timeout,
                "sha256": digest,
            }
            if changed:
                task["settings"] = changed
            if index_of is not None:
                index_of[key] = index
            index += 1
            if skip(key):
                if on_skip is not None:
                    on_skip(task)
                continue
            if ship and data is not None:
                task["data"] = data
            yield task


def error_summary(obj: str, kind: str, message: str) -> Row:
    """The row of an object that failed: ``{"object": …, "error": {"kind": …, "message": …}}``."""
    return {"object": obj, "error": {"kind": kind, "message": message}}


def _worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def finish_row(
    task: Task,
    row: Row,
    started: float,
    *,
    cpu_started: float | None = None,
    worker: str | None = None,
) -> Row:
    out: Row = {"index": task["index"], "seed": task["seed"], **row}
    out["object"] = task["object"]
    expected = task.get("expected")
    if expected is not None:
        out["expected"] = expected
        out["correct"] = "error" not in row and row.get("label") == expected
    out["options"] = task["options"]
    out["key"] = task["key"]
    out["task_seconds"] = round(time.perf_counter() - started, 4)
    if cpu_started is not None:
        out["cpu_seconds"] = round(time.process_time() - cpu_started, 4)
    out["worker"] = worker or _worker_name()
    return out


def failed_row(
    task: Task,
    kind: str,
    message: str,
    started: float,
    *,
    cpu_started: float | None = None,
    worker: str | None = None,
) -> Row:
    row = error_summary(task["object"], kind, message)
    return finish_row(task, row, started, cpu_started=cpu_started, worker=worker)


_FINGERS: dict[str, Any] = {}


def run_task(task: Task) -> Row:
    """Classify one (object, seed) task in this process, with the settings it carries; every
    failure becomes an error row.

    This is what a worker runs: a local worker process or a Dask worker thread.
    """
    with use(DEFAULTS.replaced(**task.get("settings", {}))):
        return _run_task(task)


def _run_task(task: Task) -> Row:
    started = time.perf_counter()
    cpu = time.process_time()
    try:
        from tactile_kb.pipeline import classify, knowledge_base
        from tactile_kb.touch.finger import load_finger

        opts = task["options"]
        finger = _FINGERS.get(opts["finger"])
        if finger is None:
            finger = _FINGERS[opts["finger"]] = load_finger(opts["finger"])
        kb = knowledge_base(opts["rules"])
        data = task.get("data")
        if data is None:
            result = classify(
                task["object"],
                rules=kb,
                explorer=opts["explorer"],
                finger=finger,
                noise=float(opts["noise"]),
                seed=int(task["seed"]),
            )
        else:  # shipped bytes: a private copy with the same suffix, named as the original
            suffix = Path(task["object"]).suffix
            with tempfile.TemporaryDirectory(prefix="tactile-kb-") as tmp:
                copy = os.path.join(tmp, "object" + suffix)
                with open(copy, "wb") as handle:
                    handle.write(data)
                try:
                    result = classify(
                        copy,
                        rules=kb,
                        explorer=opts["explorer"],
                        finger=finger,
                        noise=float(opts["noise"]),
                        seed=int(task["seed"]),
                    )
                except Exception as exc:
                    message = str(exc).replace(copy, task["object"])
                    return failed_row(task, type(exc).__name__, message, started, cpu_started=cpu)
        row = result.summary()
    except Exception as exc:  # any failure of one object is its row, never the batch's end
        message = str(exc) or type(exc).__name__
        name = task["object"]
        message = message if name in message else f"{name}: {message}"
        return failed_row(task, type(exc).__name__, message, started, cpu_started=cpu)
    return finish_row(task, row, started, cpu_started=cpu)


def resolve_work(work: str) -> Callable[[Task], Row]:
    module, _, name = work.partition(":")
    fn: Callable[[Task], Row] = getattr(importlib.import_module(module), name)
    return fn
