"""The JavaScript decoder's uniform ranks (format 1.9, spec/FORMAT.md §6.8: faces-traverse's
``ranks`` 1, preamble flag bit 6), in node.

Three kinds of file. Sheets whose vertices are numbered in a random order, encoded by the
reference encoder, which stores their new vertices as places in a uniform stream: node must give
the Python decoder's faces, row for row, and its positions (the same bits for a lossless file).
FACE sections made here from the spec alone (each new vertex's place among those not seen yet,
coded by the reference's uniform coder), on tables down to one vertex and up to K = 2^31, decoded
by both decoders' traversal alone: the same faces, or the same rule. Last, edits that break one
rule of ``ranks`` or of the uniform stream, damaged bytes, and a file without flag bit 6 (where
``ranks`` is an unknown parameter): node must give the Python decoder's verdict, and for the
edits the rule named here.
"""

from __future__ import annotations

import bisect
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import (
    Parts,
    SectionChange,
    edit_section,
    with_params,
    with_preamble,
)
from tests.support.js_decoder import compare_verdicts, decoded_file
from tests.test_js_topology import Cases, _tables
from tuckercodec.format import adaptive, traversal, uniform
from tuckercodec.io.samples import sheet_triangles, wave_sheet

FLAG_UNIFORM_RANKS = 1 << 6
R46, R39 = "R46-adaptive-stream", "R39-traversal"
TOLERANCE = 1e-9  # spec/FORMAT.md §8, relative to the largest |position|
VERTICES = traversal.STREAM_NAMES.index("vertices")
#: Damaged copies of the vertices stream of one encoded file.
DAMAGED = 40


def _quads(grid: int) -> np.ndarray:
    index = np.arange(grid * grid).reshape(grid, grid)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    return np.stack([a, b, c, d], -1).reshape(-1, 4)


def _scrambled(grid: int, frames: int = 5, quads: bool = False) -> tuckercodec.MeshSequence:
    """wave_sheet's sheet with its vertices renumbered at random: new vertex j is the sheet's
    vertex perm[j], so that no walk follows the file's order."""
    positions = wave_sheet(frames, grid)
    faces = _quads(grid) if quads else sheet_triangles(grid)
    perm = np.random.default_rng(grid).permutation(grid * grid)
    return tuckercodec.MeshSequence(positions[:, perm], np.argsort(perm)[faces])


#: name -> (grid, frames, quads, encode options)
ENCODED: dict[str, tuple[int, int, bool, dict[str, Any]]] = {
    "grid-6": (6, 5, False, {}),
    "grid-8-lossless": (8, 5, False, {"lossless": True}),
    "grid-12": (12, 5, False, {}),
    "grid-20-lossless": (20, 4, False, {"lossless": True}),
    "grid-40": (40, 4, False, {}),
    "quads-10": (10, 5, True, {}),
    "grid-9-segments": (9, 12, False, {"segment_frames": 4}),
}


def _encoded(name: str) -> bytes:
    grid, frames, quads, options = ENCODED[name]
    return tuckercodec.encode(_scrambled(grid, frames, quads), **options)


def _face(data: bytes) -> tuple[dict[str, Any], bytes]:
    parts = Parts(data)
    return parts.sections[parts.index("FACE")]


def _same_as_python(data: bytes, folder: Path, name: str, exact: bool) -> None:
    facts, faces, frames = decoded_file(data, folder, name)
    expected = tuckercodec.decode(data)
    assert facts["version"] == tuckercodec.info(data).format_version == "1.9"
    assert np.array_equal(faces, expected.faces)  # the same table, row for row
    if exact:  # a lossless file: the same bits (§8.1)
        assert np.array_equal(frames.view("<u8"), expected.vertices.view("<u8"))
        return
    scale = np.abs(expected.vertices).max()
    worst = np.abs(frames - expected.vertices).max()
    assert worst <= TOLERANCE * scale + 1e-12, f"largest difference {worst:.3g} of {scale:.3g}"


