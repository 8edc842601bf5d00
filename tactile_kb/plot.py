"""Pictures of what the finger found: the path, the contacts, the model, the grasp, the tree.

Every function builds a :class:`matplotlib.figure.Figure` of its own (never pyplot, so no
global state leaks between calls and nothing needs a display), returns it, and writes it to
``path`` when one is given, as PNG, SVG or PDF by the file's extension. The figure is exactly
``size`` inches at ``dpi`` (640 × 480 pixels by default).

* :func:`plot_exploration`: the object mesh (faint, when given), the finger's path, its
  contacts coloured by the sensor that fired, the reconstructed polyhedron (dashed when it is
  only the convex envelope of a non-convex object), the chosen grasp; for objects explored in
  layers, the extruded layer model the grasp was planned on, and a second panel with the
  contour polygon of each layer, the grasp and the centre of mass seen from above.
* :func:`plot_tree`: a rule file's choice tree (the paper's Fig. 3): the phases in order, the
  values of their propositions on each branch, the classes at the leaves, with the path a
  decision took highlighted.
* :func:`plot_classification`: what ``tactile-kb classify --plot`` draws for a result of
  :func:`tactile_kb.pipeline.classify`.

Examples
--------
>>> from tactile_kb.touch.finger import builtin_finger
>>> from tactile_kb.solids import box
>>> from tactile_kb.touch.synthetic import sample_record
>>> fig = plot_exploration(sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), seed=1))
>>> [round(float(v)) for v in fig.get_size_inches() * fig.dpi]
[800, 600]
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.patches import FancyBboxPatch
from mpl_toolkits.mplot3d.art3d import (  # type: ignore[import-untyped]
    Line3DCollection,
    Poly3DCollection,
)

from tactile_kb.errors import OutputError, UsageError
from tactile_kb.files import atomic_write
from tactile_kb.geometry.blocks import SectionSolid
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.grasp.planner import GraspPlan
from tactile_kb.kb.tree import TreeNode, choice_tree
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import Orientation

if TYPE_CHECKING:
    import trimesh

    from tactile_kb.kb.base import KnowledgeBase
    from tactile_kb.kb.engine import Decision
    from tactile_kb.kb.rules import RuleSet

__all__ = [
    "FORMATS",
    "plot_classification",
    "plot_exploration",
    "plot_tree",
    "save_figure",
]

FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
"""File extensions :func:`save_figure` writes, and their formats."""

DEFAULT_SIZE = (8.0, 6.0)
DEFAULT_DPI = 100
"""The choice tree enumerates r(L) up to this many minterms; beyond, only the phases show."""
TREE_LEAF_LIMIT = 48

_TREE_RIGHT = 0.66  # x of the last phase column (axes fraction)
_TREE_LEAF = 0.70  # x where the answers begin
_LEAF_CHARS = 34
_LEAF_PT = 34.0  # vertical points one answer box needs (two lines of 9 pt and a gap)
_FONT = 10  # axis labels and legends, points
_TICK_FONT = 9  # tick labels, points
_TITLE_FONT = 11
_MAX_FACE_ENTRIES = 10  # faces beyond these share one legend entry
_HIGHLIGHT = "#e66100"
_MODEL = "#1f5fbf"
_GRASP = "#c01c28"
_TILTED = "#e66100"  # the shaft at a touch made with the head indexed away from the vertical


def _figure(size: tuple[float, float], dpi: float) -> Figure:
    if len(size) != 2 or min(size) <= 0 or dpi <= 0:
        raise UsageError(f"a figure needs a positive size and dpi, got {size} at {dpi}")
    return Figure(figsize=size, dpi=dpi)


def save_figure(fig: Figure, path: str | Path, *, dpi: float | None = None) -> Path:
    """Write ``fig`` to ``path`` (.png, .svg or .pdf) at its own size; return the path."""
    p = Path(path)
    fmt = FORMATS.get(p.suffix.lower())
    if fmt is None:
        known = ", ".join(FORMATS)
        raise UsageError(f"{p}: cannot write a picture with suffix {p.suffix!r} (use {known})")
    if not p.parent.exists():
        raise UsageError(f"{p}: the directory {p.parent} does not exist")
    try:  # atomically: a failure or a kill leaves any earlier picture at ``p`` as it was
        atomic_write(p, lambda f: fig.savefig(f, format=fmt, dpi=dpi or fig.dpi))
    except OSError as exc:
        raise OutputError(f"{p}: cannot write the picture: {exc.strerror or exc}") from None
    return p


# ---------------------------------------------------------------------------------------------
# Exploration, model and grasp
# ---------------------------------------------------------------------------------------------


_Box = tuple[np.ndarray[Any, np.dtype[np.float64]], np.ndarray[Any, np.dtype[np.float64]]]
"""An axis-aligned box: its lower and upper corners."""

VIEW_MARGIN = 0.35
"""The 3-D view frames the object (its mesh, else its contacts and model) and this share of its
size around it; the finger's path is clipped there, so a long approach from the workspace's
edge does not shrink the object to a speck."""


def _view_box(
    points: np.ndarray[Any, np.dtype[np.float64]],
) -> _Box:
    """A cube (lower and upper corners) around ``points`` with :data:`VIEW_MARGIN` of its size
    to spare, its floor at most 2 mm below the lowest point (the table). A cube keeps the three
    axes at equal scales and their labels where matplotlib places them well."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2.0
    half = max(float((hi - lo).max()) / 2.0, 1e-3) * (1.0 + VIEW_MARGIN)
    low = centre - half
    low[2] = max(low[2], float(lo[2]) - 0.002)
    return low, low + 2.0 * half


