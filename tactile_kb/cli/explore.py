"""Subcommands that touch objects: ``classify``, ``explore``, ``demo``, ``plugins``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tactile_kb.cli.options import (
    add_exploration_options,
    add_object_inputs,
    check_picture,
    error_line,
    object_inputs,
    picture_paths,
)
from tactile_kb.errors import TactileKBError, UsageError

if TYPE_CHECKING:
    from tactile_kb.pipeline import Classification

# The heavy stack (trimesh, scipy, sympy, dd) is imported inside the handlers, so that
# `tactile-kb --help` and the rule-file commands start quickly.

__all__ = ["register"]


def register(sub: argparse._SubParsersAction[Any]) -> None:
    """Add ``classify``, ``explore``, ``demo`` and ``plugins``."""
    p = sub.add_parser("classify", help="explore objects by touch and name them")
    add_object_inputs(p, "classify")
    p.add_argument(
        "--rules",
        default="parallelepipeds",
        help="rule set name or YAML file (default: parallelepipeds)",
    )
    add_exploration_options(p)
    p.add_argument("--json", action="store_true", help="one JSON object per line and per object")
    p.add_argument("--plot", metavar="FILE", help="draw what the finger found (.png, .svg or .pdf)")
    p.set_defaults(func=_classify)

    p = sub.add_parser("explore", help="explore one object and save the record")
    p.add_argument("path", metavar="PATH")
    p.add_argument("--out", required=True, metavar="RECORD.json")
    add_exploration_options(p)
    p.set_defaults(func=_explore)

    p = sub.add_parser("demo", help="the paper's Fig. 5: twelve objects explored and named")
    p.add_argument("--explorer", default="stepper", help="explorer plugin (default: stepper)")
    p.add_argument("--json", action="store_true", help="one JSON object per line")
    p.set_defaults(func=_demo)

    p = sub.add_parser(
        "plugins", help="list explorers and feature extractors and whether they load"
    )
    p.set_defaults(func=_plugins)


def _emit(result: Classification, as_json: bool) -> None:
    if as_json:
        print(json.dumps(result.summary()), flush=True)
    else:
        print(f"{result.object}- {result.answer}", flush=True)


def _classify(args: argparse.Namespace) -> int:
    items = object_inputs(args)
    if args.plot:
        check_picture(args.plot, "--plot")
    from tactile_kb.explorers import get_explorer
    from tactile_kb.finger import load_finger
    from tactile_kb.pipeline import classify, classify_record, knowledge_base
    from tactile_kb.record import ExplorationRecord

    # Everything shared by the objects is checked before the first one is touched.
    kb = knowledge_base(args.rules)
    explorer = get_explorer(args.explorer) if args.paths else None
    finger = load_finger(args.finger)
    pictures = picture_paths(args.plot, [item for item, _ in items]) if args.plot else []
    failed = 0
    for index, (item, is_record) in enumerate(items):
        try:
            if is_record:
                result = classify_record(ExplorationRecord.load(item), rules=kb)
            else:
                assert explorer is not None
                result = classify(
                    item,
                    rules=kb,
                    explorer=explorer,
                    finger=finger,
                    noise=args.noise,
                    seed=args.seed,
                )
        except TactileKBError as exc:
            failed += 1
            print(error_line(item, exc), file=sys.stderr, flush=True)
            continue
        _emit(result, args.json)  # the answer is out before any picture is drawn
        if pictures:
            from tactile_kb.plot import plot_classification

            try:
                plot_classification(result, pictures[index])
            except TactileKBError as exc:
                failed += 1
                print(error_line(item, exc), file=sys.stderr, flush=True)
    return 1 if failed else 0


def _explore(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if not out.parent.exists():
        raise UsageError(f"--out {args.out}: directory {str(out.parent)!r} does not exist")
    from tactile_kb.explorers import get_explorer
    from tactile_kb.finger import load_finger

    explorer = get_explorer(args.explorer)
    record = explorer.explore(
        args.path, finger=load_finger(args.finger), seed=args.seed, noise=args.noise
    )
    record.save(out)
    print(
        f"{args.path}: {record.touches} touches, {len(record.contacts)} contacts, "
        f"path {record.path_length:.3f} m → {out}"
    )
    if record.open_ending:  # the record is written, but the model is not closed: say why
        print(f"tactile-kb: warning: {args.path}: {record.open_ending}", file=sys.stderr)
    return 0


def _demo(args: argparse.Namespace) -> int:
    from tactile_kb.explorers import get_explorer
    from tactile_kb.pipeline import classify, knowledge_base
    from tactile_kb.solids import fig5_objects

    kb = knowledge_base("parallelepipeds")
    explorer = get_explorer(args.explorer)
    failed = 0
    for name, mesh, _expected in fig5_objects():
        try:
            result = classify(mesh, rules=kb, explorer=explorer, finger="33", seed=0)
        except TactileKBError as exc:
            failed += 1
            print(error_line(name, exc), file=sys.stderr, flush=True)
            continue
        if args.json:
            print(json.dumps({**result.summary(), "object": name}), flush=True)
        else:
            print(f"{name}- {result.answer}", flush=True)
    return 1 if failed else 0


def _plugins(args: argparse.Namespace) -> int:
    from tactile_kb.explorers import available_explorers, explorer_registry
    from tactile_kb.features import feature_registry

    available_explorers()  # registers the built-in in an uninstalled checkout
    for kind, registry in (("explorer", explorer_registry), ("feature", feature_registry())):
        for status in registry.status():
            state = "ok" if status.ok else f"unavailable: {status.reason}; install: {status.hint}"
            print(f"{kind:8} {status.name:30} {state}")
    return 0
