"""Hostile input for the sequence readers (issue 5, item 2): OBJ frames, folders and .npz files.

Every broken, corrupt or crafted input must end in an :class:`InputError` that names the file (and
the line and frame where they apply), quickly and in small memory; never another exception type,
a hang, a pickle load or a huge allocation. The property tests feed random bytes and random
mutations of small valid files and accept only an InputError or a valid sequence.

``TUCKERCODEC_HYPOTHESIS_EXAMPLES`` scales the number of examples of each property test (for a
long local run); CI runs the default, derandomized so that every run tries the same inputs.
"""

from __future__ import annotations

import io
import math
import os
import pickle
import re
import struct
import sys
import tempfile
import threading
import time
import tracemalloc
import warnings
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tuckercodec import InputError, MeshSequence
from tuckercodec.io import load_sequence
from tuckercodec.io import obj as objio
from tuckercodec.io.obj import MAX_LINE_BYTES, _parse_careful, _read_text, read_obj

TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"

# A small OBJ that uses most of what the reader knows: comments, vt/vn, slashed corners, a quad
# and triangles, a negative (relative) index, CRLF on one line, a weight on one vertex.
VALID_OBJ = (
    b"# cube corner\r\nmtllib m.mtl\no thing\n"
    b"v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n"
    b"vt 0 0\nvt 1 0\nvn 0 0 1\ng side\nusemtl red\ns off\n"
    b"f 1/1/1 2/2/1 3/2/1 4/1/1\nf 1//1 2//1 5//1\nf -1 -2 2\nf 5 6 2\n"
)

