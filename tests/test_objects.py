"""Loading, checking and resting objects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from tactile_kb.errors import ObjectError
from tactile_kb.objects import MAX_SIZE, load_object, object_name


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
    with pytest.raises(ObjectError, match=r"bad\.ply: cannot read mesh"):
        load_object(bad)


def test_empty_mesh(tmp_path: Path) -> None:
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing\n")
    with pytest.raises(ObjectError, match=r"empty\.obj: "):
        load_object(empty)
    with pytest.raises(ObjectError, match="empty"):
        load_object(trimesh.Trimesh())


def test_open_mesh() -> None:
    box = trimesh.creation.box((0.05, 0.05, 0.05))
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2])
    with pytest.raises(ObjectError, match="open"):
        load_object(open_box, name="lid.stl")


def test_degenerate_mesh() -> None:
    flat = trimesh.creation.box((0.05, 0.05, 1e-5))
    with pytest.raises(ObjectError, match="degenerate"):
        load_object(flat)


def test_too_large_and_outside_the_workspace() -> None:
    big = trimesh.creation.box((MAX_SIZE * 2, 0.05, 0.05))
    with pytest.raises(ObjectError, match=r"larger than the workspace.*millimetres"):
        load_object(big)
    far = trimesh.creation.box((0.05, 0.05, 0.05))
    far.apply_translation((3.0, 0.0, 0.0))
    with pytest.raises(ObjectError, match="outside the workspace"):
        load_object(far)


def test_not_a_mesh() -> None:
    with pytest.raises(ObjectError, match="expected a trimesh"):
        load_object(42)  # type: ignore[arg-type]
