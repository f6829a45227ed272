"""Hostile files (issue 5, item 1): truncated, bit-flipped, crafted and lying files.

Every case must end in :class:`tuckercodec.FormatError` (or a subclass), within bounded time and
memory, or decode to exactly the right mesh. Never any other exception, never a hang, never a
large allocation driven by a claim the file cannot back.

Where a damaged file may still decode (documented and checked here): a single flipped bit is
harmless only inside the payload of an *unknown ancillary* section, which a decoder skips unread
without checking its CRC (spec/FORMAT.md §3, §6.6). Every other byte of a file is covered by the
signature check or by a CRC-32: the preamble's, the header's, or the section's. Beyond single
flips, a crafted file decodes when what it changes is itself allowed: an unknown header key,
the informative ``encoder`` and ``error`` fields, ``minor``, ignorable flag bits 16-31, a valid
``frame_rate``, or more byte planes than needed.
"""

from __future__ import annotations

import contextlib
import json
import math
import signal
import struct
import threading
import time
import tracemalloc
import zlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import msgpack
import numpy as np
import pytest
import zstandard
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import tuckercodec
from tuckercodec import (
    ChecksumError,
    Decoder,
    FormatError,
    LimitError,
    TruncatedFileError,
    UnsupportedVersionError,
)
from tuckercodec.format.container import HEAD_SIZE, SIGNATURE, pack_container, parse_container
from tuckercodec.format.faces import encode_faces
from tuckercodec.format.prediction import residuals
from tuckercodec.format.sections import KNOWN_SECTIONS
from tuckercodec.format.streams import compress, pack_integers
from tuckercodec.topology import mesh_parents

VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
VALID = ["v1-wave-triangles", "v1-polygons-names", "v1-ignorable-extensions"]
IDENTITY_U2 = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
#: Time one hostile case may take (they take milliseconds; a hang trips this).
CASE_SECONDS = 5.0
#: Peak traced memory a file that lies about its sizes may cost.
CLAIM_PEAK_BYTES = 4 << 20
#: Hypothesis: deterministic in CI and no example database written into the repository.
SETTINGS = {"deadline": None, "database": None, "derandomize": True,
            "suppress_health_check": [HealthCheck.too_slow, HealthCheck.data_too_large]}


# ------------------------------------------------------------------------------------------
# helpers


def vector(name: str) -> bytes:
    return (VECTORS / f"{name}.tkc").read_bytes()


class Parts:
    """A valid file taken apart: header (without the table), sections with their payloads."""

    def __init__(self, data: bytes) -> None:
        container = parse_container(data)
        self.flags = container.flags
        self.header = {k: v for k, v in container.header.items() if k != "sections"}
        self.sections: list[tuple[dict[str, Any], bytes]] = [
            ({"id": s.id, "critical": s.critical, "codec": s.codec, **s.params}, bytes(container.payload(data, s)))
            for s in container.sections
        ]

    def index(self, section_id: str) -> int:
        return next(n for n, (entry, _) in enumerate(self.sections) if entry["id"] == section_id)

    def pack(self) -> bytes:
        """The file again, offsets, lengths and every CRC-32 made right (pack_container)."""
        return pack_container(self.header, self.sections, flags=self.flags)

    def table(self) -> list[dict[str, Any]]:
        """The section table as pack_container would write it, to be edited raw."""
        out, offset = [], 0
        for entry, payload in self.sections:
            out.append({**entry, "offset": offset, "length": len(payload), "crc32": zlib.crc32(payload)})
            offset += len(payload)
        return out

    def area(self) -> bytes:
        return b"".join(payload for _, payload in self.sections)


def raw_file(header: dict[str, Any] | bytes, area: bytes = b"", *, major: int = 1, minor: int = 0,
             flags: int = 0, total: int | None = None) -> bytes:
    """A file from a header (a map, or raw msgpack bytes) and a data area, with correct
    preamble and header CRCs whatever the header says: the checks behind the CRCs are reached."""
    header_bytes = header if isinstance(header, bytes) else msgpack.packb(header, use_bin_type=True)
    if total is None:
        total = HEAD_SIZE + len(header_bytes) + 4 + len(area)
    head = SIGNATURE + struct.pack("<HHIIQ", major, minor, flags, len(header_bytes), total)
    return b"".join([head, struct.pack("<I", zlib.crc32(head)), header_bytes,
                     struct.pack("<I", zlib.crc32(header_bytes)), area])


class Hang(Exception):
    """A case ran past its deadline."""


