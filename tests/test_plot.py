"""Pictures: headless, non-empty, of the requested size; the choice tree against r(L)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from PIL import Image

from tactile_kb.errors import UsageError
from tactile_kb.geometry.model import build_model
from tactile_kb.grasp.planner import plan_grasp
from tactile_kb.kb.compiler import compile_rules
from tactile_kb.kb.tree import TreeNode, choice_tree
from tactile_kb.plot import (
    plot_classification,
    plot_exploration,
    plot_tree,
    save_figure,
)
from tactile_kb.record import ExplorationRecord
from tactile_kb.solids import box, l_shape, sphere
from tactile_kb.touch.explorers import get_explorer
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record


def _png(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def _drawn(path: Path, size: tuple[int, int]) -> None:
    pixels = _png(path)
    assert pixels.shape[:2] == (size[1], size[0])
    assert pixels.std() > 5  # not a blank canvas
    assert (pixels < 250).any(axis=2).mean() > 0.01  # something is drawn


@pytest.fixture(scope="module")
def box_record() -> ExplorationRecord:
    return sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), seed=1, name="box")


@pytest.mark.parametrize(("w", "h", "dpi"), [(6.4, 4.8, 100), (4.0, 3.0, 80), (3.0, 5.0, 50)])
def test_exploration_png_has_the_requested_size(
    tmp_path: Path, box_record: ExplorationRecord, w: float, h: float, dpi: int
) -> None:
    out = tmp_path / "box.png"
    mesh = box(0.1, 0.06, 0.04)
    plot_exploration(box_record, out, mesh=mesh, grasp=True, size=(w, h), dpi=dpi)
    _drawn(out, (round(w * dpi), round(h * dpi)))


def test_svg_and_pdf_by_extension(tmp_path: Path, box_record: ExplorationRecord) -> None:
    model = build_model(box_record)
    plot_exploration(model, tmp_path / "box.svg", grasp=plan_grasp(model))
    text = (tmp_path / "box.svg").read_text()
    assert "<svg" in text
    assert len(text) > 10_000
    plot_exploration(model, tmp_path / "box.pdf")
    assert (tmp_path / "box.pdf").read_bytes().startswith(b"%PDF")


def test_bad_picture_paths(tmp_path: Path, box_record: ExplorationRecord) -> None:
    with pytest.raises(UsageError, match="suffix"):
        plot_exploration(box_record, tmp_path / "box.gif")
    with pytest.raises(UsageError, match="does not exist"):
        plot_exploration(box_record, tmp_path / "missing" / "box.png")
    with pytest.raises(UsageError):
        plot_exploration("not a record")  # type: ignore[arg-type]
    fig = plot_exploration(box_record)
    with pytest.raises(UsageError):
        save_figure(fig, tmp_path / "box.jpeg")


def test_figures_do_not_touch_pyplot_state(box_record: ExplorationRecord) -> None:
    import matplotlib.pyplot as plt

    before = plt.get_fignums()
    plot_exploration(box_record)
    plot_tree("parallelepipeds")
    assert plt.get_fignums() == before


def test_layers_panel_for_box_unions(tmp_path: Path) -> None:
    mesh = l_shape(0.12, 0.08, 0.04, 0.04)
    record = get_explorer("stepper").explore(mesh, finger="4", seed=0)
    fig = plot_exploration(record, tmp_path / "l.png", mesh=mesh, size=(6.0, 3.0), dpi=60)
    assert len([ax for ax in fig.axes if ax.name != "3d"]) >= 1  # the contour panel
    contour_ax = next(ax for ax in fig.axes if ax.get_title().startswith("layer contours"))
    legend = contour_ax.get_legend()
    assert legend is not None
    assert any("6 corners" in t.get_text() for t in legend.get_texts())
    _drawn(tmp_path / "l.png", (360, 180))


def test_the_view_from_above_shows_every_contact() -> None:
    # a ball's model stays open when its slides fit planes of their own, and its one layer
    # contour can be a few millimetres wide: the contact points seen from above show where the
    # finger found the object, and the panel frames them all
    ball = sample_record(sphere(0.06), builtin_finger("33"), total=40, seed=2)
    contours = [c.model_copy(update={"layer": 0}) for c in ball.contacts[:3]]
    record = ball.model_copy(update={"contacts": [*contours, *ball.contacts[3:]]})
    model = build_model(record)
    assert model.layers
    assert len(model.layers[0].contour) >= 3
    model = dataclasses.replace(model, polyhedron=None)  # as open as the scanned ball's
    fig = plot_exploration(model)
    ax = next(ax for ax in fig.axes if ax.get_title().startswith("layer contours"))
    xy = np.asarray([c.point[:2] for c in record.contacts])
    dots = [c for c in ax.collections if len(c.get_offsets()) == len(xy)]
    assert len(dots) == 1
    assert np.allclose(np.sort(dots[0].get_offsets(), axis=0), np.sort(xy, axis=0))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= xy[:, 0].min()
    assert xy[:, 0].max() <= x1
    assert y0 <= xy[:, 1].min()
    assert xy[:, 1].max() <= y1
    legend = ax.get_legend()
    assert legend is not None
    assert f"contact points ({len(xy)})" in [t.get_text() for t in legend.get_texts()]


def test_box_union_grasp_is_drawn_on_the_layer_model(tmp_path: Path) -> None:
    mesh = l_shape(0.12, 0.08, 0.04, 0.04)
    record = get_explorer("stepper").explore(mesh, finger="4", seed=0)
    plan = plan_grasp(record)
    assert plan.best is not None
    fig = plot_exploration(record, tmp_path / "l.png", mesh=mesh, grasp=plan, dpi=60)
    assert "on the layer contours" in fig.texts[0].get_text()
    labels = _figure_legend(fig)
    assert "layer model" in labels
    assert "grasp (jaws and their line)" in labels
    contour_ax = next(ax for ax in fig.axes if ax.get_title().startswith("layer contours"))
    drawn = {line.get_label(): line for line in contour_ax.get_lines()}
    # the grasp seen from above joins the two grasp points
    xy = np.asarray(drawn["grasp"].get_xydata(), dtype=float)
    assert np.allclose(xy, np.asarray(plan.best.points)[:, :2])
    assert "centre of mass" in drawn
    _drawn(tmp_path / "l.png", (480, 360))


def test_a_non_convex_polyhedron_is_drawn_as_the_convex_envelope() -> None:
    mesh = l_shape(0.12, 0.08, 0.04, 0.04)
    record = sample_record(mesh, builtin_finger("33"), quantise=False, noise=0.0)
    fig = plot_exploration(record, grasp=True)
    labels = _figure_legend(fig)
    assert any(label.startswith("envelope of the touched planes\n(concave") for label in labels)
    assert not any(label.startswith("polyhedron") for label in labels)


def _figure_legend(fig: Figure) -> list[str]:
    """The labels of the figure's legend (beside or below the 3-D view)."""
    (legend,) = fig.legends
    return [t.get_text() for t in legend.get_texts()]