def _set_view(
    ax: Any,
    box: _Box,
) -> None:
    low, high = box
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_zlim(low[2], high[2])
    ax.set_box_aspect((1.0, 1.0, 1.0), zoom=0.95)


def _clip_polyline(
    path: np.ndarray[Any, np.dtype[np.float64]],
    box: _Box,
) -> list[np.ndarray[Any, np.dtype[np.float64]]]:
    """The parts of the polyline ``path`` (N, 3) inside the axis-aligned ``box``, as (2, 3)
    segments (Liang-Barsky clipping of every step)."""
    if len(path) < 2:
        return []
    low, high = box
    a, d = path[:-1], np.diff(path, axis=0)
    t0, t1 = np.zeros(len(d)), np.ones(len(d))
    with np.errstate(divide="ignore", invalid="ignore"):
        for k in range(3):
            still = np.abs(d[:, k]) < 1e-15
            outside = still & ((a[:, k] < low[k]) | (a[:, k] > high[k]))
            t1[outside] = -1.0
            ta, tb = (low[k] - a[:, k]) / d[:, k], (high[k] - a[:, k]) / d[:, k]
            enter, leave = np.minimum(ta, tb), np.maximum(ta, tb)
            t0 = np.where(still, t0, np.maximum(t0, enter))
            t1 = np.where(still, t1, np.minimum(t1, leave))
    keep = t1 > t0
    a, d, t0, t1 = a[keep], d[keep], t0[keep], t1[keep]
    return list(np.stack([a + t0[:, None] * d, a + t1[:, None] * d], axis=1))


