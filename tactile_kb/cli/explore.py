"""Subcommands that touch objects: ``classify``, ``explore``, ``demo``, ``plugins``."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tactile_kb.cli.options import (
    EXIT_OK,
    add_exploration_options,
    add_object_inputs,
    check_noise,
    check_picture,
    notices,
    object_failed,
    object_inputs,
    picture_paths,
    progress,
)
from tactile_kb.errors import UsageError

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

    p = sub.add_parser("explore", help="explore objects and save their records")
    p.add_argument(
        "paths",
        nargs="+",
        metavar="PATH",
        help="mesh files (STL, OBJ, PLY, OFF, glTF), metres unless --units",
    )
    p.add_argument(
        "--out",
        required=True,
        metavar="RECORD.json",
        help="the record; with several objects RECORD-<object>.json each",
    )
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
        print(json.dumps(result.summary(), ensure_ascii=False), flush=True)
    else:
        print(f"{result.object}- {result.answer}", flush=True)


def _classify(args: argparse.Namespace) -> int:
    items = object_inputs(args)
    if args.plot is not None:
        check_picture(args.plot, "--plot")
    from tactile_kb.pipeline import classify, classify_record, explorer_for, knowledge_base
    from tactile_kb.record import ExplorationRecord
    from tactile_kb.touch.finger import load_finger

    # Everything shared by the objects is checked before the first one is touched.
    kb = knowledge_base(args.rules)
    explorer = explorer_for(args.explorer) if args.paths else None
    finger = load_finger(args.finger)
    check_noise(args.noise, finger)
    pictures = picture_paths(args.plot, [item for item, _ in items]) if args.plot else []
    code = EXIT_OK
    for index, (item, is_record) in enumerate(items):
        try:  # any failure, even out of memory, is this object's alone
            with progress(item):
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
        except Exception as exc:
            code = max(code, object_failed(args.command, item, exc, args.json))
            continue
        for note in notices(result.record):
            print(f"tactile-kb classify: note: {item}: {note}", file=sys.stderr, flush=True)
        if result.record.open_ending:  # answered, but from an exploration that did not close
            print(
                f"tactile-kb classify: warning: {item}: {result.record.open_ending}",
                file=sys.stderr,
                flush=True,
            )
        _emit(result, args.json)  # the answer is out before any picture is drawn
        if pictures:
            from tactile_kb.objects import load_object
            from tactile_kb.plot import plot_classification

            try:  # with the true mesh, faint, when the object was a mesh file
                mesh = None if is_record else load_object(item)
                plot_classification(result, pictures[index], mesh=mesh)
            except Exception as exc:
                code = max(code, object_failed(args.command, item, exc, False))
    return code


def _explore(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if not args.out or not out.name:
        raise UsageError(f"--out {args.out!r}: give a file name for the record")
    if not out.parent.is_dir():
        raise UsageError(f"--out {args.out}: directory {str(out.parent)!r} does not exist")
    if not os.access(out.parent, os.W_OK):
        raise UsageError(f"--out {args.out}: directory {str(out.parent)!r} is not writable")
    from tactile_kb.pipeline import explorer_for
    from tactile_kb.touch.finger import load_finger

    explorer = explorer_for(args.explorer)
    finger = load_finger(args.finger)
    check_noise(args.noise, finger)
    outs = record_paths(args.out, args.paths)
    code = EXIT_OK
    for path, target in zip(args.paths, outs, strict=True):
        try:
            with progress(path):
                record = explorer.explore(path, finger=finger, seed=args.seed, noise=args.noise)
            record.save(target)
        except Exception as exc:
            code = max(code, object_failed(args.command, path, exc, False))
            continue
        for note in notices(record):
            print(f"tactile-kb explore: note: {path}: {note}", file=sys.stderr, flush=True)
        if record.open_ending:  # the record is written, but the model is not closed: say why
            print(f"tactile-kb explore: warning: {path}: {record.open_ending}", file=sys.stderr)
        print(
            f"{path}: {record.touches} touches, {len(record.contacts)} contacts, "
            f"path {record.path_length:.3f} m → {target}",
            flush=True,
        )
    return code


def record_paths(base: str, items: list[str]) -> list[Path]:
    """One record path per object: ``base`` for one, else ``base-<stem>`` (see picture_paths)."""
    return picture_paths(base, items)


def _demo(args: argparse.Namespace) -> int:
    from tactile_kb.pipeline import classify, explorer_for, knowledge_base
    from tactile_kb.solids import fig5_objects

    kb = knowledge_base("parallelepipeds")
    explorer = explorer_for(args.explorer)
    code = EXIT_OK
    for name, mesh, _expected in fig5_objects():
        try:
            with progress(name):
                result = classify(mesh, rules=kb, explorer=explorer, finger="33", seed=0)
        except Exception as exc:
            code = max(code, object_failed(args.command, name, exc, args.json))
            continue
        if args.json:
            print(json.dumps({**result.summary(), "object": name}, ensure_ascii=False), flush=True)
        else:
            print(f"{name}- {result.answer}", flush=True)
    return code


def _plugins(args: argparse.Namespace) -> int:
    from tactile_kb.features.builtin import feature_registry
    from tactile_kb.touch.explorers import available_explorers, explorer_registry

    available_explorers()  # registers the built-in in an uninstalled checkout
    for kind, registry in (("explorer", explorer_registry), ("feature", feature_registry())):
        for status in registry.status():
            state = "ok" if status.ok else f"unavailable: {status.reason}; install: {status.hint}"
            print(f"{kind:8} {status.name:30} {state}")
    return 0