EXAMPLES = int(os.environ.get("TUCKERCODEC_HYPOTHESIS_EXAMPLES", "0")) or None
# database=None: nothing is written into the repository; derandomize: CI tries the same inputs
# every run (the long, random exploration is tools/fuzz.py's job).
PROPERTY = settings(
    max_examples=EXAMPLES or 400,
    deadline=None,
    database=None,
    derandomize=EXAMPLES is None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

#: examples run by each property test, printed at the end of the module (pytest -s shows it)
EXAMPLES_RUN: dict[str, int] = {}


def write(path: Path, data: str | bytes) -> Path:
    """Write a test file verbatim (no newline translation)."""
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    return path


def expect_input_error(
    call: Callable[[], object],
    path: Path,
    *,
    line: int | None = None,
    frame: int | None = None,
    match: str | None = None,
) -> InputError:
    """Run ``call``, which must raise an InputError naming ``path``, ``line`` and ``frame``."""
    with pytest.raises(InputError, match=match) as caught:
        call()
    error = caught.value
    assert (error.path, error.line, error.frame) == (str(path), line, frame), str(error)
    where = str(path) + (f":{line}" if line is not None else "")
    assert str(error).startswith(where), str(error)
    assert len(str(error)) < 600, "messages quote tokens, never whole lines"
    return error


def check_obj_result(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """What a successful OBJ read must be: finite (K, 3), valid -1-padded faces, and the same
    result as the careful (reference) parser."""
    assert vertices.dtype == np.float64 and vertices.ndim == 2 and vertices.shape[1] == 3
    assert len(vertices) >= 1 and np.isfinite(vertices).all()
    assert faces.dtype == np.int64 and faces.ndim == 2 and faces.shape[1] >= 3
    MeshSequence(vertices[np.newaxis], faces)  # its checks: indices in range, padding at the end
    careful = _parse_careful(_read_text(path), path)
    np.testing.assert_array_equal(vertices, careful.vertices)
    np.testing.assert_array_equal(faces, careful.faces)


def check_sequence(seq: MeshSequence) -> None:
    """What a successfully loaded sequence must be."""
    assert isinstance(seq, MeshSequence)
    assert seq.vertices.dtype == np.float64 and np.isfinite(seq.vertices).all()
    assert seq.faces.dtype == np.int64
    MeshSequence(seq.vertices, seq.faces, frame_names=seq.frame_names)  # passes every check
    assert len(seq.frame_names) == seq.frame_count


# ============================================================================================
# OBJ: one bad thing at a time, each with its file, line and message


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        # coordinates: too few, a count that is neither xyz, xyzw nor xyz+rgb(a), none at all
        ("v 0 0 0\nv 1 2\n", 2, r"needs x y z .* got 2 value"),
        ("v 0 0 0\nv 1 2 3 4 5\n", 2, "got 5 value"),
        ("v 1 2 3 4 5 6 7 8\n", 1, "got 8 value"),
        ("v\n", 1, "got 0 value"),
        # not numbers
        ("v 1 two 3\n", 1, "not a number: 'two'"),
        ("v 1 0x10 3\n", 1, "not a number: '0x10'"),
        ("v 1,5 2 3\n", 1, "not a number: '1,5'"),
        ("v 1 2 3,\n", 1, "not a number: '3,'"),
        ("v 1_0 2 3\n", 1, "not a number: '1_0'"),
        ("v 1 2 3abc\n", 1, "not a number"),
        ("v 1 2 3 x\n", 1, "not a number: 'x'"),  # a weight must be a number too
        ("v 1 2 3 0.5 0.5 y\n", 1, "not a number: 'y'"),  # and a colour
        # NaN and infinity, spelled every way float() accepts, and overflow to infinity
        ("v nan 0 0\n", 1, "non-finite"),
        ("v 0 NaN 0\n", 1, "non-finite"),
        ("v 0 0 inf\n", 1, "non-finite"),
        ("v 0 0 -Infinity\n", 1, "non-finite"),
        ("v 1e999 0 0\n", 1, "non-finite"),
        ("v 0 -1e309 0\n", 1, "non-finite"),
        # faces: out of range, zero, relative past the first vertex, not integers, too short
        (TRIANGLE + "f 1 2 4\n", 4, "vertex 4, but the file has only 3"),
        (TRIANGLE + "f 0 1 2\n", 4, "0 is invalid"),
        (TRIANGLE + "f -4 -1 -2\n", 4, "counts back past the first vertex"),
        ("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n", 2, "counts back"),  # relative to its line
        (TRIANGLE + "f 1 2 x\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 3.0\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 +-3\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 /3\n", 4, "not a vertex index"),  # a corner without its vertex
        (TRIANGLE + "f 1 2\n", 4, "at least 3 corners"),
        (TRIANGLE + "f\n", 4, "at least 3 corners"),
        (TRIANGLE + "f 1 2 99999999999999999999999\n", 4, "vertex"),
        (TRIANGLE + "f 1 2 -99999999999999999999999\n", 4, "vertex"),
        (TRIANGLE + "f 1 2 " + "7" * 5000 + "\n", 4, "vertex"),  # beyond int()'s digit limit
        (TRIANGLE + "f 1 2 -" + "7" * 5000 + "\n", 4, "vertex"),
        # empty, or nothing that makes a mesh
        ("", None, "empty"),
        (" \n\t\r\n\n", None, "empty"),
        ("# only a comment\nvt 0 0\nvn 0 0 1\n", None, "no vertices"),
        ("f 1 2 3\n", None, "no vertices"),
        ("\ufeff", None, "empty"),  # a UTF-8 byte-order mark and nothing else
        # binary data
        (b"v 0 0 0\n\x00\x01\x02binary", 2, "NUL"),
        (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", 3, "NUL"),
        (b"PK\x03\x04\x14\x00\x00\x00\x08\x00", 1, "NUL"),
        (b"v 0 0 0\nv 1 0 0\n\xff\xfe\x89PNG", 3, "UTF-8"),
        (b"v 0 0 0\r\nv 1 0 0\r\n\xc0\xaf\r\n", 3, "UTF-8"),  # an overlong encoding of '/'
        (b"v 0 0 0\rv 1 0 0\r\xed\xa0\x80\r", 3, "UTF-8"),  # a surrogate; old-Mac line ends
        (b"v 0 0 0\n# caf\xc3", 2, "UTF-8"),  # the file ends inside a character
        # a line continued into the end of the file (the continuation keeps its first line)
        ("v 0 0 0\nv 1 2 \\", 2, "got 2 value"),
        ("v 0 0 0\nv 1 \\\n2 3\nf 1 2 x\n", 4, "not a vertex index"),
        ("v 0 0 0\nv 1 \\\n2 \\\n\n", 2, "got 2 value"),
    ],
)
def test_bad_obj_is_refused_with_file_and_line(
    tmp_path: Path, text: str | bytes, line: int | None, message: str
) -> None:
    path = write(tmp_path / "bad.obj", text)
    expect_input_error(lambda: read_obj(path), path, line=line, match=message)
    # the same through a sequence: a single file has no frame number
    expect_input_error(lambda: load_sequence(path, progress=False), path, line=line, match=message)


def test_messages_quote_a_long_token_only_in_part(tmp_path: Path) -> None:
    path = write(tmp_path / "long.obj", "v 0 0 " + "1" * 100_000 + "x\n")
    error = expect_input_error(lambda: read_obj(path), path, line=1, match="not a number")
    assert "..." in str(error)


def test_a_long_broken_number_is_refused_quickly(tmp_path: Path) -> None:
    # A regex that backtracks quadratically took 8 s on 20 000 digits; a line may hold millions.
    path = write(tmp_path / "digits.obj", "v 0 0 " + "1" * (MAX_LINE_BYTES - 10) + "x\n")
    start = time.perf_counter()
    expect_input_error(lambda: read_obj(path), path, line=1, match="not a number")
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize(
    ("extra", "why"),
    [("1.0", "weight w"), ("0.5 0.25 1", "RGB colour"), ("0.5 0.25 1 1", "RGBA colour")],
)
def test_weight_and_colours_are_read_past(tmp_path: Path, extra: str, why: str) -> None:
    # Documented in objio: x y z are kept, a weight (4 numbers) or colour (6 or 7) is ignored.
    path = write(tmp_path / "extra.obj", f"v 1 2 3 {extra}\nv 4 5 6 {extra}\nv 7 8 9\nf 1 2 3\n")
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    check_obj_result(path, vertices, faces)


def test_a_non_finite_weight_or_colour_is_ignored_like_any_other(tmp_path: Path) -> None:
    # ignored values are not used, so they need not be finite (but they must be numbers)
    path = write(tmp_path / "w.obj", "v 1 2 3 nan\nv 4 5 6 inf 0 0\nv 7 8 9\n")
    np.testing.assert_array_equal(read_obj(path)[0], [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


def test_negative_relative_indices_are_resolved_from_their_line(tmp_path: Path) -> None:
    text = (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\n"
        "f -3 -2 -1\n"  # the three vertices so far: 1 2 3
        "v 0 1 0\nv 2 2 2\n"
        "f -1 -2 -5\n"  # now -1 is vertex 5: 5 4 1
        "f 1/1/1 -3/2/2 -1//3\n"  # slashed relative corners: 1 3 5
        "f -5 -4 -3 -2 -1\n"  # a pentagon of every vertex
    )
    path = write(tmp_path / "relative.obj", text)
    vertices, faces = read_obj(path)
    expected = [[0, 1, 2, -1, -1], [4, 3, 0, -1, -1], [0, 2, 4, -1, -1], [0, 1, 2, 3, 4]]
    np.testing.assert_array_equal(faces, expected)
    check_obj_result(path, vertices, faces)


def test_a_face_may_name_a_vertex_defined_further_down(tmp_path: Path) -> None:
    # documented in objio: positive indices are checked against the whole file's vertices
    path = write(tmp_path / "forward.obj", "f 1 2 3\n" + TRIANGLE)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2]])
    check_obj_result(path, vertices, faces)


