"""The public API: ``tactile_kb.__all__`` is sorted, complete, and every name resolves lazily."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import tactile_kb


def test_all_is_sorted_and_matches_the_lazy_table() -> None:
    assert tactile_kb.__all__ == sorted(tactile_kb.__all__)
    assert set(tactile_kb.__all__) == {*tactile_kb._EXPORTS, "__version__"}


def test_every_public_name_resolves_to_its_module() -> None:
    for name, module in tactile_kb._EXPORTS.items():
        value = getattr(tactile_kb, name)
        assert value is getattr(importlib.import_module(module), name), name


def test_unknown_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_name"):
        tactile_kb.no_such_name  # noqa: B018


def test_importing_the_package_stays_light() -> None:
    code = "import sys, tactile_kb; print(sorted(m for m in ('trimesh', 'scipy', 'sympy', 'dd') if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"
