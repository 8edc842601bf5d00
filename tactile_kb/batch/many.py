"""Many objects classified: the options checked once, the tasks made, and the rows yielded
as local workers or a Dask cluster finish them (:func:`classify_many`)."""

from __future__ import annotations

import os
from collections.abc import Callable, Generator, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from tactile_kb.batch.cluster import dask_results
from tactile_kb.batch.inputs import BatchItem, Row, Task, expand_inputs
from tactile_kb.batch.local import local_results
from tactile_kb.batch.tasks import DEFAULT_WORK, make_tasks
from tactile_kb.errors import UsageError


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
    _work: str = DEFAULT_WORK,
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
    tasks = make_tasks(
        items,
        defaults,
        ship=ship,
        skip=skip or (lambda key: False),
        on_skip=_on_skip,
        index_of=_index_of,
    )
    if client is not None:
        return dask_results(tasks, client, _work, in_flight)
    return local_results(tasks, count, _work)