@pytest.mark.parametrize(
    "face", ["f 1/2/3 2/3/1 3/1/2", "f 1//3 2//1 3//2", "f 1/2 2/3 3/1", "f 1/ 2/ 3/"]
)
def test_slashed_corner_forms(tmp_path: Path, face: str) -> None:
    path = write(tmp_path / "slashed.obj", TRIANGLE + "vt 0 0\nvt 1 0\nvt 0 1\n" + face + "\n")
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2]])
    check_obj_result(path, vertices, faces)


def test_mixed_polygon_sizes_are_padded(tmp_path: Path) -> None:
    text = TRIANGLE + "v 1 1 0\nv 2 2 0\nf 1 2 3\nf 1 2 3 4 5\nf 1 2 3 4\n"
    path = write(tmp_path / "mixed.obj", text)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2, -1, -1], [0, 1, 2, 3, 4], [0, 1, 2, 3, -1]])
    check_obj_result(path, vertices, faces)


def test_one_huge_polygon_among_many_faces(tmp_path: Path) -> None:
    # Padding 1001 faces to 20 000 corners would be 20 M entries from a 110 kB file (a 0.7 MB
    # file asked for 45 GiB before the limit); refused at the widest face's line.
    corners = " ".join(str(1 + i % 3) for i in range(20_000))
    path = write(tmp_path / "wide.obj", TRIANGLE + "f 1 2 3\n" * 1000 + f"f {corners}\n")
    raised, elapsed, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError), raised
    assert (raised.line, raised.path) == (1004, str(path)) and "20000 corners" in str(raised)
    assert elapsed < 5.0 and peak < 64 * 2**20
    # a 500-gon cap among 2000 triangles is an ordinary mesh
    corners = " ".join(str(1 + i % 3) for i in range(500))
    path = write(tmp_path / "cap.obj", TRIANGLE + "f 1 2 3\n" * 2000 + f"f {corners}\n")
    vertices, faces = read_obj(path)
    assert faces.shape == (2001, 500)
    check_obj_result(path, vertices, faces)


@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r", "mixed"])
def test_line_endings_and_error_lines(tmp_path: Path, ending: str) -> None:
    lines = ["# head", "v 0 0 0", "v 1 0 0", "", "v 0 1 0", "f 1 2 3"]
    if ending == "mixed":  # each kind once, and "\n\r" which is two line ends
        text = "# head\r\nv 0 0 0\rv 1 0 0\n\r\nv 0 1 0\nf 1 2 3\r"
    else:
        text = ending.join(lines) + ending
    path = write(tmp_path / "ends.obj", text)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    check_obj_result(path, vertices, faces)
    # and the line number of an error counts every kind of line end the same way
    broken = write(tmp_path / "broken.obj", text.replace("f 1 2 3", "f 1 2 9"))
    expect_input_error(lambda: read_obj(broken), broken, line=6, match="vertex 9")


def test_line_continuation_is_supported(tmp_path: Path) -> None:
    path = write(tmp_path / "cont.obj", "v 0 0 \\\n0\nv 1 \\\r\n0 0\nv 0 1 0\nf 1 \\\n2 3\n")
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_non_ascii_utf8_in_comments_and_names_is_fine(tmp_path: Path) -> None:
    path = write(tmp_path / "utf8.obj", "# café ☕\no Über\n" + TRIANGLE + "g 頂点\nf 1 2 3\n")
    assert read_obj(path)[0].shape == (3, 3)


@pytest.mark.parametrize(
    "data",
    [
        pytest.param(np.random.default_rng(5).bytes(4096), id="random"),
        pytest.param(b"\x89PNG\r\n\x1a\n" + np.random.default_rng(6).bytes(300), id="png"),
        pytest.param(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n1 0 obj", id="pdf"),
        pytest.param(b"\x7fELF\x02\x01\x01", id="elf-ascii-start"),
    ],
)
def test_binary_garbage(tmp_path: Path, data: bytes) -> None:
    path = write(tmp_path / "garbage.obj", data)
    with pytest.raises(InputError) as caught:
        read_obj(path)
    assert caught.value.path == str(path)


def test_a_zip_named_obj(tmp_path: Path) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, V=np.zeros((1, 3, 3)))
    path = write(tmp_path / "archive.obj", buffer.getvalue())
    expect_input_error(lambda: read_obj(path), path, line=1, match="NUL")


