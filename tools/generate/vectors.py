"""Write the conformance vectors of spec/FORMAT.md §12 into spec/vectors/.

    python -m tools.generate.vectors [--force]          # spec/vectors/ (never needed again: below)
    python -m tools.generate.vectors --out DIR          # somewhere else, to look at them

Valid vectors: small files encoded from deterministic synthetic sequences, each with a JSON of
the header fields a decoder must report, SHA-256 digests of the dequantized arrays, and the
reference reconstruction (an .npy of the decoded positions) with its tolerance.

Invalid vectors: one per rule of §11, named after it, and a second for a rule checked at two
places (``SECOND_VECTORS``, its name the rule's and a suffix), each made by breaking that rule
in a valid file (checksums recomputed, so that nothing else is wrong before it), with the rule
id and the error class it must raise. They are a function of the valid files alone: from the
committed v1-wave-triangles.tkc (format 1.0), v1.1-segments-shared.tkc (1.1) and
v1.2-traverse-triangles.tkc (1.2) they come out byte for byte as committed (a test checks it).

The encoder is not byte-identical across machines (the SVD's signs and last bits depend on the
BLAS), so the vectors are written once and committed; every test run decodes them. Never write
them into spec/vectors/ again unless the format itself changes.

Each vector is named for the format version it exercises (``v1-`` 1.0, ``v1.3-`` 1.3), and is
encoded with that version as the encoder's ``format_version``, so that today's encoder, which
would use the newest features, writes it at that version: :func:`write_valid` refuses a file
whose version is not its name's.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import struct
import sys
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from tools import common
from tuckercodec import (
    Attribute,
    Decoder,
    FaceSet,
    Field,
    MeshSequence,
    encode,
    encode_with_report,
    internal,
)
from tuckercodec.internal import (
    DEFAULT_LIMITS,
    HEAD_SIZE,
    adaptive,
    faces,
    parse_container,
    prediction,
    qmat,
    residual,
    sheet_triangles,
    streams,
    traversal,
    unseen,
    wave_sheet,
)

VECTORS = common.REPO / "spec" / "vectors"
#: What a vector folder holds: the files, their JSON and the valid ones' reference positions.
VECTOR_SUFFIXES = (".tkc", ".json", ".npy")
#: A conforming decoder's positions may differ from the reference by rounding only (§8).
RELATIVE_TOLERANCE = 1e-9


# ------------------------------------------------------------------------------------------
# sequences


def polygons(grid: int) -> np.ndarray:
    """Quads, every third one a triangle padded with -1."""
    index = np.arange(grid * grid).reshape(grid, grid)
    quads = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], -1).reshape(
        -1, 4
    )
    quads[::3, 3] = -1
    return quads


def named_polygons() -> MeshSequence:
    """Quads padded to triangles far from the origin, with frame names and a frame rate."""
    return MeshSequence(
        wave_sheet(16, 7) * 3.0 + 10.0,
        polygons(7),
        [f"walk_{n:03d}.obj" for n in range(16)],
        frame_rate=30.0,
    )


def scrambled(sequence: MeshSequence, seed: int) -> MeshSequence:
    """The same animation with its vertices renumbered, its faces shuffled and each face's
    corners rotated (orientation kept), as an arbitrary exporter writes: faces-traverse (§6.8)
    is then the smaller FACE codec, and the file is of format 1.2."""
    rng = np.random.default_rng(seed)
    k = sequence.vertex_count
    relabel = rng.permutation(k)
    vertices = np.empty_like(sequence.vertices)
    vertices[:, relabel] = sequence.vertices
    faces_out = np.append(relabel, -1)[sequence.faces][rng.permutation(len(sequence.faces))]
    for row in faces_out:
        n = int((row >= 0).sum())
        row[:n] = np.roll(row[:n], int(rng.integers(n)))
    return MeshSequence(vertices, faces_out, sequence.frame_names, frame_rate=sequence.frame_rate)


# ------------------------------------------------------------------------------------------
# taking a file apart and putting it back with one thing changed


class Parts:
    """A file as editable parts: preamble fields, header map, section payloads."""

    def __init__(self, data: bytes) -> None:
        container = parse_container(data)
        self.major, self.minor, self.flags = container.major, container.minor, container.flags
        self.header = dict(container.header)
        self.entries = [dict(entry) for entry in container.header["sections"]]
        self.payloads = [bytes(container.payload(data, s)) for s in container.sections]

    def index(self, section_id: str) -> int:
        return next(n for n, entry in enumerate(self.entries) if entry["id"] == section_id)

    def fill_table(self) -> None:
        """Offsets, lengths and CRCs of the entries, from the payloads as they are now."""
        offset = 0
        # strict=False: R18's file keeps a payload whose entry was dropped (it stays in the body)
        for entry, payload in zip(self.entries, self.payloads, strict=False):
            entry.update(offset=offset, length=len(payload), crc32=zlib.crc32(payload))
            offset += len(payload)

    def pack(
        self, *, fix_table: bool = True, header_bytes: bytes | None = None, total: int | None = None
    ) -> bytes:
        """Bytes of the file; offsets, lengths and CRCs recomputed unless ``fix_table`` is off."""
        if fix_table:
            self.fill_table()
        if header_bytes is None:
            header_bytes = msgpack.packb(
                {**self.header, "sections": self.entries}, use_bin_type=True
            )
        body = b"".join(self.payloads)
        return internal.pack_raw(
            self.major, self.minor, self.flags, header_bytes, body, total=total
        )


def _with_crc_fixed(data: bytearray) -> bytes:
    """Recompute the preamble CRC after editing preamble fields in place."""
    data[28:32] = struct.pack("<I", zlib.crc32(bytes(data[:28])))
    return bytes(data)


def _set_preamble(data: bytes, offset: int, fmt: str, value: int) -> bytes:
    edited = bytearray(data)
    struct.pack_into(fmt, edited, offset, value)
    return _with_crc_fixed(edited)


def _edit(data: bytes, change: Callable[[Parts], None], **pack_options: Any) -> bytes:
    parts = Parts(data)
    change(parts)
    return parts.pack(**pack_options)


def _entry(section_id: str, **fields: Any) -> Callable[[Parts], None]:
    def change(parts: Parts) -> None:
        parts.entries[parts.index(section_id)].update(fields)

    return change


def _header(**fields: Any) -> Callable[[Parts], None]:
    def change(parts: Parts) -> None:
        for key, value in fields.items():
            if value is _DELETE:
                del parts.header[key]
            else:
                parts.header[key] = value

    return change


_DELETE = object()


def _payload(section_id: str, payload: bytes, **fields: Any) -> Callable[[Parts], None]:
    def change(parts: Parts) -> None:
        n = parts.index(section_id)
        parts.payloads[n] = payload
        parts.entries[n].update(fields)

    return change


def _flip_last_payload_byte(section_id: str) -> Callable[[Parts], None]:
    """Damage a section after its CRC was computed: the table keeps the old CRC."""

    def change(parts: Parts) -> None:
        n = parts.index(section_id)
        parts.fill_table()
        damaged = bytearray(parts.payloads[n])
        damaged[-1] ^= 0x01
        parts.payloads[n] = bytes(damaged)

    return change


def invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): ``good`` with that one rule broken."""
    parts = Parts(good)
    header_length = struct.unpack_from("<I", good, 16)[0]
    faces_shape = parts.entries[parts.index("FACE")]["shape"]
    k_vertices = parts.header["vertices"]
    bad_faces = np.full(faces_shape, 0, dtype=np.int64)
    bad_faces[0, 0] = k_vertices  # one past the last vertex
    face_params, face_payload = faces.encode_faces(bad_faces)  # the encoder does not check indices
    padded = np.zeros(faces_shape, dtype=np.int64)
    padded[:, 1] = -1  # padding before the end of a row
    padded_params, padded_payload = faces.encode_faces(padded)
    core_entry = parts.entries[parts.index("CORE")]
    names = msgpack.packb(["only one name"])

    return {
        "R01-signature": (b"PK\x03\x04" + good[4:], "FormatError"),
        "R02-signature-transfer": (good[:4] + b"\r\r\n" + good[7:], "FormatError"),
        "R03-preamble-truncated": (good[:20], "TruncatedFileError"),
        "R04-preamble-crc": (good[:10] + bytes([good[10] ^ 0x04]) + good[11:], "ChecksumError"),
        "R05-major-version": (_set_preamble(good, 8, "<H", 2), "UnsupportedVersionError"),
        "R06-critical-flag": (_set_preamble(good, 12, "<I", 0x8000), "UnsupportedVersionError"),
        "R07-header-limit": (_set_preamble(good, 16, "<I", (16 << 20) + 1), "LimitError"),
        "R08-total-length": (
            _set_preamble(good, 20, "<Q", HEAD_SIZE + header_length),
            "FormatError",
        ),
        "R09-trailing-bytes": (good + b"\x00\x00\x00\x00", "FormatError"),
        "R10-file-truncated": (good[:-7], "TruncatedFileError"),
        "R11-header-crc": (good[:40] + bytes([good[40] ^ 0x20]) + good[41:], "ChecksumError"),
        "R12-header-not-map": (parts.pack(header_bytes=msgpack.packb([1, 2, 3])), "FormatError"),
        "R13-section-table-missing": (
            parts.pack(
                header_bytes=msgpack.packb(
                    {k: v for k, v in parts.header.items() if k != "sections"}
                )
            ),
            "FormatError",
        ),
        "R14-section-entry-field": (
            _edit(good, _entry("U3", crc32="0"), fix_table=False),
            "FormatError",
        ),
        "R15-section-duplicate-id": (_edit(good, _entry("U3", id="U1")), "FormatError"),
        "R16-section-not-contiguous": (
            _edit(
                good,
                lambda p: p.entries[1].update(offset=p.entries[1]["offset"] + 1),
                fix_table=False,
            ),
            "FormatError",
        ),
        "R17-section-past-end": (
            _edit(
                good,
                lambda p: p.entries[-1].update(length=p.entries[-1]["length"] + 1),
                fix_table=False,
            ),
            "FormatError",
        ),
        "R18-section-coverage": (_edit(good, _forget_last_entry), "FormatError"),
        "R19-section-crc": (
            _edit(good, _flip_last_payload_byte("U1"), fix_table=False),
            "ChecksumError",
        ),
        "R20-header-field": (_edit(good, _header(vertices=_DELETE)), "FormatError"),
        # 1.4 (§4): time codes that go back, frame 2 before frame 1
        "R20-header-field-time-codes": (
            _edit(
                good,
                _header(time_codes=_time_codes_back(parts.header["frames"])),
            ),
            "FormatError",
        ),
        "R21-header-limit": (_edit(good, _header(vertices=1 << 40)), "LimitError"),
        "R22-ranks": (
            _edit(good, _header(ranks=[parts.header["ranks"][0], 10_000])),
            "FormatError",
        ),
        "R23-u2": (_edit(good, _header(u2=[1.0] * 8)), "FormatError"),
        "R24-unknown-critical-section": (
            _edit(good, _append_section({"id": "XTRA", "critical": True, "codec": "raw"}, b"?")),
            "UnsupportedVersionError",
        ),
        "R25-unknown-codec": (_edit(good, _entry("U3", codec="qmat2")), "UnsupportedVersionError"),
        "R26-required-section-missing": (_edit(good, lambda p: _drop(p, "CENT")), "FormatError"),
        "R27-criticality": (_edit(good, _entry("U1", critical=False)), "FormatError"),
        "R28-shape": (
            _edit(good, _entry("U3", shape=[parts.header["frames"] + 1, parts.header["ranks"][1]])),
            "FormatError",
        ),
        "R29-zstd-content-size": (
            _edit(good, _payload("CORE", streams.compress(b"\x00" * 3))),
            "FormatError",
        ),
        "R30-planes": (_edit(good, _entry("U1", planes=5)), "FormatError"),
        "R31-steps": (
            _edit(good, _entry("CORE", steps=np.array([0.0], "<f4").tobytes())),
            "FormatError",
        ),
        "R32-predictor": (
            _edit(good, _entry("CORE", predict=b"\x01" * len(core_entry["predict"]))),
            "FormatError",
        ),
        "R33-face-index": (
            _edit(good, _payload("FACE", face_payload, **face_params)),
            "FormatError",
        ),
        "R34-face-padding": (
            _edit(good, _payload("FACE", padded_payload, **padded_params)),
            "FormatError",
        ),
        "R36-reconstruction-finite": (_edit(good, _header(u2=[1e308] * 9)), "FormatError"),
        "R35-names": (
            _edit(good, lambda p: _add_names(p, names)),
            "FormatError",
        ),
    }


