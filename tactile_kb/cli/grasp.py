"""Subcommands for grasps and pictures: ``grasp``, ``plot``, ``tree``.

``tactile-kb grasp PATH... [--json] [--plot FILE]`` explores each object (or loads a saved
record with ``--record``) and plans a two-finger grasp on parallel faces in line with the centre
of mass (on the layer contours for objects made of boxes, e.g. with ``--finger 4``); exit 1 when
an object cannot be explored or has no grasp (the reason is printed).
``tactile-kb plot RECORD.json --out FILE.png`` draws a saved exploration;
``tactile-kb tree RULES --out FILE.png [--bits 101101111]`` draws a rule file's choice tree.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from tactile_kb.cli.options import (
    EXIT_FAILED,
    EXIT_OK,
    add_exploration_options,
    add_object_inputs,
    check_noise,
    check_picture,
    nonnegative,
    object_failed,
    object_inputs,
    picture_paths,
    positive,
    progress,
)
from tactile_kb.errors import UsageError

__all__ = ["register"]


def _size(text: str) -> tuple[float, float]:
    parts = text.lower().split("x")
    try:
        w, h = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"a size is WIDTHxHEIGHT in inches, e.g. 6.4x4.8, not {text!r}"
        ) from None
    if not (math.isfinite(w) and math.isfinite(h) and w > 0 and h > 0):
        raise argparse.ArgumentTypeError(f"a size must be positive, got {text!r}")
    return (w, h)


def _picture_options(p: argparse.ArgumentParser, default: tuple[float, float]) -> None:
    p.add_argument(
        "--size",
        type=_size,
        default=default,
        metavar="WxH",
        help=f"figure size in inches (default: {default[0]}x{default[1]})",
    )
    p.add_argument("--dpi", type=positive, default=100.0, help="dots per inch (default: 100)")


def register(sub: argparse._SubParsersAction[Any]) -> None:
    """Add ``grasp``, ``plot`` and ``tree``."""
    p = sub.add_parser("grasp", help="explore objects and plan a two-finger grasp")
    add_object_inputs(p, "plan on")
    add_exploration_options(p)
    p.add_argument("--mu", type=positive, default=0.5, help="friction coefficient (default 0.5)")
    p.add_argument(
        "--max-opening",
        type=positive,
        default=0.15,
        metavar="METRES",
        help="widest jaw opening of the pincers (default: 0.15)",
    )
    p.add_argument(
        "--margin",
        type=nonnegative,
        default=0.005,
        metavar="METRES",
        help="grasp points at least this far inside their faces (default: 0.005)",
    )
    p.add_argument(
        "--mass", type=positive, default=None, help="object mass, kg (default: 1000 kg/m³)"
    )
    p.add_argument("--json", action="store_true", help="one JSON object per line and per object")
    p.add_argument(
        "--plot", metavar="FILE", help="draw each object and its grasp (.png, .svg or .pdf)"
    )
    _picture_options(p, (6.4, 4.8))
    p.set_defaults(func=_grasp)

    p = sub.add_parser("plot", help="draw a saved exploration record")
    p.add_argument("record", metavar="RECORD.json")
    p.add_argument("--out", required=True, metavar="FILE", help="picture file (.png, .svg, .pdf)")
    p.add_argument("--mesh", metavar="MESH", help="the explored object, drawn faintly")
    p.add_argument("--no-grasp", action="store_true", help="do not plan and draw a grasp")
    _picture_options(p, (6.4, 4.8))
    p.set_defaults(func=_plot)

    p = sub.add_parser("tree", help="draw a rule file's choice tree")
    p.add_argument("rules", metavar="RULES", help="rule set name or YAML file")
    p.add_argument("--out", required=True, metavar="FILE", help="picture file (.png, .svg, .pdf)")
    p.add_argument(
        "--bits", metavar="BITS", help="truth values in declared order; highlights their path"
    )
    _picture_options(p, (9.6, 6.4))
    p.set_defaults(func=_tree)


def _line(plan: Any) -> str:
    b = plan.best
    if b is None:
        return f"{plan.object}- NO GRASP: {plan.reason}"
    force = "cannot hold" if b.least_force is None else f"{b.least_force:.2f} N"
    where = f"faces {b.faces[0]} and {b.faces[1]}"
    tail = ""
    if plan.solid is not None:
        where = f"sides {b.faces[0]} and {b.faces[1]} of the layer contour"
        top = "touched top" if plan.solid.top_touched else "top not touched"
        tail = f" [layer model {plan.solid.height * 1000:.1f} mm high, {top}]"
    return (
        f"{plan.object}- GRASP {where}: opening {b.width * 1000:.1f} mm, "
        f"planes {b.angle_deg:.1f}° apart, {b.com_offset * 1000:.1f} mm from the centre of mass, "
        f"ε = {b.quality:.3f}, least force {force}{tail}"
    )


def _grasp(args: argparse.Namespace) -> int:
    from tactile_kb.geometry.model import build_model
    from tactile_kb.grasp.planner import plan_grasp
    from tactile_kb.pipeline import explorer_for
    from tactile_kb.record import ExplorationRecord
    from tactile_kb.touch.finger import load_finger

    items = object_inputs(args)
    if args.plot is not None:
        check_picture(args.plot, "--plot", args.size, args.dpi)
    explorer = explorer_for(args.explorer) if args.paths else None
    finger = load_finger(args.finger)
    check_noise(args.noise, finger)
    pictures = picture_paths(args.plot, [item for item, _ in items]) if args.plot else []
    code = EXIT_OK
    for index, (item, is_record) in enumerate(items):
        try:  # any failure, even out of memory, is this object's alone
            with progress(item):
                if is_record:
                    record = ExplorationRecord.load(item)
                else:
                    assert explorer is not None
                    record = explorer.explore(item, finger=finger, seed=args.seed, noise=args.noise)
                model = build_model(record)
                plan = plan_grasp(
                    model,
                    mu=args.mu,
                    max_opening=args.max_opening,
                    margin=args.margin,
                    mass=args.mass,
                )
        except Exception as exc:
            code = max(code, object_failed(args.command, item, exc, args.json))
            continue
        for note in record.notes:
            print(f"tactile-kb grasp: note: {item}: {note}", file=sys.stderr, flush=True)
        if not plan.ok:
            code = max(code, EXIT_FAILED)
        if args.json:
            out = plan.to_dict()
            out["object"] = plan.object or item
            out["touches"] = record.touches
            out["contacts"] = len(record.contacts)
            print(json.dumps(out, ensure_ascii=False), flush=True)
        else:
            print(_line(plan), flush=True)
        if pictures:  # the plan is out before any picture is drawn
            from tactile_kb.plot import plot_exploration

            try:
                plot_exploration(model, pictures[index], grasp=plan, size=args.size, dpi=args.dpi)
            except Exception as exc:
                code = max(code, object_failed(args.command, item, exc, False))
    return code


def _plot(args: argparse.Namespace) -> int:
    from tactile_kb.plot import plot_exploration
    from tactile_kb.record import ExplorationRecord

    check_picture(args.out, "--out", args.size, args.dpi)
    record = ExplorationRecord.load(args.record)
    mesh = None
    if args.mesh:
        from tactile_kb.objects import load_object

        mesh = load_object(args.mesh)
    plot_exploration(
        record, args.out, mesh=mesh, grasp=not args.no_grasp, size=args.size, dpi=args.dpi
    )
    print(f"{args.record}: {record.touches} touches → {args.out}")
    return 0


def _tree(args: argparse.Namespace) -> int:
    from tactile_kb.cli.kb import _load
    from tactile_kb.kb.compiler import compile_rules
    from tactile_kb.plot import plot_tree

    check_picture(args.out, "--out", args.size, args.dpi)
    kb = compile_rules(_load(args.rules))
    decision = None
    if args.bits is not None:
        bits = args.bits.strip()
        if len(bits) != kb.n or any(ch not in "01-" for ch in bits):
            raise UsageError(
                f"--bits {args.bits!r}: give {kb.n} characters 0, 1 or - (for {', '.join(kb.ids)})"
            )
        decision = kb.classify(bits)
    plot_tree(kb, args.out, decision=decision, size=args.size, dpi=args.dpi)
    tail = f": {decision.answer}" if decision is not None else ""
    print(f"{kb.rules.name} → {args.out}{tail}")
    return 0
