"""Faces of scan-like surfaces, round 7 (issue 10): one-spot touches of edges rounded more
widely than the tip, the quantisation of sensors read with the head indexed, and a probe of a
corner that juts out beyond the workspace.

Ground truth is the geometry built here: the planes of a cube, tip centres placed where a tip
touching an edge rounded with a radius r puts them (at ρ + r from the rounding's axis), and
sensor directions turned with the head.
"""

from __future__ import annotations

import math

import numpy as np

from tactile_kb import solids
from tactile_kb.geometry.planes import Face, edge_faces, merge_planes
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import Orientation, builtin_finger
from tactile_kb.touch.servo import Ending, Probe
from tactile_kb.touch.stepper import StepperExplorer

FINGER = builtin_finger("33")
RHO = FINGER.radius
HALF = 0.075  # a 15 cm cube
SIDES = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)]
TABLE = Face((0.0, 0.0, -1.0), 0.0, 0, 0.0, 0.0, (), False, "table")


def _cube_faces() -> tuple[list[Face], np.ndarray]:
    """The five touched faces of a 15 cm cube standing on the table, each with nine tip
    centres ρ out of it (a 3 × 3 grid about its middle, 3 cm apart)."""
    faces, own = [], []
    for n in SIDES:
        v = np.asarray(n, dtype=float)
        offset = HALF if n[2] == 0 else 2 * HALF
        middle = v * offset + (np.array([0.0, 0.0, HALF]) if n[2] == 0 else 0.0)
        a = np.cross(v, [0.0, 0.0, 1.0] if n[2] == 0 else [1.0, 0.0, 0.0])
        a /= np.linalg.norm(a)
        b = np.cross(v, a)
        start = len(own)
        own += [middle + RHO * v + 0.03 * (i * a + j * b) for i in (-1, 0, 1) for j in (-1, 0, 1)]
        contacts = tuple(range(start, start + 9))
        faces.append(Face(tuple(map(float, v)), offset, 9, 0.0002, 0.5, contacts, True))
    return faces, np.asarray(own)


def _one_spot_on_the_rounding(r: float, deeper: float = 0.0) -> tuple[list[Face], np.ndarray]:
    """The cube's faces and a face touched at one spot (three tip centres along a line
    beside each other, their sensor square to the bisector) on the vertical edge x = y = HALF
    rounded with radius ``r``, ``deeper`` metres further in than the rounding puts them."""
    faces, own = _cube_faces()
    m = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
    axis = np.array([HALF - r, HALF - r, 0.0])
    spot = [axis + (RHO + r - deeper) * m + [0.0, 0.0, z] for z in (0.07, 0.075, 0.08)]
    centres = np.vstack([own, spot])
    n = len(own)
    offset = float(m @ spot[0]) - RHO
    edge = Face((m[0], m[1], 0.0), offset, 3, 0.0, 13.0, (n, n + 1, n + 2), False)
    return [*faces, edge, TABLE], centres


def test_a_one_spot_touch_of_a_widely_rounded_edge_is_an_edge_touch() -> None:
    # r = 12 mm (8 % of the 15 cm faces): the tip on the rounding's bisector lies
    # r (1 − cos 45°) = 3.5 mm inside the sharp cube's ρ-offset, deeper than half a tip
    # radius into the nearest faces' planes, which it still lies against.
    faces, centres = _one_spot_on_the_rounding(0.012)
    assert edge_faces(faces, centres, RHO, rounding=0.10) == [5]
    # the same spot 25 mm further in: a corner cut off, deeper than the widest rounding (10 %
    # of the faces' width) puts a tip
    faces, centres = _one_spot_on_the_rounding(0.012, deeper=0.025)
    assert edge_faces(faces, centres, RHO, rounding=0.10) == []


def _record(directions: np.ndarray, orientation: tuple[float, float]) -> ExplorationRecord:
    """Three exact touches along a line on the face x = 0.05 of an object, reported by
    ``directions`` (world frame) with the head at ``orientation``."""
    contacts = []
    for k, z in enumerate((0.03, 0.04, 0.05)):
        centre = (0.05 + RHO, 0.0, z)
        d = tuple(float(x) for x in directions[k])
        point = tuple(c + RHO * x for c, x in zip(centre, d, strict=True))
        contacts.append(
            Contact(
                step=k,
                centre=centre,
                sensors=(0,),
                direction=d,
                point=point,
                orientation=orientation,
            )
        )
    return ExplorationRecord(
        object="line",
        finger=FINGER.name,
        tip_radius=RHO,
        sensor_directions=[tuple(map(float, s)) for s in FINGER.matrix],
        contacts=contacts,
    )


def test_a_tilted_head_keeps_its_sensors_quantised() -> None:
    # The face touched along one vertical line spans no plane: its normal is a sensor's, and
    # as uncertain as the sensors' quantisation (half their spacing), whatever the head's
    # pose. Read with the head tilted 45° and turned 30°, the sensor pointing nearest −x in
    # the world is still one of the layout's, turned.
    pose = Orientation(45.0, 30.0)
    world = FINGER.directions_at(pose)
    k = int(np.argmax(world @ np.array([-1.0, 0.0, 0.0])))
    tilted = merge_planes(_record(np.repeat(world[k : k + 1], 3, axis=0), (45.0, 30.0)))
    k0 = int(np.argmax(FINGER.matrix @ np.array([-1.0, 0.0, 0.0])))
    vertical = merge_planes(_record(np.repeat(FINGER.matrix[k0 : k0 + 1], 3, axis=0), (0.0, 0.0)))
    assert not tilted[0].refined
    assert not vertical[0].refined
    assert vertical[0].normal_uncertainty_deg > 10.0
    assert tilted[0].normal_uncertainty_deg == vertical[0].normal_uncertainty_deg


class _OneProbe:
    """A completer that asks for ``probe`` once, then ends."""

    def __init__(self, probe: Probe) -> None:
        self.probe = probe
        self.asked = False

    def next_probe(
        self, record: ExplorationRecord, last: tuple[Probe, bool] | None
    ) -> Probe | Ending:
        if self.asked:
            return Ending("closed", "done")
        self.asked = True
        return self.probe


def test_a_probe_aimed_far_outside_the_object_starts_where_its_line_leaves_the_hint() -> None:
    # A model that lacks a face puts a corner where its neighbours' planes meet, possibly
    # further out than the workspace reaches (bounds + 15 cm). The object lies inside the
    # hint box: the probe of that corner approaches from where its line leaves the box, and
    # touches the face the model lacks.
    box = solids.box(0.08, 0.06, 0.05)  # x in ±4 cm
    far = Probe((0.40, 0.0, 0.025), (1.0, 0.0, 0.0), 0.40, "a corner juts out (test)")
    explorer = StepperExplorer(completer=lambda: _OneProbe(far))
    record = explorer.explore(box, seed=0)
    probed = [c for c in record.contacts if c.phase == "complete" and c.kind == "touch"]
    assert not [n for n in record.notes if "outside the workspace" in n]
    assert len(probed) == 1
    assert abs(probed[0].centre[0] - (0.04 + RHO)) < 1e-6
    assert np.allclose(probed[0].direction, (-1.0, 0.0, 0.0))
