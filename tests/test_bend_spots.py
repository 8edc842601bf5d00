"""A face's bend measured from tip centres that crowd at a few spots or lie on two lines.

Ground truth is built independently: the leave-one-spot-out fits are solved one by one with
numpy's least squares, and the records are a box's exact touches moved to where the tests
put them (a flat face, so any bend measured is the noise's or the jitter's)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_features import FINGER, _side_frame, _with_contact

from tactile_kb import solids
from tactile_kb.features.builtin import (
    SPOT_RHO,
    _jackknife_se,
    _spots,
    _spread_evidence,
    get_feature,
    spread_bend,
)
from tactile_kb.geometry.model import build_model
from tactile_kb.touch.synthetic import sample_record


def test_spots_are_chains_of_centres_within_reach() -> None:
    points = np.array([[0.0, 0.0], [0.002, 0.0], [0.004, 0.0], [0.0, 0.02], [0.03, 0.03]])
    labels = _spots(points, 0.0025)
    # the first three chain (each within reach of the next), the others stand alone
    assert labels[0] == labels[1] == labels[2]
    assert len({int(labels[0]), int(labels[3]), int(labels[4])}) == 3
    assert len(set(_spots(points, 0.001).tolist())) == 5


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_jackknife_error_is_that_of_the_fits_leaving_one_spot_out(seed: int) -> None:
    # five spots on a face, three centres each, every spot's centres lifted together by its
    # own bump: leaving out a spot, not a centre, is what the bend can rest on
    rng = np.random.default_rng(seed)
    spot = np.repeat(np.arange(5), 3)
    u = rng.uniform(-0.5, 0.5, 5)[spot] + rng.normal(0.0, 0.01, 15)
    v = rng.uniform(-0.5, 0.5, 5)[spot] + rng.normal(0.0, 0.01, 15)
    design = np.column_stack([np.ones(15), u, v, u * u])
    h = rng.normal(0.0, 0.0005, 5)[spot] + rng.normal(0.0, 0.0001, 15)
    beta = np.linalg.lstsq(design, h, rcond=None)[0]
    rest = h - design @ beta
    left_out = np.array(
        [np.linalg.lstsq(design[spot != s], h[spot != s], rcond=None)[0][-1] for s in range(5)]
    )
    truth = math.sqrt(4 / 5 * float(((left_out - left_out.mean()) ** 2).sum()))
    assert _jackknife_se(design, rest, spot) == pytest.approx(truth, rel=1e-6)
    # the shared bumps make the bend far less certain than its centres one by one say
    assert _jackknife_se(design, rest, spot) > 2.0 * _jackknife_se(design, rest)


def test_a_fit_that_needs_a_spot_falls_back_to_its_rows() -> None:
    # three lines across u (a lying half cylinder's three layers): leaving out a line leaves
    # the bend undetermined, so the centres are left out one at a time
    rng = np.random.default_rng(4)
    line = np.repeat(np.arange(3), 6)
    u = np.array([-0.5, 0.1, 0.5])[line]
    v = rng.uniform(-0.5, 0.5, 18)
    design = np.column_stack([np.ones(18), u, v, u * u])
    rest = rng.normal(0.0, 0.0002, 18)
    rest -= design @ np.linalg.lstsq(design, rest, rcond=None)[0]
    assert _jackknife_se(design, rest, line) == pytest.approx(_jackknife_se(design, rest))


@pytest.mark.parametrize("jitter", [0.0002, 0.0008])
def test_two_jittered_lines_across_the_turn_cannot_show_a_bend(jitter: float) -> None:
    # a flat face touched along two layers 2 cm apart, the sensors turned across the lines
    # (upwards) at every other touch, each centre off its line by up to ``jitter`` (a scan's
    # roughness): the lines fit any bend, and a fit through the jitter is no measurement
    assert jitter < SPOT_RHO * FINGER.radius
    rec = sample_record(solids.box(0.08, 0.08, 0.08), FINGER, per_face=8, quantise=False, noise=0.0)
    face, fi, centre, n, along = _side_frame(rec)
    d0 = np.asarray(rec.contacts[face.contacts[0]].direction)
    up = d0 * math.cos(math.radians(15.0)) + np.array([0.0, 0.0, math.sin(math.radians(15.0))])
    rng = np.random.default_rng(7)
    out = rec
    for k, i in enumerate(face.contacts):
        z = 0.01 * (-1) ** k + rng.uniform(-jitter, jitter)
        point = centre + along * (0.02 * (k // 2) - 0.03) + [0.0, 0.0, z]
        d = up / np.linalg.norm(up) if k % 2 else d0
        out = _with_contact(out, i, d, point + FINGER.radius * n + rng.normal(0.0, 0.0003) * n)
    lines = build_model(out)
    assert spread_bend(lines, fi)[1] == math.inf
    assert not get_feature("surface_curved").fn(lines)
    assert _spread_evidence(lines, 10.0) == (False, 1)  # the sensors' weak evidence: a fold
