"""Faces of solids in stable poses that one cluster of sensor normals mixed up (issue 11).

The solids, poses and turns are those of ``benchmarks/bench_poses.py`` that went wrong; the
truth is the construction (trimesh's icosahedron, its own face planes), never the code under
test.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.features import builtin
from tactile_kb.features.builtin import parallelism_table
from tactile_kb.geometry.planes import Face
from tactile_kb.pipeline import classify, classify_record
from tactile_kb.record import ExplorationRecord


def _icosahedron(pose: int, turn: float, circumradius: float = 0.0811) -> trimesh.Trimesh:
    m = trimesh.creation.icosahedron()
    m.apply_scale(circumradius)
    return solids.resting(m, pose, turn)


@pytest.mark.parametrize(
    ("pose", "turn"),
    [(2, 206.7760973152555), (4, 357.1283622893202), (15, 295.84512098287723)],
)
def test_icosahedron_whose_layers_met_two_faces_per_sensor(pose: int, turn: float) -> None:
    # Each contour layer met one of two faces 41.8° apart that fire the same sensor: the
    # faces are told apart (each modelled face lies within a few degrees of one of the
    # icosahedron's; mixed, they were 10-21° off), and it is no curved object.
    mesh = _icosahedron(pose, turn)
    r = classify(mesh, rules="polyhedra", noise=0.0, seed=1)
    assert r.decision.label == "other_polyhedron"
    _faces_are_the_icosahedrons(mesh, r.model.contact_faces)


def _faces_are_the_icosahedrons(
    mesh: trimesh.Trimesh, faces: Sequence[Face], within_deg: float = 5.0
) -> None:
    truth = mesh.face_normals
    for f in faces:
        k = int(np.argmax(truth @ f.normal_array))
        assert math.degrees(math.acos(min(1.0, float(truth[k] @ f.normal_array)))) < within_deg


@pytest.mark.parametrize(
    ("pose", "turn"),
    [
        (4, 86.16432678660267),
        (10, 355.08708006498665),
        (11, 122.3729807443569),
    ],
)
def test_small_icosahedron_whose_two_faces_fit_within_the_split_tolerance(
    pose: int, turn: float
) -> None:
    # A 3.6 cm icosahedron: a contour line on one face and three on the next, 41.8° away,
    # closed sensors 15° apart (one cluster) and fit one plane within the split tolerance
    # (2.1 mm of 2.5): their readings part them as exact touches, with the fits' least scale
    # as the noise (each modelled face within a few degrees of one of the icosahedron's; mixed,
    # one face bent by 3.6 mm over the face and the object was curved).
    mesh = _icosahedron(pose, turn, circumradius=0.0357)
    r = classify(mesh, rules="polyhedra", noise=0.0, seed=1)
    assert r.decision.label == "other_polyhedron"
    _faces_are_the_icosahedrons(mesh, [f for f in r.model.contact_faces if f.refined])
    # and no face mixes two: all its tip centres but the touches of an edge (two at most) lie
    # on one face's plane offset by ρ
    rho = r.record.tip_radius
    offsets = np.einsum("ij,ij->i", mesh.triangles[:, 0], mesh.face_normals) + rho
    for f in r.model.contact_faces:
        centres = np.asarray([r.record.contacts[i].centre for i in f.contacts])
        on = np.abs(centres @ mesh.face_normals.T - offsets) < 1e-4
        assert int(on.sum(axis=0).max()) >= len(centres) - 2


RECORDS = Path(__file__).parent / "data" / "records"


def test_small_icosahedron_whose_contour_line_and_a_corner_fit_one_plane() -> None:
    # A contour line on one face and a corner of the next touched 21 mm above it (two tip
    # centres at one spot) fitted one plane exactly, 19.5° off the face, and the object was
    # curved: the spot is handed back from the line, and the line's sensors, which closed
    # the same sensor at every touch, do not take it back. The record is this pose's
    # exploration as main made it before the completion allowed for rounded edges (dc0edd3):
    # the model is tested on those touches; the pose's exploration now takes another way
    # (its completion probes a side's second height lower), counted in bench_poses.
    mesh = _icosahedron(15, 275.46346524, circumradius=0.0357)
    rec = ExplorationRecord.load(RECORDS / "icosahedron-pose15-dc0edd3.json")
    r = classify_record(rec, rules="polyhedra")
    assert r.decision.label == "other_polyhedron"
    _faces_are_the_icosahedrons(mesh, [f for f in r.model.contact_faces if f.refined])


def test_icosahedron_whose_slides_ended_at_the_rims_of_two_faces() -> None:
    # Exact touches: lines on two neighbouring faces, 41.8° apart, closed two sensors and
    # fitted one plane within the split tolerance. Their readings part them, but each part
    # ended in a slide onto the rim (two centres 0.4-0.7 mm inside its plane, touching the
    # edge), and that scatter, counted as the surface's, kept them one face, bent by 3.9 mm:
    # the object was curved.
    mesh = _icosahedron(10, 125.23090867, circumradius=0.033)
    r = classify(mesh, rules="polyhedra", noise=0.0, seed=1)
    assert r.decision.label == "other_polyhedron"


def test_noisy_icosahedron_whose_slide_crossed_an_edge_with_one_sensor_closed() -> None:
    # 0.5 mm noise: a probe's slide ran from one face over the edge onto the next, 41.8°
    # away, with the same sensor closed. The two parts fit two planes far better than one
    # (a V beyond the noise), but the part on the next face, 8 centres along 2 cm, came out
    # 27° from its sensor's direction, past one sensor spacing (26°): noise turns a plane
    # fitted over so short a span by several degrees. Taken as one face, the V bent it by
    # 3.9 mm and the object was curved.
    mesh = _icosahedron(3, 187.08258874, circumradius=0.0357)
    r = classify(mesh, rules="polyhedra", noise=0.0005, seed=1)
    assert r.decision.label == "other_polyhedron"
    # and no face bends: each of the faces touched eight times or more lies within 10° of
    # one of the icosahedron's (the noise turns a face touched over a short span that far)
    _faces_are_the_icosahedrons(
        mesh, [f for f in r.model.contact_faces if f.refined and f.n_contacts >= 8], 10.0
    )


def _pyramid(n: int, r: float, h: float, turn0: float, pose: int, turn: float) -> trimesh.Trimesh:
    m = solids.rotate_about_z(solids.pyramid(n, r, h), turn0)
    return solids.resting(m, pose, turn)


@pytest.mark.parametrize(
    ("n", "r", "h", "turn0", "pose", "turn"),
    [
        (4, 0.0145, 0.02, 312.8, 1, 178.7658097675871),
        (6, 0.0315, 0.0405, 357.8, 2, 152.14622271292123),
        (6, 0.0315, 0.0405, 357.8, 4, 31.25335399736189),
    ],
)
def test_lying_pyramid_whose_faces_were_touched_at_close_heights(
    n: int, r: float, h: float, turn0: float, pose: int, turn: float
) -> None:
    # Lying on a side, the faces under the pyramid and beside its apex are met by passes a
    # millimetre or two apart, and along a layer's corner by the tip resting on an edge:
    # exact touches still fix their planes, and the lateral edges meet at the apex.
    mesh = _pyramid(n, r, h, turn0, pose, turn)
    result = classify(mesh, rules="polyhedra", noise=0.0, seed=1)
    assert result.decision.label == "pyramid"


def test_a_face_fitted_exactly_by_four_centres_is_parallel_to_none(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A large pentagonal pyramid lying on a side, exact touches: one face's four tip
    # centres fit its plane to 1e-17 m while other faces show a micrometre of scatter.
    # Pooled with that, the face's uncertainty grew a billionfold (to 90°), it was
    # parallel to every face, and the table and it were taken for a prism's ends.
    mesh = _pyramid(5, 0.1209, 0.2284, 90.6, 3, 247.52352633484526)
    normals = mesh.face_normals
    angles = np.degrees(np.arccos(np.clip(normals @ normals.T, -1.0, 1.0)))
    assert angles.max() < 170.0  # the truth: no two faces of the pyramid are parallel
    r = classify(mesh, rules="polyhedra", noise=0.0, seed=1)
    assert r.decision.label == "pyramid"
    assert not parallelism_table(r.model).any()
    # The floor itself: one face fitted by five exact centres to 1e-17 m beside faces that
    # show a micrometre keeps a small uncertainty, and without the floor turns by ~90° (a
    # face of four borrows the other faces' scatter for its uncertainty already, and that
    # scatter is what is pooled for it)
    model = r.model
    k = next(i for i in model.face_of if model.faces[i].refined)
    faces = [
        dataclasses.replace(f, residual=1e-6) if f.refined and f.n_contacts >= 6 else f
        for f in model.faces
    ]
    faces[k] = dataclasses.replace(
        faces[k], n_contacts=5, residual=1e-17, normal_uncertainty_deg=0.01
    )
    at = model.face_of.index(k)
    assert builtin._uncertainty(dataclasses.replace(model, faces=tuple(faces)))[at] < 1.0
    monkeypatch.setattr(builtin, "PRECISION_RHO", 0.0)
    assert builtin._uncertainty(dataclasses.replace(model, faces=tuple(faces)))[at] > 80.0