def test_a_folder_and_a_missing_file(tmp_path: Path) -> None:
    (tmp_path / "dir.obj").mkdir()
    expect_input_error(lambda: read_obj(tmp_path / "dir.obj"), tmp_path / "dir.obj", match="folder")
    missing = tmp_path / "missing.obj"
    expect_input_error(lambda: read_obj(missing), missing, match="cannot read")


def refused_without_waiting(call: Callable[[], object], pipe: Path) -> BaseException | None:
    """Run ``call``, which reads the named pipe ``pipe``, in a thread: what it raised (None if
    nothing), or fail the test if it is still waiting for a writer after 5 s."""
    outcome: list[BaseException | None] = []

    def run() -> None:
        try:
            call()
            outcome.append(None)
        except BaseException as error:  # noqa: BLE001 - handed to the test thread
            outcome.append(error)

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(5)
    if worker.is_alive():  # be the writer it waits for, so that the thread ends, then fail
        with open(pipe, "wb"):
            pass
        pytest.fail(f"reading {pipe.name} waited for a writer")
    return outcome[0]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
@pytest.mark.parametrize("name", ["pipe.obj", "pipe.npz"])
def test_a_named_pipe_is_refused_not_waited_on(tmp_path: Path, name: str) -> None:
    pipe = tmp_path / name
    os.mkfifo(pipe)
    raised = refused_without_waiting(lambda: load_sequence(pipe, progress=False), pipe)
    assert isinstance(raised, InputError) and "regular file" in str(raised), raised
    assert raised.path == str(pipe)
    if name.endswith(".obj"):
        raised = refused_without_waiting(lambda: read_obj(pipe), pipe)
        assert isinstance(raised, InputError) and "regular file" in str(raised), raised


# --------------------------------------------------------------------------------------------
# a 2 GB line: refused after MAX_LINE_BYTES, without reading the file, in small memory


def measure(call: Callable[[], object]) -> tuple[BaseException | None, float, int]:
    """Run ``call``: the exception it raised, its time in seconds and its peak traced memory."""
    tracemalloc.start()
    start = time.perf_counter()
    raised: BaseException | None = None
    try:
        call()
    except BaseException as error:  # noqa: BLE001 - returned to the caller
        raised = error
    elapsed = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return raised, elapsed, peak


def sparse_file(path: Path, head: bytes, size: int = 2**31) -> Path:
    """A file of ``size`` bytes that starts with ``head`` and costs no disk beyond it (the rest
    is a hole, which reads as NUL bytes)."""
    with path.open("wb") as stream:
        stream.write(head)
        stream.truncate(size)
    return path


@pytest.mark.skipif(sys.platform == "win32", reason="no sparse files by default")
def test_a_2gb_line_of_nul_bytes(tmp_path: Path) -> None:
    path = sparse_file(tmp_path / "hole.obj", b"v 0 0 0\nv 1 ")
    raised, elapsed, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError) and raised.line == 2, raised
    print(f"\n2 GB sparse line (NUL): {elapsed * 1000:.1f} ms, peak {peak / 2**20:.2f} MiB")
    assert elapsed < 2.0 and peak < 8 * 2**20


@pytest.mark.skipif(sys.platform == "win32", reason="no sparse files by default")
def test_a_2gb_line_of_digits(tmp_path: Path) -> None:
    # Real digits for more than the limit, then a hole: it is the line limit that stops it.
    head = b"v 0 0 0\nv 1 " + b"1" * (MAX_LINE_BYTES + 2**20)
    path = sparse_file(tmp_path / "long.obj", head)
    raised, elapsed, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError), raised
    assert raised.line == 2 and "longer than" in str(raised), raised
    print(f"\n2 GB line (digits then hole): {elapsed * 1000:.1f} ms, peak {peak / 2**20:.2f} MiB")
    assert elapsed < 2.0 and peak < MAX_LINE_BYTES + 4 * 2**20


@pytest.mark.parametrize("ending", [b"\n", b"\r\n", b"\r"])
def test_line_length_limit_is_exact_across_chunks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ending: bytes
) -> None:
    # A small limit makes the chunks small too, so lines cross chunk boundaries everywhere.
    monkeypatch.setattr(objio, "MAX_LINE_BYTES", 16)
    longest = b"# " + b"c" * 14  # exactly 16 bytes
    lines = [b"v 0 0 0", longest, b"v 1 0 0", b"v 0 1 0", longest, b"f 1 2 3"]
    path = write(tmp_path / "fits.obj", ending.join(lines) + ending)
    assert read_obj(path)[0].shape == (3, 3)
    for number in range(len(lines)):
        too_long = list(lines)
        too_long[number] += b" " * (17 - len(too_long[number]))  # 17 bytes: one too many
        path = write(tmp_path / f"long{number}.obj", ending.join(too_long) + ending)
        expect_input_error(
            lambda path=path: read_obj(path), path, line=number + 1, match="longer than 16"
        )
    # the last line, without a line end
    path = write(tmp_path / "last.obj", ending.join(lines) + ending + b"#" * 17)
    expect_input_error(lambda: read_obj(path), path, line=len(lines) + 1, match="longer than 16")


