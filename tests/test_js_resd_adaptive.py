"""The JavaScript decoder's adaptive corrections (format 1.7, spec/FORMAT.md §6.9 with §6.14:
a RESD chunk stored as one adaptive stream, ``coder`` 1, preamble flag bit 4), in node.

Every file here is a twin: a file with corrections in zstd chunks (made by hand from the spec,
tests/support/corrections.py, with integers up to the ends of each domain's range, so that the
chunks need every number of planes from 1 to 8), and the same file with each chunk's stored
integers s re-coded as the spec's adaptive stream by the reference coder (K rows, a column per
frame and axis, in (t, x) order), ``coder`` 1 and flag bit 4. The twins hold the same integers,
so node must decode the adaptive one to the zstd one's bits, frame by frame, and restore the
same e. Then the twins edited to break §6.9's ``coder`` or §6.14's stream rules, and damaged at
seeded bytes, must get the Python decoder's verdict (and for the edits, the rule they break).
The stream decoder itself is checked integer for integer by tests/js/adaptive.test.mjs.
"""

from __future__ import annotations

import json
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zstandard

import tuckercodec
from tests.support.compressed import (
    Parts,
    SectionChange,
    edit_section,
    vector,
    with_params,
    with_preamble,
)
from tests.support.corrections import (
    Corrections,
    exact_reconstruction,
    float_targets,
    grid_targets,
    with_corrections,
)
from tests.support.js_decoder import compare_verdicts, run_node
from tuckercodec.internal import adaptive

R46 = "R46-adaptive-stream"
FLAG_ADAPTIVE_CORRECTIONS = 1 << 4
BASES = ["v1-wave-triangles", "v1.1-segments-shared"]
DOMAINS = ["grid", "float32", "float64"]
CASES = [(b, d, p) for b in BASES for d in DOMAINS for p in (0, 1)]
#: Damaged copies of each of a few adaptive twins.
DAMAGED_PER_FILE = 25


def _stored(piece: bytes, planes: int, count: int) -> np.ndarray:
    """A zstd chunk's stored integers s (count int64, §6.9 frame-major): the planes put back
    together and the zigzag undone."""
    raw = np.frombuffer(zstandard.ZstdDecompressor().decompress(piece), np.uint8)
    u = np.zeros(count, np.uint64)
    for p in range(planes):
        u |= raw[p * count : (p + 1) * count].astype(np.uint64) << np.uint64(8 * p)
    return ((u >> np.uint64(1)) ^ (np.uint64(0) - (u & np.uint64(1)))).view(np.int64)


def adaptive_twin(data: bytes) -> bytes:
    """``data`` (a file with corrections in zstd chunks) with every RESD chunk re-coded as one
    adaptive stream of the same integers and planes (§6.9, format 1.7): column 3t + x holds
    s[t, v, x] for the K vertices in ascending order."""
    parts = Parts(data)
    K = int(parts.header["vertices"])
    segments = parts.header.get("segments")
    sizes = [int(s["frames"]) for s in segments] if segments else [int(parts.header["frames"])]
    for index, (entry, payload) in enumerate(parts.sections):
        if entry["codec"] != "residual":
            continue
        frames = sizes[int(entry["id"].partition(".")[2] or 0)]
        L = min(int(entry["chunk_frames"]), frames)
        chunks, body, at = [], b"", 0
        for c, (planes, length) in enumerate(entry["chunks"]):
            n = min(L, frames - c * L)
            s = _stored(payload[at : at + length], planes, n * K * 3)
            at += length
            assert int(s.min(initial=0)) > np.iinfo(np.int64).min  # 64 bits: not codable
            columns = np.ascontiguousarray(s.reshape(n, K, 3).transpose(0, 2, 1)).reshape(-1, K)
            stream = adaptive.encode_columns(columns, adaptive.sequence_order(K))
            chunks.append([planes, len(stream)])
            body += stream
        parts.sections[index] = ({**entry, "coder": 1, "chunks": chunks}, body)
    return parts.pack()


