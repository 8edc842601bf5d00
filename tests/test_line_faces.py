"""A face touched along one line knows its direction round that line's perpendicular from the
line, and only its turn about the line from the sensors (``features.builtin._line_axes``).

A phone lying flat has sides 12 mm tall: one contour line fits under its top, and a rough
side's bumps turn some of the sensors that read it by 30° (on ``perturb``'s phone at level 2
the model gave its sides 29.7° and 30.2°). The sensors then bound the side's normal only to
30°, and before, that bound counted the same about every axis: three standard errors of it,
90°, made each side parallel to the top and the slab no parallelepiped. The truth here is a
slab built by hand: a top touched on a grid, each side along one line at 7 mm, and the sides'
sensors spread by 30° (the faces' ``normal_uncertainty_deg`` set so).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from touching import RHO, contact, touched_record

from tactile_kb.features.builtin import (
    adjacent_faces_perpendicular,
    face_angles,
    parallel_face_pairs,
    parallelism_table,
    perpendicularity_table,
)
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.record import ExplorationRecord

LENGTH, WIDTH, HEIGHT = 0.15, 0.072, 0.012
LINE_Z = 0.007  # the contour's tip centres: between ρ over the table and the top
SPREAD = 30.0  # degrees between the sensors that read a side (a bump's slope)
SIDES = {  # outward normal: (half extent along the normal, half length along the side)
    (1.0, 0.0): (LENGTH / 2, WIDTH / 2),
    (-1.0, 0.0): (LENGTH / 2, WIDTH / 2),
    (0.0, 1.0): (WIDTH / 2, LENGTH / 2),
    (0.0, -1.0): (WIDTH / 2, LENGTH / 2),
}


def _record(points: int = 8, span: float = 0.8, turn_deg: float = 0.0) -> ExplorationRecord:
    """The slab's touches: ``points`` along each side at ``LINE_Z`` over ``span`` of its
    length, the +x side's line turned ``turn_deg`` round the vertical about its middle."""
    contacts = []
    for x in np.linspace(-0.05, 0.05, 5):
        for y in np.linspace(-0.02, 0.02, 3):
            centre = np.array([x, y, HEIGHT + RHO])
            contacts.append(contact(len(contacts), centre, np.array([0.0, 0.0, 1.0])))
    turn = np.radians(turn_deg)
    for (nx, ny), (out, half) in SIDES.items():
        n = np.array([nx, ny, 0.0])
        along = np.array([-ny, nx, 0.0])
        if (nx, ny) == (1.0, 0.0):
            n, along = (
                np.array([np.cos(turn), np.sin(turn), 0.0]),
                np.array([-np.sin(turn), np.cos(turn), 0.0]),
            )
        middle = np.array([nx, ny, 0.0]) * (out + RHO) + np.array([0.0, 0.0, LINE_Z])
        for t in np.linspace(-span * half, span * half, points):
            contacts.append(contact(len(contacts), middle + along * t, n))
    return touched_record("slab", contacts, noise=0.0005)


def _spread(model: ObjectModel) -> ObjectModel:
    """``model`` with its sides' normals as uncertain as sensors ``SPREAD``° apart make them
    (what the model gives a face whose touches fired such sensors)."""
    faces = tuple(
        dataclasses.replace(f, normal_uncertainty_deg=SPREAD) if abs(f.normal[2]) < 0.5 else f
        for f in model.faces
    )
    return dataclasses.replace(model, faces=faces)


def _sides(model: ObjectModel) -> dict[tuple[float, float], int]:
    assert model.polyhedron is not None
    normals = model.polyhedron.normals
    return {key: int(np.argmax(normals @ np.array([key[0], key[1], 0.0]))) for key in SIDES}


def test_the_sides_are_touched_along_one_line() -> None:
    model = build_model(_record())
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 6
    for k in _sides(model).values():
        assert not model.faces[model.face_of[k]].refined  # one line: no plane of the centres


def test_sides_touched_along_one_line_are_parallel_to_their_opposites_only() -> None:
    model = _spread(build_model(_record()))
    side = _sides(model)
    top = int(np.argmax(model.polyhedron.normals[:, 2]))  # type: ignore[union-attr]
    par = parallelism_table(model)
    perp = perpendicularity_table(model)
    for (nx, ny), k in side.items():
        assert par[k, side[(-nx, -ny)]]
        assert not par[k, top]  # 90° apart about the line: the sensors know that much
        beside = [j for key, j in side.items() if key not in ((nx, ny), (-nx, -ny))]
        assert not par[k, beside].any()  # their directions are the lines': to a degree
        assert perp[k, beside].all()
        assert perp[k, top]
    assert parallel_face_pairs(model, count=3)
    assert adjacent_faces_perpendicular(model)


def test_a_side_turned_round_the_vertical_is_told_from_its_opposite() -> None:
    # the +x side's line turned 12° round the vertical: its direction is measured, and it is
    # parallel to nothing, though the sensors (30° apart) would read it the same
    model = _spread(build_model(_record(turn_deg=12.0)))
    side = _sides(model)
    k, opposite = side[(1.0, 0.0)], side[(-1.0, 0.0)]
    assert 180.0 - face_angles(model)[k, opposite] == pytest.approx(12.0, abs=0.5)
    assert not parallelism_table(model)[k, opposite]
    assert not parallel_face_pairs(model, count=3)


def test_a_short_line_is_as_uncertain_about_every_axis() -> None:
    # lines shorter than LINE_RHO tip radii measure no direction: the sensors' spread, three
    # errors of it, holds about every axis, and a side is parallel to the top too
    model = _spread(build_model(_record(points=3, span=0.05)))
    side = _sides(model)
    top = int(np.argmax(model.polyhedron.normals[:, 2]))  # type: ignore[union-attr]
    assert parallelism_table(model)[side[(0.0, 1.0)], top]
    assert not parallel_face_pairs(model, count=3)