def _time_codes_back(frames: int) -> bytes:
    """A ``time_codes`` bin (§4, 1.4) of ``frames`` codes whose third is below its second."""
    codes = np.arange(frames, dtype="<f8")
    codes[2] = 0.5
    return codes.tobytes()


def _forget_last_entry(parts: Parts) -> None:
    """Keep the last section's bytes in the file but drop its entry from the table (pack()
    lays out only the sections that have entries, then appends every payload)."""
    parts.entries.pop()


def _append_section(entry: dict[str, Any], payload: bytes) -> Callable[[Parts], None]:
    def change(parts: Parts) -> None:
        parts.entries.append(dict(entry))
        parts.payloads.append(payload)

    return change


def _drop(parts: Parts, section_id: str) -> None:
    n = parts.index(section_id)
    parts.entries.pop(n)
    parts.payloads.pop(n)


def _add_names(parts: Parts, raw: bytes) -> None:
    if any(entry["id"] == "NAME" for entry in parts.entries):
        _drop(parts, "NAME")
    parts.entries.append(
        {"id": "NAME", "critical": False, "codec": "msgpack-zstd", "size": len(raw)}
    )
    parts.payloads.append(streams.compress(raw))


# ------------------------------------------------------------------------------------------
# valid vectors


def digests(decoder: Decoder) -> dict[str, str]:
    """SHA-256 of the dequantized arrays as little-endian C-order float64 (faces: int64). A
    segmented file (§6.7) has each segment's arrays, named ``u1.s`` (the U1 it uses: its own,
    or the shared one's leading columns), ``u3.s``, ``core.s`` and ``centroids.s``."""
    arrays = {"faces": np.ascontiguousarray(decoder.faces, dtype="<i8")}
    for segment in decoder.segments:
        factors = decoder.segment_factors(segment.index)
        suffix = f".{segment.index}" if decoder.segmented else ""
        for name, array in (
            ("u1", factors.u1),
            ("u3", factors.u3),
            ("core", factors.core),
            ("centroids", factors.centroids),
        ):
            arrays[name + suffix] = np.ascontiguousarray(array, dtype="<f8")
    return {name: hashlib.sha256(array.tobytes()).hexdigest() for name, array in arrays.items()}


def corrections_of(decoder: Decoder) -> dict[str, Any]:
    """A file of format 1.3's corrections (§12): the RESD parameters a decoder reads, and the
    SHA-256 of its restored integers e (little-endian int64, F x K x 3; per segment
    ``residual.s``) and, in a file with codebooks (1.8), of each axis's entries (little-endian
    int64; ``codebooks.s`` per segment, null for an axis without one)."""
    first = decoder.segment_factors(0).corrections
    assert first is not None
    found: dict[str, Any] = {
        "domain": first.domain,
        "scale": first.scale,
        "predict": first.predict,
        "chunk_frames": first.span,  # L as decoded: a larger chunk_frames is one chunk
        "sha256": {},
    }
    for segment in decoder.segments:
        part = decoder.segment_factors(segment.index)
        layout = part.corrections
        assert layout is not None
        payload = decoder._payload(part.residual_id)
        values = np.concatenate(
            [
                residual.decode_chunk(payload, layout, n, decoder.info.vertices, part.residual_id)
                for n in range(len(layout.planes))
            ]
        )
        name = f"residual.{segment.index}" if decoder.segmented else "residual"
        found["sha256"][name] = hashlib.sha256(values.astype("<i8").tobytes()).hexdigest()
        if layout.codebooks:
            books = residual.decode_codebooks(payload, layout, part.residual_id)
            key = f"codebooks.{segment.index}" if decoder.segmented else "codebooks"
            found.setdefault("codebooks", {})[key] = [
                None if book is None else hashlib.sha256(book.astype("<i8").tobytes()).hexdigest()
                for book in books
            ]
    return found


