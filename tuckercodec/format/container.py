"""§2, §4 and §5 The container: signature, preamble, header map, and the validation order.

This module knows bytes, not meshes. A file is::

    offset 0   signature       8 bytes  89 54 4B 43 0D 0A 1A 0A  ("\\x89TKC\\r\\n\\x1a\\n")
    offset 8   preamble       20 bytes  u16 major, u16 minor, u32 flags,
                                        u32 header_length, u64 total_length (little-endian)
    offset 28  preamble CRC    4 bytes  CRC-32 of bytes 0..27
    offset 32  header          header_length bytes, one msgpack map
               header CRC      4 bytes  CRC-32 of the header bytes
               data area       the sections, back to back, in the order of the section table

Validation runs in the order of §5 (steps 1-9) and each failure raises the
:class:`~tuckercodec.errors.FormatError` subclass §11 gives, carrying the rule's identifier
and naming the field or offset at fault; the section table (§3) is read by
:func:`.sections.read_section_table`. Files on disk are read by :mod:`.disk`.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import msgpack

from ..errors import (
    ChecksumError,
    FormatError,
    LimitError,
    TruncatedFileError,
    UnsupportedVersionError,
)
from .adaptive import ADAPTIVE, ADAPTIVE_MINOR, uses_adaptive
from .attachments import ATTACHMENTS_MINOR, attachment_codec
from .limits import DEFAULT_LIMITS, Limits
from .residual import (
    ADAPTIVE_CORRECTIONS,
    ADAPTIVE_CORRECTIONS_MINOR,
    CODEBOOKS,
    CODEBOOKS_MINOR,
    CORRECTIONS,
    RESIDUAL,
)
from .sections import (
    CODING_TOOLS,
    FACES_TRAVERSE,
    Section,
    read_section_table,
    with_coding_tools,
)
from .segments import SEGMENTED
from .traversal import UNIFORM_RANKS, UNIFORM_RANKS_MINOR

SIGNATURE = b"\x89TKC\r\n\x1a\n"
FORMAT_MAJOR = 1
FORMAT_MINOR = 0
#: The preamble after the signature (§2): major, minor, flags, header_length, total_length.
PREAMBLE = struct.Struct("<HHIIQ")
#: A CRC-32 as stored (§1).
CRC = struct.Struct("<I")
PREAMBLE_END = len(SIGNATURE) + PREAMBLE.size  # 28: where the preamble CRC starts
HEAD_SIZE = PREAMBLE_END + CRC.size  # 32: where the header starts

#: The header keys of format 1.4 (§4: time codes, unit, up axis): a file that has any of them
#: says minor 4 at least; every 1.x decoder reads it (those before 1.4 ignore the keys, §10).
SCENE_KEYS = ("time_codes", "meters_per_unit", "up_axis")
SCENE_MINOR = 4

#: Bits 0-15 of the preamble flags are critical: a decoder rejects any it does not know.
CRITICAL_FLAGS_MASK = 0x0000FFFF
#: Critical flags this decoder knows: bit 0, a segmented file (format 1.1, §6.7), and bit 1,
#: the coding tools of format 1.2, bit 2, corrections (format 1.3, §6.9), bit 3, adaptive
#: coding (1.6, §6.14), bit 4, adaptive corrections (1.7), bit 5, codebooks (1.8, §6.9) and
#: bit 6, new vertices in uniform streams (1.9, §6.8).
KNOWN_CRITICAL_FLAGS = (
    SEGMENTED
    | CODING_TOOLS
    | CORRECTIONS
    | ADAPTIVE
    | ADAPTIVE_CORRECTIONS
    | CODEBOOKS
    | UNIFORM_RANKS
)


@dataclass(frozen=True)
class Preamble:
    """The preamble's fields (§2), checked by :func:`read_preamble`."""

    major: int
    minor: int
    flags: int
    header_length: int
    total_length: int

    @property
    def header_end(self) -> int:
        """Where the header CRC starts: the header runs from byte 32 to here."""
        return HEAD_SIZE + self.header_length

    @property
    def data_start(self) -> int:
        """Where the data area (the first section) starts."""
        return self.header_end + CRC.size