@contextlib.contextmanager
def deadline(seconds: float = CASE_SECONDS) -> Iterator[None]:
    """Fail a case that runs too long: SIGALRM where there is one (it interrupts a Python-level
    loop); elsewhere the elapsed time is checked afterwards."""
    usable = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
    started = time.perf_counter()
    if usable:
        def expire(signum: int, frame: Any) -> None:
            raise Hang(f"the case ran for more than {seconds} s")

        previous = signal.signal(signal.SIGALRM, expire)
        signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        if usable:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)
    elapsed = time.perf_counter() - started
    assert elapsed < seconds, f"the case took {elapsed:.1f} s"


def outcome(data: bytes) -> tuple[FormatError | None, tuckercodec.MeshSequence | None]:
    """Decode the whole file (every frame reconstructed) within the deadline: ``(error, None)``
    or ``(None, sequence)``. Any exception but FormatError propagates and fails the test."""
    with deadline():
        try:
            return None, tuckercodec.decode(data)
        except FormatError as error:
            return error, None


def expect_error(data: bytes, kind: type[FormatError] = FormatError, *, exact: bool = False) -> FormatError:
    """The file must fail with ``kind`` (a subclass too, unless ``exact``); ``info`` must fail as
    well or accept only what it reads (the header)."""
    error, sequence = outcome(data)
    assert sequence is None, f"decoded although it should fail with {kind.__name__}"
    assert isinstance(error, kind), f"{type(error).__name__} ({error}) is not a {kind.__name__}"
    if exact:
        assert type(error) is kind, f"{type(error).__name__} ({error}), expected exactly {kind.__name__}"
    with deadline():
        try:
            tuckercodec.info(data)
        except FormatError:
            pass
    return error


def check_decoded(data: bytes, sequence: tuckercodec.MeshSequence) -> None:
    """A file that decodes must agree with itself: info, random access (§8), finite values."""
    header = tuckercodec.info(data)
    assert sequence.vertices.shape == (header.frames, header.vertices, 3)
    assert np.isfinite(sequence.vertices).all()
    decoder = Decoder(data)
    last = header.frames - 1
    scale = float(np.abs(sequence.vertices[last]).max())
    np.testing.assert_allclose(decoder.frame(last), sequence.vertices[last], rtol=0, atol=1e-9 * scale + 1e-12)


def accept_either(data: bytes) -> FormatError | None:
    """Hypothesis-made files: FormatError, or a decode that is consistent."""
    error, sequence = outcome(data)
    if sequence is not None:
        check_decoded(data, sequence)
    return error


def traced_peak(action: Callable[[], object]) -> int:
    """Peak bytes traced by tracemalloc while ``action`` runs (numpy reports its buffers to
    tracemalloc, and zstandard's output is a Python bytes object, so both are counted)."""
    tracemalloc.start()
    try:
        action()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


def zstd_header_only(size: int) -> bytes:
    """A 16-byte 'frame': magic, a header declaring ``size`` bytes, one empty last raw block."""
    return b"\x28\xb5\x2f\xfd" + bytes([0b11100000]) + struct.pack("<Q", size) + b"\x01\x00\x00"


# ------------------------------------------------------------------------------------------
# truncation and bit flips of the valid vectors


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
    out = [(0, 8, "signature"), (8, 28, "preamble"), (28, 32, "preamble crc"), (32, header_end, "header"),
           (header_end, header_end + 4, "header crc")]
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
                damaged = bytearray(data)
                damaged[position] ^= 1 << bit
                damaged = bytes(damaged)
                if what.startswith("section ") and what.split(" ", 1)[1] not in known:
                    decoder = Decoder(damaged)  # skipped unread: must decode, identically
                    np.testing.assert_array_equal(decoder.positions(), reference)
                    np.testing.assert_array_equal(decoder.faces, original.faces)
                    assert decoder.frame_names == original.frame_names
                    harmless += 1
                    continue
                with pytest.raises(FormatError) as raised:
                    tuckercodec.decode(damaged)
                if what == "signature":
                    assert type(raised.value) is FormatError, (position, bit)
                else:
                    assert type(raised.value) is ChecksumError, (position, bit, what, raised.value)
    unknown_bytes = sum(end - start for start, end, what in _regions(data)
                        if what.startswith("section ") and what.split(" ", 1)[1] not in known)
    assert harmless == 8 * unknown_bytes


