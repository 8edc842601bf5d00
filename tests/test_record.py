"""Exploration records: eq. (6) planes, JSON round trip, located load errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tactile_kb.errors import RecordError
from tactile_kb.record import Contact, ExplorationRecord, Layer

finite = st.floats(-1.0, 1.0, allow_nan=False)


@given(st.tuples(finite, finite, finite), st.tuples(finite, finite, finite), finite)
def test_contact_plane_is_equation_6(
    r1: tuple[float, float, float], d: tuple[float, float, float], s: float
) -> None:
    r0 = np.asarray(d)
    if np.linalg.norm(r0) < 1e-3:
        r0 = np.array([0.0, 0.0, 1.0])
    r0 = r0 / np.linalg.norm(r0)
    c = Contact(step=0, centre=r1, sensors=(0,), direction=tuple(r0), point=r1)
    # any point r with (r − r1)·r0 = 0 lies on the plane
    t = np.cross(r0, [1.0, 0.0, 0.0]) if abs(r0[0]) < 0.9 else np.cross(r0, [0.0, 1.0, 0.0])
    r = np.asarray(r1) + s * t
    assert abs(c.plane.distance(tuple(r))) < 1e-9
    # the normal points away from the object, against the sensor direction
    assert np.allclose(c.plane.normal, -r0)


def _record() -> ExplorationRecord:
    contacts = [
        Contact(
            step=i,
            centre=(0.01 * i, -0.015, 0.01),
            sensors=(3, 4),
            sensor=3,
            direction=(0.0, 1.0, 0.0),
            point=(0.01 * i, -0.01, 0.01),
            kind=k,
            phase="layer",
            layer=0,
        )
        for i, k in enumerate(["touch", "slide", "slide", "touch"])
    ]
    return ExplorationRecord(
        object="cube.stl",
        explorer="stepper",
        finger="4",
        tip_radius=0.005,
        sensor_directions=[(1.0, 0.0, 0.0)],
        seed=7,
        params={"l1": 0.01},
        contacts=contacts,
        path=[(0.0, 0.0, 0.0), (3.0, 4.0, 0.0), (3.0, 4.0, 1.0)],
        layers=[Layer(index=0, z=0.01, contour=[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)], closed=True)],
        contacts_per_phase={"layer": 4},
    )


def test_json_round_trip(tmp_path: Path) -> None:
    rec = _record()
    p = tmp_path / "r.json"
    rec.save(p)
    assert ExplorationRecord.load(p) == rec
    assert not (tmp_path / "r.json.tmp").exists()


def test_touches_and_path_length() -> None:
    rec = _record()
    assert rec.touches == 2
    assert rec.path_length == pytest.approx(6.0)


FACE = "the face facing (+1.0, +0.0, +0.0) touched at one height"
TOP = "the top facing (+0.0, +0.2, +1.0) touched along one line"


@pytest.mark.parametrize(
    ("ending", "unreachable", "budget", "expected"),
    [
        ("closed", [], "", ""),
        ("", [], "", ""),
        (
            "unreachable",
            [],
            "",
            "what stayed open could not be reached after 2 touches; still open: unknown",
        ),
        (
            "unreachable",
            ["open towards +z"],
            "",
            "what stayed open could not be reached after 2 touches; still open: open towards +z",
        ),
        (  # each side of the top and the level approach are the same items again
            "budget",
            [FACE, FACE + ", approached level", TOP + " (+ side)", TOP + " (- side)"],
            "",  # a record written before the budget was named
            f"the exploration's budget ran out after 2 touches; still open: {FACE}; {TOP}",
        ),
        (
            "budget",
            ["open towards +z"],
            "the completion's budget of 1.2 m of path",
            "the completion's budget of 1.2 m of path ran out after 2 touches; still open: "
            "open towards +z",
        ),
        (  # six items: four named, two counted
            "budget",
            [
                FACE,
                FACE + ", approached level",
                "a blind contact at (+15.0, +6.2, +10.0) mm",
                "the planes close far towards (+0.0, +1.0, +0.0)",
                "the planes close far towards (+0.0, +1.0, +0.0), straight",
                TOP + " (- side)",
                "the face facing (+0.0, -1.0, +0.0) not touched near the table",
                "open towards (+0.6, +0.8, +0.0)",
            ],
            "the motion budget of 6000 motions",
            "the motion budget of 6000 motions ran out after 2 touches; still open: "
            f"{FACE}; a blind contact at (+15.0, +6.2, +10.0) mm; the planes close far towards "
            f"(+0.0, +1.0, +0.0); {TOP}; and 2 more (the record's `unreachable` lists them all)",
        ),
    ],
)
def test_the_open_ending_names_each_item_once(
    ending: str, unreachable: list[str], budget: str, expected: str
) -> None:
    rec = _record().model_copy(
        update={"ending": ending, "unreachable": unreachable, "budget": budget}
    )
    assert rec.open_ending == expected
    assert rec.unreachable == unreachable  # the record keeps every item and approach


def test_bad_json_is_located() -> None:
    with pytest.raises(RecordError, match=r"^r\.json:1:2: not JSON"):
        ExplorationRecord.from_json("{x", file="r.json")


def test_bad_field_is_named() -> None:
    with pytest.raises(RecordError, match=r"^r\.json: contacts\.0\.centre"):
        ExplorationRecord.from_json(
            '{"contacts": [{"step": 0, "centre": [1, 2], "sensors": [], '
            '"direction": [0, 0, 1], "point": [0, 0, 0]}]}',
            file="r.json",
        )


def test_unknown_version_rejected() -> None:
    with pytest.raises(RecordError, match="version 9"):
        ExplorationRecord.from_json('{"version": 9}', file="r.json")


def test_missing_file() -> None:
    with pytest.raises(RecordError, match="cannot read"):
        ExplorationRecord.load("/nonexistent/r.json")


def test_save_failure_is_a_record_error_and_leaves_nothing(tmp_path: Path) -> None:
    with pytest.raises(RecordError, match=r"^/proc/nope\.json: cannot write"):
        _record().save("/proc/nope.json")
    assert not Path("/proc/nope.json.tmp").exists()
    with pytest.raises(RecordError, match="not a regular file"):
        _record().save(tmp_path)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{}", "r.json: not an exploration record (it names no finger and tip radius)"),
        ("[1, 2]", "r.json: not an exploration record (expected a JSON object)"),
    ],
)
def test_json_that_is_no_record_is_refused(text: str, message: str) -> None:
    with pytest.raises(RecordError) as info:
        ExplorationRecord.from_json(text, file="r.json")
    assert str(info.value) == message
