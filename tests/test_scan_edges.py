"""Scan-like solids, round 6 (issue 10): the quantisation of sensors read with the head
indexed, and a probe of a corner that juts out beyond the workspace.

Ground truth is the geometry built here: sensor directions turned with the head, and a box
whose face lies where a probe aimed far outside it must find it.
"""

from __future__ import annotations

import numpy as np
from probing import OneProbe

from tactile_kb import solids
from tactile_kb.geometry.planes import merge_planes
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import Orientation, builtin_finger
from tactile_kb.touch.servo import Probe
from tactile_kb.touch.stepper import StepperExplorer

FINGER = builtin_finger("33")
RHO = FINGER.radius


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


def test_a_probe_aimed_far_outside_the_object_starts_where_its_line_leaves_the_hint() -> None:
    # A model that lacks a face puts a corner where its neighbours' planes meet, possibly
    # further out than the workspace reaches (bounds + 15 cm). The object lies inside the
    # hint box: the probe of that corner approaches from where its line leaves the box, and
    # touches the face the model lacks.
    box = solids.box(0.08, 0.06, 0.05)  # x in ±4 cm
    far = Probe((0.40, 0.0, 0.025), (1.0, 0.0, 0.0), 0.40, "a corner juts out (test)")
    explorer = StepperExplorer(completer=lambda: OneProbe(far))
    record = explorer.explore(box, seed=0)
    probed = [c for c in record.contacts if c.phase == "complete" and c.kind == "touch"]
    assert not [n for n in record.notes if "outside the workspace" in n]
    assert len(probed) == 1
    assert abs(probed[0].centre[0] - (0.04 + RHO)) < 1e-6
    assert np.allclose(probed[0].direction, (-1.0, 0.0, 0.0))
