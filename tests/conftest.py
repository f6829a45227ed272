"""Helpers shared by the test modules, which import them with ``from conftest import ...``.

- sequences: synthetic animations, and the real sequences of ../shared/data when present;
- compressed files: the conformance vectors of spec/vectors taken apart, edited and put back
  together with correct CRCs, and decoded under a deadline;
- sequence files: OBJ and .npz inputs written byte for byte, and the checks every reader error
  must pass;
- property tests: the hypothesis settings and strategies the format and reader tests share.
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import sys
import tempfile
import threading
import time
import tracemalloc
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

import tuckercodec
from tuckercodec import Decoder, FormatError, InputError, MeshSequence
from tuckercodec.format.container import (
    CRC,
    HEAD_SIZE,
    PREAMBLE,
    SIGNATURE,
    pack_container,
    pack_raw,
    parse_container,
)
from tuckercodec.samples import sample_path, sheet_triangles, wave_sheet

# ------------------------------------------------------------------------------------------
# sequences

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def shared_file(name: str) -> Path:
    """A file of ../shared/data, or skip the test saying why it is not there."""
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(
            f"{path} is absent: the real test sequences live in ../shared/data beside the repo"
        )
    return path


def load_shared_npz(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(V, F) of a sequence in ../shared/data, or skip."""
    with np.load(shared_file(name), allow_pickle=False) as data:
        return data["V"], data["F"]


def wave_sequence(frames: int = 24, grid: int = 9, seed: int = 0) -> np.ndarray:
    """A real-looking synthetic animation (:func:`tuckercodec.samples.wave_sheet`) plus a little
    noise so that no rank is exactly zero. Shape (frames, grid*grid, 3)."""
    rng = np.random.default_rng(seed)
    out = wave_sheet(frames, grid)
    return out + 1e-4 * rng.standard_normal(out.shape)


def grid_faces(grid: int = 9) -> np.ndarray:
    """Triangles of the grid sheet used by :func:`wave_sequence`."""
    return sheet_triangles(grid)


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    """The cloth that ships with the package (60 frames of 3101 vertices)."""
    return tuckercodec.load_sequence(sample_path(), progress=False)


# ------------------------------------------------------------------------------------------
# property tests

#: Hypothesis for the format tests: deterministic in CI and no example database written into
#: the repository (each test sets its own ``max_examples``).
HYPOTHESIS_SETTINGS: dict[str, Any] = {
    "deadline": None,
    "database": None,
    "derandomize": True,
    "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large],
}

#: ``TUCKERCODEC_HYPOTHESIS_EXAMPLES`` scales the number of examples of each property test of
#: the readers (for a long local run); CI runs the default, derandomized so that every run tries
#: the same inputs (the long, random exploration is tools/fuzz.py's job).
EXAMPLES = int(os.environ.get("TUCKERCODEC_HYPOTHESIS_EXAMPLES", "0")) or None
PROPERTY = settings(
    max_examples=EXAMPLES or 400,
    deadline=None,
    database=None,
    derandomize=EXAMPLES is None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

#: Values of any msgpack type, out-of-range numbers and odd floats among them.
msgpack_leaves = (
    st.none()
    | st.booleans()
    | st.integers(-(2**63), 2**64 - 1)
    | st.sampled_from([0, 1, -1, 2, 3, 81, 24, 6])
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=20)
    | st.binary(max_size=40)
)
#: Anything msgpack can hold: leaves in lists and maps, nested.
msgpack_values = st.recursive(
    msgpack_leaves,
    lambda children: (
        st.lists(children, max_size=6) | st.dictionaries(st.text(max_size=10), children, max_size=6)
    ),
    max_leaves=25,
)


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


def scratch_folder() -> Path:
    """A scratch folder for the property tests of one module (function-scoped fixtures do not
    mix with ``given``); the module removes it in its ``teardown_module``."""
    return Path(tempfile.mkdtemp(prefix="tkc-property-"))


def report_examples(examples_run: dict[str, int]) -> None:
    """Print how many examples each property test of a module ran (shown with ``pytest -s``)."""
    if examples_run:
        sys.stdout.write(
            "\nhypothesis examples run: "
            + ", ".join(f"{name} {count}" for name, count in examples_run.items())
            + f"; total {sum(examples_run.values())}\n"
        )


# ------------------------------------------------------------------------------------------
# compressed files: the conformance vectors, taken apart, edited and decoded

VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
#: The valid conformance vectors.
VALID = ["v1-wave-triangles", "v1-polygons-names", "v1-ignorable-extensions"]
IDENTITY_U2 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
#: Time one damaged or crafted file may take to decode (they take milliseconds; a hang trips
#: this).
CASE_SECONDS = 5.0


