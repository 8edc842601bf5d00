"""``tactile-kb validate | compile | query``: rule files on the command line.

* ``validate FILE...`` lists every problem as ``file:line:column: path: message`` (warnings
  too) and exits 1 if any file has an error, 0 otherwise.
* ``compile FILE_OR_NAME [--format text|json]`` prints s(L), |r(L)|, each class's r(L) in the
  paper's notation and in ASCII with its bit strings, the new proposition L = …, the
  warnings and the economy line.
* ``query FILE_OR_NAME A=1 B=0 … | --bits 1011011 [--json]`` prints the Decision and why.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tactile_kb.cli.options import EXIT_FAILED, EXIT_OK, EXIT_USAGE, object_failed
from tactile_kb.errors import Problem, RuleFileError, UsageError

if TYPE_CHECKING:  # the compiler (dd, networkx) is imported by the commands that use it
    from tactile_kb.kb.base import KnowledgeBase
    from tactile_kb.kb.engine import Decision
    from tactile_kb.kb.rules import RuleSet

__all__ = ["register"]

MAX_BITS_SHOWN = 8
_ASSIGNMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)=(0|1|true|false)$")


def register(sub: argparse._SubParsersAction[Any]) -> None:
    """Add ``validate``, ``compile`` and ``query`` to ``sub``."""
    p = sub.add_parser("validate", help="check rule files; list every problem with its location")
    p.add_argument("files", nargs="+", metavar="FILE", help="rule files (or packaged names)")
    p.set_defaults(func=run_validate)

    p = sub.add_parser("compile", help="compile a rule file and print its r(L) models")
    p.add_argument("rules", metavar="FILE_OR_NAME", help="a rule file or a packaged name")
    p.add_argument("--format", choices=("text", "json"), default="text")
    p.add_argument("--json", action="store_true", help="print JSON (the same as --format json)")
    p.set_defaults(func=run_compile)

    p = sub.add_parser("query", help="classify an assignment of the propositions")
    p.add_argument("rules", metavar="FILE_OR_NAME", help="a rule file or a packaged name")
    p.add_argument("assignments", nargs="*", metavar="ID=0|1", help="proposition values")
    p.add_argument("--bits", help="the values as a bit string in declared order, - unknown")
    p.add_argument("--json", action="store_true", help="print the decision as JSON")
    p.set_defaults(func=run_query, interleaved="assignments")


def _load(arg: str) -> RuleSet:
    """The rule file or packaged rule set ``arg`` names (a name that names nothing is a
    usage error, exit 2)."""
    from tactile_kb.kb.rules import load_rules

    if not arg:
        raise UsageError("no rule file given ('')")
    path = Path(arg)
    if path.exists() or arg.endswith((".yaml", ".yml")) or "/" in arg:
        if not path.exists():
            return load_rules(arg)  # the UsageError naming the packaged rule sets
        return load_rules(path)
    return load_rules(arg)


def run_validate(args: argparse.Namespace) -> int:
    code = EXIT_OK
    for arg in args.files:
        try:  # any failure, even out of memory, is this file's alone
            code = max(code, _validate_one(arg))
        except Exception as exc:
            code = max(code, object_failed("validate", arg, exc, False))
    return code


def _validate_one(arg: str) -> int:
    """Print the problems of one rule file and its summary line; return its exit code (a
    name that names nothing is a usage error, 2, as docs/cli.md says)."""
    problems: list[Problem]
    try:
        rules = _load(arg)
    except RuleFileError as exc:
        problems = list(exc.problems)
        summary = ""
    except UsageError as exc:
        print(f"tactile-kb validate: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    else:
        # Feature bindings (against the registry, plugins included) and the logic are
        # checked together, so that every problem is listed at once.
        from tactile_kb.bindings import binding_problems
        from tactile_kb.kb.compiler import compile_rules

        problems = binding_problems(rules, missing="warning")
        try:
            kb = compile_rules(rules)
            problems += list(kb.problems)
            summary = (
                f"{kb.rules.file}: ok: {kb.n} propositions, {len(kb.classes)} classes, "
                f"|r(L)| = {kb.r_count}"
            )
        except RuleFileError as exc:
            problems += list(exc.problems)
            summary = ""
    problems.sort(key=lambda p: (p.file, p.line, p.column))
    for problem in problems:
        print(problem, file=sys.stderr)
    if any(p.severity == "error" for p in problems):
        return EXIT_FAILED
    warn = f", {len(problems)} warning{'s' * (len(problems) != 1)}" if problems else ""
    print(summary + warn)
    return EXIT_OK


def _bits_line(bits: tuple[str, ...]) -> str:
    shown = " ".join(bits[:MAX_BITS_SHOWN])
    if len(bits) > MAX_BITS_SHOWN:
        shown += f" … ({len(bits)} in all)"
    return shown


def compile_text(kb: KnowledgeBase) -> str:
    """The text report of ``tactile-kb compile``."""
    rules = kb.rules
    lines = [
        f"rule set {rules.name!r} ({rules.file})",
        f"base L = {{{', '.join(kb.ids)}}}: n = {kb.n}",
        f"s(L): 2^{kb.n} = {kb.s_size} conjunctions",
        f"r(L): {kb.r_count} members left by {len(rules.connections)} connections "
        f"(independent groups: {' | '.join(' '.join(g.ids) for g in kb.groups if g.ids)})",
    ]
    for k in kb.classes:
        lines += [
            "",
            f"{k.id}: {k.answer} (line {k.line}; {k.count} member{'s' * (k.count != 1)} of r(L))",
            f"  r(L) = {k.paper}",
            f"  ascii: {k.ascii}",
            f"  bits:  {_bits_line(k.bits)}",
            f"  {k.proposition}",
            f"  {k.equation}",
        ]
    lines += ["", f"otherwise: {rules.otherwise_id}: {rules.otherwise_answer}"]
    if kb.problems:
        lines += ["", "warnings:"] + [f"  {p}" for p in kb.problems]
    lines += ["", kb.economy().line]
    return "\n".join(lines)


def run_compile(args: argparse.Namespace) -> int:
    rules = _load(args.rules)
    # compile refuses what validate refuses: bad feature bindings and report measures too
    from tactile_kb.bindings import binding_problems
    from tactile_kb.kb.compiler import compile_rules

    bad = [p for p in binding_problems(rules, missing="warning") if p.severity == "error"]
    if bad:
        raise RuleFileError(bad, rules.source.excerpt(bad[0].line, bad[0].column))
    kb = compile_rules(rules)
    if args.json or args.format == "json":
        data = kb.to_dict()
        data["economy"] = kb.economy().to_dict()
        print(json.dumps(data, indent=2, ensure_ascii=False))
    else:
        print(compile_text(kb))
    return 0


def parse_assignments(items: list[str]) -> dict[str, bool]:
    """``["A=1", "B=0"]`` → ``{"A": True, "B": False}`` (UsageError on bad syntax)."""
    out: dict[str, bool] = {}
    for item in items:
        m = _ASSIGNMENT.match(item)
        if m is None:
            raise UsageError(f"bad assignment {item!r}: write ID=1 or ID=0")
        name, value = m.groups()
        if name in out:
            raise UsageError(f"proposition {name!r} is assigned twice")
        out[name] = value in ("1", "true")
    return out


def decision_text(d: Decision) -> str:
    """The text report of ``tactile-kb query``."""
    when = f"after phase {d.phase}" if d.phase else "before any evaluation"
    lines = [
        d.answer,
        f"  class: {d.label}",
        f"  bits: {d.bits}",
        f"  certain: {'yes, ' + when if d.certain else 'no'}",
    ]
    if d.matched:
        lines.append(f"  matched: {d.matched}")
    if d.nearest:
        lines.append(
            "  nearest: " + ", ".join(f"{label} (distance {dist})" for label, dist in d.nearest)
        )
    lines += [f"  violated: {v}" for v in d.violated]
    lines.append(f"  because: {d.explanation}")
    return "\n".join(lines)


def run_query(args: argparse.Namespace) -> int:
    if args.bits is not None and args.assignments:
        raise UsageError("give either ID=0|1 assignments or --bits, not both")
    if args.bits is None and not args.assignments:
        raise UsageError("give ID=0|1 assignments or --bits")
    from tactile_kb.kb.compiler import compile_rules
    from tactile_kb.kb.engine import INCONSISTENT

    assignment: Any = args.bits if args.bits is not None else parse_assignments(args.assignments)
    kb = compile_rules(_load(args.rules))
    decision = kb.classify(assignment)
    if args.json:
        print(json.dumps(decision.to_dict(), indent=2, ensure_ascii=False))
    else:
        print(decision_text(decision))
    if decision.label == INCONSISTENT:
        print(
            "tactile-kb query: error: the values contradict the connections: "
            + "; ".join(decision.violated),
            file=sys.stderr,
        )
        return 1
    return 0
