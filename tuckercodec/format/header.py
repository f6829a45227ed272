"""§4 The header's fields: written by :func:`header_map`, checked and read by :func:`read_header`.

The header is one msgpack map (its bytes are the container's business, :mod:`.container`); this
module knows what its keys mean. :class:`FileInfo` is what a reader learns from the header
alone, without decoding any section.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FormatError
from ..measures.rate import bpfv
from ..model.sequence import UP_AXES
from .attachments import AttachmentSummary, summarize
from .container import Container
from .limits import Limits, check_limit
from .reconstruction import factor_value_count
from .sections import check_sections
from .segments import (
    SegmentEntry,
    check_segmented_sections,
    checked_u2,
    is_int,
    ranks_within,
    read_segment_index,
)

#: The error definition id of §4.1: the KG error of Karni and Gotsman (2004), in percent.
KG_DEFINITION_ID = "karni-gotsman-2004"


@dataclass(frozen=True)
class FileInfo:
    """What the header of a compressed file says, read without decoding any section."""

    format_version: str
    vertices: int
    frames: int
    ranks: tuple[int, int]
    faces: int
    face_width: int
    total_bytes: int
    kg: float | None  # the KG error the encoder measured on the decoded result
    kg_definition: str | None
    target_kg: float | None
    frame_rate: float | None
    encoder: str | None
    sections: tuple[tuple[str, int, str, bool], ...]  # (id, bytes, codec, critical)
    #: the segment index of a segmented file (§6.7); empty for a file of one decomposition.
    #: ``ranks`` is then (the shared basis's columns, or the largest i; the largest k).
    segments: tuple[SegmentEntry, ...] = ()
    #: the worst vertex the encoder measured (§4.1, 1.3; written with corrections): the largest
    #: Euclidean distance, in the sequence's units, between a decoded vertex and the input's,
    #: and its [frame, vertex]. None: not recorded (or not a number / a place in the file).
    max_distance: float | None = None
    max_distance_at: tuple[int, int] | None = None
    target_max_distance: float | None = None  # the bound given to the encoder (None: none)
    lossless: bool | None = None  # the encoder checked the decode bit for bit (None: no claim)
    #: each frame's time code (§4, 1.4), or None: frame f at f; seconds are codes / frame rate
    time_codes: tuple[float, ...] | None = None
    meters_per_unit: float | None = None  # the length of a unit of the positions, in metres
    up_axis: str | None = None  # "Y" or "Z", the source's up axis (None: not recorded)
    #: (1.5) the attributes, face sets, fields and kept face order, as the section table
    #: describes them (:func:`.attachments.summarize`); empty for a file without them
    attachments: tuple[AttachmentSummary, ...] = ()

    @property
    def bpfv(self) -> float:
        """Bits per frame per vertex of the whole file (header and connectivity included)."""
        return bpfv(self.total_bytes, self.frames, self.vertices)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-safe dictionary of every field, and the bpfv. The encoder's claims ``kg``,
        ``target_kg``, ``max_distance`` and ``target_max_distance`` are any float the file holds
        (§4.1): NaN or infinity becomes ``None``, since JSON has no such numbers
        (``json.dumps`` would write a bare ``NaN``)."""
        return {
            "format_version": self.format_version,
            "vertices": self.vertices,
            "frames": self.frames,
            "ranks": list(self.ranks),
            "faces": self.faces,
            "face_width": self.face_width,
            "total_bytes": self.total_bytes,
            "bpfv": self.bpfv,
            "kg": _json_number(self.kg),
            "kg_definition": self.kg_definition,
            "target_kg": _json_number(self.target_kg),
            "max_distance": _json_number(self.max_distance),
            "max_distance_at": None if self.max_distance_at is None else list(self.max_distance_at),
            "target_max_distance": _json_number(self.target_max_distance),
            "lossless": self.lossless,
            "frame_rate": self.frame_rate,
            "time_codes": None if self.time_codes is None else list(self.time_codes),
            "meters_per_unit": self.meters_per_unit,
            "up_axis": self.up_axis,
            "attachments": [
                {
                    "kind": item.kind,
                    "name": item.name,
                    "description": item.description,
                    "bytes": item.bytes,
                    "error": None
                    if item.error is None
                    else {
                        "definition": item.error[0],
                        "value": _json_number(item.error[1]),
                        "target": _json_number(item.error[2]),
                    },
                }
                for item in self.attachments
            ],
            "encoder": self.encoder,
            "sections": [
                {"id": s, "bytes": n, "codec": c, "critical": crit}
                for s, n, c, crit in self.sections
            ],
            "segments": [
                {
                    "first_frame": s.start,
                    "frames": s.frames,
                    "ranks": list(s.ranks),
                    "basis": s.basis,
                }
                for s in self.segments
            ],
        }


def _json_number(value: float | None) -> float | None:
    return value if value is None or math.isfinite(value) else None