def vector(name: str) -> bytes:
    """The bytes of a conformance vector of spec/vectors."""
    return (VECTORS / f"{name}.tkc").read_bytes()


class Parts:
    """A valid file taken apart: header (without the table), sections with their payloads."""

    def __init__(self, data: bytes) -> None:
        container = parse_container(data)
        self.flags = container.flags
        self.header = {k: v for k, v in container.header.items() if k != "sections"}
        self.sections: list[tuple[dict[str, Any], bytes]] = [
            (
                {"id": s.id, "critical": s.critical, "codec": s.codec, **s.params},
                bytes(container.payload(data, s)),
            )
            for s in container.sections
        ]

    def index(self, section_id: str) -> int:
        return next(n for n, (entry, _) in enumerate(self.sections) if entry["id"] == section_id)

    def pack(self) -> bytes:
        """The file again, offsets, lengths and every CRC-32 made right (pack_container)."""
        return pack_container(self.header, self.sections, flags=self.flags)

    def table(self) -> list[dict[str, Any]]:
        """The section table as pack_container would write it, to be edited raw."""
        out, offset = [], 0
        for entry, payload in self.sections:
            out.append(
                {**entry, "offset": offset, "length": len(payload), "crc32": zlib.crc32(payload)}
            )
            offset += len(payload)
        return out

    def area(self) -> bytes:
        return b"".join(payload for _, payload in self.sections)


def raw_file(
    header: dict[str, Any] | bytes,
    area: bytes = b"",
    *,
    major: int = 1,
    minor: int = 0,
    flags: int = 0,
    total: int | None = None,
) -> bytes:
    """A file from a header (a map, or raw msgpack bytes) and a data area, with correct
    preamble and header CRCs whatever the header says: the checks behind the CRCs are reached."""
    header_bytes = header if isinstance(header, bytes) else msgpack.packb(header, use_bin_type=True)
    return pack_raw(major, minor, flags, header_bytes, area, total=total)


def with_preamble(
    data: bytes,
    *,
    major: int | None = None,
    minor: int | None = None,
    flags: int | None = None,
    header_length: int | None = None,
    total: int | None = None,
) -> bytes:
    """The file with preamble fields changed and the preamble CRC made right again."""
    fields = list(PREAMBLE.unpack_from(data, len(SIGNATURE)))
    for index, value in enumerate((major, minor, flags, header_length, total)):
        if value is not None:
            fields[index] = value
    head = SIGNATURE + PREAMBLE.pack(*fields)
    return head + CRC.pack(zlib.crc32(head)) + data[HEAD_SIZE:]


def table_file(
    edit: Callable[[list[dict[str, Any]], Parts], object], area: bytes | None = None
) -> bytes:
    """v1-wave-triangles with its section table edited raw by ``edit(table, parts)``, the
    header CRC made right again."""
    parts = Parts(vector("v1-wave-triangles"))
    table = parts.table()
    edit(table, parts)
    return raw_file({**parts.header, "sections": table}, parts.area() if area is None else area)


class Hang(Exception):
    """A case ran past its deadline."""


@contextlib.contextmanager
def deadline(seconds: float = CASE_SECONDS) -> Iterator[None]:
    """Fail a case that runs too long: SIGALRM where there is one (it interrupts a Python-level
    loop); elsewhere the elapsed time is checked afterwards."""
    usable = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
    started = time.perf_counter()
    if usable:

        def expire(signum: int, frame: Any) -> None:
            raise Hang(f"the case ran for more than {seconds} s")

        previous = signal.signal(signal.SIGALRM, expire)
        signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        if usable:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
    elapsed = time.perf_counter() - started
    assert elapsed < seconds, f"the case took {elapsed:.1f} s"


def outcome(data: bytes) -> tuple[FormatError | None, MeshSequence | None]:
    """Decode the whole file (every frame reconstructed) within the deadline: ``(error, None)``
    or ``(None, sequence)``. Any exception but FormatError propagates and fails the test."""
    with deadline():
        try:
            return None, tuckercodec.decode(data)
        except FormatError as error:
            return error, None


def expect_error(
    data: bytes, kind: type[FormatError] = FormatError, *, exact: bool = False
) -> FormatError:
    """The file must fail with ``kind`` (a subclass too, unless ``exact``); ``info`` must fail as
    well or accept only what it reads (the header)."""
    error, sequence = outcome(data)
    assert sequence is None, f"decoded although it should fail with {kind.__name__}"
    assert isinstance(error, kind), f"{type(error).__name__} ({error}) is not a {kind.__name__}"
    if exact:
        assert type(error) is kind, (
            f"{type(error).__name__} ({error}), expected exactly {kind.__name__}"
        )
    with deadline(), contextlib.suppress(FormatError):
        tuckercodec.info(data)
    return error