@settings(max_examples=150, **SETTINGS)
@given(name=st.sampled_from(VALID), data=st.data())
def test_a_burst_of_damage_in_a_payload_is_a_checksum_error(name, data):
    """Any burst of up to 32 bits inside one known section's payload is detected by its CRC-32
    (a CRC of degree 32 detects every burst that short), so a damaged payload is never decoded."""
    original = vector(name)
    regions = [r for r in _regions(original) if r[2].startswith("section ")
               and r[2].split(" ", 1)[1] in KNOWN_SECTIONS]
    start, end, _ = data.draw(st.sampled_from(regions))
    first = data.draw(st.integers(start, end - 1))
    width = data.draw(st.integers(1, min(4, end - first)))
    noise = data.draw(st.binary(min_size=width, max_size=width).filter(lambda b: any(b)))
    damaged = bytearray(original)
    for n in range(width):
        damaged[first + n] ^= noise[n]
    expect_error(bytes(damaged), ChecksumError, exact=True)


# ------------------------------------------------------------------------------------------
# the preamble: versions, flags, lengths, trailing bytes


def _with_preamble(data: bytes, *, major: int | None = None, minor: int | None = None, flags: int | None = None,
                   header_length: int | None = None, total: int | None = None) -> bytes:
    """The file with preamble fields changed and the preamble CRC made right again."""
    fields = list(struct.unpack_from("<HHIIQ", data, 8))
    for index, value in enumerate((major, minor, flags, header_length, total)):
        if value is not None:
            fields[index] = value
    head = SIGNATURE + struct.pack("<HHIIQ", *fields)
    return head + struct.pack("<I", zlib.crc32(head)) + data[HEAD_SIZE:]


@pytest.mark.parametrize("major", [0, 2, 3, 0x7FFF, 0xFFFF])
def test_unknown_major_version(major):
    expect_error(_with_preamble(vector("v1-wave-triangles"), major=major), UnsupportedVersionError, exact=True)


@pytest.mark.parametrize("minor", [1, 7, 0xFFFF])
def test_any_minor_version_is_read(minor):
    error, sequence = outcome(_with_preamble(vector("v1-wave-triangles"), minor=minor))
    assert error is None and sequence is not None


@pytest.mark.parametrize("flags", [1, 0x8000, 0xFFFF, 0xFFFFFFFF, 0x00010001])
def test_critical_flag_bits_are_refused(flags):
    expect_error(_with_preamble(vector("v1-wave-triangles"), flags=flags), UnsupportedVersionError, exact=True)


@pytest.mark.parametrize("flags", [0x10000, 0x80000000, 0xFFFF0000])
def test_ignorable_flag_bits_are_ignored(flags):
    error, sequence = outcome(_with_preamble(vector("v1-wave-triangles"), flags=flags))
    assert error is None and sequence is not None


@pytest.mark.parametrize(
    ("change", "kind"),
    [
        ({"header_length": 0}, ChecksumError),  # the header CRC is now read from inside the header
        ({"header_length": 0xFFFFFFFF}, LimitError),
        ({"header_length": (16 << 20) + 1}, LimitError),
        ({"header_length": 16 << 20}, FormatError),  # within the limit, beyond total_length (R08)
        ({"total": 0}, FormatError),
        ({"total": 35}, FormatError),
        ({"total": 2**64 - 1}, TruncatedFileError),
        ({"total": 2**63}, TruncatedFileError),
        ({"total": 10**12}, TruncatedFileError),
    ],
)
def test_lying_preamble_lengths(change, kind):
    data = _with_preamble(vector("v1-wave-triangles"), **change)
    error = expect_error(data, kind)
    assert type(error) is kind


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
    expect_error(data + data, FormatError, exact=True)


# ------------------------------------------------------------------------------------------
# every header field set to zero, negative, huge and every wrong type

#: 2**64 itself has no msgpack encoding (the largest msgpack int is 2**64 - 1), so "huge" is
#: 2**63, 2**64 - 1 and the floats 2.0**64 and 1e308.
HOSTILE = {
    "zero": 0, "minus one": -1, "most negative": -(2**63), "2**31": 2**31, "2**63": 2**63,
    "2**64-1": 2**64 - 1, "float 2**64": 2.0**64, "1e308": 1e308, "-1e308": -1e308, "float zero": 0.0,
    "nan": math.nan, "inf": math.inf, "-inf": -math.inf, "str": "12", "empty str": "", "bytes": b"\x01",
    "list": [1, 2], "empty list": [], "dict": {"a": 1}, "empty dict": {}, "none": None, "true": True,
    "false": False,
}
MISSING = object()


def _set(header: dict[str, Any], path: tuple, value: Any) -> None:
    target = header
    for key in path[:-1]:
        target = target[key]
    if value is MISSING:
        del target[path[-1]]
    else:
        target[path[-1]] = value


