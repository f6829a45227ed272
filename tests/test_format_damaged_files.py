"""Files damaged in transit or on disk, whatever part the damage hits: any truncation, any single
bit flip, any short burst in a payload (spec/FORMAT.md §2, §3, §5).

Every proper prefix of a valid file, the empty file included, is a TruncatedFileError. Every
byte of a file is covered by the signature check or by a CRC-32 (the preamble's, the header's, or
the section's), so a flip is a FormatError in the signature and a ChecksumError anywhere else,
with one exception: the payload of an *unknown ancillary* section, which a decoder skips unread
without checking its CRC (§3, §6.6). A flip there decodes, to the very same mesh.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tuckercodec
from tests.support.compressed import VALID, assert_same_faces, expect_error, vector
from tests.support.properties import HYPOTHESIS_SETTINGS
from tuckercodec import ChecksumError, Decoder, FormatError, TruncatedFileError
from tuckercodec.format.container import HEAD_SIZE, parse_container
from tuckercodec.format.sections import KNOWN_SECTIONS


@pytest.mark.parametrize("name", VALID)
def test_every_truncation_is_a_truncated_file_error(name, tmp_path):
    """Any proper prefix, the empty file included, is TruncatedFileError (§5): from bytes
    (decode and info) and from a path (info reads only the header)."""
    data = vector(name)
    path = tmp_path / "cut.tkc"
    for end in range(len(data)):
        cut = data[:end]
        for read in (tuckercodec.decode, tuckercodec.info):
            with pytest.raises(TruncatedFileError):
                read(cut)
        path.write_bytes(cut)
        with pytest.raises(TruncatedFileError):
            tuckercodec.info(path)


def _regions(data: bytes) -> list[tuple[int, int, str]]:
    """``(start, end, what)`` of every part of a file."""
    container = parse_container(data)
    header_end = HEAD_SIZE + (container.data_start - HEAD_SIZE - 4)
    out = [
        (0, 8, "signature"),
        (8, 28, "preamble"),
        (28, 32, "preamble crc"),
        (32, header_end, "header"),
        (header_end, header_end + 4, "header crc"),
    ]
    for entry in container.sections:
        start = entry.file_offset(container.data_start)
        out.append((start, start + entry.length, f"section {entry.id}"))
    return out


@pytest.mark.parametrize("name", VALID)
def test_every_single_bit_flip_is_caught_or_harmless(name):
    """Flip each bit of each byte. A flip in the signature is FormatError, a flip in anything a
    CRC covers (preamble, header, known sections, and the CRCs themselves) is ChecksumError,
    and only a flip in an unknown ancillary section's payload (skipped unread, §6.6) decodes,
    to the very same mesh."""
    data = vector(name)
    original = Decoder(data)
    reference = original.positions()
    known = set(KNOWN_SECTIONS)
    harmless = 0
    for start, end, what in _regions(data):
        for position in range(start, end):
            for bit in range(8):
                flipped = bytearray(data)
                flipped[position] ^= 1 << bit
                damaged = bytes(flipped)
                if what.startswith("section ") and what.split(" ", 1)[1] not in known:
                    decoder = Decoder(damaged)  # skipped unread: must decode, identically
                    np.testing.assert_array_equal(decoder.positions(), reference)
                    assert_same_faces(decoder.faces, original.faces)
                    assert decoder.frame_names == original.frame_names
                    harmless += 1
                    continue
                with pytest.raises(FormatError) as raised:
                    tuckercodec.decode(damaged)
                if what == "signature":
                    assert type(raised.value) is FormatError, (position, bit)
                else:
                    assert type(raised.value) is ChecksumError, (position, bit, what, raised.value)
    unknown_bytes = sum(
        end - start
        for start, end, what in _regions(data)
        if what.startswith("section ") and what.split(" ", 1)[1] not in known
    )
    assert harmless == 8 * unknown_bytes


@settings(max_examples=150, **HYPOTHESIS_SETTINGS)
@given(name=st.sampled_from(VALID), data=st.data())
def test_a_burst_of_damage_in_a_payload_is_a_checksum_error(name, data):
    """Any burst of up to 32 bits inside one known section's payload is detected by its CRC-32
    (a CRC of degree 32 detects every burst that short), so a damaged payload is never decoded."""
    original = vector(name)
    regions = [
        r
        for r in _regions(original)
        if r[2].startswith("section ") and r[2].split(" ", 1)[1] in KNOWN_SECTIONS
    ]
    start, end, _ = data.draw(st.sampled_from(regions))
    first = data.draw(st.integers(start, end - 1))
    width = data.draw(st.integers(1, min(4, end - first)))
    noise = data.draw(st.binary(min_size=width, max_size=width).filter(lambda b: any(b)))
    damaged = bytearray(original)
    for n in range(width):
        damaged[first + n] ^= noise[n]
    expect_error(bytes(damaged), ChecksumError, exact=True)
