"""The settings object: documented defaults, validation, overrides that take effect and are
undone, and overrides that stay in their own thread."""

from __future__ import annotations

import math
import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh

from tactile_kb import settings
from tactile_kb.errors import ObjectError, UsageError
from tactile_kb.features.builtin import adjacent_faces_perpendicular, orthogonal_faces
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.objects import load_object
from tactile_kb.solids import box
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

# The values the modules documented before the settings object existed (written out here, not
# read from the library, so that a changed default fails this test).
DOCUMENTED: dict[str, dict[str, float | str]] = {
    "world": {
        "contact_tol": 1e-7,
        "block_tol": 1e-9,
        "same_contact_deg": 1.0,
        "comply_deg": 0.0,
        "comply_step": 0.8,
        "comply_depth": 0.25,
    },
    "finger": {"align_4_deg": 10.0, "max_usable_error_deg": 25.0},
    "servo": {
        "curved_run": 3,
        "ride_step": 0.8,
        "ride_deg": 20.0,
        "ripple_deg": 35.0,
        "persist_tries": 0,
        "blind_rise": 0.5,
    },
    "explore": {
        "noise_warn_fraction": 0.2,
        "noise_object_fraction": 0.03,
        "top_nz": 0.8,
        "completion_touches": 24,
        "completion_path": 4.0,
        "completion_path_sizes": 4.0,
        "completion_attempts": 2,
        "spot_rho": 2.0,
        "spot_deg": 2.0,
        "spot_probes": 6,
        "overhang_deg": 3.0,
    },
    "geometry": {
        "cut_deg": 15.0,
        "split_tol": 0.0025,
        "span": 0.002,
        "merge_deg": 4.0,
        "unrefined_merge_cones": 2.5,
        "unrefined_merge_sigmas": 3.0,
        "table_tol": 0.001,
        "robust_rho": 0.02,
        "max_refine_deg": 35.0,
        "edge_rounding": 0.10,
        "rounded_fit_sigmas": 2.5,
        "rounded_min_width": 2.0,
        "edge_min_width": 4.0,
        "edge_sigmas": 2.0,
        "relief_rho": 0.2,
        "merge_fraction": 0.03,
        "noisy_merge_fraction": 0.05,
        "collapse_sigmas": 4.0,
        "assumed_top_deg": 10.0,
        "line_tol": 0.004,
        "plane_deg": 8.0,
        "span_2d": 0.005,
        "same_contour": 0.05,
        "top_normal_deg": 20.0,
        "section_tol": 0.001,
    },
    "features": {
        "tolerance_deg": 5.0,
        "sigmas": 3.0,
        "residual_rho": 0.3,
        "sagitta_rho": 0.5,
        "spread_deg": 10.0,
        "bend_sigma_rho": 0.02,
        "bend_sigmas": 3.0,
        "sagitta_fraction": 0.03,
        "min_sagitta_contacts": 8,
        "smooth_deg": 35.0,
        "min_smooth_edges": 6,
        "circle_faces": 5,
        "circle_rho": 0.05,
        "circle_ratio": 0.0,
        "circle_sigmas": 1.5,
        "circle_off_fraction": 0.25,
        "circle_arc_deg": 90.0,
        "sphere_fraction": 0.015,
        "rel_tol": 0.06,
        "edge_sigmas": 4.0,
        "point_tol": 0.1,
        "horizontal_deg": 10.0,
    },
    "grasp": {"table_angle_deg": 5.0, "table_height_tol": 0.002, "rank_angle_step_deg": 2.0},
    "objects": {
        "max_size": 0.6,
        "min_size": 0.002,
        "thin_factor": 1.5,
        "speck_fraction": 0.1,
        "join_fraction": 0.02,
        "weld_fraction": 1e-5,
        "speck_volume_fraction": 0.01,
        "workspace_half_width": 0.5,
        "units": "m",
        "rest": "as-given",
    },
}


def test_defaults_are_the_documented_values() -> None:
    assert settings.current() == settings.DEFAULTS == settings.Settings()
    assert settings.DEFAULTS.model_dump() == DOCUMENTED


def test_every_field_is_described() -> None:
    for name in settings.Settings.model_fields:
        group = getattr(settings.DEFAULTS, name)
        for field_name, info in type(group).model_fields.items():
            assert info.description, f"{name}.{field_name} has no description"


