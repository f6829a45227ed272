"""The compressed file's door: the decoder's oracle and the structural mutator of .tkc files.

Every input of the ``decoder`` target goes through :func:`check_input`: ``tuckercodec.decode``,
``tuckercodec.info`` and ``Decoder(data).frame(0)``. Each must either succeed or raise
:class:`tuckercodec.FormatError` (or a subclass): the documented error for a bad file. Beyond
that, the three entry points must agree: ``info`` must accept every file ``decode`` accepts and
report the same sizes, and frame 0 decoded alone must match frame 0 of the whole sequence (§8).

Most random bytes fail a CRC-32 at once, so besides libFuzzer's byte mutations a structural
mutator rebuilds the file with correct checksums after changing one header value, one
section-table entry or one decoded payload: the semantic checks behind the checksums are
reached as often as the checksums themselves.
"""

from __future__ import annotations

import random
import struct
import traceback
import zlib
from pathlib import Path
from typing import Any

# ------------------------------------------------------------------------------------------
# the oracle: what every input must do


class InvariantError(AssertionError):
    """The three entry points disagree about one input."""


def check_input(data: bytes) -> str:
    """Run one input through the decoder's entry points; return ``"ok"`` or the name of the
    :class:`~tuckercodec.FormatError` subclass it ended in.

    Raises whatever else escapes (the crash), or :class:`InvariantError`.
    """
    import numpy as np

    import tuckercodec
    from tuckercodec import Decoder, FormatError

    outcome = "ok"
    sequence = None
    try:
        sequence = tuckercodec.decode(data)
    except FormatError as error:
        outcome = type(error).__name__
    try:
        header = tuckercodec.info(data)
    except FormatError as error:
        if sequence is not None:
            raise InvariantError(f"decode accepts the file but info raises {error!r}") from None
        header = None
    sizes = None if header is None else (header.frames, header.vertices)
    if sequence is not None and sizes is not None and sizes != sequence.vertices.shape[:2]:
        raise InvariantError(
            f"info says {sizes[0]} x {sizes[1]}, decode gives {sequence.vertices.shape}"
        )
    try:
        first = Decoder(data).frame(0)
    except FormatError as error:
        if sequence is not None:
            raise InvariantError(f"decode accepts the file but frame(0) raises {error!r}") from None
        first = None
    if sequence is not None and first is not None:
        reference = sequence.vertices[0]
        tolerance = 1e-9 * float(np.abs(reference).max()) + 1e-12  # spec/FORMAT.md §8
        if not np.allclose(first, reference, rtol=0, atol=tolerance):
            raise InvariantError("frame 0 decoded alone differs from frame 0 of the whole sequence")
    return outcome


def signature_of(error: BaseException) -> str:
    """A short name for a failure: its type and where in tuckercodec (or beyond) it was raised,
    so that one bug found a thousand times is saved once."""
    frames = traceback.extract_tb(error.__traceback__)
    ours = [f for f in frames if "tuckercodec" in f.filename] or frames
    place = f"{Path(ours[-1].filename).stem}-{ours[-1].lineno}" if ours else "unknown"
    return f"{type(error).__name__}-{place}"


# ------------------------------------------------------------------------------------------
# the structural mutator


def _lenient_parse(data: bytes) -> tuple[list[int], dict[str, Any], bytes] | None:
    """``(preamble fields, header, data area)`` of anything that looks like a container, or
    ``None``. Nothing is checked: the point is to edit and re-sign."""
    import msgpack

    from tuckercodec.internal import PREAMBLE, SIGNATURE

    if len(data) < 32 or data[:8] != SIGNATURE:
        return None
    fields = list(PREAMBLE.unpack_from(data, 8))
    header_length = fields[3]
    if 32 + header_length + 4 > len(data):
        return None
    try:
        header = msgpack.unpackb(data[32 : 32 + header_length], raw=False, strict_map_key=False)
    except Exception:  # any damage means "not parseable", never a crash here
        return None
    if not isinstance(header, dict):
        return None
    return fields, header, data[36 + header_length :]


def _sections(header: dict[str, Any], area: bytes) -> list[tuple[dict[str, Any], bytes]] | None:
    """The section entries with their payloads, when the table is well formed enough."""
    table = header.get("sections")
    if not isinstance(table, list):
        return None
    out = []
    for entry in table:
        if not isinstance(entry, dict):
            return None
        offset, length = entry.get("offset"), entry.get("length")
        if not (
            isinstance(offset, int) and isinstance(length, int) and offset >= 0 and length >= 0
        ):
            return None
        out.append((dict(entry), area[offset : offset + length]))
    return out


