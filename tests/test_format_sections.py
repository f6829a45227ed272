"""The sections of version 1.0 (spec/FORMAT.md §6.6) and their codecs' parameters (§6.1-§6.5):
steps 11-17 of the validation order (§5); tuckercodec/format/sections.py.

Every entry field and codec parameter of every section set to every hostile value, required
sections missing, known sections with another codec or criticality, unknown sections, and
payloads whose decompressed content is changed and re-signed so that the checks behind zstd are
reached. A change fails with a FormatError unless the spec allows it: a parameter the codec does
not use, a value equal to the original, an unknown ancillary section (skipped unread).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import zstandard
from hypothesis import given, settings
from hypothesis import strategies as st

import tuckercodec
from tests.support.compressed import (
    HOSTILE,
    MISSING,
    VALID,
    Parts,
    accept_either,
    check_decoded,
    expect_error,
    outcome,
    table_file,
    vector,
)
from tests.support.properties import HYPOTHESIS_SETTINGS, msgpack_values
from tuckercodec import FormatError, UnsupportedVersionError
from tuckercodec.format.sections import KNOWN_SECTIONS

SECTION_PARAMS = ["shape", "planes", "steps", "predict", "critical", "codec", "id"]


@pytest.mark.parametrize("section", ["FACE", "U1", "U3", "CORE", "CENT", "NAME"])
@pytest.mark.parametrize("key", [*SECTION_PARAMS, "size"])
def test_every_section_parameter_set_to_every_hostile_value(section, key):
    """Entry fields and codec parameters of every section, in the file that has them. They
    must all fail, except: a parameter the codec does not use (ignored, §3), a value equal to
    the original, and NAME renamed to a valid unknown id (then an ignored ancillary section)."""
    name = "v1-polygons-names" if section == "NAME" else "v1-wave-triangles"
    for label, value in [*HOSTILE.items(), ("missing", MISSING)]:
        parts = Parts(vector(name))
        entry, _ = parts.sections[parts.index(section)]
        original = entry.get(key, MISSING)
        if value is MISSING:
            entry.pop(key, None)
        else:
            entry[key] = value
        error, sequence = outcome(parts.pack())
        unused = original is MISSING
        same = type(value) is type(original) and value == original
        renamed = section == "NAME" and key == "id" and label == "str"
        if unused or same or renamed:
            assert error is None, f"{section}.{key} = {label}: {error}"
            if renamed:
                assert sequence is not None
                assert sequence.frame_names[0] == "frame_00000"  # NAME gone: the default names
        else:
            assert error is not None, f"{section}.{key} = {label} was accepted"


def test_an_unknown_ancillary_section_is_skipped_whatever_it_holds():
    parts = Parts(vector("v1-wave-triangles"))
    parts.sections.insert(
        2, ({"id": "junk", "critical": False, "codec": "??", "shape": -1}, bytes(range(256)) * 4)
    )
    data = parts.pack()
    error, sequence = outcome(data)
    assert error is None and sequence is not None
    np.testing.assert_array_equal(
        sequence.vertices, tuckercodec.decode(vector("v1-wave-triangles")).vertices
    )


@pytest.mark.parametrize("section", ["FACE", "U1", "U3", "CORE", "CENT"])
def test_a_required_section_missing(section):
    parts = Parts(vector("v1-wave-triangles"))
    del parts.sections[parts.index(section)]
    error = expect_error(parts.pack(), FormatError, exact=True)
    assert error.rule == "R26-required-section-missing"


def test_a_critical_name_section_is_refused():
    parts = Parts(vector("v1-polygons-names"))
    parts.sections[parts.index("NAME")][0]["critical"] = True
    error = expect_error(parts.pack(), FormatError, exact=True)
    assert error.rule == "R27-criticality"


#: Section-table entries that name sections the decoder does not know, or known sections with
#: another codec or criticality than §6.6 gives them: the error class and rule of §11.
SECTION_ENTRY_CASES: dict[
    str, tuple[Callable[[list[dict[str, Any]], Parts], object], type[FormatError], str]
] = {
    "an unknown critical section": (
        lambda t, p: t.append(
            {**t[-1], "id": "XTRA", "offset": t[-1]["offset"] + t[-1]["length"], "length": 0}
        ),
        UnsupportedVersionError,
        "R24-unknown-critical-section",
    ),
    "a known section with another codec": (
        lambda t, p: t[1].update(codec="qmat2"),
        UnsupportedVersionError,
        "R25-unknown-codec",
    ),
    "a required section marked ancillary": (
        lambda t, p: t[0].update(critical=False),
        FormatError,
        "R27-criticality",
    ),
}


@pytest.mark.parametrize("case", list(SECTION_ENTRY_CASES))
def test_bad_section_entries(case):
    edit, kind, rule = SECTION_ENTRY_CASES[case]
    error = expect_error(table_file(edit), kind)
    assert type(error) is kind, f"{case}: {error!r}"
    assert error.rule == rule, f"{case}: {error!r}"


# ------------------------------------------------------------------------------------------
# hypothesis: parameters and payloads changed, re-signed so that the semantic checks are reached


@settings(max_examples=300, **HYPOTHESIS_SETTINGS)
@given(name=st.sampled_from(VALID), data=st.data())
def test_one_section_parameter_arbitrary(name, data):
    """One parameter of one section replaced (or added) by anything msgpack can hold."""
    parts = Parts(vector(name))
    index = data.draw(st.integers(0, len(parts.sections) - 1))
    entry, _ = parts.sections[index]
    key = data.draw(
        st.sampled_from(
            ["shape", "planes", "steps", "predict", "size", "critical", "codec", "id", "x"]
        )
    )
    entry[key] = data.draw(
        msgpack_values | st.sampled_from([[0, 0], [2**63, 1], [1, 2**63], [-1, 3], [2**32, 2**32]])
    )
    accept_either(parts.pack())


def _recompressed(parts: Parts, index: int, raw: bytes) -> None:
    entry, _ = parts.sections[index]
    parts.sections[index] = (
        entry,
        zstandard.ZstdCompressor(level=1, write_content_size=True).compress(raw),
    )


@settings(max_examples=300, **HYPOTHESIS_SETTINGS)
@given(name=st.sampled_from(VALID), data=st.data())
def test_payloads_changed_and_resigned(name, data):
    """A section's decompressed content changed (bytes set to anything, typically huge or
    negative integers, out-of-range face indices, misplaced padding), recompressed with the
    right content size and CRC: the checks behind zstd are reached. FormatError or a consistent
    decode; a face index is never out of range in a decoded mesh."""
    parts = Parts(vector(name))
    choices = [n for n, (entry, _) in enumerate(parts.sections) if entry["id"] in KNOWN_SECTIONS]
    index = data.draw(st.sampled_from(choices))
    raw = bytearray(zstandard.ZstdDecompressor().decompress(parts.sections[index][1]))
    if raw:
        for _ in range(data.draw(st.integers(1, 4))):
            position = data.draw(st.integers(0, len(raw) - 1))
            raw[position] = data.draw(
                st.sampled_from([0, 1, 0x7F, 0x80, 0xFE, 0xFF]) | st.integers(0, 255)
            )
    _recompressed(parts, index, bytes(raw))
    data_bytes = parts.pack()
    _, sequence = outcome(data_bytes)
    if sequence is not None:
        check_decoded(data_bytes, sequence)
        assert sequence.faces.max(initial=-1) < sequence.vertex_count