@pytest.mark.parametrize("name", list(ENCODED))
def test_encoded_scrambled_meshes(tmp_path, name):
    """The encoder stores these new vertices in a uniform stream (flag bit 6, ranks 1), and node
    decodes the file to the Python decoder's faces and positions."""
    data = _encoded(name)
    entry, _ = _face(data)
    assert Parts(data).flags & FLAG_UNIFORM_RANKS
    assert (entry["codec"], entry.get("coder"), entry.get("ranks")) == ("faces-traverse", 1, 1)
    _same_as_python(data, tmp_path, name, exact=ENCODED[name][3].get("lossless", False))


# ------------------------------------------------------------------------------------------
# FACE sections made from the spec, decoded by traversal alone


def _places(gaps: list[int]) -> list[int]:
    """Each new vertex's place among the vertices not seen before it (§6.8, ranks 1), from the
    walk's gaps w - last - 1."""
    seen: list[int] = []
    places, last = [], -1
    for gap in gaps:
        w = last + 1 + gap
        places.append(w - bisect.bisect_left(seen, w))
        bisect.insort(seen, w)
        last = w
    return places


def _walk_streams(faces: np.ndarray, vertices: int) -> tuple[list[list[int]], int]:
    """The four streams of the reference's walk (the vertices as gaps), and its corner order.

    The encoders size tables by K (the compiled core's, and the reference's about 2 GB at
    K = 2^31), so a table of a few vertices among very many is walked with its vertices
    renumbered 0, 1, ... in the same order, which gives the same ops (only which vertices are
    seen, and which is smallest, steer them), and its gaps are then taken between the true
    numbers. Such a table has no FAR: its references would be differences of numbers too."""
    used = np.unique(faces[faces >= 0])
    small = used.size < vertices // 2 and vertices > 1 << 16
    table = np.where(faces >= 0, np.searchsorted(used, faces), -1) if small else faces
    count = used.size if small else vertices
    params, payload, _ = traversal.encode_traversal(table, count)
    rows, width = params["shape"]
    coded, order = traversal.read_streams(payload, params, rows, width, count, "FACE")
    if small:
        assert not coded[3], "a renumbered table with FAR"
        news = np.cumsum(np.asarray(coded[VERTICES], np.int64) + 1) - 1  # w = last + 1 + gap
        true = used[news]
        coded[VERTICES] = (np.diff(true, prepend=np.int64(-1)) - 1).tolist()
    return coded, order


def _sections(
    coded: list[list[int]], shape: list[int], order: int, vertices: int
) -> tuple[tuple[dict[str, Any], bytes], tuple[dict[str, Any], bytes]]:
    """The same streams with ``coder`` 1, the new vertices once as adaptive ranks and once as
    places in a uniform stream (``ranks`` 1): ``(params, payload)`` of each."""
    places = _places(coded[VERTICES])
    ranks = np.diff(np.asarray(places, np.int64), prepend=np.int64(0)).tolist()
    streams_ = [*coded[:VERTICES], ranks, *coded[VERTICES + 1 :]]
    count, width = shape
    ranked, payload = traversal.pack_streams(
        streams_, count, width, order, 19, adaptive.CODER_ADAPTIVE
    )
    pieces, at = [], 0
    for _, _, length in ranked["streams"]:
        pieces.append(payload[at : at + length])
        at += length
    pieces[VERTICES] = uniform.encode_uniform(np.asarray(places, np.int64), vertices)
    table = [list(entry) for entry in ranked["streams"]]
    table[VERTICES] = [len(places), 0, len(pieces[VERTICES])]
    params = {
        "shape": list(shape),
        "corner_order": order,
        "coder": adaptive.CODER_ADAPTIVE,
        "ranks": 1,
        "streams": table,
    }
    return (ranked, payload), (params, b"".join(pieces))


def _small_tables() -> dict[str, tuple[np.ndarray, int]]:
    """Tables at the ends of a uniform stream's range: one, two and three vertices (the last
    place of each stream has n = 1 and takes no bit), no face at all, a face among many
    isolated vertices, and K = 2^31 (places of 31 bits, n = 2^k exactly)."""
    last = (1 << 31) - 1
    return {
        "one-vertex": (np.array([[0, 0, 0]]), 1),
        "two-vertices": (np.array([[0, 1, 1]]), 2),
        "three-vertices": (np.array([[2, 0, 1]]), 3),
        "three-vertices-two-faces": (np.array([[2, 0, 1], [1, 0, 2]]), 3),
        "no-faces": (np.zeros((0, 3), np.int64), 5),
        "no-faces-no-vertices": (np.zeros((0, 3), np.int64), 0),
        "isolated-vertices": (np.array([[700, 3, 999]]), 1000),
        "k-2-31": (np.array([[last, 0, 1 << 30], [0, last, last - 1]]), 1 << 31),
    }


