"""The docs gallery: pictures of the paper's Fig. 5 objects, the box unions and the choice tree.

Regenerate every picture of ``docs/gallery.md`` with one command::

    python -m tactile_kb.gallery docs/gallery

Each Fig. 5 object is explored by the stepper with the 33-sensor finger, classified with the
packaged ``parallelepipeds`` rules and grasped; the L, T and U box unions (the paper's Fig. 1)
are explored with the 4-sensor finger, grasped on their stacked layer contours and drawn with
them; the choice tree of
the rules is drawn with the path the cube's decision took. Pictures are small PNGs (modest
DPI) so the repository stays light.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from tactile_kb.errors import UsageError

if TYPE_CHECKING:
    import trimesh
    from matplotlib.figure import Figure

__all__ = ["GALLERY_DPI", "GALLERY_SIZE", "GalleryItem", "build_gallery", "gallery_items", "main"]

GALLERY_SIZE = (8.0, 6.0)
"""Inches: 800 × 600 pixels at :data:`GALLERY_DPI`, so that 9-point labels stay legible."""

GALLERY_DPI = 100


@dataclass(frozen=True)
class GalleryItem:
    """One picture of the gallery: its file name and a one-line caption."""

    file: str
    caption: str


def _union_specs() -> list[tuple[str, Callable[[], trimesh.Trimesh]]]:
    from tactile_kb.solids import l_shape, t_shape, u_shape

    return [
        ("L", lambda: l_shape(0.12, 0.08, 0.04, 0.04)),
        ("T", lambda: t_shape(0.12, 0.10, 0.04, 0.04)),
        ("U", lambda: u_shape(0.12, 0.08, 0.03, 0.04)),
    ]


def gallery_items() -> list[GalleryItem]:
    """The pictures :func:`build_gallery` writes, in order (without exploring anything)."""
    from tactile_kb.solids import FIG5_LABELS

    items = [GalleryItem(f"{name.lower()}.png", name) for name in FIG5_LABELS]
    items += [
        GalleryItem(f"{name.lower()}-union.png", f"{name} box union") for name, _ in _union_specs()
    ]
    items.append(GalleryItem("tree-cube.png", "choice tree, the cube's path"))
    return items


def build_gallery(
    out: str | Path,
    *,
    size: tuple[float, float] = GALLERY_SIZE,
    dpi: float = GALLERY_DPI,
    log: Callable[[str], None] | None = None,
) -> list[Path]:
    """Explore, classify, grasp and draw every gallery object into directory ``out``.

    Returns the paths written, in the order of :func:`gallery_items`.
    """
    from tactile_kb.geometry.model import build_model
    from tactile_kb.grasp.planner import plan_grasp
    from tactile_kb.pipeline import classify, knowledge_base
    from tactile_kb.plot import plot_classification, plot_exploration, plot_tree
    from tactile_kb.solids import fig5_objects
    from tactile_kb.touch.explorers import get_explorer

    directory = Path(out)
    if not directory.is_dir():
        raise UsageError(f"{directory}: not a directory (create it first)")
    say = log or (lambda _text: None)
    kb = knowledge_base("parallelepipeds")
    written: list[Path] = []
    cube_decision = None
    for name, mesh, _expected in fig5_objects():
        result = classify(mesh, rules=kb, explorer="stepper", finger="33", seed=0)
        plan = plan_grasp(result.model)
        target = directory / f"{name.lower()}.png"
        fig = plot_classification(result, None, mesh=mesh, grasp=plan, size=size, dpi=dpi)
        title = fig.texts[0].get_text().split("\n", 1)[1]  # the counts and the grasp
        fig.texts[0].set_text(f"{name}: {result.answer}\n{title}")
        _save_small_png(fig, target, dpi)
        written.append(target)
        if name == "CUBE1":
            cube_decision = result.decision
        grasp = f"grasp {plan.best.width * 1000:.0f} mm" if plan.best else "no grasp"
        say(f"{target}: {result.decision.answer}, {grasp}")
    explorer = get_explorer("stepper")
    for name, make in _union_specs():
        mesh = make()
        record = explorer.explore(mesh, finger="4", seed=0)
        model = build_model(record)
        plan = plan_grasp(model)
        target = directory / f"{name.lower()}-union.png"
        grasp = (
            f"grasp on the layer contours: jaws {plan.best.width * 1000:.0f} mm apart, "
            f"{plan.best.com_offset * 1000:.0f} mm from the centre of mass"
            if plan.best
            else f"no grasp: {plan.reason}"
        )
        fig = plot_exploration(
            model,
            None,
            mesh=mesh,
            grasp=plan,
            title=(
                f"{name} box union, 4-sensor finger: {record.touches} touches, "
                f"{len(record.contacts)} contacts\n{grasp}"
            ),
            size=size,
            dpi=dpi,
        )
        _save_small_png(fig, target, dpi)
        written.append(target)
        say(f"{target}: {record.touches} touches, {len(record.layers)} layers, {grasp}")
    target = directory / "tree-cube.png"
    fig = plot_tree(kb, None, decision=cube_decision, size=(size[0] * 1.2, size[1] * 1.5), dpi=dpi)
    _save_small_png(fig, target, dpi)
    written.append(target)
    say(f"{target}")
    return written


def _save_small_png(fig: Figure, target: Path, dpi: float) -> None:
    """Write ``fig`` as a PNG of at most 256 colours (a third of the bytes; the pictures are
    flat colours), atomically."""
    import io

    from PIL import Image

    from tactile_kb.files import atomic_write

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi)
    buffer.seek(0)
    with Image.open(buffer) as image:
        small = image.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT)
        atomic_write(target, lambda f: small.save(f, format="PNG", optimize=True))


def _print(text: str) -> None:
    sys.stdout.write(text + "\n")


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m tactile_kb.gallery DIRECTORY``: regenerate the gallery pictures."""
    parser = argparse.ArgumentParser(prog="python -m tactile_kb.gallery", description=__doc__)
    parser.add_argument("directory", nargs="?", default="docs/gallery")
    args = parser.parse_args(argv)
    directory = Path(args.directory)
    directory.mkdir(parents=True, exist_ok=True)
    build_gallery(directory, log=_print)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
