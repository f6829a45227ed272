"""The compiled core's faces-traverse walks (§6.8) against the pure-Python reference: the same
streams from the encoder, the same faces from the decoder, and for a broken walk the same error
(rule, field and message), on the conformance vectors, the shared sequences, random meshes and
thousands of damaged stream sets."""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import shared_sequence
from tests.test_format_traversal import grid
from tuckercodec import Decoder
from tuckercodec.errors import TuckerCodecError
from tuckercodec.format import faces as face_sections
from tuckercodec.format import traversal, unseen
from tuckercodec.system import native

pytestmark = pytest.mark.skipif(
    native.core() is None,
    reason="the compiled core is not installed (python -m tools.build_native), or "
    "TUCKERCODEC_NATIVE=0",
)

VECTORS = sorted((Path(__file__).resolve().parents[1] / "spec" / "vectors").glob("*.json"))
SHARED = ["chicken.npz", "samba.npz", "horse-gallop", "cloth-vellum.npz"]


def outcome(run: Callable[[], Any]) -> Any:
    """What ``run`` gives, as plain values, or the error it raises (class, rule, field,
    message)."""
    try:
        result = run()
    except TuckerCodecError as error:
        rule, field = getattr(error, "rule", None), getattr(error, "field", None)
        return type(error).__name__, rule, field, str(error)
    if isinstance(result, np.ndarray):
        return result.dtype.str, result.shape, result.tolist()
    return result


def both(run: Callable[[], Any]) -> tuple[Any, Any]:
    """The outcome of ``run`` with the compiled core, and in pure Python."""
    compiled = outcome(run)
    with native.pure_python():
        reference = outcome(run)
    return compiled, reference


def streams_of(walk: traversal._Streams) -> list[list[int]]:
    """A walk's streams and order as lists (the core gives arrays, Python lists)."""
    parts = [*walk.ops, walk.degrees, walk.new_residuals, walk.references, walk.order]
    return [np.asarray(part, dtype=np.int64).tolist() for part in parts]


def walked_streams(table: np.ndarray, k: int) -> list[list[int]]:
    """The encoder's walk of ``table``, the same both ways."""
    table = np.asarray(table, dtype=np.int64)
    compiled, reference = both(lambda: streams_of(traversal._walked(table, len(table), k)))
    assert compiled == reference
    return compiled


def decoded_both_ways(
    values: list[list[int]], count: int, width: int, k: int, corner_order: int
) -> Any:
    """The decoder's walk of the stream ``values``: the same faces or error both ways."""
    arrays = [np.array(stream, dtype=np.int64) for stream in values]
    compiled, reference = both(
        lambda: traversal.walk_streams(arrays, count, width, k, corner_order, "section FACE")
    )
    assert compiled == reference, (values, count, width, k, corner_order)
    return compiled


def check_round_trip(table: np.ndarray, k: int) -> None:
    """Encoder streams, encoded section (params and bytes) and decoded faces: the same both
    ways; and the faces decode back as the encoder says."""
    table = np.asarray(table, dtype=np.int64)
    streams = walked_streams(table, k)
    count, width = table.shape
    for corner_order in (0, 1):
        values = [streams[corner_order], streams[2], streams[3], streams[4]]
        decoded = decoded_both_ways(values, count, width, k, corner_order)
        assert decoded[2] == table[streams[5]].tolist()
    compiled, reference = both(lambda: traversal.encode_traversal(table, k, 3))
    assert compiled[:2] == reference[:2]
    assert np.array_equal(compiled[2], reference[2])
    check_ranks(streams[3], k)


def check_ranks(new_residuals: list[int], k: int) -> None:
    """The NEW vertices' ranks among the unseen (coder 1, format 1.6) and the vertices back
    from them: the same both ways."""
    placed = unseen.vertices_from_gaps(np.array(new_residuals, dtype=np.int64))
    compiled, reference = both(lambda: unseen.ranks_of(placed, k))
    assert compiled == reference
    ranks = np.array(compiled[2], dtype=np.int64)
    compiled, reference = both(lambda: unseen.vertices_of(ranks, k))
    assert compiled == reference
    assert compiled[2] == placed.tolist()


def check_adaptive_round_trip(table: np.ndarray, k: int) -> None:
    """The section the encoder writes where coder 1 is allowed, the same bytes both ways (the
    ranks, the adaptive streams and the choice), decoded to the same faces both ways."""

    def encoded() -> tuple[dict[str, Any], bytes, list[list[int]]]:
        params, payload, walked = traversal.encode_traversal(table, k, 3, adaptive_coding=True)
        return params, payload, walked.tolist()

    compiled, reference = both(encoded)
    assert compiled == reference
    params, payload, walked = compiled
    decoded = both(
        lambda: traversal.decode_traversal(payload, params, k, "FACE", adaptive_coding=True)
    )
    assert decoded[0] == decoded[1]
    assert decoded[0][2] == walked