def test_the_old_constants_are_the_defaults() -> None:
    from tactile_kb.features import builtin
    from tactile_kb.geometry import blocks, model, planes, polyhedron, sections
    from tactile_kb.grasp import planner
    from tactile_kb.touch import world

    assert builtin.TOLERANCE_DEG == 5.0
    assert builtin.EDGE_SIGMAS == 4.0
    assert planes.DEFAULT_SPLIT_TOL == 0.0025
    assert planes.EDGE_SIGMAS == 2.0
    assert polyhedron.DEFAULT_MERGE_FRACTION == 0.03
    assert model.COLLAPSE_SIGMAS == 4.0
    assert sections.LINE_TOL == 0.004
    assert blocks.SECTION_TOL == 0.001
    assert planner.TABLE_HEIGHT_TOL == 0.002
    assert world.CONTACT_TOL == 1e-7


@pytest.mark.parametrize(
    ("groups", "message"),
    [
        ({"features": {"tolerance_deg": -1.0}}, "features.tolerance_deg: Input should be greater"),
        ({"features": {"tolerance_deg": 0.0}}, "features.tolerance_deg"),
        ({"geometry": {"merge_fraction": 1.5}}, "geometry.merge_fraction: Input should be less"),
        ({"objects": {"max_size": "big"}}, "objects.max_size: Input should be a valid number"),
        ({"objects": {"units": "feet"}}, "objects.units: Input should be 'm', 'cm', 'mm' or 'in'"),
        ({"features": {"min_sagitta_contacts": 3}}, "features.min_sagitta_contacts"),
        ({"features": {"tolerance": 1.0}}, "features.tolerance: Extra inputs are not permitted"),
        ({"geometri": {"cut_deg": 1.0}}, "no group 'geometri'"),
    ],
)
def test_bad_overrides_are_refused_in_one_line(groups: dict[str, Any], message: str) -> None:
    with pytest.raises(UsageError, match=r"^settings: ") as info:
        settings.override(**groups)
    assert message in str(info.value)
    assert "\n" not in str(info.value)
    assert settings.current() is settings.DEFAULTS


def test_settings_are_immutable_and_use_wants_a_settings_object() -> None:
    from pydantic import ValidationError

    with pytest.raises(ValidationError):
        settings.DEFAULTS.features.tolerance_deg = 1.0  # type: ignore[misc]
    with pytest.raises(UsageError, match="expected a Settings object"):
        settings.use({"features": {}}).__enter__()  # type: ignore[arg-type]


def _sheared_box(deg: float) -> ObjectModel:
    """A box whose x–z faces lean by ``deg``: its adjacent faces meet at 90° ± ``deg``."""
    mesh = box(0.08, 0.06, 0.05)
    shear = np.eye(4)
    shear[0, 2] = math.tan(math.radians(deg))
    mesh.apply_transform(shear)
    return build_model(sample_record(mesh, builtin_finger("33"), seed=1))


def test_a_tighter_angle_tolerance_makes_a_sheared_box_non_rectangular() -> None:
    model = _sheared_box(3.0)  # 3° off square: within the default 5°, not within 1°
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 6
    assert adjacent_faces_perpendicular(model)
    assert orthogonal_faces(model)
    with settings.override(features={"tolerance_deg": 1.0, "sigmas": 0.0}) as s:
        assert s is settings.current()
        assert s.features.tolerance_deg == 1.0
        assert not adjacent_faces_perpendicular(model)
        assert not orthogonal_faces(model)
        # an explicit argument still wins over the settings
        assert adjacent_faces_perpendicular(model, tolerance_deg=5.0, sigmas=3.0)
    # undone after the block, and the value derived under the override is not reused
    assert settings.current() is settings.DEFAULTS
    assert adjacent_faces_perpendicular(model)
    assert orthogonal_faces(model)
    assert not adjacent_faces_perpendicular(model, tolerance_deg=1.0, sigmas=0.0)


def test_objects_max_size_refuses_a_box_only_inside_the_override() -> None:
    mesh = trimesh.creation.box((0.3, 0.05, 0.05))
    assert load_object(mesh.copy(), name="long").extents.max() == pytest.approx(0.3)
    with (
        settings.override(objects={"max_size": 0.2}),
        pytest.raises(ObjectError, match=r"long: .*at most 0\.2 m"),
    ):
        load_object(mesh.copy(), name="long")
    load_object(mesh.copy(), name="long")  # accepted again


def test_an_override_is_undone_when_the_block_raises() -> None:
    def fail() -> None:
        with settings.override(geometry={"cut_deg": 12.0}):
            assert settings.current().geometry.cut_deg == 12.0
            raise RuntimeError("boom")

    with pytest.raises(RuntimeError, match="boom"):
        fail()
    assert settings.current().geometry.cut_deg == 15.0