class _Result:
    def __init__(self, model: object, decision: object) -> None:
        self.model, self.decision, self.object = model, decision, "box"


def test_plot_classification(tmp_path: Path, box_record: ExplorationRecord) -> None:
    kb = compile_rules("parallelepipeds")
    result = _Result(build_model(box_record), kb.classify("101101011"))
    fig = plot_classification(result, tmp_path / "c.png", dpi=50)
    assert "RECTANGULAR PARALLELEPIPED" in fig.texts[0].get_text()
    _drawn(tmp_path / "c.png", (400, 300))  # the default 8 × 6 inches at 50 dpi
    with pytest.raises(UsageError):
        plot_classification(object())


def _walk(node: TreeNode, values: dict[str, bool]) -> TreeNode:
    while node.children:
        node = next(c for c in node.children if all(values[n] is v for n, v in c.values))
    return node


def test_choice_tree_agrees_with_the_engine_on_every_member_of_r_of_l() -> None:
    kb = compile_rules("parallelepipeds")
    root = choice_tree(kb)
    assert root is not None
    assert root.count == kb.r_count
    for term in kb.minterms():
        values = {name: ch == "1" for name, ch in zip(kb.ids, term, strict=True)}
        leaf = _walk(root, values)
        assert leaf.label == kb.classify(term).label
    # the tree starts with the paper's phase I: contact or not
    assert {c.values for c in root.children} == {(("A", True),), (("A", False),)}


