"""rules/polyhedra.yaml: its classes partition the consistent assignments, and the features of
real (sampled) solids give the right label."""

from __future__ import annotations

import itertools

import pytest
import trimesh

from tactile_kb import solids
from tactile_kb.features.builtin import check_binding, get_feature
from tactile_kb.geometry.model import ObjectModel, build_model
from tactile_kb.kb.expr import evaluate
from tactile_kb.kb.rules import RuleSet, load_rules
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

RULES = load_rules("polyhedra")
FINGER = builtin_finger("33")


def _label(rules: RuleSet, model: ObjectModel) -> str:
    values = {}
    for p in rules.propositions:
        assert p.feature is not None
        values[p.id] = get_feature(p.feature.name).fn(model, **p.feature.params)
    assert all(evaluate(c.expr, values) for c in rules.connections), values
    hits = [c.id for c in rules.classes if evaluate(c.expr, values)]
    assert len(hits) <= 1, (hits, values)
    return hits[0] if hits else rules.otherwise_id


def test_labels_and_bindings() -> None:
    ids = {c.id for c in RULES.classes}
    assert {
        "cube",
        "rectangular_parallelepiped",
        "nonrectangular_parallelepiped",
        "tetrahedron",
        "octahedron",
        "prism",
        "pyramid",
        "frustum",
        "curved",
    } <= ids
    assert RULES.otherwise_id == "unknown"
    for p in RULES.propositions:
        assert p.feature is not None
        assert check_binding(p.feature.name, p.feature.params) is None


def test_classes_partition_the_consistent_assignments() -> None:
    """No dead class, no overlap, no gap: by enumerating the whole truth table."""
    ids = RULES.ids
    counts = dict.fromkeys((c.id for c in RULES.classes), 0)
    for bits in itertools.product((False, True), repeat=len(ids)):
        values = dict(zip(ids, bits, strict=True))
        if not all(evaluate(c.expr, values) for c in RULES.connections):
            continue
        hits = [c.id for c in RULES.classes if evaluate(c.expr, values)]
        assert len(hits) == 1, (hits, values)
        counts[hits[0]] += 1
    assert all(n > 0 for n in counts.values()), counts


SOLIDS: list[tuple[str, trimesh.Trimesh, str]] = [
    ("cube", solids.box(0.09, 0.09, 0.09), "cube"),
    ("box", solids.box(0.15, 0.08, 0.05), "rectangular_parallelepiped"),
    (
        "oblique",
        solids.parallelepiped(0.12, 0.09, 0.06, angle_deg=62, shear_deg=8),
        "nonrectangular_parallelepiped",
    ),
    ("rhombohedron", solids.rhombohedron(0.1), "nonrectangular_parallelepiped"),
    ("tetrahedron", solids.tetrahedron(0.12), "tetrahedron"),
    ("octahedron", solids.fig5_objects()[0][1], "octahedron"),
    ("prism3", solids.prism(3, 0.06, 0.15), "prism"),
    ("prism6", solids.prism(6, 0.06, 0.1), "prism"),
    ("pyramid4", solids.pyramid(4, 0.07, 0.08), "pyramid"),
    ("pyramid6", solids.pyramid(6, 0.07, 0.05), "pyramid"),
    ("frustum4", solids.frustum(4, 0.08, 0.04, 0.05), "frustum"),
    ("cylinder", solids.cylinder(0.05, 0.1), "curved"),
    ("sphere", solids.sphere(0.06, subdivisions=2), "curved"),
]


@pytest.mark.parametrize(("name", "mesh", "label"), SOLIDS, ids=[s[0] for s in SOLIDS])
@pytest.mark.parametrize("quantise", [False, True])
def test_sampled_solids_get_their_label(
    name: str, mesh: trimesh.Trimesh, label: str, quantise: bool
) -> None:
    turned = mesh if name == "octahedron" else solids.rotate_about_z(mesh, 23.0)
    noise = 0.0005 if quantise else 0.0
    if label == "curved":
        rec = sample_record(turned, FINGER, total=300, quantise=quantise, noise=noise, seed=11)
    else:
        rec = sample_record(turned, FINGER, per_face=16, quantise=quantise, noise=noise, seed=11)
    assert _label(RULES, build_model(rec)) == label


def test_fig5_objects_by_the_polyhedra_rules() -> None:
    names = {
        "cube": "cube",
        "rectangular_parallelepiped": "rectangular_parallelepiped",
        "nonrectangular_parallelepiped": "nonrectangular_parallelepiped",
    }
    for name, mesh, expected in solids.fig5_objects():
        rec = sample_record(mesh, FINGER, per_face=16, seed=5)
        got = _label(RULES, build_model(rec))
        if expected == "not_hexahedron":
            assert got == ("octahedron" if name == "OCTA" else "tetrahedron"), name
        else:
            assert got == names[expected], name
