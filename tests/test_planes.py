"""Merging contact planes into one plane per face, refined beyond the sensor resolution."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tactile_kb import solids
from tactile_kb.errors import UsageError
from tactile_kb.geometry.planes import cut_angle, fit_face, merge_planes
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_layers, sample_record

F33 = builtin_finger("33")


def test_cut_angle_follows_the_finger() -> None:
    assert math.isclose(cut_angle(F33.directions), 0.6 * 25.905, rel_tol=1e-3)
    assert cut_angle(builtin_finger("4").directions) == 20.0
    assert cut_angle([]) == 15.0


@pytest.mark.parametrize("turn", [0.0, 13.0, 47.0])
def test_quantised_noisy_box_gives_six_refined_faces(turn: float) -> None:
    mesh = solids.rotate_about_z(solids.box(0.12, 0.08, 0.06), turn)
    rec = sample_record(mesh, F33, per_face=16, quantise=True, noise=0.0005, seed=5)
    faces = merge_planes(rec)
    assert len(faces) == 6
    assert sorted(f.n_contacts for f in faces) == [0, 16, 16, 16, 16, 16]
    truth = mesh.face_normals
    for f in faces:
        err = math.degrees(math.acos(min(1.0, float((truth @ f.normal_array).max()))))
        assert err < 2.0
        if f.source == "contacts":
            assert f.refined
            assert 0 < f.residual < 0.001
            assert 0 < f.normal_uncertainty_deg < 2.0
    # the sensors alone are off by up to 15°; the planes' offsets are right within a millimetre
    top = max(faces, key=lambda f: f.normal[2])
    assert abs(top.offset - 0.06) < 0.001
    table = [f for f in faces if f.source == "table"]
    assert table[0].normal == (0.0, 0.0, -1.0)
    assert table[0].offset == 0.0


def test_parallel_faces_at_different_offsets_stay_apart() -> None:
    mesh = solids.l_shape(0.12, 0.1, 0.04, 0.05)
    rec = sample_record(mesh, F33, per_face=12, quantise=True, noise=0.0005, seed=2)
    faces = [f for f in merge_planes(rec) if f.source == "contacts"]
    # 6 sides (two pairs of them parallel and coplanar-free) + top
    assert len(faces) == 7
    xs = sorted(round(f.offset, 3) for f in faces if f.normal[0] > 0.99)
    assert xs == [-0.02, 0.06]


def test_collinear_contacts_keep_the_sensor_plane() -> None:
    rec = sample_layers(solids.box(0.1, 0.1, 0.05), builtin_finger("4"), [0.02], quantise=True)
    faces = merge_planes(rec, include_table=False)
    assert len(faces) == 4
    for f in faces:
        assert not f.refined
        assert abs(abs(f.offset) - 0.05) < 1e-9


def test_fit_face_refines_only_when_the_centres_span() -> None:
    c = np.array([[0, 0, 1.0], [1, 0, 1.0], [0, 1, 1.0], [1, 1, 1.0]])
    s = np.tile([0.0, 0.26, 0.97], (4, 1))
    n, off, _res, refined = fit_face(c, s)
    assert refined
    assert np.allclose(n, [0, 0, 1])
    assert math.isclose(off, 1.0)
    n2, _, _, refined2 = fit_face(c[:2], s[:2])
    assert not refined2
    assert abs(n2[0]) < 1e-12


def test_table_contacts_are_ignored_and_bad_options_raise() -> None:
    c = Contact(
        step=0, centre=(0.2, 0, 0.005), sensors=(0,), direction=(0, 0, -1.0), point=(0.2, 0, 0.0)
    )
    rec = ExplorationRecord(
        finger="33", tip_radius=0.005, sensor_directions=list(F33.directions), contacts=[c]
    )
    faces = merge_planes(rec)
    assert [f.source for f in faces] == ["table"]
    with pytest.raises(UsageError, match="cut_deg"):
        merge_planes(rec, cut_deg=100)


def test_merge_plane_arrays_equals_merge_planes() -> None:
    from tactile_kb.errors import UsageError
    from tactile_kb.geometry.planes import contact_arrays, merge_plane_arrays, merge_planes
    from tactile_kb.solids import box
    from tactile_kb.touch.finger import builtin_finger
    from tactile_kb.touch.synthetic import sample_record

    rec = sample_record(box(0.1, 0.06, 0.04), builtin_finger("33"), noise=0.0005, seed=4)
    arrays = contact_arrays(rec.contacts)
    assert merge_plane_arrays(rec, arrays, range(len(rec.contacts))) == merge_planes(rec)
    with pytest.raises(UsageError):
        merge_plane_arrays(rec, arrays, range(len(rec.contacts) - 1))


def test_touches_of_an_edge_beside_a_face_do_not_tilt_it() -> None:
    # two of sixteen contacts of a face touched the edge above it: their tip centres lie 1.8 mm
    # inside the face's plane (nearer than ρ to it). The face's plane is the one its other
    # centres share, not the least-squares compromise.
    mesh = solids.box(0.08, 0.06, 0.05)
    rec = sample_record(mesh, F33, per_face=16, quantise=False, noise=0.0, seed=4)
    face = next(f for f in merge_planes(rec) if f.normal[0] > 0.99)  # x = 0.04
    top2 = sorted(face.contacts, key=lambda i: rec.contacts[i].centre[2])[-2:]
    contacts = list(rec.contacts)
    for i in top2:
        x, y, z = contacts[i].centre
        contacts[i] = contacts[i].model_copy(update={"centre": (x - 0.0018, y, z)})
    touched = rec.model_copy(update={"contacts": contacts})
    faces = merge_planes(touched)
    face = next(f for f in faces if f.normal[0] > 0.9)
    assert set(top2) <= set(face.contacts)
    assert math.degrees(math.acos(min(1.0, face.normal[0]))) < 0.01
    assert face.offset == pytest.approx(0.04, abs=1e-6)
    # the least-squares plane of the same centres is tilted by them
    c = np.asarray([touched.contacts[i].centre for i in face.contacts])
    s = np.tile([1.0, 0.0, 0.0], (len(c), 1))
    normal, _, _, _ = fit_face(c, s)
    assert math.degrees(math.acos(min(1.0, float(normal[0])))) > 0.5


def _with_line_on_face(
    rec: ExplorationRecord, sensors: tuple[int, ...], off: float, seed: int = 0
) -> ExplorationRecord:
    """``rec`` with six more contacts along a horizontal line on the box's face x = −0.05, at
    ``off`` metres outside its plane, that closed ``sensors`` together (their mean direction)."""
    s = np.asarray(rec.sensor_directions)
    d = s[list(sensors)].sum(axis=0)
    d /= np.linalg.norm(d)
    rng = np.random.default_rng(seed)
    rho = rec.tip_radius
    extra = []
    for y in np.linspace(-0.025, 0.025, 6):
        c = np.array([-0.05 - rho - off + rng.normal(0.0, 0.0001), y, 0.02])
        extra.append(
            Contact(
                step=len(rec.contacts) + len(extra),
                centre=(float(c[0]), float(c[1]), float(c[2])),
                sensors=sensors,
                sensor=sensors[-1],
                direction=(float(d[0]), float(d[1]), float(d[2])),
                point=tuple(float(v) for v in c + rho * d),
                kind="slide",
            )
        )
    return rec.model_copy(update={"contacts": [*rec.contacts, *extra]})


@pytest.mark.parametrize("tilt", [1, 2])  # the neighbouring sensor below, or both together
def test_a_line_whose_sensor_tilts_on_a_face_is_that_face(tilt: int) -> None:
    # A scanned face's bump makes the sensor below the one square to the face fire (30° off),
    # alone or with it: the contacts slid along it at one height cluster apart and span no
    # plane of their own. Their centres lie on the face's plane, so they are the face (the
    # box keeps five faces and the table); the same line on a step 5 mm out is a face of its
    # own, and so is the line 30° off when merging is switched off.
    from tactile_kb.settings import override

    rec = sample_record(solids.box(0.1, 0.08, 0.06), F33, per_face=12, noise=0.0, seed=1)
    s = np.asarray(rec.sensor_directions)
    square = int(np.argmax(s @ [1.0, 0.0, 0.0]))
    below = int(np.argmax(s @ [math.cos(math.radians(30)), 0.0, -math.sin(math.radians(30))]))
    sensors = (below,) if tilt == 1 else (square, below)
    on_face = merge_planes(_with_line_on_face(rec, sensors, 0.0))
    assert len(on_face) == 6
    left = min(on_face, key=lambda f: f.normal[0])
    assert left.n_contacts == 12 + 6
    assert left.normal[0] == pytest.approx(-1.0, abs=1e-3)
    assert len(merge_planes(_with_line_on_face(rec, sensors, 0.005))) == 7
    if tilt == 1:  # 30° off: the sensors' clusters keep it apart, only the merge joins it
        with override(geometry={"unrefined_merge_cones": 0.0}):
            assert len(merge_planes(_with_line_on_face(rec, sensors, 0.0))) == 7


def test_means_of_neighbouring_sensors_are_quantised_directions() -> None:
    from tactile_kb.geometry.planes import _is_quantised

    s = np.asarray(F33.directions, dtype=float)
    pair = s[0] + s[int(np.argsort(-(s @ s[0]))[1])]
    mean = pair / np.linalg.norm(pair)
    assert _is_quantised(np.vstack([s[:3], mean]), s)
    other = np.array([0.3, 0.5, -0.81])
    assert not _is_quantised(np.vstack([s[:3], other / np.linalg.norm(other)]), s)
