"""The container: the signature and preamble (spec/FORMAT.md §2), the section table (§3), steps
1-9 of the validation order (§5); tuckercodec/format/container.py.

A preamble that names another major version or a critical flag, lengths that lie, bytes after
the end, and section tables that overlap, leave a gap, point outside the file, repeat an id or
hold fields of the wrong type or size are each refused with the error class of §11, at once and
never with any other exception. What a decoder may ignore does not stop a decode: ``minor`` and
the flag bits 16-31. A file read from a path is read no further than its preamble declares.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import tuckercodec
from tests.support.compressed import (
    HOSTILE,
    MISSING,
    VALID,
    Parts,
    expect_error,
    outcome,
    raw_file,
    table_file,
    vector,
    with_preamble,
)
from tests.support.properties import HYPOTHESIS_SETTINGS, msgpack_leaves
from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import (
    ChecksumError,
    FormatError,
    LimitError,
    TruncatedFileError,
    UnsupportedVersionError,
)

# ------------------------------------------------------------------------------------------
# the preamble: versions, flags, lengths, trailing bytes


@pytest.mark.parametrize("major", [0, 2, 3, 0x7FFF, 0xFFFF])
def test_unknown_major_version(major):
    error = expect_error(
        with_preamble(vector("v1-wave-triangles"), major=major), UnsupportedVersionError, exact=True
    )
    assert error.rule == "R05-major-version"


@pytest.mark.parametrize("minor", [1, 7, 0xFFFF])
def test_any_minor_version_is_read(minor):
    error, sequence = outcome(with_preamble(vector("v1-wave-triangles"), minor=minor))
    assert error is None and sequence is not None


@pytest.mark.parametrize("flags", [128, 0x8000, 0xFFFF, 0xFFFFFFFF, 0x00010080])
def test_critical_flag_bits_are_refused(flags):
    error = expect_error(
        with_preamble(vector("v1-wave-triangles"), flags=flags), UnsupportedVersionError, exact=True
    )
    assert error.rule == "R06-critical-flag"


def test_the_corrections_flag_needs_a_resd_section():
    """Bit 2 is known since format 1.3 (§6.9): a file of 1.0 that sets it lacks RESD."""
    error = expect_error(
        with_preamble(vector("v1-wave-triangles"), flags=4), FormatError, exact=True
    )
    assert error.rule == "R26-required-section-missing"


def test_the_segmented_flag_needs_a_segment_index():
    """Bit 0 is known since format 1.1 (§6.7): a file of 1.0 that sets it lacks the index."""
    error = expect_error(
        with_preamble(vector("v1-wave-triangles"), flags=1), FormatError, exact=True
    )
    assert error.rule == "R37-segment-index"


@pytest.mark.parametrize("flags", [0x10000, 0x80000000, 0xFFFF0000])
def test_ignorable_flag_bits_are_ignored(flags):
    error, sequence = outcome(with_preamble(vector("v1-wave-triangles"), flags=flags))
    assert error is None and sequence is not None


@pytest.mark.parametrize(
    ("change", "kind", "rule"),
    [
        # the header CRC is now read from inside the header
        ({"header_length": 0}, ChecksumError, "R11-header-crc"),
        ({"header_length": 0xFFFFFFFF}, LimitError, "R07-header-limit"),
        ({"header_length": (16 << 20) + 1}, LimitError, "R07-header-limit"),
        # within the limit, beyond total_length
        ({"header_length": 16 << 20}, FormatError, "R08-total-length"),
        ({"total": 0}, FormatError, "R08-total-length"),
        ({"total": 35}, FormatError, "R08-total-length"),
        ({"total": 2**64 - 1}, TruncatedFileError, "R10-file-truncated"),
        ({"total": 2**63}, TruncatedFileError, "R10-file-truncated"),
        ({"total": 10**12}, TruncatedFileError, "R10-file-truncated"),
    ],
)
def test_lying_preamble_lengths(change, kind, rule):
    data = with_preamble(vector("v1-wave-triangles"), **change)
    error = expect_error(data, kind)
    assert type(error) is kind
    assert error.rule == rule


@pytest.mark.parametrize("extra", [b"\x00", b"\x00" * 4, b"TKC!", bytes(1000)])
def test_trailing_bytes(extra, tmp_path):
    data = vector("v1-wave-triangles")
    error = expect_error(data + extra, FormatError, exact=True)
    assert error.rule == "R09-trailing-bytes"
    path = tmp_path / "long.tkc"
    path.write_bytes(data + extra)
    for read in (tuckercodec.info, tuckercodec.Decoder, tuckercodec.decode):
        with pytest.raises(FormatError) as raised:
            read(path)
        assert raised.value.rule == "R09-trailing-bytes"
        assert raised.value.path == str(path)


def test_a_file_twice_over_is_trailing_bytes():
    data = vector("v1-wave-triangles")
    error = expect_error(data + data, FormatError, exact=True)
    assert error.rule == "R09-trailing-bytes"


# ------------------------------------------------------------------------------------------
# reading a path: no more than the preamble declares


def test_opening_a_huge_foreign_file_reads_only_its_first_bytes(tmp_path):
    # A sparse 4 GiB file: refused from its first 32 bytes, never loaded.
    huge = tmp_path / "huge.tkc"
    with open(huge, "wb") as handle:
        handle.truncate(4 << 30)
    with pytest.raises(FormatError, match="signature") as raised:
        tuckercodec.read_compressed(huge)
    assert raised.value.rule == "R01-signature"


def test_a_file_with_trailing_bytes_is_refused_without_reading_them_all(tmp_path):
    data = tuckercodec.encode(tuckercodec.MeshSequence(wave_sequence(6, 4), grid_faces(4)))
    padded = tmp_path / "padded.tkc"
    with open(padded, "wb") as handle:
        handle.write(data)
        handle.truncate(len(data) + (4 << 30))  # 4 GiB of zeros after the file
    with pytest.raises(FormatError, match="follow the end of the file") as raised:
        tuckercodec.read_compressed(padded)
    assert raised.value.rule == "R09-trailing-bytes"


# ------------------------------------------------------------------------------------------
# section tables that overlap, point outside, repeat, have negative or huge lengths


TABLE_FIELDS = ["offset", "length", "crc32"]


@pytest.mark.parametrize("key", TABLE_FIELDS)
@pytest.mark.parametrize("index", [0, 2, 4])
def test_every_table_field_set_to_every_hostile_value(key, index):
    """offset, length and crc32 of an entry (pack_container fills those, so the table is
    written raw here with correct CRCs for the header)."""
    parts = Parts(vector("v1-wave-triangles"))
    for _label, value in [*HOSTILE.items(), ("missing", MISSING)]:
        table = parts.table()
        original = table[index][key]
        if type(value) is type(original) and value == original:
            continue  # offset 0 of the first entry is right
        if value is MISSING:
            del table[index][key]
        else:
            table[index][key] = value
        expect_error(raw_file({**parts.header, "sections": table}, parts.area()))


def _shift(entry: dict[str, Any], by: int) -> None:
    entry["offset"] += by


#: What each edit of v1-wave-triangles' section table breaks: the error class and rule of §11.
TABLE_CASES: dict[
    str, tuple[Callable[[list[dict[str, Any]], Parts], object], type[FormatError], str]
] = {
    "two sections overlap": (
        lambda t, p: _shift(t[1], -10),
        FormatError,
        "R16-section-not-contiguous",
    ),
    "all sections at offset 0": (
        lambda t, p: [e.update(offset=0) for e in t],
        FormatError,
        "R16-section-not-contiguous",
    ),
    "a gap between sections": (
        lambda t, p: _shift(t[1], 1),
        FormatError,
        "R16-section-not-contiguous",
    ),
    "a section past the end": (
        lambda t, p: t[-1].update(length=t[-1]["length"] + 1),
        FormatError,
        "R17-section-past-end",
    ),
    "a section far outside the file": (
        lambda t, p: t[-1].update(length=2**40),
        FormatError,
        "R17-section-past-end",
    ),
    "a huge length": (
        lambda t, p: t[0].update(length=2**64 - 1),
        FormatError,
        "R17-section-past-end",
    ),
    "a 2**63 length": (
        lambda t, p: t[0].update(length=2**63),
        FormatError,
        "R17-section-past-end",
    ),
    "a negative length": (
        lambda t, p: t[0].update(length=-35),
        FormatError,
        "R17-section-past-end",
    ),
    "a most negative offset": (
        lambda t, p: t[0].update(offset=-(2**63)),
        FormatError,
        "R16-section-not-contiguous",
    ),
    "a negative length that brings the table back in step": (
        lambda t, p: (
            t[1].update(length=t[1]["length"] - 10),
            t[2].update(offset=t[2]["offset"] - 10),
        ),
        FormatError,
        "R16-section-not-contiguous",
    ),
    "a repeated id": (
        lambda t, p: t[1].update(id=t[0]["id"]),
        FormatError,
        "R15-section-duplicate-id",
    ),
    "the same entry twice": (
        lambda t, p: t.append(dict(t[-1])),
        FormatError,
        "R15-section-duplicate-id",
    ),
    "a short table": (lambda t, p: t.pop(), FormatError, "R18-section-coverage"),
    "an empty table": (lambda t, p: t.clear(), FormatError, "R18-section-coverage"),
    "a crc32 of 2**32": (
        lambda t, p: t[0].update(crc32=2**32),
        FormatError,
        "R14-section-entry-field",
    ),
    "a negative crc32": (
        lambda t, p: t[0].update(crc32=-1),
        FormatError,
        "R14-section-entry-field",
    ),
    "a wrong crc32": (
        lambda t, p: t[0].update(crc32=(t[0]["crc32"] + 1) % 2**32),
        ChecksumError,
        "R19-section-crc",
    ),
    "an id of 17 characters": (
        lambda t, p: t[0].update(id="FACE" + "x" * 13),
        FormatError,
        "R14-section-entry-field",
    ),
    "an id with a control character": (
        lambda t, p: t[0].update(id="FA\nCE"),
        FormatError,
        "R14-section-entry-field",
    ),
    "a non-ASCII id": (
        lambda t, p: t[0].update(id="FACÉ"),
        FormatError,
        "R14-section-entry-field",
    ),
    "an entry that is a list": (
        lambda t, p: t.__setitem__(0, list(t[0].items())),  # type: ignore[call-overload]  # refused
        FormatError,
        "R14-section-entry-field",
    ),
}


@pytest.mark.parametrize("case", list(TABLE_CASES))
def test_bad_section_tables(case):
    edit, kind, rule = TABLE_CASES[case]
    error = expect_error(table_file(edit), kind)
    assert type(error) is kind, f"{case}: {error!r}"
    assert error.rule == rule, f"{case}: {error!r}"


def test_more_sections_than_the_limit():
    """max_sections is the decoder's (§7): 65 entries pass the defaults (a segmented file has
    up to four per segment) and fail a decoder that allows 64, before anything is read."""

    def extend(table, parts):
        table.extend(
            {
                **table[-1],
                "id": f"x{n}",
                "critical": False,
                "length": 0,
                "offset": sum(e["length"] for e in table),
            }
            for n in range(60)
        )

    data = table_file(extend)
    assert tuckercodec.decode(data).frame_count > 0
    with pytest.raises(LimitError) as raised:
        tuckercodec.decode(data, limits=tuckercodec.Limits(max_sections=64))
    assert raised.value.rule == "R21-header-limit"


@settings(max_examples=200, **HYPOTHESIS_SETTINGS)
@given(
    table=st.lists(
        st.fixed_dictionaries(
            {
                "id": st.sampled_from(["FACE", "U1", "U3", "CORE", "CENT", "NAME", "junk"])
                | st.text(max_size=18),
                "offset": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2000),
                "length": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2000),
                "crc32": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2**32 - 1),
                "critical": st.booleans() | msgpack_leaves,
                "codec": st.sampled_from(["qmat", "faces-delta", "msgpack-zstd"]) | msgpack_leaves,
            }
        ),
        max_size=8,
    ),
    name=st.sampled_from(VALID),
)
def test_arbitrary_section_tables(table, name):
    """Any table over a vector's data area, the header CRC correct: always FormatError (a valid
    table would need the five required sections, each with the CRC of its exact payload)."""
    parts = Parts(vector(name))
    error, _ = outcome(raw_file({**parts.header, "sections": table}, parts.area()))
    assert error is not None
