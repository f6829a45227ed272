"""The .npz sequence format (tuckercodec/io/npz/): round trips, the variants it accepts, and
broken, corrupt or crafted archives.

A bad archive ends in an :class:`InputError` that names the file (and the key, and the frame
where it applies), quickly and in small memory: never another exception type, a pickle load, or
an allocation driven by a size the file cannot back (a lying .npy header, a zip bomb). The
property tests feed random bytes, mutated archives, mutated .npy members in a sound zip and any
.npy header, and accept only an InputError or a valid sequence.
"""

from __future__ import annotations

import functools
import io
import math
import pickle
import re
import shutil
import struct
import warnings
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.support.inputs import (
    CUBE_VERTICES,
    check_sequence,
    expect_input_error,
    measure,
    write_file,
)
from tests.support.properties import PROPERTY, mutations, report_examples, scratch_folder
from tests.support.sequences import shared_file
from tuckercodec import InputError, MeshSequence
from tuckercodec.cli import main
from tuckercodec.io import load_sequence, open_frames, save_sequence


def npz_bytes(compressed: bool = False, /, **arrays: Any) -> bytes:
    """The bytes of an .npz archive of ``arrays`` (stored, or deflated like savez_compressed)."""
    buffer = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buffer, **arrays)
    return buffer.getvalue()


def npy_bytes(header: dict[str, Any], payload: bytes) -> bytes:
    """A .npy member with any header at all (numpy's own writer would refuse some) and payload."""
    text = repr(header).encode("latin1")
    size = len(text) + 1  # the newline
    if size < 65000:  # version 1.0: a 2-byte header length
        padding = (64 - (10 + size) % 64) % 64
        prefix = b"\x93NUMPY\x01\x00" + struct.pack("<H", size + padding)
    else:  # version 2.0: 4 bytes
        padding = (64 - (12 + size) % 64) % 64
        prefix = b"\x93NUMPY\x02\x00" + struct.pack("<I", size + padding)
    return prefix + text + b" " * padding + b"\n" + payload