def _draw_3d(
    ax: Any,
    record: ExplorationRecord,
    model: ObjectModel | None,
    mesh: trimesh.Trimesh | None,
    grasp: GraspPlan | None,
    fig: Figure,
    layered: bool = False,
) -> None:
    extent: list[np.ndarray[Any, np.dtype[np.float64]]] = []
    if mesh is not None:
        tris = np.asarray(mesh.vertices)[np.asarray(mesh.faces)]
        ax.add_collection3d(
            Poly3DCollection(
                tris, facecolor="0.55", edgecolor="none", alpha=0.18, label="object (true mesh)"
            )
        )
        extent.append(np.asarray(mesh.vertices, dtype=float))
    if record.path:
        ax.plot([], [], [], color="0.45", lw=0.6, label="finger path (tip centre)")
    if record.contacts:
        pts = np.asarray([c.point for c in record.contacts], dtype=float)
        _draw_contacts(ax, pts, model)
        extent.append(pts)
        _draw_shafts(ax, record)
    poly = model.polyhedron if model is not None else None
    solid = grasp.solid if grasp is not None else None
    if poly is not None:
        segs = [poly.vertices[[i, j]] for i, j in poly.edges]
        curved = model is not None and _is_curved(model)
        if model is not None and (not model.convex or curved):
            # only an envelope: the object lies inside it, touching it where it was touched
            what = "curved surface" if curved else "concave faces"
            ax.add_collection3d(
                Line3DCollection(
                    segs, colors=_MODEL, linewidths=0.8, linestyles="dashed", alpha=0.6
                )
            )
            ax.plot(
                [],
                [],
                [],
                color=_MODEL,
                lw=0.8,
                ls="--",
                alpha=0.6,
                label=f"envelope of the touched planes\n({what}: the object lies inside)",
            )
        else:
            ax.add_collection3d(Line3DCollection(segs, colors=_MODEL, linewidths=1.2))
            ax.plot([], [], [], color=_MODEL, lw=1.2, label="polyhedron (the model)")
        extent.append(np.asarray(poly.vertices, dtype=float))
    if solid is not None:
        segs = _block_edges(solid)
        ax.add_collection3d(Line3DCollection(segs, colors=_MODEL, linewidths=1.0))
        ax.plot([], [], [], color=_MODEL, lw=1.0, label="layer model")
        extent.append(np.vstack(segs))
    if grasp is not None and grasp.best is not None:
        p = np.asarray(grasp.best.points, dtype=float)
        n = np.asarray(grasp.best.normals, dtype=float)
        ax.plot(p[:, 0], p[:, 1], p[:, 2], color=_GRASP, lw=1.5, ls="--")
        ax.scatter(p[:, 0], p[:, 1], p[:, 2], color=_GRASP, s=40, marker="o", depthshade=False)
        jaw = 0.25 * max(grasp.best.width, 0.02)
        for q, m in zip(p, n, strict=True):
            start = q + jaw * m
            ax.quiver(*start, *(-jaw * m), color=_GRASP, lw=2.0, arrow_length_ratio=0.3)
        ax.plot([], [], [], color=_GRASP, lw=1.5, label="grasp (jaws and their line)")
        if grasp.com is not None:
            c = np.asarray(grasp.com)
            ax.scatter(
                [c[0]],
                [c[1]],
                [c[2]],
                color="k",
                marker="x",
                s=40,
                depthshade=False,
                label="centre of mass",
            )
    path = np.asarray(record.path, dtype=float).reshape(-1, 3)
    if extent or len(path):
        box = _view_box(np.vstack(extent) if extent else path)
        steps = _clip_polyline(path, box)
        if steps:
            ax.add_collection3d(Line3DCollection(steps, colors="0.45", linewidths=0.6))
        _set_view(ax, box)
    for axis in "xyz":
        getattr(ax, f"set_{axis}label")(f"{axis} (mm)", fontsize=_FONT, labelpad=6)
    _millimetres(ax)
    ax.tick_params(labelsize=_TICK_FONT, pad=1)


def _draw_shafts(ax: Any, record: ExplorationRecord) -> None:
    """At every touch, a short segment from the tip centre along the finger's shaft: the
    head's pose there: black where the finger hung vertically, orange (and thicker) where the
    head was indexed away from the vertical to reach an overhang or an underside.
    Only records whose head ever left the vertical draw them (the paper's finger hangs
    vertically all along)."""
    touches = [c for c in record.contacts if c.kind == "touch"]
    if not any(c.orientation != (0.0, 0.0) for c in touches):
        return
    pts = np.asarray([c.centre for c in record.contacts], dtype=float)
    length = max(4.0 * record.tip_radius, 0.2 * float(np.linalg.norm(np.ptp(pts, axis=0))))
    groups: dict[bool, list[np.ndarray[Any, np.dtype[np.float64]]]] = {False: [], True: []}
    for c in touches:
        tilt, turn = c.orientation
        axis = np.asarray(Orientation(tilt, turn).axis, dtype=float)
        centre = np.asarray(c.centre, dtype=float)
        groups[abs(tilt) > 1e-9].append(np.vstack([centre, centre + length * axis]))
    if groups[False]:
        ax.add_collection3d(Line3DCollection(groups[False], colors="k", linewidths=1.4))
        ax.plot(
            [], [], [], color="k", lw=1.4, label="finger's shaft at a touch:\nhanging vertically"
        )
    if groups[True]:
        ax.add_collection3d(Line3DCollection(groups[True], colors=_TILTED, linewidths=2.0))
        ax.plot(
            [],
            [],
            [],
            color=_TILTED,
            lw=2.0,
            label="finger's shaft at a touch: head indexed,\n"
            f"tilted from the vertical ({len(groups[True])} touches)",
        )


def _millimetres(ax: Any) -> None:
    """Tick labels in millimetres (the data stay in metres), a few per axis."""
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    fmt = FuncFormatter(lambda v, _pos: f"{v * 1000:.0f}")
    for axis in (ax.xaxis, ax.yaxis, *((ax.zaxis,) if hasattr(ax, "zaxis") else ())):
        axis.set_major_locator(MaxNLocator(4))
        axis.set_major_formatter(fmt)


def _is_curved(model: ObjectModel) -> bool:
    """What the ``surface_curved`` feature says of the model (False when it cannot say)."""
    from tactile_kb.features.builtin import get_feature

    try:
        return bool(get_feature("surface_curved").fn(model))
    except Exception:  # a model the feature cannot judge is drawn as it is
        return False


