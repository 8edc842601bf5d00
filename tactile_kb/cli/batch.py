"""``tactile-kb batch``: classify many objects into a results file, on local cores or Dask."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Any

from tactile_kb.cli.options import add_exploration_options, positive
from tactile_kb.errors import TactileKBError, UsageError

# Only the standard library and tactile_kb.errors at import time: `tactile-kb --help` stays
# quick. tactile_kb.batch, the pipeline, tqdm and dask are imported inside the handler.

__all__ = ["register"]

REPORT_SUFFIXES = (".md", ".html", ".htm")


def _workers(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be ≥ 1, got {text!r}")
    return value


def _seeds(text: str) -> tuple[int, ...]:
    from tactile_kb.batch import parse_seeds

    try:
        return parse_seeds(text)
    except UsageError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def register(sub: argparse._SubParsersAction[Any]) -> None:
    """Add ``batch``."""
    p = sub.add_parser(
        "batch",
        help="classify many objects (files, folders, globs, manifests) into a results file",
        description=(
            "Classify every object once per seed, on the local cores or a Dask cluster; "
            "results stream to RESULTS (JSONL, or Parquet for *.parquet) and --resume "
            "continues a run that was cut short."
        ),
    )
    p.add_argument(
        "inputs",
        nargs="+",
        metavar="INPUT",
        help="mesh files, folders (searched recursively), globs, or CSV/JSONL manifests "
        "with a path column (optional: label, rules, explorer, finger, noise, seeds, timeout)",
    )
    p.add_argument(
        "--out", required=True, metavar="RESULTS", help="results file (.jsonl, .parquet)"
    )
    p.add_argument(
        "--rules",
        default="parallelepipeds",
        help="rule set name or YAML file (default: parallelepipeds)",
    )
    add_exploration_options(p, with_seed=False)  # one seed per run: --seeds below
    p.add_argument(
        "--seeds",
        type=_seeds,
        default=(0,),
        metavar="SEEDS",
        help="one run per seed: 0-9, 3 or 0,2,5-7 (default: 0)",
    )
    p.add_argument(
        "--timeout",
        type=positive,
        default=None,
        metavar="SECONDS",
        help="seconds one object may take; past it the object is an error line",
    )
    p.add_argument(
        "--workers",
        type=_workers,
        default=None,
        metavar="N",
        help=f"local worker processes (default: the core count, {os.cpu_count() or 1})",
    )
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on a Dask distributed cluster, e.g. tcp://host:8786 (needs tactile-kb[dask])",
    )
    p.add_argument(
        "--ship",
        action="store_true",
        help="send each mesh's bytes to the Dask workers (when they do not share this filesystem)",
    )
    p.add_argument(
        "--resume", action="store_true", help="skip the objects and seeds already in RESULTS"
    )
    p.add_argument(
        "--overwrite", action="store_true", help="start again when RESULTS already exists"
    )
    p.add_argument(
        "--report",
        metavar="FILE.md|FILE.html",
        help="write the summary, with a picture of the confusion matrix when objects have labels",
    )
    p.set_defaults(func=_batch)


def _check_report(path: str) -> None:
    p = Path(path)
    if p.suffix.lower() not in REPORT_SUFFIXES:
        raise UsageError(f"--report {path}: the file must end in {', '.join(REPORT_SUFFIXES)}")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"--report {path}: directory {str(parent)!r} does not exist")
    if p.is_dir():
        raise UsageError(f"--report {path}: is a directory")
    if not os.access(parent, os.W_OK):
        raise UsageError(f"--report {path}: directory {str(parent)!r} is not writable")


def _client(address: str) -> Any:
    import importlib

    try:
        distributed: Any = importlib.import_module("distributed")
    except ImportError:
        from tactile_kb.errors import PluginUnavailableError

        raise PluginUnavailableError(
            "dask", "pip install 'tactile-kb[dask]'", "--scheduler needs dask.distributed"
        ) from None
    try:
        return distributed.Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise TactileKBError(f"--scheduler {address}: cannot reach it ({exc})") from None


def _batch(args: argparse.Namespace) -> int:
    if args.ship and not args.scheduler:
        raise UsageError("--ship sends meshes to Dask workers: use it with --scheduler")
    if args.resume and args.overwrite:
        raise UsageError("--resume and --overwrite exclude each other")
    if args.report:
        _check_report(args.report)
    from tactile_kb.batch import check_output, expand_inputs, run_batch

    # Everything that can be refused is refused before the first object is touched.
    check_output(args.out, resume=args.resume, overwrite=args.overwrite)
    items = expand_inputs(args.inputs)
    total = sum(len(item.options.get("seeds", args.seeds)) for item in items)

    from tqdm import tqdm

    terminal = sys.stderr.isatty()
    try:  # a terminal that reports no size (a bare pty) gets 80 × 24; tqdm draws nothing in 0 × 0
        size = os.get_terminal_size(sys.stderr.fileno()) if terminal else None
    except OSError:
        size = None
    sized = size is not None and size.columns > 0 and size.lines > 0
    bar = tqdm(
        total=total,
        unit="obj",
        file=sys.stderr,
        disable=not terminal,
        dynamic_ncols=sized,
        ncols=None if sized else 80,
        nrows=None if sized else 24,
    )
    errors = 0

    def on_row(row: dict[str, Any]) -> None:
        nonlocal errors
        error = row.get("error")
        if isinstance(error, dict):
            errors += 1
            bar.set_postfix(errors=errors, refresh=False)
            message = f"tactile-kb: error: {error['message']} (seed {row['seed']}, {error['kind']})"
            if bar.disable:
                print(message, file=sys.stderr, flush=True)
            else:
                bar.write(message, file=sys.stderr)
        bar.update(1)

    def on_skip(task: dict[str, Any]) -> None:
        bar.update(1)

    client = _client(args.scheduler) if args.scheduler else None
    try:
        summary = run_batch(
            items,
            args.out,
            resume=args.resume,
            overwrite=args.overwrite,
            on_row=on_row,
            on_skip=on_skip,
            rules=args.rules,
            explorer=args.explorer,
            finger=args.finger,
            noise=args.noise,
            seeds=args.seeds,
            timeout=args.timeout,
            workers=args.workers,
            client=client,
            ship=args.ship,
        )
    finally:
        bar.close()
        if client is not None:
            client.close()
    for line in summary.lines():
        print(line)
    print(f"results: {args.out}")
    if args.report:
        summary.write_report(args.report)
        print(f"report: {args.report}")
    return 1 if summary.errors else 0
