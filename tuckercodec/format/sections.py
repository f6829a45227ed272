"""§3 The section table, and §6.6 the sections of format 1.0: ids, codecs, criticality, order
and shapes, written once.

:func:`read_section_table` checks the table's layout (§3, §5 step 8). The encoder takes from here
the entry of every section it writes (:func:`entry`) and the order it writes them in
(:data:`WRITE_ORDER`); the decoder checks the table against §6.6 (:func:`check_sections`, §5
steps 11-13).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..errors import FormatError, UnsupportedVersionError
from . import streams
from .limits import Limits, check_limit
from .residual import RESIDUAL, SECTION_STEM

#: Codec ids (§6.3-6.5, §6.8).
QMAT = "qmat"
FACES_DELTA = "faces-delta"
FACES_TRAVERSE = "faces-traverse"
MSGPACK_ZSTD = "msgpack-zstd"
#: Preamble flag bit 1 (critical, format 1.2): the file uses a coding tool of 1.2, the codec
#: faces-traverse (§6.8) or a qmat predictor above 1, which decoders of 1.0 and 1.1 cannot undo.
CODING_TOOLS = 0x0002
#: The minor version of a file that sets :data:`CODING_TOOLS`.
CODING_TOOLS_MINOR = 2


@dataclass(frozen=True)
class Section:
    """One entry of the section table, with the codec parameters it carries."""

    id: str
    offset: int  # from the start of the data area
    length: int
    crc32: int
    critical: bool
    codec: str
    params: dict[str, Any] = field(default_factory=dict)

    def file_offset(self, data_start: int) -> int:
        """The section's first byte, counted from the start of the file."""
        return data_start + self.offset


@dataclass(frozen=True)
class SectionKind:
    """One row of the table of §6.6."""

    codec: str
    critical: bool
    required: bool
    #: Codecs format 1.2 adds for the section, allowed only when the preamble sets CODING_TOOLS.
    coding_tools_codecs: tuple[str, ...] = ()


#: The sections of §6.6, in the order the decoder checks them (FACE first: U1's parents
#: come from the faces).
KNOWN_SECTIONS: dict[str, SectionKind] = {
    "FACE": SectionKind(
        FACES_DELTA, critical=True, required=True, coding_tools_codecs=(FACES_TRAVERSE,)
    ),
    "U1": SectionKind(QMAT, critical=True, required=True),
    "U3": SectionKind(QMAT, critical=True, required=True),
    "CORE": SectionKind(QMAT, critical=True, required=True),
    "CENT": SectionKind(QMAT, critical=True, required=True),
    "NAME": SectionKind(MSGPACK_ZSTD, critical=False, required=False),
}
REQUIRED_SECTIONS = tuple(name for name, kind in KNOWN_SECTIONS.items() if kind.required)
#: The corrections of format 1.3 (§6.9): known, and required, only in a file with flag bit 2.
RESIDUAL_KIND = SectionKind(RESIDUAL, critical=True, required=True)


def known_kinds(corrections: bool) -> dict[str, SectionKind]:
    """§6.6's sections, with RESD when the preamble sets flag bit 2."""
    return {**KNOWN_SECTIONS, SECTION_STEM: RESIDUAL_KIND} if corrections else KNOWN_SECTIONS


#: The order the reference encoder writes (§9): the faces first, which the decoder needs for
#: U1's mesh parents; the decoder does not depend on it (§3).
WRITE_ORDER = ("FACE", "CENT", "U3", "CORE", "U1", "RESD", "NAME")


_SECTION_KEYS: dict[str, type] = {
    "id": str,
    "offset": int,
    "length": int,
    "crc32": int,
    "critical": bool,
    "codec": str,
}


