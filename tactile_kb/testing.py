"""The contract every explorer keeps: checks that plugin authors run in their own test suites.

Use either :func:`check_explorer` (runs them all, raising ``AssertionError`` at the first
failure) or parametrize pytest over :func:`explorer_checks`::

    import pytest
    from tactile_kb.testing import explorer_checks

    @pytest.mark.parametrize(("name", "check"), explorer_checks())
    def test_contract(name, check):
        check(MyExplorer())

The checks: the same seed gives the same record (with contact-position noise on); the record
has the documented shape and survives a JSON round trip; the input mesh is not modified; a
lazy session stops at the first contact and resumes to the same record as a full run; and the
cube of the paper's Fig. 5 is classified ``OBJECT IS A CUBE`` with the ``parallelepipeds``
rules (explore → :func:`tactile_kb.geometry.model.build_model` → features → rules).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import trimesh

from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.explorers import Explorer, get_explorer
from tactile_kb.touch.finger import builtin_finger

__all__ = [
    "check_deterministic",
    "check_explorer",
    "check_fig5_cube",
    "check_lazy_session",
    "check_mesh_untouched",
    "check_record_shape",
    "classify_record",
    "explorer_checks",
    "test_box",
]

Check = Callable[[Explorer], None]


def test_box() -> trimesh.Trimesh:
    """A 6 × 4 × 3 cm box resting on the table, the object most checks explore."""
    box: trimesh.Trimesh = trimesh.creation.box((0.06, 0.04, 0.03))
    box.apply_translation((0.0, 0.0, 0.015))
    return box


test_box.__test__ = False  # type: ignore[attr-defined]  # not a pytest test


def check_deterministic(explorer: Explorer) -> None:
    """Two runs with the same seed (and 0.5 mm noise) give identical records."""
    a = explorer.explore(test_box(), finger="33", seed=7, noise=0.0005)
    b = explorer.explore(test_box(), finger="33", seed=7, noise=0.0005)
    assert a.to_json() == b.to_json(), "the same seed gave different records"


def check_record_shape(explorer: Explorer) -> None:
    """The record is complete, self-consistent and survives a JSON round trip."""
    finger = builtin_finger("33")
    rec = explorer.explore(test_box(), finger=finger, seed=1)
    assert isinstance(rec, ExplorationRecord), f"explore() returned {type(rec).__name__}"
    assert rec.explorer, "record.explorer is empty"
    assert rec.finger == finger.name, f"record.finger is {rec.finger!r}, expected {finger.name!r}"
    assert math.isclose(rec.tip_radius, finger.radius), (
        "record.tip_radius differs from the finger's"
    )
    assert len(rec.sensor_directions) == len(finger.directions), "sensor_directions incomplete"
    assert rec.complete, "a full exploration must say complete=True"
    assert rec.touches >= 1, "no touch recorded"
    assert len(rec.path) >= 2, "the path is empty"
    assert sum(rec.contacts_per_phase.values()) == len(rec.contacts), (
        "contacts_per_phase does not add up"
    )
    n = len(finger.directions)
    for c in rec.contacts:
        assert c.sensors, "a contact without sensors"
        assert all(0 <= s < n for s in c.sensors), f"bad sensors {c.sensors}"
        assert 0 <= c.sensor < n, f"bad followed sensor {c.sensor}"
        assert abs(float(np.linalg.norm(c.direction)) - 1.0) < 1e-9, (
            "direction is not a unit vector"
        )
        expect = np.asarray(c.centre) + rec.tip_radius * np.asarray(c.direction)
        assert np.allclose(expect, c.point, atol=1e-9), "point is not centre + ρ·direction"
    lo, hi = test_box().bounds
    pts = np.asarray([c.point for c in rec.contacts])
    assert (pts >= lo - 0.02).all(), "contact points far from the object"
    assert (pts <= hi + 0.02).all(), "contact points far from the object"
    again = ExplorationRecord.from_json(rec.to_json())
    assert again == rec, "the record does not survive a JSON round trip"


def check_mesh_untouched(explorer: Explorer) -> None:
    """Exploring does not modify the caller's mesh."""
    mesh = test_box()
    mesh.apply_translation((0.01, 0.0, 0.02))  # floating: the explorer must rest a copy
    vertices = np.array(mesh.vertices, copy=True)
    faces = np.array(mesh.faces, copy=True)
    explorer.explore(mesh, finger="33", seed=0)
    assert np.array_equal(mesh.vertices, vertices), "the input mesh's vertices changed"
    assert np.array_equal(mesh.faces, faces), "the input mesh's faces changed"


