"""Dask: the tasks of a batch on a ``dask.distributed`` cluster, with a bounded number of
futures in flight."""

from __future__ import annotations

import contextlib
import importlib
import os
import threading
import time
from collections.abc import Generator, Iterator
from typing import Any

from tactile_kb.batch.inputs import Row, Task
from tactile_kb.batch.tasks import failed_row, resolve_work
from tactile_kb.errors import PluginUnavailableError


class _TaskTimeout(BaseException):
    """Raised inside an abandoned task thread to stop it."""


def _run_guarded(task: Task, work: str) -> Row:
    """Run ``work`` on ``task`` in a thread of its own; past the task's timeout give a Timeout row.

    Used on Dask workers, whose processes the driver cannot kill: the task thread is sent an
    exception to stop it at its next Python instruction.
    """
    fn = resolve_work(work)
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
    return failed_row(
        task,
        "Timeout",
        f"{task['object']}: not classified within {limit:g} s (the task was stopped)",
        started,
    )


def dask_results(
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
                row = failed_row(
                    task,
                    "WorkerLost",
                    f"{task['object']}: Dask workers died running it ({exc})",
                    started,
                )
            except Exception as exc:
                row = failed_row(task, type(exc).__name__, f"{task['object']}: {exc}", started)
            future.release()
            yield row
            submit()
    finally:  # a batch stopped early leaves nothing running on the cluster
        if pending:
            client.cancel([future for _, future in pending.values()])
        futures.clear()
