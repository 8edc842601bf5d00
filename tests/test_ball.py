"""A ball's touches lie on one sphere (``features.centres_on_sphere``), a polyhedron's do not.

The records are sampled on solids constructed here (``tactile_kb.solids``) or built from
their geometry directly; the labels come from the construction.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.features.builtin import centres_on_sphere, surface_curved
from tactile_kb.geometry.model import build_model
from tactile_kb.perturb import perturb
from tactile_kb.pipeline import classify
from tactile_kb.record import Contact, ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

F33 = builtin_finger("33")
RHO = F33.radius


def _on_sphere(radius: float, seed: int) -> ExplorationRecord:
    return sample_record(solids.sphere(radius), F33, total=60, noise=0.0005, seed=seed)


@pytest.mark.parametrize("radius", [0.05, 0.08, 0.15])
@pytest.mark.parametrize("seed", [0, 1])
def test_a_ball_s_touches_lie_on_one_sphere(radius: float, seed: int) -> None:
    model = build_model(_on_sphere(radius, seed))
    assert centres_on_sphere(model)
    assert surface_curved(model)


@pytest.mark.parametrize(
    "solid",
    [
        solids.box(0.08, 0.06, 0.04),
        solids.box(0.05, 0.05, 0.05),
        solids.octahedron(0.06),
        solids.prism(8, 0.04, 0.05),
        solids.pyramid(6, 0.04, 0.05),
        solids.frustum(6, 0.03, 0.015, 0.03),
    ],
    ids=["box", "cube", "octahedron", "prism8", "pyramid6", "frustum6"],
)
@pytest.mark.parametrize("noise", [0.0, 0.0005])
def test_a_polyhedron_s_touches_miss_every_sphere(solid: trimesh.Trimesh, noise: float) -> None:
    record = sample_record(solid, F33, per_face=8, noise=noise, seed=3)
    assert not centres_on_sphere(build_model(record))


def test_a_small_ball_under_noise_is_left_to_the_other_tests() -> None:
    # 0.5 mm of noise is 3 % of a 1.2 cm ball's tip-centre sphere: more than the 1.5 % the
    # test allows, which is relative only (small polyhedra fit a sphere that well)
    assert not centres_on_sphere(build_model(_on_sphere(0.012, 0)))


def _moved(record: ExplorationRecord, contacts: list[Contact]) -> ExplorationRecord:
    return record.model_copy(update={"contacts": contacts})


def test_a_bowl_touched_from_inside_is_no_ball() -> None:
    # the same centres on a sphere, but each sensor pointing away from its centre: the inside
    # of a spherical bowl
    record = _on_sphere(0.08, 0)
    centres = np.array([c.centre for c in record.contacts])
    middle = np.array([0.0, 0.0, 0.08])
    out = (centres - middle) / np.linalg.norm(centres - middle, axis=1)[:, None]
    inside = [
        c.model_copy(update={"direction": tuple(u), "point": tuple(p + RHO * u)})
        for c, u, p in zip(record.contacts, out, centres, strict=True)
    ]
    assert centres_on_sphere(build_model(record))
    assert not centres_on_sphere(build_model(_moved(record, inside)))


def test_one_flat_face_is_no_ball() -> None:
    # centres on one plane fit a sphere only of huge radius, larger than their extent
    rng = np.random.default_rng(5)
    xy = rng.uniform(-0.04, 0.04, size=(30, 2))
    down = (0.0, 0.0, -1.0)
    contacts = [
        Contact(
            step=k,
            centre=(float(x), float(y), 0.05 + RHO + float(rng.normal(0, 0.0003))),
            sensors=(0,),
            direction=down,
            point=(float(x), float(y), 0.05),
        )
        for k, (x, y) in enumerate(xy)
    ]
    record = _moved(_on_sphere(0.08, 0), contacts)
    assert not centres_on_sphere(build_model(record))


@pytest.mark.parametrize(("radius", "seed"), [(0.05, 0), (0.0777, 2), (0.1, 1)])
def test_a_poorly_scanned_ball_is_curved(radius: float, seed: int) -> None:
    # balls of 5-10 cm under a poor scan's relief (perturbation level 3): contour slides fit
    # planes of their own within a fraction of a millimetre (a circle of a sphere is plane),
    # and the model closes as a polyhedron of a dozen faces or stays open; the touches all
    # lie on one sphere
    ball = perturb(solids.sphere(radius), 3, seed=seed)
    result = classify(ball, rules="polyhedra", seed=0)
    assert result.decision.label == "curved"
    assert centres_on_sphere(result.model)
