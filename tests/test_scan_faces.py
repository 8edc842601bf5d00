"""Faces of scan-like surfaces, round 4 (issue 10, item 3): edges rounded more widely than the
tip, a face fitted in two parts, turns that rest on one centre, and the normals of faces
touched a few times.

Ground truth is the geometry built here: the planes of a box, tip centres placed where a tip
touching a rounded edge, a bump or a hollow puts them, and leave-one-out fits enumerated.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from test_features import _bent_top, _top_face, _turned_direction, _with_contact

from tactile_kb import solids
from tactile_kb.features.builtin import (
    _bend,
    _jackknife_se,
    _spread_evidence,
    _uncertainty,
    get_feature,
)
from tactile_kb.geometry.model import build_model
from tactile_kb.geometry.planes import Face, explained_faces
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

FINGER = builtin_finger("33")
RHO = FINGER.radius
HALF = 0.075  # a 15 cm cube
SIDES = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)]


def _cube_faces(residual: float = 0.0002) -> tuple[list[Face], np.ndarray]:
    """The five touched faces of a 15 cm cube standing on the table (x, y in ±HALF, z in
    [0, 2·HALF]), each with one tip centre ρ out of its middle and the scatter of a scan."""
    faces = []
    own = []
    for k, n in enumerate(SIDES):
        v = np.asarray(n, dtype=float)
        offset = HALF if n[2] == 0 else 2 * HALF
        faces.append(Face(tuple(map(float, v)), offset, 9, residual, 0.5, (k,), True))
        middle = v * offset + (np.array([0.0, 0.0, HALF]) if n[2] == 0 else 0.0)
        own.append(middle + RHO * v)
    return faces, np.asarray(own)


TABLE = Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table")


def test_touches_of_an_edge_rounded_more_widely_than_the_tip_are_explained() -> None:
    # The vertical edge x = y = HALF rounded with r = 12 mm (8 % of the 15 cm faces, more
    # than the 5 mm tip). A tip on the rounding lies at ρ + r from its axis; at 20° from the
    # +x face it is 1 mm inside that face's ρ-offset and more than ρ inside the +y face's
    # plane, yet on the edge: its touches, with those at 45° and 70°, are no face.
    faces, own = _cube_faces()
    r = 0.012
    axis = np.array([HALF - r, HALF - r, 0.0])
    edge = []
    for phi in (20.0, 45.0, 70.0):
        u = np.array([math.cos(math.radians(phi)), math.sin(math.radians(phi)), 0.0])
        edge += [axis + (RHO + r) * u + [0.0, 0.0, z] for z in (0.04, 0.08)]
    centres = np.vstack([own, edge])
    m = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
    rounding = Face((m[0], m[1], 0.0), float(m @ axis) + r, 6, 0.0, 5.0, tuple(range(5, 11)), False)
    every = [*faces, rounding, TABLE]
    assert explained_faces(every, [True] * 7, centres, RHO) == [5]
    # the same touches 6 mm further in: a bevel 2 cm wide the cube does not have, a face
    bevel = centres.copy()
    bevel[5:] -= 0.006 * m
    cut = Face(
        (m[0], m[1], 0.0), float(m @ axis) + r - 0.006, 6, 0.0, 5.0, rounding.contacts, False
    )
    assert explained_faces([*faces, cut, TABLE], [True] * 7, bevel, RHO) == []


def _part_of_the_top(depth: float) -> tuple[list[Face], np.ndarray, list[bool]]:
    """The cube's faces, and a second "top" fitted from four centres ``depth`` below the top's
    ρ-offset, tilted by 5° so that the top's own centre lies beyond its plane (the face is
    not supporting: the object reaches past it)."""
    faces, own = _cube_faces()
    part = np.array([[x, y, 2 * HALF + RHO - depth] for x in (0.01, 0.05) for y in (-0.03, 0.03)])
    tilt = math.radians(5.0)
    n = np.array([-math.sin(tilt), 0.0, math.cos(tilt)])
    offset = float(n @ part.mean(axis=0)) - RHO
    face = Face(tuple(map(float, n)), offset, 4, 0.0002, 1.0, (5, 6, 7, 8), True)
    centres = np.vstack([own, part])
    supporting = [True] * 5 + [bool((centres @ n - offset - RHO).max() <= 0.0025), True]
    return [*faces, face, TABLE], centres, supporting


def test_a_part_of_a_face_fitted_apart_is_explained_and_a_hollow_is_not() -> None:
    # four centres 0.4 mm under the top's ρ-offset: the top's surface, fitted apart (a top
    # in two halves, one tilted a little out of the other's plane), explained
    every, centres, supporting = _part_of_the_top(0.0004)
    assert supporting[5] is False
    assert explained_faces(every, supporting, centres, RHO) == [5]
    # the same 2 cm down: a hollow's floor (a U-block's), a face of the object
    every, centres, supporting = _part_of_the_top(0.02)
    assert supporting[5] is False
    assert explained_faces(every, supporting, centres, RHO) == []
    # 3 mm down, more than half the tip's radius: no touch of the top either
    every, centres, supporting = _part_of_the_top(0.003)
    assert explained_faces(every, supporting, centres, RHO) == []


def _small_box_with_a_spot(x: float, height: float) -> tuple[list[Face], np.ndarray, list[bool]]:
    """The five touched faces of a 1.2 × 1.6 × 1.2 cm box (narrower than
    ``geometry.edge_min_width`` tip radii, as a curved object's facets are), each touched at
    four spots with a scan's scatter, and a face of one spot over the top at ``x`` (y = 0),
    ``height`` above the top's ρ-offset, its normal the sensor's that fired there, 18° from
    straight up."""
    half = np.array([0.006, 0.008, 0.006])
    faces, centres = [], []
    for n in SIDES:
        v = np.asarray(n, dtype=float)
        middle = v * half + [0.0, 0.0, half[2]]
        u = np.cross(v, [0.0, 1.0, 0.0] if n[1] == 0 else [1.0, 0.0, 0.0])
        w = np.cross(v, u)
        first = len(centres)
        centres += [middle + RHO * v + 0.003 * (a * u + b * w) for a in (-1, 1) for b in (-1, 1)]
        contacts = tuple(range(first, first + 4))
        faces.append(Face(tuple(map(float, v)), float(v @ middle), 9, 0.0002, 0.5, contacts, True))
    tilt = math.radians(18.0)
    n = np.array([math.sin(tilt), 0.0, math.cos(tilt)])
    spot = np.array([x, 0.0, 2 * half[2] + RHO + height])
    k = len(centres)
    centres += [spot, spot]
    face = Face(tuple(map(float, n)), float(n @ spot) - RHO, 2, 0.0, 15.0, (k, k + 1), False)
    c = np.asarray(centres)
    supporting = [True] * 5 + [bool((c @ n - face.offset - RHO).max() <= 0.0025), True]
    return [*faces, face, TABLE], c, supporting


def test_a_bump_on_a_small_top_is_explained_where_a_facet_by_an_edge_is_not() -> None:
    # a spot 0.8 mm above the middle of a 1.2 × 1.6 cm top (a bump under the tip, a sensor
    # 18° off firing): the top explains it, though every face is narrower than 4 ρ
    every, centres, supporting = _small_box_with_a_spot(0.0, 0.0008)
    assert explained_faces(every, supporting, centres, RHO) == [5]
    # 4 mm above: more than a bump's relief and the faces' detail, a face
    every, centres, supporting = _small_box_with_a_spot(0.0, 0.004)
    assert explained_faces(every, supporting, centres, RHO) == []
    # 2 mm from the top's edge, against the side as well: among narrow faces only, as on a
    # curved object, the facet stays
    every, centres, supporting = _small_box_with_a_spot(0.004, 0.0008)
    assert explained_faces(every, supporting, centres, RHO) == []


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_jackknife_error_is_that_of_the_fits_leaving_one_row_out(seed: int) -> None:
    rng = np.random.default_rng(seed)
    u = rng.uniform(-0.5, 0.5, 12)
    v = rng.uniform(-0.5, 0.5, 12)
    design = np.column_stack([np.ones(12), u, v, u * u])
    h = design @ [0.0, 0.001, -0.002, 0.003] + rng.normal(0.0, 0.0005, 12)
    beta = np.linalg.lstsq(design, h, rcond=None)[0]
    rest = h - design @ beta
    left_out = np.array(
        [
            np.linalg.lstsq(np.delete(design, i, 0), np.delete(h, i), rcond=None)[0][-1]
            for i in range(12)
        ]
    )
    truth = math.sqrt(11 / 12 * float(((left_out - left_out.mean()) ** 2).sum()))
    assert _jackknife_se(design, rest) == pytest.approx(truth, rel=1e-9)
    # a fit that needs every row has no leave-one-out fits
    assert _jackknife_se(design[:4], np.zeros(4)) == 0.0


def test_a_turn_resting_on_one_raised_centre_is_not_established() -> None:
    # A flat 10 cm top touched 14 times with 0.2 mm of roughness, its last touch raised by
    # 1.5 mm on a bump whose flank fired a sensor 15° off: the bent fit leans on that one
    # centre. The jackknife sees it; the face is not measured bent.
    rec = sample_record(solids.box(0.1, 0.1, 0.05), FINGER, per_face=14, quantise=False, noise=0.0)
    model, fi = _top_face(rec)
    face = model.faces[model.face_of[fi]]
    rng = np.random.default_rng(4)
    out = rec.model_copy(update={"noise": 0.0002})
    xs = [rec.contacts[i].centre[0] for i in face.contacts]
    last = face.contacts[int(np.argmax(xs))]
    for i in face.contacts:
        c = np.asarray(rec.contacts[i].centre) + np.array([0.0, 0.0, rng.normal(0.0, 0.0002)])
        d = np.asarray(rec.contacts[i].direction)
        if i == last:
            c = c + np.array([0.0, 0.0, 0.0015])
            d = _turned_direction(d, 15.0)
        out = _with_contact(out, i, d, c)
    raised, fi = _top_face(out)
    found = _bend(raised, fi, False)
    if found is not None:  # its sensors spread: the centres are asked
        turn, sigma, jack = found
        assert jack >= sigma
        assert abs(turn) - 2.0 * jack <= 10.0
    assert _spread_evidence(raised, 10.0)[0] is False
    assert not get_feature("surface_curved").fn(raised)
    # the same top really bent (R = 12 cm) stays curved
    assert get_feature("surface_curved").fn(build_model(_bent_top(rec, 0.12)))


def test_a_face_touched_a_few_times_is_no_more_certain_than_the_surface() -> None:
    # A box explored with 0.5 mm of scatter on every face but one, whose five centres happen
    # to fit their plane within 0.05 mm: its normal is as uncertain as the others' scatter
    # makes it, not the ten times more certain its own fit says.
    rec = sample_record(solids.box(0.1, 0.08, 0.06), FINGER, per_face=12, quantise=False, noise=0.0)
    model = build_model(rec)
    assert model.polyhedron is not None
    faces = list(model.faces)
    lucky = next(k for k, f in enumerate(faces) if f.source == "contacts")
    rough = []
    for k, f in enumerate(faces):
        if f.source != "contacts":
            continue
        if k == lucky:
            faces[k] = Face(
                f.normal,
                f.offset,
                5,
                0.00005,
                0.1,
                f.contacts[:5],
                True,
                f.source,
                f.offset_uncertainty,
            )
        else:
            faces[k] = Face(
                f.normal, f.offset, f.n_contacts, 0.0005, 1.0, f.contacts, True, f.source, 0.0
            )
            rough.append(k)
    scanned = dataclasses.replace(model, faces=tuple(faces))
    unc = dict(zip(scanned.face_of, _uncertainty(scanned), strict=True))
    own = math.radians(0.1)
    # pooled: ((2 · 0.05² · 5/2) + 4 · 0.5²) / 6 mm², against the fit's 0.05² · 5/2
    pooled = math.sqrt((2 * 0.05**2 * 2.5 + 4 * 0.5**2) / 6)
    expected = math.degrees(math.atan(math.tan(own) * pooled / (0.05 * math.sqrt(2.5))))
    assert unc[lucky] == pytest.approx(expected, rel=1e-6)
    assert all(unc[k] == pytest.approx(1.0) for k in rough)  # their own scatter is the surface's
    # an ideal surface (no scatter anywhere): every face keeps its own uncertainty
    ideal = [model.faces[i].normal_uncertainty_deg for i in model.face_of]
    assert list(_uncertainty(model)) == pytest.approx(ideal, abs=1e-9)
