"""The CLI dispatcher: one-line errors and exit codes, never a traceback."""

from __future__ import annotations

import argparse
from typing import Any

import pytest

from tactile_kb import cli
from tactile_kb.cli.options import BUG_HINT, error_message
from tactile_kb.errors import Problem, RuleFileError, TactileKBError, UsageError


def test_no_command_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main([]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "required" in err


def test_unknown_command(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["frobnicate"]) == 2
    assert "invalid choice" in capsys.readouterr().err


def _run_with(func: Any, monkeypatch: pytest.MonkeyPatch) -> int:
    original = cli.build_parser

    def build() -> cli.Parser:
        parser = original()
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        p = sub.add_parser("boom")
        p.set_defaults(func=func)
        return parser

    monkeypatch.setattr(cli, "build_parser", build)
    return cli.main(["boom"])


@pytest.mark.parametrize(
    ("exc", "code", "line"),
    [
        (UsageError("bad --seed"), 2, "tactile-kb boom: error: bad --seed\n"),
        (TactileKBError("object is open"), 1, "tactile-kb boom: error: object is open\n"),
        (
            ValueError("oops"),
            3,
            f"tactile-kb boom: internal error: ValueError: oops ({BUG_HINT})\n",
        ),
        (MemoryError(), 1, f"tactile-kb boom: error: {error_message(MemoryError())}\n"),
        (
            RuleFileError([Problem("r.yaml", 3, 5, "classes[0].when", "unknown id 'Q'")]),
            1,
            "r.yaml:3:5: classes[0].when: unknown id 'Q'\n",
        ),
    ],
)
def test_errors_become_one_line(
    exc: Exception,
    code: int,
    line: str,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    def func(args: argparse.Namespace) -> int:
        raise exc

    assert _run_with(func, monkeypatch) == code
    assert capsys.readouterr().err == line
