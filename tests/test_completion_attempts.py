"""The completion's second attempts: another end of a face, never the same approach twice, and
an open side approached where the object surely is.

* A face touched along one horizontal line (an undercut side met by the vertical finger's
  equator) is probed at another height. When that attempt touches something else (the model's
  outline of the face reaches into a neighbour), the second goes to the end of the face
  farthest from it, not to the same spot again.
* With exact contacts, an approach asked for again the same way (same item, same point within
  ρ/10, same direction within 1°) would touch what it touched before: it counts as tried and
  the next item goes instead. (Under noise it is another sample of the spot, and is made.) A hexagonal pyramid lying on a side asked for two such repeats in four of its
  turns, a large lying hexagonal frustum in every turn; its completion then ran out of touches
  (``benchmarks/bench_poses.py``, seed 1, the only exact miss).
* An L block lying on the ends of its arms (an upturned V) is open at its back. The first
  probe, aimed at the middle of the hint box, passes through the notch between the arms; the
  second approaches in line with a point touched on its front face, behind which the block is
  solid.

The truth is the solid's class, the stable pose's contact with the table, and the probes as
asked (plain values).
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.completion import ModelCompleter
from tactile_kb.pipeline import classify
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.servo import Ending, Probe
from tactile_kb.touch.stepper import StepperExplorer

RHO = builtin_finger("33").radius


class _Logged(ModelCompleter):
    """The model-driven completion, keeping the probes it asks for."""

    asked: ClassVar[list[Probe]] = []

    def next_probe(
        self, record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe | Ending:
        probe = super().next_probe(record, last)
        if isinstance(probe, Probe):
            _Logged.asked.append(probe)
        return probe


def _repeats(probes: list[Probe]) -> int:
    """How many probes approach a point asked for before, for the same item, the same way."""
    count = 0
    for i, p in enumerate(probes):
        for q in probes[:i]:
            if (
                p.reason == q.reason
                and math.dist(p.target, q.target) < 0.1 * RHO
                and float(np.dot(p.normal, q.normal)) > math.cos(math.radians(1.0))
            ):
                count += 1
                break
    return count


def _on_a_side(mesh: trimesh.Trimesh, turn: float) -> trimesh.Trimesh:
    side = next(n for n in np.unique(np.round(mesh.face_normals, 4), axis=0) if abs(n[2]) < 0.99)
    return solids.rotate_about_z(solids.rest_on_face(mesh, tuple(side)), turn)


@pytest.mark.parametrize(
    ("mesh", "turn", "label"),
    [
        (solids.pyramid(6, 0.0438, 0.061), 135.0, "pyramid"),
        (solids.pyramid(6, 0.0438, 0.061), 315.0, "pyramid"),
        (solids.frustum(6, 0.1348, 0.0773, 0.2408), 45.0, "frustum"),
    ],
)
def test_no_approach_is_asked_twice(mesh: trimesh.Trimesh, turn: float, label: str) -> None:
    posed = _on_a_side(mesh, turn)
    assert posed.bounds[0, 2] == pytest.approx(0.0, abs=1e-9)
    _Logged.asked = []
    explorer = StepperExplorer()
    explorer.completer = _Logged
    result = classify(posed, rules="polyhedra", finger=builtin_finger("33"), explorer=explorer)
    assert _Logged.asked, "the completion asked for no probe: the case tests nothing"
    assert _repeats(_Logged.asked) == 0
    assert result.decision.label == label


def _probe(
    z: float, reason: str = "the face facing (+1.0, +0.0, +0.0) touched at one height"
) -> Probe:
    return Probe((0.03, 0.0, z), (1.0, 0.0, 0.0), 4 * RHO, reason)


def _record() -> ExplorationRecord:
    return classify(solids.box(0.06, 0.05, 0.04), rules="polyhedra").record


def test_the_second_attempt_goes_to_the_face_s_other_end() -> None:
    """The first attempt went to z = 37 mm and touched; the model now offers the ends at
    37.5 mm and 7.5 mm: the second goes to 7.5 mm."""
    completer = ModelCompleter()
    first = _probe(0.037)
    completer._asked[first.reason] = [first]
    completer._tried[first.reason] = 1
    todo = [_probe(0.0375), _probe(0.0075)]
    assert completer._choose(todo, _record(), (first, True)).target[2] == pytest.approx(0.0075)


def test_after_another_item_s_probe_the_first_end_stays() -> None:
    """The last probe was for another item (a blind contact): the face's ends are as the
    model orders them, the farther first."""
    completer = ModelCompleter()
    first = _probe(0.037)
    completer._asked[first.reason] = [first]
    completer._tried[first.reason] = 1
    other = _probe(0.02, reason="a blind contact at (+30.0, +0.0, +20.0) mm")
    todo = [_probe(0.0375), _probe(0.0075)]
    assert completer._choose(todo, _record(), (other, True)).target[2] == pytest.approx(0.0375)


def test_an_approach_asked_before_is_recognised() -> None:
    completer = ModelCompleter()
    first = _probe(0.037)
    completer._asked[first.reason] = [first]
    assert completer._asked_before(_probe(0.037 + 0.05 * RHO), RHO)
    assert not completer._asked_before(_probe(0.037 + 0.2 * RHO), RHO)
    turned = Probe(first.target, (math.cos(0.05), math.sin(0.05), 0.0), first.reach, first.reason)
    assert not completer._asked_before(turned, RHO)  # 2.9° off: another approach


def _on_its_arms() -> trimesh.Trimesh:
    """An L block in the stable pose where it rests on the far ends of its two arms."""
    block = solids.l_shape(0.111, 0.1127, 0.0352, 0.0223)
    for posed, _ in solids.stable_poses(block):
        low = posed.vertices[np.abs(posed.vertices[:, 2]) < 1e-9]
        if len(low) == 4 and np.ptp(low[:, 0]) > 0.05 and np.ptp(low[:, 1]) < 0.05:
            return posed
        if len(low) == 4 and np.ptp(low[:, 1]) > 0.05 and np.ptp(low[:, 0]) < 0.05:
            return posed
    raise AssertionError("no pose on the ends of both arms")


def test_an_l_block_on_its_arms_is_closed_at_its_back() -> None:
    posed = solids.rotate_about_z(_on_its_arms(), 174.0)
    # the corner between the arms is the highest point, the notch under it is empty
    top = posed.vertices[int(np.argmax(posed.vertices[:, 2]))]
    assert top[2] > 0.09
    result = classify(
        posed, rules="parallelepipeds", noise=0.0005, seed=1, finger=builtin_finger("33")
    )
    assert result.model.polyhedron is not None
    assert result.decision.label == "not_hexahedron"
