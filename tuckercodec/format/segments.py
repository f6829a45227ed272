"""§6.7 Segmented files (format 1.1): the segment index and the sections of each segment.

A file whose preamble sets flag bit 0 (:data:`SEGMENTED`) splits its frames into segments. Each
segment is a Tucker decomposition of its own frames, with its own U3, CORE, CENT and U2, and
either its own U1 (``basis = "own"``, section ``U1.s``) or the leading ``i`` columns of one U1
that every such segment shares (``basis = "shared"``, section ``U1``). The header's ``segments``
array is the index: a decoder finds frame t's segment from it and reads only that segment's
sections (and the shared ones) from disk.

This module checks the index (R37-segment-index, R38-segment-ranks) and the sections it implies
(§5 steps 11-13 of a segmented file), and names the sections of segment s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NoReturn

from ..errors import FormatError
from .limits import Limits, check_limit
from .residual import SECTION_STEM
from .sections import (
    Section,
    check_face_shape,
    check_known_sections,
    check_stream_size,
    known_kinds,
    require_sections,
    section_shape,
)

#: Preamble flag bit 0 (critical): the file is segmented (§6.7). Decoders of 1.0 refuse it.
SEGMENTED = 0x0001
#: The format minor version that defines segmented files.
SEGMENTED_MINOR = 1
#: The two kinds of basis a segment can use.
BASIS_SHARED, BASIS_OWN = "shared", "own"
#: The sections a segmented file shares between its segments (U1 only with a shared basis).
SHARED_SECTIONS = ("FACE", "U1", "NAME")
#: The per-segment sections, by stem; ``U1`` only for a segment with its own basis.
SEGMENT_STEMS = ("U1", "U3", "CORE", "CENT")
#: The order the reference encoder writes the sections of one segment.
SEGMENT_WRITE_ORDER = ("CENT", "U3", "CORE", "U1")


@dataclass(frozen=True)
class SegmentEntry:
    """One entry of the segment index: frames ``start .. start + frames - 1`` of the file."""

    index: int
    start: int
    frames: int
    ranks: tuple[int, int]
    u2: tuple[float, ...]  # 9 values, row-major
    basis: str  # BASIS_SHARED or BASIS_OWN

    @property
    def stop(self) -> int:
        """One past the segment's last frame."""
        return self.start + self.frames

    def section_id(self, stem: str) -> str:
        """The id of this segment's section ``stem`` ("U3" -> "U3.4")."""
        return segment_section_id(stem, self.index)

    def u1_section_id(self) -> str:
        """The section holding this segment's U1: its own, or the shared ``U1``."""
        return self.section_id("U1") if self.basis == BASIS_OWN else "U1"

    def factor_values(self, vertices: int, shared_columns: int) -> int:
        """The numbers decoded before any frame of this segment: the U1 it uses (all of the
        shared one), its U3, core and centroids (the ``max_factor_values`` limit, §7)."""
        i, k = self.ranks
        u1_columns = i if self.basis == BASIS_OWN else shared_columns
        return vertices * u1_columns + self.frames * k + 3 * i * k + 3 * self.frames


def segment_section_id(stem: str, index: int) -> str:
    """``stem.index``, the id of a per-segment section (§6.7)."""
    return f"{stem}.{index}"


def segment_map(frames: int, ranks: tuple[int, int], u2: list[float], basis: str) -> dict[str, Any]:
    """One entry of the header's ``segments`` array, as the encoder writes it."""
    return {
        "frames": frames,
        "ranks": [ranks[0], ranks[1]],
        "u2": [float(x) for x in u2],  # msgpack floats, never ints (§4)
        "basis": basis,
    }


def is_int(value: object) -> bool:
    """An integer as msgpack gives it, not a bool (which Python counts as an int)."""
    return isinstance(value, int) and not isinstance(value, bool)


