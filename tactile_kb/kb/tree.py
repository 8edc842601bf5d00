"""The choice tree of a compiled rule set (the paper's Fig. 3), as data.

Phase by phase, the tree branches on the values of the phase's propositions that stay
consistent with r(L), and stops as soon as one class remains; a phase whose values cannot
change the answer is passed through without branching. :func:`tactile_kb.plot.plot_tree`
draws it.

Examples
--------
>>> from tactile_kb.kb.compiler import compile_rules
>>> root = choice_tree(compile_rules("parallelepipeds"))
>>> root.leaves, root.count
(14, 97)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tactile_kb.kb.base import KnowledgeBase

__all__ = ["TREE_MINTERM_LIMIT", "TreeNode", "choice_tree"]

TREE_MINTERM_LIMIT = 1 << 14
"""Rule sets with more members of r(L) than this get no tree (it would not be legible)."""


@dataclass
class TreeNode:
    """A node of the choice tree: the values decided so far and what follows.

    ``values`` are the values of the phase that led here (empty at the root); a leaf has a
    ``label`` (a class id, or the rule set's otherwise id) and ``answer``.
    """

    phase: int
    values: tuple[tuple[str, bool], ...] = ()
    children: list[TreeNode] = field(default_factory=list)
    label: str | None = None
    answer: str = ""
    count: int = 0
    y: float = 0.0

    @property
    def leaves(self) -> int:
        """Number of leaves below (1 for a leaf)."""
        return 1 if not self.children else sum(c.leaves for c in self.children)


def _labels(kb: KnowledgeBase) -> tuple[list[str], list[str]]:
    ids = [c.id for c in kb.classes] + [kb.rules.otherwise_id]
    answers = [c.answer for c in kb.classes] + [kb.rules.otherwise_answer]
    return ids, answers


def choice_tree(kb: KnowledgeBase) -> TreeNode | None:
    """The lazy choice tree of ``kb``: phase by phase, branching on the values consistent with
    r(L), stopping as soon as one class remains. None when r(L) is too large to enumerate."""
    if kb.r_count > TREE_MINTERM_LIMIT:
        return None
    terms = list(kb.minterms())
    ids, answers = _labels(kb)
    root = TreeNode(phase=-1, count=len(terms))
    if not terms:
        return root
    arr = np.array([[ch == "1" for ch in t] for t in terms], dtype=bool)
    cls = kb.classify_batch(arr)
    order = {name: i for i, name in enumerate(kb.ids)}
    phases = [[order[p] for p in ph.propositions] for ph in kb.rules.phases]

    def grow(node: TreeNode, rows: np.ndarray[Any, np.dtype[np.intp]], depth: int) -> None:
        labels = set(cls[rows].tolist())
        if len(labels) == 1 or depth >= len(phases):
            k = int(cls[rows[0]])
            node.label = ids[k] if 0 <= k < len(ids) else "inconsistent"
            node.answer = answers[k] if 0 <= k < len(answers) else ""
            if len(labels) > 1:
                node.label, node.answer = "mixed", "MORE THAN ONE ANSWER"
            return
        cols = phases[depth]
        if not _matters(arr[rows], cls[rows], cols):
            # the answer does not depend on this phase here: pass through without branching
            child = TreeNode(phase=depth, values=(), count=len(rows))
            node.children.append(child)
            grow(child, rows, depth + 1)
            return
        keys = {tuple(bool(v) for v in arr[r, cols]) for r in rows}
        for key in sorted(keys, reverse=True):
            sel = rows[np.all(arr[rows][:, cols] == np.asarray(key, dtype=bool), axis=1)]
            child = TreeNode(
                phase=depth,
                values=tuple((kb.ids[c], v) for c, v in zip(cols, key, strict=True)),
                count=len(sel),
            )
            node.children.append(child)
            grow(child, sel, depth + 1)

    grow(root, np.arange(len(terms)), 0)
    return root


def _matters(
    rows: np.ndarray[Any, np.dtype[np.bool_]],
    labels: np.ndarray[Any, np.dtype[Any]],
    cols: Sequence[int],
) -> bool:
    """Whether branching on the columns ``cols`` tells anything among these minterms.

    It does not when every value of the phase leaves the same completions (the other
    columns) and the answer is a function of those completions alone.
    """
    drop = set(cols)
    keep = [c for c in range(rows.shape[1]) if c not in drop]
    seen: dict[bytes, int] = {}
    groups: dict[bytes, set[bytes]] = {}
    for full, rest, label in zip(rows[:, list(cols)], rows[:, keep], labels.tolist(), strict=True):
        key = np.packbits(rest).tobytes()
        if seen.setdefault(key, label) != label:
            return True
        groups.setdefault(np.packbits(full).tobytes(), set()).add(key)
    completions = list(groups.values())
    return any(c != completions[0] for c in completions[1:])
