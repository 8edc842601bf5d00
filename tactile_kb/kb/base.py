"""The :class:`KnowledgeBase` facade: compiled data plus the functions over it.

:func:`~tactile_kb.kb.compiler.compile_rules` returns one. It is the compiled
:class:`~tactile_kb.kb.knowledge.Knowledge` with the engine (built on first use) and the
economy at hand, so ``kb.classify("1011011")`` reads as the paper does; every method is a
thin call into :mod:`~tactile_kb.kb.engine` or :mod:`~tactile_kb.kb.economy`, which never
import this module.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property
from typing import Any

import numpy as np

from tactile_kb.kb.economy import Economy, economy
from tactile_kb.kb.engine import Decision, Engine
from tactile_kb.kb.knowledge import Knowledge

__all__ = ["KnowledgeBase"]


class KnowledgeBase(Knowledge):
    """A compiled rule set with its engine: see :class:`~tactile_kb.kb.knowledge.Knowledge`."""

    @cached_property
    def engine(self) -> Engine:
        """The classification engine (built on first use)."""
        return Engine(self)

    def classify(self, assignment: Any) -> Decision:
        """Classify a full or partial assignment: a mapping id → bool, a bit string
        (``'1011011'``, ``-`` unknown) or a numpy bool array of shape (n,)."""
        return self.engine.classify(assignment)

    def classify_batch(self, assignments: Any) -> np.ndarray[Any, np.dtype[np.int16]]:
        """Class indices of an (m, n) bool array: ``len(classes)`` = otherwise, -1 = violates."""
        return self.engine.classify_batch(assignments)

    def decide(self, providers: Mapping[str, Any]) -> Decision:
        """Evaluate propositions lazily in phase order until one answer is left."""
        return self.engine.decide(providers)

    def economy(self) -> Economy:
        """Expected propositions evaluated (lazy phase order, optimal tree) and the bounds."""
        return economy(self)