def attachments_of(decoder: Decoder) -> dict[str, Any]:
    """Format 1.5: the faces' digest in the given order, each attribute's form and the SHA-256
    of its values (little-endian, C order, bit for bit) and indices (little-endian int64), and
    each face set's name, family and the digest of its face numbers (little-endian int64)."""

    def sha(array: np.ndarray, dtype: str) -> str:
        return hashlib.sha256(np.ascontiguousarray(array, dtype=dtype).tobytes()).hexdigest()

    return {
        "faces_given_order": sha(decoder.faces, "<i8"),
        "attributes": [
            {
                "name": a.name,
                "domain": a.domain,
                "role": a.role,
                "type": a.values.dtype.name,
                "shape": list(a.values.shape),
                "values": sha(a.values, a.values.dtype.newbyteorder("<").str),
                "indices": None if a.indices is None else sha(a.indices, "<i8"),
            }
            for a in decoder.attributes
        ],
        "face_sets": [
            {"name": s.name, "family": s.family, "faces": sha(s.faces, "<i8")}
            for s in decoder.face_sets
        ],
    }


def field_modes(decoder: Decoder) -> list[str]:
    """Each field's mode (``tucker``, ``grid`` or ``exact``), as its FLD.n says."""
    return [str(section.params.get("mode")) for section in decoder._attached.fields]


def fields_of(decoder: Decoder, name: str) -> list[dict[str, Any]]:
    """Format 1.5: each animated field's description (§6.13) and its values: in modes grid and
    exact the SHA-256 of every frame's values (little-endian, C order, bit for bit); in mode
    tucker, whose values a decoder may round otherwise (§8), the reference ``.npy`` (float64)
    beside the vector and the tolerance relative to its largest |value|."""
    out = []
    modes = field_modes(decoder)
    for number, field in enumerate(decoder.fields()):
        mode = modes[number]
        entry: dict[str, Any] = {
            "name": field.name,
            "role": field.role,
            "domain": field.domain,
            "components": field.components,
            "type": "f32" if field.values.dtype == np.float32 else "f64",
            "mode": mode,
            "shape": list(field.values.shape),
        }
        if mode == "tucker":
            entry["reference"] = f"{name}.field{number}.npy"
            entry["tolerance"] = {"relative_to_max_abs": RELATIVE_TOLERANCE}
        else:
            values = np.ascontiguousarray(field.values, field.values.dtype.newbyteorder("<"))
            entry["sha256"] = hashlib.sha256(values.tobytes()).hexdigest()
        out.append(entry)
    return out


def segment_index(decoder: Decoder) -> list[dict[str, Any]]:
    """The segment index a decoder must report (§6.7): empty for a file of format 1.0."""
    return [
        {"first_frame": s.start, "frames": s.frames, "ranks": list(s.ranks), "basis": s.basis}
        for s in decoder.info.segments
    ]


def valid_vectors() -> dict[str, tuple[bytes, str]]:
    """name -> (file bytes, what it exercises)."""
    wave_tri = MeshSequence(wave_sheet(24, 9), sheet_triangles(9))
    basic = encode(wave_tri, target_kg=0.5, format_version="1.0")
    named = named_polygons()
    extended = Parts(basic)
    extended.flags |= 0x00010000  # an ignorable flag bit
    extended.header["x-note"] = "an unknown header key is ignored"
    extended.entries.append({"id": "xmeta", "critical": False, "codec": "opaque"})
    extended.payloads.append(b"unknown ancillary data is skipped unread")
    long_wave = MeshSequence(wave_sheet(40, 9), sheet_triangles(9), frame_rate=25.0)
    return {
        **traverse_vectors(),
        **correction_vectors(),
        **scene_vectors(),
        **attachment_vectors(),
        **fields_vector(),
        **adaptive_vectors(),
        **codebook_vectors(),
        **uniform_ranks_vectors(),
        "v1-wave-triangles": (basic, "triangles, no names: the basic file"),
        "v1.1-segments-shared": (
            encode_with_report(
                long_wave, target_kg=0.5, segment_frames=12, format_version="1.1"
            ).data,
            "format 1.1: three segments of 12, 12 and 16 frames sharing one U1",
        ),
        "v1.1-segments-own": (
            encode_with_report(
                named, target_kg=0.5, segment_frames=8, basis="own", format_version="1.1"
            ).data,
            "format 1.1: two segments, each with its own U1 (mesh parents of polygons), names",
        ),
        "v1-polygons-names": (
            encode(named, target_kg=0.1, format_version="1.0"),
            "quads padded to triangles, frame names, frame rate, far from the origin",
        ),
        "v1-ignorable-extensions": (
            extended.pack(),
            "v1-wave-triangles plus an ignorable flag, header key and ancillary section",
        ),
    }


def adaptive_everywhere(data: bytes) -> bytes:
    """``data`` with every position factor (U1, U3, CORE, CENT and their ``.s`` forms) stored
    by §6.14's adaptive coder, whichever coder the encoder chose: so that a vector exercises
    both coding orders in every kind of section."""
    parts = Parts(data)
    decoder = Decoder(data)
    mesh = internal.mesh_prediction(decoder._coded_faces, decoder.info.vertices)
    for n, entry in enumerate(parts.entries):
        stem = str(entry["id"]).split(".")[0]
        if stem not in adaptive.ADAPTIVE_STEMS or entry.get("coder", 0) == 1:
            continue
        rows, cols = entry["shape"]
        stored = streams.unpack_integers(parts.payloads[n], rows * cols, entry["planes"], stem)
        order = qmat.coding_order(mesh if stem == "U1" else None, rows)
        parts.payloads[n] = adaptive.encode_columns(stored.reshape(cols, rows), order)
        entry["coder"] = adaptive.CODER_ADAPTIVE
    parts.flags |= adaptive.ADAPTIVE
    parts.minor = max(parts.minor, adaptive.ADAPTIVE_MINOR)
    return parts.pack()


def stored_integers(payload: bytes, entry: dict[str, Any], order: Any) -> np.ndarray:
    """The (rows, cols) integers a qmat section stores, from either coder."""
    rows, cols = entry["shape"]
    if entry.get("coder") == adaptive.CODER_ADAPTIVE:
        columns = adaptive.decode_columns(payload, cols, rows, order, str(entry["id"]))
    else:
        columns = streams.unpack_integers(payload, rows * cols, entry["planes"], "U1")
    return np.ascontiguousarray(columns.reshape(cols, rows).T)


def pushed_everywhere(data: bytes) -> bytes:
    """``data`` with U1's columns stored with predictor 2 under every push 0..9 in turn (§6.2,
    format 1.6), but the last, kept as the encoder stored it, adaptively coded: so that a
    vector exercises each push whichever ones the encoder would choose."""
    parts = Parts(data)
    decoder = Decoder(data)
    mesh = internal.mesh_prediction(decoder._coded_faces, decoder.info.vertices)
    n = parts.index("U1")
    entry = parts.entries[n]
    rows, cols = entry["shape"]
    q = decoder._decode_u1("U1").q
    order = qmat.coding_order(mesh, rows)
    residual = stored_integers(parts.payloads[n], entry, order)
    meaned = np.arange(cols - 1)
    predict = np.frombuffer(entry["predict"], dtype=np.uint8).copy()
    predict[meaned] = qmat.PREDICT_MEAN
    entry["predict"] = predict.tobytes()
    push = np.full(cols, prediction.PUSH, dtype=np.uint8)
    push[meaned] = np.arange(meaned.size) % len(prediction.PUSHES)
    pushed = prediction.mean_residuals(q[:, meaned], mesh.mean_steps, push[meaned])
    assert pushed is not None
    residual[:, meaned] = pushed
    parts.payloads[n] = adaptive.encode_columns(np.ascontiguousarray(residual.T), order)
    entry.update(coder=adaptive.CODER_ADAPTIVE, mean_push=push.tobytes())
    entry["planes"] = max(entry["planes"], streams.planes_needed(streams.zigzag(residual)))
    parts.flags |= adaptive.ADAPTIVE
    parts.minor = max(parts.minor, adaptive.ADAPTIVE_MINOR)
    return parts.pack()


def pinched_sheets(grid: int, frames: int) -> MeshSequence:
    """Two sheets of :func:`polygons` (quads and padded triangles) that share one vertex, the
    first's last corner and the second's first: the walk meets it again from a seed (FAR)."""
    first = wave_sheet(frames, grid)
    second = first[:, 1:] + (first[:, -1:] - first[:, :1])  # its first corner is the shared one
    k = grid * grid
    relabel = np.append(np.arange(k - 1, 2 * k - 1), -1)  # the second's vertices; -1 stays
    faces_out = np.concatenate([polygons(grid), relabel[polygons(grid)]])
    return MeshSequence(np.concatenate([first, second], axis=1), faces_out)


