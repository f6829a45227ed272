"""Zarr stores as sequences (tuckercodec/io/zarr_store.py): round trips, stores of zarr format
2 and 3 written by zarr itself (a root array, a group), chunk-by-chunk reading, and broken or
crafted stores."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from tests.support.inputs import expect_input_error
from tuckercodec import MeshSequence, load_sequence, save_sequence
from tuckercodec.io import open_frames

zarr = pytest.importorskip("zarr", reason="zarr (the [zarr] extra) is not installed")


def test_the_cloth_round_trips_with_faces_names_rate_and_time_codes(cloth, tmp_path):
    seq = MeshSequence(
        cloth.vertices,
        cloth.faces,
        frame_names=[f"shot_{n}" for n in range(cloth.frame_count)],
        frame_rate=30.0,
        time_codes=np.arange(cloth.frame_count) * 2.0 + 101,
    )
    target = tmp_path / "cloth.zarr"
    save_sequence(seq, target)
    store = zarr.open_group(str(target), mode="r")
    assert store["vertices"].dtype == np.float32  # exact for the cloth
    assert store["vertices"].chunks == (60, cloth.vertex_count, 3)  # at most 100 frames
    back = load_sequence(target)
    assert np.array_equal(back.vertices, seq.vertices)
    assert np.array_equal(back.faces, seq.faces)
    assert back.frame_names == seq.frame_names and back.frame_rate == 30.0
    assert back.time_codes is not None and seq.time_codes is not None
    assert np.array_equal(back.time_codes, seq.time_codes)


def test_a_long_sequence_is_chunked_by_100_frames_and_float64_stays(tmp_path):
    values = np.random.default_rng(0).standard_normal((250, 7, 3))
    target = tmp_path / "long.zarr"
    save_sequence(MeshSequence(values, np.zeros((0, 3))), target)
    array = zarr.open_group(str(target), mode="r")["vertices"]
    assert array.chunks == (100, 7, 3) and array.dtype == np.float64
    with open_frames(target) as source:
        assert np.array_equal(source.read(95, 205), values[95:205])


def test_writing_never_replaces_a_store_unasked_and_replaces_it_whole(cloth, tmp_path):
    target = tmp_path / "x.zarr"
    save_sequence(cloth, target)
    with pytest.raises(FileExistsError):
        save_sequence(cloth, target)
    small = MeshSequence(cloth.vertices[:3, :10], np.zeros((0, 3)))
    save_sequence(small, target, overwrite=True)
    assert not (target / "faces").exists()  # nothing of the old store is left
    assert np.array_equal(load_sequence(target).vertices, small.vertices)
    assert [p.name for p in tmp_path.iterdir()] == ["x.zarr"]  # no staging folder left


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_root_array_of_either_zarr_format_is_a_point_sequence(tmp_path, zarr_format):
    values = np.random.default_rng(1).standard_normal((9, 5, 3)).astype(np.float32)
    target = tmp_path / "root.zarr"
    array = zarr.create_array(
        store=str(target),
        shape=values.shape,
        chunks=(4, 5, 3),
        dtype="f4",
        zarr_format=zarr_format,
    )
    array[:] = values
    with open_frames(target) as source:
        assert source.faces.shape == (0, 3)
        assert np.array_equal(source.read(3, 9), values[3:9].astype(np.float64))
    assert np.array_equal(load_sequence(target).vertices, values.astype(np.float64))


@pytest.mark.parametrize("zarr_format", [2, 3])
def test_a_group_of_either_format_gives_its_faces_and_attributes(tmp_path, zarr_format):
    values = np.arange(4 * 4 * 3, dtype=np.int32).reshape(4, 4, 3)
    target = tmp_path / "group.zarr"
    group = zarr.create_group(store=str(target), zarr_format=zarr_format)
    group.create_array("vertices", data=values, chunks=(1, 4, 3))
    group.create_array("faces", data=np.array([[0, 1, 2, 3]], dtype=np.uint32))
    group.attrs.update({"frame_rate": 25, "frame_names": list("abcd")})
    seq = load_sequence(target)
    assert np.array_equal(seq.vertices, values.astype(np.float64))
    assert seq.faces.tolist() == [[0, 1, 2, 3]]
    assert seq.frame_rate == 25.0 and seq.frame_names == list("abcd")


def test_only_the_chunks_of_a_range_are_read(tmp_path):
    values = np.random.default_rng(2).standard_normal((300, 6, 3))
    target = tmp_path / "x.zarr"
    save_sequence(MeshSequence(values, np.zeros((0, 3))), target)
    chunks = sorted(
        p for p in (target / "vertices").rglob("*") if p.is_file() and p.name != "zarr.json"
    )
    assert len(chunks) == 3
    shutil.rmtree(target / "vertices" / "c" / "2")  # frames 200-299: lost
    with open_frames(target) as source:
        assert np.array_equal(source.read(50, 200), values[50:200])
        # a lost chunk reads as the writer's fill value, NaN: refused, naming the frame
        expect_input_error(lambda: source.read(150, 250), target, frame=200, match="non-finite")


def test_a_store_that_is_not_one_is_refused_naming_it(tmp_path):
    empty = tmp_path / "empty.zarr"
    empty.mkdir()
    expect_input_error(lambda: open_frames(empty), empty, match="zarr store")
    file = tmp_path / "file.zarr"
    file.write_bytes(b"not a folder")
    expect_input_error(lambda: load_sequence(file), file, match="not a zarr store")
    group = tmp_path / "group.zarr"
    zarr.create_group(store=str(group)).create_array("V", shape=(2, 3, 3), dtype="f4")
    expect_input_error(lambda: open_frames(group), group, match="no array 'vertices'.*'V'")


@pytest.mark.parametrize(
    ("shape", "dtype", "chunks", "match"),
    [
        ((2, 3, 2), "f4", None, "shape"),
        ((2, 3), "f4", None, "shape"),
        ((2, 3, 3), "bool", None, "bool"),
        ((2, 3, 3), "complex64", None, "complex"),
        ((0, 3, 3), "f4", None, "at least one frame"),
        ((20000, 20000, 3), "f4", (20000, 20000, 3), "rechunk"),
    ],
)
def test_an_array_that_is_not_positions_is_refused(tmp_path, shape, dtype, chunks, match):
    target = tmp_path / "x.zarr"
    zarr.create_array(store=str(target), shape=shape, dtype=dtype, chunks=chunks or "auto")
    expect_input_error(lambda: open_frames(target), target, match=match)


def test_chunks_and_faces_beyond_max_memory_are_refused_before_reading(tmp_path):
    """A decompression bomb: a chunk is decompressed whole, and the faces read whole."""
    target = tmp_path / "x.zarr"
    group = zarr.create_group(store=str(target))
    group.create_array("vertices", data=np.zeros((4, 1000, 3)), chunks=(2, 1000, 3))
    assert load_sequence(target, max_memory=48_000).frame_count == 4  # a chunk: 48,000 bytes
    expect_input_error(
        lambda: open_frames(target, max_memory=47_999),
        target,
        match=r"chunks \(2, 1000, 3\) of 48000 bytes, more than the 47999 read at once",
    )
    group.create_array("faces", data=np.zeros((4000, 3), dtype=np.int64))  # 96,000 bytes
    expect_input_error(
        lambda: open_frames(target, max_memory=95_999), target, match="'faces' .* too many"
    )


def test_bad_faces_or_attributes_are_refused(tmp_path):
    target = tmp_path / "x.zarr"
    group = zarr.create_group(store=str(target))
    group.create_array("vertices", data=np.zeros((2, 3, 3)))
    group.create_array("faces", data=np.array([[0, 1, 3]]))
    expect_input_error(lambda: open_frames(target), target, match="index 3 outside")
    del group["faces"]
    group.attrs["frame_rate"] = "fast"
    expect_input_error(lambda: open_frames(target), target, match="frame_rate")
    group.attrs["frame_rate"] = -1
    expect_input_error(lambda: open_frames(target), target, match="positive")
    del group.attrs["frame_rate"]
    group.attrs["frame_names"] = ["a"]
    expect_input_error(lambda: open_frames(target), target, match="1 frame names")
    group.attrs["frame_names"] = ["a", "b"]
    group.attrs["time_codes"] = [1, "x"]
    expect_input_error(lambda: open_frames(target), target, match="time_codes")


def test_a_damaged_chunk_is_an_input_error_naming_the_frames(cloth, tmp_path):
    target = tmp_path / "x.zarr"
    save_sequence(cloth, target)
    chunk = next(p for p in (target / "vertices" / "c").rglob("*") if p.is_file())
    chunk.write_bytes(b"\0" * 40)
    with open_frames(target) as source:
        expect_input_error(lambda: source.read(0, 10), target, frame=0, match="cannot be read")
