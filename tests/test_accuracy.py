"""End to end: objects of every family, explored by the stepper and classified, get their label.

The true labels come from how each object is built (a square prism is a parallelepiped, a
three-sided pyramid a tetrahedron), never from the code under test. A representative subset of
``benchmarks/bench_accuracy.py``: exact contact positions and 0.5 mm contact-position noise.
"""

from __future__ import annotations

import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from tactile_kb import solids
from tactile_kb.pipeline import classify

NOISE = 0.0005


def _turned(mesh: trimesh.Trimesh, angle: float) -> trimesh.Trimesh:
    return solids.rotate_about_z(mesh, angle)


def _faces_to_touch(mesh: trimesh.Trimesh) -> int:
    """Distinct planes of a convex mesh except the one it rests on (z = 0)."""
    seen: list[tuple[tuple[float, ...], float]] = []
    for n, tri in zip(mesh.face_normals, mesh.triangles, strict=True):
        key = tuple(round(float(c), 6) for c in n)
        d = round(float(n @ tri[0]), 6)
        if (key, d) not in seen and not (n[2] < -0.999 and abs(d) < 1e-9):
            seen.append((key, d))
    return len(seen)


# (name, mesh, rules, true label)
EXACT = [
    ("cube 3 cm", _turned(solids.box(0.03, 0.03, 0.03), 15.0), "cube"),
    ("cube 25 cm", _turned(solids.box(0.25, 0.25, 0.25), 52.0), "cube"),
    (
        "box on its side",
        _turned(solids.rest_on_face(solids.box(0.04, 0.10, 0.025), (1.0, 0.0, 0.0)), 33.0),
        "rectangular_parallelepiped",
    ),
    (
        "oblique parallelepiped",
        _turned(
            solids.parallelepiped(
                0.12, 0.07, 0.05, angle_deg=70.0, shear_deg=8.0, shear_azimuth_deg=30.0
            ),
            20.0,
        ),
        "nonrectangular_parallelepiped",
    ),
    (
        "rhombohedron",
        _turned(solids.rhombohedron(0.06, 76.0), 10.0),
        "nonrectangular_parallelepiped",
    ),
    ("tetrahedron", _turned(solids.tetrahedron(0.05), 40.0), "tetrahedron"),
    ("octahedron at any turn", _turned(solids.octahedron(0.08), 20.0), "octahedron"),
    ("triangular prism", _turned(solids.prism(3, 0.03, 0.1), 7.0), "prism"),
    ("pentagonal prism", _turned(solids.prism(5, 0.04, 0.07), 11.0), "prism"),
    ("octagonal prism", _turned(solids.prism(8, 0.05, 0.04), 3.0), "prism"),
    ("square prism", _turned(solids.prism(4, 0.04, 0.12), 25.0), "rectangular_parallelepiped"),
    ("three-sided pyramid", _turned(solids.pyramid(3, 0.04, 0.06), 50.0), "tetrahedron"),
    ("square pyramid", _turned(solids.pyramid(4, 0.05, 0.08), 17.0), "pyramid"),
    ("hexagonal pyramid", _turned(solids.pyramid(6, 0.04, 0.05), 5.0), "pyramid"),
    ("square frustum", _turned(solids.frustum(4, 0.06, 0.03, 0.05), 5.0), "frustum"),
    ("hexagonal frustum", _turned(solids.frustum(6, 0.05, 0.03, 0.05), 12.0), "frustum"),
    ("cylinder", solids.cylinder(0.03, 0.06), "curved"),
    ("sphere", solids.sphere(0.03), "curved"),
]


@pytest.mark.parametrize(("name", "mesh", "label"), EXACT, ids=[c[0] for c in EXACT])
def test_every_family_gets_its_label(name: str, mesh: trimesh.Trimesh, label: str) -> None:
    result = classify(mesh, rules="polyhedra", seed=0)
    assert result.decision.label == label, f"{name}: {result.decision.explanation}"


NOISY = [
    ("cube 3 cm", _turned(solids.box(0.03, 0.03, 0.03), 15.0), "cube", 0),
    ("cube 3 cm", _turned(solids.box(0.03, 0.03, 0.03), 15.0), "cube", 1),
    ("box", _turned(solids.box(0.16, 0.08, 0.05), 64.0), "rectangular_parallelepiped", 2),
    (
        "rhombohedron",
        _turned(solids.rhombohedron(0.08, 78.0), 200.0),
        "nonrectangular_parallelepiped",
        3,
    ),
    ("octahedron", _turned(solids.octahedron(0.12), 20.0), "octahedron", 0),
    ("pentagonal prism", _turned(solids.prism(5, 0.04, 0.07), 11.0), "prism", 1),
    ("square pyramid", _turned(solids.pyramid(4, 0.05, 0.08), 17.0), "pyramid", 2),
    ("hexagonal frustum", _turned(solids.frustum(6, 0.05, 0.03, 0.05), 12.0), "frustum", 3),
]


