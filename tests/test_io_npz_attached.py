"""Attributes, face sets and fields in an .npz archive (tuckercodec/io/npz,
io/common/attached_keys.py): kept bit for bit, read a range of frames at a time, archives
written before them still read, and a damaged description or member named."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import (
    Attribute,
    FaceSet,
    Field,
    InputError,
    MeshSequence,
    load_sequence,
    save_sequence,
)
from tuckercodec.io.npz import NpzFrames
from tuckercodec.io.registry import format_named


def every_kind(frames: int = 4, grid: int = 4) -> MeshSequence:
    """A moving grid with attributes of every domain (one indexed), face sets and fields."""
    vertices = wave_sequence(frames, grid)
    faces = grid_faces(grid)
    vertex_count, face_count = vertices.shape[1], len(faces)
    corners = int((faces >= 0).sum())
    rng = np.random.default_rng(9)
    table = rng.random((7, 2), np.float32)
    return MeshSequence(
        vertices,
        faces,
        attributes=[
            Attribute("st", "corner", table, rng.integers(0, 7, corners), role="uv"),
            Attribute("N", "vertex", rng.random((vertex_count, 3)), role="normal"),
            Attribute("id", "face", np.arange(face_count, dtype=np.int32)),
            Attribute("Cd", "corner", rng.random((corners, 4), np.float32), role="color"),
        ],
        face_sets=[
            FaceSet("skin", np.arange(0, face_count, 2), "materialBind"),
            FaceSet("skin", np.array([1, 3]), "group"),
            FaceSet('éclat/"odd" name', np.array([], np.int64)),
        ],
        fields=[
            Field("velocities", rng.random((frames, vertex_count, 3), np.float32), role="velocity"),
            Field("heat", rng.random((frames, face_count, 1)), domain="face"),
        ],
    )


def same(back: MeshSequence, seq: MeshSequence) -> None:
    assert len(back.attributes) == len(seq.attributes)
    for found, attribute in zip(back.attributes, seq.attributes, strict=True):
        assert found.same_as(attribute), attribute.name
    assert len(back.face_sets) == len(seq.face_sets)
    for found_set, face_set in zip(back.face_sets, seq.face_sets, strict=True):
        assert found_set.same_as(face_set)
    assert [f.name for f in back.fields] == [f.name for f in seq.fields]
    for found_field, item in zip(back.fields, seq.fields, strict=True):
        assert (found_field.domain, found_field.role) == (item.domain, item.role)
        assert found_field.values.dtype == item.values.dtype
        assert found_field.values.tobytes() == item.values.tobytes()


@pytest.mark.parametrize("compressed", [False, True])
def test_everything_round_trips_bit_for_bit(tmp_path, compressed):
    seq = every_kind()
    path = tmp_path / "a.npz"
    save_sequence(seq, path)
    if compressed:  # as np.savez_compressed would have written it
        with np.load(path) as data:
            np.savez_compressed(path, **{key: data[key] for key in data.files})
    back = load_sequence(path)
    assert np.array_equal(back.vertices, seq.vertices)
    same(back, seq)
    source = NpzFrames(path)
    for start, stop in [(1, 3), (0, 4), (2, 2)]:
        for found, item in zip(source.read_fields(start, stop), seq.fields, strict=True):
            assert found.values.tobytes() == item.values[start:stop].tobytes()
    hook = format_named("npz").cannot_keep
    assert hook is not None and hook(seq) == []


def test_the_keys_are_numbered_and_the_names_in_the_description(tmp_path):
    save_sequence(every_kind(), tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as data:
        keys = set(data.files)
        description = json.loads(str(data["attached"]))
    assert {"V", "F", "attached", "attribute/0/values", "attribute/0/indices"} <= keys
    assert {"attribute/3/values", "face_set/2", "field/0", "field/1"} <= keys
    assert "attribute/1/indices" not in keys
    assert description["face_sets"][2] == {"name": 'éclat/"odd" name', "family": ""}
    assert description["fields"][0] == {
        "name": "velocities",
        "domain": "vertex",
        "role": "velocity",
    }


def test_an_archive_without_them_reads_as_before(tmp_path):
    seq = MeshSequence(wave_sequence(3, 3), grid_faces(3))
    save_sequence(seq, tmp_path / "a.npz")
    with np.load(tmp_path / "a.npz") as data:
        assert "attached" not in data.files
    back = load_sequence(tmp_path / "a.npz")
    assert not back.attached


def test_npy_names_all_it_cannot_keep():
    hook = format_named("npy").cannot_keep
    assert hook is not None
    assert hook(every_kind()) == [
        "attribute 'st'",
        "attribute 'N'",
        "attribute 'id'",
        "attribute 'Cd'",
        "face set 'skin' (materialBind)",
        "face set 'skin' (group)",
        "face set 'éclat/\"odd\" name'",
        "field 'velocities'",
        "field 'heat'",
    ]


def rewritten(path, **changes):
    """The archive at ``path`` with keys replaced (a value of None: removed)."""
    with np.load(path) as data:
        arrays = {key: data[key] for key in data.files}
    for key, value in changes.items():
        if value is None:
            arrays.pop(key)
        else:
            arrays[key] = value
    with zipfile.ZipFile(path, "w") as archive:
        for key, value in arrays.items():
            with archive.open(key + ".npy", "w") as member:
                np.lib.format.write_array(member, np.asarray(value))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"attached": np.array("{not json")}, "key 'attached' is not JSON"),
        ({"attached": np.array([1, 2])}, "key 'attached' must be one string"),
        ({"attribute/1/values": None}, "key 'attribute/1/values': is missing"),
        (
            {"attribute/2/values": np.zeros((5, 1), np.int32)},
            "attribute 'id' has 5 face values, the mesh has 18 faces",
        ),
        ({"attribute/0/indices": np.full(48, 7)}, "element 0 has index 7, outside the 7 values"),
        ({"attribute/1/values": np.zeros((16, 3), np.int64)}, "must be float32, float64 or int32"),
        ({"face_set/0": np.array([0.5])}, "key 'face_set/0': holds float64 values"),
        ({"face_set/1": np.array([18])}, "face set 'skin' names face 18, the mesh has 18 faces"),
        (
            {"field/1": np.zeros((4, 17, 1))},
            r"key 'field/1' \(field 'heat'\) has shape \(4, 17, 1\)",
        ),
        ({"field/0": None}, "key 'field/0' is missing"),
    ],
)
def test_a_damaged_description_or_member_is_named(tmp_path, changes, message):
    path = tmp_path / "a.npz"
    save_sequence(every_kind(), path)
    rewritten(path, **changes)
    with pytest.raises(InputError, match=message) as caught:
        load_sequence(path)
    assert caught.value.path == str(path)


def test_a_non_finite_field_value_names_its_frame(tmp_path):
    path = tmp_path / "a.npz"
    seq = every_kind()
    save_sequence(seq, path)
    heat = seq.fields[1].values.copy()
    heat[2, 5, 0] = np.nan
    rewritten(path, **{"field/1": heat})
    source = NpzFrames(path)
    source.read_fields(0, 2)
    with pytest.raises(
        InputError, match="key 'field/1': field 'heat': face 5 has a non-finite"
    ) as caught:
        source.read_fields(1, 4)
    assert (caught.value.path, caught.value.frame) == (str(path), 2)


# ------------------------------------------------------------------------------------------
# zarr stores: the same layout as arrays of the group


def test_a_zarr_store_keeps_everything_bit_for_bit(tmp_path):
    pytest.importorskip("zarr", reason="zarr (the [zarr] extra) is not installed")
    from tuckercodec.io.zarr_store import ZarrFrames

    seq = every_kind(frames=5)
    save_sequence(seq, tmp_path / "a.zarr")
    back = load_sequence(tmp_path / "a.zarr")
    assert np.array_equal(back.vertices, seq.vertices)
    same(back, seq)
    source = ZarrFrames(tmp_path / "a.zarr")
    for found, item in zip(source.read_fields(2, 4), seq.fields, strict=True):
        assert found.values.tobytes() == item.values[2:4].tobytes()
    hook = format_named("zarr").cannot_keep
    assert hook is not None and hook(seq) == []


def test_a_zarr_store_missing_a_field_array_is_named(tmp_path):
    zarr = pytest.importorskip("zarr", reason="zarr (the [zarr] extra) is not installed")
    save_sequence(every_kind(), tmp_path / "a.zarr")
    group = zarr.open_group(store=str(tmp_path / "a.zarr"), mode="a")
    del group["field/1"]
    with pytest.raises(InputError, match=r"its array 'field/1' \(field 'heat'\) has shape None"):
        load_sequence(tmp_path / "a.zarr")
