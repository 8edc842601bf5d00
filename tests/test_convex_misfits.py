"""Faces of a convex object whose planes make it look concave (issue 10, item 3).

A face touched at a few places has a plane a few degrees off, or is a rounded edge's: the
touches beyond its edges then lie beyond its plane, and the object was not convex. When its
touches lie on the outside of the object (``model._on_the_hull``: within the tolerance of the
tip centres' convex hull, on its facets facing the face's way), it is dropped. A concave face
stays: its touches lie inside the hull, or a face parallel to it reaches further out (a step).

Ground truth is the geometry built here: the tip centres a tip of radius ρ puts on the six
faces of a box (exact, so every true plane supports them), a face given a normal turned by a
known angle, a hollow, L- and T-shaped blocks whose inner faces are concave, and a saved
exploration of a scan-like heptagonal prism, a convex solid.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

from tactile_kb import solids
from tactile_kb.features.builtin import measure
from tactile_kb.geometry.model import _on_the_hull, _support, build_model
from tactile_kb.geometry.planes import Face
from tactile_kb.pipeline import classify, classify_record
from tactile_kb.record import ExplorationRecord

RHO = 0.005
TOL = 0.0025
HALF = np.array([0.08, 0.06, 0.02])  # a 16 × 12 × 4 cm box about the origin
NORMALS = np.array(
    [[1.0, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float
)


def _box_centres(per_face: int = 9, seed: int = 0) -> tuple[np.ndarray, list[list[int]]]:
    """Tip centres ρ outside the box's faces, ``per_face`` on each (within 90 % of its
    half-sizes), and each face's indices."""
    rng = np.random.default_rng(seed)
    pts: list[np.ndarray] = []
    groups: list[list[int]] = []
    for n in NORMALS:
        group = []
        for _ in range(per_face):
            p = n * (np.abs(n) @ HALF + RHO)
            for a in (a for a in range(3) if n[a] == 0):
                p[a] = rng.uniform(-0.9, 0.9) * HALF[a]
            group.append(len(pts))
            pts.append(p)
        groups.append(group)
    return np.asarray(pts), groups


def _turned(n: np.ndarray, deg: float) -> np.ndarray:
    """``n`` (horizontal) turned by ``deg`` about the vertical: along the face's length, so
    that its own touches at one end lie beyond the turned plane."""
    t = math.radians(deg)
    return np.array(
        [n[0] * math.cos(t) - n[1] * math.sin(t), n[0] * math.sin(t) + n[1] * math.cos(t), 0.0]
    )


def _faces(
    centres: np.ndarray,
    groups: list[list[int]],
    off: int | None = None,
    normal: np.ndarray | None = None,
    sensed: bool = True,
) -> tuple[Face, ...]:
    """The box's faces, face ``off`` with ``normal`` through its tip centres' middle: known
    from its sensors (a 13° cone) when ``sensed``, else fitted (1° uncertainty)."""
    out = []
    for j, (n, group) in enumerate(zip(NORMALS, groups, strict=True)):
        refined, unc = True, 0.2
        if j == off and normal is not None:
            n = normal
            refined, unc = (False, 13.0) if sensed else (True, 1.0)
        offset = float(centres[group].mean(axis=0) @ n) - RHO
        out.append(
            Face(tuple(float(x) for x in n), offset, len(group), 0.0, unc, tuple(group), refined)
        )
    return tuple(out)


@pytest.mark.parametrize(("deg", "sensed"), [(8.0, True), (25.0, True), (2.5, False)])
def test_a_face_turned_off_its_plane_lies_on_the_hull(deg: float, sensed: bool) -> None:
    centres, groups = _box_centres()
    faces = _faces(centres, groups, 2, _turned(NORMALS[2], deg), sensed)
    supporting = _support(centres, RHO, faces, TOL)[3]
    assert supporting == [True, True, False, True, True, True]  # its own touches beyond it
    # its touches lie on the box's +y side, the hull's facets there
    assert _on_the_hull(faces, supporting, centres, RHO, TOL) == [2]


