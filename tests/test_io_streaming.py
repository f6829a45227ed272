"""Reading a sequence a range of frames at a time (tuckercodec/model/sources.py and every
format's ``open``): the same numbers as load_sequence for any range, in every format, after
pickling too; ranges, blocks, options; and the forward decompression of a deflated .npz.

The .npy reader's own tests (only the range is touched, bounded memory, hostile headers) are
tests/test_io_npy.py; zarr's are tests/test_io_zarr.py.
"""

from __future__ import annotations

import pickle
import zipfile

import numpy as np
import pytest

from tests.support.inputs import expect_input_error, write_cube_frames
from tests.support.sequences import shared_file
from tuckercodec import InputError, MeshSequence, load_sequence, save_sequence
from tuckercodec.io import FrameSource, SequenceFrames, open_frames

#: A file of each format the cloth is written to, and the FrameSource class that reads it.
STREAMED = {
    "cloth.npy": "NpyFrames",
    "cloth.npz": "NpzFrames",
    "cloth.pc2": "Pc2Frames",
    "cloth.mdd": "MddFrames",
    "cloth.zarr": "ZarrFrames",
    "cloth.pvd": "PvdFrames",
    "cloth.xdmf": "XdmfFrames",
    "cloth.glb": "GltfFrames",
    "frames": "FileFrames",
}
#: Ranges read from the 60 frames of the cloth: forward, backward, single frames, the whole.
RANGES = [(0, 60), (3, 17), (17, 40), (5, 6), (0, 1), (59, 60), (20, 60), (0, 25)]


def same_description(source: FrameSource, seq: MeshSequence) -> None:
    assert (source.frame_count, source.vertex_count) == (seq.frame_count, seq.vertex_count)
    assert source.faces.dtype == np.int64 and np.array_equal(source.faces, seq.faces)
    assert source.frame_names == seq.frame_names
    assert source.frame_rate == seq.frame_rate
    if seq.time_codes is None:
        assert source.time_codes is None
    else:
        assert source.time_codes is not None and seq.time_codes is not None
        assert np.array_equal(source.time_codes, seq.time_codes)
    assert source.input_bytes == seq.frame_count * seq.vertex_count * 12


def check_ranges(source: FrameSource, expected: np.ndarray) -> None:
    """Every range reads as the loaded sequence's frames, bit for bit, C-contiguous float64."""
    for start, stop in RANGES:
        stop = min(stop, len(expected))
        values = source.read(start, stop)
        assert values.dtype == np.float64 and values.flags.c_contiguous
        assert values.shape == (stop - start, *expected.shape[1:])
        assert np.array_equal(values, expected[start:stop]), (start, stop)
        assert values.tobytes() == expected[start:stop].tobytes()  # -0.0 and 0.0 too


@pytest.mark.parametrize("name", sorted(STREAMED))
def test_every_range_reads_as_load_sequence_gives_it(cloth, tmp_path, name):
    target = tmp_path / name
    save_sequence(cloth, target, progress=False)
    loaded = load_sequence(target, progress=False)
    with open_frames(target) as source:
        assert type(source).__name__ == STREAMED[name]
        same_description(source, loaded)
        check_ranges(source, loaded.vertices)
        assert np.array_equal(source.load().vertices, loaded.vertices)


@pytest.mark.parametrize("name", sorted(STREAMED))
def test_a_source_reads_the_same_after_a_pickle_round_trip(cloth, tmp_path, name):
    target = tmp_path / name
    save_sequence(cloth, target, progress=False)
    expected = load_sequence(target, progress=False).vertices
    with open_frames(target) as source:
        source.read(10, 20)  # files are open now: the pickle must drop them
        copy = pickle.loads(pickle.dumps(source))
        with copy:
            assert type(copy) is type(source)
            check_ranges(copy, expected)
        assert np.array_equal(source.read(30, 31), expected[30:31])  # the original still reads


def test_every_format_streams():
    from tuckercodec.io import formats

    for found in formats():  # a whole sequence by ranges, or a folder of frames file by file
        assert found.open is not None or found.read_frame is not None, f"{found.name} reads none"


def test_a_sequence_in_memory_is_a_source(cloth):
    source = SequenceFrames(cloth)
    same_description(source, cloth)
    check_ranges(source, cloth.vertices)
    assert source.read(0, 5) is not source.read(0, 5)  # copies, never the sequence's own array
    copy = pickle.loads(pickle.dumps(source))
    check_ranges(copy, cloth.vertices)
    assert source.load() is cloth


