"""Files of format 1.6 made by hand from any valid file: every position factor (U1, U3, CORE,
CENT and their ``.s`` forms) re-coded through the reference adaptive coder
(``tuckercodec/format/adaptive.py``, spec/FORMAT.md §6.14) with ``coder`` 1, flag bit 3 and
minor 6. The integers, and so the positions, are the original file's: a decoder of 1.6 must
decode the copy to the same positions as the original. For the JavaScript decoder's tests and
measurements while the encoder does not write 1.6 itself.

    python -m tests.support.adaptive_files IN.tkc OUT.tkc
"""

from __future__ import annotations

import re
import sys
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import msgpack
import numpy as np

from tuckercodec.format import adaptive, faces, streams
from tuckercodec.format.container import pack_raw, parse_container
from tuckercodec.model.topology import mesh_prediction

#: The sections §6.14 allows ``coder`` 1 in.
POSITION_FACTOR = re.compile(r"^(U1|U3|CORE|CENT)(\.\d+)?$")
#: Preamble flag bit 3 (adaptive coding) and the minor version that goes with it.
FLAG_ADAPTIVE = 1 << 3
ADAPTIVE_MINOR = 6


def stored_columns(params: dict[str, Any], payload: bytes, where: str) -> np.ndarray:
    """A qmat section's stored integers (q or residuals, §6.3) as (cols, rows) int64."""
    rows, cols = params["shape"]
    stream = streams.unpack_integers(payload, rows * cols, params["planes"], where)
    return np.asarray(stream, dtype=np.int64).reshape(cols, rows)


def coding_order(section_id: str, rows: int, mesh: Any) -> adaptive.CodingOrder:
    """§6.14's coding order: U1's mesh order from predictor 2's structure, else ascending."""
    if section_id.split(".")[0] != "U1":
        return adaptive.sequence_order(rows)
    steps = mesh.mean_steps
    return adaptive.mesh_order(rows, steps.rows, steps.sources, steps.source_ends)


@dataclass
class AdaptiveParts:
    """A file taken apart with its position factors re-coded: preamble flags (bit 3 set) and
    minor version, header (without the table) and sections, ``(entry, payload)`` in file order,
    to be edited (tests that break a rule) and put back together by :meth:`pack`."""

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


def adaptive_parts(data: bytes) -> AdaptiveParts:
    """``data`` (a valid file of 1.5 or before) taken apart, every position factor re-coded
    in an adaptive stream with ``coder`` 1."""
    container = parse_container(data)
    header = {k: v for k, v in container.header.items() if k != "sections"}
    vertices = int(header["vertices"])
    face = next(s for s in container.sections if s.id == "FACE")
    coded_faces = faces.decode_face_section(
        face.codec, container.payload(data, face), face.params, vertices, "section FACE"
    )
    mesh = mesh_prediction(coded_faces, vertices)
    sections = []
    for section in container.sections:
        entry = {"id": section.id, "critical": section.critical, "codec": section.codec}
        entry.update(section.params)
        payload = bytes(container.payload(data, section))
        if POSITION_FACTOR.match(section.id) and section.codec == "qmat":
            columns = stored_columns(section.params, payload, f"section {section.id}")
            order = coding_order(section.id, columns.shape[1], mesh)
            payload = adaptive.encode_columns(columns, order)
            entry["coder"] = 1
        sections.append((entry, payload))
    minor = max(container.minor, ADAPTIVE_MINOR)
    return AdaptiveParts(container.flags | FLAG_ADAPTIVE, minor, header, sections)


def adaptive_copy(data: bytes) -> bytes:
    """``data`` with every position factor in an adaptive stream (format 1.6)."""
    return adaptive_parts(data).pack()


def main(argv: list[str]) -> None:
    source, target = (Path(a) for a in argv)
    target.write_bytes(adaptive_copy(source.read_bytes()))


if __name__ == "__main__":
    main(sys.argv[1:])