class RangeReader(Protocol):
    """Reads ``length`` bytes of a file from ``offset`` (:class:`.disk.FileRanges`)."""

    def read(self, offset: int, length: int) -> bytes: ...


@dataclass(frozen=True)
class Container:
    """A parsed container: the preamble fields, the header map and the section table.

    The section payloads are not read or checked until :meth:`payload` asks for one.
    """

    major: int
    minor: int
    flags: int
    header: dict[str, Any]
    sections: tuple[Section, ...]
    data_start: int
    total_length: int

    def section(self, section_id: str) -> Section | None:
        """The section with this id, or ``None``."""
        for entry in self.sections:
            if entry.id == section_id:
                return entry
        return None

    @property
    def segmented(self) -> bool:
        """Whether the preamble sets flag bit 0: frames in segments (§6.7)."""
        return bool(self.flags & SEGMENTED)

    @property
    def coding_tools(self) -> bool:
        """Whether the preamble sets flag bit 1: the coding tools of format 1.2 (§6.8)."""
        return bool(self.flags & CODING_TOOLS)

    @property
    def corrections(self) -> bool:
        """Whether the preamble sets flag bit 2: corrections (format 1.3, §6.9, §8.1)."""
        return bool(self.flags & CORRECTIONS)

    @property
    def adaptive(self) -> bool:
        """Whether the preamble sets flag bit 3: adaptive coding (format 1.6, §6.14)."""
        return bool(self.flags & ADAPTIVE)

    @property
    def adaptive_corrections(self) -> bool:
        """Whether the preamble sets flag bit 4: corrections in adaptive streams (format 1.7,
        §6.9)."""
        return bool(self.flags & ADAPTIVE_CORRECTIONS)

    @property
    def codebooks(self) -> bool:
        """Whether the preamble sets flag bit 5: corrections with codebooks (format 1.8, §6.9)."""
        return bool(self.flags & CODEBOOKS)

    @property
    def uniform_ranks(self) -> bool:
        """Whether the preamble sets flag bit 6: faces-traverse's new vertices in a uniform
        stream (format 1.9, §6.8)."""
        return bool(self.flags & UNIFORM_RANKS)

    def payload(self, data: bytes | memoryview | RangeReader, entry: Section) -> memoryview:
        """The bytes of a section, after checking its CRC-32 (§5 step 9); ``data`` is the whole
        file, or a reader of the file's byte ranges (:class:`.disk.FileRanges`) that reads just
        this section from disk."""
        start = entry.file_offset(self.data_start)
        if isinstance(data, (bytes, memoryview)):
            view = memoryview(data)[start : start + entry.length]
        else:
            view = memoryview(data.read(start, entry.length))
        if zlib.crc32(view) != entry.crc32:
            raise ChecksumError(
                "the section's CRC-32 does not match its bytes (the file is damaged)",
                rule="R19-section-crc",
                field=f"section {entry.id}",
                offset=start,
            )
        return view


# ------------------------------------------------------------------------------------------
# writing