def zip_bytes(members: dict[str, bytes], compression: int = zipfile.ZIP_STORED) -> bytes:
    """A zip archive of the given members."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression) as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    return buffer.getvalue()


def _members(arrays: dict[str, np.ndarray]) -> dict[str, bytes]:
    """The .npy bytes of each array."""
    out = {}
    for name, array in arrays.items():
        buffer = io.BytesIO()
        np.lib.format.write_array(buffer, array, allow_pickle=False)
        out[name] = buffer.getvalue()
    return out


V3 = np.arange(2 * 3 * 3, dtype=np.float64).reshape(2, 3, 3)


TRI = np.array([[0, 1, 2]])


# ------------------------------------------------------------------------------------------
# reading and writing


def test_npz_round_trip(tmp_path: Path) -> None:
    seq = MeshSequence(
        np.random.default_rng(0).standard_normal((4, 8, 3)),
        np.array([[0, 1, 2, 3], [4, 5, 6, -1]]),
        frame_names=["a", "b", "c", "d"],
        frame_rate=25.0,
    )
    path = tmp_path / "seq.npz"
    save_sequence(seq, path)
    again = load_sequence(path)
    np.testing.assert_array_equal(again.vertices, seq.vertices)
    np.testing.assert_array_equal(again.faces, seq.faces)
    assert again.frame_names == seq.frame_names and again.frame_rate == 25.0
    with pytest.raises(FileExistsError, match=r"seq\.npz"):
        save_sequence(seq, path)
    save_sequence(seq, path, overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seq.npz"]


def test_npz_single_frame_and_no_faces(tmp_path: Path) -> None:
    path = tmp_path / "one.npz"
    np.savez(path, V=CUBE_VERTICES.astype(np.float32))
    seq = load_sequence(path)
    assert (seq.frame_count, seq.vertex_count, seq.faces.shape) == (1, 8, (0, 3))


def test_npz_accepted_variants(tmp_path: Path) -> None:
    # one frame as (K, 3), float32, big-endian, Fortran order, int, unsigned faces, -1 padding
    cases = [
        {"V": V3[0].astype(np.float32)},
        {"V": V3.astype(">f8"), "F": TRI.astype(">i4")},
        {"V": np.asfortranarray(V3), "F": np.asfortranarray(TRI)},
        {"V": V3.astype(np.int16), "F": np.array([[0, 1, 2, -1], [2, 1, 0, 1]])},
        {"V": V3, "F": TRI.astype(np.uint8), "extra": np.array([1, 2])},
        {"V": V3, "F": np.zeros((0,), dtype=np.float64)},  # an empty F: a point cloud
    ]
    for number, arrays in enumerate(cases):
        path = write_file(tmp_path / f"ok{number}.npz", npz_bytes(**arrays))
        seq = load_sequence(path)
        check_sequence(seq)
        np.testing.assert_array_equal(seq.vertices.reshape(-1, 3), arrays["V"].reshape(-1, 3))


@pytest.mark.parametrize(
    "header",
    [
        b"{'descr': '<f8', 'fortran_order': False, 'shape': (2L, 3L, 3L), }",  # Python 2
        b"{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3, 3), }\n  ",  # a line break
    ],
)
def test_python2_headers_are_read_without_a_warning(tmp_path: Path, header: bytes) -> None:
    # numpy reads both after rewriting the header, and warns; warnings are errors in the tests
    size = len(header) + 1
    padding = (64 - (10 + size) % 64) % 64
    member = b"\x93NUMPY\x01\x00" + struct.pack("<H", size + padding) + header
    member += b" " * padding + b"\n" + V3.tobytes()
    path = write_file(tmp_path / "py2.npz", zip_bytes({"V.npy": member}))
    np.testing.assert_array_equal(load_sequence(path).vertices, V3)


def test_a_deprecated_dtype_alias_is_read_without_a_warning(tmp_path: Path) -> None:
    # 'a' is numpy's deprecated alias of 'S', and np.dtype warns about it
    members = {f"{name}.npy": npy for name, npy in _members({"V": V3}).items()}
    names = {"descr": "|a1", "fortran_order": False, "shape": (2,)}
    members["frame_files.npy"] = npy_bytes(names, b"pq")
    path = write_file(tmp_path / "alias.npz", zip_bytes(members))
    assert load_sequence(path).frame_names == ["p", "q"]


@pytest.mark.parametrize(
    ("name", "shape"),
    [
        ("cloth-vellum.npz", (60, 3101, 5912)),
        ("samba.npz", (175, 9971, 19938)),
        ("chicken.npz", (400, 3030, 5664)),
    ],
)
def test_shared_npz_sequences(name: str, shape: tuple[int, int, int]) -> None:
    path = shared_file(name)
    seq = load_sequence(path)
    assert (seq.frame_count, seq.vertex_count, len(seq.faces)) == shape
    with np.load(path, allow_pickle=False) as data:
        np.testing.assert_array_equal(seq.vertices, data["V"])


# ------------------------------------------------------------------------------------------
# bad arrays: each names the file and the key


@pytest.mark.parametrize(
    ("arrays", "key", "message"),
    [
        ({"X": np.zeros((2, 3, 3))}, "'V'", "missing key"),
        ({"V": np.array([["a", "b", "c"]])}, "'V'", "real numbers"),
        ({"V": np.array([[[0, 0, 0]]], dtype=object)}, "'V'", "Python objects"),
        ({"V": np.zeros((2, 3, 2))}, "'V'", "shape"),
        ({"V": np.full((2, 3, 3), np.nan)}, "'V'", "non-finite"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([[0.0, 1.0, 2.0]])}, "'F'", "integer"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([0, 1, 2])}, "'F'", "shape"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([[1, 2, 3]])}, "'F'", "1-based"),
        ({"V": np.zeros((2, 3, 3)), "frame_files": np.array(["a"])}, "'frame_files'", "2 strings"),
        ({"V": np.zeros((2, 3, 3)), "frame_rate": np.array(-1.0)}, "'frame_rate'", "positive"),
    ],
)
def test_bad_npz_names_file_and_key(
    tmp_path: Path, arrays: dict[str, Any], key: str, message: str
) -> None:
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(InputError, match=message) as caught:
        load_sequence(path)
    assert caught.value.path == str(path)
    assert key in str(caught.value)


def _code_points(*points: int) -> np.ndarray:
    """Two one-character names holding these code points as numpy stores them, unchecked."""
    return np.frombuffer(np.array(points, dtype="<u4").tobytes(), dtype="<U1")


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        # keys
        ({}, "missing key 'V'"),
        ({"X": V3}, r"missing key 'V'.*\['X'\]"),
        ({"v": V3, "f": TRI}, r"missing key 'V'.*\['f', 'v'\]"),
        # dtypes of V
        ({"V": np.array([[["a", "b", "c"]]])}, "'V' must hold real numbers, got dtype <U1"),
        ({"V": np.array([[[b"a", b"b", b"c"]]])}, "'V' must hold real numbers"),
        ({"V": V3.astype(complex)}, "'V' must hold real numbers, got dtype complex128"),
        ({"V": V3 > 1}, "'V' must hold real numbers, got dtype bool"),
        ({"V": np.zeros((1, 3), dtype="i4,i4,i4")}, "'V' must hold real numbers"),
        ({"V": np.zeros((1, 3, 3), dtype="datetime64[s]")}, "'V' must hold real numbers"),
        ({"V": np.array([[[0, 0, 0]]], dtype=object)}, "'V' holds Python objects"),
        # shapes of V
        ({"V": np.zeros(9)}, r"'V' must have shape \(frames, vertices, 3\), got \(9,\)"),
        ({"V": np.zeros((3, 2))}, "'V' must have shape"),
        ({"V": np.zeros((2, 3, 4))}, r"got \(2, 3, 4\)"),
        ({"V": np.zeros((2, 3, 3, 1))}, "'V' must have shape"),
        ({"V": np.zeros((0, 3, 3))}, "'V' must have shape"),
        ({"V": np.zeros((2, 0, 3))}, "'V' must have shape"),
        ({"V": np.zeros((0,))}, "'V' must have shape"),
        ({"V": np.float64(1.0)}, "'V' must have shape"),
        # F
        ({"V": V3, "F": np.array([[0.0, 1.0, 2.0]])}, "'F' must hold integer"),
        ({"V": V3, "F": np.array([[True, False, True]])}, "'F' must hold integer"),
        ({"V": V3, "F": np.array([["0", "1", "2"]])}, "'F' must hold integer"),
        ({"V": V3, "F": np.array([[0, 1, 2]], dtype=object)}, "'F' holds Python objects"),
        ({"V": V3, "F": np.array([[0, 1], [1, 2]])}, r"'F' must have shape .* got \(2, 2\)"),
        ({"V": V3, "F": np.array([0, 1, 2])}, "'F' must have shape"),
        ({"V": V3, "F": np.zeros((1, 3, 1), dtype=int)}, "'F' must have shape"),
        (
            {"V": V3, "F": np.array([[0, 1, -2]])},
            r"'F': face 0 has a vertex index -2 outside 0\.\.2",
        ),
        ({"V": V3, "F": np.array([[0, 1, 3]])}, "1-based"),
        ({"V": V3, "F": np.array([[0, 1, 7]])}, r"outside 0\.\.2"),
        ({"V": V3, "F": np.array([[0, 1, 2**62]])}, r"outside 0\.\.2"),
        (
            {"V": V3, "F": np.array([[0, -1, 1, 2]])},
            "face 0 is padded before its end",
        ),  # padding inside
        (
            {"V": V3, "F": np.array([[0, 1, -1]])},
            "face 0 is padded before its end",
        ),  # under 3 corners
        # unsigned indices that a cast to int64 would turn into -1 padding
        ({"V": V3, "F": np.array([[0, 1, 2, 2**64 - 1]], dtype=np.uint64)}, r"outside 0\.\.2"),
        # frame names and rate
        ({"V": V3, "frame_files": np.array(["a"])}, "'frame_files' must be 2 strings"),
        ({"V": V3, "frame_files": np.array([1, 2])}, "'frame_files' must be 2 strings"),
        ({"V": V3, "frame_files": np.array(["a", "b"], dtype=object)}, "Python objects"),
        ({"V": V3, "frame_files": np.array([b"a", b"\xff"])}, "not UTF-8"),
        # numpy stores code points it never checks: one beyond Unicode, and a lone surrogate
        ({"V": V3, "frame_files": _code_points(0x61, 0x110000)}, "not Unicode"),
        ({"V": V3, "frame_files": _code_points(0x61, 0xD800)}, "not Unicode"),
        ({"V": V3, "frame_rate": np.array(np.nan)}, "'frame_rate' must be a positive"),
        ({"V": V3, "frame_rate": np.array([25.0, 30.0])}, "'frame_rate' must be one number"),
        ({"V": V3, "frame_rate": np.array("25")}, "'frame_rate' must be one number"),
    ],
)
def test_bad_npz_is_refused_naming_file_and_key(
    tmp_path: Path, arrays: dict[str, np.ndarray], message: str
) -> None:
    path = write_file(tmp_path / "bad.npz", npz_bytes(**arrays))
    expect_input_error(lambda: load_sequence(path), path, match=message)
    compressed = write_file(tmp_path / "bad_compressed.npz", npz_bytes(True, **arrays))
    expect_input_error(lambda: load_sequence(compressed), compressed, match=message)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, "overflow"])
def test_npz_non_finite_vertex_names_its_frame(tmp_path: Path, bad: float | str) -> None:
    values = V3.copy()
    if bad == "overflow":  # finite in long double, infinite in float64 (where they differ)
        if np.finfo(np.longdouble).max == np.finfo(np.float64).max:
            pytest.skip("long double is float64 here")
        values = values.astype(np.longdouble)
        values[1, 2, 0] = np.finfo(np.longdouble).max
    else:
        values[1, 2, 0] = bad
    path = write_file(tmp_path / "nan.npz", npz_bytes(V=values))
    expect_input_error(lambda: load_sequence(path), path, frame=1, match="vertex 2 .*non-finite")


class _Trap:
    """Unpickling this would create the file named by ``target``: it must never happen."""

    def __init__(self, target: str) -> None:
        self.target = target

    def __reduce__(self) -> tuple[Any, ...]:
        return (open, (self.target, "w"))


def test_pickles_are_never_loaded(tmp_path: Path) -> None:
    trap = tmp_path / "pickle-was-loaded"
    payload = pickle.dumps(np.array([_Trap(str(trap))], dtype=object), protocol=3)
    header = {"descr": "|O", "fortran_order": False, "shape": (1,)}
    for key in ("V", "F", "frame_files", "frame_rate"):
        members = {
            "V.npy": npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24))
        }
        members[f"{key}.npy"] = npy_bytes(header, payload)
        path = write_file(tmp_path / f"{key}.npz", zip_bytes(members))
        expect_input_error(functools.partial(load_sequence, path), path, match="Python objects")
        assert not trap.exists()
    # a structured dtype with an object field is just as much a pickle
    header = {"descr": [("a", "|O")], "fortran_order": False, "shape": (1,)}
    path = write_file(tmp_path / "field.npz", zip_bytes({"V.npy": npy_bytes(header, payload)}))
    expect_input_error(lambda: load_sequence(path), path, match="Python objects")
    assert not trap.exists()


# ------------------------------------------------------------------------------------------
# bad archives: not a zip, cut, damaged, crafted


def test_not_an_npz(tmp_path: Path) -> None:
    path = write_file(tmp_path / "fake.npz", b"this is not a zip archive")
    with pytest.raises(InputError, match="npz") as caught:
        load_sequence(path)
    assert caught.value.path == str(path)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "not an .npz"),
        (b"this is not a zip archive", "not an .npz"),
        (b"PK", "npz"),
        (b"PK\x03\x04" + bytes(40), "npz"),
        (zip_bytes({}), "missing key 'V'"),
        (zip_bytes({"readme.txt": b"hello"}), r"missing key 'V'.*readme\.txt"),
        (zip_bytes({"V.npy": b"hello, not an array"}), "'V' is not a NumPy array"),
        (zip_bytes({"V": b"raw bytes under the bare key"}), "'V' is not a NumPy array"),
        (zip_bytes({"V.npy": b"\x93NUMPY\x09\x00"}), "'V' is in .npy format 9.0"),
        (zip_bytes({"V.npy": b"\x93NUMPY\x01\x00\x10\x00{'descr': '<f8'}"}), "'V' cannot be read"),
        # an unclosed bracket: numpy's tokenize raised TokenError, no ValueError
        (
            zip_bytes({"V.npy": b"\x93NUMPY\x01\x00\x10\x00{'descr': ('<f8' \n"}),
            "'V' cannot be read",
        ),
    ],
)
def test_files_that_are_not_npz(tmp_path: Path, data: bytes, message: str) -> None:
    path = write_file(tmp_path / "odd.npz", data)
    expect_input_error(lambda: load_sequence(path), path, match=message)


def test_a_truncated_npz_at_every_offset(tmp_path: Path) -> None:
    for compressed in (False, True):
        whole = npz_bytes(compressed, V=V3, F=TRI, frame_files=np.array(["a", "b"]))
        path = tmp_path / "cut.npz"
        for end in range(len(whole)):
            write_file(path, whole[:end])
            expect_input_error(functools.partial(load_sequence, path), path)
        write_file(path, whole)
        check_sequence(load_sequence(path))


def test_damaged_array_data_is_caught_by_the_crc(tmp_path: Path) -> None:
    whole = bytearray(npz_bytes(V=V3))
    data_at = bytes(whole).find(V3.tobytes())
    whole[data_at + 5] ^= 0x10  # one bit of one coordinate
    path = write_file(tmp_path / "flipped.npz", bytes(whole))
    expect_input_error(lambda: load_sequence(path), path, match="'V'.*CRC")


def test_an_npy_member_with_trailing_bytes(tmp_path: Path) -> None:
    # Not what numpy writes; and the bytes after the array would escape the CRC check.
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24) + b"x")
    path = write_file(tmp_path / "trailing.npz", zip_bytes({"V.npy": member}))
    expect_input_error(lambda: load_sequence(path), path, match="'V'.*25 bytes")


def test_a_key_stored_twice(tmp_path: Path) -> None:
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24))
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns of the duplicate name: that is the point
        archive.writestr("V.npy", member)
        archive.writestr("V.npy", member)
    path = write_file(tmp_path / "twice.npz", buffer.getvalue())
    expect_input_error(lambda: load_sequence(path), path, match="'V' twice")


@pytest.mark.parametrize(
    ("header", "payload", "message"),
    [
        # a billion by a billion vertices in a few hundred bytes
        (
            {"descr": "<f8", "fortran_order": False, "shape": (10**9, 10**9, 3)},
            bytes(64),
            "'V' declares",
        ),
        (
            {"descr": "<f8", "fortran_order": False, "shape": (10**4, 10**4, 3)},
            bytes(64),
            "'V' declares",
        ),
        ({"descr": "<U1000000000", "fortran_order": False, "shape": (1,)}, bytes(8), "'V' cannot"),
        ({"descr": "<f8", "fortran_order": False, "shape": (2**62, 2**62, 3)}, b"", "'V' declares"),
        # shapes and headers numpy itself would choke on
        (
            {"descr": "<f8", "fortran_order": False, "shape": (-1, 3, 3)},
            bytes(72),
            "'V' .*negative",
        ),
        (
            {"descr": "<f8", "fortran_order": False, "shape": (-1, -3, 3)},
            bytes(72),
            "'V' .*negative",
        ),
        ({"descr": "<f8", "fortran_order": False, "shape": (1,) * 70}, bytes(8), "'V'"),
        (
            {"descr": "<f8", "fortran_order": "yes", "shape": (1, 3)},
            bytes(24),
            "'V' cannot be read",
        ),
        (
            {"descr": "<q9", "fortran_order": False, "shape": (1, 3)},
            bytes(24),
            "'V' cannot be read",
        ),
        ({"descr": "<f8", "shape": (1, 3)}, bytes(24), "'V' cannot be read"),
        # numpy sorts the keys: TypeError on keys of mixed types, not a ValueError
        (
            {b"x": 1, "descr": "<f8", "fortran_order": False, "shape": (1, 3)},
            bytes(24),
            "'V' cannot",
        ),
        ({1: 2, "descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24), "'V' cannot"),
        # np.dtype(",<f8") raises SyntaxError (from ast.literal_eval), not a ValueError
        ({"descr": ",<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24), "'V' cannot"),
        ({"descr": "f8,(", "fortran_order": False, "shape": (1, 3)}, bytes(24), "'V' cannot"),
        (
            {"descr": "<f8", "fortran_order": False, "shape": "(1, 3)"},
            bytes(24),
            "'V' cannot be read",
        ),
    ],
)
def test_hostile_npy_headers_allocate_nothing(
    tmp_path: Path, header: dict[str, Any], payload: bytes, message: str
) -> None:
    for compression in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        path = write_file(
            tmp_path / "huge.npz", zip_bytes({"V.npy": npy_bytes(header, payload)}, compression)
        )
        raised, _, peak = measure(functools.partial(load_sequence, path))
        assert isinstance(raised, InputError) and raised.path == str(path), raised
        assert re.search(message, str(raised)), raised
        assert peak < 4 * 2**20, peak


def test_a_huge_header_is_refused(tmp_path: Path) -> None:
    header = {"descr": "<f8", "fortran_order": False, "shape": (1, 3), "x": "y" * 200_000}
    path = write_file(tmp_path / "header.npz", zip_bytes({"V.npy": npy_bytes(header, bytes(24))}))
    expect_input_error(lambda: load_sequence(path), path, match="'V' cannot be read")


def test_a_zip_bomb_member_is_refused_before_inflating(tmp_path: Path) -> None:
    # A deflated member that claims a gigabyte from a kilobyte: deflate expands at most about
    # 1032 times, so the claim is false and nothing is allocated or inflated for it.
    header = {"descr": "<f8", "fortran_order": False, "shape": (2**27, 1, 1)}
    head = npy_bytes(header, b"")
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    body = compressor.compress(head + bytes(2**20)) + compressor.flush()
    path = tmp_path / "bomb.npz"
    write_file(path, _zip_with_sizes("V.npy", body, zipfile.ZIP_DEFLATED, len(head) + 2**30, 0))
    load_sequence(zeros_npz(tmp_path / "small.npz", V=((1, 4, 3), "<f8")))  # imports done first
    raised, _, peak = measure(lambda: load_sequence(path))
    assert isinstance(raised, InputError) and "expand" in str(raised), raised
    assert peak < 4 * 2**20  # no time limit: a test may not assume how fast a machine runs


def zeros_npz(path: Path, **shapes: tuple[tuple[int, ...], str]) -> Path:
    """An archive of deflated members of zeros, ``key=(shape, dtype)``, written a MiB at a
    time (never a whole array in memory)."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for key, (shape, dtype) in shapes.items():
            with archive.open(f"{key}.npy", "w", force_zip64=True) as member:
                header = {"descr": np.dtype(dtype).str, "fortran_order": False, "shape": shape}
                np.lib.format.write_array_header_1_0(member, header)
                left = math.prod(shape) * np.dtype(dtype).itemsize
                while left:
                    member.write(bytes(min(left, 2**20)))
                    left -= min(left, 2**20)
    return path