def ranks_within(ranks: object, largest_i: int, largest_k: int) -> tuple[int, int] | None:
    """``(i, k)`` if ``ranks`` is [i, k], two integers with 1 <= i <= largest_i and
    1 <= k <= largest_k, else None: the shape of a header's ranks and of a segment's, whose
    bounds and rules (R22-ranks, R38-segment-ranks) differ."""
    if (
        isinstance(ranks, list)
        and len(ranks) == 2
        and all(is_int(r) for r in ranks)
        and 1 <= ranks[0] <= largest_i
        and 1 <= ranks[1] <= largest_k
    ):
        return ranks[0], ranks[1]
    return None


def read_segment_index(
    header: Mapping[str, Any], vertices: int, frames: int, limits: Limits
) -> tuple[SegmentEntry, ...]:
    """The segment index (§6.7): an array of 1..max_segments maps whose ``frames`` add up to
    F (R37-segment-index); each segment's ranks in range for its frames (R38-segment-ranks) and
    its ``u2`` nine finite floats (R23-u2). Shared-basis ranks are checked against the shared
    U1 later, by :func:`check_segmented_sections`."""
    index = header.get("segments")
    if not isinstance(index, list) or not index:
        raise FormatError(
            f"a segmented file needs a non-empty array of segments, got {_short(index)}",
            rule="R37-segment-index",
            field="header.segments",
        )
    check_limit(
        len(index), limits, "max_segments", what=f"{len(index)} segments", field="header.segments"
    )
    entries = []
    start = 0
    for number, item in enumerate(index):
        where = f"header.segments[{number}]"
        if not isinstance(item, dict):
            raise FormatError(
                f"a segment is a map, got {_short(item)}", rule="R37-segment-index", field=where
            )
        count: Any = item.get("frames")
        if not (is_int(count) and count >= 1):
            raise FormatError(
                f"frames must be an integer >= 1, got {_short(count)}",
                rule="R37-segment-index",
                field=f"{where}.frames",
            )
        if start + count > frames:
            raise FormatError(
                f"segment {number} ends at frame {start + count - 1}, past the file's last frame "
                f"{frames - 1}",
                rule="R37-segment-index",
                field=f"{where}.frames",
            )
        basis = item.get("basis")
        if basis not in (BASIS_SHARED, BASIS_OWN):
            raise FormatError(
                f"basis must be {BASIS_SHARED!r} or {BASIS_OWN!r}, got {_short(basis)}",
                rule="R37-segment-index",
                field=f"{where}.basis",
            )
        ranks = _segment_ranks(item.get("ranks"), vertices, count, basis, f"{where}.ranks")
        u2 = checked_u2(item.get("u2"), f"{where}.u2")
        entries.append(SegmentEntry(number, start, count, ranks, u2, basis))
        start += count
    if start != frames:
        raise FormatError(
            f"the segments hold {start} frames, the header declares {frames}",
            rule="R37-segment-index",
            field="header.segments",
        )
    return tuple(entries)


def _segment_ranks(
    ranks: object, vertices: int, frames: int, basis: str, field: str
) -> tuple[int, int]:
    """[i, k] with 1 <= k <= min(F_s, 3K), and 1 <= i <= min(K, 3F_s) for an own basis; a
    shared-basis segment may use any of the shared U1's columns, checked against them later
    (R38-segment-ranks)."""
    largest_i = min(vertices, 3 * frames) if basis == BASIS_OWN else vertices
    largest_k = min(frames, 3 * vertices)
    checked = ranks_within(ranks, largest_i, largest_k)
    if checked is None:
        _refuse_ranks(
            f"must be [i, k], two integers with 1 <= i <= {largest_i} and 1 <= k <= "
            f"min(F, 3K) = {largest_k} for the segment's {frames} frames and {basis} basis: got "
            f"{_short(ranks)}",
            field,
        )
    return checked


def _refuse_ranks(message: str, field: str) -> NoReturn:
    raise FormatError(message, rule="R38-segment-ranks", field=field)


