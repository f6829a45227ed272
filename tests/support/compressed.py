"""Compressed files: the conformance vectors of spec/vectors taken apart, edited and put back
together with correct CRCs, and decoded under a deadline; the reference walk of spec §6.2 and
what a decoded file must agree with."""

from __future__ import annotations

import contextlib
import math
import signal
import threading
import time
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

import tuckercodec
from tuckercodec import Decoder, FormatError, MeshSequence
from tuckercodec.encoder.attachments import smallest_corner_first
from tuckercodec.format import faces, qmat, residual, sections
from tuckercodec.format.container import (
    CRC,
    HEAD_SIZE,
    PREAMBLE,
    SIGNATURE,
    pack_container,
    pack_raw,
    parse_container,
)
from tuckercodec.format.header import header_map

VECTORS = Path(__file__).resolve().parents[2] / "spec" / "vectors"
#: The valid conformance vectors.
VALID = ["v1-wave-triangles", "v1-polygons-names", "v1-ignorable-extensions"]
IDENTITY_U2 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
#: Time one damaged or crafted file may take to decode (they take milliseconds; a hang trips
#: this).
CASE_SECONDS = 60.0


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


#: An edit of one section: its (entry, payload) to the new ones.
SectionChange = Callable[[dict[str, Any], bytes], tuple[dict[str, Any], bytes]]


def edit_section(data: bytes, section_id: str, change: SectionChange) -> bytes:
    """``data`` with section ``section_id``'s (entry, payload) replaced by
    ``change(entry, payload)``, the file repacked (offsets, lengths, CRCs made right)."""
    parts = Parts(data)
    index = parts.index(section_id)
    parts.sections[index] = change(*parts.sections[index])
    return parts.pack()


def with_params(section_id: str, **params: Any) -> Callable[[bytes], bytes]:
    """An edit that sets ``params`` in section ``section_id``'s entry, its payload kept."""
    return lambda data: edit_section(
        data, section_id, lambda entry, payload: ({**entry, **params}, payload)
    )


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
    """The same faces, each with its corners in the same cyclic order (its winding), in any face
    order and from any first corner: what a file keeps where no data follows the corners
    (faces-traverse, §6.8, lists them in its walk's order, each from its smallest vertex)."""
    decoded, original = np.asarray(decoded), np.asarray(original)
    assert decoded.shape == original.shape
    decoded, original = smallest_corner_first(decoded), smallest_corner_first(original)
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


def chunked_file(
    vertices: int,
    frames: int,
    chunk_frames: int,
    predict: int = 0,
    *,
    face_count: int = 1,
    level: int = 3,
    rank: int = 1,
) -> bytes:
    """A file of format 1.3 of ``vertices`` x ``frames`` built part by part (the encoder would
    take minutes on so many positions): rank (``rank``, 1) factors that decode to zeros, grid
    corrections of zeros in chunks of ``chunk_frames`` frames, and ``face_count`` copies of the
    triangle (0, 1, 2); a few KB however large they decode."""
    ones = qmat.QuantizedMatrix(np.ones((vertices, rank), np.int64), np.ones(rank, np.float32))
    zero_core = qmat.QuantizedMatrix(np.zeros((3 * rank, 1), np.int64), np.ones(1, np.float32))
    time = qmat.QuantizedMatrix(np.ones((frames, 1), np.int64), np.ones(1, np.float32))
    cent = qmat.QuantizedMatrix(np.zeros((frames, 3), np.int64), np.ones(3, np.float32))
    triangles = np.broadcast_to(np.array([0, 1, 2]), (face_count, 3))
    face_params, face_payload = faces.encode_faces(triangles, level)
    table = [(sections.entry("FACE", face_params), face_payload)]
    for section_id, matrix in (("CENT", cent), ("U3", time), ("CORE", zero_core), ("U1", ones)):
        params, payload = qmat.encode_matrix(matrix, None, allow_predict=False, level=level)
        table.append((sections.entry(section_id, params), payload))
    params, payload = residual.encode_section(
        np.broadcast_to(np.zeros((1, 1, 1), np.int64), (frames, vertices, 3)),
        residual.Domain(residual.GRID, 1e-3),
        level,
        chunk_frames=chunk_frames,
        predict=predict,
    )
    table.append(({"id": "RESD", "critical": True, "codec": residual.RESIDUAL, **params}, payload))
    header = header_map(
        vertices=vertices,
        frames=frames,
        ranks=(rank, 1),
        u2=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        kg=0.0,
        truncation_kg=0.0,
        target_kg=None,
        encoder="tests",
        frame_rate=None,
    )
    return pack_container(
        header, table, flags=residual.CORRECTIONS, minor=residual.CORRECTIONS_MINOR
    )
