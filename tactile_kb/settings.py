"""Every tolerance of the pipeline in one typed, documented, overridable settings object.

The stages read their tolerances from :func:`current` when they run, so a user can change
one for a block of code (thread- and task-safe: the settings live in a
:class:`contextvars.ContextVar`)::

    with settings.override(geometry={"cut_deg": 12.0}):
        model = build_model(record)

The groups follow the stages: :class:`WorldSettings` (the worlds' contact band),
:class:`FingerSettings`, :class:`ServoSettings` (the controller), :class:`ExploreSettings`
(the explorers' noise checks, the completion), :class:`GeometrySettings`
(faces, polyhedron, layers), :class:`FeatureSettings` (the built-in predicates),
:class:`GraspSettings` and :class:`ObjectSettings` (which meshes are accepted). Each field says
its unit and meaning; values are validated (a tolerance is positive, a fraction below 1).

Examples
--------
>>> from tactile_kb import settings
>>> settings.current().features.tolerance_deg
5.0
>>> with settings.override(features={"tolerance_deg": 2.0}) as s:
...     s.features.tolerance_deg, settings.current().features.tolerance_deg
(2.0, 2.0)
>>> settings.current().features.tolerance_deg
5.0
>>> settings.override(features={"tolerance_deg": -1.0})
Traceback (most recent call last):
...
tactile_kb.errors.UsageError: settings: features.tolerance_deg: Input should be greater than 0 (got -1.0)

The command line takes the same changes as ``--set GROUP.FIELD=VALUE`` or from a TOML file
(``--settings FILE``, one table per group): :meth:`Settings.assigned` and :func:`load`.

>>> settings.DEFAULTS.assigned(["explore.completion_touches=10"]).changes()
{'explore': {'completion_touches': 10}}
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Iterator, Mapping, Sequence
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from tactile_kb.errors import UsageError

__all__ = [
    "DEFAULTS",
    "ExploreSettings",
    "FeatureSettings",
    "FingerSettings",
    "GeometrySettings",
    "GraspSettings",
    "ObjectSettings",
    "ServoSettings",
    "Settings",
    "WorldSettings",
    "current",
    "load",
    "override",
    "use",
]


class _Group(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid", validate_default=True)


class WorldSettings(_Group):
    """The contact band every world (analytic, MuJoCo) shares."""

    contact_tol: float = Field(
        1e-7,
        gt=0,
        description="Metres: the tip touches the object when its centre is within ρ + contact_tol of it.",
    )
    block_tol: float = Field(
        1e-9,
        gt=0,
        description="Metres: a world blocks the tip where its distance to the object would drop "
        "below ρ − block_tol.",
    )
    same_contact_deg: float = Field(
        1.0,
        gt=0,
        lt=90,
        description="Degrees: a contact on a triangle's side this close in direction to a contact "
        "inside a face is the same contact (the analytic world).",
    )
    comply_deg: float = Field(
        0.0,
        ge=0,
        lt=90,
        description="Degrees: a slide in the analytic world rides over an irregularity (a bump, a "
        "dip, a crease between a scan's triangles) whose surface turns at most this far from the "
        "contact where the slide began, as a finger under force control does; a real edge turns "
        "further and ends the slide as a straight slide would (0, the default: straight slides "
        "only; 12 rides over a careful scan's roughness, but also over a 48-sided cylinder's "
        "7.5° facets).",
    )
    comply_step: float = Field(
        0.8,
        gt=0,
        le=1,
        description="Tip radii: how far ahead a compliant slide that lost the surface looks for it "
        "again (past a real convex edge the surface found there has turned by at least "
        "asin(comply_step), 53°, or by the edge's whole angle: more than comply_deg).",
    )
    comply_depth: float = Field(
        0.25,
        gt=0,
        le=1,
        description="Tip radii: the deepest dip a compliant slide rides over (it lifts this far off "
        "the surface, steps on by comply_step and presses back up to twice as far).",
    )


class FingerSettings(_Group):
    """What a finger layout must achieve."""

    align_4_deg: float = Field(
        10.0,
        gt=0,
        lt=90,
        description="Degrees: the 4-sensor finger is meant for surfaces facing its sensors; a "
        "surface turned further from its sensor is reported.",
    )
    max_usable_error_deg: float = Field(
        25.0,
        gt=0,
        lt=90,
        description="Degrees: the largest quantisation of a contact direction a layout may have "
        "for the features to be decided reliably (the 33-sensor finger: 20.3°).",
    )


class ServoSettings(_Group):
    """The controller that follows the surface."""

    curved_run: int = Field(
        3,
        ge=1,
        description="Edge touches in a row (each rolling off within edge_slide) that mean a "
        "curved surface.",
    )
    ride_step: float = Field(
        0.8,
        gt=0,
        description="Tip radii: how far a ride over an irregularity steps on before pressing back.",
    )
    ride_deg: float = Field(
        20.0,
        gt=0,
        lt=90,
        description="Degrees: a touch while riding over an irregularity whose sensors point this "
        "close to the surface's normal is the surface followed.",
    )
    ripple_deg: float = Field(
        35.0,
        gt=0,
        lt=90,
        description="Degrees: a sensor closing during a slide while the followed one stays ON, "
        "this close to it (a neighbour), is a ripple of the same surface, not a new touch.",
    )
    persist_tries: int = Field(
        0,
        ge=0,
        description="How often a blocked slide's re-acquisition backs off and steps on, each time "
        "twice as far, before the contour ends (0: a blocked slide ends it, as in the paper; 3 "
        "goes round rough scans).",
    )
    blind_rise: float = Field(
        0.5,
        ge=0,
        le=1,
        description="Tip radii: a contour's motion blocked where no sensor fires (a rough face's "
        "bump met above the sensors' cones) is tried again this much and twice this much above "
        "the layer (0: the blind block stands, as in the paper).",
    )


class ExploreSettings(_Group):
    """The explorers and the model-driven completion of an exploration."""

    noise_warn_fraction: float = Field(
        0.2,
        gt=0,
        description="Fraction of the tip radius: a contact-position noise σ above this is warned "
        "about (on the 5 mm tip, σ ≥ 1.5 mm makes flat faces read as curved).",
    )
    noise_object_fraction: float = Field(
        0.03,
        gt=0,
        description="Fraction of the object's thinnest extent: a noise σ above this is noted in "
        "the record.",
    )
    top_nz: float = Field(
        0.8,
        gt=0,
        le=1,
        description="A face whose normal's z component is at least this is a top, probed from "
        "above when its tip centres lie along one line.",
    )
    completion_touches: int = Field(
        24,
        ge=0,
        description="The completion's touch budget: at most this many touches after contour "
        "following (or two per face of the model, when that is more); 0: no completion.",
    )
    completion_path: float = Field(
        4.0,
        ge=0,
        description="Metres: the completion's path budget (or completion_path_sizes times the "
        "touched extent per touch of the budget, when that is more).",
    )
    completion_path_sizes: float = Field(
        4.0,
        gt=0,
        description="Touched extents: the completion's path budget per touch of its budget, when "
        "more than completion_path (a probe goes round the object to its start and back, about "
        "three extents, and some probes touch nothing).",
    )
    completion_attempts: int = Field(
        2,
        ge=1,
        description="Probes for one open item (a direction, a face) before the completion "
        "names it unreachable.",
    )
    spot_rho: float = Field(
        2.0,
        gt=0,
        description="Tip radii: a face whose tip centres all lie within this distance of each "
        "other in its plane was touched at one spot only (one probe and its short slide); the "
        "completion touches it once more, as far from there as the face allows.",
    )
    spot_deg: float = Field(
        2.0,
        ge=0,
        description="Degrees: a face touched at one spot is probed at a second one only when "
        "its normal's estimated uncertainty is at least this.",
    )
    spot_probes: int = Field(
        6,
        ge=0,
        description="At most this many second-spot probes per exploration (a face touched at "
        "one spot, touched again elsewhere); 0: none.",
    )
    overhang_deg: float = Field(
        3.0,
        ge=0,
        lt=90,
        description="Degrees: a side whose normal points down by more than this overhangs. "
        "The model's corners on the table are checked by level probes only when no side "
        "overhangs (an undercut's table corners are the probes near the table's business).",
    )


class GeometrySettings(_Group):
    """Faces from contacts, the enveloping polyhedron, layer sections and blocks."""

    cut_deg: float = Field(
        15.0,
        gt=0,
        lt=180,
        description="Degrees: cut of the normal clustering when the record names no sensor "
        "directions.",
    )
    split_tol: float = Field(
        0.0025,
        gt=0,
        description="Metres: largest distance of a tip centre from its face's fitted plane before "
        "the face is split (and the largest for two faces to merge as coplanar); records that "
        "declare a larger noise use six times that.",
    )
    span: float = Field(
        0.002,
        gt=0,
        description="Metres (RMS): centres span a face when their spread across the fitted line "
        "is at least this.",
    )
    merge_deg: float = Field(
        4.0,
        gt=0,
        lt=90,
        description="Degrees: two faces whose normals differ by less than this may merge if "
        "coplanar.",
    )
    unrefined_merge_cones: float = Field(
        2.5,
        ge=0,
        description="Sensor cones: a face whose tip centres do not span a plane (its normal the "
        "quantised sensors': a scanned face's bump fires the neighbouring sensor, 30° off on the "
        "33-sensor finger) merges with another face when their normals differ by less than this "
        "many of the finger's quantisation cones (half its sensor spacing), their centres together "
        "span one plane within split_tol, and that plane is the spanning face's (two faces that "
        "span none: within this angle of both).",
    )
    unrefined_merge_sigmas: float = Field(
        3.0,
        gt=0,
        description="A face whose tip centres do not span a plane merges with a spanning one "
        "(unrefined_merge_cones) only when the plane of both passes within this many times the "
        "spanning face's own scatter (at least robust_rho tip radii, or the declared noise) of "
        "the other's centres (their median).",
    )
    table_tol: float = Field(
        0.001,
        gt=0,
        description="Metres: contacts whose plane is the table top (normal within 10° of +z, "
        "|offset| below this) are ignored.",
    )
    robust_rho: float = Field(
        0.02,
        gt=0,
        description="Tip radii: the least scale of the robust plane fit of a face's tip centres "
        "(else the declared noise, or the centres' own scatter): centres further than 4 scales "
        "off its plane (touches of an edge beside it, relief) are left out.",
    )
    max_refine_deg: float = Field(
        35.0,
        gt=0,
        lt=90,
        description="Degrees: a fitted normal further than this from the contacts' sensor normal "
        "is not trusted.",
    )
    edge_rounding: float = Field(
        0.10,
        ge=0,
        lt=1,
        description="Fraction: real edges are rounded with a radius up to this fraction of the "
        "narrower of the two faces they join.",
    )
    rounded_fit_sigmas: float = Field(
        2.5,
        ge=0,
        description="When positive, a face the rounded envelope of the other faces explains "
        "(its touches within this many robust σ of it and on average within 2 σ/√m, mostly on "
        "an edge's or a corner's rounding) is dropped (tactile_kb.geometry.rounded); 0 keeps "
        "every face.",
    )
    rounded_min_width: float = Field(
        2.0,
        ge=0,
        description="Tip radii: the rounded envelope explains a face only by faces at least this "
        "wide (a curved object's narrow facets stay).",
    )
    edge_min_width: float = Field(
        4.0,
        gt=0,
        description="Tip radii: edge faces are looked for only against faces at least this wide.",
    )
    edge_sigmas: float = Field(
        2.0,
        ge=0,
        description="An edge face's penetration is allowed this many σ/√m of noise on top.",
    )
    relief_rho: float = Field(
        0.2,
        ge=0,
        description="Tip radii: the largest surface detail that is not shape (bumps, ripples, "
        "printed or embossed relief: 1 mm for the 5 mm tip). A face's tip centres may lie this "
        "far outside its plane, and a face's bending or turn is curvature only beyond what "
        "relief this high under its contacts can produce.",
    )
    merge_fraction: float = Field(
        0.03,
        gt=0,
        lt=1,
        description="Fraction of the object's diameter: vertices closer than this are merged.",
    )
    noisy_merge_fraction: float = Field(
        0.05,
        gt=0,
        lt=1,
        description="Fraction of the touched points' smallest extent: the vertex merge distance "
        "when the record declares contact-position noise (if larger than merge_fraction's).",
    )
    collapse_sigmas: float = Field(
        4.0,
        gt=0,
        description="Edges of a noisy model shorter than this many σ of their length are "
        "collapsed.",
    )
    assumed_top_deg: float = Field(
        10.0,
        gt=0,
        lt=90,
        description="Degrees: an open model is closed by an assumed top when every open direction "
        "is within this angle of +z.",
    )
    line_tol: float = Field(
        0.004,
        gt=0,
        description="Metres: two touched lines of a layer within this distance (and plane_deg) "
        "are the same plane.",
    )
    plane_deg: float = Field(
        8.0,
        gt=0,
        lt=90,
        description="Degrees: two touched lines of a layer within this angle (and line_tol) are "
        "the same plane.",
    )
    span_2d: float = Field(
        0.005,
        gt=0,
        description="Metres (RMS): a layer side's line is refined from its tip centres when they "
        "spread this much.",
    )
    same_contour: float = Field(
        0.05,
        gt=0,
        lt=1,
        description="Fraction: consecutive layers form one block when their contours differ by "
        "less than this fraction of the smaller one's area (symmetric difference).",
    )
    top_normal_deg: float = Field(
        20.0,
        gt=0,
        lt=90,
        description='Degrees: a contact whose normal is within this angle of "up" touched a top.',
    )
    section_tol: float = Field(
        0.001,
        gt=0,
        description="Metres: gaps and obstacles thinner than this along a grasp line or between "
        "layers are slivers of noise.",
    )


class FeatureSettings(_Group):
    """The built-in feature predicates."""

    tolerance_deg: float = Field(
        5.0,
        gt=0,
        lt=90,
        description="Degrees: faces and edges this close in angle are parallel or perpendicular "
        "(widened by sigmas × the face normals' uncertainty).",
    )
    sigmas: float = Field(
        3.0,
        ge=0,
        description="Standard deviations of the normals' uncertainty added to tolerance_deg.",
    )
    residual_rho: float = Field(
        0.3,
        gt=0,
        description="Tip radii (RMS): a face whose tip centres miss its plane by more than this is "
        "curved.",
    )
    sagitta_rho: float = Field(
        0.5,
        gt=0,
        description="Tip radii: a face whose centres bend by more than this over the face (and "
        "sagitta_fraction) is curved.",
    )
    sagitta_fraction: float = Field(
        0.03,
        gt=0,
        lt=1,
        description="Fraction of the face's extent: a face bending by more than this (and "
        "sagitta_rho) is curved.",
    )
    spread_deg: float = Field(
        10.0,
        gt=0,
        lt=180,
        description="Degrees: a face whose interior contacts fired sensors further apart, and "
        "whose tip centres turn by more than this (by bend_sigmas standard errors), is "
        "curved; where the centres cannot measure the turn, or estimate it at least this "
        "without establishing it, the spread counts as one gentle fold towards "
        "min_smooth_edges.",
    )
    bend_sigma_rho: float = Field(
        0.02,
        gt=0,
        description="Tip radii: the least scatter of tip centres (surface detail, the world's "
        "numerics) assumed when a face's turn is measured from them, if the record declares "
        "less noise.",
    )
    bend_sigmas: float = Field(
        3.0,
        gt=0,
        description="Standard errors by which a face's measured turn must exceed spread_deg to "
        "make the surface curved. Each face whose sensors spread is tested: at two, a flat "
        "face's turn passes one time in 44 (one-sided), a model with six such faces one time "
        "in eight; at three, one face in 740.",
    )
    min_sagitta_contacts: int = Field(
        8,
        ge=6,
        description="Fewer contacts on a face do not determine its bending (a quadric has six "
        "unknowns).",
    )
    smooth_deg: float = Field(
        35.0,
        gt=0,
        lt=180,
        description="Degrees: polyhedron edges whose faces turn by less than this are smooth "
        "(a tessellated curved surface).",
    )
    min_smooth_edges: int = Field(
        6,
        ge=1,
        description="At least this many smooth edges make a curved surface.",
    )
    circle_faces: int = Field(
        5,
        ge=3,
        description="Faces: at least this many faces around one axis whose tip centres lie on one "
        "circle (circle_rho, circle_arc_deg) make a curved surface (a lying cylinder touched "
        "in narrow facets).",
    )
    circle_rho: float = Field(
        0.05,
        gt=0,
        description="Tip radii (RMS, or circle_ratio × the faces' scatter): tip centres of faces around one "
        "axis that miss one circle by no more than this, over circle_arc_deg, with a radius "
        "over 1.5 ρ and sensors that turn with them, lie on a curved surface.",
    )
    circle_ratio: float = Field(
        0.0,
        ge=0,
        description="Factor: the RMS miss of the tip centres from their circle (circle_rho) may "
        "exceed the faces' own scatter about their planes by at most this (a polyhedron's "
        "faces fit their planes better than a circle under noise); 0, the default: only "
        "circle_rho (at 1.25 a small octagonal prism under 0.5 mm noise fits a circle too).",
    )
    circle_sigmas: float = Field(
        1.5,
        ge=0,
        description="Standard deviations: every contact whose sensor is square to an axis, "
        "whichever face the model made of it, lies on a curved surface when the tip centres "
        "miss one circle by an RMS of at most this × the record's declared σ (or circle_rho), "
        "their sensors take at least circle_faces readings about the axis, and at most "
        "circle_off_fraction of them point off its centre by more than a third of the sensor "
        "spacing.",
    )
    circle_off_fraction: float = Field(
        0.25,
        ge=0,
        le=1,
        description="Fraction: of the contacts around one axis (circle_sigmas), at most this "
        "share may have a sensor further from the circle's centre than a third of the finger's "
        "sensor spacing (a reading's quantisation): a prism's face keeps one sensor while its "
        "tip centres go round the axis by the face's angle.",
    )
    circle_arc_deg: float = Field(
        90.0,
        gt=0,
        le=360,
        description="Degrees: the tip centres on one circle (circle_rho) must go at least this "
        "far round it.",
    )
    sphere_fraction: float = Field(
        0.015,
        gt=0,
        lt=1,
        description="Fraction: every tip centre of the record on one sphere, missing it by an RMS "
        "of at most this × its radius, with sensors that point at its centre, lies on a ball "
        "(the benchmarks' polyhedra miss their best sphere by 2.5 % of its radius and more, "
        "balls of 8 cm under a poor scan's relief by 1 %).",
    )
    rel_tol: float = Field(
        0.06,
        gt=0,
        lt=1,
        description="Fraction: lengths this close relative to each other are equal (equal edges, "
        "congruent faces), and an edge no longer than this of the mean edge is a split corner.",
    )
    edge_sigmas: float = Field(
        4.0,
        ge=0,
        description="Standard deviations: the range of a dozen edge lengths allowed by noise "
        "(4·√2·σ is exceeded with a probability below 1 %).",
    )
    point_tol: float = Field(
        0.1,
        gt=0,
        lt=1,
        description="Fraction of the diameter: lateral faces whose planes meet within this of one "
        "point share a common point (noisy frusta miss their apex by up to 0.065, an "
        "octahedron's lateral edges miss any point by 0.2 or more).",
    )
    horizontal_deg: float = Field(
        10.0,
        gt=0,
        lt=90,
        description="Degrees: a face whose normal is within this of ±z is horizontal (a cap); "
        "lateral faces are within this of horizontal normals.",
    )


class GraspSettings(_Group):
    """The grasp planner."""

    table_angle_deg: float = Field(
        5.0,
        gt=0,
        lt=90,
        description="Degrees: a face whose normal is within this of −z is the object's base on "
        "the table.",
    )
    table_height_tol: float = Field(
        0.002,
        gt=0,
        description="Metres: a base face this close to the table (z = 0) stands on it.",
    )
    rank_angle_step_deg: float = Field(
        2.0,
        gt=0,
        description="Degrees: candidates whose planes' angles fall in the same step rank as "
        "equally parallel.",
    )


class ObjectSettings(_Group):
    """Which meshes the explorers accept."""

    max_size: float = Field(
        0.6,
        gt=0,
        description="Metres: the largest extent an object may have (the motors' range).",
    )
    min_size: float = Field(
        0.002,
        gt=0,
        description="Metres: an object thinner than this in any direction is degenerate.",
    )
    thin_factor: float = Field(
        1.5,
        gt=0,
        description="Tip radii: an object must be at least this wide in every direction.",
    )
    speck_fraction: float = Field(
        0.1,
        gt=0,
        lt=1,
        description="Fraction: a separate body whose bounding-box diagonal is under this fraction "
        "of the largest body's is a floating speck and is dropped.",
    )
    join_fraction: float = Field(
        0.02,
        ge=0,
        lt=0.5,
        description="Fraction of the object's diagonal: bodies of a mesh closer than this to "
        "the largest one are parts of one object (a convex decomposition, a handle modelled "
        "apart) and are explored together; farther ones must be specks.",
    )
    weld_fraction: float = Field(
        1e-5,
        gt=0,
        lt=0.01,
        description="Fraction of the object's diagonal: in a mesh that is not closed, vertices "
        "closer than this are welded when that closes it or joins its bodies (CAD seams).",
    )
    speck_volume_fraction: float = Field(
        0.01,
        gt=0,
        lt=1,
        description="Fraction: a separate body whose bounding box holds under this fraction of "
        "the largest body's bounding-box volume is a floating speck too, however long it is.",
    )
    workspace_half_width: float = Field(
        0.5,
        gt=0,
        description="Metres: every point of the object must lie within this distance of the z "
        "axis in x and y; an object that does not is first centred over the origin.",
    )
    units: Literal["m", "cm", "mm", "in"] = Field(
        "m",
        description="The length unit of mesh files (m, cm, mm or in): a mesh is scaled to "
        "metres as it is read (CAD exports are often in millimetres).",
    )
    rest: Literal["as-given", "stable"] = Field(
        "as-given",
        description="How an object is put on the table: as-given keeps the mesh's "
        "orientation (its lowest point on the table); stable turns it to the most probable "
        "pose it comes to rest in when dropped (trimesh's stable poses).",
    )


class Settings(BaseModel):
    """All tolerances, one group per stage (see the module docstring)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    world: WorldSettings = Field(default_factory=WorldSettings)
    finger: FingerSettings = Field(default_factory=FingerSettings)
    servo: ServoSettings = Field(default_factory=ServoSettings)
    explore: ExploreSettings = Field(default_factory=ExploreSettings)
    geometry: GeometrySettings = Field(default_factory=GeometrySettings)
    features: FeatureSettings = Field(default_factory=FeatureSettings)
    grasp: GraspSettings = Field(default_factory=GraspSettings)
    objects: ObjectSettings = Field(default_factory=ObjectSettings)

    def assigned(self, assignments: Sequence[str]) -> Settings:
        """A copy with ``GROUP.FIELD=VALUE`` assignments applied (the command line's
        ``--set``), validated; values are converted to the field's type.

        Raises
        ------
        UsageError
            An assignment not of that form, an unknown group or field, or a value out of range.
        """
        groups: dict[str, dict[str, str]] = {}
        for item in assignments:
            name, eq, value = item.partition("=")
            group, dot, field = name.strip().partition(".")
            if not (eq and dot and group and field):
                raise UsageError(
                    f"--set {item!r}: expected GROUP.FIELD=VALUE, e.g. explore.completion_touches=10"
                )
            groups.setdefault(group, {})[field] = value.strip()
        try:
            return self.replaced(**groups)
        except UsageError as exc:
            text = str(exc).removeprefix("settings: ")
            named = re.match(r"(\w+)\.(\w+):|no group '(\w+)'", text)
            culprit = ""
            if named:
                group, field, missing = named.groups()
                for item in assignments:
                    g, _, rest = item.partition("=")[0].strip().partition(".")
                    if (g, rest) == (group, field) or (missing is not None and g == missing):
                        culprit = f" {item}"
                        break
            raise UsageError(f"--set{culprit}: {text}") from None

    def changes(self) -> dict[str, dict[str, Any]]:
        """The fields that differ from :data:`DEFAULTS`, by group (``{}`` for the defaults)."""
        mine, base = self.model_dump(), Settings().model_dump()
        out: dict[str, dict[str, Any]] = {}
        for group, values in mine.items():
            diff = {k: v for k, v in values.items() if base[group][k] != v}
            if diff:
                out[group] = diff
        return out

    def replaced(self, **groups: Mapping[str, Any] | BaseModel) -> Settings:
        """A copy with the fields named in ``groups`` changed, validated.

        Each keyword is a group name; its value a mapping of field names to new values (or a
        whole group model).

        Raises
        ------
        UsageError
            An unknown group or field, or a value out of range.
        """
        data = self.model_dump()
        for name, change in groups.items():
            if name not in data:
                raise UsageError(f"settings: no group {name!r} (groups: {', '.join(sorted(data))})")
            update = change.model_dump() if isinstance(change, BaseModel) else dict(change)
            data[name] = {**data[name], **update}
        try:
            return Settings.model_validate(data)
        except ValidationError as exc:
            err = exc.errors()[0]
            where = ".".join(str(p) for p in err["loc"])
            raise UsageError(f"settings: {where}: {err['msg']} (got {err['input']!r})") from None


