"""Sequence files: OBJ and .npz inputs written byte for byte, and the checks every reader error
and every loaded sequence must pass."""

from __future__ import annotations

import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from tuckercodec import InputError, MeshSequence

#: Three vertices, the start of many OBJ test files.
TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"

#: A small OBJ that uses most of what the reader knows: comments, vt/vn, slashed corners, a
#: quad and triangles, a negative (relative) index, CRLF on one line, a weight on one vertex.
VALID_OBJ = (
    b"# cube corner\r\nmtllib m.mtl\no thing\n"
    b"v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n"
    b"vt 0 0\nvt 1 0\nvn 0 0 1\ng side\nusemtl red\ns off\n"
    b"f 1/1/1 2/2/1 3/2/1 4/1/1\nf 1/1/1 2/2/1 5/1/1\nf -1/-1/-1 -2/-2/1 2/2/1\n"
    b"f 5/1/1 6/2/1 2/2/1\n"
)

#: Tokens that have broken OBJ readers: non-numbers, huge numbers, odd separators and line
#: ends, bytes that are not UTF-8, a NUL.
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

CUBE_VERTICES = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float64,
)


def write_file(path: Path, data: str | bytes) -> Path:
    """Write a test file verbatim (no newline translation)."""
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    return path


def obj_text(vertices: np.ndarray, faces: list[list[int]]) -> str:
    """A minimal OBJ text: ``v`` lines, then 1-based ``f`` lines."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices).tolist()]
    lines += ["f " + " ".join(str(i) for i in face) for face in faces]
    return "\n".join(lines) + "\n"


def write_cube_frames(folder: Path, count: int, name: str = "frame{}.obj") -> list[Path]:
    """``count`` OBJ frames of a moving cube (vertex x shifted by the frame number)."""
    folder.mkdir(parents=True, exist_ok=True)
    faces = [[1, 2, 3, 4], [5, 6, 7, 8], [1, 2, 6]]
    paths = []
    for frame in range(count):
        path = folder / name.format(frame)
        write_file(path, obj_text(CUBE_VERTICES + np.array([frame, 0, 0]), faces))
        paths.append(path)
    return paths


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


def check_sequence(seq: MeshSequence) -> None:
    """What a successfully loaded sequence must be."""
    assert isinstance(seq, MeshSequence)
    assert seq.vertices.dtype == np.float64 and np.isfinite(seq.vertices).all()
    assert seq.faces.dtype == np.int64
    MeshSequence(seq.vertices, seq.faces, frame_names=seq.frame_names)  # passes every check
    assert len(seq.frame_names) == seq.frame_count


def measure(call: Callable[[], object]) -> tuple[BaseException | None, float, int]:
    """Run ``call``: the exception it raised, its time in seconds and its peak traced memory
    (numpy reports its buffers to tracemalloc)."""
    tracemalloc.start()
    start = time.perf_counter()
    raised: BaseException | None = None
    try:
        call()
    except BaseException as error:  # returned to the caller, whatever it is
        raised = error
    elapsed = time.perf_counter() - start
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return raised, elapsed, peak