def test_an_honest_bomb_is_refused_beyond_max_memory_before_inflating(tmp_path, capsys):
    """A decompression bomb: a member of zeros that declares, truly, the size it inflates to
    (1,100 times its own) is bounded by --max-memory; reading a range at a time still works."""
    path = zeros_npz(tmp_path / "bomb.npz", V=((64, 2**16, 3), "<f8"))  # 96 MiB from 94 KB
    limit = 16 * 2**20
    small = zeros_npz(tmp_path / "small.npz", V=((1, 4, 3), "<f8"))
    load_sequence(small)  # the reader's modules imported before measuring
    raised, _, peak = measure(lambda: load_sequence(path, max_memory=limit))
    assert isinstance(raised, InputError) and raised.path == str(path), raised
    assert "key 'V' (V.npy): inflates to 101 MB, beyond the 16.8 MB" in str(raised)
    assert peak < 2**20, peak  # nothing inflated
    with open_frames(path, max_memory=limit) as frames:  # a range at a time: what fits
        assert frames.read(0, 1).shape == (1, 2**16, 3)
    out = tmp_path / "out.pc2"
    assert main(["convert", str(path), str(out), "--max-memory", "16MiB"]) == 4
    said = capsys.readouterr().err
    assert said.count("\n") == 1 and said.startswith(f"tuckercodec: bad input: {path}"), said
    assert "beyond the 16.8 MB a read may decompress" in said and not out.exists()