def pack_container(
    header: Mapping[str, Any],
    sections: list[tuple[dict[str, Any], bytes]],
    *,
    flags: int = 0,
    minor: int = FORMAT_MINOR,
    coding_tools: bool | None = None,
    adaptive: bool | None = None,
) -> bytes:
    """Assemble a file from its header map and its sections.

    Args:
        header: every header field except ``sections``, which is built here.
        sections: ``(entry, payload)`` pairs in file order; each entry holds ``id``,
            ``critical``, ``codec`` and the codec's parameters. ``offset``, ``length`` and
            ``crc32`` are filled in from the payload.
        flags: the preamble flags (0 in format 1.0; :data:`SEGMENTED` for a segmented file).
        minor: the format's minor version (0, or 1 for a segmented file); raised to 4 when the
            header has a key of format 1.4 (:data:`SCENE_KEYS`), and to 5 when a section is
            one of format 1.5 (:mod:`.attachments`).
        coding_tools: whether to set flag bit 1 and minor version 2 (§6.8); by default, when a
            section needs it (:func:`.sections.uses_coding_tools`). Only files that break the
            rules on purpose (conformance vectors) say ``False`` for such sections.
        adaptive: whether to set flag bit 3 and minor version 6 (§6.14); by default, when a
            section stores its integers with ``coder`` 1.

    Flag bit 4 and minor version 7 are set when a RESD section stores its chunks with ``coder``
    1 (§6.9), flag bit 5 and minor version 8 when one has ``codebooks``, and flag bit 6 and
    minor version 9 when a faces-traverse FACE has ``ranks`` 1 (§6.8).
    """
    flags, minor = with_coding_tools([entry for entry, _ in sections], flags, minor, coding_tools)
    if any(key in header for key in SCENE_KEYS):
        minor = max(minor, SCENE_MINOR)
    if any(attachment_codec(entry.get("id")) is not None for entry, _ in sections):
        minor = max(minor, ATTACHMENTS_MINOR)
    if adaptive is None:
        adaptive = uses_adaptive([entry for entry, _ in sections])
    if adaptive:
        flags, minor = flags | ADAPTIVE, max(minor, ADAPTIVE_MINOR)
    if any(entry.get("codec") == RESIDUAL and entry.get("coder") == 1 for entry, _ in sections):
        flags, minor = flags | ADAPTIVE_CORRECTIONS, max(minor, ADAPTIVE_CORRECTIONS_MINOR)
    if any(entry.get("codec") == RESIDUAL and "codebooks" in entry for entry, _ in sections):
        flags, minor = flags | CODEBOOKS, max(minor, CODEBOOKS_MINOR)
    if any(entry.get("codec") == FACES_TRAVERSE and "ranks" in entry for entry, _ in sections):
        flags, minor = flags | UNIFORM_RANKS, max(minor, UNIFORM_RANKS_MINOR)
    table = []
    offset = 0
    for entry, payload in sections:
        table.append(
            {**entry, "offset": offset, "length": len(payload), "crc32": zlib.crc32(payload)}
        )
        offset += len(payload)
    header_bytes = msgpack.packb({**header, "sections": table}, use_bin_type=True)
    body = b"".join(payload for _, payload in sections)
    return pack_raw(FORMAT_MAJOR, minor, flags, header_bytes, body)


def pack_raw(
    major: int,
    minor: int,
    flags: int,
    header_bytes: bytes,
    body: bytes,
    *,
    total: int | None = None,
) -> bytes:
    """A file from its raw parts, with both CRCs right and nothing else checked (§2's layout).

    :func:`pack_container` builds valid files with it; tests and the vector writer build files
    that break one rule (``total`` defaults to the true length).
    """
    if total is None:
        total = HEAD_SIZE + len(header_bytes) + CRC.size + len(body)
    head = SIGNATURE + PREAMBLE.pack(major, minor, flags, len(header_bytes), total)
    return b"".join(
        [head, CRC.pack(zlib.crc32(head)), header_bytes, CRC.pack(zlib.crc32(header_bytes)), body]
    )


# ------------------------------------------------------------------------------------------
# reading