def _pack(
    fields: list[int],
    header: dict[str, Any],
    sections: list[tuple[dict[str, Any], bytes]] | None,
    area: bytes,
    rng: random.Random,
) -> bytes:
    """A file with correct CRCs (and mostly correct offsets and lengths) from edited parts."""
    import msgpack

    from tuckercodec.internal import pack_raw

    header = dict(header)
    if sections is not None:
        table, offset, parts = [], 0, []
        for entry, payload in sections:
            entry = dict(entry)
            if rng.random() < 0.95:  # now and then keep a stale field, to reach the table checks
                entry.update(offset=offset, length=len(payload), crc32=zlib.crc32(payload))
            table.append(entry)
            offset += len(payload)
            parts.append(payload)
        header["sections"] = table
        area = b"".join(parts)
    major, minor, flags, _, _ = fields
    return pack_raw(major, minor, flags, msgpack.packb(header, use_bin_type=True), area)


_EDGE_INTS = [
    0,
    1,
    -1,
    2,
    3,
    4,
    5,
    64,
    65,
    255,
    256,
    2**16,
    2**24,
    2**24 + 1,
    2**26,
    2**26 + 1,
    2**27,
    2**28,
    2**31 - 1,
    2**31,
    2**32 - 1,
    2**32,
    2**53 + 1,
    2**63 - 1,
    -(2**63),
    2**64 - 1,
    10**9,
]
_EDGE_FLOATS = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    1e308,
    -1e308,
    5e-324,
    float("nan"),
    float("inf"),
    float("-inf"),
    3.4e38,
]


def _hostile_value(rng: random.Random, current: Any, depth: int = 0) -> Any:
    """A value a careless decoder might trip over, often close to ``current``."""
    import msgpack

    kind = rng.randrange(12)
    if kind == 0 and isinstance(current, int) and not isinstance(current, bool):
        return max(
            -(2**63), min(2**64 - 1, current + rng.choice([-1, 1, -2, 2, current, -current]))
        )
    if kind == 1:
        return rng.choice(_EDGE_INTS)
    if kind == 2:
        return rng.choice(_EDGE_FLOATS)
    if kind == 3:
        return rng.choice([None, True, False])
    if kind == 4:
        return rng.choice(
            [
                "",
                "FACE",
                "U1",
                "U3",
                "CORE",
                "CENT",
                "NAME",
                "qmat",
                "faces-delta",
                "msgpack-zstd",
                "x" * 17,
                "\x00",
                "é",
                "karni-gotsman-2004",
            ]
        )
    if kind == 5:
        return bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 3, 4, 8, 12, 24])))
    if kind == 6 and isinstance(current, bytes) and current:
        out = bytearray(current)
        out[rng.randrange(len(out))] = rng.randrange(256)
        return bytes(out)
    if kind == 7 and depth < 3:
        return [_hostile_value(rng, None, depth + 1) for _ in range(rng.choice([0, 1, 2, 3, 9]))]
    if kind == 8 and depth < 3:
        return {rng.choice(["shape", "planes", "id", "x"]): _hostile_value(rng, None, depth + 1)}
    if kind == 9:
        return msgpack.ExtType(rng.choice([1, 5, 127]), b"\x00" * rng.choice([0, 4]))
    if kind == 10 and isinstance(current, list) and current:
        items = list(current)
        items[rng.randrange(len(items))] = _hostile_value(rng, None, depth + 1)
        return items
    return rng.choice(_EDGE_INTS + _EDGE_FLOATS)


def _containers_in(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[tuple[Any, ...], Any]]:
    """Every (path, value) in a header tree, to pick one to change."""
    out = [(path, value)]
    if isinstance(value, dict):
        for key, item in value.items():
            out.extend(_containers_in(item, (*path, key)))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            out.extend(_containers_in(item, (*path, index)))
    return out


def _set_path(root: Any, path: tuple[Any, ...], value: Any) -> None:
    for key in path[:-1]:
        root = root[key]
    root[path[-1]] = value


def _mutate_header(rng: random.Random, header: dict[str, Any]) -> None:
    """Change, delete or add one value anywhere in the header (the table included)."""
    paths = [p for p, _ in _containers_in(header) if p]
    if not paths or rng.random() < 0.1:
        header[rng.choice(["vertices", "frames", "ranks", "u2", "frame_rate", "x-new"])] = (
            _hostile_value(rng, None)
        )
        return
    path = rng.choice(paths)
    parent = header
    for key in path[:-1]:
        parent = parent[key]
    current = parent[path[-1]]
    if isinstance(parent, dict) and rng.random() < 0.15:
        del parent[path[-1]]
    else:
        _set_path(header, path, _hostile_value(rng, current))