def test_tree_picture_with_the_decision_path(tmp_path: Path) -> None:
    out = tmp_path / "tree.png"
    fig = plot_tree("parallelepipeds", out, assignment="101101111", size=(8.0, 5.0), dpi=60)
    assert "OBJECT IS A CUBE" in fig.texts[0].get_text()
    _drawn(out, (480, 300))
    hot = {
        t.get_text()
        for ax in fig.axes
        for t in ax.texts
        if (patch := t.get_bbox_patch()) is not None and to_hex(patch.get_edgecolor()) == "#e66100"
    }
    assert hot == {"OBJECT IS A CUBE"}


def test_gallery_page_shows_every_picture_and_they_are_small() -> None:
    from tactile_kb.gallery import gallery_items

    docs = Path(__file__).resolve().parents[1] / "docs"
    page = (docs / "gallery.md").read_text(encoding="utf-8")
    items = gallery_items()
    assert len(items) == 16  # twelve Fig. 5 objects, three box unions, the tree
    for item in items:
        assert f"(gallery/{item.file})" in page
        image = docs / "gallery" / item.file
        assert image.is_file(), image
        assert image.stat().st_size <= 100_000


def test_gallery_command_writes_every_picture(tmp_path: Path) -> None:
    from tactile_kb.gallery import gallery_items, main

    assert main([str(tmp_path)]) == 0
    for item in gallery_items():
        pixels = _png(tmp_path / item.file)
        assert pixels.std() > 5


