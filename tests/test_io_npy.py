"""The ``.npy`` sequence format (tuckercodec/io/npz/npy.py): round trips, faces from ``--faces``,
a range read touching only its range in bounded memory, and broken or crafted files."""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import expect_input_error, measure, write_cube_frames
from tuckercodec import MeshSequence, load_sequence, save_sequence
from tuckercodec.cli import main
from tuckercodec.io import open_frames
from tuckercodec.model import sources as streaming


def npy_file(path: Path, values: np.ndarray) -> Path:
    np.save(path, values, allow_pickle=False)
    return path


def test_the_cloth_round_trips_exactly_as_float32(cloth, tmp_path):
    target = tmp_path / "cloth.npy"
    save_sequence(cloth, target)
    assert np.load(target).dtype == np.float32  # the cloth is float32 data: exact in half
    seq = load_sequence(target)
    assert np.array_equal(seq.vertices, cloth.vertices)
    assert seq.faces.shape == (0, 3)  # a .npy holds positions only


def test_positions_beyond_float32_are_kept_as_float64(tmp_path):
    values = np.random.default_rng(0).standard_normal((4, 5, 3))
    target = tmp_path / "x.npy"
    save_sequence(MeshSequence(values, np.zeros((0, 3))), target)
    assert np.load(target).dtype == np.float64
    assert np.array_equal(load_sequence(target).vertices, values)


@pytest.mark.parametrize("dtype", ["<f4", ">f4", "<f8", ">f8"])
def test_either_byte_order_of_either_precision_reads(tmp_path, dtype):
    values = np.random.default_rng(1).standard_normal((7, 6, 3)).astype(dtype)
    target = npy_file(tmp_path / "x.npy", values)
    with open_frames(target) as source:
        assert np.array_equal(source.read(2, 5), values[2:5].astype(np.float64))
    assert np.array_equal(load_sequence(target).vertices, values.astype(np.float64))


def test_a_single_frame_array_is_one_frame(tmp_path):
    values = np.arange(12, dtype=np.float32).reshape(4, 3)
    seq = load_sequence(npy_file(tmp_path / "one.npy", values))
    assert seq.frame_count == 1 and np.array_equal(seq.vertices[0], values)


def test_faces_come_from_a_mesh_file(tmp_path):
    frames = write_cube_frames(tmp_path, 1)
    values = np.random.default_rng(2).standard_normal((3, 8, 3)).astype(np.float32)
    target = npy_file(tmp_path / "cube.npy", values)
    mesh = load_sequence(frames[0])
    with open_frames(target, faces=frames[0]) as source:
        assert np.array_equal(source.faces, mesh.faces)
    assert np.array_equal(load_sequence(target, faces=frames[0]).faces, mesh.faces)
    other = npy_file(tmp_path / "other.npy", values[:, :5])
    expect_input_error(lambda: open_frames(other, faces=frames[0]), other, match="8 vertices")
    expect_input_error(lambda: open_frames(target, prim="/x"), target, match="--prim")


def test_convert_writes_an_npy_from_the_command_line(cloth, tmp_path, capsys):
    source = tmp_path / "cloth.npz"
    save_sequence(cloth, source)
    assert main(["convert", str(source), str(tmp_path / "cloth.npy")]) == 0
    assert np.array_equal(load_sequence(tmp_path / "cloth.npy").vertices, cloth.vertices)


# ------------------------------------------------------------------------------------------
# only the range


def test_a_bad_frame_outside_the_range_does_not_stop_reading_it(tmp_path):
    values = np.random.default_rng(3).standard_normal((12, 9, 3)).astype(np.float32)
    values[7, 4, 1] = np.nan
    target = npy_file(tmp_path / "nan.npy", values)
    with open_frames(target) as source:
        assert np.array_equal(source.read(0, 7), values[:7].astype(np.float64))
        assert np.array_equal(source.read(8, 12), values[8:].astype(np.float64))
        error = expect_input_error(lambda: source.read(5, 9), target, frame=7, match="vertex 4")
        assert "non-finite" in error.reason
    expect_input_error(lambda: load_sequence(target), target, frame=7, match="vertex 4")


def test_a_range_reads_only_its_bytes(tmp_path, monkeypatch):
    values = np.random.default_rng(4).standard_normal((40, 50, 3))
    target = npy_file(tmp_path / "x.npy", values)
    data = bytearray(target.read_bytes())
    frame = 50 * 3 * 8
    header = len(data) - 40 * frame
    data[header : header + 10 * frame] = b"\xff" * (10 * frame)  # frames 0-9: NaN
    data[header + 30 * frame :] = b"\xff" * (10 * frame)  # frames 30-39: NaN
    target.write_bytes(bytes(data))
    with open_frames(target) as source:
        assert np.array_equal(source.read(10, 30), values[10:30])