def test_hand_made_sections(tmp_path):
    """Every table both ways (adaptive ranks, and places in a uniform stream) in a file with
    flag bit 6, and the adaptive one also with ``ranks`` 0: node gives the reference's faces,
    which are the walk's."""
    cases = Cases(tmp_path)
    names = []
    for name, (faces, vertices) in {**_tables(), **_small_tables()}.items():
        coded, order = _walk_streams(faces, vertices)
        shape = list(faces.shape) if faces.size else [0, 3]
        (ranked, ranked_payload), (params, payload) = _sections(coded, shape, order, vertices)
        cases.traverse(name, params, payload, vertices, adaptive=True, uniform=True)
        cases.traverse(f"{name}-adaptive", ranked, ranked_payload, vertices, None, True, True)
        zero = {**ranked, "ranks": 0}
        cases.traverse(f"{name}-ranks-0", zero, ranked_payload, vertices, None, True, True)
        names.append(name)
    results = cases.check()
    for name in names:
        assert cases.expected[name][0] == "ok", (name, results[name])
        assert cases.expected[name] == cases.expected[f"{name}-adaptive"], name
        assert cases.expected[name] == cases.expected[f"{name}-ranks-0"], name
    # one more vertex than 2^31: ranks 1 is R46 before any stream is read
    faces, vertices = _small_tables()["k-2-31"]
    coded, order = _walk_streams(faces, vertices)
    _, (params, payload) = _sections(coded, list(faces.shape), order, vertices)
    cases = Cases(tmp_path)
    cases.traverse("k-above-2-31", params, payload, vertices + 1, None, True, True)
    results = cases.check()
    assert results["k-above-2-31"]["rule"] == R46


# ------------------------------------------------------------------------------------------
# one rule broken at a time, damaged streams, and a file without flag bit 6


def _base() -> bytes:
    return _encoded("grid-8-lossless")


def _edit(data: bytes, change: SectionChange) -> bytes:
    return edit_section(data, "FACE", change)


_set = partial(with_params, "FACE")


def _drop(key: str):
    return lambda data: _edit(
        data, lambda entry, payload: ({k: v for k, v in entry.items() if k != key}, payload)
    )


def _vertices_stream(change):
    """An edit of the vertices stream: ``change(count, stream)`` gives its new count and bytes."""

    def edit(data: bytes) -> bytes:
        def section(entry: dict[str, Any], payload: bytes) -> tuple[dict[str, Any], bytes]:
            table = [list(item) for item in entry["streams"]]
            start = sum(length for _, _, length in table[:VERTICES])
            count, planes, length = table[VERTICES]
            new_count, stream = change(count, payload[start : start + length])
            table[VERTICES] = [new_count, planes, len(stream)]
            body = payload[:start] + stream + payload[start + length :]
            return {**entry, "streams": table}, body

        return _edit(data, section)

    return edit


def _without_flag(data: bytes) -> bytes:
    """The file with flag bit 6 cleared (minor 8): ``ranks`` is then an unknown parameter."""
    return with_preamble(data, flags=Parts(data).flags & ~FLAG_UNIFORM_RANKS, minor=8)