def test_ranges_outside_the_frames_are_misuse_and_an_empty_range_is_empty(cloth):
    source = SequenceFrames(cloth)
    assert source.read(7, 7).shape == (0, cloth.vertex_count, 3)
    for start, stop in [(-1, 3), (5, 3), (0, 61), (61, 61)]:
        with pytest.raises(ValueError, match="not a range"):
            source.read(start, stop)
    with pytest.raises(TypeError):
        source.read(0.5, 3)  # type: ignore[arg-type]


def test_blocks_cover_every_frame_in_order(cloth):
    source = SequenceFrames(cloth)
    blocks = list(source.blocks(25))
    assert [start for start, _ in blocks] == [0, 25, 50]
    assert [len(block) for _, block in blocks] == [25, 25, 10]
    assert np.array_equal(np.concatenate([block for _, block in blocks]), cloth.vertices)
    with pytest.raises(ValueError, match="at least one frame"):
        next(source.blocks(0))


def test_options_a_format_does_not_take_are_refused_as_by_load_sequence(cloth, tmp_path):
    target = tmp_path / "cloth.npz"
    save_sequence(cloth, target)
    with pytest.raises(InputError, match="--prim"):
        open_frames(target, prim="/Root/mesh")
    with pytest.raises(InputError, match="--fps"):
        open_frames(tmp_path, fps=24)
    with pytest.raises(InputError, match="no such file"):
        open_frames(tmp_path / "missing.npz")


# ------------------------------------------------------------------------------------------
# one frame per file


def test_files_are_read_only_when_their_frames_are(tmp_path):
    files = write_cube_frames(tmp_path, 6)
    files[4].write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")  # another mesh
    with open_frames(tmp_path) as source:
        assert source.frame_count == 6 and source.path == str(tmp_path)
        source.read(0, 4)
        source.read(5, 6)
        expect_input_error(lambda: source.read(3, 6), files[4], line=3, frame=4, match="vertices")


def test_a_list_of_files_streams_in_the_order_given(tmp_path):
    files = write_cube_frames(tmp_path, 4)
    order = [files[2], files[0], files[3]]
    with open_frames(order) as source:
        assert source.path is None
        assert source.frame_names == [file.name for file in order]
        assert np.array_equal(source.read(0, 3), load_sequence(order).vertices)


def test_a_whole_sequence_file_in_a_list_is_refused_naming_it(cloth, tmp_path):
    files = write_cube_frames(tmp_path, 2)
    npz = tmp_path / "x.npz"
    save_sequence(cloth, npz)
    expect_input_error(lambda: open_frames([files[0], npz]), npz, frame=1, match="on its own")


# ------------------------------------------------------------------------------------------
# .npz


def test_a_deflated_npz_is_decompressed_once_when_read_forward(cloth, tmp_path, monkeypatch):
    target = tmp_path / "cloth.npz"
    np.savez_compressed(target, V=cloth.vertices, F=cloth.faces)
    decompressed = []
    original = zipfile.ZipExtFile.read

    def counting(self, n=-1):
        data = original(self, n)
        decompressed.append(len(data))
        return data

    with open_frames(target) as source:
        monkeypatch.setattr(zipfile.ZipExtFile, "read", counting)
        for start in range(0, 60, 7):
            stop = min(start + 7, 60)
            assert np.array_equal(source.read(start, stop), cloth.vertices[start:stop])
        member = cloth.vertices.nbytes
        assert member <= sum(decompressed) < member + 4096  # once, plus the .npy header
        decompressed.clear()
        assert np.array_equal(source.read(2, 3), cloth.vertices[2:3])  # backward: from the start
        assert sum(decompressed) >= 2 * cloth.vertex_count * 24