EVERYTHING = set(HOSTILE) | {"missing"}
#: Header paths -> (hostile values, by HOSTILE's names, under which the file stays valid;
#: values that may or may not make the reconstruction overflow, R36). All others must fail.
HEADER_FIELDS: dict[tuple, tuple[set[str], set[str]]] = {
    ("vertices",): (set(), set()),
    ("frames",): (set(), set()),
    ("ranks",): (set(), set()),
    ("ranks", 0): (set(), set()),
    ("ranks", 1): (set(), set()),
    ("u2",): (set(), set()),
    # any finite float: the decoder does not check that U2 is orthogonal
    ("u2", 0): ({"float zero"}, {"float 2**64", "1e308", "-1e308"}),
    ("u2", 8): ({"float zero"}, {"float 2**64", "1e308", "-1e308"}),
    ("frame_rate",): ({"float 2**64", "1e308", "none", "missing"}, set()),  # positive finite, nil or absent
    ("encoder",): (EVERYTHING, set()),  # informative only (§4)
    ("error",): (EVERYTHING, set()),
    ("error", "kg"): (EVERYTHING, set()),
    ("error", "definition"): (EVERYTHING, set()),
    ("sections",): (set(), set()),
}


@pytest.mark.parametrize("path", list(HEADER_FIELDS), ids=lambda p: ".".join(map(str, p)))
def test_every_header_field_set_to_every_hostile_value(path):
    allowed, either = HEADER_FIELDS[path]
    for label, value in [*HOSTILE.items(), ("missing", MISSING)]:
        parts = Parts(vector("v1-wave-triangles"))
        parts.header["frame_rate"] = 24.0
        if path == ("sections",):
            header = {**parts.header, "sections": None}
            if value is not MISSING:
                header["sections"] = value
            else:
                del header["sections"]
            data = raw_file(header, parts.area())
        else:
            _set(parts.header, path, value)
            data = parts.pack()
        error, sequence = outcome(data)
        if label in allowed:
            assert error is None, f"{path} = {label}: {error}"
            check_decoded(data, sequence)
        elif label in either:
            if sequence is not None:
                check_decoded(data, sequence)
        else:
            assert error is not None, f"{path} = {label} was accepted"
        if path in {("vertices",), ("frames",)} and label in {"2**31", "2**63", "2**64-1"}:
            assert type(error) is LimitError, f"{path} = {label}: {error!r}"


SECTION_PARAMS = ["shape", "planes", "steps", "predict", "critical", "codec", "id"]


@pytest.mark.parametrize("section", ["FACE", "U1", "U3", "CORE", "CENT", "NAME"])
@pytest.mark.parametrize("key", SECTION_PARAMS + ["size"])
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
                assert sequence.frame_names[0] == "frame_00000"  # NAME gone: the default names
        else:
            assert error is not None, f"{section}.{key} = {label} was accepted"


TABLE_FIELDS = ["offset", "length", "crc32"]


@pytest.mark.parametrize("key", TABLE_FIELDS)
@pytest.mark.parametrize("index", [0, 2, 4])
def test_every_table_field_set_to_every_hostile_value(key, index):
    """offset, length and crc32 of an entry (pack_container fills those, so the table is
    written raw here with correct CRCs for the header)."""
    parts = Parts(vector("v1-wave-triangles"))
    for label, value in [*HOSTILE.items(), ("missing", MISSING)]:
        table = parts.table()
        original = table[index][key]
        if type(value) is type(original) and value == original:
            continue  # offset 0 of the first entry is right
        if value is MISSING:
            del table[index][key]
        else:
            table[index][key] = value
        expect_error(raw_file({**parts.header, "sections": table}, parts.area()))


@pytest.mark.parametrize("label", list(HOSTILE))
def test_info_as_json_is_strict_json_whatever_the_error_map_claims(label):
    """The informative ``error`` values are not checked (§4.1), but ``FileInfo.to_dict`` (what
    ``tuckercodec info --json`` prints) must stay valid JSON: no bare NaN or Infinity."""
    parts = Parts(vector("v1-wave-triangles"))
    parts.header["error"] = {"kg": HOSTILE[label], "target_kg": HOSTILE[label], "definition": HOSTILE[label]}
    text = json.dumps(tuckercodec.info(parts.pack()).to_dict(), allow_nan=False)
    assert json.loads(text)["vertices"] == 81


# ------------------------------------------------------------------------------------------
# section tables that overlap, point outside, repeat, have negative or huge lengths


def _table_case(edit: Callable[[list[dict[str, Any]], Parts], None], area: bytes | None = None) -> bytes:
    parts = Parts(vector("v1-wave-triangles"))
    table = parts.table()
    edit(table, parts)
    return raw_file({**parts.header, "sections": table}, parts.area() if area is None else area)


def _shift(entry: dict[str, Any], by: int) -> None:
    entry["offset"] += by