def _mutate_table(rng: random.Random, sections: list[tuple[dict[str, Any], bytes]]) -> None:
    """Reorder, repeat, drop or relabel section entries."""
    if not sections:
        return
    what = rng.randrange(5)
    index = rng.randrange(len(sections))
    if what == 0:
        sections.insert(rng.randrange(len(sections) + 1), sections[index])
    elif what == 1:
        del sections[index]
    elif what == 2:
        rng.shuffle(sections)
    elif what == 3:
        entry, payload = sections[index]
        sections[index] = (
            {**entry, "id": rng.choice(["FACE", "U1", "U3", "CORE", "CENT", "NAME", "XTRA"])},
            payload,
        )
    else:
        entry, payload = sections[index]
        sections[index] = ({**entry, "critical": not entry.get("critical")}, payload)


def decompressed_start(payload: bytes, limit: int = 1 << 20) -> bytearray:
    """At most ``limit`` bytes of a zstd frame's content, or the payload itself if it is not
    one. Streamed: ``ZstdDecompressor.decompress`` allocates what a frame header declares,
    whatever ``max_output_size`` says, so a crafted frame made the mutator raise MemoryError
    (or allocate gigabytes)."""
    import zstandard

    try:
        with zstandard.ZstdDecompressor().stream_reader(payload) as reader:
            return bytearray(reader.read(limit))
    except zstandard.ZstdError:
        return bytearray(payload)


def _mutate_payload(rng: random.Random, sections: list[tuple[dict[str, Any], bytes]]) -> None:
    """Decompress one section, change its content and compress it again, declaring the new
    size (or a wrong one): the integer-level checks behind zstd are reached."""
    import zstandard

    if not sections:
        return
    index = rng.randrange(len(sections))
    entry, payload = sections[index]
    raw = decompressed_start(payload)
    what = rng.randrange(8)
    if raw and what <= 2:  # a few bytes to anything
        for _ in range(rng.choice([1, 1, 2, 4])):
            raw[rng.randrange(len(raw))] = rng.randrange(256)
    elif raw and what == 3:  # a run of 0xFF: the largest values a plane can hold
        start = rng.randrange(len(raw))
        raw[start : start + rng.choice([1, 4, 16])] = b"\xff" * len(raw[start : start + 16])
    elif what == 4:  # grow or shrink the content
        raw = (
            raw[: rng.randrange(len(raw) + 1)]
            if rng.random() < 0.5
            else raw + bytes(rng.choice([1, 3, 4, 81]))
        )
    elif what == 5 and isinstance(entry.get("planes"), int) and entry["planes"] in (1, 2, 3):
        # the same integers in more planes: still valid, exercises the plane arithmetic
        planes = entry["planes"]
        count = len(raw) // planes
        extra = rng.choice([0, 255])
        raw = raw + bytes([extra]) * count
        entry = {**entry, "planes": planes + 1}
    compressor = zstandard.ZstdCompressor(
        level=1, write_content_size=rng.random() < 0.9, write_checksum=rng.random() < 0.2
    )
    new = compressor.compress(bytes(raw))
    if what == 6:
        new += rng.choice(
            [b"\x00", new, struct.pack("<II", 0x184D2A50, 0)]
        )  # trailing data, a second frame
    elif what == 7 and len(new) > 6:
        new = new[: rng.randrange(4, len(new))]  # a cut frame
    sections[index] = (entry, new)


def structural_mutation(data: bytes, rng: random.Random) -> bytes | None:
    """One structural edit of a container, re-signed; ``None`` if ``data`` is not one."""
    parsed = _lenient_parse(data)
    if parsed is None:
        return None
    fields, header, area = parsed
    sections = _sections(header, area)
    what = rng.randrange(10)
    if what <= 3 or sections is None:
        _mutate_header(rng, header)
    elif what <= 5:
        _mutate_table(rng, sections)
    else:
        _mutate_payload(rng, sections)
    if rng.random() < 0.05:  # the preamble: major, minor (u16) or flags (u32)
        which = rng.randrange(3)
        fields[which] = rng.choice(
            [0, 1, 2, 0xFFFF] if which < 2 else [0, 1, 0x8000, 0x10000, 0xFFFFFFFF]
        )
    return _pack(fields, header, sections, area, rng)


