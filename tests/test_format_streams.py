"""Integer streams (spec/FORMAT.md §6.1): zigzag, byte planes, and the zstd frame around them,
checked before its content is used; tuckercodec/format/streams.py."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from tuckercodec import FormatError
from tuckercodec.format import streams


def test_zigzag_and_planes_round_trip():
    values = np.array([0, -1, 1, -2, 2, 2**31 - 1, -(2**31), 12345, -70000], dtype=np.int64)
    unsigned = streams.zigzag(values)
    assert unsigned[:5].tolist() == [0, 1, 2, 3, 4]
    np.testing.assert_array_equal(streams.unzigzag(unsigned), values)
    planes = streams.planes_needed(unsigned)
    assert planes == 4
    raw = streams.to_planes(unsigned, planes)
    # plane-major: the low bytes of all values come first
    assert raw[: len(values)] == bytes(int(u) & 0xFF for u in unsigned)
    np.testing.assert_array_equal(streams.from_planes(raw, len(values), planes), unsigned)
    payload, planes = streams.pack_integers(values)
    np.testing.assert_array_equal(
        streams.unpack_integers(payload, len(values), planes, "test"), values
    )


def test_unpacking_unzigzags_block_by_block_at_every_boundary(monkeypatch):
    # a small block, so that a few values cross every boundary case: none, one, several blocks
    # and a short last one
    monkeypatch.setattr(streams, "_UNZIGZAG_BLOCK", 4)
    rng = np.random.default_rng(5)
    for count in (0, 1, 3, 4, 5, 8, 13):
        values = rng.integers(-(2**31), 2**31, count)
        payload, planes = streams.pack_integers(values)
        out = streams.unpack_integers(payload, count, planes, "test")
        assert out.dtype == np.int64
        np.testing.assert_array_equal(out, values)


def test_integers_beyond_the_format_range_are_refused():
    with pytest.raises(ValueError, match="32-bit"):
        streams.pack_integers(np.array([2**31 + 5]))


def test_zstd_frames_are_checked_before_use():
    payload = streams.compress(b"x" * 100)
    assert streams.decompress_exact(payload, 100, "s") == b"x" * 100
    with pytest.raises(
        FormatError, match="declares 100 bytes, but the section's shape needs 99"
    ) as raised:
        streams.decompress_exact(payload, 99, "s")
    assert raised.value.rule == "R29-zstd-content-size"
    with pytest.raises(FormatError, match="zstd frame header") as raised:
        streams.decompress_exact(b"not zstd at all", 10, "s")
    assert raised.value.rule == "R29-zstd-content-size"
    with pytest.raises(FormatError, match="does not decompress") as raised:
        streams.decompress_exact(payload + payload, 100, "s")  # trailing data
    assert raised.value.rule == "R29-zstd-content-size"
    with pytest.raises(FormatError, match="does not decompress") as raised:
        streams.decompress_exact(payload[:-2], 100, "s")
    assert raised.value.rule == "R29-zstd-content-size"


def test_skippable_zstd_frames_are_not_payloads():
    with pytest.raises(FormatError, match="zstd frame header") as raised:
        streams.decompress_exact(struct.pack("<II", 0x184D2A50, 4) + b"abcd", 0, "s")
    assert raised.value.rule == "R29-zstd-content-size"