def read_section_table(
    header: dict[str, Any], data_length: int, limits: Limits
) -> tuple[Section, ...]:
    """Check the section table (§3, §5 step 8): entries back to back from offset 0 to the end
    of the file, each id once."""
    table = header.get("sections")
    if not isinstance(table, list):
        raise FormatError(
            "missing or not an array", rule="R13-section-table-missing", field="header.sections"
        )
    check_limit(
        len(table), limits, "max_sections", what=f"{len(table)} sections", field="header.sections"
    )
    sections = []
    expected_offset = 0
    seen: set[str] = set()
    for index, entry in enumerate(table):
        where = f"header.sections[{index}]"
        problem = _entry_problem(entry, where)
        if problem is not None:
            raise FormatError(problem[1], rule="R14-section-entry-field", field=problem[0])
        section_id = entry["id"]
        if section_id in seen:
            raise FormatError(
                f"section {section_id!r} appears twice",
                rule="R15-section-duplicate-id",
                field=f"{where}.id",
            )
        seen.add(section_id)
        if entry["offset"] != expected_offset:
            raise FormatError(
                f"section {section_id!r} starts at {entry['offset']}, but sections are back to "
                f"back and this one must start at {expected_offset}",
                rule="R16-section-not-contiguous",
                field=f"{where}.offset",
            )
        if entry["length"] < 0 or entry["offset"] + entry["length"] > data_length:
            raise FormatError(
                f"section {section_id!r} ({entry['length']} bytes at {entry['offset']}) runs past "
                f"the end of the data area ({data_length} bytes)",
                rule="R17-section-past-end",
                field=f"{where}.length",
            )
        if not 0 <= entry["crc32"] <= 0xFFFFFFFF:
            raise FormatError(
                f"not a CRC-32: {entry['crc32']}",
                rule="R14-section-entry-field",
                field=f"{where}.crc32",
            )
        expected_offset += entry["length"]
        params = {k: v for k, v in entry.items() if k not in _SECTION_KEYS}
        sections.append(
            Section(
                section_id,
                entry["offset"],
                entry["length"],
                entry["crc32"],
                entry["critical"],
                entry["codec"],
                params,
            )
        )
    if expected_offset != data_length:
        raise FormatError(
            f"the sections cover {expected_offset} bytes of a {data_length}-byte data area",
            rule="R18-section-coverage",
            field="header.sections",
        )
    return tuple(sections)


def _entry_problem(entry: object, where: str) -> tuple[str, str] | None:
    """``(field, reason)`` if an entry lacks one of the six fields or its type, or its id is not
    1-16 printable ASCII characters; the first part of R14-section-entry-field."""
    if not isinstance(entry, dict):
        return where, "a section entry must be a map"
    for key, kind in _SECTION_KEYS.items():
        value = entry.get(key)
        # bool is an int in Python: keep the two apart
        if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
            return f"{where}.{key}", f"missing or not {kind.__name__}: {value!r}"
    section_id = entry["id"]
    if not (1 <= len(section_id) <= 16 and section_id.isascii() and section_id.isprintable()):
        return f"{where}.id", f"a section id is 1 to 16 printable ASCII characters: {section_id!r}"
    return None


def entry(section_id: str, params: Mapping[str, Any], codec: str | None = None) -> dict[str, Any]:
    """The section-table entry of a known section: its id, criticality, codec (its kind's, unless
    given) and parameters (the container adds offset, length and CRC). A segment's section
    (``U3.2``) has the kind of its stem."""
    kind = KNOWN_SECTIONS[section_id.split(".")[0]]
    return {"id": section_id, "critical": kind.critical, "codec": codec or kind.codec, **params}


def with_coding_tools(
    entries: list[dict[str, Any]], flags: int, minor: int, coding_tools: bool | None
) -> tuple[int, int]:
    """The preamble's ``(flags, minor)`` for a file of these section entries: with flag bit 1
    and minor version 2 if ``coding_tools`` says so, or (``None``) if a section needs it."""
    if coding_tools is None:
        coding_tools = uses_coding_tools(entries)
    if coding_tools:
        return flags | CODING_TOOLS, max(minor, CODING_TOOLS_MINOR)
    return flags, minor


def uses_coding_tools(entries: list[dict[str, Any]]) -> bool:
    """Whether any of these section entries needs preamble flag bit 1 (format 1.2): a codec of
    1.2, or a qmat predictor above 1."""
    for item in entries:  # any entry: files broken on purpose (tests, vectors) pass here too
        kind = KNOWN_SECTIONS.get(str(item.get("id", "")).split(".")[0])
        codec = item.get("codec")
        if kind is not None and codec in kind.coding_tools_codecs:
            return True
        predict = item.get("predict")
        ancillary = item.get("critical") is False  # a field's factors (1.5) allow them anyway
        if (
            codec == QMAT
            and not ancillary
            and isinstance(predict, bytes)
            and any(b > 1 for b in predict)
        ):
            return True
    return False


def section_shape(
    params: Mapping[str, Any],
    where: str,
    *,
    expected: tuple[int, int] | None = None,
    min_cols: int = 0,
    max_cols: int | None = None,
    rows_of: int | None = None,
) -> tuple[int, int]:
    """The declared ``shape`` [rows, cols] of a stream section (R28-shape): two non-negative
    ints, at least ``min_cols`` columns (and at most ``max_cols``), ``rows_of`` rows if given,
    and equal to ``expected`` when that is given."""
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
    elif max_cols is not None and cols > max_cols:
        problem = f"has at most {max_cols} columns, the width is {cols}"
    elif rows_of is not None and rows != rows_of:
        problem = f"has {rows_of} rows (one per vertex), not {rows}"
    elif expected is not None and (rows, cols) != expected:
        problem = (
            f"shape is [{rows}, {cols}], but the header's vertices, frames and ranks make it "
            f"[{expected[0]}, {expected[1]}]"
        )
    if problem is not None:
        raise FormatError(problem, rule="R28-shape", field=f"{where}.shape")
    return rows, cols