TABLE_CASES: dict[str, tuple[Callable[[list, Parts], None], type[FormatError]]] = {
    "two sections overlap": (lambda t, p: _shift(t[1], -10), FormatError),
    "all sections at offset 0": (lambda t, p: [e.update(offset=0) for e in t], FormatError),
    "a gap between sections": (lambda t, p: _shift(t[1], 1), FormatError),
    "a section past the end": (lambda t, p: t[-1].update(length=t[-1]["length"] + 1), FormatError),
    "a section far outside the file": (lambda t, p: t[-1].update(length=2**40), FormatError),
    "a huge length": (lambda t, p: t[0].update(length=2**64 - 1), FormatError),
    "a 2**63 length": (lambda t, p: t[0].update(length=2**63), FormatError),
    "a negative length": (lambda t, p: t[0].update(length=-35), FormatError),
    "a most negative offset": (lambda t, p: t[0].update(offset=-(2**63)), FormatError),
    "a negative length that brings the table back in step": (
        lambda t, p: (t[1].update(length=t[1]["length"] - 10), t[2].update(offset=t[2]["offset"] - 10)), FormatError),
    "a repeated id": (lambda t, p: t[1].update(id=t[0]["id"]), FormatError),
    "the same entry twice": (lambda t, p: t.append(dict(t[-1])), FormatError),
    "a short table": (lambda t, p: t.pop(), FormatError),
    "an empty table": (lambda t, p: t.clear(), FormatError),
    "65 entries": (lambda t, p: t.extend({**t[-1], "id": f"x{n}", "critical": False, "length": 0,
                                          "offset": sum(e["length"] for e in t)} for n in range(60)), LimitError),
    "a crc32 of 2**32": (lambda t, p: t[0].update(crc32=2**32), FormatError),
    "a negative crc32": (lambda t, p: t[0].update(crc32=-1), FormatError),
    "a wrong crc32": (lambda t, p: t[0].update(crc32=(t[0]["crc32"] + 1) % 2**32), ChecksumError),
    "an id of 17 characters": (lambda t, p: t[0].update(id="FACE" + "x" * 13), FormatError),
    "an id with a control character": (lambda t, p: t[0].update(id="FA\nCE"), FormatError),
    "a non-ASCII id": (lambda t, p: t[0].update(id="FACÉ"), FormatError),
    "an entry that is a list": (lambda t, p: t.__setitem__(0, list(t[0].items())), FormatError),
    "an unknown critical section": (lambda t, p: t.append({**t[-1], "id": "XTRA", "offset": t[-1]["offset"]
                                                           + t[-1]["length"], "length": 0}), UnsupportedVersionError),
    "a known section with another codec": (lambda t, p: t[1].update(codec="qmat2"), UnsupportedVersionError),
    "a required section marked ancillary": (lambda t, p: t[0].update(critical=False), FormatError),
}


@pytest.mark.parametrize("case", list(TABLE_CASES))
def test_bad_section_tables(case):
    edit, kind = TABLE_CASES[case]
    error = expect_error(_table_case(edit), kind)
    assert type(error) is kind, f"{case}: {error!r}"


def test_an_unknown_ancillary_section_is_skipped_whatever_it_holds():
    parts = Parts(vector("v1-wave-triangles"))
    parts.sections.insert(2, ({"id": "junk", "critical": False, "codec": "??", "shape": -1}, bytes(range(256)) * 4))
    data = parts.pack()
    error, sequence = outcome(data)
    assert error is None
    np.testing.assert_array_equal(sequence.vertices, tuckercodec.decode(vector("v1-wave-triangles")).vertices)


@pytest.mark.parametrize("section", ["FACE", "U1", "U3", "CORE", "CENT"])
def test_a_required_section_missing(section):
    parts = Parts(vector("v1-wave-triangles"))
    del parts.sections[parts.index(section)]
    expect_error(parts.pack(), FormatError, exact=True)


def test_a_critical_name_section_is_refused():
    parts = Parts(vector("v1-polygons-names"))
    parts.sections[parts.index("NAME")][0]["critical"] = True
    expect_error(parts.pack(), FormatError, exact=True)


# ------------------------------------------------------------------------------------------
# headers that claim far more than the file holds: refused before anything is allocated


def _tiny(header: dict[str, Any], sections: list[tuple[dict[str, Any], bytes]] | None = None) -> bytes:
    return pack_container({"u2": IDENTITY_U2, **header}, sections or [])


