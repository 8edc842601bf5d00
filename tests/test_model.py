"""The model: full chain from a record, partial records, non-convex objects, saved records."""

from __future__ import annotations

import numpy as np

from tactile_kb import solids
from tactile_kb.geometry.model import NOISY_MERGE_FRACTION, build_model
from tactile_kb.geometry.polyhedron import DEFAULT_MERGE_FRACTION
from tactile_kb.record import ExplorationRecord
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_layers, sample_record

F33 = builtin_finger("33")


def test_model_of_a_saved_and_loaded_record_is_the_same(tmp_path: object) -> None:
    rec = sample_record(solids.tetrahedron(0.1), F33, per_face=10, seed=8)
    back = ExplorationRecord.from_json(rec.to_json())
    a, b = build_model(rec), build_model(back)
    assert a.polyhedron is not None
    assert b.polyhedron is not None
    assert np.allclose(a.polyhedron.vertices, b.polyhedron.vertices)
    assert a.convex
    assert len(a.faces) == 4


def test_empty_and_partial_records_give_no_polyhedron() -> None:
    empty = build_model(ExplorationRecord())
    assert empty.polyhedron is None
    assert "do not bound" in empty.open_reason
    assert len(empty.faces) == 1
    assert empty.faces[0].source == "table"
    mesh = solids.box(0.1, 0.1, 0.1)
    rec = sample_record(mesh, F33, per_face=6, quantise=False, noise=0.0)
    # leave out every contact on the face looking along +x
    keep = [i for i, c in enumerate(rec.contacts) if c.direction[0] > -0.5]
    partial = rec.model_copy(update={"contacts": [rec.contacts[i] for i in keep]})
    m = build_model(partial)
    assert m.polyhedron is None
    assert m.open_directions[0] == (1.0, 0.0, 0.0)


def test_non_convex_object_keeps_its_convex_envelope_and_layers() -> None:
    mesh = solids.l_shape(0.1, 0.08, 0.03, 0.04)
    rec = sample_record(mesh, F33, per_face=10, quantise=False, noise=0.0, seed=3)
    m = build_model(rec)
    assert not m.convex
    assert sum(not s for s in m.supporting) == 2  # the two inner sides
    assert m.polyhedron is not None
    assert np.isclose(m.polyhedron.volume, 0.1 * 0.08 * 0.04)  # the bounding box
    layered = build_model(sample_layers(mesh, builtin_finger("4"), [0.01, 0.03]))
    assert len(layered.layers) == 2
    assert len(layered.distinct_planes()) == 6


def test_derived_values_are_computed_once_per_model() -> None:
    import dataclasses

    from tactile_kb.geometry.model import build_model, derived
    from tactile_kb.solids import box
    from tactile_kb.touch.finger import builtin_finger
    from tactile_kb.touch.synthetic import sample_record

    model = build_model(sample_record(box(0.08, 0.08, 0.08), builtin_finger("33"), seed=1))
    calls: list[int] = []

    def compute() -> int:
        calls.append(1)
        return 42

    assert derived(model, ("test", "x"), compute) == 42
    assert derived(model, ("test", "x"), compute) == 42
    assert len(calls) == 1
    fresh = dataclasses.replace(model)
    assert derived(fresh, ("test", "x"), compute) == 42
    assert len(calls) == 2


def test_noisy_octahedra_keep_six_vertices_more_often() -> None:
    # four noisy planes meet near, not at, each vertex: they merge at the noisy tolerance
    merged = split = 0
    for seed in range(10):
        rec = sample_record(solids.octahedron(0.08), F33, per_face=10, noise=0.0005, seed=seed)
        model = build_model(rec)
        assert model.polyhedron is not None
        tol = model.options["merge_tol"]
        # the octahedron's smallest extent (between parallel faces) is 0.08·√(2/3)
        assert tol >= NOISY_MERGE_FRACTION * 0.08 * (2 / 3) ** 0.5 * 0.95
        merged += len(model.polyhedron.vertices) == 6
        at_exact = build_model(
            rec, merge_fraction=DEFAULT_MERGE_FRACTION + 1e-9, collapse_sigmas=None
        ).polyhedron
        assert at_exact is not None
        split += len(at_exact.vertices) == 6
    assert merged >= 7
    assert merged > split
    exact = build_model(sample_record(solids.octahedron(0.04), F33, per_face=10, noise=0.0))
    assert exact.options["merge_tol"] is None
    assert exact.polyhedron is not None
    assert len(exact.polyhedron.vertices) == 6


def test_noisy_merge_keeps_the_short_edges_of_a_thin_prism() -> None:
    mesh = solids.prism(7, 0.0133, 0.29)  # edges of 1.15 cm on an object 29 cm tall
    rec = sample_record(mesh, F33, per_face=10, noise=0.0005, seed=0)
    model = build_model(rec)
    assert model.options["merge_tol"] < 0.8 * 2 * 0.0133 * np.sin(np.pi / 7)
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 9


def test_assumed_top_closes_a_model_open_only_upwards() -> None:
    rec = sample_record(solids.box(0.08, 0.06, 0.05), builtin_finger("4"), noise=0.0, seed=3)
    touched_top = max(c.point[2] for c in rec.contacts)
    assert build_model(rec).polyhedron is None  # the default: open, and says so
    model = build_model(rec, assume_top=True)
    assert model.polyhedron is not None
    assert model.assumed_top is not None
    assert model.faces[-1].source == "assumed"
    assert model.faces[-1].n_contacts == 0
    # the lid is at the highest touched point: the object is at least that tall (5 cm)
    assert touched_top - 1e-9 <= model.assumed_top <= 0.05 + 1e-9
    extent = np.ptp(model.polyhedron.vertices, axis=0)
    assert np.allclose(extent[:2], [0.08, 0.06], atol=1e-3)  # the true footprint
    assert abs(extent[2] - model.assumed_top) < 1e-6
    assert len(model.faces) == 6
    assert model.convex


