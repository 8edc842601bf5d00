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

import collections
import contextlib
import csv
import glob
import hashlib
import importlib
import io
import json
import os
import socket
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable, Generator, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tactile_kb.errors import PluginUnavailableError, Problem, SourceError, UsageError

__all__ = [
    "MANIFEST_SUFFIXES",
    "ROW_OPTIONS",
    "TRANSIENT_ERRORS",
    "BatchItem",
    "BatchSummary",
    "classify_many",
    "error_summary",
    "expand_inputs",
    "parse_seeds",
    "read_results",
    "run_batch",
    "run_task",
]

Row = dict[str, Any]
Task = dict[str, Any]

MANIFEST_SUFFIXES = (".csv", ".jsonl", ".ndjson")
"""Files read as manifests (a ``path`` column, optionally ``label`` and :data:`ROW_OPTIONS`)."""

ROW_OPTIONS = ("rules", "explorer", "finger", "noise", "seeds", "timeout")
"""The per-object options a manifest row may set (an empty cell keeps the batch's)."""

TRANSIENT_ERRORS = frozenset({"WorkerLost"})
"""Error kinds that ``resume`` runs again: the worker was lost (killed, crashed), which says
nothing about the object. Every other row, errors included, counts as done."""

_DEFAULT_WORK = "tactile_kb.batch:run_task"


# --- inputs -------------------------------------------------------------------------------------


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


# --- tasks --------------------------------------------------------------------------------------


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