@dataclass
class SpecWalk:
    """The breadth-first walk of spec/FORMAT.md §6.2, literally: each vertex's neighbours,
    parent and depth, and the order in which the walk reaches the vertices."""

    neighbours: list[set[int]]
    parent: list[int]
    depth: list[int]
    reached_order: list[int]


def spec_walk(faces: np.ndarray, count: int) -> SpecWalk:
    """§6.2's pseudocode in plain Python, for tests to hold the reference to."""
    neighbours: list[set[int]] = [set() for _ in range(count)]
    for face in faces.tolist():
        for j, a in enumerate(face):
            if a < 0:
                continue
            b = face[j + 1] if j + 1 < len(face) and face[j + 1] >= 0 else face[0]
            if a != b:
                neighbours[a].add(b)
                neighbours[b].add(a)
    parent, depth, reached_order = [-1] * count, [0] * count, []
    reached = [False] * count
    for s in range(count):
        if reached[s]:
            continue
        reached[s] = True
        reached_order.append(s)
        queue, head = [s], 0
        while head < len(queue):
            u = queue[head]
            head += 1
            for w in sorted(neighbours[u]):
                if not reached[w]:
                    reached[w], parent[w], depth[w] = True, u, depth[u] + 1
                    reached_order.append(w)
                    queue.append(w)
    return SpecWalk(neighbours, parent, depth, reached_order)


def assert_same_faces(decoded: np.ndarray, original: np.ndarray) -> None:
    """The same faces, each with its corners in the same order, in any face order: what a file
    keeps (faces-traverse, §6.8, lists them in its walk's order)."""
    decoded, original = np.asarray(decoded), np.asarray(original)
    assert decoded.shape == original.shape
    assert sorted(map(tuple, decoded.tolist())) == sorted(map(tuple, original.tolist()))


def check_decoded(data: bytes, sequence: MeshSequence) -> None:
    """A file that decodes must agree with itself: info, random access (§8), finite values."""
    header = tuckercodec.info(data)
    assert sequence.vertices.shape == (header.frames, header.vertices, 3)
    assert np.isfinite(sequence.vertices).all()
    decoder = Decoder(data)
    last = header.frames - 1
    scale = float(np.abs(sequence.vertices[last]).max())
    np.testing.assert_allclose(
        decoder.frame(last), sequence.vertices[last], rtol=0, atol=1e-9 * scale + 1e-12
    )


def accept_either(data: bytes) -> FormatError | None:
    """Hypothesis-made files: FormatError, or a decode that is consistent."""
    error, sequence = outcome(data)
    if sequence is not None:
        check_decoded(data, sequence)
    return error


#: Values for any field of a header or a section: zero, negative, huge and every wrong type.
#: 2**64 itself has no msgpack encoding (the largest msgpack int is 2**64 - 1), so "huge" is
#: 2**63, 2**64 - 1 and the floats 2.0**64 and 1e308.
HOSTILE = {
    "zero": 0,
    "minus one": -1,
    "most negative": -(2**63),
    "2**31": 2**31,
    "2**63": 2**63,
    "2**64-1": 2**64 - 1,
    "float 2**64": 2.0**64,
    "1e308": 1e308,
    "-1e308": -1e308,
    "float zero": 0.0,
    "nan": math.nan,
    "inf": math.inf,
    "-inf": -math.inf,
    "str": "12",
    "empty str": "",
    "bytes": b"\x01",
    "list": [1, 2],
    "empty list": [],
    "dict": {"a": 1},
    "empty dict": {},
    "none": None,
    "true": True,
    "false": False,
}
#: A field removed instead of set.
MISSING = object()


# ------------------------------------------------------------------------------------------
# sequence files: OBJ and .npz inputs, and what a reader's answer must be

#: Three vertices, the start of many OBJ test files.
TRIANGLE = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"

#: A small OBJ that uses most of what the reader knows: comments, vt/vn, slashed corners, a
#: quad and triangles, a negative (relative) index, CRLF on one line, a weight on one vertex.
VALID_OBJ = (
    b"# cube corner\r\nmtllib m.mtl\no thing\n"
    b"v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nv 0 0 1\nv 1 0 1\n"
    b"vt 0 0\nvt 1 0\nvn 0 0 1\ng side\nusemtl red\ns off\n"
    b"f 1/1/1 2/2/1 3/2/1 4/1/1\nf 1//1 2//1 5//1\nf -1 -2 2\nf 5 6 2\n"
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
