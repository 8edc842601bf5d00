"""Corner probes: a closed model whose corner no touch confirmed is tested, and a face the
model lacks is found (ground truth: solids built here, and their true faces)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tactile_kb import completion, solids
from tactile_kb.completion import corner_juts, corner_probes
from tactile_kb.geometry.model import build_model
from tactile_kb.record import ExplorationRecord
from tactile_kb.settings import override
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.stepper import StepperExplorer
from tactile_kb.touch.synthetic import sample_record

RHO = 0.005  # the 33-sensor finger's tip radius
A, B, C = 0.08, 0.06, 0.05  # the box: x from −A/2 to A/2, y from −B/2 to B/2, z from 0 to C
CUT = 0.025  # the chamfer cuts this much off each edge at the corner (+A/2, +B/2, C)
CORNER = np.array([A / 2, B / 2, C])
CHAMFER_N = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)


def _chamfered_box() -> trimesh.Trimesh:
    """The box with its corner (+x, +y, top) cut off by a plane through the three points
    ``CUT`` from the corner along its edges."""
    corners = np.array(
        [[x, y, z] for x in (-A / 2, A / 2) for y in (-B / 2, B / 2) for z in (0.0, C)]
    )
    keep = corners[np.linalg.norm(corners - CORNER, axis=1) > 1e-9]
    cut = CORNER - CUT * np.eye(3)
    return trimesh.convex.convex_hull(np.vstack([keep, cut]))


def _record(*, with_chamfer: bool) -> ExplorationRecord:
    """Contacts sampled on the chamfered box's faces, exact; without the chamfer's own."""
    rec = sample_record(
        _chamfered_box(), builtin_finger("33"), per_face=6, quantise=False, noise=0.0, seed=3
    )
    if with_chamfer:
        return rec
    d = CHAMFER_N @ CORNER - CUT / np.sqrt(3.0)  # the chamfer's plane: n·x = d
    keep = [c for c in rec.contacts if abs(float(CHAMFER_N @ np.asarray(c.point)) - d) > 1e-6]
    assert len(keep) < len(rec.contacts)  # the chamfer had contacts, now left out
    return rec.model_copy(update={"contacts": keep})


def test_the_corner_a_missing_face_cuts_off_is_probed_first() -> None:
    model = build_model(_record(with_chamfer=False))
    poly = model.polyhedron
    assert poly is not None
    # the model is the whole box: its corner where the object is not juts out furthest
    juts = corner_juts(model)
    at = int(np.argmin(np.linalg.norm(poly.vertices - CORNER, axis=1)))
    assert np.linalg.norm(poly.vertices[at] - CORNER) < 1e-3
    assert juts[at] == juts.max()
    assert juts[at] > CUT / np.sqrt(3.0)
    probes = corner_probes(model)
    assert probes, "the cut corner is tested"
    first = probes[0]
    # approached from outside along the corner's outward direction, aimed at the corner:
    # the chamfer faces the approach
    assert np.linalg.norm(np.asarray(first.target) - CORNER) < 2.0 * RHO
    assert float(np.asarray(first.normal) @ CHAMFER_N) > 0.9
    # it may go past the modelled corner as far as the corner juts out, to meet the face
    assert first.reach >= juts[at]
    assert first.reason.startswith("a corner juts out")


def test_with_every_face_touched_no_corner_is_probed_there() -> None:
    model = build_model(_record(with_chamfer=True))
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 7
    for p in corner_probes(model):
        assert np.linalg.norm(np.asarray(p.target) - CORNER) > CUT


def test_a_modelled_box_whose_faces_were_all_touched_has_no_corner_to_test() -> None:
    rec = sample_record(
        solids.box(A, B, C), builtin_finger("33"), per_face=6, quantise=False, noise=0.0, seed=3
    )
    assert corner_probes(build_model(rec)) == []


def _lying_prism() -> trimesh.Trimesh:
    """A long pentagonal prism lying on a side: its two upper sides meet in a ridge along its
    length, and one end of the ridge the contour layers never reach."""
    mesh = solids.rotate_about_z(solids.prism(5, 0.0486, 0.1792), 201.8)
    posed = [m for m, _ in solids.stable_poses(mesh, min_probability=0.02)]
    return solids.rotate_about_z(posed[3], 225.54)


def test_every_corner_of_a_lying_prism_lies_on_the_object() -> None:
    """A lying prism whose model once kept two corners nearly 9 cm above the object, where a
    side touched along one line (its quantised normal made it look concave) was left out.
    Corner probes found that side; since the contour records the ripples of a slide as slides
    (not touches), the side is fitted without them too. Either way every modelled corner lies
    on the object and the exploration closes."""
    mesh = _lying_prism()
    rec = completion.completing(StepperExplorer()).explore(mesh, seed=1)
    model = build_model(rec)
    assert model.polyhedron is not None
    outside = -trimesh.proximity.signed_distance(mesh, model.polyhedron.vertices)
    assert float(outside.max()) < RHO, outside
    assert rec.ending == "closed", rec.notes


def _sides(corners: int, monkeypatch: pytest.MonkeyPatch, rise: float = 0.0) -> list[int]:
    """The directions (degrees, mod 45) of the modelled sides of a scan-like octagonal prism
    (perturbed at level 2) explored with at most ``corners`` corner probes, a blind block
    tried again ``rise`` tip radii higher (``servo.blind_rise``; 0: it ends the contour)."""
    from tactile_kb.perturb import perturb

    monkeypatch.setattr(completion, "CORNER_PROBES", corners)
    mesh = perturb(solids.rotate_about_z(solids.prism(8, 0.0793, 0.0396), 245.8), 2, seed=0)
    with override(servo={"blind_rise": rise}):
        rec = completion.completing(StepperExplorer()).explore(mesh, seed=0)
    poly = build_model(rec).polyhedron
    assert poly is not None
    sides = [n for n in poly.normals if abs(float(n[2])) < 0.3]
    return sorted(round(float(np.degrees(np.arctan2(n[1], n[0]))) % 45) for n in sides)


def test_a_scan_like_prism_gets_the_sides_its_contour_missed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A scan-like octagonal prism: its contour stops early (at a blind block, with the rise
    over it turned off), some sides are never touched, and the other sides' planes close the
    envelope in corners where the object is not. Without corner probes the model has 4 of its
    8 sides; with them, the probes at those corners touch missing sides, and the model has
    more, every one of them a side of the octagon. (Which sides, and how many, follows the
    exploration's path: before the completion's probes kept clear of a rounding's reach, a
    variant of this exploration, its blocked slides ending the layers, found all 8; with the
    rise, the contour alone finds all 8.)"""
    probes = completion.CORNER_PROBES
    without = _sides(0, monkeypatch)
    assert len(without) == 4, without
    with_corners = _sides(probes, monkeypatch)
    assert len(with_corners) > len(without), with_corners
    # one direction mod 45°: the octagon's (within the perturbation's 5°)
    spread = max(with_corners) - min(with_corners)
    assert min(spread, 45 - spread) <= 5, with_corners
    # tried again higher, the blind block no longer ends the contour: every side is touched
    assert len(_sides(0, monkeypatch, rise=0.5)) == 8