#: name -> (edit of the encoded file, the rule the reference gives it)
EDITS: dict[str, tuple[Any, str]] = {
    "ranks-2": (_set(ranks=2), R46),
    "ranks-float": (_set(ranks=1.0), R46),
    "ranks-bool": (_set(ranks=True), R46),
    "ranks-negative": (_set(ranks=-1), R46),
    "ranks-string": (_set(ranks="1"), R46),
    "ranks-nil": (_set(ranks=None), R46),
    "ranks-huge": (_set(ranks=2**64 - 1), R46),
    "ranks-with-coder-0": (_set(coder=0), R46),
    "ranks-without-coder": (_drop("coder"), R46),
    # `ranks` right after `coder`, before the streams table (§5 step 15)
    "coder-before-ranks": (_set(coder=2, ranks=2), R46),
    "corner-order-before-ranks": (_set(corner_order=2, ranks=2), R39),
    "ranks-before-streams": (_set(ranks=2, streams=[]), R46),
    "stream-cut": (_vertices_stream(lambda count, s: (count, s[:-1])), R46),
    "stream-byte-after": (_vertices_stream(lambda count, s: (count, s + b"\0")), R46),
    "stream-first-byte": (_vertices_stream(lambda count, s: (count, b"\1" + s[1:])), R46),
    "stream-short": (_vertices_stream(lambda count, s: (count, b"\0\0\0\0")), R46),
    # 64 places from no bytes: more than 32768 per byte, refused before they are decoded
    "stream-empty": (_vertices_stream(lambda count, s: (count, b"")), R46),
    # a place fewer: the last of K places (n = 1) takes no bit, so the stream reads through
    # and the walk runs out of new vertices
    "stream-count-less": (_vertices_stream(lambda count, s: (count - 1, s)), R39),
    "stream-count-more": (_vertices_stream(lambda count, s: (count + 1, s)), R39),
    # without ranks (0, or absent) the places are read as an adaptive stream of ranks, which
    # here ends with bytes left over
    "ranks-0": (_set(ranks=0), R46),
    "ranks-absent": (_drop("ranks"), R46),
    # without flag bit 6, ranks is an unknown parameter: the same as absent
    "without-flag-bit-6": (_without_flag, R46),
}


@pytest.mark.parametrize("name", list(EDITS))
def test_broken_rule_same_verdict_as_python(tmp_path, name):
    edit, rule = EDITS[name]
    data = edit(_base())
    differ, _, (python,) = compare_verdicts([data], tmp_path, lambda p, j: False)
    assert not differ, differ
    assert python == {"accepted": False, "rule": rule, "kind": "FormatError"}, python


def test_unknown_ranks_is_ignored_without_flag_bit_6(tmp_path):
    """A file without flag bit 6 whose FACE says ``ranks`` 1 over adaptive ranks: both decoders
    ignore the parameter, and give the faces and positions of the file with flag bit 6."""
    data = _base()
    entry, payload = _face(data)
    count, width = entry["shape"]
    K = int(Parts(data).header["vertices"])
    coded, order = traversal.read_streams(
        payload, entry, count, width, K, "FACE", adaptive_coding=True, uniform_ranks=True
    )
    (ranked, ranked_payload), _ = _sections(coded, [count, width], order, K)
    edited = _edit(data, lambda old, _: ({**old, **ranked, "ranks": 1}, ranked_payload))
    edited = _without_flag(edited)
    assert not Parts(edited).flags & FLAG_UNIFORM_RANKS
    assert _face(edited)[0]["ranks"] == 1
    facts, faces, frames = decoded_file(edited, tmp_path, "without-bit-6")
    assert facts["version"] == "1.8"
    expected = tuckercodec.decode(data)
    assert np.array_equal(tuckercodec.decode(edited).faces, expected.faces)
    assert np.array_equal(faces, expected.faces)
    assert np.array_equal(frames.view("<u8"), expected.vertices.view("<u8"))


def test_damaged_streams_same_verdict_as_python(tmp_path):
    """The uniform stream with one byte changed at seeded places (the CRC made right): whatever
    the reference makes of each, accepted or refused with its rule, node makes of it too."""
    rng = np.random.default_rng(64)
    files = []
    for name in ("grid-8-lossless", "quads-10"):
        data = _encoded(name)
        length = _face(data)[0]["streams"][VERTICES][2]
        for _ in range(DAMAGED):
            at, change = int(rng.integers(length)), int(rng.integers(1, 256))

            def damage(count: int, stream: bytes, at: int = at, change: int = change) -> Any:
                broken = bytearray(stream)
                broken[at] = (broken[at] + change) % 256
                return count, bytes(broken)

            files.append(_vertices_stream(damage)(data))
    differ, _, verdicts = compare_verdicts(files, tmp_path, lambda p, j: False)
    assert not differ, differ
    rules = {v.get("rule") for v in verdicts}
    assert R46 in rules, rules
