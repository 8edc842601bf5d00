"""Objects nobody on the project made: the vendored real meshes get their expected labels, and
the scan-like perturbations of the ideal solids (:mod:`tactile_kb.perturb`) behave as scans."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.errors import UsageError
from tactile_kb.features.builtin import get_feature
from tactile_kb.geometry import planes
from tactile_kb.geometry.model import build_model
from tactile_kb.objects import load_object
from tactile_kb.perturb import (
    LEVELS,
    Perturbation,
    perturb,
    rounded,
    sharp_edge_length,
    touch_record,
)
from tactile_kb.pipeline import classify, classify_record
from tactile_kb.touch.finger import builtin_finger

REAL = Path(__file__).parent / "data" / "real"
with (REAL / "manifest.csv").open(newline="") as _f:
    ROWS = list(csv.DictReader(_f))
FINGER = builtin_finger("33")


def test_vendored_files_are_small_closed_solids_in_metres() -> None:
    sizes = [p.stat().st_size for p in REAL.glob("*.ply")]
    assert len(sizes) >= 6
    assert max(sizes) < 300_000
    assert sum(sizes) < 3_000_000
    for row in ROWS:
        mesh = load_object(REAL / row["path"])
        assert mesh.is_watertight
        assert mesh.body_count == 1
        assert 0.02 <= float(mesh.extents.max()) <= 0.3  # toy and grocery sizes, metres
    assert {r["path"] for r in ROWS} == {p.name for p in REAL.glob("*.ply")}


# Known failures, none now: the carton's gable (the layers skip it and a touch from above
# slides along the sealing ridge) is found by the completion's probes beside the ridge.
KNOWN: set[tuple[str, str]] = set()


@pytest.mark.parametrize(
    "row",
    [
        pytest.param(
            r,
            marks=pytest.mark.xfail(
                (r["path"], r["rules"]) in KNOWN, reason="gable not explored", strict=True
            ),
        )
        for r in ROWS
    ],
    ids=[f"{r['path']}-{r['rules']}" for r in ROWS],
)
def test_real_object_gets_its_label(row: dict[str, str]) -> None:
    result = classify(REAL / row["path"], rules=row["rules"], seed=0)
    assert result.decision.label == row["label"], result.decision.explanation


@pytest.mark.parametrize("seed", [0, 1])
def test_the_toy_half_cylinder_is_curved_with_noise(seed: int) -> None:
    # its folds (22° between facets) inside one face bend the tip centres beyond what 0.5 mm
    # of noise explains
    result = classify(REAL / "toy_half_cylinder.ply", rules="polyhedra", noise=0.0005, seed=seed)
    assert result.decision.label == "curved", result.decision.explanation


def test_perturb_is_deterministic_and_keeps_the_solid_on_the_table() -> None:
    box = solids.box(0.08, 0.06, 0.04)
    a, b = perturb(box, 2, seed=3), perturb(box, 2, seed=3)
    assert np.array_equal(a.vertices, b.vertices)
    assert not np.array_equal(a.vertices, perturb(box, 2, seed=4).vertices)
    for level in (1, 2):
        scan = perturb(box, level, seed=0)
        assert scan.is_watertight
        assert scan.body_count == 1
        assert float(scan.bounds[0, 2]) == 0.0
        # nothing moves by more than the level's bumps, relief and 5 σ of noise
        p = LEVELS[level]
        reach = p.bump_height * p.bumps + p.relief_height + 5 * p.noise
        assert np.all(np.abs(scan.extents - box.extents) <= 2 * reach + 1e-9)
    holed = perturb(box, 3, seed=0)
    assert not holed.is_watertight
    assert holed.body_count == 1 + LEVELS[3].specks


def test_rounded_edges_keep_faces_and_round_corners() -> None:
    box = trimesh.Trimesh(
        *trimesh.remesh.subdivide_to_size(
            solids.box(0.08, 0.06, 0.04).vertices, solids.box(0.08, 0.06, 0.04).faces, 0.002
        )
    )
    r = 0.004
    out = rounded(box, r)
    assert np.allclose(out.extents, [0.08, 0.06, 0.04])  # faces stay where they were
    # the corner (0.04, 0.03, 0.04) is cut: its nearest surface point is r(√3 − 1) inside
    corner = np.array([0.04, 0.03, 0.04])
    gap = float(np.linalg.norm(out.vertices - corner, axis=1).min())
    assert gap == pytest.approx(r * (np.sqrt(3) - 1), rel=0.05)
    assert sharp_edge_length(solids.box(0.08, 0.06, 0.04)) == pytest.approx(0.04)
    with pytest.raises(UsageError, match="too large"):
        rounded(box, 0.03)
    with pytest.raises(UsageError, match="convex"):
        rounded(solids.l_shape(0.1, 0.08, 0.03, 0.04), 0.002)
    with pytest.raises(UsageError, match="level"):
        perturb(box, 4)


@pytest.mark.parametrize(
    ("mesh", "label"),
    [
        (solids.rotate_about_z(solids.box(0.1, 0.06, 0.04), 35.0), "rectangular_parallelepiped"),
        (solids.prism(6, 0.04, 0.07), "prism"),
        (solids.tetrahedron(0.08), "tetrahedron"),
    ],
)
@pytest.mark.parametrize("level", [1])
def test_touched_scans_keep_their_class(mesh: trimesh.Trimesh, label: str, level: int) -> None:
    for seed in (0, 1):
        scan = perturb(mesh, level, seed=seed)
        rec = touch_record(scan, mesh, FINGER, per_face=6, seed=seed)
        assert classify_record(rec, rules="polyhedra").decision.label == label


def test_a_touch_on_a_rounded_edge_is_not_a_face() -> None:
    box = solids.rotate_about_z(solids.box(0.06, 0.06, 0.06), 20.0)
    scan = perturb(box, Perturbation(rounding=0.1), seed=0)
    rec = touch_record(scan, box, FINGER, per_face=6, seed=0)
    tilted = [c for c in rec.contacts if c.direction not in {d.direction for d in rec.contacts[:1]}]
    assert tilted  # some touches near the edges fired a neighbouring sensor
    model = build_model(rec)
    assert len(model.contact_faces) == 5
    assert model.options["edge_contacts"]
    assert build_model(rec, edge_rounding=None).contact_faces != model.contact_faces


@pytest.mark.parametrize(
    ("mesh", "rules", "label"),
    [
        # a 9.5 cm cube scanned at level 1 (0.2 mm noise, 3 % rounding, 0.3 mm bumps): one side
        # was touched at one spot where a bump closed two sensors, so its normal leaned 15° and
        # the probe along it met the top's rounded edge; the level probe finds the side
        (
            solids.rotate_about_z(solids.box(0.0949, 0.0949, 0.0949), 236.3),
            "parallelepipeds",
            "cube",
        ),
        # a 13 cm tetrahedron at level 1: one face slid along with the sensor below the square
        # one firing was a second face 8° from the first; its centres lie on the first's plane
        (solids.rotate_about_z(solids.tetrahedron(0.131), 104.7), "polyhedra", "tetrahedron"),
    ],
)
def test_explored_scans_keep_their_class(mesh: trimesh.Trimesh, rules: str, label: str) -> None:
    scan = perturb(mesh, 1, seed=0)
    result = classify(scan, rules=rules, explorer="stepper", seed=0)
    assert result.decision.label == label
    assert result.record.ending == "closed"


@pytest.mark.parametrize(
    ("mesh", "noise", "label"),
    [
        # a 15 cm octahedron at level 1 (0.2 mm vertex noise, 0.3 mm bumps): six faces whose
        # contacts near their edges fired sensors 10–40° apart, their centres measuring turns
        # of 5–10° ± 2–4° (relief under 5–12 contacts), counted as six gentle folds: curved
        (solids.rotate_about_z(solids.octahedron(0.1488), 174.2), 0.0, "octahedron"),
        # a 13 cm tetrahedron with 0.5 mm of noise: one face's 13 centres all within 2.5 mm
        # across the direction its sensors turned, a plane plus a·u² through them bending by
        # 187° ± 85°, "measured" beyond 10°; no tip centres bend more than 1/ρ
        (solids.rotate_about_z(solids.tetrahedron(0.131), 104.7), 0.0005, "tetrahedron"),
    ],
)
def test_scanned_flat_faces_are_not_read_curved(
    mesh: trimesh.Trimesh, noise: float, label: str
) -> None:
    result = classify(
        perturb(mesh, 1, seed=0), rules="polyhedra", explorer="stepper", noise=noise, seed=0
    )
    assert not get_feature("surface_curved").fn(result.model)
    # the octahedron's envelope has 7 faces, one short (other_polyhedron): another matter
    assert result.decision.label in (label, "other_polyhedron")


@pytest.mark.parametrize(
    ("mesh", "label"),
    [
        # an 11.5 cm pentagonal prism: a contour round a rounded vertical edge (6 mm of
        # centres) and one spot of the next side fit a plane 23° off that side, which the
        # object reaches beyond; without it the others' polyhedron holds those centres, the
        # rounding's 1.8 mm inside its ρ-offset, more than the 1.5 mm a face fitted apart
        # was allowed: a rounded edge's inset is
        (solids.rotate_about_z(solids.prism(5, 0.1151, 0.1282), 304.9), "prism"),
        # a 14 cm triangular frustum: a side touched at one spot whose sensors read 47° off
        # it cut into the object; the faces scatter no more than the 0.5 mm noise, and such a
        # spot was never looked at on a surface that shows no detail beyond the noise
        (solids.rotate_about_z(solids.frustum(3, 0.1391, 0.0652, 0.1229), 145.2), "frustum"),
    ],
)
def test_level_two_scans_keep_their_class_under_noise(mesh: trimesh.Trimesh, label: str) -> None:
    result = classify(
        perturb(mesh, 2, seed=0), rules="polyhedra", explorer="stepper", noise=0.0005, seed=0
    )
    assert result.decision.label == label


def test_a_poor_scans_flat_patches_are_no_ideal_surface(monkeypatch: pytest.MonkeyPatch) -> None:
    # an 11 cm triangular prism scanned at level 3, exact contacts: a contour over a patch
    # that is exactly flat between bumps is as straight as an ideal face's, and the tests
    # meant for an ideal surface's exact touches (strays off a straight line) took touches
    # of its faces away; its faces' scatter (tenths of a millimetre) says it is a scan, at
    # every model the exploration builds, while the ideal prism's exact touches are an ideal
    # surface's. (The scan's answer rests on the way its completion goes: prism when this
    # test was written; since the rounded-edge sink of planes.edge_faces it goes another way
    # and ends "other polyhedron", a corner touch 11 mm inside the sharp corner kept as a
    # face; the figures of docs/benchmarks.md count it.)
    judged: list[bool] = []
    ideal = planes._ideal

    def spy(*args: Any, **kwargs: Any) -> bool:
        judged.append(ideal(*args, **kwargs))
        return judged[-1]

    monkeypatch.setattr(planes, "_ideal", spy)
    mesh = solids.rotate_about_z(solids.prism(3, 0.1086, 0.0909), 109.0)
    classify(perturb(mesh, 3, seed=0), rules="polyhedra", explorer="stepper", seed=0)
    assert judged
    assert not any(judged)
    judged.clear()
    result = classify(mesh, rules="polyhedra", explorer="stepper", seed=0)
    assert any(judged)
    assert result.decision.label == "prism"