def check_known_sections(
    table: tuple[Section, ...], known: Mapping[str, SectionKind], *, coding_tools: bool = False
) -> dict[str, Section]:
    """§5 step 11: each entry of a known id has its kind's criticality (R27) and codec (R25);
    an unknown critical id is refused (R24) and an unknown ancillary one skipped. Returns the
    known sections by id. With ``coding_tools`` (preamble flag bit 1), the codecs of format 1.2
    are known too."""
    present: dict[str, Section] = {}
    for section in table:
        where = f"section {section.id}"
        kind = known.get(section.id)
        if kind is None:
            if section.critical:
                raise UnsupportedVersionError(
                    "unknown critical section: this decoder cannot reconstruct the file without it",
                    rule="R24-unknown-critical-section",
                    field=where,
                )
            continue  # unknown ancillary sections are skipped unread
        codecs = (kind.codec, *kind.coding_tools_codecs) if coding_tools else (kind.codec,)
        check_kind(section, kind.critical, codecs)
        present[section.id] = section
    return present


def check_kind(section: Section, critical: bool, codecs: tuple[str, ...]) -> None:
    """A known section's criticality (R27), then its codec, the first of ``codecs`` or one of
    the others (R25): §5 step 11, and step 19 for the sections of 1.5."""
    where = f"section {section.id}"
    if section.critical != critical:
        raise FormatError(
            f"must be marked critical={critical}", rule="R27-criticality", field=f"{where}.critical"
        )
    if section.codec not in codecs:
        raise UnsupportedVersionError(
            f"unknown codec {section.codec!r} (expected {codecs[0]!r})",
            rule="R25-unknown-codec",
            field=f"{where}.codec",
        )


def require_sections(present: Mapping[str, Section], required: list[str]) -> None:
    """§5 step 12: every id of ``required`` is in the table, checked in that order (R26)."""
    for section_id in required:
        if section_id not in present:
            raise FormatError(
                "a required section is missing",
                rule="R26-required-section-missing",
                field=f"section {section_id}",
            )


def check_stream_size(rows: int, cols: int, limits: Limits, where: str) -> None:
    """rows x cols values of up to four bytes fit ``max_section_bytes`` (R21)."""
    check_limit(
        rows * cols * streams.MAX_PLANES,
        limits,
        "max_section_bytes",
        what=f"{rows} x {cols} values of up to {streams.MAX_PLANES} bytes",
        field=f"{where}.shape",
    )


def check_face_shape(params: Mapping[str, Any], limits: Limits) -> None:
    """§5 step 13 for FACE: at least 3 columns, within max_faces and max_face_width."""
    where = "section FACE"
    rows, cols = section_shape(params, where, min_cols=3)
    check_limit(rows, limits, "max_faces", what=f"{rows} faces", field=f"{where}.shape")
    check_limit(
        cols, limits, "max_face_width", what=f"faces of {cols} corners", field=f"{where}.shape"
    )
    check_stream_size(rows, cols, limits, where)


def check_sections(
    table: tuple[Section, ...],
    vertices: int,
    frames: int,
    ranks: tuple[int, int],
    limits: Limits,
    *,
    coding_tools: bool = False,
    corrections: bool = False,
) -> None:
    """§5 steps 11-13: known sections with their codec and criticality, unknown critical ones
    refused, the required ones present (RESD too with ``corrections``, flag bit 2), and every
    shape as the header implies and within the limits."""
    present = check_known_sections(table, known_kinds(corrections), coding_tools=coding_tools)
    require_sections(present, list(REQUIRED_SECTIONS) + ([SECTION_STEM] if corrections else []))
    i, k = ranks
    expected_shapes = {
        "U1": (vertices, i),
        "U3": (frames, k),
        "CORE": (i * 3 * k, 1),
        "CENT": (frames, 3),
    }
    check_face_shape(present["FACE"].params, limits)
    for section_id, shape in expected_shapes.items():
        where = f"section {section_id}"
        rows, cols = section_shape(present[section_id].params, where, expected=shape)
        check_stream_size(rows, cols, limits, where)