# --------------------------------------------------------------------------------------------
# sequences: frames that disagree name both files and the frame


def write_frames(folder: Path, count: int) -> list[Path]:
    """``count`` frames of a quad and a triangle, the vertices moving along x."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for frame in range(count):
        vertices = "".join(f"v {x + frame} {y} 0\n" for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)])
        paths.append(write(folder / f"f{frame}.obj", vertices + "v 2 2 2\nf 1 2 3 4\nf 2 3 5\n"))
    return paths


def test_frames_with_other_vertex_counts_name_both_files(tmp_path: Path) -> None:
    paths = write_frames(tmp_path / "seq", 4)
    write(paths[2], paths[2].read_text() + "v 3 3 3\n")
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=8,  # the first vertex too many
        frame=2,
        match="has 6 vertices but the first frame has 5",
    )
    assert str(paths[0]) in str(error)
    # fewer vertices: the line of the last one there is
    write(paths[2], "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 2 3 4\n")
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=4,
        frame=2,
        match="has 4 vertices but the first frame has 5",
    )
    assert str(paths[0]) in str(error)


def test_frames_with_other_faces_name_both_files(tmp_path: Path) -> None:
    paths = write_frames(tmp_path / "seq", 3)
    write(paths[1], paths[1].read_text().replace("f 2 3 5", "f 2 5 3"))
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[1],
        line=7,
        frame=1,
        match="face 2 is f 2 5 3 but in the first frame it is f 2 3 5",
    )
    assert str(paths[0]) in str(error)


def test_frames_with_other_relative_faces_are_compared_by_meaning(tmp_path: Path) -> None:
    paths = write_frames(tmp_path / "seq", 3)
    write(paths[1], paths[1].read_text().replace("f 2 3 5", "f -4 -3 -1"))  # the same face
    write(paths[2], paths[2].read_text().replace("f 2 3 5", "f -4 -1 -3"))  # another one
    expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=7,
        frame=2,
        match="face 2 is f 2 5 3",
    )


def test_frames_read_by_trimesh_name_both_files_too(tmp_path: Path) -> None:
    folder = tmp_path / "off"
    folder.mkdir()
    square = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
    write(folder / "a0.off", square)
    write(
        folder / "a1.off", square.replace("4 1 0", "5 1 0").replace("0 1 0\n4", "0 1 0\n2 2 2\n4")
    )
    error = expect_input_error(
        lambda: load_sequence(folder, progress=False),
        folder / "a1.off",
        frame=1,
        match="has 5 vertices but the first frame has 4",
    )
    assert str(folder / "a0.off") in str(error)


@pytest.mark.parametrize(
    ("damage", "line", "message"),
    [
        (lambda text: text.replace("v 2 2 2", "v 2 2"), 5, "got 2 value"),
        (lambda text: text.replace("v 2 2 2", "v 2 2 nan"), 5, "non-finite"),
        (lambda text: "", None, "empty"),
        (lambda text: text + "\x00", 8, "NUL"),
    ],
)
def test_a_bad_middle_frame_is_named(
    tmp_path: Path, damage: Callable[[str], str], line: int | None, message: str
) -> None:
    paths = write_frames(tmp_path / "seq", 4)
    write(paths[2], damage(paths[2].read_text()))
    for source in (tmp_path / "seq", str(tmp_path / "seq" / "*.obj"), paths):
        expect_input_error(
            lambda source=source: load_sequence(source, progress=False),
            paths[2],
            line=line,
            frame=2,
            match=message,
        )


# ============================================================================================
# .npz


def npz_bytes(compressed: bool = False, **arrays: np.ndarray) -> bytes:
    """The bytes of an .npz archive of ``arrays`` (stored, or deflated like savez_compressed)."""
    buffer = io.BytesIO()
    (np.savez_compressed if compressed else np.savez)(buffer, **arrays)
    return buffer.getvalue()


def npy_bytes(header: dict, payload: bytes) -> bytes:
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


V3 = np.arange(2 * 3 * 3, dtype=np.float64).reshape(2, 3, 3)
TRI = np.array([[0, 1, 2]])


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
        ({"V": V3, "F": np.array([[0, 1, -2]])}, r"'F': face 0 has a vertex index -2 outside 0\.\.2"),
        ({"V": V3, "F": np.array([[0, 1, 3]])}, "1-based"),
        ({"V": V3, "F": np.array([[0, 1, 7]])}, r"outside 0\.\.2"),
        ({"V": V3, "F": np.array([[0, 1, 2**62]])}, r"outside 0\.\.2"),
        ({"V": V3, "F": np.array([[0, -1, 1, 2]])}, "face 0 is padded before its end"),  # padding inside
        ({"V": V3, "F": np.array([[0, 1, -1]])}, "face 0 is padded before its end"),  # under 3 corners
        # unsigned indices that a cast to int64 would turn into -1 padding
        ({"V": V3, "F": np.array([[0, 1, 2, 2**64 - 1]], dtype=np.uint64)}, r"outside 0\.\.2"),
        # frame names and rate
        ({"V": V3, "frame_files": np.array(["a"])}, "'frame_files' must be 2 strings"),
        ({"V": V3, "frame_files": np.array([1, 2])}, "'frame_files' must be 2 strings"),
        ({"V": V3, "frame_files": np.array(["a", "b"], dtype=object)}, "Python objects"),
        ({"V": V3, "frame_files": np.array([b"a", b"\xff"])}, "not UTF-8"),
        ({"V": V3, "frame_rate": np.array(np.nan)}, "'frame_rate' must be a positive"),
        ({"V": V3, "frame_rate": np.array([25.0, 30.0])}, "'frame_rate' must be one number"),
        ({"V": V3, "frame_rate": np.array("25")}, "'frame_rate' must be one number"),
    ],
)
def test_bad_npz_is_refused_naming_file_and_key(
    tmp_path: Path, arrays: dict[str, np.ndarray], message: str
) -> None:
    path = write(tmp_path / "bad.npz", npz_bytes(**arrays))
    expect_input_error(lambda: load_sequence(path), path, match=message)
    compressed = write(tmp_path / "bad_compressed.npz", npz_bytes(True, **arrays))
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
    path = write(tmp_path / "nan.npz", npz_bytes(V=values))
    expect_input_error(lambda: load_sequence(path), path, frame=1, match="vertex 2 .*non-finite")


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
        path = write(tmp_path / f"ok{number}.npz", npz_bytes(**arrays))
        seq = load_sequence(path)
        check_sequence(seq)
        np.testing.assert_array_equal(seq.vertices.reshape(-1, 3), arrays["V"].reshape(-1, 3))


def test_the_api_checks_what_the_npz_reader_checks() -> None:
    vertices = np.zeros((1, 3, 3))
    with pytest.raises(InputError, match="outside 0..2"):  # not read as -1 padding
        MeshSequence(vertices, np.array([[0, 1, 2, 2**64 - 1]], dtype=np.uint64))
    if np.finfo(np.longdouble).max > np.finfo(np.float64).max:
        huge = np.full((1, 3, 3), np.finfo(np.longdouble).max, dtype=np.longdouble)
        with pytest.raises(InputError, match="non-finite"):  # and no RuntimeWarning
            MeshSequence(huge, np.zeros((0, 3), dtype=int))


class _Trap:
    """Unpickling this would create the file named by ``target``: it must never happen."""

    def __init__(self, target: str) -> None:
        self.target = target

    def __reduce__(self) -> tuple:
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
        path = write(tmp_path / f"{key}.npz", zip_bytes(members))
        expect_input_error(lambda path=path: load_sequence(path), path, match="Python objects")
        assert not trap.exists()
    # a structured dtype with an object field is just as much a pickle
    header = {"descr": [("a", "|O")], "fortran_order": False, "shape": (1,)}
    path = write(tmp_path / "field.npz", zip_bytes({"V.npy": npy_bytes(header, payload)}))
    expect_input_error(lambda: load_sequence(path), path, match="Python objects")
    assert not trap.exists()


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
    path = write(tmp_path / "odd.npz", data)
    expect_input_error(lambda: load_sequence(path), path, match=message)


def test_a_truncated_npz_at_every_offset(tmp_path: Path) -> None:
    for compressed in (False, True):
        whole = npz_bytes(compressed, V=V3, F=TRI, frame_files=np.array(["a", "b"]))
        path = tmp_path / "cut.npz"
        for end in range(len(whole)):
            write(path, whole[:end])
            expect_input_error(lambda path=path: load_sequence(path), path)
        write(path, whole)
        check_sequence(load_sequence(path))


def test_damaged_array_data_is_caught_by_the_crc(tmp_path: Path) -> None:
    whole = bytearray(npz_bytes(V=V3))
    data_at = bytes(whole).find(V3.tobytes())
    whole[data_at + 5] ^= 0x10  # one bit of one coordinate
    path = write(tmp_path / "flipped.npz", bytes(whole))
    expect_input_error(lambda: load_sequence(path), path, match="'V'.*CRC")


def test_an_npy_member_with_trailing_bytes(tmp_path: Path) -> None:
    # Not what numpy writes; and the bytes after the array would escape the CRC check.
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24) + b"x")
    path = write(tmp_path / "trailing.npz", zip_bytes({"V.npy": member}))
    expect_input_error(lambda: load_sequence(path), path, match="'V'.*25 bytes")


def test_a_key_stored_twice(tmp_path: Path) -> None:
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24))
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # zipfile warns of the duplicate name: that is the point
        archive.writestr("V.npy", member)
        archive.writestr("V.npy", member)
    path = write(tmp_path / "twice.npz", buffer.getvalue())
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
    tmp_path: Path, header: dict, payload: bytes, message: str
) -> None:
    for compression in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        path = write(
            tmp_path / "huge.npz", zip_bytes({"V.npy": npy_bytes(header, payload)}, compression)
        )
        raised, elapsed, peak = measure(lambda path=path: load_sequence(path))
        assert isinstance(raised, InputError) and raised.path == str(path), raised
        assert re.search(message, str(raised)), raised
        assert elapsed < 1.0 and peak < 4 * 2**20, (elapsed, peak)


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
    path = write(tmp_path / "py2.npz", zip_bytes({"V.npy": member}))
    np.testing.assert_array_equal(load_sequence(path).vertices, V3)


def test_a_deprecated_dtype_alias_is_read_without_a_warning(tmp_path: Path) -> None:
    # 'a' is numpy's deprecated alias of 'S', and np.dtype warns about it
    members = {f"{name}.npy": npy for name, npy in _members({"V": V3}).items()}
    names = {"descr": "|a1", "fortran_order": False, "shape": (2,)}
    members["frame_files.npy"] = npy_bytes(names, b"pq")
    path = write(tmp_path / "alias.npz", zip_bytes(members))
    assert load_sequence(path).frame_names == ["p", "q"]


def test_a_huge_header_is_refused(tmp_path: Path) -> None:
    header = {"descr": "<f8", "fortran_order": False, "shape": (1, 3), "x": "y" * 200_000}
    path = write(tmp_path / "header.npz", zip_bytes({"V.npy": npy_bytes(header, bytes(24))}))
    expect_input_error(lambda: load_sequence(path), path, match="'V' cannot be read")


def test_a_zip_bomb_member_is_refused_before_inflating(tmp_path: Path) -> None:
    # A deflated member that claims a gigabyte from a kilobyte: deflate expands at most about
    # 1032 times, so the claim is false and nothing is allocated or inflated for it.
    header = {"descr": "<f8", "fortran_order": False, "shape": (2**27, 1, 1)}
    head = npy_bytes(header, b"")
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    body = compressor.compress(head + bytes(2**20)) + compressor.flush()
    path = tmp_path / "bomb.npz"
    write(path, _zip_with_sizes("V.npy", body, zipfile.ZIP_DEFLATED, len(head) + 2**30, 0))
    raised, elapsed, peak = measure(lambda: load_sequence(path))
    assert isinstance(raised, InputError) and "expand" in str(raised), raised
    assert elapsed < 1.0 and peak < 4 * 2**20


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
    path = write(
        tmp_path / "stored.npz",
        _zip_with_sizes("V.npy", head + bytes(64), zipfile.ZIP_STORED, len(head) + 2**30, 0),
    )
    raised, elapsed, peak = measure(lambda: load_sequence(path))
    assert isinstance(raised, InputError) and raised.path == str(path), raised
    assert elapsed < 1.0 and peak < 4 * 2**20


def test_encrypted_and_unsupported_members(tmp_path: Path) -> None:
    member = npy_bytes({"descr": "<f8", "fortran_order": False, "shape": (1, 3)}, bytes(24))
    data = bytearray(zip_bytes({"V.npy": member}))
    encrypted = bytearray(data)
    for signature, flag_at in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):
        at = bytes(encrypted).find(signature) + flag_at
        encrypted[at] |= 1
    path = write(tmp_path / "encrypted.npz", bytes(encrypted))
    expect_input_error(lambda: load_sequence(path), path, match="'V' is encrypted")
    odd = bytearray(data)
    for signature, method_at in ((b"PK\x03\x04", 8), (b"PK\x01\x02", 10)):
        at = bytes(odd).find(signature) + method_at
        odd[at : at + 2] = struct.pack("<H", 99)
    path = write(tmp_path / "method99.npz", bytes(odd))
    expect_input_error(lambda: load_sequence(path), path, match="'V' .*method 99")
    path = write(tmp_path / "bzip2.npz", zip_bytes({"V.npy": member}, zipfile.ZIP_BZIP2))
    expect_input_error(lambda: load_sequence(path), path, match="'V' .*method 12")


# ============================================================================================
# property tests: random bytes and random mutations


def _scratch() -> Path:
    """A scratch folder for one property test (function-scoped fixtures do not mix with given)."""
    return Path(tempfile.mkdtemp(prefix="tkc-hostile-"))


# Tokens that have broken OBJ readers: non-numbers, huge numbers, odd separators and line ends,
# bytes that are not UTF-8, a NUL.
OBJ_TOKENS = [
    b"nan",
    b"inf",
    b"-inf",
    b"1e999",
    b"-0",
    b"0",
    b"-1",
    b"-9",
    b"+3",
    b".",
    b"e5",
    b"1.5e",
    b"/",
    b"//",
    b"#",
    b"\\",
    b"\\\n",
    b"\r",
    b"\n",
    b"\r\n",
    b"\t",
    b" ",
    b"v ",
    b"f ",
    b"vt ",
    b"99999999999999999999",
    b"7" * 5000,
    b"1/2/3",
    b"-1/-1/-1",
    b"\xff",
    b"\xc3",
    b"\xe2\x82",
    b"\x00",
    b"\xef\xbb\xbf",
    b"\x0b",
    b"\x0c",
]


@st.composite
def mutations(draw: st.DrawFn, base: bytes, tokens: list[bytes]) -> bytes:
    """``base`` after 1 to 8 random edits: bytes flipped, set, inserted, deleted, lines
    duplicated or dropped, tokens inserted, or the end cut off."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(["flip", "set", "insert", "delete", "token", "line", "cut"]))
        at = draw(st.integers(0, len(data)))
        if kind == "flip" and at < len(data):
            data[at] ^= 1 << draw(st.integers(0, 7))
        elif kind == "set" and at < len(data):
            data[at] = draw(st.integers(0, 255))
        elif kind == "insert":
            data[at:at] = draw(st.binary(min_size=1, max_size=8))
        elif kind == "delete":
            del data[at : at + draw(st.integers(1, 16))]
        elif kind == "token":
            data[at:at] = draw(st.sampled_from(tokens))
        elif kind == "line":
            lines = bytes(data).split(b"\n")
            row = draw(st.integers(0, len(lines) - 1))
            if draw(st.booleans()):
                lines.insert(row, lines[row])
            else:
                del lines[row]
            data = bytearray(b"\n".join(lines))
        elif kind == "cut":
            del data[at:]
    return bytes(data)