def _claiming(vertices: int, frames: int, i: int, k: int, *, faces: np.ndarray | None = None,
              lie_in: tuple[str, ...] = ("FACE", "U1", "U3", "CORE", "CENT")) -> bytes:
    """A small file whose sections have the shapes a header of these sizes implies, every
    payload in ``lie_in`` a 16-byte zstd header that claims the whole size; others real."""
    faces = np.zeros((0, 3), np.int64) if faces is None else faces
    face_params, face_payload = encode_faces(faces)
    sections = [({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload)]
    for section_id, rows, cols in [("U1", vertices, i), ("U3", frames, k), ("CORE", i * 3 * k, 1), ("CENT", frames, 3)]:
        payload = zstd_header_only(rows * cols) if section_id in lie_in else compress(bytes(rows * cols))
        sections.append(({"id": section_id, "critical": True, "codec": "qmat", "shape": [rows, cols], "planes": 1,
                          "steps": np.ones(cols, "<f4").tobytes(), "predict": bytes(cols)}, payload))
    return pack_container({"vertices": vertices, "frames": frames, "ranks": [i, k], "u2": IDENTITY_U2}, sections)


BILLION = 10**9
CLAIMS: dict[str, tuple[Callable[[], bytes], type[FormatError]]] = {
    "a billion vertices": (lambda: _tiny({"vertices": BILLION, "frames": 10, "ranks": [5, 5]}), LimitError),
    "a billion frames": (lambda: _tiny({"vertices": 10, "frames": BILLION, "ranks": [5, 5]}), LimitError),
    "a billion of both": (lambda: _tiny({"vertices": BILLION, "frames": BILLION, "ranks": [BILLION, BILLION]}), LimitError),
    "a billion ranks": (lambda: _tiny({"vertices": 2**20, "frames": 2**8, "ranks": [BILLION, BILLION]}), FormatError),
    "2**64-1 vertices": (lambda: _tiny({"vertices": 2**64 - 1, "frames": 1, "ranks": [1, 1]}), LimitError),
    "K*F beyond max_positions": (lambda: _tiny({"vertices": 2**26, "frames": 2**24, "ranks": [1, 1]}), LimitError),
    "ranks beyond max_factor_values": (lambda: _tiny({"vertices": 2**20, "frames": 2**8, "ranks": [768, 256]}), LimitError),
    "max_vertices, payloads that cannot hold them": (lambda: _claiming(2**26, 1, 1, 1), FormatError),
    "max_frames, payloads that cannot hold them": (lambda: _claiming(1, 2**24, 1, 3, lie_in=("U3", "CENT")),
                                                   FormatError),
    "max_vertices, only U1 lies": (lambda: _claiming(2**26, 1, 1, 1, lie_in=("U1",)), FormatError),
    "max_vertices, a face, U1 lies": (lambda: _claiming(2**26, 1, 1, 1, faces=np.array([[0, 1, 2**26 - 1]]),
                                                        lie_in=("U1",)), FormatError),
    "max_factor_values in U1 and CORE": (lambda: _claiming(2**24, 8, 7, 8), FormatError),
}


def _face_claim(rows: int, cols: int, planes: int = 4) -> bytes:
    parts = Parts(vector("v1-wave-triangles"))
    index = parts.index("FACE")
    entry, _ = parts.sections[index]
    parts.sections[index] = ({**entry, "shape": [rows, cols], "planes": planes}, zstd_header_only(rows * cols * planes))
    return parts.pack()


def _name_claim(size: int) -> bytes:
    parts = Parts(vector("v1-polygons-names"))
    index = parts.index("NAME")
    entry, _ = parts.sections[index]
    parts.sections[index] = ({**entry, "size": size}, zstd_header_only(size))
    return parts.pack()


CLAIMS.update({
    "2**28 faces of 4 corners in 16 bytes": (lambda: _face_claim(2**28, 4), FormatError),
    "faces beyond max_section_bytes": (lambda: _face_claim(2**28, 5), LimitError),
    "faces beyond max_faces": (lambda: _face_claim(2**28 + 1, 3), LimitError),
    "faces of 65 corners": (lambda: _face_claim(10, 65), LimitError),
    "4 GiB of names in 16 bytes": (lambda: _name_claim(2**32), FormatError),
    "names beyond max_section_bytes": (lambda: _name_claim(2**32 + 1), LimitError),
    "a 16 MiB header in a small file": (lambda: _with_preamble(vector("v1-wave-triangles"), header_length=16 << 20,
                                                               total=(16 << 20) + 36), TruncatedFileError),
    "2**64-1 total bytes": (lambda: _with_preamble(vector("v1-wave-triangles"), total=2**64 - 1), TruncatedFileError),
})


@pytest.mark.parametrize("case", list(CLAIMS))
def test_claims_beyond_the_file_cost_no_memory(case):
    """Each file is at most a few KB and lies about its sizes; decoding it must fail with the
    right error, at once, with a traced peak under CLAIM_PEAK_BYTES (the file included)."""
    build, kind = CLAIMS[case]
    data = build()
    assert len(data) < 4096, len(data)
    errors: list[FormatError] = []

    def attempt() -> None:
        for read in (tuckercodec.decode, tuckercodec.info):
            try:
                read(data)
            except FormatError as error:
                errors.append(error)

    started = time.perf_counter()
    with deadline(2.0):
        peak = traced_peak(attempt)
    elapsed = time.perf_counter() - started
    assert errors and isinstance(errors[0], kind), f"{case}: {errors!r}"
    assert type(errors[0]) is kind, f"{case}: {errors[0]!r}"
    assert peak < CLAIM_PEAK_BYTES, f"{case}: {peak / 2**20:.1f} MiB traced"
    assert elapsed < 1.0, f"{case}: {elapsed:.2f} s"


def test_a_billion_vertex_header_in_200_bytes():
    data = _tiny({"vertices": BILLION, "frames": BILLION, "ranks": [BILLION, BILLION]})
    assert len(data) <= 200
    def attempt() -> None:
        with pytest.raises(LimitError):
            tuckercodec.decode(data)

    assert traced_peak(attempt) < 1 << 20


def test_a_deep_strip_of_faces_decodes_quickly():
    """A valid 866-byte file whose 2**19 vertices form one strip: the breadth-first walk of
    §6.2 is 2**18 levels deep (one Python pass per level took 5 s; minutes at 2**26)."""
    count = 2**19
    row = np.arange(count - 2)
    faces = np.stack([row, row + 1, row + 2], 1)
    face_params, face_payload = encode_faces(faces)
    q = np.zeros((count, 1), np.int64)
    q[0] = 1
    payload, planes = pack_integers(np.ascontiguousarray(residuals(q, mesh_parents(faces, count)).T))
    one = np.ones(1, "<f4").tobytes()
    sections = [
        ({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload),
        ({"id": "U1", "critical": True, "codec": "qmat", "shape": [count, 1], "planes": planes, "steps": one,
          "predict": b"\x01"}, payload),
        ({"id": "U3", "critical": True, "codec": "qmat", "shape": [1, 1], "planes": 1, "steps": one,
          "predict": b"\x00"}, compress(b"\x02")),
        ({"id": "CORE", "critical": True, "codec": "qmat", "shape": [3, 1], "planes": 1, "steps": one,
          "predict": b"\x00"}, compress(b"\x02\x00\x00")),
        ({"id": "CENT", "critical": True, "codec": "qmat", "shape": [1, 3], "planes": 1,
          "steps": np.ones(3, "<f4").tobytes(), "predict": b"\x00\x00\x00"}, compress(b"\x00\x00\x00")),
    ]
    data = pack_container({"vertices": count, "frames": 1, "ranks": [1, 1], "u2": IDENTITY_U2}, sections)
    started = time.perf_counter()
    with deadline(10.0):
        decoder = Decoder(data)
    assert time.perf_counter() - started < 2.0
    expected = np.zeros((count, 1))
    expected[0] = 1
    np.testing.assert_array_equal(decoder.u1, expected)  # every residual summed along the strip
    assert decoder.frame(0)[0].tolist() == [1.0, 0.0, 0.0]


# ------------------------------------------------------------------------------------------
# hypothesis: arbitrary headers, re-signed so that the semantic checks are reached

leaves = (
    st.none() | st.booleans() | st.integers(-(2**63), 2**64 - 1) | st.sampled_from([0, 1, -1, 2, 3, 81, 24, 6])
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=20) | st.binary(max_size=40)
)
msgpack_values = st.recursive(
    leaves, lambda children: st.lists(children, max_size=6) | st.dictionaries(st.text(max_size=10), children, max_size=6),
    max_leaves=25,
)
HEADER_KEYS = ["vertices", "frames", "ranks", "u2", "frame_rate", "encoder", "error", "x-unknown"]


@settings(max_examples=300, **SETTINGS)
@given(header=st.dictionaries(st.sampled_from(HEADER_KEYS) | st.text(max_size=8), msgpack_values, max_size=8),
       name=st.sampled_from(VALID))
def test_arbitrary_headers_over_real_sections(header, name):
    """Any header map at all, with a vector's real sections (pack_container re-signs the CRCs)."""
    parts = Parts(vector(name))
    header.pop("sections", None)
    accept_either(pack_container(header, parts.sections))


@settings(max_examples=300, **SETTINGS)
@given(name=st.sampled_from(VALID), key=st.sampled_from(HEADER_KEYS), value=msgpack_values)
def test_one_header_field_arbitrary(name, key, value):
    """A valid header with one field replaced by anything msgpack can hold."""
    parts = Parts(vector(name))
    parts.header[key] = value
    error = accept_either(parts.pack())
    if key in {"vertices", "frames", "ranks"} and value != Parts(vector(name)).header[key]:
        # a size changed: no section's shape can still match it (u2 may change to any finite
        # floats, which is still a valid file)
        assert error is not None


@settings(max_examples=300, **SETTINGS)
@given(name=st.sampled_from(VALID), data=st.data())
def test_one_section_parameter_arbitrary(name, data):
    """One parameter of one section replaced (or added) by anything msgpack can hold."""
    parts = Parts(vector(name))
    index = data.draw(st.integers(0, len(parts.sections) - 1))
    entry, _ = parts.sections[index]
    key = data.draw(st.sampled_from(["shape", "planes", "steps", "predict", "size", "critical", "codec", "id", "x"]))
    entry[key] = data.draw(msgpack_values | st.sampled_from([[0, 0], [2**63, 1], [1, 2**63], [-1, 3], [2**32, 2**32]]))
    accept_either(parts.pack())


@settings(max_examples=200, **SETTINGS)
@given(table=st.lists(st.fixed_dictionaries({
    "id": st.sampled_from(["FACE", "U1", "U3", "CORE", "CENT", "NAME", "junk"]) | st.text(max_size=18),
    "offset": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2000),
    "length": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2000),
    "crc32": st.integers(-(2**63), 2**64 - 1) | st.integers(0, 2**32 - 1),
    "critical": st.booleans() | leaves,
    "codec": st.sampled_from(["qmat", "faces-delta", "msgpack-zstd"]) | leaves,
}), max_size=8), name=st.sampled_from(VALID))
def test_arbitrary_section_tables(table, name):
    """Any table over a vector's data area, the header CRC correct: always FormatError (a valid
    table would need the five required sections, each with the CRC of its exact payload)."""
    parts = Parts(vector(name))
    error, _ = outcome(raw_file({**parts.header, "sections": table}, parts.area()))
    assert error is not None