def test_the_keys_read_whole_share_the_ceiling(tmp_path: Path) -> None:
    faces = ((2**18, 3), "<i8")  # 6 MiB
    path = zeros_npz(tmp_path / "faces.npz", V=((1, 4, 3), "<f8"), F=faces, time_codes=faces)
    # zero faces are degenerate: what matters is how far the reading goes
    expect_input_error(lambda: load_sequence(path, max_memory=2**20), path, match="key 'F' ")
    expect_input_error(
        lambda: load_sequence(path, max_memory=7 * 2**20),
        path,
        match=r"key 'time_codes' \(time_codes.npy\): inflates to 6.29 MB beside the 6.29 MB",
    )


def _zip_with_sizes(name: str, body: bytes, method: int, file_size: int, crc: int) -> bytes:
    """One zip member with the given (compressed) body and whatever sizes and CRC we claim."""
    encoded = name.encode()
    local = struct.pack(
        "<4s5H3L2H", b"PK\x03\x04", 20, 0, method, 0, 0, crc, len(body), file_size, len(encoded), 0
    )
    central_at = len(local) + len(encoded) + len(body)
    central = struct.pack(
        "<4s6H3L5H2L",
        b"PK\x01\x02",
        20,
        20,
        0,
        method,
        0,
        0,
        crc,
        len(body),
        file_size,
        len(encoded),
        0,
        0,
        0,
        0,
        0,
        0,
    )
    end = struct.pack(
        "<4s4H2LH", b"PK\x05\x06", 0, 0, 1, 1, len(central) + len(encoded), central_at, 0
    )
    return local + encoded + body + central + encoded + end


