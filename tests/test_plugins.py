"""The plugin registry: lazy references, entry points, install hints, broken plugins."""

from __future__ import annotations

import logging
from importlib.metadata import EntryPoint
from typing import Any

import pytest

from tactile_kb import plugins
from tactile_kb.errors import PluginError, PluginUnavailableError
from tactile_kb.plugins import Registry


def test_code_registration_and_lazy_reference() -> None:
    reg: Registry[Any] = Registry("tk.test.none", "thing")
    reg.register("dumps", "json:dumps")
    reg.register("three", 3)
    import json

    assert reg.get("dumps") is json.dumps
    assert reg.get("three") == 3
    assert reg.names() == ["dumps", "three"]


def test_unknown_name_lists_the_known_ones() -> None:
    reg: Registry[int] = Registry("tk.test.none", "thing")
    reg.register("a", 1)
    with pytest.raises(PluginError, match=r"unknown thing 'b' \(known: a\)"):
        reg.get("b")


def test_missing_module_raises_with_hint_never_falls_back() -> None:
    reg: Registry[Any] = Registry("tk.test.none", "explorer")
    reg.register("ghost", "tk_no_such_module:Ghost")
    reg.register_hint("ghost", "pip install ghost")
    with pytest.raises(PluginUnavailableError) as info:
        reg.get("ghost")
    assert info.value.hint == "pip install ghost"
    status = {s.name: s for s in reg.status()}
    assert not status["ghost"].ok
    assert reg.available() == []


def test_check_rejects_invalid_plugins() -> None:
    reg: Registry[Any] = Registry("tk.test.none", "number", check=lambda x: isinstance(x, int))
    with pytest.raises(PluginError, match="not a valid number"):
        reg.register("x", 1.5)
    reg.register("s", "json:dumps")  # a lazy reference is checked when it loads
    with pytest.raises(PluginError, match="not a valid number"):
        reg.get("s")


def test_entry_points_providers_and_broken_ones(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    eps = [
        EntryPoint("single", "json:loads", "tk.test.eps"),
        EntryPoint("bundle", "os:environ", "tk.test.eps"),  # not used: replaced below
        EntryPoint("broken", "tk_no_such_module:X", "tk.test.eps"),
    ]
    provided = {"p1": 1, "p2": 2}

    def fake_entry_points(group: str) -> list[EntryPoint]:
        return eps if group == "tk.test.eps" else []

    monkeypatch.setattr(plugins, "entry_points", fake_entry_points)
    monkeypatch.setattr(
        EntryPoint, "load", lambda self: provided if self.name == "bundle" else _load(self)
    )
    reg: Registry[Any] = Registry("tk.test.eps", "thing")
    with caplog.at_level(logging.WARNING, logger="tactile_kb.plugins"):
        names = reg.names()
    assert names == ["p1", "p2", "single"]
    assert "skipping thing 'broken'" in caplog.text
    with pytest.raises(PluginUnavailableError):
        reg.get("broken")


def _load(ep: EntryPoint) -> Any:
    import importlib

    module, _, attr = ep.value.partition(":")
    return getattr(importlib.import_module(module), attr)
