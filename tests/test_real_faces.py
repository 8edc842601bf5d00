"""Faces of real surfaces: bumps, relief and rounded edges are not shape (issue 10, item 3).

Ground truth is the geometry built here: a box with bumps of a millimetre is flat, a cylinder
of 5 cm radius is curved, and touches of a rounded edge between two faces are no face.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from scanlike import bumped, rounded_box

from tactile_kb.features.builtin import surface_curved
from tactile_kb.geometry.model import build_model
from tactile_kb.geometry.planes import explained_faces
from tactile_kb.perturb import touch_record
from tactile_kb.solids import box
from tactile_kb.touch.finger import builtin_finger

FINGER = builtin_finger("33")
RHO = FINGER.radius


def _box() -> trimesh.Trimesh:
    return box(0.08, 0.06, 0.04)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_box_with_millimetre_bumps_is_flat(seed: int) -> None:
    ideal = _box()
    scan = bumped(ideal, 0.001, bumps=12, seed=seed)
    record = touch_record(scan, ideal, FINGER, per_face=12, seed=seed)
    model = build_model(record)
    assert model.polyhedron is not None
    assert not surface_curved(model)


@pytest.mark.parametrize("seed", [0, 1])
def test_cylinder_of_five_centimetres_is_curved(seed: int) -> None:
    cylinder = trimesh.creation.cylinder(radius=0.05, height=0.06, sections=96)
    cylinder.apply_translation([0.0, 0.0, 0.03])
    record = touch_record(cylinder, cylinder, FINGER, total=120, seed=seed)
    assert surface_curved(build_model(record))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_touches_of_rounded_edges_are_no_face(seed: int) -> None:
    # a 10 × 8 × 6 cm box with edges rounded by 5 mm (8 % of its shortest edge), touched up
    # to its faces' edges: many touches land on the roundings and report tilted sensors
    ideal = box(0.10, 0.08, 0.06)
    scan = rounded_box(0.10, 0.08, 0.06, 0.005)
    scan.apply_translation(ideal.bounds[0] - scan.bounds[0])
    record = touch_record(scan, ideal, FINGER, per_face=14, margin=0.0, seed=seed)
    model = build_model(record)
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 6
    assert not surface_curved(model)


def test_explained_faces_drops_an_edge_touch_and_keeps_a_real_face() -> None:
    # the faces of a unit-ish box (5 cm cube) as planes, and the tip centres of touches on
    # its edge x = y = 0.025 rounded with r = 3 mm, whose direction bisects the two faces
    from tactile_kb.geometry.planes import Face

    half = 0.025
    sides = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)]
    # a scan's faces: their tip centres scatter by 0.3 mm about their planes
    faces = [
        Face(tuple(map(float, n)), half if n[2] == 0 else 2 * half, 9, 0.0003, 0.5, (k,), True)
        for k, n in enumerate(sides)
    ]
    faces.append(Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table"))
    r = 0.003
    axis = np.array([half - r, half - r, 0.0])
    m = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    edge = np.array([axis + (RHO + r) * m + [0, 0, z] for z in (0.01, 0.02, 0.03)])
    # each side's own touch (one centre ρ out of its middle), then the edge touches
    own = np.array([np.array(n, float) * (RHO + (half if n[2] == 0 else 2 * half)) for n in sides])
    own[:, 2] += np.where(own[:, 2] == 0, half, 0.0)
    centres = np.vstack([own, edge])
    edge_face = Face((m[0], m[1], 0.0), float(m @ axis) + r, 3, 0.0, 5.0, (5, 6, 7), False)
    all_faces = [*faces[:5], edge_face, faces[5]]
    supporting = [True] * len(all_faces)
    assert explained_faces(all_faces, supporting, centres, RHO) == [5]
    # the same touches 6 mm further in: a bevel the box does not have, a face
    bevel = centres.copy()
    bevel[5:] -= 0.006 * m
    bevel_face = Face((m[0], m[1], 0.0), float(m @ axis) + r - 0.006, 3, 0.0, 5.0, (5, 6, 7), False)
    assert explained_faces([*faces[:5], bevel_face, faces[5]], supporting, bevel, RHO) == []
    # an ideal solid's faces (no scatter beyond the noise): no detail to explain an edge
    # touch away; edge_faces is the one that judges it
    smooth = [dataclasses.replace(f, residual=0.0) for f in all_faces]
    assert explained_faces(smooth, supporting, centres, RHO) == []
