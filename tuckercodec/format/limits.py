"""§7 Decoder limits: what a decoder accepts before it allocates anything.

Limits belong to a decoder, not to the format: a file beyond them can be valid, and a decoder
with higher limits reads it. Every declared size is checked against them (R21-header-limit,
through :func:`check_limit`; the header's own length is R07-header-limit, checked with the
preamble) before memory that depends on it is reserved.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import LimitError


@dataclass(frozen=True)
class Limits:
    """What a decoder accepts before allocating anything (``spec/FORMAT.md`` §7).

    The defaults suit files of up to a few GiB of decoded positions; raise them for larger
    sequences. Every declared size is checked against these before memory is reserved.
    """

    max_header_bytes: int = 16 << 20
    max_vertices: int = 1 << 26
    max_frames: int = 1 << 24
    max_positions: int = 1 << 28  # K * F, the number of decoded vertex positions
    max_faces: int = 1 << 28
    max_face_width: int = 64
    max_sections: int = 1 << 18  # a segmented file has up to 4 per segment (§6.7)
    max_segments: int = 1 << 15
    max_section_bytes: int = 1 << 32  # decompressed size of one section
    # K*i + F*k + 3*i*k + 3*F, the numbers decoded before any frame
    max_factor_values: int = 1 << 27
    # the integers N_c of a RESD chunk of more than one frame (§6.9): a frame costs its chunk
    max_chunk_values: int = 1 << 21


DEFAULT_LIMITS = Limits()


def check_limit(value: int, limits: Limits, limit: str, *, what: str, field: str) -> None:
    """Raise R21-header-limit if ``value`` exceeds the limit named ``limit`` (a field of
    :class:`Limits`). ``what`` says what was counted ("3 sections"), ``field`` where it was
    declared."""
    allowed = getattr(limits, limit)
    if value > allowed:
        raise LimitError(
            f"{what} exceed this decoder's limit {limit} = {allowed}",
            rule="R21-header-limit",
            field=field,
        )
