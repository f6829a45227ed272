"""The compiled core's text formats against the pure-Python reference: Python's ``repr`` of
millions of float64 and float32 bit patterns and the edge values, whole OBJ files written from
the shared sequences byte for byte, the shared OBJ folder read to the same arrays, and thousands
of mutated OBJ texts read to the same mesh or refused with the same error (class, message,
line), with the text checks run on small chunks too."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import shared_file, shared_sequence
from tuckercodec.errors import InputError
from tuckercodec.io import obj
from tuckercodec.io.common import float_text
from tuckercodec.io.registry import MeshFrame
from tuckercodec.system import native

CORE: Any = native.core()
pytestmark = pytest.mark.skipif(
    CORE is None,
    reason="the compiled core is not installed (python -m tools.build_native)",
)


def _reprs(values: np.ndarray) -> bytes:
    """``repr`` of each value, one a line: the reference the core's text must equal."""
    return "".join([repr(value) + "\n" for value in values.tolist()]).encode("ascii")


def _check_repr(values: np.ndarray) -> None:
    values = np.ascontiguousarray(values, dtype=np.float64).reshape(-1)
    made = CORE.float_repr_text(values)
    expected = _reprs(values)
    if made != expected:
        pairs = zip(made.decode().splitlines(), expected.decode().splitlines(), strict=True)
        first = next(pair for pair in pairs if pair[0] != pair[1])
        pytest.fail(f"the core's text differs from repr: {first}")


def _edge_values() -> np.ndarray:
    tiny = np.float64(5e-324)
    powers = [float(f"1e{n}") for n in range(-330, 310)] + [2.0**n for n in range(-1074, 1024)]
    edges = [
        0.0,
        1e-4,
        9.999999999999999e-05,
        1e16,
        9999999999999998.0,
        1e15,
        0.1,
        0.3,
        2.2250738585072014e-308,
        2.225073858507201e-308,
        1.7976931348623157e308,
        float(tiny),
        float(tiny * 2),
        float(np.nextafter(0.0, 1.0) * 3),
        2.0**53,
        2.0**53 + 2,
        123456789012345678.0,
        float("inf"),
        float("nan"),
    ]
    values = np.array(powers + edges, dtype=np.float64)
    # each value's neighbours: the ends of intervals and of the positional range
    with np.errstate(over="ignore"):  # the largest float's neighbour up is inf: kept
        near = np.concatenate([np.nextafter(values, np.inf), np.nextafter(values, -np.inf)])
    both = np.concatenate([values, near])
    return np.concatenate([both, -both])


def test_repr_of_edge_values() -> None:
    _check_repr(_edge_values())


@pytest.mark.parametrize("seed", range(4))
def test_repr_of_random_float64_bit_patterns(seed: int) -> None:
    """Half a million bit patterns a seed: every exponent, subnormals, NaN payloads."""
    bits = np.random.default_rng(seed).integers(0, 2**64, 500_000, dtype=np.uint64)
    _check_repr(bits.view(np.float64))


@pytest.mark.parametrize("seed", range(4))
def test_repr_of_random_float32_bit_patterns(seed: int) -> None:
    """Decoded positions are float32 widened to float64: half a million bit patterns a seed."""
    bits = np.random.default_rng(100 + seed).integers(0, 2**32, 500_000, dtype=np.uint32)
    with np.errstate(invalid="ignore"):  # NaN patterns widened: NaN, as repr says
        widened = bits.view(np.float32).astype(np.float64)
    _check_repr(widened)


@pytest.mark.parametrize("seed", range(2))
def test_repr_of_random_values_at_every_scale(seed: int) -> None:
    rng = np.random.default_rng(200 + seed)
    scales = 10.0 ** rng.integers(-12, 20, 500_000)
    values = rng.standard_normal(500_000) * scales
    _check_repr(values)
    _check_repr(values.astype(np.float32).astype(np.float64))
    _check_repr(np.round(values, int(rng.integers(0, 8))))


def _both(make: Callable[[], object]) -> tuple[object, object]:
    """``make()`` with the core and in pure Python: each result, or the error raised."""
    outcomes = []
    for pure in (False, True):
        try:
            if pure:
                with native.pure_python():
                    outcomes.append(make())
            else:
                outcomes.append(make())
        except Exception as error:  # the class and message are compared
            outcomes.append(error)
    return outcomes[0], outcomes[1]


def test_vertex_text_equals_the_numpy_reference() -> None:
    rng = np.random.default_rng(7)
    vertices = rng.standard_normal((20_000, 3)) * 10.0 ** rng.integers(-8, 18, (20_000, 3))
    made, reference = _both(lambda: float_text.vertex_text(vertices))
    assert made == reference