def _obj_outcome(path: Path) -> None:
    """Read ``path`` as OBJ: it must succeed with a valid mesh or raise an InputError naming it."""
    try:
        vertices, faces = read_obj(path)
    except InputError as error:
        assert error.path == str(path) and str(error).startswith(str(path))
        return
    check_obj_result(path, vertices, faces)


@PROPERTY
@given(data=st.binary(max_size=2048))
def test_random_bytes_as_obj(data: bytes) -> None:
    EXAMPLES_RUN["random bytes as OBJ"] = EXAMPLES_RUN.get("random bytes as OBJ", 0) + 1
    path = write(SCRATCH / "random.obj", data)
    _obj_outcome(path)


@PROPERTY
@given(data=mutations(VALID_OBJ, OBJ_TOKENS))
def test_mutated_obj(data: bytes) -> None:
    EXAMPLES_RUN["mutated OBJ"] = EXAMPLES_RUN.get("mutated OBJ", 0) + 1
    path = write(SCRATCH / "mutated.obj", data)
    _obj_outcome(path)


@PROPERTY
@given(data=mutations(VALID_OBJ, OBJ_TOKENS))
def test_mutated_second_frame(data: bytes) -> None:
    """A sequence whose second frame is mutated: a valid sequence, or an error naming frame 1."""
    EXAMPLES_RUN["mutated frame of a sequence"] = (
        EXAMPLES_RUN.get("mutated frame of a sequence", 0) + 1
    )
    folder = SCRATCH / "seq"
    folder.mkdir(exist_ok=True)
    write(folder / "a0.obj", VALID_OBJ)
    second = write(folder / "a1.obj", data)
    try:
        seq = load_sequence(folder, progress=False)
    except InputError as error:
        assert (error.path, error.frame) == (str(second), 1), str(error)
        return
    check_sequence(seq)
    assert seq.frame_count == 2


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
        assert error.path == str(path) and str(error).startswith(str(path))
        return
    check_sequence(seq)