def check_lazy_session(explorer: Explorer) -> None:
    """A session stops at the first contact, then resumes to the same record as explore()."""
    session = explorer.session(test_box(), finger="33", seed=3)
    first = session.advance("contact")
    assert first.touches >= 1, "advance('contact') returned no touch"
    assert not first.complete, "advance('contact') ran to the end"
    assert not session.done, "advance('contact') ran to the end"
    full = session.advance("complete")
    assert session.done, "advance('complete') did not finish"
    assert full.complete, "advance('complete') did not finish"
    assert len(full.contacts) > len(first.contacts), "resuming explored nothing more"
    direct = explorer.explore(test_box(), finger="33", seed=3)
    assert full.to_json() == direct.to_json(), "a resumed session differs from a full run"


def classify_record(record: ExplorationRecord, rules: str = "parallelepipeds") -> str:
    """The class id the rule set gives to the model built from ``record``.

    Uses :func:`tactile_kb.kb.compiler.compile_rules` when available, else evaluates the rule
    file's class expressions directly (the compiled and direct answers agree by construction).
    """
    from tactile_kb.features.builtin import get_feature
    from tactile_kb.geometry.model import build_model
    from tactile_kb.kb.expr import evaluate
    from tactile_kb.kb.rules import load_rules

    model = build_model(record)
    rs = load_rules(rules)
    values: dict[str, bool] = {}
    for prop in rs.propositions:
        if prop.feature is None:
            continue
        feature: Any = get_feature(prop.feature.name)
        values[prop.id] = bool(feature(model, **prop.feature.params))
    try:
        from tactile_kb.kb.compiler import compile_rules  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        for cls in rs.classes:
            if all(name in values for name in _names(cls.expr)) and evaluate(cls.expr, values):
                return str(cls.id)
        return str(rs.otherwise_id)
    decision = compile_rules(rs).classify(values)
    return str(decision.label)


def _names(expr: Any) -> frozenset[str]:
    from tactile_kb.kb.expr import names

    return names(expr)


def check_fig5_cube(explorer: Explorer) -> None:
    """The cube of Fig. 5, explored with the 33-sensor finger, is classified a cube."""
    from tactile_kb.solids import fig5_objects

    name, mesh, expected = next(o for o in fig5_objects() if o[0] == "CUBE1")
    rec = explorer.explore(mesh, finger="33", seed=0)
    label = classify_record(rec)
    assert label == expected, f"{name}: classified {label!r}, expected {expected!r}"


_CHECKS: tuple[tuple[str, Check], ...] = (
    ("deterministic", check_deterministic),
    ("record_shape", check_record_shape),
    ("mesh_untouched", check_mesh_untouched),
    ("lazy_session", check_lazy_session),
    ("fig5_cube", check_fig5_cube),
)


def explorer_checks() -> list[tuple[str, Check]]:
    """``(name, check)`` pairs: every contract check, for ``pytest.mark.parametrize``."""
    return list(_CHECKS)


def check_explorer(explorer: Explorer | str) -> None:
    """Run every contract check on ``explorer`` (an instance or a registered name)."""
    inst = get_explorer(explorer)
    for _name, check in _CHECKS:
        check(inst)
