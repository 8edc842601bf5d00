"""The fast paths of the face fitting equal plain reference computations."""

import numpy as np

from tactile_kb.geometry.planes import _spots


def _spots_reference(c: np.ndarray, radius: float) -> int:
    """The greedy count written out point by point."""
    places: list[np.ndarray] = []
    for p in c:
        if all(float(np.linalg.norm(p - q)) > radius for q in places):
            places.append(p)
    return len(places)


def test_spots_equals_the_pointwise_greedy_count() -> None:
    rng = np.random.default_rng(3)
    for trial in range(200):
        n = int(rng.integers(0, 40))
        # clustered points: a few places with scatter, so counts vary around the radius
        centres = rng.uniform(-0.05, 0.05, size=(int(rng.integers(1, 8)), 3))
        c = centres[rng.integers(0, len(centres), size=n)] + rng.normal(0, 0.004, size=(n, 3))
        radius = float(rng.uniform(0.001, 0.02))
        want = _spots_reference(c, radius)
        assert _spots(c, radius) == want, trial
        for limit in (1, 3, 5):
            got = _spots(c, radius, limit)
            assert got == (want if want <= limit else limit + 1), (trial, limit)


def test_spots_on_constructed_places() -> None:
    # three places 1 cm apart, each touched 4 times within 1 mm; a radius of 5 mm sees 3
    base = np.array([[0.0, 0, 0], [0.01, 0, 0], [0.0, 0.01, 0]])
    offsets = np.array([[0, 0, 0], [0.0005, 0, 0], [0, 0.0005, 0], [0, 0, 0.0005]])
    c = (base[:, None, :] + offsets[None, :, :]).reshape(-1, 3)
    assert _spots(c, 0.005) == 3
    assert _spots(c, 0.005, 2) == 3  # stops at limit + 1
    assert _spots(c, 0.0001) == 12
    assert _spots(c[:0], 0.005) == 0


def test_median_is_numpys_median() -> None:
    """The partition median of the robust fits equals np.median, bit for bit, odd and even."""
    from tactile_kb.geometry.planes import _median

    rng = np.random.default_rng(7)
    for n in (1, 2, 3, 4, 5, 10, 11, 100, 101):
        for _ in range(20):
            a = rng.normal(size=n) * rng.uniform(1e-6, 10.0)
            assert _median(a) == float(np.median(a))
    assert _median(np.array([3.0, 1.0, 2.0, 2.0])) == 2.0
