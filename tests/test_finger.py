"""The finger: built-in layouts, YAML layouts with located errors, coverage reports."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tactile_kb.errors import LayoutFileError, UsageError
from tactile_kb.touch.finger import Finger, builtin_finger, coverage, load_finger, load_layout


def test_builtin_layouts() -> None:
    four = builtin_finger("4")
    assert len(four.directions) == 4
    assert four.fired([(1.0, 0.0, 0.0)]) == (0,)
    assert four.fired([(0.0, 0.0, -1.0)]) == ()
    f33 = builtin_finger("33")
    assert len(f33.directions) == 33
    assert f33.nearest((0.0, 0.0, -1.0)) == 0
    # planes 30 degrees apart fire different sensors
    a = f33.nearest((1.0, 0.0, 0.0))
    b = f33.nearest((math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0))
    assert a != b
    assert builtin_finger("33", radius=0.01).radius == 0.01
    with pytest.raises(UsageError, match="unknown finger layout"):
        builtin_finger("7")


@given(st.floats(-math.pi / 2, math.radians(20.0)), st.floats(0.0, 2 * math.pi))
@settings(max_examples=60, deadline=None)
def test_every_direction_up_to_20_degrees_above_the_equator_fires_on_the_33_finger(
    elev: float, az: float
) -> None:
    d = (math.cos(elev) * math.cos(az), math.cos(elev) * math.sin(az), math.sin(elev))
    f = builtin_finger("33")
    fired = f.fired([d])
    assert fired
    # and every sensor that fires lies within its cone of d
    cos = f.matrix[list(fired)] @ np.asarray(d)
    assert (cos >= f.cos_cone - 1e-9).all()


GOOD = """\
name: hex
description: six sensors on the axes
radius: 0.004
cone_deg: 60
sensors:
  - [1, 0, 0]
  - [-2, 0, 0]
  - {elevation: 0, azimuth: 90}
  - {elevation: 0, azimuth: 270}
rings:
  - {elevation: -90, count: 1}
  - {elevation: 90, count: 1}
