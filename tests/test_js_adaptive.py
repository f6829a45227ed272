"""The JavaScript decoder's adaptive coding (format 1.6, spec/FORMAT.md §6.14:
tuckercodec/web/tkc/adaptive.js, and the `coder` parameter in qmat.js), in node.

Each valid file here is written twice (tests/support/adaptive_files.py): every position factor
in §6.1's zstd planes (a file of 1.5 or before), and every one in an adaptive stream of the
reference coder (1.6). The two hold the same integers, so the JavaScript decoder must give them
the same frames, bit for bit (test_js_decoder.py holds it to the Python decoder). Files that
break §6.14 in one way each, and adaptive streams damaged at seeded places, must get the Python
decoder's verdict, which for the former is the rule §5 step 16's order gives. The stream
decoder itself is checked integer for integer against the reference by ``npm test``
(tests/js/adaptive.test.mjs) on tests/js/adaptive_fixture.json, which the first test here keeps
as the reference writes it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.adaptive_files import (
    AdaptiveParts,
    adaptive_copy,
    adaptive_parts,
    taken_apart,
    zstd_copy,
)
from tests.support.compressed import vector
from tests.support.js_decoder import VALID, compare_verdicts, decoded_frames
from tests.support.sequences import shared_case, shared_encoded
from tools.generate import adaptive_fixture
from tuckercodec.io.samples import sample_path

R46 = "R46-adaptive-stream"
#: Damaged copies of each vector of 1.6.
DAMAGED_PER_VECTOR = 40


def test_the_fixture_is_what_the_reference_writes():
    """tests/js/adaptive_fixture.json is current: run ``python -m tools.generate.adaptive_fixture``
    after a change to the reference coder or to the cases."""
    assert adaptive_fixture.OUT.read_text() == adaptive_fixture.fixture()


def _same_as_original(original: bytes, tmp_path: Path) -> None:
    """Its twin with every position factor in zstd planes and its twin with every one in an
    adaptive stream: the same frames."""
    zstd, copy = zstd_copy(original), adaptive_copy(original)
    pushed = b"mean_push" in zstd  # predictor 2's pushes keep a file 1.6 (§6.2)
    assert tuckercodec.info(zstd).format_version != "1.6" or pushed
    # adaptive corrections (1.7) and codebooks (1.8) are kept in both twins
    version = tuckercodec.info(original).format_version
    kept = int(version.split(".")[1]) >= 7
    assert tuckercodec.info(copy).format_version == (version if kept else "1.6")
    assert np.array_equal(
        decoded_frames(copy, tmp_path, "copy"),
        decoded_frames(zstd, tmp_path, "zstd"),
        equal_nan=True,
    )


@pytest.mark.parametrize("name", [n.removesuffix(".json") for n in VALID])
def test_the_vectors_in_adaptive_streams_give_the_same_positions(tmp_path, name):
    """Every valid vector (1.0 to 1.6: segments shared and own, traversed faces, corrections,
    attributes, fields) both ways: the same frames, bit for bit."""
    _same_as_original(vector(name), tmp_path)


@pytest.mark.parametrize(
    "options",
    [{"target_kg": 0.1}, {"target_kg": 0.1, "segment_frames": 16}],
    ids=["whole", "segments"],
)
def test_the_sample_in_adaptive_streams_gives_the_same_positions(tmp_path, options):
    sequence = tuckercodec.load_sequence(sample_path())
    _same_as_original(tuckercodec.encode_with_report(sequence, **options).data, tmp_path)


@pytest.mark.parametrize("name", [shared_case("samba.npz")])
def test_samba_in_adaptive_streams_gives_the_same_positions(tmp_path, name):
    """A real mesh: U1's mesh order over 9,971 vertices and 150 columns or so."""
    _same_as_original(shared_encoded(name).data, tmp_path)


# ------------------------------------------------------------------------------------------
# files that break §6.14, one way each


def _sample() -> bytes:
    sequence = tuckercodec.load_sequence(sample_path())
    return tuckercodec.encode_with_report(sequence, target_kg=0.1).data


