"""Loading, checking and resting objects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from tactile_kb import settings
from tactile_kb.completion import model_completer
from tactile_kb.errors import ObjectError
from tactile_kb.objects import MAX_SIZE, NOTES_KEY, load_object, min_width, object_name
from tactile_kb.touch.stepper import StepperExplorer


def floating_box() -> trimesh.Trimesh:
    m: trimesh.Trimesh = trimesh.creation.box((0.06, 0.04, 0.02))
    turn = trimesh.transformations.rotation_matrix(0.3, (1, 1, 0))  # type: ignore[no-untyped-call]
    m.apply_transform(turn)
    m.apply_translation((0.01, -0.02, 0.3))
    return m


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply"])
def test_files_load_and_rest_on_the_table_keeping_orientation(tmp_path: Path, suffix: str) -> None:
    mesh = floating_box()
    path = tmp_path / f"box{suffix}"
    mesh.export(path)
    obj = load_object(path)
    assert obj.bounds[0, 2] == pytest.approx(0.0, abs=1e-12)
    # orientation and x-y position kept: a pure vertical translation of the original
    shift = mesh.bounds[0, 2]
    assert np.allclose(
        np.sort(obj.vertices, axis=0), np.sort(mesh.vertices - [0, 0, shift], axis=0), atol=1e-6
    )
    assert obj.volume == pytest.approx(mesh.volume, rel=1e-6)
    assert object_name(path) == str(path)


def test_a_mesh_is_copied_not_modified() -> None:
    mesh = floating_box()
    before = mesh.vertices.copy()
    obj = load_object(mesh)
    assert obj is not mesh
    assert np.array_equal(mesh.vertices, before)
    assert obj.bounds[0, 2] == pytest.approx(0.0, abs=1e-12)


def test_inside_out_meshes_are_turned_outwards() -> None:
    mesh = trimesh.creation.box((0.05, 0.05, 0.05))
    mesh.invert()
    assert mesh.volume < 0
    assert load_object(mesh).volume > 0


def test_missing_and_unsupported_files(tmp_path: Path) -> None:
    with pytest.raises(ObjectError, match=r"nope\.stl: no such file"):
        load_object(tmp_path / "nope.stl")
    other = tmp_path / "thing.step"
    other.write_text("solid")
    with pytest.raises(ObjectError, match=r"thing\.step: unsupported mesh format '\.step'"):
        load_object(other)


def test_unreadable_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"ply\nformat nonsense\n\x00\x01garbage")
    with pytest.raises(ObjectError, match=r"^\S*bad\.ply: not a readable PLY mesh file$"):
        load_object(bad)
    garbage = tmp_path / "garbage.obj"
    garbage.write_text("v 1 2\nf a b c\nxyz\n")
    with pytest.raises(ObjectError, match=r"^\S*garbage\.obj: not a readable OBJ mesh file"):
        load_object(garbage)
    text = tmp_path / "notes.stl"
    text.write_text("hello, this is not a mesh\n")
    with pytest.raises(
        ObjectError, match=r"^\S*notes\.stl: not a readable STL mesh file: no triangles found$"
    ):
        load_object(text)


def test_empty_mesh(tmp_path: Path) -> None:
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    with pytest.raises(ObjectError, match=r"empty\.obj: not a readable OBJ mesh file"):
        load_object(empty)
    with pytest.raises(ObjectError, match="empty"):
        load_object(trimesh.Trimesh())


def test_a_mesh_with_a_hole_is_filled_with_a_note() -> None:
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-1])  # one triangle missing
    assert not open_box.is_watertight
    mesh = load_object(open_box, name="lid.stl")
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(0.05**3)
    assert mesh.metadata[NOTES_KEY] == ["holes in the mesh filled (trimesh.repair.fill_holes)"]


def test_a_mesh_trimesh_cannot_close_is_explored_as_it_is() -> None:
    # a cup: a cylinder without its top (a 48-sided hole trimesh does not fill)
    cup = trimesh.creation.cylinder(radius=0.03, height=0.05, sections=48)
    top = cup.face_normals[:, 2] > 0.99
    open_cup = trimesh.Trimesh(cup.vertices, cup.faces[~top])
    mesh = load_object(open_cup, name="cup.stl")
    assert not mesh.is_watertight
    (note,) = mesh.metadata[NOTES_KEY]
    assert note == (
        "the mesh is not closed (48 boundary edges trimesh cannot fill); explored as it is"
    )
    rec = StepperExplorer(completer=model_completer()).explore(mesh, seed=0)
    assert note in rec.notes
    assert rec.touches > 0


def test_a_mesh_with_an_edge_of_three_triangles_is_said_not_closed_for_that() -> None:
    # a closed box with a fin: one more triangle on one of its edges, an edge of three
    # triangles (as in robosuite's bottle), and the fin's own two free edges
    box = trimesh.creation.box((0.05, 0.04, 0.03))
    a, b = box.edges_unique[0]
    middle = (box.vertices[a] + box.vertices[b]) / 2
    fin_tip = middle * 1.5  # out from the box's centre, beyond the edge
    vertices = np.vstack([box.vertices, fin_tip])
    faces = np.vstack([box.faces, [[a, b, len(box.vertices)]]])
    finned = trimesh.Trimesh(vertices, faces, process=False)
    assert int(np.sum(np.bincount(finned.edges_unique_inverse) > 2)) == 1
    assert int(np.sum(np.bincount(finned.edges_unique_inverse) == 1)) == 2  # the fin's own
    mesh = load_object(finned, name="fin.stl")
    assert mesh.metadata[NOTES_KEY] == [
        "the mesh is not closed (2 boundary edges trimesh cannot fill, 1 edges shared by more "
        "than two triangles); explored as it is"
    ]


def test_degenerate_mesh() -> None:
    flat = trimesh.creation.box((0.05, 0.05, 1e-5))
    with pytest.raises(ObjectError, match="degenerate"):
        load_object(flat)


def test_too_large_for_the_workspace() -> None:
    big = trimesh.creation.box((MAX_SIZE * 2, 0.05, 0.05))
    with pytest.raises(ObjectError) as refused:
        load_object(big)
    # 1.2 m by 5 cm: in no other unit an object the finger can explore, so no unit is offered
    assert str(refused.value).endswith(
        f"larger than the workspace: {MAX_SIZE * 2:.3g} m across (at most {MAX_SIZE:g} m)"
    )


def test_an_object_outside_the_workspace_is_centred_over_the_origin() -> None:
    # a scan in its scanner's coordinates: 3 m along x, 0.8 m along −y, 1 m up
    far = trimesh.creation.box((0.08, 0.05, 0.04))
    far.apply_translation((3.0, -0.8, 1.0))
    obj = load_object(far)
    assert np.allclose(obj.bounds, [[-0.04, -0.025, 0.0], [0.04, 0.025, 0.04]])
    assert np.allclose(obj.metadata["moved_xy"], (-3.0, 0.8))
    assert obj.metadata["moved_z"] == pytest.approx(-0.98)
    assert np.allclose(far.bounds[0], [2.96, -0.825, 0.98])  # the input is not modified
    # within the workspace, x and y are kept
    near = trimesh.creation.box((0.08, 0.05, 0.04))
    near.apply_translation((0.3, -0.2, 0.0))
    kept = load_object(near)
    assert np.allclose(kept.bounds[:, :2], near.bounds[:, :2])
    assert kept.metadata["moved_xy"] == (0.0, 0.0)
    # a workspace too narrow for the object even centred on it: one line naming it
    narrow = settings.override(objects={"workspace_half_width": 0.03})
    with narrow, pytest.raises(ObjectError) as refused:
        load_object(far, name="far.stl")
    assert str(refused.value) == (
        "far.stl: does not fit the workspace (|x|, |y| ≤ 0.03 m) even centred on it: 0.08 × 0.05 m"
    )


def test_the_record_says_how_far_the_object_was_moved() -> None:
    far = trimesh.creation.box((0.06, 0.06, 0.06))
    far.apply_translation((-2.0, 1.5, 0.03))
    record = StepperExplorer().explore(far, finger="4")
    assert (
        "the mesh was moved (+2000, -1500) mm along x and y so that it lies in the workspace"
        in (" ".join(record.notes))
    )
    assert record.contacts


def test_not_a_mesh() -> None:
    with pytest.raises(ObjectError, match="expected a trimesh"):
        load_object(42)  # type: ignore[arg-type]


def _nan_cube_text(bad: str) -> str:
    return f"v {bad} 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_non_finite_coordinates_are_one_line_without_numpy_warnings(
    tmp_path: Path, bad: str
) -> None:
    # pytest turns warnings into errors: a RuntimeWarning from numpy would fail this test
    path = tmp_path / "tet.obj"
    path.write_text(_nan_cube_text(bad))
    with pytest.raises(ObjectError) as info:
        load_object(path)
    assert (
        str(info.value) == f"{path}: the mesh has non-finite (NaN or infinite) vertex coordinates"
    )
    good = tmp_path / "good.obj"
    good.write_text(_nan_cube_text("0"))
    assert load_object(good).volume == pytest.approx(0.05**3 / 6)
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    v = box.vertices.copy()
    v[3, 2] = float(bad)
    with pytest.raises(ObjectError, match=r"^cube: the mesh has non-finite"):
        load_object(trimesh.Trimesh(v, box.faces, process=False), name="cube")


def test_two_bodies_in_one_file_are_rejected(tmp_path: Path) -> None:
    a = trimesh.creation.box((0.05, 0.05, 0.05))
    b = a.copy()
    b.apply_translation((0.1, 0.0, 0.0))
    path = tmp_path / "pair.stl"
    trimesh.util.concatenate([a, b]).export(path)
    with pytest.raises(ObjectError) as info:
        load_object(path)
    assert str(info.value) == (
        f"{path}: the mesh holds 2 separate objects (bodies more than 1.7 mm apart); "
        "explore one object at a time"
    )
    # one body from an STL (unmerged triangle soup in the file) is one body
    one = tmp_path / "one.stl"
    a.export(one)
    assert load_object(one).body_count == 1


@pytest.mark.parametrize(
    ("dims", "thin"),
    [
        ((0.05, 0.05, 0.004), True),  # a plate lying flat, 4 mm
        ((0.006, 0.05, 0.05), True),  # a plate on its edge, 6 mm
        ((0.0074, 0.05, 0.05), True),
        ((0.0076, 0.05, 0.05), False),
        ((0.03, 0.03, 0.03), False),
    ],
)
def test_objects_thinner_than_the_tip_resolves_are_rejected(
    dims: tuple[float, float, float], thin: bool
) -> None:
    from tactile_kb.objects import THIN_FACTOR, check_thickness

    # ground truth: a box's thinnest width is its smallest side, whatever its turn
    mesh = trimesh.creation.box(dims)
    turn = trimesh.transformations.rotation_matrix(0.5, (0, 0, 1))  # type: ignore[no-untyped-call]
    mesh.apply_transform(turn)
    assert (min(dims) < THIN_FACTOR * 0.005) == thin
    if thin:
        with pytest.raises(ObjectError, match=r"^plate: too thin for the finger: .* 7\.5 mm$"):
            check_thickness(mesh, 0.005, name="plate")
    else:
        check_thickness(mesh, 0.005, name="plate")
    check_thickness(mesh, min(dims) / THIN_FACTOR * 0.99, name="plate")  # a finer tip


def test_explorers_reject_thin_objects_before_exploring() -> None:
    from tactile_kb.touch.stepper import StepperExplorer

    plate = trimesh.creation.box((0.006, 0.05, 0.05))
    with pytest.raises(ObjectError, match="too thin for the finger"):
        StepperExplorer().session(plate, finger="33")
    from tactile_kb.touch.finger import builtin_finger

    fine = builtin_finger("33", radius=0.003)
    assert StepperExplorer().session(plate, finger=fine).done is False


def test_floating_specks_are_dropped_with_a_note(tmp_path: Path) -> None:
    body = trimesh.creation.box((0.06, 0.05, 0.04))
    specks = [trimesh.creation.icosphere(subdivisions=1, radius=0.001) for _ in range(3)]
    for k, speck in enumerate(specks):
        speck.apply_translation((0.05 + 0.01 * k, 0.0, 0.0))
    path = tmp_path / "scan.stl"
    trimesh.util.concatenate([body, *specks]).export(path)
    mesh = load_object(path)
    assert mesh.body_count == 1
    assert mesh.volume == pytest.approx(0.06 * 0.05 * 0.04)
    assert mesh.metadata[NOTES_KEY] == [
        "3 floating speck(s) dropped (each under 10% of the object's size or 1% "
        "of its bounding volume); the largest body is explored"
    ]
    rec = StepperExplorer(completer=model_completer()).explore(path, seed=0)
    assert mesh.metadata[NOTES_KEY][0] in rec.notes


def test_a_speck_large_beside_a_small_object_but_tiny_in_volume_is_dropped() -> None:
    small = trimesh.creation.box((0.022, 0.022, 0.02))
    speck = trimesh.creation.box((0.004, 0.004, 0.004))  # 20 % of the diagonal, 0.7 % of the volume
    speck.apply_translation((0.03, 0.0, 0.0))
    mesh = load_object(trimesh.util.concatenate([small, speck]), name="small")
    assert mesh.body_count == 1
    assert mesh.volume == pytest.approx(0.022 * 0.022 * 0.02)
    assert "1 floating speck(s) dropped" in mesh.metadata[NOTES_KEY][0]


def test_a_second_body_larger_than_a_speck_is_refused() -> None:
    a = trimesh.creation.box((0.06, 0.05, 0.04))
    b = trimesh.creation.box((0.02, 0.02, 0.02))  # 35 % of the box's diagonal, 6.7 % of its volume
    b.apply_translation((0.08, 0.0, 0.0))
    with pytest.raises(ObjectError, match="holds 2 separate objects"):
        load_object(trimesh.util.concatenate([a, b]), name="two")


@pytest.mark.parametrize(
    ("what", "text"),
    [
        ("plane", "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0.05 0.05 0\nf 1 2 3\nf 2 4 3\n"),
        ("line", "v 0 0 0\nv 0.05 0 0\nv 0.1 0 0\nf 1 2 3\n"),
        ("points", "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\n"),
    ],
)
def test_a_mesh_that_is_not_a_solid_is_one_line(tmp_path: Path, what: str, text: str) -> None:
    path = tmp_path / f"{what}.obj"
    path.write_text(text)
    with pytest.raises(ObjectError) as info:
        load_object(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert "\n" not in message
    assert ("not a solid" in message) or ("no triangles" in message)


def test_the_width_of_a_dense_hull_is_computed_without_a_dense_matrix() -> None:
    # 82k triangles, every vertex on the hull: 0.1 issued a 25 GiB vertices x normals matrix
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=0.04)
    assert min_width(sphere) == pytest.approx(0.08, abs=5e-4)
    assert min_width(sphere) <= 0.08 + 1e-12  # never overestimated
    plate = trimesh.creation.box((0.05, 0.05, 0.004))
    assert min_width(plate) == pytest.approx(0.004)


def test_seams_nanometres_apart_are_welded_with_a_note() -> None:
    # a CAD export whose two halves do not share vertices: 50 nm apart along the seam
    whole = trimesh.creation.box((0.06, 0.05, 0.04))
    corners = whole.vertices[whole.faces]  # (12, 3, 3): every triangle its own vertices
    right = corners.mean(axis=1)[:, 0] > 0.0
    corners[right] += (5e-8, -3e-8, 2e-8)
    soup = trimesh.Trimesh(corners.reshape(-1, 3), np.arange(36).reshape(-1, 3))
    assert not soup.is_watertight  # as trimesh loads it
    mesh = load_object(soup, name="cad")
    assert mesh.is_watertight
    assert mesh.body_count == 1
    assert mesh.volume == pytest.approx(0.06 * 0.05 * 0.04, rel=1e-5)
    assert mesh.metadata[NOTES_KEY][0] == (
        "seams under 0.88 µm apart welded (the mesh was not closed)"
    )
    # a real gap (0.1 mm) is not a seam: nothing is welded; the two open halves, closer than
    # the finger could pass between, are explored side by side as one object
    corners[right] += (1e-4, 0.0, 0.0)
    gap = trimesh.Trimesh(corners.reshape(-1, 3), np.arange(36).reshape(-1, 3))
    halves = load_object(gap, name="gap")
    assert not any(n.startswith("seams under") for n in halves.metadata[NOTES_KEY])
    assert halves.metadata[NOTES_KEY][0].startswith("2 parts under 1.")
    assert halves.extents[0] == pytest.approx(0.0601, abs=1e-6)


def test_parts_of_one_object_are_joined_and_far_bodies_refused() -> None:
    # an L modelled as two overlapping boxes: their union, one closed body
    a = trimesh.creation.box((0.08, 0.03, 0.03))
    b = trimesh.creation.box((0.03, 0.03, 0.06))
    b.apply_translation((0.025, 0.0, 0.015))
    l_shape = load_object(trimesh.util.concatenate([a, b]), name="L")
    assert l_shape.body_count == 1
    assert l_shape.is_watertight
    overlap = 0.03 * 0.03 * 0.03  # x 0.01…0.04, y and z ±0.015
    assert l_shape.volume == pytest.approx(a.volume + b.volume - overlap, rel=1e-6)
    assert l_shape.metadata[NOTES_KEY] == [
        "2 parts under 1.8 mm apart explored as one object (their union)"
    ]
    # a handle modelled apart, 1 mm off the cup's wall: one object
    cup = trimesh.creation.cylinder(radius=0.03, height=0.08)
    handle = trimesh.creation.box((0.01, 0.004, 0.05))
    handle.apply_translation((0.03 + 0.001 + 0.005, 0.0, 0.0))
    mug = load_object(trimesh.util.concatenate([cup, handle]), name="mug")
    assert mug.bounds[1][0] == pytest.approx(0.041, abs=1e-6)  # the handle is kept
    assert "2 parts under" in mug.metadata[NOTES_KEY][0]
    # a block 2 cm off the cup is a second object
    block = trimesh.creation.box((0.03, 0.03, 0.05))
    block.apply_translation((0.03 + 0.02 + 0.015, 0.0, 0.0))
    with pytest.raises(ObjectError, match="mug: the mesh holds 2 separate objects"):
        load_object(trimesh.util.concatenate([cup, block]), name="mug")


def test_pieces_that_overlap_are_one_object_however_many() -> None:
    # a cross of two bars: no corner of either lies near the other's surface, yet they overlap
    a = trimesh.creation.box((0.10, 0.02, 0.02))
    b = trimesh.creation.box((0.02, 0.10, 0.02))
    cross = load_object(trimesh.util.concatenate([a, b]), name="cross")
    assert cross.extents == pytest.approx((0.10, 0.10, 0.02), abs=1e-6)
    assert cross.volume == pytest.approx(a.volume + b.volume - 0.02**3, rel=1e-6)
    # a slab decomposed into 100 overlapping cubes (a convex decomposition of more pieces
    # than MAX_PARTS once allowed): one object, their union
    cubes = []
    for i in range(10):
        for j in range(10):
            c = trimesh.creation.box((0.01, 0.01, 0.01))
            c.apply_translation((0.008 * i, 0.008 * j, 0.0))
            cubes.append(c)
    slab = load_object(trimesh.util.concatenate(cubes), name="slab")
    assert slab.extents == pytest.approx((0.082, 0.082, 0.01), abs=1e-6)
    assert slab.volume == pytest.approx(0.082 * 0.082 * 0.01, rel=1e-6)
    assert slab.metadata[NOTES_KEY][0].startswith("100 parts under")


INSIDE_NOTE = (
    "1 shell(s) inside the object dropped (a cavity or an enclosed part: the finger touches "
    "only the outside)"
)


@pytest.mark.parametrize("facing", ["inwards", "outwards"])
def test_a_cavity_or_an_enclosed_part_is_dropped_with_a_note(facing: str) -> None:
    # a hollow box's inner wall (its triangles facing into the cavity), or a part modelled
    # inside another: no finger reaches it, and it is no second object
    outer = trimesh.creation.box((0.08, 0.05, 0.04))
    inner = trimesh.creation.box((0.04, 0.025, 0.02))
    inner.apply_translation((0.01, 0.005, 0.0))
    faces = inner.faces[:, ::-1] if facing == "inwards" else inner.faces
    shell = trimesh.Trimesh(inner.vertices, faces, process=False)
    obj = load_object(trimesh.util.concatenate([outer, shell]), name="hollow")
    assert obj.body_count == 1
    assert obj.extents == pytest.approx((0.08, 0.05, 0.04), abs=1e-9)
    assert obj.volume == pytest.approx(0.08 * 0.05 * 0.04, rel=1e-9)
    assert obj.metadata[NOTES_KEY] == [INSIDE_NOTE]
    # the same box beside the object, not inside it, is a second object
    beside = shell.copy()
    beside.apply_translation((0.1, 0.0, 0.0))
    with pytest.raises(ObjectError, match="the mesh holds 2 separate objects"):
        load_object(trimesh.util.concatenate([outer, beside]), name="pair")


def test_a_box_with_a_corner_moved_onto_another_loads_without_warnings(tmp_path: Path) -> None:
    # pytest turns warnings into errors: read from an STL (a triangle soup), the body of no
    # volume this leaves had trimesh's mass properties divide by zero while it was tested
    # against the rest
    box = trimesh.creation.box((0.08, 0.05, 0.04))
    v = box.vertices.copy()
    v[0] = v[1]
    path = tmp_path / "dented.stl"
    trimesh.Trimesh(v, box.faces, process=False).export(path)
    obj = load_object(path)
    # what is left: the box less the wedge between the moved corner and its three edges
    assert obj.volume == pytest.approx(0.08 * 0.05 * 0.04 - 0.08 * 0.05 * 0.04 / 6, rel=1e-6)


def test_thousands_of_loose_triangles_beside_an_object_are_specks() -> None:
    # a scan's debris: 2000 loose triangles of about a millimetre in and around a box; only the
    # largest bodies are tried as parts (MAX_PARTS), the rest are specks
    from tactile_kb.objects import MAX_PARTS

    rng = np.random.default_rng(0)
    box = trimesh.creation.box((0.06, 0.05, 0.04))
    loose = [
        trimesh.Trimesh(rng.uniform(-0.03, 0.03, 3) + rng.normal(size=(3, 3)) * 0.001, [[0, 1, 2]])
        for _ in range(2000)
    ]
    mesh = load_object(trimesh.util.concatenate([box, *loose]), name="debris")
    notes = mesh.metadata[NOTES_KEY]
    inside = int(notes[0].split()[0]) if "inside the object" in notes[0] else 0
    dropped = int(notes[1].split()[0]) if inside else int(notes[0].split()[0])
    parts = [int(n.split()[0]) for n in notes if "parts under" in n] or [1]
    assert inside + dropped + parts[0] == 2001
    # at least as many are dropped as inside as lie well inside the box (4 mm from its faces)
    centres = [t.vertices.mean(axis=0) for t in loose]
    deep = sum(
        bool(np.all(np.abs(c) < (0.03 - 0.004, 0.025 - 0.004, 0.02 - 0.004))) for c in centres
    )
    assert deep <= inside <= 2000
    assert parts[0] <= MAX_PARTS
    assert mesh.extents == pytest.approx((0.06, 0.05, 0.04), abs=0.012)  # kept parts stick out


# --- units and resting poses (settings objects.units and objects.rest) ------------------------


@pytest.mark.parametrize(
    ("units", "per_metre"), [("mm", 1000.0), ("cm", 100.0), ("in", 1 / 0.0254)]
)
def test_a_mesh_in_other_units_is_scaled_to_metres(units: str, per_metre: float) -> None:
    mesh = trimesh.creation.box((0.08, 0.06, 0.04))
    mesh.apply_scale(per_metre)
    with settings.override(objects={"units": units}):
        obj = load_object(mesh)
    assert np.allclose(sorted(obj.extents), [0.04, 0.06, 0.08])
    assert obj.bounds[0][2] == pytest.approx(0.0, abs=1e-12)


def test_a_millimetre_mesh_read_as_metres_names_the_units_setting() -> None:
    mesh = trimesh.creation.box((80.0, 60.0, 40.0))
    with pytest.raises(ObjectError) as refused:
        load_object(mesh)
    assert str(refused.value).endswith(
        "larger than the workspace: 80 m across (at most 0.6 m); if its unit is not the metre, "
        "read it with --units mm (8 cm across), or the setting objects.units"
    )


def test_a_mesh_of_unit_size_is_offered_the_units_it_fits_in() -> None:
    # a cube one unit across (a simulator's unit cube): 1 m is too large, 1 mm too thin; as
    # inches or centimetres it is an object, the inch (nearer 10 cm) named first
    cube = trimesh.creation.box((1.0, 1.0, 1.0))
    offer = "--units in (2.54 cm across) or --units cm (1 cm across), or the setting objects.units"
    with pytest.raises(ObjectError) as refused:
        load_object(cube, name="cube.obj")
    assert str(refused.value) == (
        "cube.obj: larger than the workspace: 1 m across (at most 0.6 m); if its unit is not "
        f"the metre, read it with {offer}"
    )
    with settings.override(objects={"units": "mm"}), pytest.raises(ObjectError) as refused:
        load_object(cube, name="cube.obj")
    assert str(refused.value).startswith("cube.obj: not a solid: 1 mm thick")
    assert str(refused.value).endswith(f"if its unit is not the millimetre, read it with {offer}")
    with settings.override(objects={"units": "in"}):
        assert load_object(cube).extents == pytest.approx((0.0254,) * 3)


def _tilted(mesh: trimesh.Trimesh, seed: int) -> trimesh.Trimesh:
    out = mesh.copy()
    out.apply_transform(
        trimesh.transformations.random_rotation_matrix(np.random.default_rng(seed).random(3))
    )
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rest_stable_lays_a_tilted_slab_on_a_broad_face(seed: int) -> None:
    # a 8 × 6 × 2 cm slab comes to rest on one of its two broad faces: 2 cm high
    slab = trimesh.creation.box((0.08, 0.06, 0.02))
    tilted = _tilted(slab, seed)
    as_given = load_object(tilted)
    assert as_given.extents[2] > 0.03  # standing on an edge or a corner as given
    with settings.override(objects={"rest": "stable"}):
        rested = load_object(tilted)
    assert rested.extents[2] == pytest.approx(0.02, abs=1e-9)
    assert np.isclose(rested.vertices[:, 2], 0.0, atol=1e-9).sum() == 4  # a face on the table
    assert rested.volume == pytest.approx(slab.volume)
    assert any("most probable stable pose" in n for n in rested.metadata[NOTES_KEY])


def test_rest_stable_puts_a_tilted_tetrahedron_on_a_face() -> None:
    tetra = trimesh.Trimesh(
        [[0, 0, 0], [0.06, 0, 0], [0.01, 0.05, 0], [0.02, 0.02, 0.04]],
        [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    )
    tilted = _tilted(tetra, 5)
    with settings.override(objects={"rest": "stable"}):
        rested = load_object(tilted)
    assert np.isclose(rested.vertices[:, 2], 0.0, atol=1e-9).sum() == 3


def test_rest_stable_keeps_an_object_already_at_rest() -> None:
    slab = trimesh.creation.box((0.08, 0.06, 0.02))
    with settings.override(objects={"rest": "stable"}):
        rested = load_object(slab)
    assert rested.extents[2] == pytest.approx(0.02)
    assert np.allclose(rested.bounds.mean(axis=0)[:2], slab.bounds.mean(axis=0)[:2])


@pytest.mark.parametrize("suffix", [".off", ".glb", ".gltf"])
def test_off_and_gltf_files_load_gltf_with_y_up(tmp_path: Path, suffix: str) -> None:
    # 2 cm in x, 10 cm in y, 4 cm in z, as stored in the file
    mesh = trimesh.creation.box((0.02, 0.10, 0.04))
    path = tmp_path / f"part{suffix}"
    if suffix == ".gltf":  # a JSON file and its buffers (trimesh's export leaves a file open)
        for name, data in trimesh.exchange.gltf.export_gltf(mesh).items():
            (tmp_path / ("part.gltf" if name == "model.gltf" else name)).write_bytes(data)
    else:
        mesh.export(path)
    obj = load_object(path)
    assert obj.is_watertight
    assert obj.volume == pytest.approx(0.02 * 0.10 * 0.04)
    # glTF's up is +y: the 10 cm side stands up; OFF keeps z up
    want = [0.02, 0.04, 0.10] if suffix in (".glb", ".gltf") else [0.02, 0.10, 0.04]
    assert np.allclose(obj.extents, want)