@PROPERTY
@given(data=st.one_of(st.binary(max_size=1024), st.binary(max_size=1024).map(lambda b: b"PK" + b)))
def test_random_bytes_as_npz(data: bytes) -> None:
    EXAMPLES_RUN["random bytes as npz"] = EXAMPLES_RUN.get("random bytes as npz", 0) + 1
    _npz_outcome(write(SCRATCH / "random.npz", data))


@PROPERTY
@given(
    data=st.one_of(mutations(VALID_NPZ, NPZ_TOKENS), mutations(VALID_NPZ_COMPRESSED, NPZ_TOKENS))
)
def test_mutated_npz(data: bytes) -> None:
    EXAMPLES_RUN["mutated npz"] = EXAMPLES_RUN.get("mutated npz", 0) + 1
    _npz_outcome(write(SCRATCH / "mutated.npz", data))


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
    _npz_outcome(write(SCRATCH / "member.npz", zip_bytes(members, method)))


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
def test_any_npy_header(descr: str, shape: tuple, fortran: bool, payload: int, key: str) -> None:
    """Any dtype and shape in a header, with any amount of data behind it: an InputError or a
    valid sequence, in small memory."""
    EXAMPLES_RUN["any .npy header"] = EXAMPLES_RUN.get("any .npy header", 0) + 1
    if payload < 0:
        try:
            payload = max(0, min(math.prod(shape) * np.dtype(descr).itemsize, 4096))
        except Exception:  # noqa: BLE001 - a descr numpy refuses: any payload will do
            payload = 0
    member = npy_bytes({"descr": descr, "fortran_order": fortran, "shape": shape}, bytes(payload))
    members = {f"{name}.npy": npy for name, npy in _members({"V": V3}).items()}
    members[f"{key}.npy"] = member
    path = write(SCRATCH / "header.npz", zip_bytes(members))
    raised, _, peak = measure(lambda: check_sequence(load_sequence(path)))
    assert raised is None or isinstance(raised, InputError), repr(raised)
    assert peak < 4 * 2**20, peak


def _members(arrays: dict[str, np.ndarray]) -> dict[str, bytes]:
    """The .npy bytes of each array."""
    out = {}
    for name, array in arrays.items():
        buffer = io.BytesIO()
        np.lib.format.write_array(buffer, array, allow_pickle=False)
        out[name] = buffer.getvalue()
    return out


SCRATCH = _scratch()


def teardown_module() -> None:
    """Report how many examples each property test ran (shown with ``pytest -s``)."""
    import shutil

    shutil.rmtree(SCRATCH, ignore_errors=True)
    if EXAMPLES_RUN:
        sys.stdout.write(
            "\nhypothesis examples run: "
            + ", ".join(f"{name} {count}" for name, count in EXAMPLES_RUN.items())
            + f"; total {sum(EXAMPLES_RUN.values())}\n"
        )