@pytest.mark.parametrize(
    ("name", "mesh", "label", "seed"), NOISY, ids=[f"{c[0]}-{c[3]}" for c in NOISY]
)
def test_labels_hold_with_half_a_millimetre_of_noise(
    name: str, mesh: trimesh.Trimesh, label: str, seed: int
) -> None:
    result = classify(mesh, rules="polyhedra", noise=NOISE, seed=seed)
    assert result.decision.label == label, f"{name}: {result.decision.explanation}"


# Faces turned between two equator sensors of the 33-sensor finger: one layer fires a sensor,
# the next the mean of it and its neighbour, so two contacts inside one flat face read 15°
# apart. Their tip centres lie on one plane: flat faces, whatever the sensors say.
BETWEEN_SENSORS = [
    ("cube 89 mm", _turned(solids.box(0.0891, 0.0891, 0.0891), 310.9), "cube"),
    ("octagonal prism", _turned(solids.prism(8, 0.0442, 0.0218), 132.7), "prism"),
    ("small hexagonal pyramid", _turned(solids.pyramid(6, 0.0152, 0.02), 52.8), "pyramid"),
]


@pytest.mark.parametrize("noise", [0.0, NOISE])
@pytest.mark.parametrize(
    ("name", "mesh", "label"), BETWEEN_SENSORS, ids=[c[0] for c in BETWEEN_SENSORS]
)
def test_a_face_between_two_sensors_is_not_curved(
    name: str, mesh: trimesh.Trimesh, label: str, noise: float
) -> None:
    result = classify(mesh, rules="polyhedra", noise=noise, seed=0)
    assert result.decision.label == label, f"{name}: {result.decision.explanation}"


@pytest.mark.parametrize(("edge", "angle"), [(0.0307, 335.0), (0.051, 229.9), (0.031, 20.0)])
def test_a_small_octahedron_is_an_octahedron(edge: float, angle: float) -> None:
    # a 3 cm octahedron's lower faces are small; touches of the edges and vertices beside
    # them land in their sensor clusters, and must neither tilt them nor make a neighbour
    # look concave
    result = classify(_turned(solids.octahedron(edge), angle), rules="polyhedra", seed=0)
    assert result.decision.label == "octahedron", result.decision.explanation
    assert result.planes == 8


@pytest.mark.parametrize(
    ("radius", "height", "noise", "seed"),
    [(0.0127, 0.0648, 0.0, 0), (0.0127, 0.0648, NOISE, 0), (0.0123, 0.1357, NOISE, 1)],
)
def test_a_small_cylinder_is_curved(radius: float, height: float, noise: float, seed: int) -> None:
    # a 1.3 cm cylinder's faces, as the 5 mm tip sees them, are too narrow to have an
    # inside: its sensors spread near their edges, and the centres cannot rule the turn out
    result = classify(solids.cylinder(radius, height), rules="polyhedra", noise=noise, seed=seed)
    assert result.decision.label == "curved", result.decision.explanation


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_small_cube_of_fig5_is_a_cube_with_noise(seed: int) -> None:
    # CUBE11, the 3 cm cube of the paper's Fig. 5, with the paper's rules
    name, mesh, label = next(o for o in solids.fig5_objects() if o[0] == "CUBE11")
    result = classify(mesh, rules="parallelepipeds", noise=NOISE, seed=seed)
    assert result.decision.answer == "OBJECT IS A CUBE", name
    assert result.decision.label == label


@given(
    size=st.floats(0.02, 0.18),
    ratio=st.sampled_from([1.0, 1.6]),
    angle=st.floats(0.0, 360.0),
    noisy=st.booleans(),
)
@settings(max_examples=6, deadline=None, derandomize=True)
def test_hexahedra_at_any_turn_are_named_with_at_most_two_touches_per_face(
    size: float, ratio: float, angle: float, noisy: bool
) -> None:
    height = size * ratio  # a box's edges differ by 60 %, well beyond equal_edges' 15 %
    mesh = _turned(solids.box(size, size, height), angle)
    result = classify(mesh, rules="polyhedra", noise=NOISE if noisy else 0.0, seed=1)
    want = "cube" if ratio == 1.0 else "rectangular_parallelepiped"
    assert result.decision.label == want
    assert result.record.touches <= 2 * _faces_to_touch(mesh)


@given(edge=st.floats(0.06, 0.25), angle=st.floats(0.0, 120.0))
@settings(max_examples=4, deadline=None, derandomize=True)
def test_an_octahedron_is_felt_whole_at_any_turn(edge: float, angle: float) -> None:
    # its lower faces overhang by 19.47°: the 33-sensor finger feels them at every heading
    mesh = _turned(solids.octahedron(edge), angle)
    result = classify(mesh, rules="polyhedra", seed=0)
    assert result.decision.label == "octahedron"
    assert result.planes == 8


@pytest.mark.parametrize("seed", [0, 1, 5, 7])
def test_a_cube_is_classified_right_despite_sensor_drop_outs(seed: int) -> None:
    from tactile_kb.touch.stepper import StepperExplorer

    cube = _turned(solids.box(0.05, 0.05, 0.05), 20.0)
    result = classify(cube, explorer=StepperExplorer(dropout=0.05), seed=seed)
    assert result.decision.label == "cube"
    assert result.record.complete
