"""Who is watching an exploration: a context variable holding a callback, so that a terminal
can show the touches and the phase of a long exploration while it runs.

The controller asks :func:`current_watcher` after every motion and calls it; with nobody
watching (the default, and always inside libraries and workers) that is one context-variable
read. The callback must return at once: it runs in the exploring thread.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from contextvars import ContextVar

__all__ = ["Watcher", "current_watcher", "watching"]

Watcher = Callable[[str, int, int], None]
"""``watcher(phase, touches, motions)``: the phase of the servo cycle ("layers", "probe",
"top", "complete"…), the touches and the motions so far."""

_WATCHER: ContextVar[Watcher | None] = ContextVar("tactile_kb_watcher", default=None)


def current_watcher() -> Watcher | None:
    """The watcher of explorations run here, or None."""
    return _WATCHER.get()


@contextlib.contextmanager
def watching(watcher: Watcher) -> Iterator[None]:
    """Call ``watcher`` with the progress of every exploration run inside the block."""
    token = _WATCHER.set(watcher)
    try:
        yield
    finally:
        _WATCHER.reset(token)