def _facing(normal: Sequence[float]) -> str:
    """A few words for a face's outward normal: top, bottom, or the side it faces."""
    x, y, z = (float(v) for v in normal)
    if z > 0.9:
        return "top"
    if z < -0.9:
        return "bottom"
    names = ["+x", "+x+y", "+y", "−x+y", "−x", "−x−y", "−y", "+x−y"]
    side = names[round(float(np.degrees(np.arctan2(y, x))) / 45.0) % 8]
    tilt = "" if abs(z) < 0.26 else (", up" if z > 0 else ", down")
    return f"{side}{tilt}"


def _draw_contacts(
    ax: Any, pts: np.ndarray[Any, np.dtype[np.float64]], model: ObjectModel | None
) -> None:
    """Contact points coloured by the face (fitted plane) they were assigned to, with a legend
    entry per face; contacts on no face are grey."""
    from matplotlib import colormaps

    faces = [] if model is None else [f for f in model.faces if f.source == "contacts"]
    owner = np.full(len(pts), -1)
    for k, face in enumerate(faces):
        idx = [i for i in face.contacts if 0 <= i < len(pts)]
        owner[idx] = k
    cmap = colormaps["tab10"]
    order = sorted(range(len(faces)), key=lambda k: -len(faces[k].contacts))
    for rank, k in enumerate(order):
        sel = owner == k
        if not sel.any():
            continue
        many = rank >= _MAX_FACE_ENTRIES
        label = None if many else f"face {rank + 1}: {_facing(faces[k].normal)} ({int(sel.sum())})"
        colour = "0.35" if many else cmap(rank % 10)
        ax.scatter(*pts[sel].T, color=colour, s=10, depthshade=False, label=label)
    rest = owner == -1
    if len(faces) > _MAX_FACE_ENTRIES:
        ax.scatter(
            [], [], [], color="0.35", s=10, label=f"{len(faces) - _MAX_FACE_ENTRIES} more faces"
        )
    if rest.any():
        what = "contacts" if not faces else "on no face"
        ax.scatter(
            *pts[rest].T, color="0.6", s=8, depthshade=False, label=f"{what} ({int(rest.sum())})"
        )


def _block_edges(solid: SectionSolid) -> list[np.ndarray[Any, np.dtype[np.float64]]]:
    """The edges of the extruded layer contours: bottom and top rings and vertical edges."""
    segs = []
    for block in solid.blocks:
        ring = np.asarray(block.polygon, dtype=float)
        nxt = np.roll(ring, -1, axis=0)
        for z in (block.z0, block.z1):
            segs += [np.array([[*a, z], [*b, z]]) for a, b in zip(ring, nxt, strict=True)]
        segs += [np.array([[*a, block.z0], [*a, block.z1]]) for a in ring]
    return segs


def _draw_layers(ax: Any, model: ObjectModel, grasp: GraspPlan | None = None) -> None:
    layers = [lay for lay in model.layers if len(lay.contour) >= 3]
    colours = Normalize(0, max(len(layers) - 1, 1))
    from matplotlib import colormaps

    cmap = colormaps["viridis"]
    rec = model.record
    if rec.contacts:  # every contact, beneath the contours: where the finger found the object
        pts = np.asarray([c.point for c in rec.contacts], dtype=float)
        ax.scatter(
            pts[:, 0], pts[:, 1], color="0.6", s=6, zorder=1, label=f"contact points ({len(pts)})"
        )
    for k, lay in enumerate(layers):
        c = np.asarray(lay.contour, dtype=float)
        loop = np.vstack([c, c[:1]]) if lay.closed else c
        ax.plot(
            loop[:, 0],
            loop[:, 1],
            color=cmap(colours(k)),
            lw=1.2,
            marker="o",
            ms=2.5,
            label=f"z = {lay.z * 1000:.0f} mm ({len(c)} corners)",
        )
    for rec_layer in rec.layers:
        if rec_layer.path:
            p = np.asarray(rec_layer.path, dtype=np.float64)
            ax.plot(p[:, 0], p[:, 1], color="0.7", lw=0.5)
    if grasp is not None and grasp.best is not None:
        p = np.asarray(grasp.best.points, dtype=float)
        ax.plot(p[:, 0], p[:, 1], color=_GRASP, lw=1.5, ls="--", marker="o", ms=4, label="grasp")
    if grasp is not None and grasp.com is not None:
        ax.plot([grasp.com[0]], [grasp.com[1]], "kx", ms=5, label="centre of mass")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("layer contours, seen from above", fontsize=_FONT)
    ax.set_xlabel("x (mm)", fontsize=_FONT)
    ax.set_ylabel("y (mm)", fontsize=_FONT)
    _millimetres(ax)
    ax.tick_params(labelsize=_TICK_FONT)
    if layers:  # below the panel, never over the contours
        box = ax.get_position()  # below the x axis's ticks and label, whatever the axes' height
        below = 3.2 * _FONT / (72.0 * float(ax.figure.get_size_inches()[1]))
        ax.legend(
            fontsize=_FONT - 1,
            frameon=False,
            loc="upper center",
            bbox_to_anchor=(box.x0 + box.width / 2.0, box.y0 - below),
            bbox_transform=ax.figure.transFigure,
            ncol=1,
        )