def test_a_stored_member_larger_than_the_file(tmp_path: Path) -> None:
    header = {"descr": "<f8", "fortran_order": False, "shape": (2**27, 1, 1)}
    head = npy_bytes(header, b"")
    path = write_file(
        tmp_path / "stored.npz",
        _zip_with_sizes("V.npy", head + bytes(64), zipfile.ZIP_STORED, len(head) + 2**30, 0),
    )
    raised, _, peak = measure(lambda: load_sequence(path))
    assert isinstance(raised, InputError) and raised.path == str(path), raised
    assert peak < 4 * 2**20


def test_encrypted_and_unsupported_members(tmp_path: Path) -> None:
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24))
    data = bytearray(zip_bytes({"V.npy": member}))
    encrypted = bytearray(data)
    for signature, flag_at in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):
        at = bytes(encrypted).find(signature) + flag_at
        encrypted[at] |= 1
    path = write_file(tmp_path / "encrypted.npz", bytes(encrypted))
    expect_input_error(lambda: load_sequence(path), path, match="'V' is encrypted")
    odd = bytearray(data)
    for signature, method_at in ((b"PK\x03\x04", 8), (b"PK\x01\x02", 10)):
        at = bytes(odd).find(signature) + method_at
        odd[at : at + 2] = struct.pack("<H", 99)
    path = write_file(tmp_path / "method99.npz", bytes(odd))
    expect_input_error(lambda: load_sequence(path), path, match="'V' .*method 99")
    path = write_file(tmp_path / "bzip2.npz", zip_bytes({"V.npy": member}, zipfile.ZIP_BZIP2))
    expect_input_error(lambda: load_sequence(path), path, match="'V' .*method 12")