def _zstd_file(base: str, domain: str, predict: int, seed: int) -> bytes:
    """``base`` with corrections in ``domain``, chunks of 1 to all frames, some with more
    planes than needed (up to 8)."""
    data = vector(base)
    rng = np.random.default_rng(seed)
    items = []
    for number, P in enumerate(exact_reconstruction(data)):
        if domain == "grid":
            e, _ = grid_targets(P, 1e-4 * (number + 1), rng)
            item = Corrections(e, "grid", step=1e-4 * (number + 1))
        else:
            e, _ = float_targets(P, 32 if domain == "float32" else 64, rng)
            item = Corrections(e, domain)
        item.predict = predict
        item.chunk_frames = [5, 1, 1 << 40][(number + seed) % 3]
        item.extra_planes = (number + seed) % 4
        items.append(item)
    return with_corrections(data, items)


def _run(jobs: list[dict[str, Any]], folder: Path) -> list[dict[str, Any]]:
    spec = folder / "jobs.json"
    spec.write_text(json.dumps(jobs))
    return run_node("corrections.mjs", spec)


@pytest.fixture(scope="module")
def twins(tmp_path_factory) -> dict[tuple[str, str, int], Any]:
    """Every case's twins, each decoded by node (every frame alone, backward, then every
    segment's restored integers)."""
    folder = tmp_path_factory.mktemp("twins")
    jobs, made = [], {}
    for n, case in enumerate(CASES):
        zstd = _zstd_file(*case, seed=n)
        made[case] = (zstd, adaptive_twin(zstd))
        for name, data in zip(("zstd", "adaptive"), made[case], strict=True):
            path = folder / f"case{n}.{name}.tkc"
            path.write_bytes(data)
            jobs.append(
                {"path": str(path), "out": str(folder / f"case{n}.{name}"), "order": "backward"}
            )
    results = _run(jobs, folder)
    return {
        case: (made[case], results[2 * n : 2 * n + 2], folder, n) for n, case in enumerate(CASES)
    }


@pytest.mark.parametrize("case", CASES, ids=["-".join(map(str, c)) for c in CASES])
def test_adaptive_twin_decodes_to_the_zstd_twins_bits(twins, case):
    (zstd, twin), results, folder, n = twins[case]
    assert all(r["accepted"] for r in results), [r.get("message") for r in results]
    assert [r["version"] for r in results] == ["1.3", "1.7"]
    assert [r["coder"] for r in results[1]["residual"]] == [1] * len(results[1]["residual"])
    assert [r["coder"] for r in results[0]["residual"]] == [0] * len(results[0]["residual"])
    zstd_bytes = (folder / f"case{n}.zstd").read_bytes()
    assert (folder / f"case{n}.adaptive").read_bytes() == zstd_bytes  # positions, then e
    # and those are the reference decoder's, from either twin
    expected = tuckercodec.decode(zstd).vertices.reshape(-1).view("<u8")
    assert np.array_equal(tuckercodec.decode(twin).vertices.reshape(-1).view("<u8"), expected)
    assert np.array_equal(np.frombuffer(zstd_bytes[: 8 * expected.size], "<u8"), expected)


def test_the_twins_have_chunks_of_every_planes(twins):
    """Chunks of 1 to 8 planes: both of the JavaScript decoder's paths (32-bit integers within
    4 planes, 64-bit ones past them) are taken."""
    planes = set()
    for (_, twin), _, _, _ in twins.values():
        for entry, _ in Parts(twin).sections:
            if entry["codec"] == "residual":
                planes |= {int(p) for p, _ in entry["chunks"]}
    assert planes == set(range(1, 9))


# ------------------------------------------------------------------------------------------
# one rule broken at a time, and damaged streams: the Python decoder's verdict


def _twin() -> bytes:
    """The adaptive twin of v1-wave-triangles with float64 corrections: 8 planes, 5 chunks."""
    return adaptive_twin(_zstd_file("v1-wave-triangles", "float64", 1, seed=2))


def _edit(data: bytes, change: SectionChange) -> bytes:
    return edit_section(data, "RESD", change)


_set = partial(with_params, "RESD")


def _first_chunk(change):
    """An edit of the first chunk: ``change(planes, stream)`` gives its new planes and bytes."""

    def edit(data: bytes) -> bytes:
        def section(entry: dict[str, Any], payload: bytes) -> tuple[dict[str, Any], bytes]:
            (planes, length), *rest = entry["chunks"]
            new_planes, stream = change(planes, payload[:length])
            chunks = [[new_planes, len(stream)], *rest]
            return {**entry, "chunks": chunks}, stream + payload[length:]

        return _edit(data, section)

    return edit