def plot_exploration(
    record_or_model: ExplorationRecord | ObjectModel,
    path: str | Path | None = None,
    *,
    mesh: trimesh.Trimesh | None = None,
    grasp: GraspPlan | bool | None = None,
    title: str | None = None,
    size: tuple[float, float] = DEFAULT_SIZE,
    dpi: float = DEFAULT_DPI,
) -> Figure:
    """Draw an exploration: mesh, path, contacts by sensor, polyhedron, grasp, layer contours.

    Parameters
    ----------
    record_or_model
        An exploration record (its model is built) or a model.
    path
        Write the figure there (.png, .svg or .pdf) when given.
    mesh
        The true object, drawn faintly (a record does not carry it).
    grasp
        A plan to draw, or True to plan one with :func:`tactile_kb.grasp.planner.plan_grasp`.
    title
        Default: the object's name, its contact and face counts.
    size, dpi
        Figure size in inches and its resolution.
    """
    if isinstance(record_or_model, ObjectModel):
        model = record_or_model
    elif isinstance(record_or_model, ExplorationRecord):
        model = build_model(record_or_model)
    else:
        raise UsageError(
            f"plot_exploration needs a record or a model, got {type(record_or_model).__name__}"
        )
    record = model.record
    plan: GraspPlan | None
    if grasp is True:
        from tactile_kb.grasp.planner import plan_grasp

        plan = plan_grasp(model)
    elif isinstance(grasp, GraspPlan):
        plan = grasp
    else:
        plan = None
    fig = _figure(size, dpi)
    if title is None:
        title = f"{record.object or 'object'}\n{_counts(model)}"
        if plan is not None:
            title += "\n" + _grasp_line(plan)
    title = _wrap(title, size[0])
    # the panels start below the title's lines (and the layer panel's own title line)
    line = 1.35 * _TITLE_FONT / (72.0 * size[1])  # one title line, a share of the height
    below = 0.985 - (title.count("\n") + 1) * line
    layered = any(len(lay.contour) >= 3 for lay in model.layers) and (
        model.polyhedron is None or not model.convex
    )
    if layered:  # the 3-D view and the layer contours side by side, each legend below its view
        top = min(0.86, below)
        ax3 = fig.add_axes((0.0, 0.30, 0.52, top - 0.30), projection="3d")
        top = min(0.84, below - 1.6 * _FONT / (72.0 * size[1]))
        ax2 = fig.add_axes((0.62, 0.40, 0.35, top - 0.40))
        _draw_layers(ax2, model, plan)
    else:  # the 3-D view, its legend on the right
        ax3 = fig.add_axes((0.0, 0.02, 0.56, min(0.84, below) - 0.02), projection="3d")
    _draw_3d(ax3, record, model, mesh, plan, fig, layered)
    handles, labels = ax3.get_legend_handles_labels()
    if handles:  # an empty record draws nothing to name
        where: dict[str, Any] = (
            {"loc": "upper center", "ncol": 2, "bbox_to_anchor": (0.27, 0.255)}
            if layered
            else {"loc": "center left", "ncol": 1, "bbox_to_anchor": (0.58, 0.45)}
        )
        _fitting_legend(
            fig,
            handles,
            labels,
            title="(n): contacts on the face" if any(": " in x for x in labels) else None,
            right=0.6 if layered else 1.0,
            **where,
        )
    fig.suptitle(title, fontsize=_TITLE_FONT)
    if path is not None:
        save_figure(fig, path)
    return fig