def _tasks(
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


def _finish_row(
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


def _failed(
    task: Task,
    kind: str,
    message: str,
    started: float,
    *,
    cpu_started: float | None = None,
    worker: str | None = None,
) -> Row:
    row = error_summary(task["object"], kind, message)
    return _finish_row(task, row, started, cpu_started=cpu_started, worker=worker)


_FINGERS: dict[str, Any] = {}


def run_task(task: Task) -> Row:
    """Classify one (object, seed) task in this process; every failure becomes an error row.

    This is what a worker runs: a local worker process or a Dask worker thread.
    """
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
                    return _failed(task, type(exc).__name__, message, started, cpu_started=cpu)
        row = result.summary()
    except Exception as exc:  # any failure of one object is its row, never the batch's end
        message = str(exc) or type(exc).__name__
        name = task["object"]
        message = message if name in message else f"{name}: {message}"
        return _failed(task, type(exc).__name__, message, started, cpu_started=cpu)
    return _finish_row(task, row, started, cpu_started=cpu)


def _resolve(work: str) -> Callable[[Task], Row]:
    module, _, name = work.partition(":")
    fn: Callable[[Task], Row] = getattr(importlib.import_module(module), name)
    return fn


# --- local workers ------------------------------------------------------------------------------


def _worker_main(conn: Any, work: str) -> None:  # pragma: no cover - runs in a child process
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    fn = _resolve(work)
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            return
        if task is None:
            return
        conn.send(fn(task))


@contextlib.contextmanager
def _without_main(work: str) -> Iterator[None]:
    """Start workers without the driver's main script.

    A new worker of the spawn and fork-server kinds re-runs the driver's ``__main__`` (by path
    or module name) before it starts: a script without an ``if __name__ == "__main__":`` guard
    would run again in every worker, and a script read from stdin cannot be found at all. The
    workers run only library code, so ``__main__`` is hidden from them while they start (unless
    the work function itself lives there).
    """
    import sys

    main = sys.modules.get("__main__")
    if main is None or work.startswith("__main__:"):
        yield
        return
    saved: dict[str, Any] = {
        name: main.__dict__[name] for name in ("__file__", "__spec__") if name in main.__dict__
    }
    main.__dict__.pop("__file__", None)
    main.__dict__["__spec__"] = None  # as for `python -c`
    try:
        yield
    finally:
        main.__dict__.update(saved)


class _Slot:
    """One local worker process and the tasks sent to it, the first one running."""

    def __init__(self, ctx: Any, work: str) -> None:
        parent, child = ctx.Pipe()
        self.process = ctx.Process(target=_worker_main, args=(child, work), daemon=True)
        with _without_main(work):
            self.process.start()
        child.close()
        self.conn = parent
        self.tasks: collections.deque[Task] = collections.deque()
        self.started = 0.0
        """When the first task started (when the one before it finished)."""
        self.name = f"{socket.gethostname()}:{self.process.pid}"

    def send(self, task: Task) -> None:
        self.conn.send(task)
        if not self.tasks:
            self.started = time.perf_counter()
        self.tasks.append(task)

    def done(self) -> Task:
        self.started = time.perf_counter()
        return self.tasks.popleft()

    def stop(self, *, kill: bool = False) -> None:
        if kill:
            self.process.kill()
        else:
            try:
                self.conn.send(None)
            except OSError:
                self.process.kill()
        self.process.join(timeout=5)
        if self.process.is_alive():  # pragma: no cover - a worker that ignores the stop
            self.process.kill()
            self.process.join()
        self.conn.close()


def _mp_context() -> Any:
    import multiprocessing

    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        # Workers fork from a server that has imported the pipeline once: no start-up per worker.
        ctx.set_forkserver_preload(["tactile_kb.pipeline"])
        return ctx
    return multiprocessing.get_context("spawn")  # pragma: no cover - Windows


def _local_results(
    tasks: Iterator[Task], workers: int, work: str, depth: int = 2
) -> Generator[Row, None, None]:
    """Run ``tasks`` on ``workers`` processes, each sent up to ``depth`` tasks ahead.

    The second task waits in the worker's pipe, so that a worker never idles while the driver
    writes a row. When a worker dies or is stopped, its running task is an error row and the
    tasks queued behind it go to the other workers.
    """
    from multiprocessing.connection import wait

    ctx = _mp_context()
    slots: list[_Slot] = []
    retry: collections.deque[Task] = collections.deque()
    exhausted = False

    def next_task() -> Task | None:
        nonlocal exhausted
        if retry:
            return retry.popleft()
        if exhausted:
            return None
        task = next(tasks, None)
        exhausted = task is None
        return task

    def drop(slot: _Slot) -> Task:
        """Stop ``slot``'s process; return its running task, requeue the others."""
        slots.remove(slot)
        slot.stop(kill=True)
        running = slot.tasks.popleft()
        retry.extendleft(reversed(slot.tasks))
        return running

    try:
        while True:
            while True:  # fill: a new worker while there are fewer than asked, then queues
                if len(slots) < workers and all(slot.tasks for slot in slots):
                    target = None
                else:
                    target = min(slots, key=lambda slot: len(slot.tasks), default=None)
                    if target is not None and len(target.tasks) >= depth:
                        break
                task = next_task()
                if task is None:
                    break
                if target is None:
                    target = _Slot(ctx, work)
                    slots.append(target)
                try:
                    target.send(task)
                except OSError:  # the worker was killed while it waited: a fresh one
                    retry.extendleft(reversed(target.tasks))
                    retry.appendleft(task)
                    slots.remove(target)
                    target.stop(kill=True)
            busy = [slot for slot in slots if slot.tasks]
            if not busy:
                return
            now = time.perf_counter()
            deadlines = [
                slot.started + slot.tasks[0]["timeout"] - now
                for slot in busy
                if slot.tasks[0].get("timeout")
            ]
            wait_for = max(0.0, min(deadlines)) if deadlines else None
            handles = [slot.conn for slot in busy] + [slot.process.sentinel for slot in busy]
            ready = set(wait(handles, wait_for))
            for slot in busy:
                if slot.conn in ready or slot.process.sentinel in ready:
                    row: Row | None = None
                    try:
                        if slot.conn.poll():
                            row = slot.conn.recv()
                    except (EOFError, OSError):
                        row = None
                    if row is not None:
                        slot.done()
                        yield row
                        continue
                    slot.process.join(timeout=1)  # the process ended without an answer
                    code = slot.process.exitcode
                    task = drop(slot)
                    how = f"killed by signal {-code}" if code and code < 0 else f"exit code {code}"
                    yield _failed(
                        task,
                        "WorkerLost",
                        f"{task['object']}: the worker process ended while classifying it ({how})",
                        slot.started,
                        worker=slot.name,
                    )
                    continue
                limit = slot.tasks[0].get("timeout")
                if limit and time.perf_counter() - slot.started >= limit:
                    task = drop(slot)
                    yield _failed(
                        task,
                        "Timeout",
                        f"{task['object']}: not classified within {limit:g} s "
                        "(the worker was stopped)",
                        slot.started,
                        worker=slot.name,
                    )
    finally:
        for slot in slots:
            slot.stop(kill=bool(slot.tasks))


# --- Dask ---------------------------------------------------------------------------------------


class _TaskTimeout(BaseException):
    """Raised inside an abandoned task thread to stop it."""


def _run_guarded(task: Task, work: str) -> Row:
    """Run ``work`` on ``task`` in a thread of its own; past the task's timeout give a Timeout row.

    Used on Dask workers, whose processes the driver cannot kill: the task thread is sent an
    exception to stop it at its next Python instruction.
    """
    fn = _resolve(work)
    limit = task.get("timeout")
    if not limit:
        return fn(task)
    started = time.perf_counter()
    box: list[Row] = []

    def target() -> None:
        with contextlib.suppress(_TaskTimeout):
            box.append(fn(task))

    thread = threading.Thread(target=target, name="tactile-kb-task", daemon=True)
    thread.start()
    thread.join(limit)
    if box:
        return box[0]
    if thread.ident is not None and thread.is_alive():
        import ctypes

        ctypes.pythonapi.PyThreadState_SetAsyncExc(
            ctypes.c_ulong(thread.ident), ctypes.py_object(_TaskTimeout)
        )
    return _failed(
        task,
        "Timeout",
        f"{task['object']}: not classified within {limit:g} s (the task was stopped)",
        started,
    )


def _dask_results(
    tasks: Iterator[Task], client: Any, work: str, in_flight: int | None
) -> Generator[Row, None, None]:
    try:
        distributed: Any = importlib.import_module("distributed")
    except ImportError:  # pragma: no cover - the client came from somewhere
        raise PluginUnavailableError(
            "dask", "pip install 'tactile-kb[dask]'", "distributed is not installed"
        ) from None
    limit = in_flight or max(2, 2 * sum(client.nthreads().values()))
    run = f"tactile-kb-{os.getpid()}-{time.time_ns()}"
    pending: dict[str, tuple[Task, Any]] = {}
    futures = distributed.as_completed(loop=client.loop)

    def submit() -> bool:
        task = next(tasks, None)
        if task is None:
            return False
        key = f"{run}-{task['index']}"
        future = client.submit(_run_guarded, task, work, key=key, retries=0)
        pending[key] = (task, future)
        futures.add(future)
        return True

    try:
        for _ in range(limit):
            if not submit():
                break
        for future in futures:
            task, _ = pending.pop(future.key)
            started = time.perf_counter()
            try:
                row: Row = future.result()
            except distributed.KilledWorker as exc:
                row = _failed(
                    task,
                    "WorkerLost",
                    f"{task['object']}: Dask workers died running it ({exc})",
                    started,
                )
            except Exception as exc:
                row = _failed(task, type(exc).__name__, f"{task['object']}: {exc}", started)
            future.release()
            yield row
            submit()
    finally:  # a batch stopped early leaves nothing running on the cluster
        if pending:
            client.cancel([future for _, future in pending.values()])
        futures.clear()


# --- the batch ----------------------------------------------------------------------------------


def _defaults(
    rules: str,
    explorer: str,
    finger: str,
    noise: float,
    seeds: Iterable[int],
    timeout: float | None,
) -> dict[str, Any]:
    if not isinstance(explorer, str) or not isinstance(finger, str) or not isinstance(rules, str):
        raise UsageError(
            "a batch sends its options to other processes: give rules, explorer and finger by "
            "name or file path"
        )
    if noise < 0:
        raise UsageError(f"noise must be ≥ 0 metres, got {noise}")
    seed_list = tuple(int(s) for s in seeds)
    if not seed_list or any(s < 0 for s in seed_list):
        raise UsageError(f"seeds must be one or more whole numbers ≥ 0, got {seed_list}")
    if timeout is not None and not timeout > 0:
        raise UsageError(f"timeout must be > 0 seconds, got {timeout}")
    return {
        "rules": str(rules),
        "explorer": explorer,
        "finger": str(finger),
        "noise": float(noise),
        "seeds": seed_list,
        "timeout": timeout,
    }


def _check_options(items: Sequence[BatchItem], defaults: Mapping[str, Any]) -> None:
    """Load every distinct rule set, finger and explorer once, before any object is touched."""
    from tactile_kb.pipeline import knowledge_base
    from tactile_kb.touch.explorers import get_explorer
    from tactile_kb.touch.finger import load_finger

    seen: set[tuple[str, str]] = set()
    for opts in [defaults, *(item.options for item in items)]:
        for name, check in (
            ("rules", knowledge_base),
            ("finger", load_finger),
            ("explorer", get_explorer),
        ):
            if name in opts and (name, str(opts[name])) not in seen:
                seen.add((name, str(opts[name])))
                check(str(opts[name]))


def classify_many(
    inputs: Iterable[str | Path | BatchItem],
    *,
    rules: str = "parallelepipeds",
    explorer: str = "stepper",
    finger: str = "33",
    noise: float = 0.0,
    seeds: Iterable[int] = (0,),
    timeout: float | None = None,
    workers: int | None = None,
    client: Any = None,
    ship: bool = False,
    skip: Callable[[str], bool] | None = None,
    in_flight: int | None = None,
    _work: str = _DEFAULT_WORK,
    _on_skip: Callable[[Task], None] | None = None,
    _index_of: dict[str, int] | None = None,
) -> Generator[Row, None, None]:
    """Classify every object of ``inputs`` once per seed; yield each result row as it finishes.

    Parameters
    ----------
    inputs
        Mesh files, folders, globs, CSV/JSONL manifests or :class:`BatchItem` values
        (:func:`expand_inputs`).
    rules, explorer, finger, noise
        As for :func:`~tactile_kb.pipeline.classify`, by name or file path; a manifest row may
        override them.
    seeds
        One task per seed and object; the same seed gives the same answer on any worker.
    timeout
        Seconds one task may take; past it the task is an error row of kind ``Timeout``.
    workers
        Local worker processes (default: the core count). Ignored with ``client``.
    client
        A ``dask.distributed.Client``: the tasks run on its cluster.
    ship
        Send each mesh's bytes with its task (for Dask workers that do not share the
        driver's filesystem).
    skip
        Called with each task's key; tasks it accepts are not run (``run_batch``'s resume).
    in_flight
        With ``client``: at most this many tasks submitted and unfinished (default: twice
        the cluster's threads). Local workers hold two tasks each.

    The inputs and everything shared by the objects (rule files, fingers, explorers) are
    checked when this is called, before any task starts; a problem raises here. The rows come
    in the order tasks finish; their ``index`` gives the input order.
    """
    defaults = _defaults(rules, explorer, finger, noise, seeds, timeout)
    count = workers if workers is not None else (os.cpu_count() or 1)
    if count < 1:
        raise UsageError(f"workers must be ≥ 1, got {count}")
    items = expand_inputs(inputs)
    _check_options(items, defaults)
    tasks = _tasks(
        items,
        defaults,
        ship=ship,
        skip=skip or (lambda key: False),
        on_skip=_on_skip,
        index_of=_index_of,
    )
    if client is not None:
        return _dask_results(tasks, client, _work, in_flight)
    return _local_results(tasks, count, _work)


# --- results files ------------------------------------------------------------------------------


def _stream_path(out: Path) -> Path:
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


def _prepare_stream(path: Path) -> set[str]:
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


class _Appender:
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
    stream = _stream_path(p)
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


def _finish(stream: Path, out: Path, index_of: Mapping[str, int], summary: BatchSummary) -> None:
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


# --- summary ------------------------------------------------------------------------------------


@dataclass
class BatchSummary:
    """Counts over result rows: answers, errors per kind, and expected × answered labels."""

    rows: int = 0
    answers: Counter[str] = field(default_factory=Counter)
    errors: Counter[str] = field(default_factory=Counter)
    confusion: Counter[tuple[str, str]] = field(default_factory=Counter)
    """(expected label, answered label or ``"error"``) → count, for rows with a label."""

    def add(self, row: Mapping[str, Any]) -> None:
        """Count one row."""
        self.rows += 1
        error = row.get("error")
        if isinstance(error, dict):
            self.errors[str(error.get("kind"))] += 1
            answered = "error"
        else:
            self.answers[str(row.get("answer"))] += 1
            answered = str(row.get("label"))
        expected = row.get("expected")
        if expected is not None:
            self.confusion[(str(expected), answered)] += 1

    @property
    def labelled(self) -> bool:
        """Whether any row carried an expected label."""
        return bool(self.confusion)

    def classes(self) -> tuple[list[str], list[str]]:
        """The expected labels (rows) and the answered labels (columns; ``error`` last)."""
        expected = sorted({e for e, _ in self.confusion})
        answered = sorted({a for _, a in self.confusion if a != "error"} | set(expected))
        if any(a == "error" for _, a in self.confusion):
            answered.append("error")
        return expected, answered

    def accuracy(self) -> dict[str, tuple[int, int]]:
        """Per expected label: (answered right, total)."""
        out: dict[str, tuple[int, int]] = {}
        for (expected, answered), n in self.confusion.items():
            right, total = out.get(expected, (0, 0))
            out[expected] = (right + (n if answered == expected else 0), total + n)
        return dict(sorted(out.items()))

    def lines(self) -> list[str]:
        """The summary as text lines: counts, answers, errors, confusion matrix, accuracy."""
        errors = sum(self.errors.values())
        out = [f"{self.rows} results: {self.rows - errors} answered, {errors} failed"]
        if self.answers:
            out.append("answers:")
            width = max(len(a) for a in self.answers)
            out += [f"  {a:<{width}}  {n:>6}" for a, n in sorted(self.answers.items())]
        if self.errors:
            out.append("errors:")
            width = max(len(k) for k in self.errors)
            out += [f"  {k:<{width}}  {n:>6}" for k, n in sorted(self.errors.items())]
        if self.labelled:
            expected, answered = self.classes()
            head = max(len("expected"), *(len(e) for e in expected))
            widths = [max(len(a), 3) for a in answered]
            out.append("confusion matrix (rows: expected label, columns: answered label):")
            out.append(
                "  "
                + " " * head
                + "".join(f"  {a:>{w}}" for a, w in zip(answered, widths, strict=True))
            )
            for e in expected:
                cells = "".join(
                    f"  {self.confusion.get((e, a), 0):>{w}}"
                    for a, w in zip(answered, widths, strict=True)
                )
                out.append(f"  {e:<{head}}{cells}")
            out.append("accuracy per class:")
            right_all = total_all = 0
            for e, (right, total) in self.accuracy().items():
                right_all += right
                total_all += total
                out.append(f"  {e:<{head}}  {right:>6} of {total:<6} {100 * right / total:5.1f} %")
            out.append(
                f"  {'all':<{head}}  {right_all:>6} of {total_all:<6} "
                f"{100 * right_all / total_all:5.1f} %"
            )
        return out

    def plot_confusion(self, path: str | Path | io.BytesIO) -> None:
        """Draw the confusion matrix (counts, each row shaded by its share) to a PNG or SVG."""
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
        import numpy as np

        expected, answered = self.classes()
        counts = np.array(
            [[self.confusion.get((e, a), 0) for a in answered] for e in expected], dtype=float
        )
        share = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
        width = max(6.0, 2.5 + 1.0 * len(answered) + 0.09 * max(len(e) for e in expected))
        height = max(3.5, 1.8 + 0.6 * len(expected) + 0.07 * max(len(a) for a in answered))
        fig, ax = plt.subplots(figsize=(width, height), dpi=120)
        try:
            image = ax.imshow(share, cmap="Blues", vmin=0, vmax=1, aspect="auto")
            bar = fig.colorbar(image, ax=ax, fraction=0.05, pad=0.03)
            bar.set_label("share of the row", fontsize=10)
            for i in range(len(expected)):
                for j in range(len(answered)):
                    n = int(counts[i, j])
                    if n:
                        ax.text(
                            j,
                            i,
                            str(n),
                            ha="center",
                            va="center",
                            fontsize=11,
                            color="white" if share[i, j] > 0.6 else "black",
                        )
            ax.set_xticks(range(len(answered)), answered, rotation=35, ha="right", fontsize=10)
            ax.set_yticks(range(len(expected)), expected, fontsize=10)
            ax.set_xlabel("answered label", fontsize=11)
            ax.set_ylabel("expected label", fontsize=11)
            right = sum(r for r, _ in self.accuracy().values())
            total = sum(t for _, t in self.accuracy().values())
            ax.set_title(
                f"Confusion matrix: {right} of {total} right ({100 * right / total:.1f} %)",
                fontsize=12,
            )
            fig.tight_layout()
            fig.savefig(path, format="png" if isinstance(path, io.BytesIO) else None)
        finally:
            plt.close(fig)

    def write_report(self, path: str | Path, *, title: str = "tactile-kb batch") -> None:
        """A Markdown or HTML report (by the suffix) with the matrix drawn beside it.

        Markdown links a PNG written next to it (``NAME-confusion.png``); HTML embeds it.
        """
        import base64
        import html

        p = Path(path)
        text = "\n".join(self.lines())
        if p.suffix.lower() in (".html", ".htm"):
            image = ""
            if self.labelled:
                buffer = io.BytesIO()
                self.plot_confusion(buffer)
                data = base64.b64encode(buffer.getvalue()).decode("ascii")
                image = f'<img alt="confusion matrix" src="data:image/png;base64,{data}">\n'
            body = (
                f'<!doctype html>\n<html><head><meta charset="utf-8"><title>{html.escape(title)}'
                f"</title></head><body>\n<h1>{html.escape(title)}</h1>\n{image}"
                f"<pre>{html.escape(text)}</pre>\n</body></html>\n"
            )
        else:
            image = ""
            if self.labelled:
                picture = p.with_name(p.stem + "-confusion.png")
                self.plot_confusion(picture)
                image = f"![confusion matrix]({picture.name})\n\n"
            body = f"# {title}\n\n{image}```text\n{text}\n```\n"
        p.write_text(body, encoding="utf-8")


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
    stream = _stream_path(path)
    done = _prepare_stream(stream) if resume else set()
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
    appender: _Appender | None = None
    try:
        for row in rows:
            if appender is None:
                appender = _Appender(stream)
            appender.write(row)
            if on_row is not None:
                on_row(row)
    finally:
        rows.close()
        if appender is not None:
            appender.close()
    summary = BatchSummary()
    if stream.exists():
        _finish(stream, path, index_of, summary)
    return summary
