"""Bounded tables of computed values: the geometry's answers kept for the next model.

A completion probe adds a touch or two to the record, and the model is built again from the
start (:func:`tactile_kb.geometry.model.build_model`): the same groups of contacts are fitted
again and the same plane sets intersected again, with the same numbers. A :class:`Memo`
keeps such answers by the exact inputs that decide them (array bytes and the tolerances in
force), so a second computation of the same thing is a look-up and gives the identical value.

Examples
--------
>>> memo: Memo[str, int] = Memo(2)
>>> memo.get("a", lambda: 1), memo.get("a", lambda: 99)  # made once, then recalled
(1, 1)
>>> _ = memo.get("b", lambda: 2); _ = memo.get("c", lambda: 3)  # "a" is the oldest: dropped
>>> len(memo), memo.get("a", lambda: 4)
(2, 4)
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

__all__ = ["Memo"]

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")


class Memo(Generic[K, V]):
    """At most ``size`` values by key, the least recently used dropped first.

    A lock guards the table (a batch may run a timed-out task's thread beside the next one);
    the value is made outside it. Values are shared by every caller that asks for the same
    key: keep them immutable (read-only arrays, frozen dataclasses).
    """

    def __init__(self, size: int) -> None:
        self.size = size
        self._table: OrderedDict[K, V] = OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: K, make: Callable[[], V]) -> V:
        """The value kept for ``key``, or ``make()``'s, then kept."""
        with self._lock:
            if key in self._table:
                self._table.move_to_end(key)
                return self._table[key]
        value = make()
        with self._lock:
            self._table[key] = value
            while len(self._table) > self.size:
                self._table.popitem(last=False)
        return value

    def clear(self) -> None:
        """Forget every value."""
        with self._lock:
            self._table.clear()

    def __len__(self) -> int:
        return len(self._table)