#: An entry value that removes the key.
REMOVED = object()


def _edited(
    parts: AdaptiveParts, section_id: str, payload: bytes | None = None, **changes: Any
) -> bytes:
    """The file with one section's entry keys changed (REMOVED: the key taken out) and, when
    given, its payload replaced."""
    n = parts.index(section_id)
    entry, old = parts.sections[n]
    entry = {k: v for k, v in {**entry, **changes}.items() if v is not REMOVED}
    sections = list(parts.sections)
    sections[n] = (entry, old if payload is None else payload)
    return AdaptiveParts(parts.flags, parts.minor, parts.header, sections).pack()


def _crafted() -> list[tuple[str, bytes, str | None]]:
    """(what, file, the rule it breaks or None for a valid file)."""
    original = _sample()
    parts = adaptive_parts(original)
    zstd = taken_apart(zstd_copy(original))
    u3_entry, u3_zstd = zstd.sections[zstd.index("U3")]
    planes = u3_entry["planes"]  # the zstd payload's (the fewest that hold its integers)
    u3 = parts.sections[parts.index("U3")][1]
    u1_planes = parts.sections[parts.index("U1")][0]["planes"]
    assert u1_planes >= 2  # so that one plane fewer breaks the bound
    # without predictor 2's pushes, which flag bit 3 also allows and R32 checks before coder
    pushless = [({k: v for k, v in e.items() if k != "mean_push"}, p) for e, p in parts.sections]
    unflagged = AdaptiveParts(parts.flags & ~8, parts.minor, parts.header, pushless)
    flagged_zstd = AdaptiveParts(zstd.flags | 8, 6, zstd.header, zstd.sections)
    fields = adaptive_parts(vector("v1.5-fields"))
    delta = adaptive_parts(vector("v1-wave-triangles"))
    assert delta.sections[delta.index("FACE")][0]["codec"] == "faces-delta"
    assert parts.sections[parts.index("FACE")][0]["codec"] == "faces-traverse"
    assert parts.sections[parts.index("FACE")][0].get("coder") == 1  # the encoder's choice
    zstd_faces = AdaptiveParts(parts.flags, parts.minor, zstd.header, zstd.sections)
    traversed = taken_apart(vector("v1.2-traverse-triangles"))  # FACE coder 0, no flag bit 3
    unflagged_faces = AdaptiveParts(
        traversed.flags, traversed.minor, traversed.header, traversed.sections
    )
    return [
        ("the copy", parts.pack(), None),
        ("flag bit 3 and no adaptive section", flagged_zstd.pack(), None),
        ("coder 0 on a zstd payload", _edited(parts, "U3", u3_zstd, coder=0, planes=planes), None),
        (
            "no coder on a zstd payload",
            _edited(parts, "U3", u3_zstd, coder=REMOVED, planes=planes),
            None,
        ),
        ("coder on a faces-delta FACE, ignored", _edited(delta, "FACE", coder=7), None),
        ("coder 7 on a faces-traverse FACE", _edited(parts, "FACE", coder=7), R46),
        ("coder 1.0 on a faces-traverse FACE", _edited(parts, "FACE", coder=1.0), R46),
        ("coder true on a faces-traverse FACE", _edited(parts, "FACE", coder=True), R46),
        ("coder 1 on FACE's zstd streams", _edited(zstd_faces, "FACE", coder=1), "R30-planes"),
        ("FACE's coder 1 without flag bit 3", _edited(unflagged_faces, "FACE", coder=1), R46),
        ("coder 0 on a field's factor", _edited(fields, "FLD.0.U1", coder=0), None),
        ("coder 1 on a field's factor", _edited(fields, "FLD.0.U1", coder=1), R46),
        ("coder 2", _edited(parts, "U3", coder=2), R46),
        ("coder 1.0", _edited(parts, "U3", coder=1.0), R46),
        ("coder true", _edited(parts, "U3", coder=True), R46),
        ("coder nil", _edited(parts, "U3", coder=None), R46),
        ("coder 1 without flag bit 3", unflagged.pack(), R46),
        ("planes before coder", _edited(parts, "U1", planes=0, coder=2), "R30-planes"),
        ("steps before coder", _edited(parts, "U1", steps=b"", coder=2), "R31-steps"),
        ("predict before coder", _edited(parts, "U1", predict=b"", coder=2), "R32-predictor"),
        ("coder 1 on a zstd payload", _edited(parts, "U3", u3_zstd, planes=planes), R46),
        ("a cut stream", _edited(parts, "U3", u3[:-1]), R46),
        ("a byte after the stream", _edited(parts, "U3", u3 + b"\0"), R46),
        ("integers beyond the planes", _edited(parts, "U1", planes=u1_planes - 1), R46),
    ]


