"""The indexing head: oriented sensors, the colliding shaft, probes under overhangs, poses."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.errors import ExplorationError, LayoutFileError
from tactile_kb.pipeline import classify
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import VERTICAL, Orientation, Wrist, builtin_finger, load_layout
from tactile_kb.touch.sensors import FaultySensors
from tactile_kb.touch.stepper import StepperWorld
from tactile_kb.touch.world import OrientableWorld
from tactile_kb.types import FloatArray


def _cube() -> trimesh.Trimesh:
    cube = trimesh.creation.box((0.1, 0.1, 0.1))
    cube.apply_translation((0.0, 0.0, 0.05))
    return cube


def test_orientation_turns_the_pole_and_the_shaft() -> None:
    # tilt 90 then turn 90: the pole (tip) points to −y, the shaft to +y
    o = Orientation(90.0, 90.0)
    assert np.allclose(o.pole, (0.0, -1.0, 0.0), atol=1e-12)
    assert np.allclose(o.axis, (0.0, 1.0, 0.0), atol=1e-12)
    assert np.allclose(VERTICAL.pole, (0.0, 0.0, -1.0))
    f = builtin_finger("33")
    d = f.directions_at(o)
    assert np.allclose(d[0], o.pole)  # sensor 0 is the pole
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    # angles between sensors do not change
    assert np.allclose(d @ d.T, f.matrix @ f.matrix.T)


def test_wrist_poses_and_the_index_step() -> None:
    w = Wrist(step_deg=30.0, max_tilt_deg=90.0)
    poses = w.poses()
    assert poses[0] == VERTICAL
    assert len(poses) == 1 + 3 * 12  # tilts 30, 60, 90 × 12 turns
    with pytest.raises(ValueError, match="divide 90"):
        Wrist(step_deg=25.0)


def test_an_index_step_not_dividing_90_is_a_located_error() -> None:
    text = "name: x\ncone_deg: 30\nsensors:\n  - [1, 0, 0]\nwrist:\n  step_deg: 40\n"
    with pytest.raises(LayoutFileError) as exc:
        load_layout(text, file="f.yaml")
    assert str(exc.value).startswith("f.yaml:6:13: wrist.step_deg:")
    assert "divide 90" in str(exc.value)


def test_a_ball_stylus_may_have_upper_sensors_and_a_stem() -> None:
    text = (
        "name: stylus\ncone_deg: 30\nshaft_radius: 0.001\nrings:\n"
        "  - {elevation: 45, count: 6}\n  - {elevation: -45, count: 6}\n"
        "sensors:\n  - [0, 0, -1]\n"
    )
    f = load_layout(text)
    assert f.shaft_radius == 0.001
    assert f.wrist == Wrist()
    assert max(d[2] for d in f.directions) > 0.7
    # an underside is faced by an upper sensor without indexing
    assert f.index_for((0.0, 0.0, -1.0)) is not None


def test_index_for_keeps_the_paper_finger_vertical_for_what_it_feels() -> None:
    f = builtin_finger("33")
    for n in [(1.0, 0.0, 0.0), (0.0, -1.0, 0.3), (0.6, 0.0, 0.8)]:
        assert f.index_for(n) == VERTICAL
    under = f.index_for((0.5, 0.0, -0.866))  # a face overhanging 60°
    assert under is not None
    assert not under.vertical
    # a sensor of the indexed finger faces the surface, and the shaft leans away from it
    n = np.array([0.5, 0.0, -0.866])
    assert (f.directions_at(under) @ -n).max() >= f.cos_cone
    assert float(np.asarray(under.axis) @ n) > 0.4
    assert builtin_finger("33").model_copy(update={"wrist": None}).index_for(n) is None


def test_the_turned_finger_touches_with_the_sensor_facing_the_face() -> None:
    world = StepperWorld(_cube(), builtin_finger("33"))
    turned = world.oriented(Orientation(90.0, 180.0))  # tip pointing +x
    m = turned.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    assert m.event == "touch"
    assert m.closed == (0,)
    assert m.end[0] == pytest.approx(-0.055, abs=1e-6)
    assert isinstance(world, OrientableWorld)


def test_the_shaft_collides_with_the_object() -> None:
    finger = builtin_finger("33").model_copy(update={"shaft_radius": 0.002, "shaft_length": 0.05})
    world = StepperWorld(_cube(), finger)
    # the shaft along +x, 5 cm ahead of the tip: moving +x, it meets the face x = -0.05 first
    away = world.oriented(Orientation(90.0, 0.0))
    m = away.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3)
    assert m.event == "blocked"
    # the tip centre stops where the shaft's end meets the face, less the shaft's radius
    # (the last ball of the chain lies within one spacing, 1.5 mm, of the end)
    assert m.end[0] == pytest.approx(-0.05 - 0.05 - 0.002, abs=0.0016)
    assert away.shaft_collides((-0.08, 0.0, 0.05))
    assert not world.shaft_collides((-0.2, 0.0, 0.05))  # vertical: the shaft goes up
    with pytest.raises(ExplorationError, match=r"^the head at tilt 90°, turn 0° collides"):
        world.oriented(Orientation(90.0, 0.0), at=(-0.08, 0.0, 0.05))
    # the vertical finger passing under a slab: the tip would pass, the shaft hits its side
    slab = trimesh.creation.box((0.1, 0.1, 0.02))
    slab.apply_translation((0.06, 0.0, 0.05))  # x in [0.01, 0.11], z in [0.04, 0.06]
    m = StepperWorld(slab, finger).move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.25)
    assert m.event == "blocked"
    assert m.end[0] == pytest.approx(0.01 - 0.002, abs=1e-6)
    m = StepperWorld(slab, builtin_finger("33")).move((-0.1, 0.0, 0.02), (1.0, 0.0, 0.0), 0.25)
    assert m.event in ("none", "limit")  # no shaft modelled: the tip passes under


def test_faulty_sensors_pass_the_orientation_through() -> None:
    world = FaultySensors(StepperWorld(_cube(), builtin_finger("33")), seed=1)
    turned = world.oriented(Orientation(90.0, 180.0))
    assert turned.orientation == Orientation(90.0, 180.0)
    assert world.orientation == VERTICAL
    assert turned.move((-0.2, 0.0, 0.05), (1.0, 0.0, 0.0), 0.3).closed == (0,)


def _lying_hexagonal_prism() -> trimesh.Trimesh:
    return solids.stable_poses(solids.prism(6, 0.03, 0.1))[0][0]  # its most probable pose


def test_a_hexagonal_prism_on_its_side_is_a_prism_with_six_sides() -> None:
    m = _lying_hexagonal_prism()
    # ground truth: lying on a side face; two lateral faces overhang by 30°
    normals = np.unique(np.round(m.face_normals, 6), axis=0)
    assert sum(1 for n in normals if -0.6 < n[2] < -0.4) == 2
    r = classify(m, rules="polyhedra")
    assert r.decision.label == "prism"
    assert r.record.ending == "closed", r.record.unreachable
    faces = r.model.contact_faces
    assert len(faces) == 7  # 8 faces but the one on the table
    # the overhanging faces were touched, by the indexed head
    under = [f for f in faces if f.normal[2] < -0.4]
    assert len(under) == 2
    assert r.record.orientations
    tilted = [c for c in r.record.contacts if c.orientation != (0.0, 0.0)]
    assert tilted
    assert all(c.orientation[0] > 0 for c in tilted)
    for f in under:
        assert math.degrees(math.acos(min(1.0, -f.normal[2]))) == pytest.approx(60.0, abs=3.0)


def test_records_without_orientations_still_load() -> None:
    rec = ExplorationRecord.from_json(
        '{"version": 2, "finger": "33", "tip_radius": 0.005, "contacts": [{"step": 1, "centre": [0, 0, 0.01], "sensors": [0],'
        ' "direction": [0, 0, -1], "point": [0, 0, 0.005]}]}'
    )
    assert rec.orientations == []
    assert rec.contacts[0].orientation == (0.0, 0.0)


def test_the_4_sensor_finger_stays_vertical_unless_given_a_wrist() -> None:
    four = builtin_finger("4")
    assert four.wrist is None  # the paper's finger: it never feels a top (an assumed top)
    cube = solids.box(0.06, 0.06, 0.06)
    plain = classify(cube, finger=four, rules="parallelepipeds")
    assert plain.model.assumed_top is not None
    assert plain.decision.label == "rectangular_parallelepiped"
    # with an indexing head its equator sensors face down when tilted: the top is felt
    wrist = classify(
        cube, finger=four.model_copy(update={"wrist": Wrist()}), rules="parallelepipeds"
    )
    assert wrist.model.assumed_top is None
    assert wrist.decision.label == "cube"
    tops = [c for c in wrist.record.contacts if c.kind == "touch" and c.direction[2] < -0.5]
    assert tops
    assert all(c.orientation[0] > 0 for c in tops)


def test_an_oblique_parallelepiped_in_every_stable_pose() -> None:
    # ground truth from the construction: a parallelepiped with a 65° face angle and its top
    # sheared by 12°, so that some sides lean over the finger in some poses
    block = solids.parallelepiped(
        0.09, 0.07, 0.05, angle_deg=65.0, shear_deg=12.0, shear_azimuth_deg=30.0
    )
    poses = solids.stable_poses(block)
    assert len(poses) == 6  # each face is a stable face
    leaning = 0
    for k, (posed, _) in enumerate(poses):
        m = solids.rotate_about_z(posed, 47.0 * k)
        truth = np.unique(np.round(m.face_normals, 6), axis=0)
        assert len(truth) == 6
        leaning += int((truth[:, 2] < -0.2).any())
        r = classify(m, rules="polyhedra")
        assert r.decision.label == "nonrectangular_parallelepiped", k
        # closed, or what a probe could not confirm is named (never silently guessed)
        assert r.record.ending in ("closed", "unreachable"), (k, r.record.unreachable)
        assert (r.record.ending == "closed") == (not r.record.unreachable)
        assert all(u.startswith("the face facing") for u in r.record.unreachable)
        poly = r.model.polyhedron
        assert poly is not None
        assert len(poly.faces) == 6
        # every face of the construction is in the model, within 3°
        for n in truth:
            assert float(np.max(poly.normals @ n)) >= math.cos(math.radians(3.0)), (k, n)
    assert leaning >= 2  # poses with a side leaning over the finger were among them


def test_a_frustum_on_its_small_end_is_met_with_the_head_indexed() -> None:
    # ground truth: upside down, every side of the frustum leans over the vertical finger
    m = solids.rest_on_face(solids.frustum(4, 0.0895, 0.041, 0.081), (0.0, 0.0, 1.0))
    sides = np.unique(np.round(m.face_normals, 6), axis=0)
    assert sum(1 for n in sides if -0.9 < n[2] < -0.2) == 4
    r = classify(m, rules="polyhedra")
    first = r.record.contacts[0]
    assert first.kind == "touch"
    assert first.orientation[0] > 0  # the vertical finger met every side blind
    assert r.record.blind
    assert r.decision.label == "frustum"
    assert r.record.ending == "closed", r.record.unreachable


def _slants(count: int, lo: float = 0.6, hi: float = 0.8) -> Callable[[FloatArray], bool]:
    """A test of face normals: ``count`` of them have ``lo < |z| < hi``."""
    return lambda n: int(((abs(n[:, 2]) > lo) & (abs(n[:, 2]) < hi)).sum()) == count


def _posed(
    m: trimesh.Trimesh, turn_deg: float, keep: Callable[[FloatArray], bool]
) -> trimesh.Trimesh:
    """``m`` in its most probable stable pose (trimesh's ``compute_stable_poses``) whose face
    normals pass ``keep``, turned about z, centred on the table."""
    transforms, probs = trimesh.poses.compute_stable_poses(m)
    for k in np.argsort(-probs):
        posed = m.copy()
        posed.apply_transform(transforms[k])
        if keep(np.unique(np.round(posed.face_normals, 6), axis=0)):
            break
    else:
        raise AssertionError("no such stable pose")
    posed.apply_translation(
        (-posed.bounds.mean(axis=0)[0], -posed.bounds.mean(axis=0)[1], -posed.bounds[0][2])
    )
    return solids.rotate_about_z(posed, turn_deg)


@pytest.mark.parametrize("turn", [0.0, 70.0])
def test_a_lying_octagonal_prism_has_its_slanted_sides(turn: float) -> None:
    # ground truth: on a side face, so four sides slant at 45° (two up, two overhanging), and
    # the vertical finger's layers meet the upper ones at one height, near their lower edge:
    # those touches are a face of their own, not the edge of a box
    m = _posed(solids.prism(8, 0.0495, 0.0958), turn, _slants(4))
    truth = np.unique(np.round(m.face_normals, 6), axis=0)
    assert len(truth) == 10
    slanted = [n for n in truth if 0.6 < abs(n[2]) < 0.8]
    assert len(slanted) == 4
    r = classify(m, rules="polyhedra")
    assert r.decision.label == "prism"
    poly = r.model.polyhedron
    assert poly is not None
    # every face the vertical finger can reach is in the model, within 3° (the two that
    # overhang by 45° are met by no layer and leave no blind contact: not asked for here)
    for n in truth:
        if n[2] > -0.5:
            assert float(np.max(poly.normals @ n)) >= math.cos(math.radians(3.0)), n


def _stable(m: trimesh.Trimesh, k: int, turn_deg: float) -> trimesh.Trimesh:
    """``m`` in its ``k``-th stable pose of probability ≥ 2 % (trimesh's order), turned about
    z, centred on the table."""
    return solids.resting(m, k, turn_deg)


@pytest.mark.parametrize(("pose", "turn"), [(2, 66.0), (3, 347.0)])
def test_a_pyramid_on_a_lateral_face_is_probed_again_nearer_its_touches(
    pose: int, turn: float
) -> None:
    # ground truth: a pentagonal pyramid on a lateral face (its base stands tilted, one
    # lateral face overhangs); the probes the model places at a face's other height miss the
    # object while its normals are quantised, and are sent again nearer where it was touched
    m = _stable(solids.rotate_about_z(solids.pyramid(5, 0.0518, 0.0547), 290.9), pose, turn)
    truth = np.unique(np.round(m.face_normals, 6), axis=0)
    assert len(truth) == 6
    assert (truth[:, 2] < -0.99).sum() == 1  # on a face
    assert (np.abs(truth[:, 2]) < 0.99).sum() == 5  # the base is not on the table
    r = classify(m, rules="polyhedra")
    assert r.decision.label == "pyramid"


def test_a_face_touched_along_one_line_is_touched_off_it() -> None:
    # ground truth: a hexagonal pyramid on a lateral face; two probes touched one of its faces
    # at two heights but along one line (each probe slides a little), which fits no plane: the
    # quantised normals of such faces split the apex, unless one more touch off the line fits it
    m = _stable(solids.rotate_about_z(solids.pyramid(6, 0.0315, 0.0405), 357.8), 3, 316.0)
    truth = np.unique(np.round(m.face_normals, 6), axis=0)
    assert len(truth) == 7
    r = classify(m, rules="polyhedra")
    assert r.decision.label == "pyramid"
    # the apex is one vertex: no edge of the model is short (the construction's are ≥ 3 cm)
    poly = r.model.polyhedron
    assert poly is not None
    lengths = [float(np.linalg.norm(poly.vertices[i] - poly.vertices[j])) for i, j in poly.edges]
    assert min(lengths) > 0.01


@pytest.mark.parametrize(("pose", "turn"), [(0, 307.0), (1, 50.0)])
def test_a_corner_the_contour_went_round_inside_the_model_is_probed(pose: int, turn: float) -> None:
    # ground truth: a small triangular frustum lying on a side; its small end overhangs a
    # little and no layer touches it, so the three sides close into a tetrahedron, whose
    # corner the layer's path went round inside of: a probe there finds the small end
    m = _stable(solids.rotate_about_z(solids.frustum(3, 0.0194, 0.0096, 0.02), 268.0), pose, turn)
    truth = np.unique(np.round(m.face_normals, 6), axis=0)
    assert len(truth) == 5
    r = classify(m, rules="polyhedra")
    assert r.decision.label == "frustum"
    poly = r.model.polyhedron
    assert poly is not None
    assert len(poly.faces) == 5
    # every face of the construction is in the model (the small end, touched once, within
    # the sensors' quantisation)
    for n in truth:
        assert float(np.max(poly.normals @ n)) >= math.cos(math.radians(15.0)), n
    assert (r.record.ending == "closed") == (not r.record.unreachable)
    assert any(c.phase == "complete" for c in r.record.contacts)


@pytest.mark.parametrize(("pose", "turn"), [(2, 128.0), (4, 243.0)])
def test_an_l_block_standing_on_its_end_has_its_foot_found(pose: int, turn: float) -> None:
    # ground truth: an L-block standing on an end: its foot lies below the first contour
    # layer, so the layers touch the leg only; the hint box (the object's visual extent)
    # reaches past the leg's envelope, a probe from that side near the table meets the foot,
    # and its touches beyond the leg's (now concave) face are kept as a face
    m = _stable(solids.l_shape(0.0839, 0.0776, 0.0255, 0.0344), pose, turn)
    truth = np.unique(np.round(m.face_normals, 6), axis=0)
    assert len(truth) == 6  # two pairs of opposite faces are parallel, not one face each
    r = classify(m, rules="parallelepipeds")
    assert r.decision.label == "not_hexahedron"
    assert not r.model.convex