def _fitting_legend(
    fig: Figure,
    handles: Sequence[Any],
    labels: Sequence[str],
    *,
    title: str | None,
    right: float,
    **where: Any,
) -> None:
    """The figure's legend at ``where``, its font made smaller (down to 5 points) until it lies
    inside the figure, left of ``right`` (a share of the width: the layer panel's legend is
    on the right). A long legend of a small figure would otherwise be cut off."""
    width, height = fig.bbox.width, fig.bbox.height
    size = float(_FONT - 1)
    while True:
        legend = fig.legend(
            handles,
            labels,
            fontsize=size,
            frameon=False,
            title=title,
            title_fontsize=size,
            columnspacing=1.0,
            **where,
        )
        box = legend.get_window_extent()  # laid out by the figure's own renderer
        inside = box.x0 >= 0 and box.y0 >= 0 and box.x1 <= right * width and box.y1 <= height
        if inside or size <= 5.0:
            return
        legend.remove()
        size -= 0.5


def _counts(model: ObjectModel) -> str:
    """``9 touches, 139 contacts, 6 faces``: what the finger did and what it found."""
    record = model.record
    if model.polyhedron is None and model.layers:
        found = f"{len(model.layers)} layer contours"
    else:
        n = len(model.polyhedron.faces) if model.polyhedron is not None else 0
        found = f"{n} face{'s' * (n != 1)} in the model"
    return (
        f"{record.touches} touches (a sensor closing), {len(record.contacts)} contacts "
        f"recorded, {found}"
    )


def _grasp_line(plan: GraspPlan) -> str:
    b = plan.best
    if b is None:
        return f"no grasp: {plan.reason}"
    force = "cannot hold it" if b.least_force is None else f"least force {b.least_force:.1f} N"
    where = " on the layer contours" if plan.basis == "sections" else ""
    return (
        f"grasp{where}: jaws {b.width * 1000:.0f} mm apart, "
        f"{b.com_offset * 1000:.0f} mm from the centre of mass, {force}"
    )


def _wrap(text: str, width_in: float) -> str:
    """Wrap each line of a title to the figure's width (about 11 characters per inch at 11 pt)."""
    chars = max(int(width_in * 11), 20)
    return "\n".join(textwrap.fill(line, chars) for line in text.splitlines())


def plot_classification(
    result: Any,
    path: str | Path | None = None,
    *,
    mesh: trimesh.Trimesh | None = None,
    grasp: GraspPlan | bool | None = True,
    size: tuple[float, float] = DEFAULT_SIZE,
    dpi: float = DEFAULT_DPI,
) -> Figure:
    """Draw a :class:`tactile_kb.pipeline.Classification`: its model, grasp and answer.

    ``result`` needs ``.model`` (an ObjectModel), ``.decision`` (with ``.answer`` and
    ``.bits``) and ``.object``.
    """
    model = getattr(result, "model", None)
    decision = getattr(result, "decision", None)
    if not isinstance(model, ObjectModel) or decision is None:
        raise UsageError("plot_classification needs a classification result (model, decision)")
    answer = getattr(result, "answer", decision.answer)  # with its reported measures
    name = getattr(result, "object", "") or model.record.object
    title = f"{name}: {answer}\n{_counts(model)}"
    if isinstance(grasp, GraspPlan):
        title += "\n" + _grasp_line(grasp)
    elif grasp is True:
        from tactile_kb.grasp.planner import plan_grasp

        grasp = plan_grasp(model)
        title += "\n" + _grasp_line(grasp)
    fig = plot_exploration(model, None, mesh=mesh, grasp=grasp, title=title, size=size, dpi=dpi)
    if path is not None:
        save_figure(fig, path)
    return fig


# ---------------------------------------------------------------------------------------------
# The choice tree
# ---------------------------------------------------------------------------------------------


def _mathtext(values: Sequence[tuple[str, bool]]) -> str:
    parts = [(rf"\bar{{{n}}}" if not v else n).replace("_", r"\_") for n, v in values]
    return "$" + r"\cdot ".join(parts) + "$" if parts else ""


def _on_path(node: TreeNode, values: Mapping[str, bool | None]) -> bool:
    return all(values.get(n) is v for n, v in node.values)


def _hot(node: TreeNode, values: Mapping[str, bool | None], decision: Decision) -> bool:
    """Whether the decision's path takes this branch: its values are the decision's, or it is
    a leaf of the decided class whose other values the decision left open (they did not
    matter)."""
    if _on_path(node, values):
        return True
    return (
        not node.children
        and node.label == decision.label
        and all(values.get(n) in (v, None) for n, v in node.values)
    )


