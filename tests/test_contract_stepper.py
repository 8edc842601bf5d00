"""The built-in stepper keeps the explorer contract of tactile_kb.testing."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tactile_kb.testing import check_explorer, explorer_checks
from tactile_kb.touch.explorers import Explorer
from tactile_kb.touch.stepper import StepperExplorer


@pytest.mark.parametrize(("name", "check"), explorer_checks())
def test_contract(name: str, check: Callable[[Explorer], None]) -> None:
    check(StepperExplorer())


def test_check_explorer_by_name() -> None:
    check_explorer("stepper")


class _Broken(StepperExplorer):
    """An explorer that forgets to copy the mesh."""

    name = "broken"

    def explore(self, obj, *, finger="33", seed=0, noise=0.0):  # type: ignore[no-untyped-def]
        obj.apply_translation((0.0, 0.0, 1e-3))
        return super().explore(obj, finger=finger, seed=seed, noise=noise)


def test_the_contract_catches_a_broken_explorer() -> None:
    checks = dict(explorer_checks())
    with pytest.raises(AssertionError, match="mesh"):
        checks["mesh_untouched"](_Broken())
