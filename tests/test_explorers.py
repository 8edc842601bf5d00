"""The explorer registry and lazy sessions."""

from __future__ import annotations

import pytest

from tactile_kb.errors import PluginError, PluginUnavailableError, UsageError
from tactile_kb.testing import test_box as box
from tactile_kb.touch.explorers import (
    MUJOCO_HINT,
    ExplorationSession,
    Explorer,
    available_explorers,
    explorer_registry,
    get_explorer,
)
from tactile_kb.touch.servo import ServoParams
from tactile_kb.touch.stepper import StepperExplorer


def test_stepper_is_available_and_loads_by_name() -> None:
    assert "stepper" in available_explorers()
    e = get_explorer("stepper")
    assert isinstance(e, StepperExplorer)
    assert isinstance(e, Explorer)
    assert e.name == "stepper"


def test_an_instance_is_accepted_where_a_name_is() -> None:
    mine = StepperExplorer(ServoParams(l1=0.01))
    assert get_explorer(mine) is mine


def test_not_an_explorer() -> None:
    with pytest.raises(PluginError, match="not an explorer"):
        get_explorer(42)  # type: ignore[arg-type]


def test_unknown_name_lists_the_known_ones() -> None:
    with pytest.raises(PluginError, match=r"unknown explorer 'nope'.*stepper"):
        get_explorer("nope")


def test_known_but_missing_plugin_raises_its_install_hint(monkeypatch: pytest.MonkeyPatch) -> None:
    import tactile_kb.touch.explorers as ex
    from tactile_kb.plugins import Registry

    fresh: Registry[object] = Registry("tactile_kb.explorers", "explorer", check=ex._is_explorer)
    monkeypatch.setattr(ex, "explorer_registry", fresh)
    fresh.register_hint("ghost", "pip install tactile-kb-ghost")
    with pytest.raises(PluginUnavailableError, match="pip install tactile-kb-ghost"):
        get_explorer("ghost")
    fresh.register("ghost2", "tactile_kb_ghost_module:Explorer")
    with pytest.raises(PluginUnavailableError, match="ghost2"):
        get_explorer("ghost2")
    assert "ghost2" not in available_explorers()


def test_mujoco_has_an_install_hint() -> None:
    assert "pip install -e ./explorers/mujoco" in MUJOCO_HINT
    status = {s.name: s for s in explorer_registry.status()}
    assert "mujoco" in status
    if not status["mujoco"].ok:
        assert status["mujoco"].hint == MUJOCO_HINT


def test_session_is_lazy_and_resumable() -> None:
    session = StepperExplorer().session(box(), finger="33", seed=0)
    assert isinstance(session, ExplorationSession)
    assert session.record.contacts == []  # nothing explored before advance()
    first = session.advance("contact")
    assert first.touches == 1
    assert first.contacts_per_phase == {"first-contact": 1}
    layer = session.advance("layer")
    assert layer.layers
    assert layer.layers[0].closed
    assert not session.done
    full = session.advance()
    assert session.done
    assert full.complete
    assert session.advance() == full  # nothing more to do


def test_bad_goal_and_bad_noise() -> None:
    session = StepperExplorer().session(box())
    with pytest.raises(UsageError, match="goal"):
        session.advance("everything")  # type: ignore[arg-type]
    with pytest.raises(UsageError, match="noise"):
        StepperExplorer().session(box(), noise=-0.1)


def test_record_names_and_parameters() -> None:
    rec = StepperExplorer().explore(box(), finger="4", seed=11, noise=0.0002)
    assert rec.explorer == "stepper"
    assert rec.finger == "4"
    assert rec.seed == 11
    assert rec.noise == 0.0002
    assert rec.params["l2"] == ServoParams().l2