"""


def test_yaml_layout(tmp_path: Path) -> None:
    f = load_layout(GOOD)
    assert f.name == "hex"
    assert f.radius == 0.004
    assert np.allclose(f.matrix[1], [-1, 0, 0])  # normalised
    assert np.allclose(f.matrix[2], [0, 1, 0])
    assert np.allclose(f.matrix[4], [0, 0, -1])
    path = tmp_path / "hex.yaml"
    path.write_text(GOOD)
    assert load_finger(str(path)) == f
    assert load_finger(path, radius=0.002).radius == 0.002
    assert load_finger("4") == builtin_finger("4")
    assert load_finger(f) is f
    with pytest.raises(UsageError, match="unknown finger 'nine'"):
        load_finger("nine")


def test_octahedral_layout_covers_the_sphere_with_the_known_radius() -> None:
    # ground truth: the direction farthest from the six axes is a cube diagonal, at
    # arccos(1/sqrt(3)) = 54.7356 degrees
    f = load_layout(GOOD)
    c = coverage(f, max_elevation_deg=90.0)
    assert c.complete
    assert c.covering_radius_deg == pytest.approx(
        math.degrees(math.acos(1 / math.sqrt(3))), abs=0.3
    )
    narrow = f.model_copy(update={"cone_deg": 50.0})
    c2 = coverage(narrow, max_elevation_deg=90.0)
    assert not c2.complete
    assert len(c2.gaps) == 8  # one gap around each cube diagonal
    for elev, _az, _size in c2.gaps:
        assert abs(abs(elev) - math.degrees(math.asin(1 / math.sqrt(3)))) < 1.0


def test_coverage_of_the_builtin_layouts() -> None:
    c33 = coverage(builtin_finger("33"))
    assert c33.complete
    assert c33.max_error_deg <= builtin_finger("33").cone_deg
    assert 20.0 < c33.covering_radius_deg < 21.0
    # faces overhanging by up to 20° (an octahedron's lower faces: 19.47°) are felt at any
    # heading: ground truth, the equator sensors are 30° apart and their cones 25° wide, so a
    # direction e above the equator, 15° off two sensors, fires when cos e cos 15° >= cos 25°
    limit = math.degrees(math.acos(math.cos(math.radians(25)) / math.cos(math.radians(15))))
    assert 20.0 < limit < 20.5
    assert coverage(builtin_finger("33"), max_elevation_deg=20.0).complete
    up = coverage(builtin_finger("33"), max_elevation_deg=22.0)
    assert not up.complete
    assert all(20.0 <= elev <= 22.5 for elev, _az, _size in up.gaps)
    c4 = coverage(builtin_finger("4"))
    assert not c4.complete
    # the 4-sensor finger feels only near the equator: straight down is in the gap
    elev, _az, size = c4.gaps[0]
    assert elev < -40
    assert size > 40
    assert c4.uncovered_fraction > 0.3


def _error(text: str) -> LayoutFileError:
    with pytest.raises(LayoutFileError) as info:
        load_layout(text, file="f.yaml")
    return info.value


def test_located_errors() -> None:
    err = _error("name: x\ncone_deg: 95\nsensors:\n  - [1, 0]\n  - [0, 0, 0]\n")
    text = str(err)
    assert "f.yaml:2:11: cone_deg:" in text
    assert "f.yaml:4:5: sensors[0]" in text
    err = _error("name: x\ncone_deg: 30\nsensors:\n  - [0, 0, 0]\n  - [1, 0, 0]\n  - [2, 0, 0]\n")
    assert [str(p) for p in err.problems] == [
        "f.yaml:4:5: sensors[0]: a sensor direction needs a non-zero length",
        "f.yaml:6:5: sensors[2]: the same direction as sensors[1]",
    ]
    err = _error("name: x\ncone_deg: 30\ncolour: red\n")
    assert "f.yaml:3:1: colour: unknown field" in str(err)
    err = _error("name: x\ncone_deg: 30\n")
    assert "at least one sensor" in str(err)
    err = _error("name: x\nname: y\ncone_deg: 30\n")
    assert "duplicate key" in str(err)
    err = _error("- just a list\n")
    assert "mapping" in str(err)


def test_a_finger_validates_its_directions() -> None:
    with pytest.raises(ValueError, match="at least one sensor"):
        Finger(name="none", directions=(), cone_deg=10)


def test_every_problem_is_reported_at_once_with_its_column() -> None:
    text = (
        "name: x\n"  # 1
        "name: y\n"  # 2
        "cone_deg: 95\n"  # 3
        "sensors:\n"  # 4
        "  - [1, 0, .inf]\n"  # 5
        "  - {elevation: 0, azimut: 3}\n"  # 6
        "  - [1, 0]\n"  # 7
        "  - [1, true, 0]\n"  # 8
        "  - {elevation: 100, azimuth: 0}\n"  # 9
        "  - 7\n"  # 10
        "rings:\n"  # 11
        "  - {elevation: .nan, count: 2}\n"  # 12
    )
    err = _error(text)
    assert [str(p) for p in err.problems] == [
        "f.yaml:2:1: name: duplicate key 'name' (first at line 1)",
        "f.yaml:3:11: cone_deg: Input should be less than 90",
        "f.yaml:5:12: sensors[0][2]: z is not finite (inf)",
        "f.yaml:6:5: sensors[1]: a sensor given by angles needs azimuth",
        "f.yaml:6:20: sensors[1].azimut: unknown field "
        "(a sensor is [x, y, z] or {elevation: degrees, azimuth: degrees})",
        "f.yaml:7:5: sensors[2]: a sensor direction needs 3 numbers [x, y, z], got 2",
        "f.yaml:8:9: sensors[3][1]: y must be a number, got True",
        "f.yaml:9:17: sensors[4].elevation: elevation must lie in [-90, 90], got 100",
        "f.yaml:10:5: sensors[5]: a sensor is [x, y, z] or {elevation: degrees, azimuth: "
        "degrees}, got 7",
        "f.yaml:12:17: rings[0].elevation: Input should be a finite number",
    ]
    # no pydantic union noise: internal class names never reach the user
    for noise in ("_Angles", "_Ring", "instance of"):
        assert noise not in str(err)
    assert err.excerpt.splitlines()[:3] == ["1 | name: x", "2 | name: y", "  | ^"]


@pytest.mark.parametrize("bad", [".inf", "-.inf", ".nan"])
def test_non_finite_sensor_components_say_not_finite(bad: str) -> None:
    err = _error(f"name: x\ncone_deg: 30\nsensors:\n  - [{bad}, 0, 0]\n")
    assert len(err.problems) == 1
    assert str(err.problems[0]).startswith("f.yaml:4:6: sensors[0][0]: x is not finite")
    err = _error(f"name: x\ncone_deg: 30\nsensors:\n  - {{elevation: 0, azimuth: {bad}}}\n")
    assert str(err.problems[0]).startswith("f.yaml:4:29: sensors[0].azimuth: azimuth is not finite")


def test_a_layout_file_on_disk_names_itself(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text("name: x\ncone_deg: 30\nsensors:\n  - [0, 0, 0]\n")
    with pytest.raises(LayoutFileError) as info:
        load_finger(path)
    assert str(info.value) == f"{path}:4:5: sensors[0]: a sensor direction needs a non-zero length"


def test_align_deg_says_which_surfaces_a_layout_is_for() -> None:
    assert builtin_finger("4").align_deg == 10.0
    assert builtin_finger("33").align_deg is None
    f = load_layout("name: x\ncone_deg: 40\nalign_deg: 5\nrings:\n  - {elevation: 0, count: 4}\n")
    assert f.align_deg == 5.0
    err = _error("name: x\ncone_deg: 40\nalign_deg: 90\nsensors:\n  - [1, 0, 0]\n")
    assert [str(p) for p in err.problems] == [
        "f.yaml:3:12: align_deg: Input should be less than 90"
    ]
