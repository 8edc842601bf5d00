"""The polyhedron cache and the batched arithmetic give what a fresh, one-at-a-time build gives.

:func:`polyhedron_from_planes` keeps the polyhedra of recent plane sets, and builds faces,
vertex least squares and face widths in stacked batches. Each test builds the same thing the
plain way (caches emptied, one item at a time, or scipy's graph search) and asks for equal
bits, on planes of constructed solids and on noisy plane sets.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components

from tactile_kb import solids
from tactile_kb.completion import ModelCompleter
from tactile_kb.errors import GeometryError, OpenModelError
from tactile_kb.geometry import polyhedron as ph
from tactile_kb.geometry.model import build_model
from tactile_kb.geometry.planes import nearest_points
from tactile_kb.touch.finger import builtin_finger
from tactile_kb.touch.synthetic import sample_record

FIELDS = (
    "vertices",
    "faces",
    "normals",
    "offsets",
    "edges",
    "edge_faces",
    "dihedral_deg",
    "volume",
    "centroid",
    "face_areas",
    "face_centroids",
    "plane_index",
)


def _planes(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    n = mesh.face_normals
    return n, np.einsum("ij,ij->i", n, mesh.triangles_center)


def _noisy(mesh: trimesh.Trimesh, seed: int, copies: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Each plane of ``mesh`` ``copies`` times, tilted by ~1° and shifted by ~0.3 mm."""
    n, d = _planes(mesh)
    rng = np.random.default_rng(seed)
    n = np.repeat(n, copies, axis=0) + rng.normal(scale=0.02, size=(copies * len(n), 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    return n, np.repeat(d, copies) + rng.normal(scale=3e-4, size=len(n))


def _clear() -> None:
    ph._BUILT.clear()
    ph._CENTRES.clear()


def _same(a: ph.Polyhedron, b: ph.Polyhedron) -> None:
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape, name
            assert np.array_equal(x, y), name
        else:
            assert x == y, name


SOLIDS = [
    solids.box(0.1, 0.06, 0.04),
    solids.tetrahedron(0.1),
    solids.octahedron(0.1),
    solids.prism(7, 0.05, 0.1),
    solids.frustum(5, 0.06, 0.03, 0.04),
    trimesh.creation.icosphere(subdivisions=1, radius=0.05),
]


@pytest.mark.parametrize("mesh", SOLIDS)
@pytest.mark.parametrize("noisy", [False, True])
def test_cached_polyhedron_equals_a_fresh_build(mesh: trimesh.Trimesh, noisy: bool) -> None:
    n, d = _noisy(mesh, 1) if noisy else _planes(mesh)
    hint = np.asarray(mesh.centroid) + 1e-4
    for kwargs in ({}, {"interior": hint}, {"tol": 0.002}, {"merge_fraction": 0.05}):
        _clear()
        fresh = ph.polyhedron_from_planes(n, d, **kwargs)
        again = ph.polyhedron_from_planes(n, d, **kwargs)
        assert again is fresh  # from the cache
        _clear()
        _same(ph.polyhedron_from_planes(n, d, **kwargs), fresh)
        # the planes in another order are another key, and give the same solid (noisy
        # near-duplicates merge a little differently in another order)
        flip = np.arange(len(n))[::-1]
        other = ph.polyhedron_from_planes(n[flip], d[flip], **kwargs)
        assert other is not fresh
        assert other.volume == pytest.approx(fresh.volume, rel=0.01 if noisy else 1e-9)


def test_cached_polyhedra_are_read_only() -> None:
    n, d = _planes(solids.box(0.1, 0.06, 0.04))
    poly = ph.polyhedron_from_planes(n, d)
    with pytest.raises(ValueError, match="read-only"):
        poly.vertices[0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        poly.normals[0] *= -1.0


def test_bound_is_tested_on_every_call() -> None:
    """The cache keeps Qhull's vertices, so a bound too tight for them raises again."""
    box = solids.box(0.1, 0.06, 0.04)
    n, d = _planes(box)
    centre = np.asarray(box.centroid)
    _clear()
    ph.polyhedron_from_planes(n, d)  # cached without a bound
    with pytest.raises(OpenModelError, match="close only far") as err:
        ph.polyhedron_from_planes(n, d, bound=(centre, 0.02))
    assert err.value.open_directions  # the directions of the far vertices
    # a bound wide enough: the same cached polyhedron
    assert ph.polyhedron_from_planes(n, d, bound=(centre, 0.2)) is ph.polyhedron_from_planes(n, d)


def test_errors_are_cached_and_raised_fresh() -> None:
    n = np.vstack([np.eye(3), -np.eye(3)[:2]])  # nothing below: open towards −z
    d = np.full(5, 0.05)
    _clear()
    raised = []
    for _ in range(2):
        with pytest.raises(OpenModelError, match="do not bound a region") as err:
            ph.polyhedron_from_planes(n, d)
        assert err.value.open_directions == [(0.0, 0.0, -1.0)]
        raised.append(err.value)
    assert raised[0] is not raised[1]
    # empty: two opposite half-spaces that do not meet
    n2 = np.vstack([np.eye(3), -np.eye(3)])
    d2 = np.array([0.05, 0.05, 0.05, 0.05, 0.05, -0.06])
    for _ in range(2):
        with pytest.raises(GeometryError, match="enclose no region"):
            ph.polyhedron_from_planes(n2, d2)


def test_components_match_scipy() -> None:
    rng = np.random.default_rng(3)
    for size in (1, 2, 5, 12, 40):
        for density in (0.0, 0.05, 0.2, 0.6):
            a = rng.random((size, size)) < density
            a = a | a.T
            np.fill_diagonal(a, True)
            _, truth = connected_components(csr_array(a), directed=False)
            assert np.array_equal(ph._components(a), truth)
    # a long chain needs more rounds than the propagation takes: scipy finishes it
    chain = np.eye(30, dtype=bool) | np.eye(30, k=1, dtype=bool) | np.eye(30, k=-1, dtype=bool)
    perm = rng.permutation(30)
    chain = chain[perm][:, perm]
    _, truth = connected_components(csr_array(chain), directed=False)
    assert np.array_equal(ph._components(chain), truth)


@pytest.mark.parametrize("mesh", SOLIDS)
def test_face_widths_in_batches_equal_one_at_a_time(mesh: trimesh.Trimesh) -> None:
    n, d = _noisy(mesh, 2)
    _clear()
    poly = ph.polyhedron_from_planes(n, d)
    for f in range(len(poly.faces)):
        assert ph.face_width(poly, f) == ph._face_width(poly, f)
    box = ph.polyhedron_from_planes(*_planes(solids.box(0.1, 0.06, 0.04)))
    assert sorted(round(ph.face_width(box, f), 9) for f in range(6)) == [
        0.04,
        0.04,
        0.04,
        0.04,
        0.06,
        0.06,
    ]


def test_polygons_in_batches_are_ordered_as_one_at_a_time() -> None:
    rng = np.random.default_rng(4)
    for m in (3, 4, 5, 8, 11):
        pts = rng.normal(size=(7, m, 3))
        normals = rng.normal(size=(7, 3))
        normals /= np.linalg.norm(normals, axis=1)[:, None]
        pts[0] = pts[0].mean(axis=0)  # the first point at the centre: ordered alone
        pts[0, 1:] += rng.normal(size=(m - 1, 3))
        pts[0, 0] = pts[0].sum(axis=0) / m
        got = ph._order_polygons(pts, normals)
        assert got == [ph._order_polygon(p, v) for p, v in zip(pts, normals, strict=True)]


def test_vertex_least_squares_in_batches() -> None:
    """Each vertex is the least-squares point of the planes active there, as solved alone."""
    n, d = _noisy(solids.octahedron(0.1), 5, copies=2)
    raw = np.random.default_rng(5).normal(scale=0.03, size=(9, 3))
    active = np.random.default_rng(6).random((9, len(n))) < 0.3
    active[0] = False  # no plane: the raw point
    labels = np.arange(9)
    got = ph._cluster_vertices(raw, labels, 9, active, n, d, np.inf)
    for v in range(9):
        planes = np.flatnonzero(active[v])
        if len(planes) < 3:
            assert np.array_equal(got[v], raw[v])
            continue
        a, b = n[planes].T @ n[planes], n[planes].T @ d[planes]
        assert np.array_equal(got[v], np.linalg.solve(a, b))


def test_completer_reuses_the_model_only_for_the_same_inputs() -> None:
    finger = builtin_finger("33")
    record = sample_record(solids.box(0.08, 0.06, 0.05), finger, per_face=4, seed=2)
    completer = ModelCompleter()
    first = completer._model(record)
    # the same contacts in a new record (a probe that touched nothing; the path grew)
    later = record.model_copy(update={"path": [*record.path, (0.5, 0.5, 0.5)]})
    second = completer._model(later)
    assert second.record is later
    fresh = build_model(later)
    for name in ("faces", "supporting", "face_of", "open_reason", "layers", "options"):
        assert getattr(second, name) == getattr(fresh, name), name
    assert second.polyhedron is not None
    assert fresh.polyhedron is not None
    _same(second.polyhedron, fresh.polyhedron)
    assert dataclasses.replace(first, record=later) is not first
    # one contact fewer: built again, as a fresh build of that record
    fewer = record.model_copy(update={"contacts": record.contacts[:-1]})
    third = completer._model(fewer)
    assert third.faces == build_model(fewer).faces
    assert third.record is fewer


def _plain_nearest(x: np.ndarray, n: np.ndarray, d: np.ndarray) -> np.ndarray:
    """:func:`nearest_points` as it was: every plane projected in every sweep."""
    over = x @ n.T - d
    worst = over.argmax(axis=1)
    q = x - np.maximum(over[np.arange(len(x)), worst], 0.0)[:, None] * n[worst]
    hard = np.flatnonzero((q @ n.T - d).max(axis=1) > 1e-12)
    if len(hard) == 0:
        return q
    y = x[hard].copy()
    corr = np.zeros((len(n), *y.shape))
    for _ in range(60):
        for i in range(len(n)):
            z = y + corr[i]
            y = z - np.maximum(z @ n[i] - d[i], 0.0)[:, None] * n[i][None, :]
            corr[i] = z - y
    q[hard] = y
    return q


@pytest.mark.parametrize("mesh", SOLIDS)
def test_nearest_points_skip_only_idle_planes(mesh: trimesh.Trimesh) -> None:
    """Skipping the planes every point lies well inside of gives the plain projections' bits."""
    n, d = _planes(mesh)
    rng = np.random.default_rng(7)
    for size in (1, 3, 40):
        x = np.asarray(mesh.centroid) + rng.normal(scale=0.08, size=(size, 3))
        got = nearest_points(x, n, d)
        assert np.array_equal(got, _plain_nearest(x, n, d))
        inside = (x @ n.T - d).max(axis=1) <= 0
        assert np.array_equal(got[inside], x[inside])


def _wedge(deg: float) -> tuple[np.ndarray, np.ndarray]:
    """A box 8 × 6 × 5 cm whose +x side is cut by a plane ``deg`` off it: two planes at a
    small angle, along whose edge Dykstra's projections creep."""
    t = np.radians(deg)
    n = np.vstack([np.eye(3), -np.eye(3), [np.cos(t), 0.0, np.sin(t)]])
    d = np.array([0.04, 0.03, 0.05, 0.04, 0.03, 0.0, 0.04 * np.cos(t) + 0.04 * np.sin(t)])
    return n, d


@pytest.mark.parametrize("deg", [2.0, 10.0, 45.0])
def test_nearest_points_stop_only_at_the_fixed_point(deg: float) -> None:
    """A sweep that changes nothing ends the projections: the points are the 60 sweeps'
    bits, whether they settled in a few sweeps or crept on to the last (points beyond the
    edge of two planes ``deg`` apart); and no more sweeps are needed where they settled."""
    n, d = _wedge(deg)
    rng = np.random.default_rng(11)
    x = np.array([0.04, 0.0, 0.04]) + rng.normal(scale=0.03, size=(60, 3))
    got = nearest_points(x, n, d)
    assert np.array_equal(got, _plain_nearest(x, n, d))
    longer = nearest_points(x, n, d, iterations=400)
    settled = np.all(longer == got, axis=1)
    assert settled.sum() >= 30  # most points had reached the fixed point within 60 sweeps
    # every point lies in the set, and no nearer point of it is found on a finer grid
    assert (longer @ n.T - d).max() <= 1e-9
    grid = np.stack(
        np.meshgrid(
            *(np.linspace(-0.04, 0.04, 33), np.linspace(-0.03, 0.03, 25), np.linspace(0, 0.05, 21))
        ),
        axis=-1,
    ).reshape(-1, 3)
    grid = grid[(grid @ n.T - d).max(axis=1) <= 0]
    nearest_grid = np.sqrt(((x[:, None, :] - grid[None]) ** 2).sum(axis=2)).min(axis=1)
    assert np.all(np.linalg.norm(x - longer, axis=1) <= nearest_grid + 1e-9)


def test_nearest_points_of_a_box_are_clipped_coordinates() -> None:
    lo, hi = np.array([-0.04, -0.03, 0.0]), np.array([0.04, 0.03, 0.05])
    n = np.vstack([np.eye(3), -np.eye(3)])
    d = np.concatenate([hi, -lo])
    x = np.random.default_rng(8).uniform(-0.1, 0.1, size=(200, 3))
    assert np.allclose(nearest_points(x, n, d), np.clip(x, lo, hi), atol=1e-12)