def _judged(cases: list[tuple[str, bytes, str | None]], tmp_path: Path) -> list[Any]:
    """The cases whose verdicts differ between the decoders, or from what the case expects."""
    files = [data for _, data, _ in cases]
    differ, _, verdicts = compare_verdicts(files, tmp_path, lambda python, javascript: False)
    wrong: list[Any] = list(differ)
    for (what, _, rule), python in zip(cases, verdicts, strict=True):
        expected = {"accepted": True} if rule is None else {"accepted": False, "rule": rule}
        if {k: python.get(k) for k in expected} != expected:
            wrong.append((what, expected, python))
    return wrong


def test_coder_and_streams_are_checked_in_step_16s_order(tmp_path):
    """Each file breaks §6.14 in one way (or is valid): both decoders refuse it with the rule of
    the first check it fails in §5 step 16's order, planes, steps and predict before the coder,
    the coder before its stream; a coder is no parameter of faces-delta (ignored), one of
    faces-traverse (§6.8: 0, or 1 with flag bit 3 and planes 0), and a field's factors (1.5)
    keep zstd."""
    wrong = _judged(_crafted(), tmp_path)
    assert not wrong, wrong


def _damaged(base: bytes, rng: np.random.Generator) -> bytes:
    """``base`` (a file of 1.6) with one of its adaptive streams damaged, CRC made right: a
    byte changed, the stream cut or lengthened, or its entry's coder or planes changed."""
    parts = taken_apart(base)
    adaptive = [n for n, (entry, _) in enumerate(parts.sections) if entry.get("coder") == 1]
    n = int(rng.choice(adaptive))
    entry, payload = parts.sections[n]
    kind = int(rng.integers(0, 5))
    if kind <= 1:
        at = int(rng.integers(0, len(payload)))
        payload = (
            payload[:at]
            + bytes([(payload[at] + int(rng.integers(1, 256))) % 256])
            + payload[at + 1 :]
        )
    elif kind == 2:
        payload = payload[: int(rng.integers(0, len(payload)))]
    elif kind == 3:
        payload = payload + bytes(rng.integers(0, 256, size=int(rng.integers(1, 4))).tolist())
    else:
        entry = {**entry, "planes": int(rng.integers(0, 6)), "coder": int(rng.integers(0, 3))}
    parts.sections[n] = (entry, payload)
    return parts.pack()


def test_damaged_adaptive_streams_get_the_same_verdict(tmp_path):
    """The vectors of 1.6 with a stream damaged at seeded places: the same verdict from both
    decoders (R46 mostly; a damaged stream can also decode to other integers, accepted or
    refused later, R32, or for FACE's streams R39)."""
    rng = np.random.default_rng(46)
    files = [
        _damaged(vector(name), rng)
        for name in ["v1.6-adaptive", "v1.6-adaptive-segments", "v1.6-faces-adaptive"]
        for _ in range(DAMAGED_PER_VECTOR)
    ]
    differ, _, verdicts = compare_verdicts(files, tmp_path, lambda python, javascript: False)
    assert not differ, differ
    assert sum(v.get("rule") == R46 for v in verdicts) > len(files) // 2
