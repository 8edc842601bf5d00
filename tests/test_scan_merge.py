"""A face touched a few times beside one touched often (issue 10, round 8): the few touches'
own plane may turn by several degrees (noise over a short span); when every one of their
centres lies on the well-touched face's plane they are that face, and when they lie off it
they stay a face of their own.

Ground truth is the geometry built here: tip centres ρ outside the plane x = 50 mm (and, for
the second face, outside a plane turned 10° from it about their common edge).
"""

from __future__ import annotations

import math

import numpy as np
from touching import RHO, contact, touched_record

from tactile_kb.geometry.planes import merge_planes
from tactile_kb.record import ExplorationRecord

NOISE = 0.0005


def _record(small: list[np.ndarray], small_sensor: np.ndarray) -> ExplorationRecord:
    """Twenty touches of the face x = 0.05 (y < 0) on a grid, with their sensor the face's;
    then the ``small`` group's centres, touched by the sensor nearest ``small_sensor``."""
    x = np.array([1.0, 0.0, 0.0])
    jitter = [0.0004, -0.0003, 0.0001, -0.0004, 0.0002]
    contacts = []
    for a, z in enumerate((0.01, 0.025, 0.04, 0.055)):
        for b, y in enumerate((-0.05, -0.04, -0.03, -0.02, -0.01)):
            dx = jitter[(a + 2 * b) % 5]
            contacts.append(contact(len(contacts), np.array([0.05 + RHO + dx, y, z]), x))
    for c in small:
        contacts.append(contact(len(contacts), c, small_sensor))
    return touched_record("two groups", contacts, noise=NOISE)


# the sensor beside the face's: the surface's detail under a few touches turned it
TILTED = np.array([math.cos(math.radians(25.0)), math.sin(math.radians(25.0)), 0.0])


def _small_on_the_face() -> list[np.ndarray]:
    # two short lines on the plane x = 0.05, their centres within 0.4 mm of it, leaning so
    # that their own plane turns by about 6° about z
    rows = [(0.02, 0.000, 0.0004), (0.02, 0.004, 0.0), (0.02, 0.008, -0.0004)]
    rows += [(0.05, 0.002, 0.0003), (0.05, 0.006, -0.0003)]
    return [np.array([0.05 + RHO + dx, y, z]) for z, y, dx in rows]


def _own_fit_angle(centres: list[np.ndarray]) -> float:
    c = np.asarray(centres)
    _, _, vt = np.linalg.svd(c - c.mean(axis=0))
    return math.degrees(math.acos(abs(float(vt[2][0]))))


def test_a_few_touches_on_a_well_touched_face_join_it() -> None:
    small = _small_on_the_face()
    assert _own_fit_angle(small) > 4.0  # beyond geometry.merge_deg on their own
    faces = [f for f in merge_planes(_record(small, TILTED)) if f.source == "contacts"]
    assert len(faces) == 1
    assert faces[0].n_contacts == 25
    assert math.degrees(math.acos(min(1.0, faces[0].normal[0]))) < 1.0


def test_a_few_touches_off_the_face_stay_a_face() -> None:
    # the same lines 2.5 mm proud of the face (a step, a lid's rim): together with the face
    # they still fit one plane within geometry.split_tol at this noise, but their centres lie
    # off its plane by more than three times its scatter
    small = [c + np.array([0.0025, 0.0, 0.0]) for c in _small_on_the_face()]
    faces = [f for f in merge_planes(_record(small, TILTED)) if f.source == "contacts"]
    assert len(faces) == 2
    assert sorted(f.n_contacts for f in faces) == [5, 20]


def _rough_record(small: list[np.ndarray]) -> ExplorationRecord:
    """Exact touches of a scanned face x = 0.05 whose tip centres mostly lie within 0.2 mm of
    its plane and, over four bumps and dips, 1.2 mm off it (a rough scan's heavy tails); then
    the ``small`` group's, read by the tilted sensor."""
    x = np.array([1.0, 0.0, 0.0])
    fine = [0.0002, -0.0001, 0.00005, -0.0002, 0.00015]
    bumps = {(0, 1): 0.0012, (1, 3): -0.0012, (2, 0): -0.0012, (3, 4): 0.0012}
    contacts = []
    for a, z in enumerate((0.01, 0.025, 0.04, 0.055)):
        for b, y in enumerate((-0.05, -0.04, -0.03, -0.02, -0.01)):
            dx = bumps.get((a, b), fine[(a + 2 * b) % 5])
            contacts.append(contact(len(contacts), np.array([0.05 + RHO + dx, y, z]), x))
    for c in small:
        contacts.append(contact(len(contacts), c, TILTED))
    return touched_record("a rough face", contacts, noise=0.0)


def test_a_few_touches_as_far_off_a_rough_face_as_its_own_join_it() -> None:
    # the few touches lie on the face, up to 0.8 mm off it (their own plane turned by 4.7°):
    # further than three robust σ of the face's own centres (from their median deviation,
    # 0.67 mm), nearer than three of their standard deviations (1.8 mm: its bumps)
    rows = [(0.02, 0.000, 0.0008), (0.02, 0.004, 0.0006), (0.02, 0.008, 0.0007)]
    rows += [(0.035, 0.010, -0.0006), (0.035, 0.016, -0.0007)]
    small = [np.array([0.05 + RHO + dx, y, z]) for z, y, dx in rows]
    assert _own_fit_angle(small) > 4.0  # beyond geometry.merge_deg on their own
    faces = [f for f in merge_planes(_rough_record(small)) if f.source == "contacts"]
    assert [f.n_contacts for f in faces] == [25]
    assert math.degrees(math.acos(min(1.0, faces[0].normal[0]))) < 1.0


def test_a_few_touches_beyond_a_rough_face_s_scatter_stay_a_face() -> None:
    # the same touches 2 mm proud of the rough face: beyond three of its standard deviations
    # (a step, a lid's rim)
    rows = [(0.02, 0.000, 0.0008), (0.02, 0.004, 0.0006), (0.02, 0.008, 0.0007)]
    rows += [(0.035, 0.010, -0.0006), (0.035, 0.016, -0.0007)]
    small = [np.array([0.05 + RHO + dx + 0.002, y, z]) for z, y, dx in rows]
    faces = [f for f in merge_planes(_rough_record(small)) if f.source == "contacts"]
    assert sorted(f.n_contacts for f in faces) == [5, 20]
