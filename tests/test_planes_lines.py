"""Two parallel faces touched along one line each by the same sensor (geometry/planes.py,
``_parallel_lines``): the sensors that stayed OFF tell them from one tilted face.

Ground truth is constructed: tip centres placed at ρ outside planes of known normals and
offsets, each read as the stepper reads it: every sensor whose acceptance cone holds the
surface's inward direction closes, and the reported direction is their mean.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from touching import FINGER, RHO, touched_record

from tactile_kb.geometry.planes import merge_planes
from tactile_kb.record import Contact


def _read(step: int, point: np.ndarray, normal: np.ndarray) -> Contact:
    """The touch of the surface point ``point`` of outward ``normal``, read physically."""
    inward = -normal / np.linalg.norm(normal)
    fired = FINGER.fired([tuple(float(x) for x in inward)])
    mean = FINGER.matrix[list(fired)].sum(axis=0)
    mean /= np.linalg.norm(mean)
    k = fired[int(np.argmax(FINGER.matrix[list(fired)] @ mean))]
    centre = point + RHO * normal / np.linalg.norm(normal)
    return Contact(
        step=step,
        centre=(float(centre[0]), float(centre[1]), float(centre[2])),
        sensors=fired,
        sensor=k,
        direction=(float(mean[0]), float(mean[1]), float(mean[2])),
        point=tuple(float(c + RHO * x) for c, x in zip(centre, mean, strict=True)),
        kind="slide",
    )


def _line(start: int, normal: np.ndarray, offset: float, z: float) -> list[Contact]:
    """Five touches along a horizontal line of the plane ``normal · r = offset`` at height z."""
    n = normal / np.linalg.norm(normal)
    across = np.cross([0.0, 0.0, 1.0], n)
    across /= np.linalg.norm(across)
    base = np.array([0.0, 0.0, z])
    base += n * (offset - float(n @ base)) / float(n @ n)  # onto the plane, at height ≈ z
    return [
        _read(start + k, base + t * across, n) for k, t in enumerate(np.linspace(-0.012, 0.012, 5))
    ]


def _faces(contacts: list[Contact]) -> list:
    return [f for f in merge_planes(touched_record("lines", contacts)) if f.source == "contacts"]


@pytest.mark.parametrize("turn", [0.0, 83.0, 104.0])
def test_two_parallel_faces_of_one_sensor_stay_two(turn: float) -> None:
    # a T-block standing on its crossbar: the stem's side touched high, the crossbar's end
    # low, both by the one equator sensor facing them
    a = math.radians(turn)
    n = np.array([math.cos(a), math.sin(a), 0.0])
    contacts = _line(0, n, 0.0154, 0.0876) + _line(5, n, 0.0452, 0.0109)
    # the ten centres fit one plane through both lines exactly: the geometry alone keeps them
    c = np.asarray([x.centre for x in contacts])
    _, s, _ = np.linalg.svd(c - c.mean(axis=0), full_matrices=False)
    assert s[2] < 1e-9
    faces = _faces(contacts)
    assert len(faces) == 2
    assert sorted(round(f.offset, 6) for f in faces) == [0.0154, 0.0452]
    for f in faces:
        assert f.n_contacts == 5
        assert math.degrees(math.acos(min(1.0, float(f.normal_array @ n)))) < 0.01


@pytest.mark.parametrize("tilt", [21.0, 15.0, 35.0])
def test_one_tilted_face_touched_at_two_heights_stays_one(tilt: float) -> None:
    # a frustum's side, touched by two contour layers: its sensors say it is tilted
    t = math.radians(tilt)
    n = np.array([math.cos(t), 0.0, math.sin(t)])
    contacts = _line(0, n, 0.03, 0.08) + _line(5, n, 0.03, 0.02)
    faces = _faces(contacts)
    assert len(faces) == 1
    assert faces[0].n_contacts == 10
    assert math.degrees(math.acos(min(1.0, float(faces[0].normal_array @ n)))) < 0.01