def read_preamble(data: bytes | memoryview, limits: Limits = DEFAULT_LIMITS) -> Preamble:
    """Check the signature and preamble (§5 steps 1-4). Needs only the first 32 bytes."""
    if len(data) >= len(SIGNATURE) and bytes(data[: len(SIGNATURE)]) != SIGNATURE:
        _refuse_signature(bytes(data[: len(SIGNATURE)]))
    if len(data) < HEAD_SIZE:
        part = "signature" if len(data) < len(SIGNATURE) else "preamble"
        raise TruncatedFileError(
            f"the file is {len(data)} bytes, shorter than the {HEAD_SIZE}-byte signature and "
            "preamble",
            rule="R03-preamble-truncated",
            field=part,
            offset=0 if part == "signature" else len(data),
        )
    (stored_crc,) = CRC.unpack_from(data, PREAMBLE_END)
    if zlib.crc32(data[:PREAMBLE_END]) != stored_crc:
        raise ChecksumError(
            "the preamble's CRC-32 does not match (the file is damaged)",
            rule="R04-preamble-crc",
            field="preamble",
            offset=PREAMBLE_END,
        )
    preamble = Preamble(*PREAMBLE.unpack_from(data, len(SIGNATURE)))
    if preamble.major != FORMAT_MAJOR:
        raise UnsupportedVersionError(
            f"format version {preamble.major}.{preamble.minor} is not supported: this decoder "
            f"reads major version {FORMAT_MAJOR}",
            rule="R05-major-version",
            field="preamble.major",
            offset=8,
        )
    unknown = preamble.flags & CRITICAL_FLAGS_MASK & ~KNOWN_CRITICAL_FLAGS
    if unknown:
        raise UnsupportedVersionError(
            f"critical flag bits {unknown:#06x} are set, which this decoder does not know",
            rule="R06-critical-flag",
            field="preamble.flags",
            offset=12,
        )
    if preamble.header_length > limits.max_header_bytes:
        raise LimitError(
            f"a header of {preamble.header_length} bytes exceeds this decoder's limit "
            f"max_header_bytes = {limits.max_header_bytes}",
            rule="R07-header-limit",
            field="preamble.header_length",
            offset=16,
        )
    if preamble.total_length < preamble.data_start:
        raise FormatError(
            f"total_length {preamble.total_length} is smaller than the preamble and header it "
            f"must hold ({preamble.data_start} bytes)",
            rule="R08-total-length",
            field="preamble.total_length",
            offset=20,
        )
    return preamble


def _refuse_signature(found: bytes) -> None:
    """Say what kind of damage a wrong signature suggests (the PNG signature's design)."""
    if found[1:4] != SIGNATURE[1:4]:
        raise FormatError(
            f"not a tuckercodec file (signature {found.hex(' ')})",
            rule="R01-signature",
            field="signature",
            offset=0,
        )
    if found[0] != SIGNATURE[0]:
        damage = "high-bit byte was changed: the file went through a 7-bit channel"
    else:
        damage = "line-ending bytes were changed: the file was transferred in text mode"
    raise FormatError(
        f"the signature's {damage}", rule="R02-signature-transfer", field="signature", offset=0
    )


def check_not_longer(size: int, total_length: int) -> None:
    """§5 step 5: a file of ``size`` bytes must not run past its ``total_length``."""
    if size > total_length:
        raise FormatError(
            f"{size - total_length} bytes follow the end of the file that total_length "
            f"declares ({total_length} bytes)",
            rule="R09-trailing-bytes",
            field="preamble.total_length",
            offset=total_length,
        )


def check_reaches(size: int, needed: int, what: str, field: str) -> None:
    """§5 step 6: a file of ``size`` bytes must reach byte ``needed``, the end of ``what``."""
    if size < needed:
        raise TruncatedFileError(
            f"the file ends at byte {size}, inside {what} that ends at byte {needed}: it was "
            "cut short",
            rule="R10-file-truncated",
            field=field,
            offset=size,
        )