# ------------------------------------------------------------------------------------------
# property tests: random bytes and random mutations


VALID_NPZ_ARRAYS = {
    "V": V3,
    "F": np.array([[0, 1, 2, -1], [2, 1, 0, 1]]),
    "frame_files": np.array(["a.obj", "b.obj"]),
    "frame_rate": np.array(25.0),
}


VALID_NPZ = npz_bytes(**VALID_NPZ_ARRAYS)


VALID_NPZ_COMPRESSED = npz_bytes(True, **VALID_NPZ_ARRAYS)


NPZ_TOKENS = [
    b"\x00" * 4,
    b"\xff" * 4,
    b"\x7f\xff\xff\xff",
    b"PK\x03\x04",
    b"PK\x01\x02",
    b"PK\x05\x06",
]


def _npz_outcome(path: Path) -> None:
    """Load ``path`` as .npz: a valid sequence, or an InputError naming it."""
    try:
        seq = load_sequence(path)
    except InputError as error:
        refused = error
    else:
        check_sequence(seq)
        return
    assert refused.path == str(path) and str(refused).startswith(str(path))


@PROPERTY
@given(data=st.one_of(st.binary(max_size=1024), st.binary(max_size=1024).map(lambda b: b"PK" + b)))
def test_random_bytes_as_npz(data: bytes) -> None:
    EXAMPLES_RUN["random bytes as npz"] = EXAMPLES_RUN.get("random bytes as npz", 0) + 1
    _npz_outcome(write_file(SCRATCH / "random.npz", data))