def _recompressed(parts: Parts, index: int, raw: bytes) -> None:
    entry, _ = parts.sections[index]
    parts.sections[index] = (entry, zstandard.ZstdCompressor(level=1, write_content_size=True).compress(raw))


@settings(max_examples=300, **SETTINGS)
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
            raw[position] = data.draw(st.sampled_from([0, 1, 0x7F, 0x80, 0xFE, 0xFF]) | st.integers(0, 255))
    _recompressed(parts, index, bytes(raw))
    data_bytes = parts.pack()
    _, sequence = outcome(data_bytes)
    if sequence is not None:
        check_decoded(data_bytes, sequence)
        assert sequence.faces.max(initial=-1) < sequence.vertex_count


@settings(max_examples=100, **SETTINGS)
@given(count=st.integers(1, 40), faces=st.lists(st.lists(st.integers(-1, 39), min_size=3, max_size=5), max_size=30),
       repeat=st.integers(1, 300))
def test_mesh_parents_match_the_walk_of_the_spec(count, faces, repeat):
    """The compiled breadth-first search gives the parents of §6.2's queue walk, whatever the
    faces: repeated (even 300 times), degenerate, padded, or leaving vertices alone."""
    width = max((len(f) for f in faces), default=3)
    array = np.full((len(faces), width), -1, dtype=np.int64)
    for row, face in enumerate(faces):
        real = [v % count for v in face if v >= 0][:width]
        real += [real[0] if real else 0] * (3 - len(real))  # at least 3 real corners
        array[row, : len(real)] = real
    if len(array):
        array = np.concatenate([array, np.repeat(array[:1], repeat, axis=0)])
    assert mesh_parents(array, count).tolist() == _spec_walk(array, count)


def _spec_walk(faces: np.ndarray, count: int) -> list[int]:
    """The pseudocode of spec/FORMAT.md §6.2, literally."""
    neighbours: list[set[int]] = [set() for _ in range(count)]
    for face in faces.tolist():
        for j, a in enumerate(face):
            if a < 0:
                continue
            b = face[j + 1] if j + 1 < len(face) and face[j + 1] >= 0 else face[0]
            if a != b:
                neighbours[a].add(b)
                neighbours[b].add(a)
    parent, reached = [-1] * count, [False] * count
    for s in range(count):
        if reached[s]:
            continue
        reached[s] = True
        queue, head = [s], 0
        while head < len(queue):
            u = queue[head]
            head += 1
            for w in sorted(neighbours[u]):
                if not reached[w]:
                    reached[w], parent[w] = True, u
                    queue.append(w)
    return parent