def resign(data: bytes) -> bytes:
    """Make the preamble's and header's CRC-32 right again after a byte-level mutation, so
    that it is judged on what it changed, not on the checksum."""
    from tuckercodec.internal import CRC, PREAMBLE, SIGNATURE

    if len(data) < 32 or data[:8] != SIGNATURE:
        return data
    out = bytearray(data)
    CRC.pack_into(out, 28, zlib.crc32(out[:28]))
    header_length = PREAMBLE.unpack_from(out, 8)[3]
    if 32 + header_length + 4 <= len(out):
        CRC.pack_into(out, 32 + header_length, zlib.crc32(out[32 : 32 + header_length]))
    return bytes(out)


def mutate_container(data: bytes, max_size: int, seed: int) -> bytes:
    """libFuzzer's custom mutator: byte mutations as they are, byte mutations re-signed, or a
    structural edit. It never raises: a failed edit falls back to libFuzzer's own."""
    import atheris

    rng = random.Random(seed)
    choice = rng.random()
    try:
        if choice < 0.45:
            out = structural_mutation(data, rng)
            if out is not None and len(out) <= max_size:
                return out
        mutated = atheris.Mutate(data, max_size)
        return resign(mutated) if choice < 0.75 else mutated
    except Exception:  # the mutator must not stop the run
        return atheris.Mutate(data, max_size)


# ------------------------------------------------------------------------------------------
# seeds


def decoder_seeds() -> dict[str, bytes]:
    """Small valid files of shapes the conformance vectors lack, by name: a point
    cloud, one frame, three vertices, padded polygons with repeated corners, names and a frame
    rate, many planes, fixed ranks, one vertex (built by hand: the encoder needs a KG error,
    which one vertex has not). The encoder is not byte-stable, so these are written once and
    committed like the vectors."""
    import numpy as np

    import tuckercodec as tc
    from tuckercodec.internal import pack_container, sections, sheet_triangles, streams, wave_sheet

    frames = wave_sheet(8, 5)
    triangles = sheet_triangles(5)
    polygons = np.array(
        [[0, 1, 6, 5, -1], [1, 2, 7, -1, -1], [2, 3, 8, 8, 7], [10, 11, 16, 15, 10]]
    )
    files = {
        "seed-triangles.tkc": tc.encode(tc.MeshSequence(frames, triangles), target_kg=1.0),
        "seed-point-cloud.tkc": tc.encode(
            tc.MeshSequence(frames, np.zeros((0, 3), int)), target_kg=1.0
        ),
        "seed-one-frame.tkc": tc.encode(tc.MeshSequence(frames[:1], triangles), target_kg=1.0),
        "seed-three-vertices.tkc": tc.encode(
            tc.MeshSequence(frames[:, :3], np.array([[0, 1, 2]])), target_kg=1.0
        ),
        "seed-polygons.tkc": tc.encode(tc.MeshSequence(frames, polygons), target_kg=1.0),
        "seed-names-rate.tkc": tc.encode(
            tc.MeshSequence(
                frames, triangles, frame_names=[f"é{n}" for n in range(8)], frame_rate=30.0
            ),
            target_kg=1.0,
        ),
        "seed-many-planes.tkc": tc.encode(
            tc.MeshSequence(frames * 1000, triangles), target_kg=1e-4
        ),
        "seed-fixed-ranks.tkc": tc.encode(tc.MeshSequence(frames, triangles), ranks=(3, 2)),
    }
    one = np.ones(1, "<f4").tobytes()
    entry, compress = sections.entry, streams.compress

    def qmat(section_id: str, shape: list[int], steps: bytes, predict: bytes) -> dict[str, Any]:
        return entry(section_id, {"planes": 1, "shape": shape, "steps": steps, "predict": predict})

    files["seed-one-vertex.tkc"] = pack_container(
        {
            "vertices": 1,
            "frames": 2,
            "ranks": [1, 1],
            "u2": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        },
        [
            (entry("FACE", {"shape": [0, 3], "planes": 1}), compress(b"")),
            (qmat("U1", [1, 1], one, b"\x01"), compress(b"\x02")),
            (qmat("U3", [2, 1], one, b"\x01"), compress(b"\x02\x01")),
            (qmat("CORE", [3, 1], one, b"\x00"), compress(b"\x02\x04\x06")),
            (
                qmat("CENT", [2, 3], np.ones(3, "<f4").tobytes(), b"\x01\x00\x01"),
                compress(bytes([2, 1, 3, 3, 5, 0])),
            ),
            ({"id": "note", "critical": False, "codec": "text"}, b"an ancillary section"),
        ],
        flags=0x10000,
    )
    for data in files.values():
        tc.decode(data)  # every seed is valid
    return files
