"""``benchmarks/truth.py``: a solid's truth put into an exploration record (issue 10).

``bench_real.py --rejudge DIR --truth ITEMS`` measures what each imperfection of a scan costs
by taking it away. The truth is checked here on a box whose geometry is built by hand: which
tip centres lie over a rounded edge (the rounded box is the box shrunk by r, grown by a ball
of r), which sensor an ideal face fires for a finger hanging or tilted, and where a tip centre
lies when the bump under it is taken away.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import truth

from tactile_kb import solids
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import Orientation, builtin_finger

RHO = 0.005
R = 0.004  # the rounding's radius


@pytest.fixture(scope="module")
def box() -> tuple[object, np.ndarray, np.ndarray]:
    mesh = solids.box(0.08, 0.06, 0.04)
    lo, hi = mesh.bounds
    return mesh, np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)


def _contact(
    centre: np.ndarray, direction: np.ndarray, orientation: tuple[float, float] = (0, 0)
) -> Contact:
    d = direction / np.linalg.norm(direction)
    return Contact(
        step=0,
        centre=tuple(float(v) for v in centre),
        sensors=(0,),
        sensor=0,
        direction=tuple(float(v) for v in d),
        point=tuple(float(v) for v in centre + RHO * d),
        orientation=orientation,
    )


def _record(contacts: list[Contact]) -> ExplorationRecord:
    finger = builtin_finger("33")
    return ExplorationRecord(
        finger="33",
        tip_radius=RHO,
        sensor_directions=list(finger.directions),
        contacts=contacts,
    )


def test_centres_over_a_rounded_edge_are_told_from_those_on_its_faces(box) -> None:  # type: ignore[no-untyped-def]
    mesh, lo, hi = box
    z = 0.5 * (lo[2] + hi[2])
    x = hi[0] + RHO  # the +x face's tip centres
    axis = np.array([hi[0] - R, hi[1] - R, z])  # the +x/+y edge's rounding axis
    half = math.radians(45.0)
    centres = np.array(
        [
            [x, 0.5 * (lo[1] + hi[1]), z],  # the middle of the face
            [x, hi[1] - R - 3e-4, z],  # just before the rounding begins
            [x, hi[1] - R + 3e-4, z],  # just past it
            axis + (RHO + R) * np.array([math.cos(half), math.sin(half), 0.0]),  # half way round
            [hi[0] - R - 0.001, hi[1] + RHO, z],  # the +y face, beside the rounding
        ]
    )
    got = truth.on_roundings(centres, mesh, R)
    assert got.tolist() == [False, False, True, True, False]
    assert not truth.on_roundings(centres, mesh, 0.0).any()


def test_only_the_perturbed_convex_solids_were_rounded(box) -> None:  # type: ignore[no-untyped-def]
    mesh, _, _ = box
    # level 3 rounds with 10 % of the shortest sharp edge, 4 cm here
    assert truth.rounding_radius(mesh, "level 3") == pytest.approx(0.004)
    assert truth.rounding_radius(mesh, "level 1") == pytest.approx(0.0012)
    assert truth.rounding_radius(mesh, "ideal") == 0.0
    assert truth.rounding_radius(solids.l_shape(0.08, 0.06, 0.02, 0.03), "level 3") == 0.0


@pytest.mark.parametrize("orientation", [(0.0, 0.0), (90.0, 0.0), (60.0, 30.0)])
def test_readings_are_those_an_ideal_face_fires(box, orientation: tuple[float, float]) -> None:  # type: ignore[no-untyped-def]
    mesh, lo, hi = box
    centre = np.array([hi[0] + RHO, 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])])
    wrong = np.array([-1.0, 0.0, -0.6])  # a sensor turned down by a bump
    rec = _record([_contact(centre, wrong, orientation)])
    got = truth.corrected(rec, mesh, "level 2", ["readings"]).contacts[0]
    finger = builtin_finger("33")
    world = finger.matrix @ Orientation(*orientation).rotation.T
    # the sensor followed is the finger's nearest to the face's inward normal, as the head
    # holds it; the sensors on are those whose cones hold that normal
    angles = np.degrees(np.arccos(np.clip(world @ np.array([-1.0, 0.0, 0.0]), -1, 1)))
    assert got.sensor == int(np.argmin(angles))
    assert np.allclose(got.direction, world[got.sensor])
    assert set(got.sensors) == set(np.flatnonzero(angles <= finger.cone_deg + 1e-9).tolist())
    assert got.centre == rec.contacts[0].centre  # readings alone leave the centre
    assert np.allclose(got.point, np.asarray(got.centre) + RHO * np.asarray(got.direction))


def test_centres_are_moved_onto_the_ideal_surface_along_its_normal(box) -> None:  # type: ignore[no-untyped-def]
    mesh, lo, hi = box
    y, z = 0.5 * (lo[1] + hi[1]) + 0.01, 0.5 * (lo[2] + hi[2]) - 0.005
    bumped = np.array([hi[0] + RHO + 0.0013, y, z])  # on a bump 1.3 mm high
    rec = _record([_contact(bumped, np.array([-1.0, 0.1, 0.0]))])
    got = truth.corrected(rec, mesh, "level 2", ["centres"]).contacts[0]
    assert np.allclose(got.centre, [hi[0] + RHO, y, z], atol=1e-12)
    assert got.direction == rec.contacts[0].direction


def test_roundings_drop_their_touches_and_nothing_else_changes_them(box) -> None:  # type: ignore[no-untyped-def]
    mesh, lo, hi = box
    z = 0.5 * (lo[2] + hi[2])
    axis = np.array([hi[0] - R, hi[1] - R, z])
    on_face = _contact(np.array([hi[0] + RHO + 0.001, 0.0, z]), np.array([-1.0, 0.0, 0.0]))
    d = np.array([math.cos(0.6), math.sin(0.6), 0.0])
    on_edge = _contact(axis + (RHO + R) * d, -d)
    rec = _record([on_face, on_edge])
    assert truth.rounding_radius(mesh, "level 3") == pytest.approx(R)
    dropped = truth.corrected(rec, mesh, "level 3", ["roundings"])
    assert [c.centre for c in dropped.contacts] == [on_face.centre]
    # readings and centres change the face's touch, never the rounding's
    fixed = truth.corrected(rec, mesh, "level 3", ["readings", "centres"])
    assert fixed.contacts[1] == on_edge
    assert fixed.contacts[0] != on_face


def test_bad_items_are_refused_in_one_line() -> None:
    assert truth.parse_items("centres, roundings") == ("roundings", "centres")
    with pytest.raises(SystemExit, match=r"--truth roundings,nosuch: no item 'nosuch' \(choose"):
        truth.parse_items("roundings,nosuch")
    with pytest.raises(SystemExit, match="name at least one of roundings, readings, centres"):
        truth.parse_items(",")


def test_an_edge_too_shallow_to_be_rounded_has_no_rounding() -> None:
    # the sides of a 24-sided prism meet 15° apart, under perturb's SHARP_DEG (20°): a tip
    # centre off the edge between two of them lies over no rounding, but over its rim does
    mesh = solids.prism(24, 0.05, 0.04)
    lo, hi = mesh.bounds
    middle = 0.5 * (lo + hi)
    corner = mesh.vertices[np.argmax(mesh.vertices[:, 0] + 1e-3 * mesh.vertices[:, 2])]
    out = corner - np.array([middle[0], middle[1], corner[2]])
    out[2] = 0.0
    out /= np.linalg.norm(out)
    side = np.array([corner[0], corner[1], middle[2]]) + RHO * out
    rim = np.array([corner[0], corner[1], hi[2]]) + RHO * (
        out + np.array([0.0, 0.0, 1.0])
    ) / math.sqrt(2)
    assert truth.on_roundings(np.array([side, rim]), mesh, R).tolist() == [False, True]