def test_touches_inside_the_hull_are_no_misfit() -> None:
    # a patch of touches 6 mm inside the box's +y face (a hollow): deeper than the tolerance
    centres, groups = _box_centres()
    inner = centres[groups[2]] - np.array([0.0, 0.006, 0.0])
    centres = np.vstack([centres, inner])
    groups.append(list(range(len(centres) - len(inner), len(centres))))
    faces = (
        *_faces(centres, groups[:6]),
        Face((0.0, 1.0, 0.0), float(HALF[1]) - 0.006, len(inner), 0.0, 0.2, tuple(groups[6]), True),
    )
    supporting = _support(centres, RHO, faces, TOL)[3]
    assert supporting == [True] * 6 + [False]
    assert _on_the_hull(faces, supporting, centres, RHO, TOL) == []


@pytest.mark.parametrize("finger", ["33", "4"])
def test_the_inner_faces_of_an_l_block_stay_concave(finger: str) -> None:
    # the 4-sensor finger feels the inner faces at one height, where the hull's bottom
    # facet lies too: only the facets facing the faces' way count
    result = classify(
        solids.l_shape(0.1, 0.08, 0.03, 0.04),
        rules="polyhedra",
        finger=finger,
        noise=0.0005,
        seed=2,
    )
    model = result.model
    concave = [f.normal_array for f, s in zip(model.faces, model.supporting, strict=True) if not s]
    assert len(concave) == 2
    assert all(abs(n[2]) < 0.1 for n in concave)  # the two upright faces of the notch
    assert abs(float(np.dot(*concave))) < 0.1
    assert result.decision.label == "composed_of_boxes"


@pytest.mark.parametrize("turn", [58.0, 193.0])
def test_a_t_block_whose_notch_lies_on_the_hull_stays_concave(turn: float) -> None:
    # standing on its stem (its least probable stable pose), a T-block is felt by nine or
    # ten touches; its stem's sides, touched where they lie on the hull of all the touches,
    # are concave all the same: the crossbar's ends, parallel to them, reach 4 cm further out
    block = solids.t_shape(0.1163, 0.1073, 0.0344, 0.041)
    poses = solids.stable_poses(block, min_probability=0.02)
    standing = solids.rotate_about_z(poses[5][0], turn)
    result = classify(standing, rules="parallelepipeds", seed=1)
    model = result.model
    sides = [f for f, s in zip(model.faces, model.supporting, strict=True) if not s]
    assert len(sides) == 2
    for face in sides:  # half the stem's width out; the crossbar's end, half its length
        assert face.offset == pytest.approx(0.0344 / 2, abs=0.002)
        assert any(
            s and float(g.normal_array @ face.normal_array) > 0.99 and g.offset > face.offset + 0.03
            for g, s in zip(model.faces, model.supporting, strict=True)
        )
    assert result.decision.label == "not_hexahedron"


def test_a_scanned_prism_is_convex() -> None:
    # a level-3 scan (bumps, letters, edges rounded by 10 % of the shortest) of a heptagonal
    # prism, 11.9 cm across and 6.9 cm high, explored by the stepper in 26 touches (draw 2 of
    # bench_real.py): two of its faces, of three and four touches, had touches of the faces
    # beside them beyond their planes, and the prism was answered a polyhedron of another
    # kind; their touches lie on the hull, so they go
    path = Path(__file__).parent / "data" / "records" / "prism7-level3-draw2.json.gz"
    record = ExplorationRecord.model_validate_json(gzip.decompress(path.read_bytes()))
    plain = build_model(record, rounded=False)  # as the exploration's models: nothing dropped
    assert not plain.convex
    result = classify_record(record, rules="polyhedra")
    assert result.model.convex
    assert set(result.model.options["edge_contacts"]) >= {
        i for f, s in zip(plain.faces, plain.supporting, strict=True) if not s for i in f.contacts
    }
    assert result.decision.label == "prism"
    assert 5 <= measure(result.model, "sides") <= 7