def test_assumed_top_only_when_the_top_alone_is_open() -> None:
    # a box touched on three sides only: open sideways too, so no lid is assumed
    rec = sample_record(solids.box(0.08, 0.06, 0.05), builtin_finger("4"), noise=0.0, seed=3)
    keep = [c for c in rec.contacts if c.direction[0] > -0.5]  # drop the −x side
    partial = rec.model_copy(update={"contacts": keep})
    model = build_model(partial, assume_top=True)
    assert model.polyhedron is None
    assert model.assumed_top is None
    assert model.open_directions
    assert model.open_directions != [(0.0, 0.0, 1.0)]


def test_assumed_reach_closes_a_side_no_face_was_touched_on() -> None:
    # a box whose +x side was never touched: the model is open that way; closed by an assumed
    # face through the farthest touched point, the object reaches at least that far
    rec = sample_record(solids.box(0.08, 0.06, 0.05), F33, per_face=8, noise=0.0, seed=3)
    keep = [c for c in rec.contacts if c.direction[0] > -0.5]  # not the +x side (sensed −x)
    partial = rec.model_copy(update={"contacts": keep})
    assert build_model(partial).polyhedron is None
    assert build_model(partial, assume_top=True).polyhedron is None  # not only upwards
    model = build_model(partial, assume_reach=True)
    assert model.polyhedron is not None
    assert len(model.assumed_reach) == 1
    assert np.allclose(model.assumed_reach[0], (1.0, 0.0, 0.0), atol=1e-6)
    assumed = [f for f in model.faces if f.source == "assumed"]
    assert len(assumed) == 1
    assert assumed[0].n_contacts == 0
    reach = max(c.point[0] for c in keep)
    assert assumed[0].offset == reach  # the farthest touched point that way
    assert reach <= 0.04 + 1e-9  # the box's own +x face is at 4 cm: never beyond the object
    x0, x1 = model.polyhedron.vertices[:, 0].min(), model.polyhedron.vertices[:, 0].max()
    assert abs(x0 + 0.04) < 1e-6
    assert abs(x1 - reach) < 1e-6
    # nothing to assume on a closed model
    whole = build_model(rec, assume_reach=True)
    assert whole.assumed_reach == ()
    assert all(f.source != "assumed" for f in whole.faces)


def test_features_that_need_the_true_extent_are_not_established_on_an_assumed_reach() -> None:
    from tactile_kb.features.builtin import congruent_faces, equal_edges

    rec = sample_record(solids.box(0.06, 0.06, 0.06), F33, per_face=8, noise=0.0, seed=3)
    assert equal_edges(build_model(rec))  # a cube touched on every side
    keep = [c for c in rec.contacts if c.direction[1] > -0.5]  # not on the +y side
    model = build_model(rec.model_copy(update={"contacts": keep}), assume_reach=True)
    assert model.assumed_reach
    assert not equal_edges(model)
    assert not congruent_faces(model)


def test_assumed_reach_gives_up_when_the_planes_do_not_close() -> None:
    # two faces touched only: more open directions than MAX_ASSUMED allows, or none closes
    rec = sample_record(solids.box(0.08, 0.06, 0.05), F33, per_face=8, noise=0.0, seed=3)
    keep = [c for c in rec.contacts if c.direction[0] > 0.5]  # the −x side alone
    model = build_model(rec.model_copy(update={"contacts": keep}), assume_reach=True)
    assert model.polyhedron is None
    assert model.assumed_reach == ()
    assert model.open_reason


def test_noisy_small_octahedra_collapse_their_split_vertices() -> None:
    # 3–5 cm: four noisy planes at a vertex leave 1–4 mm edges, beyond the merge tolerance
    whole = kept_split = 0
    for seed, edge in enumerate([0.03, 0.035, 0.04, 0.045, 0.05] * 2):
        rec = sample_record(solids.octahedron(edge), F33, per_face=10, noise=0.0005, seed=seed)
        model = build_model(rec)
        assert model.polyhedron is not None
        p = model.polyhedron
        assert len(p.vertices) - len(p.edges) + len(p.faces) == 2
        if (len(p.vertices), len(p.edges), len(p.faces)) == (6, 12, 8):
            whole += 1
            assert all(len(f) == 3 for f in p.faces)
            assert np.allclose(p.edge_lengths(), edge, rtol=0.1)
        plain = build_model(rec, collapse_sigmas=None).polyhedron
        assert plain is not None
        kept_split += len(plain.vertices) > 6
    assert whole >= 9
    assert kept_split >= 3  # the records do split vertices the merge alone leaves


def test_exact_records_are_not_collapsed() -> None:
    for mesh in (solids.octahedron(0.03), solids.frustum(6, 0.015, 0.006, 0.02)):
        rec = sample_record(mesh, F33, per_face=10, noise=0.0, seed=1)
        a = build_model(rec).polyhedron
        b = build_model(rec, collapse_sigmas=None).polyhedron
        assert a is not None
        assert b is not None
        assert np.array_equal(a.vertices, b.vertices)
        assert a.faces == b.faces


def test_noisy_thin_frustum_keeps_its_short_top_edges() -> None:
    mesh = solids.frustum(6, 0.02, 0.008, 0.03)  # top edges of 8 mm
    rec = sample_record(mesh, F33, per_face=10, noise=0.0005, seed=2)
    model = build_model(rec)
    assert model.polyhedron is not None
    assert len(model.polyhedron.faces) == 8
    assert len(model.polyhedron.vertices) == 12
