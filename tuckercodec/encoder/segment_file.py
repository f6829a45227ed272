"""The bytes of a segmented file (format 1.1, spec/FORMAT.md §6.7): its sections in the order
the reference encoder writes them, and the header with the segment index."""

from __future__ import annotations

from typing import Any

from .._version import __version__
from ..format import qmat
from ..format.container import pack_container
from ..format.header import KG_DEFINITION_ID
from ..format.qmat import QuantizedMatrix
from ..format.sections import KNOWN_SECTIONS
from ..format.sections import entry as section_entry
from ..format.segments import (
    SEGMENT_WRITE_ORDER,
    SEGMENTED,
    SEGMENTED_MINOR,
    segment_map,
    segment_section_id,
)
from ..topology import MeshPrediction
from .segment_work import Quantized, SegmentedEncode


def segment_sections(
    work: SegmentedEncode, quantized: Quantized, level: int
) -> list[tuple[dict[str, Any], bytes]]:
    """The file's sections: FACE, the shared U1, each segment's CENT, U3, CORE (and U1),
    then NAME."""
    out: list[tuple[dict[str, Any], bytes]] = [
        (section_entry("FACE", work.face_section[0], work.face_codec), work.face_section[1])
    ]
    if work.fixed_basis is not None:  # a given basis: its section, byte for byte
        out.append((_entry("U1", work.fixed_basis.params), work.fixed_basis.payload))
    elif quantized.shared_u1 is not None:
        params, payload = qmat.encode_matrix(quantized.shared_u1, work.mesh, level=level)
        out.append((_entry("U1", params), payload))
    for s in range(len(work.models)):
        matrices: dict[str, tuple[QuantizedMatrix, MeshPrediction | None, bool]] = {
            "CENT": (quantized.centroids[s], None, True),
            "U3": (quantized.u3[s], None, True),
            "CORE": (quantized.core[s], None, False),
        }
        own = quantized.own_u1[s]
        if own is not None:
            matrices["U1"] = (own, work.mesh, True)
        for stem in SEGMENT_WRITE_ORDER:
            if stem not in matrices:
                continue
            matrix, parents, predict = matrices[stem]
            params, payload = qmat.encode_matrix(
                matrix, parents, allow_predict=predict, level=level
            )
            out.append((_entry(segment_section_id(stem, s), params, stem), payload))
    if work.name_section is not None:
        out.append((_entry("NAME", work.name_section[0]), work.name_section[1]))
    return out


def pack_segmented(
    work: SegmentedEncode, quantized: Quantized, error2: float, target_kg: float | None
) -> tuple[bytes, dict[str, int]]:
    segments = [
        segment_map(model.frames, ranks, model.u2.reshape(-1).tolist(), work.basis)
        for model, ranks in zip(work.models, quantized.choice.ranks, strict=True)
    ]
    header: dict[str, Any] = {
        "vertices": work.vertex_count,
        "frames": work.frame_count,
        "segments": segments,
        "error": {
            "kg": work.kg(error2),
            "definition": KG_DEFINITION_ID,
            "truncation_kg": work.kg(quantized.choice.truncation2),
            "target_kg": target_kg,
        },
        "encoder": f"tuckercodec {__version__}",
    }
    if work.source.frame_rate is not None:
        header["frame_rate"] = float(work.source.frame_rate)
    packed = segment_sections(work, quantized, work.level)
    sizes: dict[str, int] = {}
    for entry, payload in packed:
        stem = entry["id"].split(".")[0]
        sizes[stem] = sizes.get(stem, 0) + len(payload)
    data = pack_container(header, packed, flags=SEGMENTED, minor=SEGMENTED_MINOR)
    return data, sizes


def _entry(section_id: str, params: dict[str, Any], stem: str | None = None) -> dict[str, Any]:
    """A section-table entry: the kind of ``stem`` (the section's own id if not given)."""
    kind = KNOWN_SECTIONS[stem or section_id]
    return {"id": section_id, "critical": kind.critical, "codec": kind.codec, **params}