def test_overrides_nest_and_keep_the_outer_changes() -> None:
    with settings.override(geometry={"cut_deg": 12.0}):
        with settings.override(features={"sigmas": 1.0}) as inner:
            assert inner.geometry.cut_deg == 12.0
            assert inner.features.sigmas == 1.0
        assert settings.current().features.sigmas == 3.0
    assert settings.current() is settings.DEFAULTS


def test_overrides_in_two_threads_do_not_leak() -> None:
    barrier = threading.Barrier(3)
    seen: dict[str, list[float]] = {}

    def worker(name: str, value: float) -> None:
        out = seen.setdefault(name, [])
        with settings.override(features={"tolerance_deg": value}):
            barrier.wait()  # both threads are inside their blocks at once
            out.append(settings.current().features.tolerance_deg)
            barrier.wait()
        out.append(settings.current().features.tolerance_deg)

    threads = [
        threading.Thread(target=worker, args=("a", 1.0)),
        threading.Thread(target=worker, args=("b", 9.0)),
    ]
    with settings.override(features={"tolerance_deg": 7.0}):
        for t in threads:
            t.start()
        barrier.wait()
        main_inside = settings.current().features.tolerance_deg
        barrier.wait()
        for t in threads:
            t.join()
    assert seen == {"a": [1.0, 5.0], "b": [9.0, 5.0]}  # a new thread starts from the defaults
    assert main_inside == 7.0
    assert settings.current() is settings.DEFAULTS


def test_object_model_is_keyword_only() -> None:
    model = _sheared_box(0.0)
    with pytest.raises(TypeError):
        ObjectModel(model.record, model.faces, None, model.supporting)  # type: ignore[misc]
    rebuilt = ObjectModel(
        record=model.record, faces=model.faces, polyhedron=None, supporting=model.supporting
    )
    assert rebuilt.open_reason == ""
    assert not hasattr(rebuilt, "_derived")


def test_the_docs_table_is_the_one_the_model_generates() -> None:
    from pathlib import Path

    rows = ["| setting | default | meaning |", "|---|---|---|"]
    for group in settings.Settings.model_fields:
        values = getattr(settings.DEFAULTS, group)
        for name, info in type(values).model_fields.items():
            rows.append(f"| `{group}.{name}` | {getattr(values, name)!r} | {info.description} |")
    text = (Path(__file__).parent.parent / "docs" / "settings.md").read_text(encoding="utf-8")
    assert "\n".join(rows) in text


# --- the command line's settings: TOML files and GROUP.FIELD=VALUE assignments ---------------


def test_a_settings_file_changes_only_what_it_names(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text("# budgets\n[explore]\ncompletion_touches = 40\n\n[features]\nsigmas = 0\n")
    chosen = settings.load(path)
    assert chosen.changes() == {"explore": {"completion_touches": 40}, "features": {"sigmas": 0.0}}
    assert chosen.geometry == settings.DEFAULTS.geometry
    assert settings.DEFAULTS.changes() == {}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "[explore]\ntop_nz = 0.5\ncompletion_touches = -3\n",
            ":3: explore.completion_touches: Input should be greater than or equal to 0 (got -3)",
        ),
        ("[explore\n", ":1:9: not TOML: Expected ']' at the end of a table declaration"),
        ("\n[explor]\nx = 1\n", ":2: no group 'explor' (groups: explore, features, finger,"),
        ("[features]\ncut_deg = 3\n", ":2: features.cut_deg: Extra inputs are not permitted"),
        ("explore = 3\n", ":1: 'explore' must be a table of its fields"),
    ],
)
def test_a_bad_settings_file_is_one_located_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(UsageError) as caught:
        settings.load(path)
    assert str(caught.value).startswith(f"{path}{message}")
    assert "\n" not in str(caught.value)
    with pytest.raises(UsageError, match="cannot read the settings file"):
        settings.load(tmp_path / "missing.toml")


def test_assignments_are_typed_and_located() -> None:
    chosen = settings.DEFAULTS.assigned(
        ["explore.completion_touches=7", " features.tolerance_deg = 2.5"]
    )
    assert chosen.explore.completion_touches == 7
    assert chosen.features.tolerance_deg == 2.5
    for bad, message in [
        ("explore.completion_touches", "expected GROUP.FIELD=VALUE"),
        ("completion_touches=3", "expected GROUP.FIELD=VALUE"),
        ("explore.completion_touches=abc", "--set explore.completion_touches=abc: explore."),
        ("nope.x=1", "--set nope.x=1: no group 'nope'"),
        ("explore.nope=1", "--set explore.nope=1: explore.nope: Extra inputs"),
    ]:
        with pytest.raises(UsageError) as caught:
            settings.DEFAULTS.assigned(["features.sigmas=1", bad])
        assert message in str(caught.value)