def checked_u2(value: object, field: str) -> tuple[float, ...]:
    """U2 as the header (§4) or a segment (§6.7) holds it: 9 finite floats (R23-u2)."""
    if not (
        isinstance(value, list)
        and len(value) == 9
        and all(isinstance(x, float) and math.isfinite(x) for x in value)
    ):
        raise FormatError("must be 9 finite floats (U2, row-major)", rule="R23-u2", field=field)
    return tuple(value)


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def known_segment_kinds(
    segments: tuple[SegmentEntry, ...], corrections: bool = False
) -> dict[str, tuple[str, int | None]]:
    """Every section id a segmented file may hold -> (its kind in §6.6's table, its segment);
    the shared sections have segment ``None``. With ``corrections`` (flag bit 2), each
    segment's ``RESD.s`` too."""
    known: dict[str, tuple[str, int | None]] = {stem: (stem, None) for stem in SHARED_SECTIONS}
    stems = SEGMENT_STEMS + ((SECTION_STEM,) if corrections else ())
    for segment in segments:
        for stem in stems:
            if stem == "U1" and segment.basis != BASIS_OWN:
                continue
            known[segment.section_id(stem)] = (stem, segment.index)
    return known


def check_segmented_sections(
    table: tuple[Section, ...],
    vertices: int,
    segments: tuple[SegmentEntry, ...],
    limits: Limits,
    *,
    coding_tools: bool = False,
    corrections: bool = False,
) -> int:
    """§5 steps 11s-13s for a segmented file; returns the shared U1's column count (0 if none).

    Known ids are FACE, NAME, U1 (the shared basis) and each segment's ``U3.s``, ``CORE.s``,
    ``CENT.s`` and, for a segment with its own basis, ``U1.s``; any other critical id is
    unknown (R24), including ``U3``, ``CORE`` and ``CENT`` without a segment number.
    """
    known = known_kinds(corrections)
    kinds = {
        section_id: known[stem]
        for section_id, (stem, _) in known_segment_kinds(segments, corrections).items()
    }
    present = check_known_sections(table, kinds, coding_tools=coding_tools)
    shared_needed = any(segment.basis == BASIS_SHARED for segment in segments)
    required = ["FACE"] + (["U1"] if shared_needed else [])
    for segment in segments:
        stems = SEGMENT_STEMS if segment.basis == BASIS_OWN else SEGMENT_STEMS[1:]
        required += [segment.section_id(stem) for stem in stems]
        if corrections:
            required.append(segment.section_id(SECTION_STEM))
    require_sections(present, required)

    check_face_shape(present["FACE"].params, limits)
    shared_columns = 0
    if "U1" in present:
        # at most K columns; not bounded by 3F: a shared basis may come from more frames than
        # the file's own (a zarr chunk encoded with a basis fitted on the whole array)
        largest = vertices
        rows, shared_columns = section_shape(
            present["U1"].params, "section U1", min_cols=1, max_cols=largest, rows_of=vertices
        )
        check_stream_size(rows, shared_columns, limits, "section U1")
    for segment in segments:
        i, k = segment.ranks
        if segment.basis == BASIS_SHARED and i > shared_columns:
            _refuse_ranks(
                f"the segment uses {i} columns of a shared basis of {shared_columns}",
                f"header.segments[{segment.index}].ranks",
            )
        expected = {
            "U3": (segment.frames, k),
            "CORE": (i * 3 * k, 1),
            "CENT": (segment.frames, 3),
        }
        if segment.basis == BASIS_OWN:
            expected["U1"] = (vertices, i)
        for stem, shape in expected.items():
            where = f"section {segment.section_id(stem)}"
            rows, cols = section_shape(
                present[segment.section_id(stem)].params, where, expected=shape
            )
            check_stream_size(rows, cols, limits, where)
        values = segment.factor_values(vertices, shared_columns)
        check_limit(
            values,
            limits,
            "max_factor_values",
            what=f"segment {segment.index}'s {values} factor values",
            field=f"header.segments[{segment.index}].ranks",
        )
        check_limit(
            vertices * segment.frames,
            limits,
            "max_positions",
            what=f"{vertices} vertices x {segment.frames} frames of segment {segment.index}",
            field=f"header.segments[{segment.index}].frames",
        )
    return shared_columns


__all__ = [
    "BASIS_OWN",
    "BASIS_SHARED",
    "SEGMENTED",
    "SEGMENTED_MINOR",
    "SegmentEntry",
    "check_segmented_sections",
    "read_segment_index",
    "segment_map",
    "segment_section_id",
]