@PROPERTY
@given(
    data=st.one_of(mutations(VALID_NPZ, NPZ_TOKENS), mutations(VALID_NPZ_COMPRESSED, NPZ_TOKENS))
)
def test_mutated_npz(data: bytes) -> None:
    EXAMPLES_RUN["mutated npz"] = EXAMPLES_RUN.get("mutated npz", 0) + 1
    _npz_outcome(write_file(SCRATCH / "mutated.npz", data))


HEADER_TOKENS = [b"'", b"(", b")", b",", b"9" * 12, b"-1", b"True", b"'|O'", b"'<c16'", b"{", b"}"]


@PROPERTY
@given(
    key=st.sampled_from(["V", "F", "frame_files", "frame_rate"]),
    data=st.data(),
    compressed=st.booleans(),
)
def test_mutated_npy_member_in_a_sound_zip(key: str, data: st.DataObject, compressed: bool) -> None:
    """The member's bytes are mutated and the zip rebuilt around them, CRC and all, so that the
    mutation reaches numpy's header parser and our checks instead of the zip's CRC."""
    EXAMPLES_RUN["mutated .npy in a sound zip"] = (
        EXAMPLES_RUN.get("mutated .npy in a sound zip", 0) + 1
    )
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, VALID_NPZ_ARRAYS[key], allow_pickle=False)
    member = data.draw(mutations(buffer.getvalue(), HEADER_TOKENS + NPZ_TOKENS))
    members = {f"{name}.npy": npy for name, npy in _members(VALID_NPZ_ARRAYS).items()}
    members[f"{key}.npy"] = member
    method = zipfile.ZIP_DEFLATED if compressed else zipfile.ZIP_STORED
    _npz_outcome(write_file(SCRATCH / "member.npz", zip_bytes(members, method)))


