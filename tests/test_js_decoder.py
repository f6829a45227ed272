"""The JavaScript decoder (tuckercodec/web/tkc/) against the Python decoder, in node: the same
faces and frames on real sequences (the built-in sample and ../shared/data, whole and in
segments), and the same verdict, rule for rule, on files damaged in every part (the vectors'
own checks are in test_js_conformance.py)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import Parts, vector
from tests.support.js_decoder import compare_verdicts, decoded_file, run_node
from tests.support.sequences import shared_case, shared_encoded
from tuckercodec.format.container import HEAD_SIZE, PREAMBLE, SIGNATURE, pack_raw
from tuckercodec.io.samples import sample_path

TOLERANCE = 1e-9  # spec/FORMAT.md §8, relative to the largest |position|
VECTORS = Path(__file__).resolve().parents[1] / "spec" / "vectors"
VALID_VECTORS = [
    "v1-wave-triangles",
    "v1-polygons-names",
    "v1-ignorable-extensions",
    "v1.1-segments-shared",
    "v1.1-segments-own",
    "v1.2-traverse-triangles",
    "v1.2-traverse-polygons-segments",
    "v1.3-bound-grid",
    "v1.3-lossless-float32",
    "v1.3-lossless-float64",
]


def _same_as_python(data: bytes, tmp_path: Path) -> dict[str, Any]:
    facts, faces, frames = decoded_file(data, tmp_path, "in")
    expected = tuckercodec.decode(data)
    assert facts["version"] == tuckercodec.info(data).format_version
    assert facts["names"] == list(expected.frame_names)
    assert np.array_equal(faces, expected.faces)  # the same table, row for row
    scale = np.abs(expected.vertices).max()
    worst = np.abs(frames - expected.vertices).max()
    assert worst <= TOLERANCE * scale + 1e-12, f"largest difference {worst:.3g} of {scale:.3g}"
    return facts


@pytest.mark.parametrize("segment_frames", [None, 16], ids=["whole", "segments"])
def test_sample(tmp_path, segment_frames):
    """The built-in cloth at KG 0.1, whole (format 1.2) and in shared-basis segments."""
    sequence = tuckercodec.load_sequence(sample_path())
    data = tuckercodec.encode_with_report(
        sequence, target_kg=0.1, segment_frames=segment_frames
    ).data
    facts = _same_as_python(data, tmp_path)
    assert facts["frames"] == 60


def test_sample_own_bases(tmp_path):
    sequence = tuckercodec.load_sequence(sample_path())
    data = tuckercodec.encode_with_report(
        sequence, target_kg=0.5, segment_frames=20, basis="own"
    ).data
    _same_as_python(data, tmp_path)


@pytest.mark.parametrize(
    "name",
    [shared_case(s) for s in ["samba.npz", "chicken.npz", "horse-gallop", "cloth-vellum.npz"]],
)
def test_shared_sequences(tmp_path, name):
    """The real sequences at KG 0.1: polygons, boundaries, 1.2's predictors on real meshes."""
    _same_as_python(shared_encoded(name).data, tmp_path)


def test_simd_and_the_javascript_loop_give_the_same_bits(tmp_path):
    """reconstruct.js: WebAssembly SIMD (two vertices a lane each) and the plain loop add the
    same products in the same order, so every frame is the same bits either way: the valid
    vectors (a shared basis with fewer columns used, own bases, polygons) and the sample."""
    paths = [VECTORS / f"{name}.tkc" for name in VALID_VECTORS]
    sample = tmp_path / "sample.tkc"
    sequence = tuckercodec.load_sequence(sample_path())
    sample.write_bytes(
        tuckercodec.encode_with_report(sequence, target_kg=0.1, segment_frames=16).data
    )  # four segments of one shared basis
    results = run_node("simd_same.mjs", *paths, sample)
    assert all(r["simd"] for r in results), "node runs WebAssembly SIMD (node 16 and newer)"
    assert [r["differ"] for r in results] == [0] * len(results)
    assert all(r["values"] > 0 for r in results)


# ------------------------------------------------------------------------------------------
# damaged files: the same verdict from both decoders

BASES = [
    "v1-wave-triangles",
    "v1-polygons-names",
    "v1.1-segments-shared",
    "v1.1-segments-own",
    "v1.2-traverse-triangles",
    "v1.2-traverse-polygons-segments",
    "v1.3-bound-grid",
    "v1.3-lossless-float64",
]
CASES_PER_BASE = 80


def _mutate_payload(parts: Parts, rng: np.random.Generator) -> bytes:
    """A few bits of one section flipped, its CRC made right: the codecs' own checks."""
    index = int(rng.integers(len(parts.sections)))
    entry, payload = parts.sections[index]
    damaged = bytearray(payload)
    if damaged:
        for _ in range(int(rng.integers(1, 4))):
            damaged[int(rng.integers(len(damaged)))] ^= 1 << int(rng.integers(8))
    parts.sections[index] = (entry, bytes(damaged))
    return parts.pack()


