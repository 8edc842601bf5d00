"""Side by side: the analytic ``stepper`` and the ``mujoco`` explorer on the same objects.

For each object both explorers run with the same finger and seed; each record goes through the
same downstream chain (:func:`tactile_kb.geometry.model.build_model`, the features, the rules), and the
two models' planes are matched one to one (Hungarian assignment on normal angle and offset).

Examples
--------
>>> from tactile_kb import solids
>>> row = compare_object("CUBE", solids.box(0.06, 0.06, 0.06), finger="33")
>>> row.same_answer, row.planes[0] == row.planes[1], row.max_angle_deg < 0.01
(True, True, True)
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.optimize import linear_sum_assignment

from tactile_kb.errors import TactileKBError
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.explorers import Explorer, get_explorer
from tactile_kb.touch.finger import Finger

__all__ = [
    "ExplorerRun",
    "PlaneAgreement",
    "SideBySide",
    "compare_all",
    "compare_object",
    "match_planes",
]


@dataclass(frozen=True)
class PlaneAgreement:
    """How two models' planes agree after a one-to-one matching.

    ``matched`` pairs, the largest angle between matched normals (degrees) and the largest
    difference of matched offsets (metres); ``unmatched`` planes of either model are left over
    when the counts differ.
    """

    matched: int
    unmatched: int
    max_angle_deg: float
    max_offset: float


def match_planes(a: ObjectModel, b: ObjectModel) -> PlaneAgreement:
    """Match the faces of ``a`` and ``b`` one to one and measure their disagreement."""
    na = np.array([f.normal for f in a.faces], dtype=float).reshape(-1, 3)
    nb = np.array([f.normal for f in b.faces], dtype=float).reshape(-1, 3)
    oa = np.array([f.offset for f in a.faces], dtype=float)
    ob = np.array([f.offset for f in b.faces], dtype=float)
    if len(na) == 0 or len(nb) == 0:
        return PlaneAgreement(0, len(na) + len(nb), 0.0, 0.0)
    angle = np.degrees(np.arccos(np.clip(na @ nb.T, -1.0, 1.0)))
    offset = np.abs(oa[:, None] - ob[None, :])
    i, j = linear_sum_assignment(angle + 1e3 * offset)  # 1 mm weighs as 1°
    return PlaneAgreement(
        matched=len(i),
        unmatched=len(na) + len(nb) - 2 * len(i),
        max_angle_deg=float(angle[i, j].max()),
        max_offset=float(offset[i, j].max()),
    )


@dataclass(frozen=True)
class ExplorerRun:
    """One explorer's run on one object: the record, its model, its answer and its time.

    ``label`` is the class id (``"cube"``), ``answer`` the text (``"OBJECT IS A CUBE"``).
    """

    explorer: str
    record: ExplorationRecord
    model: ObjectModel
    label: str
    answer: str
    seconds: float

    @property
    def corners(self) -> tuple[int, ...]:
        """Corner count of each layer's contour polygon (non-convex explorations), bottom up."""
        return tuple(len(layer.contour) for layer in self.model.layers)


@dataclass(frozen=True)
class SideBySide:
    """Both explorers on one object, and how their models agree."""

    name: str
    finger: str
    runs: tuple[ExplorerRun, ExplorerRun]
    agreement: PlaneAgreement

    @property
    def same_answer(self) -> bool:
        """Whether both explorers' records are classified the same."""
        return (self.runs[0].label, self.runs[0].answer) == (
            self.runs[1].label,
            self.runs[1].answer,
        )

    @property
    def planes(self) -> tuple[int, int]:
        """Number of planes (faces) in each model."""
        return (len(self.runs[0].model.faces), len(self.runs[1].model.faces))

    @property
    def max_angle_deg(self) -> float:
        """Largest angle between matched planes, degrees."""
        return self.agreement.max_angle_deg

    @property
    def max_offset(self) -> float:
        """Largest offset difference between matched planes, metres."""
        return self.agreement.max_offset


def _default_answer(
    record: ExplorationRecord, model: ObjectModel, *, rules: str = "parallelepipeds"
) -> tuple[str, str]:
    """The pipeline's ``(label, answer)`` for ``record`` with ``rules`` (an error's text for
    both when it cannot classify)."""
    from tactile_kb.pipeline import classify_record

    try:
        decision = classify_record(record, rules=rules).decision
    except TactileKBError as exc:
        text = f"{type(exc).__name__}: {exc}"
        return text, text
    return str(decision.label), str(decision.answer)


def compare_object(
    name: str,
    mesh: trimesh.Trimesh,
    *,
    finger: Finger | str = "33",
    seed: int = 0,
    explorers: Sequence[str | Explorer] = ("stepper", "mujoco"),
    rules: str = "parallelepipeds",
    answer: Callable[[ExplorationRecord, ObjectModel], tuple[str, str]] | None = None,
) -> SideBySide:
    """Explore ``mesh`` with both ``explorers``, classify both records, match their planes.

    ``answer`` maps a record and its model to ``(label, answer)`` (default: the pipeline's
    decision, :func:`tactile_kb.pipeline.classify_record`, with ``rules``).
    """
    classify = answer or functools.partial(_default_answer, rules=rules)
    runs = []
    for spec in explorers:
        explorer = get_explorer(spec)
        t0 = time.perf_counter()
        record = explorer.explore(mesh, finger=finger, seed=seed)
        seconds = time.perf_counter() - t0
        model = build_model(record)
        label, text = classify(record, model)
        runs.append(
            ExplorerRun(
                explorer=explorer.name,
                record=record,
                model=model,
                label=label,
                answer=text,
                seconds=seconds,
            )
        )
    first, second = runs
    return SideBySide(
        name=name,
        finger=finger if isinstance(finger, str) else finger.name,
        runs=(first, second),
        agreement=match_planes(first.model, second.model),
    )


def compare_all(
    objects: Iterable[tuple[str, trimesh.Trimesh, str]], *, seed: int = 0
) -> list[SideBySide]:
    """:func:`compare_object` for each ``(name, mesh, finger)``."""
    return [compare_object(name, mesh, finger=finger, seed=seed) for name, mesh, finger in objects]
