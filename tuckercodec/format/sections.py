"""§6.6 The sections of format 1.0: ids, codecs, criticality, order and shapes, written once.

The encoder takes from here the entry of every section it writes (:func:`entry`) and the order
it writes them in (:data:`WRITE_ORDER`); the decoder checks the section table against the same
table (:func:`check_sections`, §5 steps 11-13).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import FormatError, UnsupportedVersionError
from . import streams
from .container import Container
from .limits import Limits, check_limit

#: Codec ids (§6.3-6.5).
QMAT = "qmat"
FACES_DELTA = "faces-delta"
MSGPACK_ZSTD = "msgpack-zstd"


@dataclass(frozen=True)
class SectionKind:
    """One row of the table of §6.6."""

    codec: str
    critical: bool
    required: bool


#: The sections of §6.6, in the order the decoder checks them (FACE first: U1's parents
#: come from the faces).
KNOWN_SECTIONS: dict[str, SectionKind] = {
    "FACE": SectionKind(FACES_DELTA, critical=True, required=True),
    "U1": SectionKind(QMAT, critical=True, required=True),
    "U3": SectionKind(QMAT, critical=True, required=True),
    "CORE": SectionKind(QMAT, critical=True, required=True),
    "CENT": SectionKind(QMAT, critical=True, required=True),
    "NAME": SectionKind(MSGPACK_ZSTD, critical=False, required=False),
}
REQUIRED_SECTIONS = tuple(name for name, kind in KNOWN_SECTIONS.items() if kind.required)
#: The order the reference encoder writes (§9): the faces first, which the decoder needs for
#: U1's mesh parents; the decoder does not depend on it (§3).
WRITE_ORDER = ("FACE", "CENT", "U3", "CORE", "U1", "NAME")


def entry(section_id: str, params: Mapping[str, Any]) -> dict[str, Any]:
    """The section-table entry of a known section: its id, criticality, codec and parameters
    (the container adds offset, length and CRC)."""
    kind = KNOWN_SECTIONS[section_id]
    return {"id": section_id, "critical": kind.critical, "codec": kind.codec, **params}


def section_shape(
    params: Mapping[str, Any],
    where: str,
    *,
    expected: tuple[int, int] | None = None,
    min_cols: int = 0,
) -> tuple[int, int]:
    """The declared ``shape`` [rows, cols] of a stream section (R28-shape): two non-negative
    ints, at least ``min_cols`` columns, and equal to ``expected`` when that is given."""
    shape = params.get("shape")
    rows, cols = -1, -1
    if (
        isinstance(shape, list)
        and len(shape) == 2
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape)
    ):
        rows, cols = shape
    problem = None
    if rows < 0:
        problem = f"shape must be [rows, cols] of non-negative integers, got {shape!r}"
    elif cols < min_cols:
        problem = f"needs at least {min_cols} columns, the width is {cols}"
    elif expected is not None and (rows, cols) != expected:
        problem = (
            f"shape is [{rows}, {cols}], but the header's vertices, frames and ranks make it "
            f"[{expected[0]}, {expected[1]}]"
        )
    if problem is not None:
        raise FormatError(problem, rule="R28-shape", field=f"{where}.shape")
    return rows, cols


def check_sections(
    container: Container,
    vertices: int,
    frames: int,
    ranks: tuple[int, int],
    limits: Limits,
) -> None:
    """§5 steps 11-13: known sections with their codec and criticality, unknown critical ones
    refused, the required ones present, and every shape as the header implies and within the
    limits."""
    for section in container.sections:
        where = f"section {section.id}"
        kind = KNOWN_SECTIONS.get(section.id)
        if kind is None:
            if section.critical:
                raise UnsupportedVersionError(
                    "unknown critical section: this decoder cannot reconstruct the file without it",
                    rule="R24-unknown-critical-section",
                    field=where,
                )
            continue  # unknown ancillary sections are skipped unread
        if section.critical != kind.critical:
            raise FormatError(
                f"must be marked critical={kind.critical}",
                rule="R27-criticality",
                field=f"{where}.critical",
            )
        if section.codec != kind.codec:
            raise UnsupportedVersionError(
                f"unknown codec {section.codec!r} (expected {kind.codec!r})",
                rule="R25-unknown-codec",
                field=f"{where}.codec",
            )
    present = {section.id: section for section in container.sections}
    for section_id in REQUIRED_SECTIONS:
        if section_id not in present:
            raise FormatError(
                "a required section is missing",
                rule="R26-required-section-missing",
                field=f"section {section_id}",
            )

    i, k = ranks
    expected_shapes = {"U1": (vertices, i), "U3": (frames, k), "CORE": (i * 3 * k, 1)}
    expected_shapes["CENT"] = (frames, 3)
    for section_id in REQUIRED_SECTIONS:
        where = f"section {section_id}"
        params = present[section_id].params
        if section_id == "FACE":
            rows, cols = section_shape(params, where, min_cols=3)
            check_limit(rows, limits, "max_faces", what=f"{rows} faces", field=f"{where}.shape")
            check_limit(
                cols,
                limits,
                "max_face_width",
                what=f"faces of {cols} corners",
                field=f"{where}.shape",
            )
        else:
            rows, cols = section_shape(params, where, expected=expected_shapes[section_id])
        check_limit(
            rows * cols * streams.MAX_PLANES,
            limits,
            "max_section_bytes",
            what=f"{rows} x {cols} values of up to {streams.MAX_PLANES} bytes",
            field=f"{where}.shape",
        )