def face_streams(parts: Parts) -> tuple[list[list[int]], int, int, int]:
    """A faces-traverse FACE's four streams as the walk reads them (the NEW vertices as gaps,
    whichever the coder), its corner order, its coder and the file's vertex count."""
    n = parts.index("FACE")
    entry = parts.entries[n]
    count, width = entry["shape"]
    vertices = parts.header["vertices"]
    values, corner_order = traversal.read_streams(
        parts.payloads[n],
        entry,
        count,
        width,
        vertices,
        "FACE",
        adaptive_coding=True,
        uniform_ranks=True,
    )
    return values, corner_order, entry.get("coder", adaptive.CODER_ZSTD), vertices


def packed_face(
    values: list[list[int]], shape: list[int], corner_order: int, coder: int, vertices: int
) -> tuple[dict[str, Any], bytes]:
    """The FACE parameters and payload of ``values`` (as :func:`face_streams` gives them),
    with ``coder`` 1 the gaps turned into ranks among the unseen vertices first."""
    values = list(values)
    if coder == adaptive.CODER_ADAPTIVE:
        placed = unseen.vertices_from_gaps(np.array(values[2], dtype=np.int64))
        values[2] = unseen.ranks_of(placed, vertices).tolist()
    count, width = shape
    return traversal.pack_streams(values, count, width, corner_order, 19, coder)


def with_adaptive_faces(data: bytes) -> bytes:
    """``data`` (with a faces-traverse FACE) with its FACE's streams stored with ``coder`` 1
    (§6.8, format 1.6): the same walk and values, the NEW vertices as ranks, each stream one
    adaptive column; whichever coder the encoder chose."""
    parts = Parts(data)
    values, corner_order, _, vertices = face_streams(parts)
    n = parts.index("FACE")
    params, parts.payloads[n] = packed_face(
        values, parts.entries[n]["shape"], corner_order, adaptive.CODER_ADAPTIVE, vertices
    )
    parts.entries[n].update(params)
    parts.flags |= adaptive.ADAPTIVE
    parts.minor = max(parts.minor, adaptive.ADAPTIVE_MINOR)
    return parts.pack()


