"""Local workers: one ``multiprocessing`` process per task slot, each with the next task
waiting in its pipe; a crash, a kill or a timeout becomes an error row and a fresh process."""

from __future__ import annotations

import collections
import contextlib
import socket
import time
from collections.abc import Generator, Iterator
from typing import Any

from tactile_kb.batch.inputs import Row, Task
from tactile_kb.batch.tasks import failed_row, resolve_work


def _worker_main(conn: Any, work: str) -> None:  # pragma: no cover - runs in a child process
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    fn = resolve_work(work)
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


def local_results(
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
                    yield failed_row(
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
                    yield failed_row(
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