# ------------------------------------------------------------------------- the conformance vectors


def test_every_faces_traverse_section_of_the_vectors(monkeypatch):
    """Every FACE section of codec faces-traverse that a vector's decode reaches, valid or not,
    decodes to the same faces or fails the same way; and the decoders agree on every vector."""
    sections: list[tuple[Any, ...]] = []
    decode = traversal.decode_traversal  # the function faces.py calls

    def recorded(*args: Any, **kwargs: Any) -> np.ndarray:
        sections.append((args, kwargs))
        return decode(*args, **kwargs)

    monkeypatch.setattr(face_sections, "decode_traversal", recorded)
    for path in VECTORS:
        expected = json.loads(path.read_text())
        data = (path.parent / expected["file"]).read_bytes()
        compiled, reference = both(partial(_opened, data))
        assert compiled == reference, path.name
    assert sections, "no vector has a faces-traverse FACE section"
    for args, kwargs in sections:
        compiled, reference = both(partial(decode, *args, **kwargs))
        assert compiled == reference


def _opened(data: bytes) -> Any:
    """The faces of a file and its first frame, or the error that opening it raises."""
    decoder = Decoder(data)
    faces = decoder.faces
    return None if faces is None else np.asarray(faces).tolist(), decoder.frame(0).tolist()


# ----------------------------------------------------------------------- the shared sequences


@pytest.mark.parametrize("name", SHARED)
def test_the_shared_sequences_walk_the_same_both_ways(name):
    sequence = shared_sequence(name)
    check_round_trip(np.asarray(sequence.faces), sequence.vertex_count)


@pytest.mark.parametrize("name", SHARED[1:3])
def test_the_shared_sequences_code_the_same_with_coder_1_both_ways(name):
    """Coder 1 is chosen on real meshes: the same bytes and faces from the core and Python."""
    sequence = shared_sequence(name)
    faces = np.asarray(sequence.faces, dtype=np.int64)
    assert (
        traversal.encode_traversal(faces, sequence.vertex_count, adaptive_coding=True)[0]["coder"]
        == 1
    )
    check_adaptive_round_trip(faces, sequence.vertex_count)


# --------------------------------------------------------------------------------- random meshes