# ------------------------------------------------------------------------------------------
# writing


def header_map(
    *,
    vertices: int,
    frames: int,
    ranks: tuple[int, int],
    u2: list[float],
    kg: float,
    truncation_kg: float,
    target_kg: float | None,
    encoder: str,
    frame_rate: float | None,
    claims: dict[str, Any] | None = None,
    scene: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Every header field but the section table, in the order the reference encoder writes
    them (the order changes the bytes, not the meaning). ``claims``: more keys of the
    informative ``error`` map (§4.1: the worst vertex of a file with a bound, format 1.3),
    after the others, so that a file without them is written as before; ``scene``: the time
    and scene keys of :func:`scene_keys` (format 1.4), last."""
    header: dict[str, Any] = {
        "vertices": vertices,
        "frames": frames,
        "ranks": [ranks[0], ranks[1]],
        "u2": [float(x) for x in u2],
        "error": {
            "kg": kg,
            "definition": KG_DEFINITION_ID,
            "truncation_kg": truncation_kg,
            "target_kg": target_kg,
            **(claims or {}),
        },
        "encoder": encoder,
    }
    if frame_rate is not None:
        header["frame_rate"] = float(frame_rate)  # a msgpack float, never an int (§4)
    header.update(scene or {})
    return header


def scene_keys(
    frames: int,
    time_codes: np.ndarray | None,
    meters_per_unit: float | None,
    up_axis: str | None,
) -> dict[str, Any]:
    """The time and scene keys of §4 (format 1.4) a sequence carries: ``time_codes`` only when
    they are not 0, 1, 2... (what their absence means), each other key only when known. Empty
    for a sequence that carries none, whose file is then written as before, byte for byte."""
    keys: dict[str, Any] = {}
    if time_codes is not None:
        codes = np.asarray(time_codes, dtype="<f8")
        if not np.array_equal(codes, np.arange(frames, dtype=np.float64)):
            keys["time_codes"] = codes.tobytes()  # bin: F little-endian binary64
    if meters_per_unit is not None:
        keys["meters_per_unit"] = float(meters_per_unit)  # a msgpack float, never an int
    if up_axis is not None:
        keys["up_axis"] = str(up_axis)
    return keys


# ------------------------------------------------------------------------------------------
# reading


def _field(header: dict[str, Any], key: str, valid: Callable[[Any], bool], wanted: str) -> Any:
    """The value of a header field of R20-header-field, checked by ``valid``."""
    value = header.get(key)
    if not valid(value):
        raise _bad_field(key, f"must be {wanted}, got {value!r}")
    return value


def _bad_field(key: str, problem: str) -> FormatError:
    """R20-header-field for the header's ``key``."""
    return FormatError(problem, rule="R20-header-field", field=f"header.{key}")


def _is_frame_rate(value: object) -> bool:
    return value is None or (isinstance(value, float) and math.isfinite(value) and value > 0)


def _number(value: object) -> float | None:
    """An informative number of the ``error`` map: an int or a float, never a bool (§4.1)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return None


def _place(value: object, frames: int, vertices: int) -> tuple[int, int] | None:
    """``max_distance_at`` of the ``error`` map (§4.1): [frame, vertex], two ints (not bools)
    naming a vertex of the file; anything else is no claim."""
    if not isinstance(value, list) or len(value) != 2:
        return None
    frame, vertex = value
    if not (is_int(frame) and is_int(vertex) and 0 <= frame < frames and 0 <= vertex < vertices):
        return None
    return (frame, vertex)


def read_header(container: Container, limits: Limits) -> FileInfo:
    """Check the header's fields (§5 steps 10 and 14) and the section table against them
    (steps 11-13); what the header says."""
    header = container.header
    vertices = _field(header, "vertices", lambda v: is_int(v) and v >= 1, "an integer >= 1")
    check_limit(
        vertices, limits, "max_vertices", what=f"{vertices} vertices", field="header.vertices"
    )
    frames = _field(header, "frames", lambda v: is_int(v) and v >= 1, "an integer >= 1")
    check_limit(frames, limits, "max_frames", what=f"{frames} frames", field="header.frames")
    if not container.segmented:  # a segmented file is decoded a segment at a time (§6.7)
        check_limit(
            vertices * frames,
            limits,
            "max_positions",
            what=f"{vertices} vertices x {frames} frames of decoded positions",
            field="header.vertices",
        )
    segments: tuple[SegmentEntry, ...] = ()
    if container.segmented:  # §6.7: the index replaces ranks and u2
        segments = read_segment_index(header, vertices, frames, limits)
        shared = check_segmented_sections(
            container.sections,
            vertices,
            segments,
            limits,
            coding_tools=container.coding_tools,
            corrections=container.corrections,
        )
        i = shared or max(segment.ranks[0] for segment in segments)
        k = max(segment.ranks[1] for segment in segments)
    else:
        i, k = _ranks(header.get("ranks"), vertices, frames)
        _check_single(header, vertices, frames, (i, k), limits)
        check_sections(
            container.sections,
            vertices,
            frames,
            (i, k),
            limits,
            coding_tools=container.coding_tools,
            corrections=container.corrections,
        )
    frame_rate = _field(
        header, "frame_rate", _is_frame_rate, "absent, nil or a positive finite float"
    )
    time_codes, meters_per_unit, up_axis = _scene(header, frames)

    error = header.get("error")
    error = error if isinstance(error, dict) else {}  # informative only (§4.1): never trusted
    definition = error.get("definition")
    lossless = error.get("lossless")
    encoder = header.get("encoder")
    face = container.section("FACE")
    assert face is not None  # check_sections found every required section
    face_rows, face_width = face.params["shape"]
    return FileInfo(
        format_version=f"{container.major}.{container.minor}",
        vertices=vertices,
        frames=frames,
        ranks=(i, k),
        faces=face_rows,
        face_width=face_width,
        total_bytes=container.total_length,
        kg=_number(error.get("kg")),
        kg_definition=definition if isinstance(definition, str) else None,
        target_kg=_number(error.get("target_kg")),
        max_distance=_number(error.get("max_distance")),
        max_distance_at=_place(error.get("max_distance_at"), frames, vertices),
        target_max_distance=_number(error.get("target_max_distance")),
        lossless=lossless if isinstance(lossless, bool) else None,
        frame_rate=frame_rate,
        time_codes=time_codes,
        meters_per_unit=meters_per_unit,
        up_axis=up_axis,
        encoder=encoder if isinstance(encoder, str) else None,
        sections=tuple((s.id, s.length, s.codec, s.critical) for s in container.sections),
        segments=segments,
        attachments=summarize(container.sections),
    )


def _scene(header: dict[str, Any], frames: int) -> tuple[tuple[float, ...] | None, Any, Any]:
    """The time and scene keys (§4, format 1.4; §5 step 14 after ``frame_rate``): the time
    codes, the unit and the up axis, each checked (R20-header-field)."""
    codes = _time_codes(header.get("time_codes"), frames)
    unit = _field(
        header, "meters_per_unit", _is_frame_rate, "absent, nil or a positive finite float"
    )
    axis = _field(header, "up_axis", lambda v: v is None or v in UP_AXES, 'absent, nil, "Y" or "Z"')
    return codes, unit, axis


def _time_codes(value: object, frames: int) -> tuple[float, ...] | None:
    """``time_codes`` (§4, 1.4): absent or nil, or F little-endian binary64 values as a bin of
    8·F bytes, finite and strictly increasing (R20-header-field)."""
    if value is None:
        return None
    if not isinstance(value, bytes) or len(value) != 8 * frames:
        got = f"{len(value)} bytes" if isinstance(value, bytes) else type(value).__name__
        raise _bad_field(
            "time_codes", f"must be {8 * frames} bytes (a binary64 per frame), got {got}"
        )
    codes = np.frombuffer(value, dtype="<f8")
    if not np.isfinite(codes).all():
        frame = int(np.flatnonzero(~np.isfinite(codes))[0])
        raise _bad_field("time_codes", f"must be finite: frame {frame}'s is not")
    if frames > 1 and not (np.diff(codes) > 0).all():
        frame = int(np.flatnonzero(np.diff(codes) <= 0)[0]) + 1
        raise _bad_field(
            "time_codes",
            f"must increase: frame {frame}'s {codes[frame]!r} follows {codes[frame - 1]!r}",
        )
    listed: list[float] = codes.tolist()
    return tuple(listed)


def _check_single(
    header: dict[str, Any], vertices: int, frames: int, ranks: tuple[int, int], limits: Limits
) -> None:
    """§5 step 10 after the ranks, for a file of one decomposition: the factor values within
    the limit, then ``u2``."""
    i, k = ranks
    factor_values = factor_value_count(vertices, frames, i, k)
    check_limit(
        factor_values,
        limits,
        "max_factor_values",
        what=f"ranks ({i}, {k}) make {factor_values} factor values, which",
        field="header.ranks",
    )
    checked_u2(header.get("u2"), "header.u2")


def _ranks(ranks: object, vertices: int, frames: int) -> tuple[int, int]:
    """``ranks`` [i, k] with 1 <= i <= min(K, 3F) and 1 <= k <= min(F, 3K) (R22-ranks)."""
    largest_i, largest_k = min(vertices, 3 * frames), min(frames, 3 * vertices)
    checked = ranks_within(ranks, largest_i, largest_k)
    if checked is None:
        raise FormatError(
            f"must be [i, k], two integers with 1 <= i <= min(K, 3F) = {largest_i} and "
            f"1 <= k <= min(F, 3K) = {largest_k}: got {ranks!r}",
            rule="R22-ranks",
            field="header.ranks",
        )
    return checked