def test_module_examples() -> None:
    import doctest

    import tactile_kb.plot

    result = doctest.testmod(tactile_kb.plot, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0


def test_a_large_tree_is_folded_off_the_path_and_the_answer_highlighted() -> None:
    kb = compile_rules("polyhedra")
    full = choice_tree(kb)
    assert full is not None
    assert full.leaves > 48
    decision = kb.classify("101101111000000")
    fig = plot_tree(kb, decision=decision)
    (ax,) = fig.axes
    boxes = [t for t in ax.texts if t.get_bbox_patch() is not None]
    assert 4 <= len(boxes) <= 20  # legible: folded to what fits
    hot = [t for t in boxes if to_hex(t.get_bbox_patch().get_edgecolor()) == "#e66100"]
    assert [t.get_text().replace("\n", " ") for t in hot] == [decision.answer]
    assert all(t.get_fontsize() >= 6 for t in ax.texts)
    assert "folded" in fig.texts[0].get_text()


def test_an_answer_reached_with_values_left_open_is_highlighted() -> None:
    """A cube's bits leave S open (it no longer matters): both R·S and R·S̄ cube leaves are
    lit, and only they; a leaf of another class with compatible values stays grey."""
    kb = compile_rules("polyhedra")
    decision = kb.classify("10110111110011-")
    assert decision.label == "cube"
    assert decision.values["S"] is None
    fig = plot_tree(kb, decision=decision)
    (ax,) = fig.axes
    boxes = [t for t in ax.texts if t.get_bbox_patch() is not None]
    hot = [t for t in boxes if to_hex(t.get_bbox_patch().get_edgecolor()) == "#e66100"]
    assert [t.get_text() for t in hot] == [decision.answer, decision.answer]
    assert all(len(t.get_text().splitlines()) <= 2 for t in boxes)  # no box spills over


def test_classify_plot_draws_the_true_mesh(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import tactile_kb.plot
    from tactile_kb.cli import main

    seen: list[object] = []
    real = tactile_kb.plot.plot_classification

    def spy(result: object, path: object = None, **kw: object) -> object:
        seen.append(kw.get("mesh"))
        return real(result, path, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(tactile_kb.plot, "plot_classification", spy)
    stl = tmp_path / "cube.stl"
    box(0.08, 0.08, 0.08).export(stl)
    assert main(["classify", str(stl), "--plot", str(tmp_path / "c.png")]) == 0
    (mesh,) = seen
    assert mesh is not None
    assert len(mesh.faces) == 12  # type: ignore[attr-defined]


def test_the_shaft_at_each_touch_shows_the_heads_pose(box_record: ExplorationRecord) -> None:
    # the paper's finger hangs vertically all along: no shafts are drawn
    assert not any("shaft" in label for label in _figure_legend(plot_exploration(box_record)))
    touches = [i for i, c in enumerate(box_record.contacts) if c.kind == "touch"]
    tilted = set(touches[:3])
    contacts = [
        c.model_copy(update={"orientation": (90.0, 45.0)}) if i in tilted else c
        for i, c in enumerate(box_record.contacts)
    ]
    record = box_record.model_copy(update={"contacts": contacts})
    fig = plot_exploration(record)
    labels = _figure_legend(fig)
    assert any(
        label.endswith(f"tilted from the vertical ({len(tilted)} touches)") for label in labels
    )
    assert any(
        label.startswith("finger's shaft at a touch:\nhanging vertically") for label in labels
    )
    # the tilted shafts run along the head's axis: at tilt 90°, turn 45° the shaft is horizontal
    # towards (+1, +1)/√2 (the tip points the other way)
    ax = fig.axes[0]
    orange = [
        c
        for c in ax.collections
        if type(c).__name__ == "Line3DCollection" and to_hex(c.get_color()[0]) == "#e66100"
    ]
    (shafts,) = orange
    segs = np.asarray(shafts._segments3d)
    d = segs[:, 1] - segs[:, 0]
    d /= np.linalg.norm(d, axis=1)[:, None]
    assert len(segs) == len(tilted)
    np.testing.assert_allclose(d, np.tile([0.5**0.5, 0.5**0.5, 0.0], (len(tilted), 1)), atol=1e-9)


def test_clip_polyline_keeps_what_lies_inside_the_box() -> None:
    from tactile_kb.plot import _clip_polyline

    box = (np.zeros(3), np.ones(3))
    path = np.array(
        [
            [-1.0, 0.5, 0.5],  # enters through x = 0 ...
            [0.5, 0.5, 0.5],  # ... inside ...
            [0.5, 0.5, 3.0],  # ... leaves through z = 1
            [2.0, 2.0, 2.0],  # wholly outside
            [2.0, 0.5, 0.5],  # outside, still outside
            [-2.0, 0.5, 0.5],  # crosses the whole box along x
        ]
    )
    segs = _clip_polyline(path, box)
    want = [
        [[0.0, 0.5, 0.5], [0.5, 0.5, 0.5]],
        [[0.5, 0.5, 0.5], [0.5, 0.5, 1.0]],
        [[1.0, 0.5, 0.5], [0.0, 0.5, 0.5]],
    ]
    np.testing.assert_allclose(np.array(segs), np.array(want), atol=1e-12)
    assert _clip_polyline(path[:1], box) == []
    # a step along the box's face (d = 0 in two coordinates) stays when on it, goes when beside
    edge = np.array([[0.0, 0.0, -1.0], [0.0, 0.0, 2.0]])
    np.testing.assert_allclose(_clip_polyline(edge, box)[0], [[0, 0, 0], [0, 0, 1]])
    assert _clip_polyline(edge + np.array([0.0, -0.1, 0.0]), box) == []


def test_the_view_frames_the_object_not_the_long_approach(box_record: ExplorationRecord) -> None:
    from tactile_kb.plot import VIEW_MARGIN

    far = [(-0.45, 0.4, 0.3), *box_record.path]  # an approach from the workspace's corner
    record = box_record.model_copy(update={"path": far})
    mesh = box(0.1, 0.1, 0.1)
    fig = plot_exploration(record, mesh=mesh)
    ax = next(ax for ax in fig.axes if ax.name == "3d")
    size = float(np.ptp(np.asarray(mesh.vertices), axis=0).max())
    spans = [hi - lo for lo, hi in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())]
    for span in spans:
        assert span <= size * (1.0 + VIEW_MARGIN) * 1.05  # matplotlib pads 3-D limits a little
    xlo, xhi = ax.get_xlim()
    assert xlo > -0.2  # the corner at x = -0.45 is outside the view
    assert xhi < 0.2