def parse_container(
    data: bytes | memoryview,
    limits: Limits = DEFAULT_LIMITS,
    *,
    whole: bool = True,
    size: int | None = None,
) -> Container:
    """Parse and check everything but the section payloads (§5 steps 1-8).

    Args:
        data: the file, or with ``whole=False`` at least its first ``32 + header_length + 4``
            bytes (enough for :func:`tuckercodec.info` without reading the sections).
        limits: the decoder's limits.
        whole: ``data`` is the whole file, so its length must equal ``total_length``.
        size: the size of the file on disk when ``data`` holds only its head: the whole-file
            checks (§5 steps 5 and 6) then use it, in their place in the order.
    """
    preamble = read_preamble(data, limits)
    if size is not None:
        check_not_longer(size, preamble.total_length)
    elif whole:
        check_not_longer(len(data), preamble.total_length)
    check_reaches(len(data), preamble.data_start, "the header", "header")
    header_bytes = data[HEAD_SIZE : preamble.header_end]
    (stored_crc,) = CRC.unpack_from(data, preamble.header_end)
    if zlib.crc32(header_bytes) != stored_crc:
        raise ChecksumError(
            "the header's CRC-32 does not match (the file is damaged)",
            rule="R11-header-crc",
            field="header",
            offset=HEAD_SIZE,
        )
    if size is not None:
        check_reaches(size, preamble.total_length, "the data area", "preamble.total_length")
    elif whole:
        check_reaches(len(data), preamble.total_length, "the data area", "preamble.total_length")
    header = _unpack_header(bytes(header_bytes))
    sections = read_section_table(header, preamble.total_length - preamble.data_start, limits)
    return Container(
        preamble.major,
        preamble.minor,
        preamble.flags,
        header,
        sections,
        preamble.data_start,
        preamble.total_length,
    )


class _HeaderProblem(Exception):
    """Why the header bytes are not one valid msgpack map; reported as R12 by
    :func:`_unpack_header`."""


def _reject_ext(code: int, data: bytes) -> None:
    raise _HeaderProblem(f"msgpack extension type {code} is not allowed in the header")


def _strict_map(pairs: list[tuple[Any, Any]]) -> dict[str, Any]:
    """A map whose keys are all str and all different: otherwise two decoders taking the first
    or the last of a repeated key would read different files."""
    out: dict[str, Any] = {}
    for key, value in pairs:
        if not isinstance(key, str):
            raise _HeaderProblem(f"map keys must be strings, got {key!r}")
        if key in out:
            raise _HeaderProblem(f"the key {key!r} appears twice in one map")
        out[key] = value
    return out


def _reject_timestamps(header: dict[str, Any]) -> None:
    """msgpack decodes its timestamp extension (type -1) itself, past the ext hook. The walk
    keeps its own stack: msgpack nests up to 1024 deep, beyond Python's recursion limit."""
    pending: list[Any] = [header]
    while pending:
        value = pending.pop()
        if isinstance(value, msgpack.Timestamp):
            raise _HeaderProblem(
                "msgpack extension type -1 (timestamp) is not allowed in the header"
            )
        if isinstance(value, dict):
            pending.extend(value.values())
        elif isinstance(value, list):
            pending.extend(value)


def _unpack_header(header_bytes: bytes) -> dict[str, Any]:
    """The header map (§4): one msgpack map with string keys, each once, no extension types
    (R12-header-not-map)."""
    try:
        header = _unpack_map(header_bytes)
    except _HeaderProblem as problem:
        raise FormatError(str(problem), rule="R12-header-not-map", field="header") from None
    return header


def _unpack_map(header_bytes: bytes) -> dict[str, Any]:
    try:
        header = msgpack.unpackb(
            header_bytes,
            raw=False,
            strict_map_key=True,
            ext_hook=_reject_ext,
            use_list=True,
            object_pairs_hook=_strict_map,
            timestamp=0,
        )
    except _HeaderProblem:
        raise
    except msgpack.StackError:
        raise _HeaderProblem("the header nests deeper than msgpack's 1024 levels") from None
    except (ValueError, TypeError, msgpack.UnpackException, RecursionError) as error:
        # ExtraData, FormatError and invalid UTF-8 all derive from ValueError
        reason = str(error) or type(error).__name__
        raise _HeaderProblem(f"the header is not one valid msgpack map ({reason})") from None
    if not isinstance(header, dict):
        raise _HeaderProblem(f"the header is a msgpack {type(header).__name__}, not a map")
    _reject_timestamps(header)
    return header