def codebook_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.8 (§6.9's codebooks): lossless sheets whose coordinates
    take few distinct values (a grid's x and y, the heights rounded to a coarse step)."""
    rough = wave_sheet(24, 9) + np.random.default_rng(31).normal(scale=2e-3, size=(24, 81, 3))
    coarse = rough.copy()
    coarse[..., 2] = np.round(coarse[..., 2] * 64.0) / 64.0  # few heights
    coarse[..., :2] = wave_sheet(24, 9)[..., :2]  # the grid's x and y, as given
    return {
        "v1.8-lossless-codebooks": (
            encode(MeshSequence(coarse, sheet_triangles(9)), lossless=True, format_version="1.8"),
            "format 1.8: lossless float64 values whose heights lie on a grid of 1/64, the "
            "corrections positions in each axis's codebook",
        ),
        "v1.8-lossless-codebooks-float32": (
            encode(
                MeshSequence(coarse.astype(np.float32).astype(np.float64), sheet_triangles(9)),
                lossless=True,
                format_version="1.8",
            ),
            "format 1.8: lossless float32 values with codebooks of binary32 ordered integers",
        ),
        "v1.8-segments-codebooks": (
            encode_with_report(
                MeshSequence(coarse, sheet_triangles(9)),
                lossless=True,
                segment_frames=8,
                format_version="1.8",
            ).data,
            "format 1.8 and 1.1: lossless values in three segments, each RESD.s with its codebooks",
        ),
    }


def uniform_ranks_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.9 (§6.8's ``ranks`` 1): scrambled meshes, whose vertex
    order the walk does not follow, so that the encoder stores their new vertices as places in
    a uniform stream (a ``ValueError`` if it no longer does)."""
    triangles = scrambled(MeshSequence(wave_sheet(24, 9), sheet_triangles(9)), seed=41)
    polygons = scrambled(pinched_sheets(7, 12), seed=43)
    vectors = {
        "v1.9-faces-uniform-ranks": (
            encode(triangles, target_kg=0.1, format_version="1.9"),
            "format 1.9: faces-traverse of scrambled triangles with coder 1 and ranks 1, the "
            "new vertices' places among the unseen in a uniform stream",
        ),
        "v1.9-faces-uniform-polygons": (
            encode(polygons, target_kg=0.1, format_version="1.9"),
            "format 1.9: ranks 1 for scrambled polygons in two sheets that share a vertex "
            "(degrees, seeds, FAR)",
        ),
    }
    for name, (data, _) in vectors.items():
        if Parts(data).entries[Parts(data).index("FACE")].get("ranks") != 1:
            raise ValueError(f"{name}: the encoder no longer chooses ranks 1 for it")
    return vectors


def uniform_ranks_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """vector name -> (file bytes, error class name): the 1.9 file ``good`` (FACE with
    ``ranks`` 1) with §6.8's uniform ranks broken, all R46: ``ranks`` 2; ``ranks`` 1 with
    ``coder`` 0 (checked before the streams, which stay as they are); a byte after the uniform
    stream's end."""
    parts = Parts(good)
    entry = parts.entries[parts.index("FACE")]
    streams = [list(stream) for stream in entry["streams"]]
    offsets = np.cumsum([0] + [length for _, _, length in streams])
    payload = parts.payloads[parts.index("FACE")]
    vertices = traversal.NEW_VERTICES
    end = int(offsets[vertices + 1])
    longer = payload[:end] + b"\x00" + payload[end:]
    streams[vertices][2] += 1
    return {
        "R46-adaptive-stream-ranks": (_edit(good, _entry("FACE", ranks=2)), "FormatError"),
        "R46-adaptive-stream-ranks-coder": (_edit(good, _entry("FACE", coder=0)), "FormatError"),
        "R46-adaptive-stream-uniform": (
            _edit(good, _payload("FACE", longer, streams=streams)),
            "FormatError",
        ),
    }


def adaptive_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.6 (§6.14): every position factor adaptively coded, in a
    whole file and in segments with their own U1."""
    triangles = scrambled(MeshSequence(wave_sheet(24, 9), sheet_triangles(9)), seed=21)
    named = named_polygons()
    return {
        "v1.6-adaptive": (
            adaptive_everywhere(encode(triangles, target_kg=0.1, format_version="1.6")),
            "format 1.6: U1 (the mesh's coding order), U3, CORE and CENT (ascending) through the "
            "adaptive range coder, faces-traverse of scrambled triangles",
        ),
        "v1.6-mean-push": (
            pushed_everywhere(encode(triangles, ranks=(12, 6), format_version="1.6")),
            "format 1.6: U1's predictor 2 with each push 0..9 (mean_push), adaptively coded",
        ),
        "v1.6-adaptive-segments": (
            adaptive_everywhere(
                encode_with_report(
                    named, target_kg=0.1, segment_frames=8, basis="own", format_version="1.6"
                ).data
            ),
            "format 1.6 and 1.1: two segments with their own U1.s, U3.s, CORE.s and CENT.s, all "
            "adaptively coded, polygons and names",
        ),
        "v1.6-faces-adaptive": (
            with_adaptive_faces(
                encode(
                    scrambled(pinched_sheets(7, 12), seed=31), target_kg=0.1, format_version="1.6"
                )
            ),
            "format 1.6: faces-traverse with coder 1 (adaptive streams, NEW vertices as ranks "
            "among the unseen, negative ones too) of scrambled polygons in two sheets that share "
            "a vertex (seeds, FAR)",
        ),
    }


def adaptive_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the 1.6 file ``good`` with §6.14 broken.
    R46: U1's adaptive stream with a byte after its end; and U1's coder 1 in a file whose
    preamble no longer sets flag bit 3."""
    parts = Parts(good)
    trailing = parts.payloads[parts.index("U1")] + b"\x00"
    without_flag = Parts(good)
    without_flag.flags &= ~adaptive.ADAPTIVE
    pushed = Parts(good)
    n = pushed.index("U1")
    cols = pushed.entries[n]["shape"][1]
    pushed.entries[n]["mean_push"] = bytes([10] * cols)  # 0..9 only
    return {
        "R32-predictor-push": (pushed.pack(), "FormatError"),
        "R46-adaptive-stream": (_edit(good, _payload("U1", trailing)), "FormatError"),
        "R46-adaptive-stream-coder": (without_flag.pack(), "FormatError"),
    }


def faces_adaptive_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """vector name -> (file bytes, error class name): the 1.6 file ``good``, whose FACE has
    ``coder`` 1, with §6.8 broken. R39: the last NEW vertex's rank one beyond the unseen
    vertices (the walk is not reached: the ranks are turned into vertices before it). R30: a
    stream's ``planes`` 1, not 0. R46: coder 1 in a file whose preamble no longer sets flag
    bit 3 (FACE is the first section read)."""
    parts = Parts(good)
    entry = parts.entries[parts.index("FACE")]
    values, corner_order, _, vertices = face_streams(parts)
    placed = unseen.vertices_from_gaps(np.array(values[2], dtype=np.int64))
    ranks = unseen.ranks_of(placed, vertices)
    # the last NEW tip has K - (its turn) unseen vertices to name: one more names none
    ranks[-1] += vertices - (len(placed) - 1)
    values[2] = ranks.tolist()
    count, width = entry["shape"]
    params, beyond = traversal.pack_streams(
        values, count, width, corner_order, 19, adaptive.CODER_ADAPTIVE
    )
    planes = [list(stream) for stream in entry["streams"]]
    planes[0][1] = 1
    without_flag = Parts(good)
    without_flag.flags &= ~adaptive.ADAPTIVE
    return {
        "R39-traversal-rank": (_edit(good, _payload("FACE", beyond, **params)), "FormatError"),
        "R30-planes-faces-coder": (_edit(good, _entry("FACE", streams=planes)), "FormatError"),
        "R46-adaptive-stream-faces-coder": (without_flag.pack(), "FormatError"),
    }


def attached_sheet(grid: int, frames: int) -> MeshSequence:
    """A scrambled wave sheet (so that the walk reorders its faces) with an attribute of every
    domain and type, and face sets: what the valid vectors of format 1.5 hold."""
    sheet = scrambled(MeshSequence(wave_sheet(frames, grid), sheet_triangles(grid)), seed=15)
    faces, vertex_count = sheet.faces, sheet.vertex_count
    rng = np.random.default_rng(15)
    corners = faces[faces >= 0]  # each corner's vertex, in corner order (§6.11)
    seams = np.where(np.arange(corners.size) % 7 == 0, corners + vertex_count, corners)
    table = np.unique(seams, return_inverse=True)[1]
    uv = rng.random((int(table.max()) + 1, 2)).astype(np.float32)
    uv[3] = np.float32(np.nan)  # any bit pattern is stored
    attached = [
        Attribute("st", "corner", uv, table, "uv"),
        Attribute(
            "displayColor", "face", rng.random((len(faces), 3)).astype(np.float32), None, "color"
        ),
        Attribute("rest", "vertex", sheet.vertices[0] * np.pi, None, "generic"),
        Attribute("id", "face", rng.integers(-(2**31), 2**31, (len(faces), 1), dtype=np.int32)),
        Attribute("N", "vertex", rng.random((5, 3)), rng.integers(0, 5, vertex_count), "normal"),
    ]
    sets = [
        FaceSet("left", np.arange(0, len(faces) // 2), "materialBind"),
        FaceSet("right", np.arange(len(faces) // 2, len(faces)), "materialBind"),
        FaceSet("odd", np.arange(1, len(faces), 2), "group"),
        FaceSet("none", np.zeros(0, dtype=np.int64), ""),
    ]
    return MeshSequence(sheet.vertices, faces, attributes=attached, face_sets=sets)


def attachment_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.5 (§6.10-§6.12): attributes and face sets, with the faces'
    given order, and in the walk's order in a segmented file."""
    sheet = attached_sheet(9, 24)
    return {
        "v1.5-attributes": (
            encode(sheet, target_kg=0.5, format_version="1.5"),
            "format 1.5: ORDER, an attribute of every domain and type (indexed UVs with a NaN, "
            "face colours, float64 per vertex, int32 per face, indexed normals), face sets",
        ),
        "v1.5-attributes-walk-segments": (
            encode_with_report(
                sheet, target_kg=0.5, segment_frames=12, face_order="walk", format_version="1.5"
            ).data,
            "format 1.5 and 1.1: the same attributes following the walk's face order, no "
            "ORDER, two segments",
        ),
    }


def fields_vector() -> dict[str, tuple[bytes, str]]:
    """The valid vector of format 1.5's animated fields (§6.13): one field in each mode."""
    sheet = MeshSequence(wave_sheet(24, 9), sheet_triangles(9))
    velocity = np.gradient(sheet.vertices, axis=0) * 24.0
    faces = sheet.faces
    face_velocity = velocity[:, faces].mean(axis=2).astype(np.float32)
    fields = [
        Field("velocity", velocity, "vertex", "velocity"),
        Field("speed", np.linalg.norm(velocity, axis=2).astype(np.float32)),
        Field("face velocity", face_velocity, "face", "velocity"),
        Field("height", sheet.vertices[..., 2:] * np.pi, "vertex"),
    ]
    targets = {"velocity": "rel:1", "speed": "max:0.001", "face velocity": "lossless"}
    data = encode(
        MeshSequence(sheet.vertices, faces, fields=fields),
        target_kg=0.5,
        field_targets={**targets, "height": "lossless"},
        format_version="1.5",
    )
    modes = field_modes(Decoder(data))
    assert modes == ["tucker", "grid", "exact", "exact"], modes
    return {
        "v1.5-fields": (
            data,
            "format 1.5: animated fields, one in each mode: a float64 velocity per vertex "
            "(tucker), a float32 speed (grid), a float32 velocity per face and a float64 value "
            "per vertex (exact)",
        )
    }


def attachment_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the 1.5 file ``good`` with a rule of §6.10 to
    §6.13 broken. R42: ORDER's first step repeated (two faces get one number). R43: ATTR.0's
    value stream declared one value short. R44: a set names the face M. R45: a field section
    FLD.1 without FLD.0."""
    parts = Parts(good)
    order = parts.entries[parts.index("ORDER")]
    faces = order["faces"]
    steps = np.zeros(faces, dtype=np.int64)
    steps[1] = -1  # faces 0 and 1 both numbered 0
    broken_order, planes = streams.pack_integers(steps, 19)
    attribute = parts.entries[parts.index("ATTR.0")]
    short = [list(entry) for entry in attribute["streams"]]
    short[0][0] -= 1
    past, past_planes = streams.pack_integers(np.array([faces], dtype=np.int64), 19)
    field = {"id": "FLD.1", "critical": False, "codec": "field"}
    return {
        "R42-face-order": (
            _edit(good, _payload("ORDER", broken_order, planes=planes)),
            "FormatError",
        ),
        "R43-attribute": (_edit(good, _entry("ATTR.0", streams=short)), "FormatError"),
        "R44-face-sets": (
            _edit(good, _payload("FSET", past, sets=[["past", "", 1]], planes=past_planes)),
            "FormatError",
        ),
        "R45-field": (_edit(good, _append_section(field, b"")), "FormatError"),
    }


def scene_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.4 (§4): time codes, unit and up axis in the header."""
    # a film cache's frames from 1001, one sample dropped (uneven), in metres and Z up
    codes = np.concatenate([np.arange(1001.0, 1011.0), np.arange(1012.0, 1026.0)])
    film = MeshSequence(
        wave_sheet(24, 9),
        sheet_triangles(9),
        frame_rate=24.0,
        time_codes=codes,
        meters_per_unit=1.0,
        up_axis="Z",
    )
    seconds = MeshSequence(  # times at 0.5 s, 0.75 s...: time codes in frames of 8 fps
        wave_sheet(40, 9), sheet_triangles(9), frame_rate=8.0, time_codes=np.arange(4.0, 44.0)
    )
    return {
        "v1.4-scene-times": (
            encode(film, target_kg=0.5, format_version="1.4"),
            "format 1.4: time codes from 1001 with one frame missing, metres, Z up",
        ),
        "v1.4-scene-segments": (
            encode_with_report(
                seconds, target_kg=0.5, segment_frames=16, format_version="1.4"
            ).data,
            "format 1.4 and 1.1: time codes offset by 4 frames in three segments, no unit or axis",
        ),
    }


def traverse_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.2 (§6.8): faces-traverse, alone and with segments."""
    triangles = scrambled(MeshSequence(wave_sheet(24, 9), sheet_triangles(9)), seed=12)
    polygons_in_segments = scrambled(  # larger than `named`, for the walk to beat faces-delta
        MeshSequence(
            wave_sheet(16, 12) * 3.0 + 10.0,
            polygons(12),
            [f"walk_{n:03d}.obj" for n in range(16)],
            frame_rate=30.0,
        ),
        seed=13,
    )
    return {
        "v1.2-traverse-triangles": (
            encode(triangles, target_kg=0.5, format_version="1.2"),
            "format 1.2: faces-traverse, triangles shuffled, vertices renumbered, corners rotated",
        ),
        "v1.2-traverse-polygons-segments": (
            encode_with_report(
                polygons_in_segments, target_kg=0.5, segment_frames=8, format_version="1.2"
            ).data,
            "format 1.2 and 1.1 together: faces-traverse of scrambled polygons (degrees), two "
            "segments sharing U1, names",
        ),
    }


def correction_vectors() -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.3 (§6.9, §8.1): corrections in each domain, and in
    segments."""
    # noise no low rank captures, so that a Tucker part alone cannot meet the bound
    rough = wave_sheet(24, 9) + np.random.default_rng(23).normal(scale=2e-3, size=(24, 81, 3))
    wave = MeshSequence(rough, sheet_triangles(9))
    single = MeshSequence(wave_sheet(20, 8).astype(np.float32), sheet_triangles(8))
    named = named_polygons()
    return {
        "v1.3-bound-grid": (
            encode(wave, max_error="0.05%", format_version="1.3"),
            "format 1.3: every vertex of a noisy sheet within 0.05 % of the diagonal, on a grid",
        ),
        "v1.3-lossless-float32": (
            encode(single, lossless=True, format_version="1.3"),
            "format 1.3: lossless float32 values, corrections of binary32 ordered integers",
        ),
        "v1.3-lossless-float64": (
            encode(named, lossless=True, format_version="1.3"),
            "format 1.3: lossless float64 values far from the origin, polygons and names",
        ),
        "v1.3-lossless-digits": (
            encode(as_text(rough, "{:.6g}"), lossless=True, format_version="1.3"),
            "format 1.3: lossless values read from %.6g text, decimals of 6 significant digits",
        ),
        "v1.3-lossless-digits-float32": (
            encode(as_text(rough, "{:.6g}", np.float32), lossless=True, format_version="1.3"),
            "format 1.3: lossless float32 values read from %.6g text",
        ),
        "v1.3-segments-lossless": (
            encode_with_report(
                MeshSequence(rough.astype(np.float32).astype(np.float64), sheet_triangles(9)),
                lossless=True,
                segment_frames=8,
                format_version="1.3",
            ).data,
            "format 1.3 and 1.1 together: lossless float32 values in three segments sharing U1, "
            "each with its RESD.s",
        ),
        "v1.3-lossless-places": (
            encode(as_text(rough + 20.0, "{:.5f}"), lossless=True, format_version="1.3"),
            "format 1.3: lossless values read from %.5f text, decimals of 5 places",
        ),
    }


def derived_valid_vectors(corrected: bytes) -> dict[str, tuple[bytes, str]]:
    """Valid vectors made by editing the committed 1.3 file ``corrected`` (lossless float32,
    one chunk), as the invalid ones are: what an encoder may write that ours does not."""
    return {
        "v1.3-chunk-frames-u64": (
            _edit(corrected, _entry("RESD", chunk_frames=2**64 - 1)),
            "format 1.3: chunk_frames 2**64 - 1, the largest a msgpack int holds, which §6.9 "
            "allows: more than the frames, so the section is one chunk",
        ),
    }


def adaptive_correction_vectors(
    float32: bytes, float64: bytes, segments: bytes
) -> dict[str, tuple[bytes, str]]:
    """The valid vectors of format 1.7 (§6.9's ``coder`` 1), made from the 1.3 files as the
    derived ones are: their corrections, the same integers, stored as adaptive streams."""
    return {
        "v1.7-lossless-adaptive": (
            with_adaptive_corrections(float32, predict=1),
            "format 1.7: lossless float32 values, the RESD chunk one adaptive stream of the "
            "frames' differences (predict 1), at most 4 planes",
        ),
        "v1.7-lossless-float64-adaptive": (
            with_adaptive_corrections(float64, predict=0),
            "format 1.7: lossless float64 values, the RESD chunk one adaptive stream of "
            "corrections past 32 bits (more than 4 planes)",
        ),
        "v1.7-segments-adaptive": (
            with_adaptive_corrections(segments, predict=1),
            "format 1.7 and 1.1: lossless values in three segments, each RESD.s an adaptive stream",
        ),
    }


def with_adaptive_corrections(data: bytes, predict: int) -> bytes:
    """``data`` (a file with corrections) with every RESD section's integers stored as adaptive
    streams (§6.9 ``coder`` 1, format 1.7) with ``predict``, whichever coding the encoder chose;
    flag bit 4 set."""
    parts = Parts(data)
    for n, entry in enumerate(parts.entries):
        if entry.get("codec") != residual.RESIDUAL:
            continue
        integers = _corrections(parts, n)
        layout_domain = residual.Domain(entry["domain"], entry.get("step"), _scale(entry))
        params, payload = residual.encode_section(
            integers,
            layout_domain,
            19,
            exponent=entry["exponent"],
            predict=predict,
            chunk_frames=entry["chunk_frames"],
            adaptive_coding=True,
            adaptive_gain=-1.0,  # whatever it costs: the vector is for the coding
        )
        parts.entries[n] = {**{k: entry[k] for k in ("id", "critical", "codec")}, **params}
        parts.payloads[n] = payload
    parts.flags |= residual.ADAPTIVE_CORRECTIONS
    parts.minor = max(parts.minor, residual.ADAPTIVE_CORRECTIONS_MINOR)
    return parts.pack()


def codebook_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the 1.8 file ``good`` (lossless, codebooks)
    with a rule of its codebooks broken. R40: two entries for three axes. R29: the first
    codebook's count one less than its frame holds. R47: its second entry repeating the first
    (a step of 0), and its last entry beyond the domain's ordered integers. R41: the first
    stored integer past the end of its axis's codebook (the section repacked as zstd chunks)."""
    parts = Parts(good)
    n = parts.index("RESD")
    entry, payload = parts.entries[n], parts.payloads[n]
    books = [list(book) for book in entry["codebooks"]]
    axis = next(a for a, book in enumerate(books) if book[0] > 1)
    start = sum(book[2] for book in books[:axis])
    count, planes, length = books[axis]
    head, tail = payload[:start], payload[start + length :]
    steps = streams.unpack_integers(payload[start : start + length], count, planes, "codebook")
    domain = residual.Domain(entry["domain"], entry.get("step"), _scale(entry))

    def with_steps(changed: np.ndarray) -> Callable[[Parts], None]:
        unsigned = streams.zigzag(changed)
        wide = streams.planes_needed(unsigned)
        frame = streams.compress(streams.to_planes(unsigned, wide), 19)
        table = [list(book) for book in books]
        table[axis] = [count, wide, len(frame)]
        return _payload("RESD", head + frame + tail, codebooks=table)

    repeated = steps.copy()
    repeated[1] = 0
    beyond = steps.copy()
    beyond[-1] += residual.domain_range(domain)[1]  # the last entry past the largest
    integers = _corrections(parts, n)
    integers[0, 0, axis] = count  # j + e beyond the last position
    shared = (books, payload[: sum(book[2] for book in books)])
    packed = residual._packed_section(
        integers, domain, 19, entry["exponent"], entry["chunk_frames"], 0, books=shared
    )
    assert packed is not None  # zstd chunks take every int64
    params, broken = packed
    return {
        "R40-residual-codebooks": (_edit(good, _entry("RESD", codebooks=books[:2])), "FormatError"),
        "R29-zstd-content-size-codebook": (
            _edit(
                good,
                _entry(
                    "RESD",
                    codebooks=[*books[:axis], [count - 1, planes, length], *books[axis + 1 :]],
                ),
            ),
            "FormatError",
        ),
        "R47-codebook": (_edit(good, with_steps(repeated)), "FormatError"),
        "R47-codebook-range": (_edit(good, with_steps(beyond)), "FormatError"),
        "R41-residual-value-codebook": (
            _edit(good, _payload("RESD", broken, **{**params, "coder": 0})),
            "FormatError",
        ),
    }


def _scale(entry: dict[str, Any]) -> int | None:
    """A RESD entry's places or digits, if its domain has them."""
    return entry.get("places", entry.get("digits"))


def _corrections(parts: Parts, n: int) -> np.ndarray:
    """The restored integers e (F', K, 3) of the RESD section at ``n``."""
    entry, payload = parts.entries[n], parts.payloads[n]
    vertices = parts.header["vertices"]
    frames = _section_frames(parts, str(entry["id"]))
    layout = residual.read_layout(
        entry,
        len(payload),
        frames,
        vertices,
        DEFAULT_LIMITS,
        str(entry["id"]),
        adaptive_corrections=bool(parts.flags & residual.ADAPTIVE_CORRECTIONS),
        codebooks=bool(parts.flags & residual.CODEBOOKS),
    )
    return np.concatenate(
        [
            residual.decode_chunk(payload, layout, c, vertices, str(entry["id"]))
            for c in range(len(layout.planes))
        ]
    )


def _section_frames(parts: Parts, section_id: str) -> int:
    """F': the frames a RESD section covers (the file's, or its segment's)."""
    if "." not in section_id:
        return int(parts.header["frames"])
    number = int(section_id.split(".")[1])
    segment = parts.header["segments"][number]
    return int(segment["frames"]) if "frames" in segment else int(segment[1]) - int(segment[0])


def adaptive_correction_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the 1.7 file ``good`` (one adaptive RESD
    chunk) with §6.9's ``coder`` 1 broken. R46: a byte after the chunk's stream; ``coder`` 2;
    ``planes`` 1 for integers that need more. R29: ``coder`` 1 in a file without flag bit 4,
    where it is an unknown parameter, so the chunk is read as a zstd frame, which it is not."""
    parts = Parts(good)
    n = parts.index("RESD")
    entry, payload = parts.entries[n], parts.payloads[n]
    (planes, length), *rest = entry["chunks"]
    trailing = _edit(
        good, _payload("RESD", payload + b"\x00", chunks=[[planes, length + 1], *rest])
    )
    without_flag = Parts(good)
    without_flag.flags &= ~residual.ADAPTIVE_CORRECTIONS
    return {
        "R46-adaptive-stream-resd": (trailing, "FormatError"),
        "R46-adaptive-stream-resd-coder": (_edit(good, _entry("RESD", coder=2)), "FormatError"),
        "R46-adaptive-stream-resd-planes": (
            _edit(good, _entry("RESD", chunks=[[1, length], *rest])),
            "FormatError",
        ),
        "R29-zstd-content-size-resd-coder": (without_flag.pack(), "FormatError"),
    }


def as_text(positions: np.ndarray, style: str, dtype: type = np.float64) -> MeshSequence:
    """The sheet as an OBJ of ``style`` would give it back: each value parsed from its text
    (as float32 values, with ``dtype``, each parsed straight to float32)."""
    texts = [style.format(v) for v in positions.reshape(-1)]
    values = np.array(texts, dtype=dtype).astype(np.float64)
    return MeshSequence(values.reshape(positions.shape), sheet_triangles(9))


def correction_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the 1.3 file ``good`` (lossless float32) with
    a rule of §6.9 broken. R40: a domain the format does not have. R41: the first integer of the
    first chunk made 2**40, beyond binary32's range of corrections (its frame repacked, so that
    only the value is wrong)."""
    parts = Parts(good)
    section = parts.index("RESD")
    entry = parts.entries[section]
    values = _corrections(parts, section)
    values[0, 0, 0] = 1 << 40
    domain = residual.Domain(entry["domain"], entry.get("step"), _scale(entry))
    params, broken = residual.encode_section(
        values, domain, 19, chunk_frames=entry["chunk_frames"], predict=0
    )
    return {
        "R40-residual": (_edit(good, _entry("RESD", domain="float16")), "FormatError"),
        "R41-residual-value": (_edit(good, _payload("RESD", broken, **params)), "FormatError"),
    }


def traverse_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """vector name -> (file bytes, error class name): the 1.2 file ``good`` with a rule of §6.8
    broken. R39-traversal: the walk's first op (the first seed's first corner) made PREV, which
    names no vertex before any corner exists. Its second vector declares one new vertex more than
    the header's K in the streams' table (§6.8's third bound, checked before the streams are
    decompressed: the stream itself is unchanged). R21's second declares 2**28 triangles, within
    max_faces and max_section_bytes, and 6 * 2**28 ops of 4 planes, within §6.8's bounds: the
    streams would decompress to more than max_section_bytes, which a file of a few hundred bytes
    can ask, and is refused before anything is allocated by it."""
    parts = Parts(good)
    entry = parts.entries[parts.index("FACE")]
    width = entry["shape"][1]
    values, corner_order, coder, vertices = face_streams(parts)
    values[0][0] = traversal.TIP_PREV
    params, broken = packed_face(values, entry["shape"], corner_order, coder, vertices)
    table = [list(stream) for stream in entry["streams"]]
    too_many = [table[0], table[1], [vertices + 1, *table[2][1:]], table[3]]
    faces = 1 << 28
    # 4 planes, or with coder 1 planes 0 and 32-bit integers: the same bytes (§6.8)
    ops = [6 * faces, 4 if coder == adaptive.CODER_ZSTD else 0, table[0][2]]
    return {
        "R39-traversal": (_edit(good, _payload("FACE", broken, **params)), "FormatError"),
        "R39-traversal-vertex-count": (
            _edit(good, _entry("FACE", streams=too_many)),
            "FormatError",
        ),
        "R21-header-limit-face-streams": (
            _edit(good, _entry("FACE", shape=[faces, width], streams=[ops, *table[1:]])),
            "LimitError",
        ),
    }


#: Vectors that break a rule which has a vector of its name already, and the rule.
SECOND_VECTORS = {
    "R39-traversal-vertex-count": "R39-traversal",
    "R21-header-limit-face-streams": "R21-header-limit",
    "R20-header-field-time-codes": "R20-header-field",
    "R46-adaptive-stream-coder": "R46-adaptive-stream",
    "R46-adaptive-stream-resd": "R46-adaptive-stream",
    "R46-adaptive-stream-resd-coder": "R46-adaptive-stream",
    "R46-adaptive-stream-resd-planes": "R46-adaptive-stream",
    "R29-zstd-content-size-resd-coder": "R29-zstd-content-size",
    "R39-traversal-rank": "R39-traversal",
    "R30-planes-faces-coder": "R30-planes",
    "R46-adaptive-stream-faces-coder": "R46-adaptive-stream",
    "R32-predictor-push": "R32-predictor",
    "R40-residual-codebooks": "R40-residual",
    "R29-zstd-content-size-codebook": "R29-zstd-content-size",
    "R47-codebook-range": "R47-codebook",
    "R41-residual-value-codebook": "R41-residual-value",
    "R46-adaptive-stream-ranks": "R46-adaptive-stream",
    "R46-adaptive-stream-ranks-coder": "R46-adaptive-stream",
    "R46-adaptive-stream-uniform": "R46-adaptive-stream",
}


def named_version(name: str) -> str:
    """The format version a vector's name promises: ``v1-...`` 1.0, ``v1.3-...`` 1.3."""
    match = re.match(r"v(\d+)(?:\.(\d+))?-", name)
    if match is None:
        raise ValueError(f"a valid vector's name starts with its format version: {name!r}")
    return f"{match.group(1)}.{match.group(2) or 0}"


def write_valid(folder: Path, name: str, data: bytes, purpose: str) -> None:
    """One valid vector: the file, its reference positions and the JSON of what it holds;
    ``ValueError`` for a file of another format version than its name says."""
    decoder = Decoder(data)
    if decoder.info.format_version != named_version(name):
        raise ValueError(
            f"{name} is a file of format {decoder.info.format_version}, not the "
            f"{named_version(name)} its name says"
        )
    positions = decoder.positions()
    (folder / f"{name}.tkc").write_bytes(data)
    np.save(folder / f"{name}.positions.npy", positions)
    header = decoder.info
    exact = decoder.corrections is not None  # §8.1: every decoder returns the same bits
    expected: dict[str, Any] = {
        "file": f"{name}.tkc",
        "valid": True,
        "purpose": purpose,
        "header": {
            "format_version": header.format_version,
            "vertices": header.vertices,
            "frames": header.frames,
            "ranks": list(header.ranks),
            "faces": header.faces,
            "face_width": header.face_width,
            "total_bytes": header.total_bytes,
            "frame_rate": header.frame_rate,
            "kg": header.kg,
        },
        "frame_names": decoder.frame_names,
        "segments": segment_index(decoder),
        "sha256": digests(decoder),
        "reference": f"{name}.positions.npy",
        "tolerance": {"relative_to_max_abs": 0.0 if exact else RELATIVE_TOLERANCE},
    }
    if exact:
        expected["residual"] = corrections_of(decoder)
    if decoder.attributes or decoder.face_sets:  # 1.5, only where a file has them
        expected.update(attachments_of(decoder))
    if decoder.field_names:  # 1.5's fields, a tucker field's values beside the vector
        expected["fields"] = fields_of(decoder, name)
        for number, field in enumerate(decoder.fields()):
            if expected["fields"][number]["mode"] == "tucker":
                np.save(folder / f"{name}.field{number}.npy", field.values.astype("<f8"))
    if header.time_codes is not None:  # 1.4 (§4): only where a file has them, so that the
        expected["header"]["time_codes"] = list(header.time_codes)  # older JSON stays as it is
    if header.meters_per_unit is not None:
        expected["header"]["meters_per_unit"] = header.meters_per_unit
    if header.up_axis is not None:
        expected["header"]["up_axis"] = header.up_axis
    (folder / f"{name}.json").write_text(json.dumps(expected, indent=2) + "\n")


def segmented_invalid_vectors(good: bytes) -> dict[str, tuple[bytes, str]]:
    """rule id -> (file bytes, error class name): the segmented ``good`` with one rule of §6.7
    broken."""
    parts = Parts(good)
    segments = parts.header["segments"]
    short = [dict(entry) for entry in segments[:-1]]  # the index lost its last entry
    too_deep = [dict(entry) for entry in segments]
    too_deep[0]["ranks"] = [too_deep[0]["ranks"][0], too_deep[0]["frames"] + 1]
    return {
        "R37-segment-index": (_edit(good, _header(segments=short)), "FormatError"),
        "R38-segment-ranks": (_edit(good, _header(segments=too_deep)), "FormatError"),
    }


def write_invalid(
    folder: Path,
    good: bytes,
    segmented: bytes,
    traversed: bytes,
    corrected: bytes,
    attached: bytes,
    adaptively_coded: bytes,
    faces_coded: bytes,
    corrected_adaptively: bytes,
    codebooks: bytes,
    uniform_ranks: bytes,
) -> int:
    """The invalid vectors made from the valid files ``good`` (format 1.0), ``segmented``
    (1.1), ``traversed`` (1.2), ``corrected`` (1.3), ``attached`` (1.5), ``adaptively_coded``
    and ``faces_coded`` (1.6), ``corrected_adaptively`` (1.7), ``codebooks`` (1.8) and
    ``uniform_ranks`` (1.9), with their JSON; how many."""
    vectors = {
        **invalid_vectors(good),
        **segmented_invalid_vectors(segmented),
        **traverse_invalid_vectors(traversed),
        **correction_invalid_vectors(corrected),
        **attachment_invalid_vectors(attached),
        **adaptive_invalid_vectors(adaptively_coded),
        **faces_adaptive_invalid_vectors(faces_coded),
        **adaptive_correction_invalid_vectors(corrected_adaptively),
        **codebook_invalid_vectors(codebooks),
        **uniform_ranks_invalid_vectors(uniform_ranks),
    }
    for name, (data, error) in vectors.items():
        write_invalid_vector(folder, name, data, error)
    return len(vectors)


def write_invalid_vector(folder: Path, name: str, data: bytes, error: str) -> None:
    """One invalid vector and its JSON."""
    (folder / f"{name}.tkc").write_bytes(data)
    rule = SECOND_VECTORS.get(name, name)
    expected = {"file": f"{name}.tkc", "valid": False, "rule": rule, "error": error}
    (folder / f"{name}.json").write_text(json.dumps(expected, indent=2) + "\n")


#: The valid file each group of invalid vectors is made from.
INVALID_SOURCES = {
    "adaptive": "v1.6-adaptive",
    "faces-adaptive": "v1.6-faces-adaptive",
    "attachments": "v1.5-attributes",
    "invalid": "v1-wave-triangles",
    "segmented": "v1.1-segments-shared",
    "traverse": "v1.2-traverse-triangles",
    "corrections": "v1.3-lossless-float32",
    "corrections-float64": "v1.3-lossless-float64",
    "corrections-segments": "v1.3-segments-lossless",
}
#: The valid file of 1.7 the invalid vectors of §6.9's coder 1 are made from (itself derived).
ADAPTIVE_CORRECTIONS_SOURCE = "v1.7-lossless-adaptive"
#: The valid file of 1.8 the invalid vectors of §6.9's codebooks are made from.
CODEBOOKS_SOURCE = "v1.8-lossless-codebooks"
#: The valid file of 1.9 the invalid vectors of §6.8's uniform ranks are made from.
UNIFORM_RANKS_SOURCE = "v1.9-faces-uniform-ranks"


def write_only(out: Path, names: list[str]) -> int:
    """Write the named vectors alone; the valid files invalid ones are made from are read from
    ``out`` (written first if they are among ``names``)."""
    valid = valid_vectors()
    unknown = []
    for name in names:
        if name in valid:
            write_valid(out, name, *valid[name])
    sources = {key: (out / f"{name}.tkc").read_bytes() for key, name in INVALID_SOURCES.items()}
    derived = {
        **derived_valid_vectors(sources["corrections"]),
        **adaptive_correction_vectors(
            sources["corrections"], sources["corrections-float64"], sources["corrections-segments"]
        ),
    }
    for name in names:
        if name in derived:
            write_valid(out, name, *derived[name])
    invalid = {
        **invalid_vectors(sources["invalid"]),
        **segmented_invalid_vectors(sources["segmented"]),
        **traverse_invalid_vectors(sources["traverse"]),
        **correction_invalid_vectors(sources["corrections"]),
        **attachment_invalid_vectors(sources["attachments"]),
        **adaptive_invalid_vectors(sources["adaptive"]),
        **faces_adaptive_invalid_vectors(sources["faces-adaptive"]),
        **adaptive_correction_invalid_vectors(
            (out / f"{ADAPTIVE_CORRECTIONS_SOURCE}.tkc").read_bytes()
        ),
        **codebook_invalid_vectors((out / f"{CODEBOOKS_SOURCE}.tkc").read_bytes()),
        **uniform_ranks_invalid_vectors((out / f"{UNIFORM_RANKS_SOURCE}.tkc").read_bytes()),
    }
    for name in names:
        if name in invalid:
            write_invalid_vector(out, name, *invalid[name])
        elif name not in valid and name not in derived:
            unknown.append(name)
    if unknown:
        print(f"no vector is named {', '.join(unknown)}", file=sys.stderr)
        return 1
    print(f"wrote {len(names)} vectors to {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.generate.vectors", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--out", type=Path, default=VECTORS, help="where to write them (default: spec/vectors/)"
    )
    parser.add_argument("--force", action="store_true", help="replace existing vectors")
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="write just these vectors, the others left as committed (an invalid vector is made "
        "from the committed valid file it breaks): vectors are written once, and today's encoder "
        "writes other bytes than the one that made the older ones",
    )
    args = parser.parse_args(argv)
    out: Path = args.out
    if args.only:
        return write_only(out, args.only)
    existing = [p for p in out.iterdir() if p.suffix in VECTOR_SUFFIXES] if out.is_dir() else []
    if existing and not args.force:
        print(f"{out} holds vectors: pass --force to write the vectors again", file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    for old in existing:  # stale vectors go; anything else in the folder stays
        old.unlink()
    valid = valid_vectors()
    for name, (data, purpose) in valid.items():
        write_valid(out, name, data, purpose)
    derived = {
        **derived_valid_vectors(valid["v1.3-lossless-float32"][0]),
        **adaptive_correction_vectors(
            valid["v1.3-lossless-float32"][0],
            valid["v1.3-lossless-float64"][0],
            valid["v1.3-segments-lossless"][0],
        ),
    }
    for name, (data, purpose) in derived.items():
        write_valid(out, name, data, purpose)
    invalid = write_invalid(
        out,
        valid["v1-wave-triangles"][0],
        valid["v1.1-segments-shared"][0],
        valid["v1.2-traverse-triangles"][0],
        valid["v1.3-lossless-float32"][0],
        valid["v1.5-attributes"][0],
        valid["v1.6-adaptive"][0],
        valid["v1.6-faces-adaptive"][0],
        derived["v1.7-lossless-adaptive"][0],
        valid[CODEBOOKS_SOURCE][0],
        valid[UNIFORM_RANKS_SOURCE][0],
    )
    print(f"wrote {len(valid) + len(derived)} valid and {invalid} invalid vectors to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