# dtypes of every kind, and descr strings that have made np.dtype raise odd exceptions
DESCRS = [
    "<f8",
    ">f4",
    "<f2",
    "<f16",
    "<i8",
    "|u1",
    ">u8",
    "|b1",
    "<c16",
    "|O",
    "<U4",
    "|S2",
    "V8",
    "<M8[s]",
    "<m8[as/0]",
    "<U0",
    "S0",
    ",<f8",
    "f8,(",
    "<f8,<f8",
    "(2,)<f8",
    "(3)f8",
    "a",
]


@PROPERTY
@given(
    descr=st.sampled_from(DESCRS),
    shape=st.lists(st.integers(-2, 8) | st.integers(-2, 2**40), max_size=4).map(tuple),
    fortran=st.booleans(),
    payload=st.just(-1) | st.integers(0, 300),  # -1: exactly the bytes the header declares
    key=st.sampled_from(["V", "F", "frame_files", "frame_rate"]),
)
def test_any_npy_header(
    descr: str, shape: tuple[int, ...], fortran: bool, payload: int, key: str
) -> None:
    """Any dtype and shape in a header, with any amount of data behind it: an InputError or a
    valid sequence, in small memory."""
    EXAMPLES_RUN["any .npy header"] = EXAMPLES_RUN.get("any .npy header", 0) + 1
    if payload < 0:
        try:
            payload = max(0, min(math.prod(shape) * np.dtype(descr).itemsize, 4096))
        except Exception:  # a descr numpy refuses: any payload will do
            payload = 0
    member = npy_bytes({"descr": descr, "fortran_order": fortran, "shape": shape}, bytes(payload))
    members = {f"{name}.npy": npy for name, npy in _members({"V": V3}).items()}
    members[f"{key}.npy"] = member
    path = write_file(SCRATCH / "header.npz", zip_bytes(members))
    raised, _, peak = measure(lambda: check_sequence(load_sequence(path)))
    assert raised is None or isinstance(raised, InputError), repr(raised)
    assert peak < 4 * 2**20, peak


EXAMPLES_RUN: dict[str, int] = {}  # examples run by each property test, printed at the end
SCRATCH = scratch_folder()


def teardown_module() -> None:
    """Remove the scratch folder; report how many examples each property test ran (``-s``)."""
    shutil.rmtree(SCRATCH, ignore_errors=True)
    report_examples(EXAMPLES_RUN)