def plot_tree(
    rules: RuleSet | KnowledgeBase | str | Path,
    path: str | Path | None = None,
    *,
    decision: Decision | None = None,
    assignment: Mapping[str, bool] | str | None = None,
    size: tuple[float, float] = (9.6, 6.4),
    dpi: float = DEFAULT_DPI,
) -> Figure:
    """Draw the choice tree of a rule file, with the path of a decision highlighted.

    Parameters
    ----------
    rules
        A packaged rule set name, a YAML file, a RuleSet or a compiled KnowledgeBase.
    path
        Write the figure there when given.
    decision
        Highlight the branches this decision took and its class.
    assignment
        Or: truth values (a mapping, or a bit string like ``"101101111"``) to classify and
        highlight.
    size, dpi
        Figure size (inches) and resolution.
    """
    from tactile_kb.kb.base import KnowledgeBase
    from tactile_kb.kb.compiler import compile_rules

    kb = rules if isinstance(rules, KnowledgeBase) else compile_rules(rules)
    if decision is None and assignment is not None:
        decision = kb.classify(assignment)
    values: dict[str, bool | None] = dict(decision.values) if decision is not None else {}
    fig = _figure(size, dpi)
    ax = fig.add_axes((0.01, 0.01, 0.98, 0.9))
    ax.set_axis_off()
    phases = kb.rules.phases
    ncol = len(phases) + 1
    root = choice_tree(kb)
    collapsed = False
    fit = max(6, int(0.84 * size[1] * 72.0 / _LEAF_PT))  # leaves that fit, legibly
    if root is not None and root.leaves > fit:
        root = _collapse(root, values if decision is not None else None, fit)
        collapsed = True
    xs = np.linspace(0.03, _TREE_RIGHT, ncol)
    # phase headers: the paper's "classification carried out in phases"
    column_pt = (xs[1] - xs[0]) * 0.98 * size[0] * 72.0
    head_font = float(np.clip(column_pt / 7.0, 6.5, 9.0))
    chars = max(int(column_pt / (0.55 * head_font)), 4)
    for k, ph in enumerate(phases):
        props = ", ".join(ph.propositions)
        head = textwrap.fill(f"{ph.id} {ph.title}".strip(), chars)
        ax.text(
            (xs[k] + xs[k + 1]) / 2,
            1.0,
            f"{head}\n{textwrap.fill(props, chars)}",
            ha="center",
            va="top",
            fontsize=head_font,
            color="0.25",
        )
    ax.text(_TREE_LEAF + 0.01, 1.0, "answer", ha="left", va="top", fontsize=9, color="0.25")
    ax.set_xlim(0, 1)
    ax.set_ylim(-0.02, 1.02)
    title = f"choice tree of {kb.rules.name}"
    if decision is not None:
        title += f": {decision.answer} (bits {decision.bits}, the highlighted path)"
    if collapsed:
        title += (
            "\nbranches off the path folded: each grey box lists the answers below it"
            if decision is not None
            else "\nthe deeper branches folded: each grey box lists the answers below it"
        )
    fig.suptitle(title, fontsize=_TITLE_FONT)
    if root is None:
        _phase_summary(ax, kb, xs, values)
    else:
        _draw_tree(ax, kb, root, xs, values, decision, size)
    if path is not None:
        save_figure(fig, path)
    return fig


def _answers_below(node: TreeNode) -> list[str]:
    if not node.children:
        return [node.answer] if node.answer else []
    out: list[str] = []
    for child in node.children:
        out += [a for a in _answers_below(child) if a not in out]
    return out


def _folded(node: TreeNode) -> TreeNode:
    """A leaf standing for ``node``'s subtree, listing the answers below it."""
    answers = _answers_below(node)
    if len(answers) == 1 and node.leaves == 1:
        return node
    shown = "; ".join(a.removeprefix("OBJECT IS ").lower() for a in answers[:2])
    more = f"; +{len(answers) - 2} more" if len(answers) > 2 else ""
    return TreeNode(
        phase=node.phase,
        values=node.values,
        label="folded",
        answer=f"({node.leaves} cases) {shown}{more}",
        count=node.count,
    )


def _collapse(root: TreeNode, values: Mapping[str, bool | None] | None, limit: int) -> TreeNode:
    """A copy of the tree small enough to read: with ``values``, the branches off the path
    they take are folded into one leaf each; without, the tree is unfolded level by level
    while it has at most ``limit`` leaves."""
    if values is not None:

        def keep(node: TreeNode) -> TreeNode:
            kids = [keep(c) if _on_path(c, values) else _folded(c) for c in node.children]
            return TreeNode(node.phase, node.values, kids, node.label, node.answer, node.count)

        return keep(root)
    # Unfold the biggest folded branch (most members of r(L)) while the tree still fits.
    opened: set[int] = {id(root)}
    blocked: set[int] = set()

    def build(node: TreeNode) -> TreeNode:
        if id(node) not in opened:
            return _folded(node)
        kids = [build(c) for c in node.children]
        return TreeNode(node.phase, node.values, kids, node.label, node.answer, node.count)

    def folded_nodes(node: TreeNode) -> list[TreeNode]:
        if id(node) not in opened:
            return [node] if node.children and id(node) not in blocked else []
        return [f for c in node.children for f in folded_nodes(c)]

    while True:
        candidates = sorted(folded_nodes(root), key=lambda n: -n.count)
        if not candidates:
            return build(root)
        best = candidates[0]
        opened.add(id(best))
        if build(root).leaves > limit:
            opened.discard(id(best))
            blocked.add(id(best))