def _mutate_parameter(parts: Parts, rng: np.random.Generator) -> bytes:
    """One codec parameter of one section changed."""
    index = int(rng.integers(len(parts.sections)))
    entry, payload = parts.sections[index]
    entry = dict(entry)
    key = str(rng.choice([k for k in entry if k not in ("id", "critical", "codec")] or ["id"]))
    value = entry.get(key)
    if isinstance(value, bytes) and value:
        damaged = bytearray(value)
        damaged[int(rng.integers(len(damaged)))] = int(rng.integers(256))
        entry[key] = bytes(damaged)
    elif isinstance(value, int) and not isinstance(value, bool):
        entry[key] = value + int(rng.choice([-2, -1, 1, 2, 1 << 20]))
    elif isinstance(value, list):
        flat = json.loads(json.dumps(value))
        target = flat
        while isinstance(target, list) and target and isinstance(target[0], list):
            target = target[int(rng.integers(len(target)))]
        if target:
            target[int(rng.integers(len(target)))] += int(rng.choice([-1, 1, 7]))
        entry[key] = flat
    else:
        entry[key] = None
    parts.sections[index] = (entry, payload)
    return parts.pack()


def _mutate_header(data: bytes, rng: np.random.Generator) -> bytes:
    """Bytes of the msgpack header changed, both CRCs made right: the header's own checks."""
    major, minor, flags, header_length, _ = PREAMBLE.unpack_from(data, len(SIGNATURE))
    header = bytearray(data[HEAD_SIZE : HEAD_SIZE + header_length])
    for _ in range(int(rng.integers(1, 3))):
        header[int(rng.integers(len(header)))] = int(rng.integers(256))
    body = data[HEAD_SIZE + header_length + 4 :]
    return pack_raw(major, minor, flags, bytes(header), body)


def _mutate_fields(parts: Parts, rng: np.random.Generator) -> bytes:
    """A header field changed in type or value."""
    key = str(rng.choice([k for k in parts.header if k != "error"]))
    value = parts.header[key]
    choices: list[Any] = [None, 0, -1, 2**40, 1.5, "x", [1, 2]]
    if isinstance(value, list) and value:
        value = list(value)
        at = int(rng.integers(len(value)))
        value[at] = choices[int(rng.integers(len(choices)))] if rng.random() < 0.5 else 0
        parts.header[key] = value
    else:
        parts.header[key] = choices[int(rng.integers(len(choices)))]
    return parts.pack()


def _damaged_files() -> list[bytes]:
    rng = np.random.default_rng(14)
    files = []
    for name in BASES:
        base = vector(name)
        for case in range(CASES_PER_BASE):
            kind = case % 4
            if kind == 0:
                files.append(_mutate_payload(Parts(base), rng))
            elif kind == 1:
                files.append(_mutate_parameter(Parts(base), rng))
            elif kind == 2:
                files.append(_mutate_header(base, rng))
            else:
                files.append(_mutate_fields(Parts(base), rng))
    return files


def test_damaged_files_same_verdict(tmp_path):
    files = _damaged_files()
    differ, zstd_only, verdicts = compare_verdicts(files, tmp_path, _zstd_strictness)
    rejected = sum(not verdict["accepted"] for verdict in verdicts)
    assert not differ, f"{len(differ)} of {len(files)} verdicts differ: {differ[:5]}"
    # 11 of these 640 cases (all payload damage): libzstd and fzstd each refuse some the other takes
    assert len(zstd_only) <= len(files) // 25, f"zstd disagrees too often: {zstd_only}"
    assert rejected > len(files) // 2  # the damage reaches the checks, not only valid edits


#: Rules checked on integers a stream decoded to: a decoder whose zstd took a corrupt frame can
#: meet one of them where the other refused the frame (R29).
LATER_RULES = {
    "R32-predictor",
    "R33-face-index",
    "R34-face-padding",
    "R35-names",
    "R36-reconstruction-finite",
    "R39-traversal",
    "R41-residual-value",
}


def _zstd_strictness(python: dict[str, Any], javascript: dict[str, Any]) -> bool:
    """A corrupt Zstandard frame that one decoder's zstd notices and the other's does not
    (libzstd accepts some entropy-coded streams that do not end where RFC 8878 says, which fzstd
    refuses): spec/FORMAT.md §6.1 says both verdicts can occur, and the decoder that took the
    frame can then refuse the integers it got (in 1.3, U1's integers bound §8.1's weights, R41);
    any other difference is a bug."""
    verdicts = [python, javascript]
    refused = [v for v in verdicts if v.get("rule") == "R29-zstd-content-size"]
    others = [v for v in verdicts if v.get("rule") != "R29-zstd-content-size"]
    return len(refused) == 1 and (others[0]["accepted"] or others[0].get("rule") in LATER_RULES)