def random_mesh(rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """A face table and its vertex count: a soup of triangles or polygons on few vertices (edges
    of many faces, both orientations, repeated corners), or grids (boundaries, several
    components) shuffled, renumbered and with vertices on no face."""
    kind = int(rng.integers(4))
    if kind == 0:  # a triangle soup
        k = int(rng.integers(3, 12))
        return rng.integers(0, k, size=(int(rng.integers(1, 30)), 3)), k
    if kind == 1:  # a polygon soup, padded
        k, width = int(rng.integers(3, 10)), int(rng.integers(3, 7))
        rows = [
            rng.integers(0, k, size=int(rng.integers(3, width + 1))).tolist()
            for _ in range(int(rng.integers(1, 25)))
        ]
        return np.array([row + [-1] * (width - len(row)) for row in rows]), k
    quads = kind == 3
    parts, k = [], 0
    for _ in range(int(rng.integers(1, 4))):
        n = int(rng.integers(2, 6))
        parts.append(grid(n, quads) + k)
        k += n * n
    faces = np.concatenate(parts)
    k += int(rng.integers(0, 3))  # vertices on no face
    relabel = rng.permutation(k)
    faces = relabel[faces][rng.permutation(len(faces))]
    if rng.random() < 0.3:  # some faces turned over: an edge met in both orientations
        flip = rng.random(len(faces)) < 0.3
        faces[flip] = faces[flip][:, ::-1]
    return faces, k


def test_random_meshes_walk_the_same_both_ways():
    rng = np.random.default_rng(20261204)
    for _ in range(300):
        faces, k = random_mesh(rng)
        check_round_trip(faces, k)


def test_random_meshes_code_the_same_with_coder_1_both_ways():
    rng = np.random.default_rng(16)
    for _ in range(60):
        faces, k = random_mesh(rng)
        check_adaptive_round_trip(np.asarray(faces, dtype=np.int64), k)


def test_random_ranks_name_the_same_vertices_or_fail_the_same_both_ways():
    """Ranks of any value, K of any size (a table of nodes or a hash map): the same vertices,
    or the same first rank refused (as R39-traversal's detail)."""
    rng = np.random.default_rng(39)
    refused = 0
    for _ in range(2000):
        k = int(rng.choice([0, 1, 2, 5, 17, 1000, 2**40]))
        ranks = rng.integers(-4, 6, size=int(rng.integers(0, 12)))
        if rng.random() < 0.2 and ranks.size:
            ranks[0] = int(rng.integers(0, max(k, 1)))
        compiled, reference = both(partial(_placed, ranks, k))
        assert compiled == reference, (ranks, k)
        refused += isinstance(compiled, str)
    assert 100 < refused < 1900


def _placed(ranks: np.ndarray, k: int) -> Any:
    try:
        return unseen.vertices_of(ranks, k).tolist()
    except unseen.RankError as error:
        return str(error)


def test_fans_and_tables_the_core_hands_back_to_python():
    """Fans (an edge of many faces), a table with a row of fewer than 3 corners and a vertex
    beyond K (the core hands those back to the reference), and no faces at all."""
    tips = np.arange(2, 402)
    fan = np.stack([np.zeros_like(tips), np.ones_like(tips), tips], axis=1)
    check_round_trip(fan, 402)
    fan[1::2, :2] = fan[1::2, 1::-1]
    check_round_trip(fan, 402)
    for table, k in (
        (np.array([[0, 1, 2, -1], [2, 1, -1, -1]]), 3),
        (np.array([[0, 1, 2], [2, 1, 5]]), 4),
        (np.zeros((0, 3), dtype=np.int64), 4),
    ):
        compiled, reference = both(partial(_encoded, table, k))
        assert compiled == reference


def _encoded(table: np.ndarray, k: int) -> Any:
    try:
        params, payload, walked = traversal.encode_traversal(table, k, 3)
    except IndexError as error:
        return "IndexError", str(error)
    return params, payload, walked.tolist()


# --------------------------------------------------------------------------- damaged streams


def damaged(values: list[list[int]], rng: np.random.Generator) -> list[list[int]]:
    """``values`` with one to three changes: a value moved, replaced, removed or added, or a
    stream emptied or cut short."""
    out = [list(stream) for stream in values]
    for _ in range(int(rng.integers(1, 4))):
        stream = out[int(rng.choice([0, 0, 0, 1, 2, 2, 3]))]
        change = int(rng.integers(7))
        position = int(rng.integers(len(stream))) if stream else 0
        if change == 5:
            stream.clear()
        elif change == 6:
            del stream[position:]
        elif change == 4 or not stream:
            stream.insert(position, int(rng.integers(-3, 30)))
        elif change == 0:
            stream[position] += int(rng.choice([-8, -2, -1, 1, 2, 4, 8, 24]))
        elif change == 1:
            stream[position] = int(rng.integers(-3, 40))
        elif change == 2:
            del stream[position]
        else:
            # the extremes a stream holds (at most 4 planes: 32 bits after zigzag)
            stream[position] = int(rng.choice([-(2**31), 2**31 - 1]))
    return out


def test_thousands_of_damaged_stream_sets_decode_or_fail_the_same_both_ways():
    rng = np.random.default_rng(7)
    failures: set[str] = set()
    decoded = 0
    for _ in range(60):
        faces, k = random_mesh(rng)
        streams = walked_streams(faces, k)
        count, width = faces.shape
        for _ in range(60):
            corner_order = int(rng.integers(2))
            values = [streams[corner_order], streams[2], streams[3], streams[4]]
            values = damaged(values, rng) if rng.random() < 0.9 else values
            shape_k = (count + int(rng.choice([0, 0, 0, -1, 1])), width, k)
            if rng.random() < 0.1:
                shape_k = (count, width, k + int(rng.choice([-3, -1, 1, 1000])))
            result = decoded_both_ways(values, *shape_k, corner_order)
            if len(result) == 4:
                failures.add(result[3].split("breaks: ")[-1][:14])
            else:
                decoded += 1
    assert decoded > 100 and len(failures) >= 8, failures  # faces, and many kinds of failure


def test_random_stream_values_decode_or_fail_the_same_both_ways():
    """Streams of random values: mostly broken walks, every kind of first error."""
    rng = np.random.default_rng(3)
    for _ in range(1500):
        count, width = int(rng.integers(0, 6)), int(rng.integers(3, 6))
        k = int(rng.integers(0, 9))
        values = [
            rng.integers(-2, 8 * width + 2, size=int(rng.integers(0, 4 * count + 3))).tolist(),
            rng.integers(-1, 3, size=count if rng.random() < 0.4 else 0).tolist(),
            rng.integers(-2, 4, size=int(rng.integers(0, 8))).tolist(),
            rng.integers(-5, 5, size=int(rng.integers(0, 5))).tolist(),
        ]
        decoded_both_ways(values, count, width, k, int(rng.integers(2)))


def test_a_broken_section_raises_the_same_error_both_ways():
    """Through decode_traversal: the core's error is raised again as the reference's
    FormatError, with its rule, field and message."""
    faces, k = grid(5), 25
    params, payload, _ = traversal.encode_traversal(faces, k)
    values, corner_order = traversal.read_streams(payload, params, len(faces), 3, k, "FACE")
    values[0][-1] += 3
    broken, data = traversal.pack_streams(values, len(faces), 3, corner_order, 1)
    compiled, reference = both(lambda: traversal.decode_traversal(data, broken, k, "FACE"))
    assert compiled == reference
    assert compiled[:3] == ("FormatError", "R39-traversal", "FACE")