def _draw_tree(
    ax: Any,
    kb: KnowledgeBase,
    root: TreeNode,
    xs: np.ndarray[Any, np.dtype[np.float64]],
    values: Mapping[str, bool | None],
    decision: Decision | None,
    size: tuple[float, float],
) -> None:
    n_leaves = max(root.leaves, 1)
    top, bottom = 0.86, 0.02
    step = (top - bottom) / max(n_leaves - 1, 1) if n_leaves > 1 else 0.0
    counter = [0]
    # leaves: two lines of _LEAF_CHARS characters in the right-hand column
    width_pt = (1.0 - _TREE_LEAF - 0.01) * 0.98 * size[0] * 72.0
    height_pt = (top - bottom) * 0.9 * size[1] * 72.0 / n_leaves
    font = float(np.clip(min(width_pt / (0.6 * _LEAF_CHARS), height_pt / 3.0), 6.0, 9.0))

    def place(node: TreeNode) -> float:
        if not node.children:
            node.y = top - counter[0] * step if n_leaves > 1 else (top + bottom) / 2
            counter[0] += 1
        else:
            ys = [place(c) for c in node.children]
            node.y = float(np.mean(ys))
        return node.y

    place(root)
    x_leaf = _TREE_LEAF

    def draw(node: TreeNode, hot: bool) -> None:
        x = xs[node.phase + 1]
        for child in node.children:
            child_hot = hot and decision is not None and _hot(child, values, decision)
            end_x = xs[child.phase + 1] if child.children else x_leaf
            colour = _HIGHLIGHT if child_hot else "0.55"
            width = 2.2 if child_hot else 0.7
            ax.plot([x, x, end_x], [node.y, child.y, child.y], color=colour, lw=width, zorder=1)
            ax.text(
                (x + xs[child.phase + 1]) / 2 if child.children else (x + end_x) / 2,
                child.y + 0.004,
                _mathtext(child.values),
                ha="center",
                va="bottom",
                fontsize=font,
                color=colour,
            )
            draw(child, child_hot)
        if not node.children:
            label_hot = hot and decision is not None and node.label == decision.label
            folded = node.label == "folded"
            ax.text(
                x_leaf + 0.01,
                node.y,
                "\n".join(textwrap.wrap(node.answer, _LEAF_CHARS, max_lines=2, placeholder=" …")),
                ha="left",
                va="center",
                fontsize=font,
                color="k",
                bbox={
                    "boxstyle": "round,pad=0.25",
                    "fc": "#fde2cf" if label_hot else "0.93" if folded else "#eef2f8",
                    "ec": _HIGHLIGHT if label_hot else "0.6",
                    "lw": 1.6 if label_hot else 0.5,
                },
                zorder=3,
            )
        ax.plot([x], [node.y], "o", ms=3, color="0.3", zorder=2)

    draw(root, True)


def _phase_summary(
    ax: Any,
    kb: KnowledgeBase,
    xs: np.ndarray[Any, np.dtype[np.float64]],
    values: Mapping[str, bool | None],
) -> None:
    """When r(L) is too large for a tree: each phase's propositions with their values."""
    for k, ph in enumerate(kb.rules.phases):
        lines = []
        for pid in ph.propositions:
            v = values.get(pid)
            mark = {True: "1", False: "0", None: "·"}[v]
            lines.append(f"{pid} = {mark}")
        box = FancyBboxPatch(
            (xs[k] + 0.005, 0.35), xs[k + 1] - xs[k] - 0.01, 0.45, boxstyle="round,pad=0.005"
        )
        box.set(fc="#eef2f8", ec="0.6", lw=0.5)
        ax.add_patch(box)
        ax.text((xs[k] + xs[k + 1]) / 2, 0.78, "\n".join(lines), ha="center", va="top", fontsize=6)
    classes = [c.answer for c in kb.classes] + [kb.rules.otherwise_answer]
    ax.text(_TREE_LEAF + 0.01, 0.8, "\n".join(classes), ha="left", va="top", fontsize=5)
