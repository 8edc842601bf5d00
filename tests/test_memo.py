"""The kept answers of the geometry: a :class:`Memo` is a bounded LRU table, and the plane fits
kept by their inputs give, bit for bit, what a fresh computation gives.

The model is built again after every completion probe from mostly the same groups of
contacts, so :func:`tactile_kb.geometry.planes._fit` keeps its answers by the exact inputs
(the centres' and normals' bytes and the tolerances in force). Each test here computes the
same thing with the memo emptied and asks for equal bits, or changes a tolerance and asks for
the fresh answer.
"""

from __future__ import annotations

import threading

import numpy as np
import pytest

from tactile_kb import solids
from tactile_kb.geometry import planes
from tactile_kb.geometry.memo import Memo
from tactile_kb.geometry.model import build_model
from tactile_kb.perturb import perturb, touch_record
from tactile_kb.settings import override
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record


def test_memo_keeps_the_most_recently_used_and_makes_the_rest_again() -> None:
    made: list[str] = []

    def maker(key: str) -> str:
        def make() -> str:
            made.append(key)
            return key.upper()

        return make

    memo: Memo[str, str] = Memo(2)
    assert memo.get("a", maker("a")) == "A"
    assert memo.get("b", maker("b")) == "B"
    assert memo.get("a", maker("a")) == "A"  # recalled; "a" is now the most recent
    assert memo.get("c", maker("c")) == "C"  # "b", the least recently used, goes
    assert len(memo) == 2
    assert memo.get("a", maker("a")) == "A"
    assert memo.get("b", maker("b")) == "B"  # made again
    assert made == ["a", "b", "c", "b"]
    memo.clear()
    assert len(memo) == 0
    assert memo.get("a", maker("a")) == "A"
    assert made[-1] == "a"


def test_memo_stays_bounded_and_consistent_under_threads() -> None:
    memo: Memo[int, int] = Memo(16)
    wrong: list[tuple[int, int]] = []

    def work(offset: int) -> None:
        for i in range(2000):
            key = (i * 7 + offset) % 50
            value = memo.get(key, lambda key=key: key * key)
            if value != key * key:
                wrong.append((key, value))

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert wrong == []
    assert len(memo) <= 16


def _record(index: int) -> object:
    """One of four records: sampled from a box, a prism and a frustum, and touched on a
    level-2 scan of an octahedron."""
    finger = builtin_finger("33")
    if index == 0:
        return sample_record(solids.box(0.1, 0.06, 0.04), finger, noise=0.0005, seed=3)
    if index == 1:
        return sample_record(solids.prism(7, 0.05, 0.1), finger, noise=0.0005, seed=4)
    if index == 2:
        return sample_record(solids.frustum(5, 0.06, 0.03, 0.04), finger, noise=0.0, seed=5)
    octahedron = solids.octahedron(0.08)
    return touch_record(perturb(octahedron, 2, seed=6), octahedron, finger, noise=0.0005, seed=6)


def _faces(record: object) -> list[tuple[bytes, float, tuple[int, ...], bool]]:
    model = build_model(record)  # type: ignore[arg-type]
    return [(np.asarray(f.normal).tobytes(), f.offset, f.contacts, f.refined) for f in model.faces]


@pytest.mark.parametrize("index", range(4))
def test_a_model_from_kept_fits_equals_one_from_fresh_fits(index: int) -> None:
    record = _record(index)
    planes._FITS.clear()
    fresh = _faces(record)
    assert len(planes._FITS) > 0
    warm = _faces(record)  # every fit now from the memo
    assert warm == fresh
    planes._FITS.clear()
    assert _faces(record) == fresh


def test_kept_fits_are_read_only_and_shared() -> None:
    rng = np.random.default_rng(1)
    centres = rng.normal(scale=0.02, size=(12, 3)) * np.array([1.0, 1.0, 0.01])
    normals = np.tile([0.0, 0.0, 1.0], (12, 1))
    planes._FITS.clear()
    a = planes._fit(centres, normals, 0.001, 0.0005)
    b = planes._fit(centres.copy(), normals.copy(), 0.001, 0.0005)  # equal bytes: the same fit
    assert b is a
    with pytest.raises(ValueError, match="read-only"):
        a.normal[0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        a.residuals[0] = 1.0
    # another tolerance is another key
    assert planes._fit(centres, normals, 0.001, 0.0) is not a


def test_a_changed_setting_is_not_answered_from_the_memo() -> None:
    """The fit reads ``geometry.max_refine_deg``: a normal fitted 40° from the sensors'
    is refined under the default (35°)… only when the limit allows it."""
    rng = np.random.default_rng(2)
    xy = rng.uniform(-0.02, 0.02, size=(10, 2))
    tilt = np.radians(30.0)
    centres = np.column_stack([xy[:, 0], xy[:, 1], np.tan(tilt) * xy[:, 0]])
    normals = np.tile([0.0, 0.0, 1.0], (10, 1))  # the sensors read straight up
    planes._FITS.clear()
    wide = planes._fit(centres, normals, 0.001)
    assert wide.refined  # 30° from the sensors: within the default 35°
    with override(geometry={"max_refine_deg": 20.0}):
        narrow = planes._fit(centres, normals, 0.001)
    assert not narrow.refined  # the fresh answer, not the kept one
    assert planes._fit(centres, normals, 0.001) is wide


def test_a_large_group_is_fitted_afresh_with_the_same_answer() -> None:
    rng = np.random.default_rng(3)
    rows = planes._FITS_ROWS + 1
    centres = rng.normal(scale=0.02, size=(rows, 3)) * np.array([1.0, 1.0, 0.01])
    normals = np.tile([0.0, 0.0, 1.0], (rows, 1))
    planes._FITS.clear()
    a = planes._fit(centres, normals, 0.001)
    b = planes._fit(centres, normals, 0.001)
    assert len(planes._FITS) == 0  # not kept
    assert b is not a
    assert a.normal.tobytes() == b.normal.tobytes()
    assert a.residuals.tobytes() == b.residuals.tobytes()
    assert a.centre_offset == b.centre_offset
    fresh = planes._fit_anew(centres, normals, 0.001)
    assert fresh.normal.tobytes() == a.normal.tobytes()