DEFAULTS = Settings()
"""The documented defaults."""


def load(path: str | Path, base: Settings | None = None) -> Settings:
    """The settings of a TOML file: one table per group, ``field = value`` in it, for example
    ``[explore]`` then ``completion_touches = 10``; fields not named keep ``base`` (default
    :data:`DEFAULTS`).

    Raises
    ------
    UsageError
        The file cannot be read, is not TOML, or names an unknown group or field or a value out
        of range; the message names the file and, where it can, the line.
    """
    where = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"{where}: cannot read the settings file: {exc}") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        found = re.search(r"\(at line (\d+), column (\d+)\)", str(exc))
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(exc))
        at = f"{where}:{found.group(1)}:{found.group(2)}" if found else where
        raise UsageError(f"{at}: not TOML: {message}") from None
    groups: dict[str, Mapping[str, Any]] = {}
    for name, table in data.items():
        if not isinstance(table, dict):
            line = _line_of(text, None, name)
            raise UsageError(
                f"{where}{line}: {name!r} must be a table of its fields ([{name}] and then "
                "field = value lines)"
            )
        groups[name] = table
    try:
        return (base or DEFAULTS).replaced(**groups)
    except UsageError as exc:
        located = re.match(r"settings: (?:(\w+)\.(\w+)|no group '(\w+)')", str(exc))
        line = ""
        if located:
            group, field, missing = located.groups()
            line = _line_of(text, group, field) if group else _line_of(text, None, missing)
        raise UsageError(f"{where}{line}: {str(exc).removeprefix('settings: ')}") from None