def _written(tmp_path: Path, vertices: np.ndarray, faces: np.ndarray) -> tuple[bytes, bytes]:
    """One OBJ file written with the core and in pure Python: both files' bytes."""
    texts = []
    for name, pure in (("native.obj", False), ("pure.obj", True)):
        obj._last_faces = None  # the face text made afresh by each
        if pure:
            with native.pure_python():
                obj.write_obj(tmp_path / name, vertices, faces, overwrite=True)
        else:
            obj.write_obj(tmp_path / name, vertices, faces, overwrite=True)
        texts.append((tmp_path / name).read_bytes())
    return texts[0], texts[1]


@pytest.mark.parametrize("name", ["samba.npz", "chicken.npz", "cloth-vellum.npz", "horse-gallop"])
def test_obj_files_of_the_shared_sequences_are_byte_identical(tmp_path: Path, name: str) -> None:
    sequence = shared_sequence(name)
    frames = np.linspace(0, sequence.frame_count - 1, 3).astype(int)
    for frame in frames.tolist():
        positions = sequence.vertices[frame]
        for vertices in (positions, positions.astype(np.float32)):  # as read, as decoded
            made, reference = _written(tmp_path, vertices, sequence.faces)
            assert made == reference, f"{name} frame {frame}"


def test_padded_faces_are_written_alike(tmp_path: Path) -> None:
    vertices = np.arange(30, dtype=np.float64).reshape(10, 3) / 7
    faces = np.array([[0, 1, 2, -1, -1], [3, 4, 5, 6, 7], [9, 8, 7, 6, -1]])
    made, reference = _written(tmp_path, vertices, faces)
    assert made == reference
    made, reference = _written(tmp_path, vertices, np.zeros((0, 3), dtype=np.int64))
    assert made == reference


def _same_outcome(native_result: object, pure_result: object) -> None:
    """Both read the same mesh, or both raised the same error (class, message, line)."""
    if isinstance(pure_result, Exception) or isinstance(native_result, Exception):
        assert type(native_result) is type(pure_result), (native_result, pure_result)
        assert str(native_result) == str(pure_result)
        assert getattr(native_result, "line", None) == getattr(pure_result, "line", None)
        return
    assert isinstance(native_result, MeshFrame) and isinstance(pure_result, MeshFrame)
    assert native_result.vertices.dtype == pure_result.vertices.dtype == np.float64
    assert native_result.vertices.shape == pure_result.vertices.shape
    assert native_result.vertices.tobytes() == pure_result.vertices.tobytes()
    assert native_result.faces.dtype == pure_result.faces.dtype
    assert np.array_equal(native_result.faces, pure_result.faces)
    assert native_result.faces.shape == pure_result.faces.shape


def test_the_shared_obj_folder_reads_alike() -> None:
    """Every frame read as a sequence reads it: against the first frame, both ways."""
    files = sorted(shared_file("horse-gallop").glob("*.obj"))
    first_native = obj.read_obj_frame(files[0])
    with native.pure_python():
        first_pure = obj.read_obj_frame(files[0])
    _same_outcome(first_native, first_pure)
    for path in files[1:]:
        made = obj.read_obj_frame(path, first_native)
        with native.pure_python():
            expected = obj.read_obj_frame(path, first_pure)
        _same_outcome(made, expected)
        assert made.faces is first_native.faces  # one table shared by every frame


# the pieces mutations are made of: what a tidy file holds and what a broken one may
_PIECES = [
    b" ", b"  ", b"\t", b"\n", b"\r\n", b"\r", b"\x0b", b"\x0c", b"#", b"# note\n", b"\\",
    b"\\\n", b"v", b"v ", b"f ", b"vt ", b"vn 0 0 1", b"/", b"//", b"-", b"+", b"+-", b".", b"e",
    b"E-3", b"0", b"1", b"7", b"-1", b"-2", b"00000000000000000001", b"1234567890123456789",
    b"nan", b"-inf", b"Infinity", b"+-inf", b"1e999", b"1e-400", b"1_0", b"0x1", b"1.5e+3",
    b".5", b"5.", b"0.1000000000000000055511151231257827", b"\xc3\xa9", b"\xe2\x82", b"\xff",
    b"\x00", b"\xef\xbb\xbf", b"x" * 45,
]  # fmt: skip

