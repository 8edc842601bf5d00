"""A face's scatter is never taken as less than the declared noise (geometry/planes.py).

Ground truth is constructed: six tip centres placed exactly ρ outside the plane x = 40 mm, on
a record that declares 0.5 mm of noise. Six centres can fit a plane far better than their
noise by chance (three degrees of freedom); the face's uncertainties must still reflect the
noise the record declares, not the chance fit.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from touching import RHO, contact, touched_record

from tactile_kb.geometry.planes import merge_planes

NOISE = 0.0005


def _face(noise: float) -> tuple[float, float]:
    x = np.array([1.0, 0.0, 0.0])
    spots = [(-0.01, 0.01), (0.0, 0.01), (0.01, 0.01), (-0.01, 0.03), (0.0, 0.03), (0.01, 0.03)]
    contacts = [contact(k, np.array([0.04 + RHO, y, z]), x) for k, (y, z) in enumerate(spots)]
    faces = [
        f
        for f in merge_planes(touched_record("six", contacts, noise=noise))
        if f.source == "contacts"
    ]
    assert len(faces) == 1
    assert faces[0].refined
    assert faces[0].residual == pytest.approx(0.0, abs=1e-12)  # the centres fit exactly
    return faces[0].offset_uncertainty, faces[0].normal_uncertainty_deg


def test_a_chance_fit_of_six_noisy_centres_keeps_the_declared_noise() -> None:
    offset, normal = _face(NOISE)
    assert offset == pytest.approx(NOISE / math.sqrt(6), rel=1e-9)
    assert normal > 0.5  # degrees: 0.5 mm over a 2 cm spread, not the chance fit's 0


def test_without_declared_noise_an_exact_fit_is_exact() -> None:
    offset, normal = _face(0.0)
    assert offset == pytest.approx(0.0, abs=1e-12)
    assert normal == pytest.approx(0.0, abs=1e-9)