def _line_of(text: str, group: str | None, key: str) -> str:
    """``":N"`` for the line of ``[group]`` … ``key =`` in a TOML text (or of ``[key]`` when
    ``group`` is None), ``""`` when it is not found."""
    table: str | None = None
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        header = re.fullmatch(r"\[\s*([\w.-]+)\s*\]", stripped)
        if header:
            table = header.group(1)
            if group is None and table == key:
                return f":{n}"
            continue
        if re.match(rf"{re.escape(key)}\s*=", stripped) and (table == group or group is None):
            return f":{n}"
    return ""


_CURRENT: ContextVar[Settings] = ContextVar("tactile_kb_settings", default=DEFAULTS)


def current() -> Settings:
    """The settings in force in this thread or task (:data:`DEFAULTS` unless overridden)."""
    return _CURRENT.get()


@contextmanager
def use(settings: Settings) -> Iterator[Settings]:
    """Make ``settings`` the current settings inside the ``with`` block (this context only)."""
    if not isinstance(settings, Settings):
        raise UsageError(f"settings: expected a Settings object, got {type(settings).__name__}")
    token = _CURRENT.set(settings)
    try:
        yield settings
    finally:
        _CURRENT.reset(token)


def override(**groups: Mapping[str, Any] | BaseModel) -> AbstractContextManager[Settings]:
    """A context manager: the current settings with ``groups`` changed (see
    :meth:`Settings.replaced`), validated at once.

    >>> with override(geometry={"cut_deg": 12.0}, objects={"max_size": 1.0}) as s:
    ...     s.geometry.cut_deg, s.objects.max_size
    (12.0, 1.0)
    """
    return use(current().replaced(**groups))