def _without_flag(data: bytes) -> bytes:
    flags = Parts(data).flags & ~FLAG_ADAPTIVE_CORRECTIONS
    return with_preamble(data, flags=flags)


#: name -> (edit of the twin, the rule it breaks, or None: accepted)
EDITS: dict[str, tuple[Any, str | None]] = {
    "coder-2": (_set(coder=2), R46),
    "coder-float": (_set(coder=1.0), R46),
    "coder-bool": (_set(coder=True), R46),
    "coder-string": (_set(coder="1"), R46),
    # `coder` comes right after `predict` (§5 step 18): before chunk_frames, after predict
    "coder-before-chunk-frames": (_set(coder=2, chunk_frames=0), R46),
    "predict-before-coder": (_set(coder=2, predict=2), "R40-residual"),
    # without flag bit 4, `coder` is an unknown parameter: the streams read as zstd frames
    "without-flag-bit-4": (_without_flag, "R29-zstd-content-size"),
    "planes-too-few": (_first_chunk(lambda planes, s: (planes - 1, s)), R46),
    "planes-more": (_first_chunk(lambda planes, s: (8, s)), None),
    "stream-cut": (_first_chunk(lambda planes, s: (planes, s[:-1])), R46),
    "stream-byte-after": (_first_chunk(lambda planes, s: (planes, s + b"\0")), R46),
    "stream-first-byte": (_first_chunk(lambda planes, s: (planes, b"\1" + s[1:])), R46),
    "stream-short": (_first_chunk(lambda planes, s: (planes, b"\0\0\0\0")), R46),
    # N_c integers from no bytes: more than 32768 per byte, refused before they are decoded
    "stream-empty": (_first_chunk(lambda planes, s: (planes, b"")), R46),
}


@pytest.mark.parametrize("name", list(EDITS))
def test_broken_rule_same_verdict_as_python(tmp_path, name):
    edit, rule = EDITS[name]
    data = edit(_twin())
    differ, _, (python,) = compare_verdicts([data], tmp_path, lambda p, j: False)
    assert not differ, differ
    assert python == ({"accepted": True} if rule is None else python | {"rule": rule}), python


def test_coder_zero_or_absent_with_flag_bit_4_reads_zstd(tmp_path):
    """With flag bit 4 a RESD `coder` of 0, or none, is §6.1's zstd planes: the same bits."""
    zstd = _zstd_file("v1-wave-triangles", "grid", 0, seed=4)
    flags = Parts(zstd).flags | FLAG_ADAPTIVE_CORRECTIONS
    files = [
        with_preamble(zstd, flags=flags, minor=7),
        _set(coder=0)(with_preamble(zstd, flags=flags)),
    ]
    jobs = [
        {"path": str(tmp_path / f"{n}.tkc"), "out": str(tmp_path / f"{n}.out")} for n in range(2)
    ]
    for job, data in zip(jobs, files, strict=True):
        Path(job["path"]).write_bytes(data)
    results = _run(jobs, tmp_path)
    assert all(r["accepted"] for r in results), [r.get("message") for r in results]
    expected = tuckercodec.decode(zstd).vertices.reshape(-1).view("<u8")
    for job in jobs:
        got = np.frombuffer(Path(job["out"]).read_bytes()[: 8 * expected.size], "<u8")
        assert np.array_equal(got, expected)


def test_damaged_streams_same_verdict_as_python(tmp_path):
    """Adaptive chunks with one byte changed at seeded places (the CRC made right): whatever the
    reference makes of each, accepted or refused with its rule, node makes of it too."""
    rng = np.random.default_rng(46)
    files = []
    for case in [("v1-wave-triangles", "float64", 1), ("v1-wave-triangles", "grid", 0)]:
        twin = adaptive_twin(_zstd_file(*case, seed=7))
        length = len(Parts(twin).sections[Parts(twin).index("RESD")][1])
        for _ in range(DAMAGED_PER_FILE):
            at, change = int(rng.integers(length)), int(rng.integers(1, 256))

            def damage(entry, payload, at=at, change=change):
                broken = bytearray(payload)
                broken[at] = (broken[at] + change) % 256
                return entry, bytes(broken)

            files.append(_edit(twin, damage))
    differ, _, verdicts = compare_verdicts(files, tmp_path, lambda p, j: False)
    assert not differ, differ
    rules = {v.get("rule") for v in verdicts}
    assert R46 in rules and None in rules, rules  # damage both refused and read through