def test_reading_a_range_costs_its_float64_array_and_a_bounded_piece(tmp_path, monkeypatch):
    # 400 frames of 4000 vertices of float32: 19 MB on disk; a range of 10 frames is 0.96 MB
    # as float64. Reading the whole file, or the range as float32 and converting it after,
    # would exceed the bound checked here.
    monkeypatch.setattr(streaming, "PIECE_BYTES", 64 * 1024)
    values = np.ones((400, 4000, 3), dtype=np.float32)
    target = npy_file(tmp_path / "big.npy", values)
    del values
    with open_frames(target) as source:
        result: list[np.ndarray] = []
        raised, _, peak = measure(lambda: result.append(source.read(100, 110)))
        assert raised is None
        out = 10 * 4000 * 3 * 8
        frame = 4000 * 3 * 4
        assert peak < out + 64 * 1024 + frame + 64 * 1024, peak  # result, one piece, slack
        assert result[0].shape == (10, 4000, 3) and (result[0] == 1).all()


def test_the_file_is_read_not_mapped(tmp_path, monkeypatch):
    target = npy_file(tmp_path / "x.npy", np.zeros((3, 4, 3), np.float32))

    def refuse(*args, **kwargs):
        raise AssertionError("the reader memory-maps the file")

    monkeypatch.setattr(np, "memmap", refuse)
    monkeypatch.setattr(np, "load", refuse)
    with open_frames(target) as source:
        source.read(0, 3)


# ------------------------------------------------------------------------------------------
# broken or crafted files


def test_a_file_that_is_not_npy_is_refused(tmp_path):
    target = tmp_path / "x.npy"
    target.write_bytes(b"PK\x03\x04 not numpy")
    expect_input_error(lambda: open_frames(target), target, match="signature")
    target.write_bytes(b"")
    expect_input_error(lambda: load_sequence(target), target, match="signature")
    folder = tmp_path / "dir.npy"
    folder.mkdir()
    with pytest.raises(Exception, match="folder"):
        load_sequence(folder)


def header_bytes(text: str, version: int = 1) -> bytes:
    """A .npy header declaring ``text`` (a dict literal), padded as numpy pads it."""
    body = text.encode("latin1")
    size = struct.calcsize("<H" if version == 1 else "<I")
    pad = (-(6 + 2 + size + len(body) + 1)) % 64
    body += b" " * pad + b"\n"
    count = struct.pack("<H" if version == 1 else "<I", len(body))
    return b"\x93NUMPY" + bytes([version, 0]) + count + body


@pytest.mark.parametrize(
    ("header", "match"),
    [
        ("{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3, 3), }", "int32"),
        ("{'descr': '<f2', 'fortran_order': False, 'shape': (2, 3, 3), }", "float16"),
        ("{'descr': '|O', 'fortran_order': False, 'shape': (2, 3, 3), }", "Python objects"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 2), }", "shape"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (0, 3, 3), }", "shape"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (7, 3), }", "truncated"),
        ("{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3, 3), }", "Fortran"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (2, -3, 3), }", "negative"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 3), ", "cannot be read"),
        ("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 3), 1: 2}", "cannot be read"),
        ("{'descr': '<f4', 'shape': (2, 3, 3), }", "cannot be read"),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (10**12, 10**12, 3), }".replace(
                "10**12", str(10**12)
            ),
            "truncated",
        ),
    ],
)
def test_a_bad_header_is_refused_naming_the_file(tmp_path, header, match):
    target = tmp_path / "x.npy"
    target.write_bytes(header_bytes(header) + bytes(2 * 3 * 3 * 4))
    expect_input_error(lambda: open_frames(target), target, match=match)
    expect_input_error(lambda: load_sequence(target), target, match=match)


def test_a_header_of_format_3_is_refused(tmp_path):
    target = tmp_path / "x.npy"
    head = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 3), }"
    target.write_bytes(header_bytes(head, 2).replace(b"\x02\x00", b"\x03\x00", 1) + bytes(72))
    expect_input_error(lambda: open_frames(target), target, match="format 3.0")


def test_a_truncated_or_longer_file_is_refused_with_both_sizes(tmp_path):
    target = npy_file(tmp_path / "x.npy", np.zeros((5, 4, 3), np.float32))
    data = target.read_bytes()
    target.write_bytes(data[:-10])
    expect_input_error(lambda: open_frames(target), target, match="truncated.*10 missing")
    target.write_bytes(data + b"\0" * 3)
    expect_input_error(lambda: open_frames(target), target, match="3 trailing bytes")


def test_a_file_that_shrinks_after_it_is_opened_fails_on_the_read(tmp_path):
    target = npy_file(tmp_path / "x.npy", np.zeros((5, 4, 3), np.float32))
    with open_frames(target) as source:
        source.close()
        target.write_bytes(target.read_bytes()[:-48])
        source.read(0, 4)
        expect_input_error(lambda: source.read(4, 5), target, match="short")