_SEEDS = [
    b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
    b"# header\r\nv 0.5 -1.25e-3 2 1\r\nv 1 0 0 0.1 0.2 0.3\r\nv 0 1 0\r\nf 1/1/1 2//2 3/3\r\n",
    b"v -0.0 1e-5 123456.789 0.2 0.3 0.4 1\nv 1 2 3\nv 4 5 6\nv 7 8 9\nf -4 -3 -2 -1\nf 1 2 3\n",
    b"o thing\ng part\nusemtl m\ns off\nv 1 2 3 \\\n  # continued\nv 4 5 6\nv 7 8 9\n"
    b"f 1 2 \\\n 3\n",
    b"v 1 1 1\nf 1 2 3\nv 2 2 2\nv 3 3 3\nf 1 2 3 2 1\nl 1 2\n",
    b"\tv 1 2 3\nv 2 3 4\nv\t3 4 5\nf 1 2 3 # tri\n",
]


def _mutate(rng: np.random.Generator, text: bytes) -> bytes:
    data = bytearray(text)
    for _ in range(int(rng.integers(1, 4))):
        at = int(rng.integers(0, len(data) + 1))
        choice = int(rng.integers(0, 4))
        if choice == 0 and data:  # delete a few bytes
            del data[at : at + int(rng.integers(1, 4))]
        elif choice == 1:  # replace a byte
            data[at : at + 1] = _PIECES[int(rng.integers(0, len(_PIECES)))]
        elif choice == 2:  # duplicate a line
            lines = bytes(data).split(b"\n")
            pick = int(rng.integers(0, len(lines)))
            lines.insert(pick, lines[pick])
            data = bytearray(b"\n".join(lines))
        else:  # insert a piece
            data[at:at] = _PIECES[int(rng.integers(0, len(_PIECES)))]
    return bytes(data)


def _read_both(path: Path, reference_pair: tuple[MeshFrame, MeshFrame] | None) -> None:
    native_reference = reference_pair[0] if reference_pair else None
    pure_reference = reference_pair[1] if reference_pair else None
    made, _ = _both(lambda: obj.read_obj_frame(path, native_reference))
    try:
        with native.pure_python():
            expected: object = obj.read_obj_frame(path, pure_reference)
    except Exception as error:  # the class and message are compared
        expected = error
    _same_outcome(made, expected)


@pytest.mark.parametrize("seed", range(4))
def test_mutated_obj_texts_read_alike(tmp_path: Path, seed: int) -> None:
    """Each mutated text read alone and as a later frame of its seed's sequence."""
    rng = np.random.default_rng(300 + seed)
    path = tmp_path / "frame.obj"
    references = {}
    for index, text in enumerate(_SEEDS):
        path.write_bytes(text)
        references[index] = (obj.read_obj_frame(path), _pure_read(path))
    for _ in range(1000):
        index = int(rng.integers(0, len(_SEEDS)))
        path.write_bytes(_mutate(rng, _SEEDS[index]))
        _read_both(path, None)
        _read_both(path, references[index])


@pytest.mark.parametrize("limit", [5, 9, 16])
def test_mutated_texts_checked_in_small_chunks_alike(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, limit: int
) -> None:
    """A line limit of a few bytes reads a few bytes a chunk: characters, "\\r\\n" and lines
    split between chunks, and lines too long, all found on the same line both ways."""
    monkeypatch.setattr(obj, "MAX_LINE_BYTES", limit)
    rng = np.random.default_rng(400 + limit)
    path = tmp_path / "frame.obj"
    for _ in range(600):
        text = _mutate(rng, _SEEDS[int(rng.integers(0, len(_SEEDS)))])
        # short lines, so that some texts pass the limit and go on to be parsed
        text = text.replace(b" ", b"\n" if rng.random() < 0.3 else b" ")
        path.write_bytes(text)
        _read_both(path, None)


def _pure_read(path: Path) -> MeshFrame:
    with native.pure_python():
        return obj.read_obj_frame(path)


def test_the_core_parser_reports_the_references_errors(tmp_path: Path) -> None:
    """The core's own line and message (which a fuzzer sees) are the reference's, for texts
    whose quoted tokens are printable ASCII."""
    rng = np.random.default_rng(500)
    path = tmp_path / "frame.obj"
    compared = 0
    for _ in range(3000):
        text = _mutate(rng, _SEEDS[int(rng.integers(0, len(_SEEDS)))])
        if not all(32 <= byte < 127 or byte in b"\t\n\r\x0b\x0c" for byte in text):
            continue
        data = text.removeprefix(b"\xef\xbb\xbf").replace(b"\r\n", b"\n").replace(b"\r", b"\n")
        if not data.strip():
            continue
        try:
            with native.pure_python():
                obj._parse_careful(data, path)
            expected = None
        except InputError as error:
            expected = (error.line, error.reason)
        try:
            CORE.obj_parse(data)
            made = None
        except CORE.ObjError as error:
            made = error.args
        assert made == expected, text
        compared += expected is not None
    assert compared > 500