def test_a_damaged_deflated_npz_fails_on_the_read_that_meets_the_damage(cloth, tmp_path):
    target = tmp_path / "cloth.npz"
    np.savez_compressed(target, V=cloth.vertices)
    data = bytearray(target.read_bytes())
    data[len(data) // 2] ^= 0xFF  # inside V's deflated stream
    target.write_bytes(bytes(data))
    with open_frames(target) as source, pytest.raises(InputError, match="key 'V'") as caught:
        source.read(0, 60)
    assert caught.value.path == str(target)


def test_an_npz_in_fortran_order_is_read_whole(cloth, tmp_path):
    target = tmp_path / "cloth.npz"
    np.savez(target, V=np.asfortranarray(cloth.vertices))
    with open_frames(target) as source:
        source.read(0, 1)  # its frames are scattered over the member: key V is read whole
        target.unlink()  # and held, so that no other range reads the file
        check_ranges(source, cloth.vertices)


def test_an_npz_of_integers_or_one_frame_streams_as_it_loads(tmp_path):
    target = tmp_path / "ints.npz"
    values = np.arange(5 * 4 * 3, dtype=">i2").reshape(5, 4, 3)
    np.savez(target, V=values, frame_rate=np.float64(30))
    with open_frames(target) as source:
        assert np.array_equal(source.read(1, 4), values[1:4].astype(np.float64))
        assert source.frame_rate == 30.0
    single = tmp_path / "one.npz"
    np.savez(single, V=values[0].astype(np.float32))
    with open_frames(single) as source:
        assert source.frame_count == 1
        assert np.array_equal(source.read(0, 1), load_sequence(single).vertices)


def test_npz_metadata_is_checked_when_opened(tmp_path):
    target = tmp_path / "bad.npz"
    np.savez(target, V=np.zeros((3, 4, 3)), frame_files=np.array(["a", "b"]))
    expect_input_error(lambda: open_frames(target), target, match="frame_files")
    np.savez(target, V=np.zeros((3, 4, 3)), time_codes=np.array([0.0, 2.0, 1.0]))
    expect_input_error(lambda: open_frames(target), target, frame=2, match="increase")


# ------------------------------------------------------------------------------------------
# real sequences


# USD and Alembic: tests/test_io_isolated_frames.py, on the cloth (each costs a child or two)
@pytest.mark.parametrize(
    "suffix", ["", ".npy", ".npz", ".pc2", ".mdd", ".zarr", ".pvd", ".xdmf", ".glb"]
)
def test_horse_gallop_streams_as_it_loads(tmp_path, suffix):
    folder = shared_file("horse-gallop")
    expected = load_sequence(folder, progress=False)
    target = folder
    if suffix:
        target = tmp_path / f"horse{suffix}"
        save_sequence(expected, target)
        expected = load_sequence(target)
    with open_frames(target) as source:
        assert np.array_equal(source.read(10, 30), expected.vertices[10:30])
        assert np.array_equal(source.read(47, 48), expected.vertices[47:48])
        assert np.array_equal(source.faces, expected.faces)
        copy = pickle.loads(pickle.dumps(source))
        with copy:
            assert np.array_equal(copy.read(0, 48), expected.vertices)


# ------------------------------------------------------------------------------------------
# series and animations


def test_a_series_reads_a_frame_file_only_when_its_frame_is_read(cloth, tmp_path):
    target = tmp_path / "cloth.pvd"
    save_sequence(cloth, target)
    missing = sorted((tmp_path / "cloth").glob("*.vtp"))[40]
    missing.unlink()
    with open_frames(target) as source:
        assert np.array_equal(source.read(0, 40), cloth.vertices[:40])
        assert np.array_equal(source.read(41, 60), cloth.vertices[41:])
        expect_input_error(lambda: source.read(30, 50), missing, frame=40, match="cannot read")


def test_xdmf_steps_sharing_a_geometry_are_found_across_ranges(cloth, tmp_path):
    target = tmp_path / "cloth.xdmf"
    save_sequence(cloth, target)
    text = target.read_text()
    target.write_text(text.replace("cloth.h5:/points/000005<", "cloth.h5:/points/000001<"))
    with open_frames(target) as source:
        assert np.array_equal(source.read(0, 3), cloth.vertices[:3])
        error = expect_input_error(lambda: source.read(4, 8), target, frame=5, match="static")
        assert "time step 1" in error.reason
    expect_input_error(lambda: load_sequence(target), target, frame=5, match="time step 1")


@pytest.mark.parametrize("fps", [None, 7.0])
@pytest.mark.parametrize("interpolation", ["LINEAR", "CUBICSPLINE"])
def test_a_foreign_gltf_animation_evaluates_every_range_as_it_loads(tmp_path, fps, interpolation):
    from tests.test_io_gltf import _animated  # a file built by hand, with weights and a moving node

    path = _animated(tmp_path, interpolation=interpolation)
    expected = load_sequence(path, fps=fps)
    with open_frames(path, fps=fps) as source:
        same_description(source, expected)
        count = source.frame_count
        for start in range(count):
            for stop in range(start + 1, count + 1):
                assert source.read(start, stop).tobytes() == expected.vertices[start:stop].tobytes()
