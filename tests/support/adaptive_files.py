"""A valid file's twins that differ only in how its position factors (U1, U3, CORE, CENT and
their ``.s`` forms) turn their integers into bytes: :func:`adaptive_copy`, every one through the
reference adaptive coder (spec/FORMAT.md §6.14) with ``coder`` 1, whichever coder the encoder
chose (tools/generate/vectors.py's ``adaptive_everywhere``, which wrote the vectors of 1.6; FACE
as it is); and :func:`zstd_copy`, every one, and a faces-traverse FACE's streams, in §6.1's zstd
planes, as files were before 1.6 (its new vertices as gaps again, whether they were adaptive
ranks or, format 1.9, places in a uniform stream; a RESD section's adaptive chunks, format 1.7,
are kept as they are). The integers, and
so the positions, are the original file's. Taken apart as :class:`AdaptiveParts`, a file can be
edited to break one rule, its preamble flags included, and put back together with every CRC
right.

    python -m tests.support.adaptive_files adaptive|zstd IN.tkc OUT.tkc
"""

from __future__ import annotations

import sys
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from tools.generate.vectors import adaptive_everywhere
from tuckercodec.format import adaptive, faces, qmat, streams, traversal
from tuckercodec.format.container import pack_container, pack_raw, parse_container
from tuckercodec.format.residual import CORRECTIONS, CORRECTIONS_MINOR
from tuckercodec.format.segments import SEGMENTED, SEGMENTED_MINOR
from tuckercodec.format.traversal import UNIFORM_RANKS
from tuckercodec.model.topology import MeshPrediction, mesh_prediction


@dataclass
class AdaptiveParts:
    """A file taken apart: preamble flags and minor version, header (without the table) and
    sections, ``(entry, payload)`` in file order. :meth:`pack` writes the flags as they are
    (unlike ``pack_container``, which sets flag bit 3 wherever a section has ``coder`` 1)."""

    flags: int
    minor: int
    header: dict[str, Any]
    sections: list[tuple[dict[str, Any], bytes]]

    def index(self, section_id: str) -> int:
        return next(n for n, (entry, _) in enumerate(self.sections) if entry["id"] == section_id)

    def pack(self) -> bytes:
        """The file, offsets, lengths and CRCs made right whatever the entries say."""
        table, offset = [], 0
        for entry, payload in self.sections:
            crc = zlib.crc32(payload)
            table.append({**entry, "offset": offset, "length": len(payload), "crc32": crc})
            offset += len(payload)
        header_bytes = msgpack.packb({**self.header, "sections": table}, use_bin_type=True)
        body = b"".join(payload for _, payload in self.sections)
        return pack_raw(1, self.minor, self.flags, header_bytes, body)


def adaptive_copy(data: bytes) -> bytes:
    """``data`` (a valid file) with every position factor in an adaptive stream."""
    return adaptive_everywhere(data)


def adaptive_parts(data: bytes) -> AdaptiveParts:
    """:func:`adaptive_copy` of ``data``, taken apart."""
    return taken_apart(adaptive_copy(data))


def taken_apart(data: bytes) -> AdaptiveParts:
    """A valid file as :class:`AdaptiveParts`."""
    container = parse_container(data)
    header = {k: v for k, v in container.header.items() if k != "sections"}
    sections = [
        (
            {"id": s.id, "critical": s.critical, "codec": s.codec, **s.params},
            bytes(container.payload(data, s)),
        )
        for s in container.sections
    ]
    return AdaptiveParts(container.flags, container.minor, header, sections)


def stored_integers(
    section_id: str, params: dict[str, Any], payload: bytes, mesh: MeshPrediction
) -> np.ndarray:
    """The integers a position factor stores (q or residuals, §6.3), in stream order (int64),
    whichever its coder: §6.1's planes, or §6.14's stream in its coding order (``mesh``: the
    file's, from its faces as FACE decodes them)."""
    rows, cols = params["shape"]
    if params.get("coder", adaptive.CODER_ZSTD) == adaptive.CODER_ZSTD:
        return streams.unpack_integers(payload, rows * cols, params["planes"], section_id)
    order = qmat.coding_order(mesh if section_id.split(".")[0] == "U1" else None, rows)
    return adaptive.decode_columns(payload, cols, rows, order, section_id).reshape(-1)


def zstd_copy(data: bytes) -> bytes:
    """``data`` (a valid file) with every adaptive stream stored as §6.1's zstd planes, in the
    fewest planes that hold its integers (FACE's streams too, its new vertices as gaps again),
    flag bit 3 (and bit 6, uniform ranks) cleared: a file of 1.5 or before, with the minor
    version it would have had; unless predictor 2's pushes (``mean_push``, also 1.6) keep it a
    file of 1.6."""
    parts = taken_apart(data)
    uniform = bool(parts.flags & UNIFORM_RANKS)
    face_n = parts.index("FACE")
    face_entry, face_payload = parts.sections[face_n]
    vertices = int(parts.header["vertices"])
    params = {k: v for k, v in face_entry.items() if k not in ("id", "critical", "codec")}
    coded = faces.decode_face_section(
        face_entry["codec"],
        face_payload,
        params,
        vertices,
        "section FACE",
        adaptive_coding=True,
        uniform_ranks=uniform,
    )
    mesh = mesh_prediction(coded, vertices)
    if face_entry.get("coder") == adaptive.CODER_ADAPTIVE:
        count, width = face_entry["shape"]
        values, corner_order = traversal.read_streams(
            face_payload,
            params,
            count,
            width,
            vertices,
            "FACE",
            adaptive_coding=True,
            uniform_ranks=uniform,
        )
        face_params, packed = traversal.pack_streams(
            values, count, width, corner_order, streams.DEFAULT_LEVEL
        )
        dropped = ("coder", "ranks", "streams")
        entry = {k: v for k, v in face_entry.items() if k not in dropped}
        parts.sections[face_n] = ({**entry, **face_params}, packed)
    for n, (entry, payload) in enumerate(parts.sections):
        # a RESD section's coder (format 1.7, flag bit 4) is not a position factor's: kept
        if entry.get("coder") != adaptive.CODER_ADAPTIVE or entry["codec"] == "residual":
            continue
        stream = stored_integers(str(entry["id"]), entry, payload, mesh)
        packed, planes = streams.pack_integers(stream)
        entry = {k: v for k, v in entry.items() if k != "coder"}
        parts.sections[n] = ({**entry, "planes": planes}, packed)
    # the minor version the file had before 1.6: pack_container raises it for the coding
    # tools (1.2), the keys of 1.4 and the sections of 1.5
    minor = 0
    if parts.flags & SEGMENTED:
        minor = SEGMENTED_MINOR
    if parts.flags & CORRECTIONS:
        minor = CORRECTIONS_MINOR
    flags = parts.flags & ~UNIFORM_RANKS  # no ranks is left
    if adaptive.uses_adaptive([entry for entry, _ in parts.sections]):
        return pack_container(parts.header, parts.sections, flags=flags, minor=minor)
    flags &= ~adaptive.ADAPTIVE
    return pack_container(parts.header, parts.sections, flags=flags, minor=minor, adaptive=False)


def main(argv: list[str]) -> None:
    kind, source, target = argv
    copy = {"adaptive": adaptive_copy, "zstd": zstd_copy}[kind]
    Path(target).write_bytes(copy(Path(source).read_bytes()))


if __name__ == "__main__":
    main(sys.argv[1:])
