"""§6.8 faces-traverse with ``coder`` 1 (format 1.6): the four streams as adaptive columns
(§6.14) and the NEW vertices as ranks among the unseen ones. The ranks mean what the spec's two
readings say; every face table round-trips; the encoder keeps coder 1 only where it is smaller;
and every file that breaks the coding is refused with the rule §5 step 15 gives."""

from __future__ import annotations

from typing import Any

import msgpack
import numpy as np
import pytest

from tests.test_format_traversal import TETRAHEDRON, grid, pad, scrambled, sorted_rows, torus
from tuckercodec import FormatError, LimitError
from tuckercodec.format import adaptive, traversal, unseen
from tuckercodec.format.container import pack_container, parse_container
from tuckercodec.format.limits import Limits


def by_definition(rank: int, last: int, unseen_vertices: list[int]) -> int | None:
    """The vertex §6.8 says a rank names: the (r+1)-th unseen above ``last`` ascending (from 0
    when last is -1), or the (-r)-th below it descending; None where there is none."""
    if rank >= 0:
        above = [v for v in unseen_vertices if v > last]
        return above[rank] if rank < len(above) else None
    below = [v for v in unseen_vertices if v < last][::-1]
    return below[-rank - 1] if -rank <= len(below) else None


def test_ranks_name_the_vertices_the_spec_reads():
    rng = np.random.default_rng(16)
    for _ in range(200):
        k = int(rng.integers(1, 30))
        order = rng.permutation(k)[: int(rng.integers(1, k + 1))]
        ranks = unseen._ranks_python(order, k)
        left, last = list(range(k)), -1
        for w, r in zip(order.tolist(), ranks.tolist(), strict=True):
            assert by_definition(r, last, left) == w
            left.remove(w)
            last = w
        assert unseen._vertices_python(ranks, k).tolist() == order.tolist()


def test_a_rank_naming_no_unseen_vertex_is_refused():
    # K = 4: 2 first, then 3 (the first above), 0 (the second below 3), then 1 is all that is left
    assert unseen._vertices_python(np.array([2, 0, -2, 0]), 4).tolist() == [2, 3, 0, 1]
    for bad in ([2, 0, -2, 1], [2, 0, -2, -1], [4], [-1], [2, 1, 0]):
        with pytest.raises(unseen.RankError, match="names no unseen vertex"):
            unseen._vertices_python(np.array(bad), 4)


def test_a_huge_vertex_count_sizes_no_table():
    """K is only the header's claim: the tree's nodes are made as vertices are placed."""
    ranks = np.array([2**40, -5, 3], dtype=np.int64)
    vertices = unseen._vertices_python(ranks, 2**41)
    assert vertices.tolist() == [2**40, 2**40 - 5, 2**40 - 1]
    assert unseen._ranks_python(vertices, 2**41).tolist() == ranks.tolist()


def adaptive_round_trip(faces: np.ndarray, k: int) -> dict[str, Any]:
    """The section coded with coder 1 forced (both corner orders), decoded back: the walk's
    faces; returns its parameters."""
    table = np.asarray(faces, dtype=np.int64)
    count, width = table.shape
    walk = traversal._walked(table, count, k)
    ranks = unseen.ranks_of(unseen.vertices_from_gaps(np.asarray(walk.new_residuals)), k)
    walked = table[np.asarray(walk.order, dtype=np.int64)]
    for corner_order in (0, 1):
        values = [walk.ops[corner_order], walk.degrees, ranks.tolist(), walk.references]
        params, payload = traversal.pack_streams(values, count, width, corner_order, 3, 1)
        assert params["coder"] == 1 and all(entry[1] == 0 for entry in params["streams"])
        decoded = traversal.decode_traversal(payload, params, k, "FACE", adaptive_coding=True)
        assert decoded.tolist() == walked.tolist()
        assert sorted_rows(decoded) == sorted_rows(table)
    return params


@pytest.mark.parametrize(
    ("faces", "vertex_count"),
    [
        (scrambled(grid(9), 81, 1), 81),
        (scrambled(grid(7, quads=True), 49, 2), 49),  # degrees
        (np.array(TETRAHEDRON), 4),
        (scrambled(torus(), 30, 3), 30),
        (pad([[0, 1, 2], [2, 1, 3, 4], [4, 3, 5, 6, 7], [9, 8, 10]]), 12),  # isolated vertex
        (np.array([[0, 1, 2], [0, 3, 4], [0, 5, 6]]), 7),  # FAR
        (np.concatenate([grid(4), grid(4) + 16, grid(3) + 40]), 49),  # seeds
        (np.zeros((0, 3), dtype=np.int64), 5),  # no faces: empty streams
    ],
    ids=lambda value: None if isinstance(value, int) else f"{len(value)}faces",
)
def test_every_face_table_round_trips_with_coder_1(faces, vertex_count):
    adaptive_round_trip(faces, vertex_count)


def locally_shuffled(n: int, seed: int, window: int) -> np.ndarray:
    """A grid of triangles whose vertex order follows the surface only roughly (each run of
    ``window`` vertices shuffled), faces shuffled: as real meshes are, where coder 1 is the
    smaller (a grid in its own order, or in a random one, is zstd's)."""
    rng = np.random.default_rng(seed)
    order = np.arange(n * n)
    for start in range(0, n * n, window):
        rng.shuffle(order[start : start + window])
    faces = np.append(order, -1)[grid(n)]
    return faces[rng.permutation(len(faces))]


FACES, K = locally_shuffled(12, 1, 4), 144


def test_the_encoder_keeps_the_smallest_and_coder_1_only_where_allowed():
    plain = traversal.encode_traversal(FACES, K)
    chosen = traversal.encode_traversal(FACES, K, adaptive_coding=True)
    assert "coder" not in plain[0]
    assert chosen[0]["coder"] == 1  # smaller here

    def size(params: dict[str, Any], payload: bytes) -> int:
        return len(payload) + len(msgpack.packb(params))

    assert size(*chosen[:2]) < size(*plain[:2])
    decoded = traversal.decode_traversal(chosen[1], chosen[0], K, "F", adaptive_coding=True)
    assert decoded.tolist() == chosen[2].tolist()
    for faces, k in ((grid(20), 400), (scrambled(grid(20), 400, 1), 400)):
        # zstd is smaller: a regular grid; an order with no locality
        assert (
            traversal.encode_traversal(faces, k, adaptive_coding=True)[:2]
            == (traversal.encode_traversal(faces, k)[:2])
        )


def coded(faces: np.ndarray, k: int) -> tuple[dict[str, Any], bytes]:
    params, payload, _ = traversal.encode_traversal(faces, k, adaptive_coding=True)
    assert params.get("coder") == 1
    return params, payload


@pytest.mark.parametrize("coder", [2, -1, 1.0, True, None, "1"])
def test_a_coder_other_than_0_or_1_is_r46(coder):
    params, payload = coded(FACES, K)
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(
            payload, {**params, "coder": coder}, K, "FACE", adaptive_coding=True
        )
    assert raised.value.rule == "R46-adaptive-stream"


def test_coder_1_needs_flag_bit_3():
    params, payload = coded(FACES, K)
    with pytest.raises(FormatError, match="needs flag bit 3") as raised:
        traversal.decode_traversal(payload, params, K, "FACE")
    assert raised.value.rule == "R46-adaptive-stream"


def test_coder_is_checked_after_corner_order_and_before_the_stream_table():
    params, payload = coded(FACES, K)
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(payload, {**params, "corner_order": 2, "coder": 2}, K, "F")
    assert raised.value.rule == "R39-traversal"
    broken = {**params, "coder": 2, "streams": [[1, 0, 1]]}
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(payload, broken, K, "F", adaptive_coding=True)
    assert raised.value.rule == "R46-adaptive-stream"


@pytest.mark.parametrize("planes", [1, 4, 5])
def test_a_stream_of_coder_1_has_planes_0(planes):
    params, payload = coded(FACES, K)
    table = [list(entry) for entry in params["streams"]]
    table[2][1] = planes
    with pytest.raises(FormatError, match="0 with coder 1") as raised:
        traversal.decode_traversal(
            payload, {**params, "streams": table}, K, "FACE", adaptive_coding=True
        )
    assert raised.value.rule == "R30-planes"
    assert raised.value.field == "FACE.streams.vertices.planes"


def _repacked(params: dict[str, Any], payload: bytes, change) -> tuple[dict[str, Any], bytes]:
    """The section with its streams (ranks in *vertices*) changed by ``change`` and packed
    again with coder 1."""
    count, width = params["shape"]
    values, corner_order = traversal.read_streams(
        payload, params, count, width, K, "FACE", adaptive_coding=True
    )
    placed = unseen.vertices_from_gaps(np.array(values[2]))
    values[2] = unseen.ranks_of(placed, K).tolist()
    change(values)
    return traversal.pack_streams(values, count, width, corner_order, 3, 1)


@pytest.mark.parametrize(
    ("where", "value"),
    [(0, K), (-1, 1), (-1, -(K - 1) - 1), (5, -(2**31))],
    ids=["first-beyond-K", "last-beyond", "below-0", "far-below"],
)
def test_a_rank_beyond_the_unseen_vertices_is_r39(where, value):
    params, payload = coded(FACES, K)

    def change(values: list[list[int]]) -> None:
        values[2][where] += value

    broken, data = _repacked(params, payload, change)
    with pytest.raises(FormatError, match="names no unseen vertex") as raised:
        traversal.decode_traversal(data, broken, K, "FACE", adaptive_coding=True)
    assert raised.value.rule == "R39-traversal"


def test_an_integer_beyond_32_bits_is_r46():
    params, payload = coded(FACES, K)
    count, width = params["shape"]
    values, _ = traversal.read_streams(
        payload, params, count, width, K, "FACE", adaptive_coding=True
    )
    values[3] = [2**31]  # FAR residual beyond 32 bits: written by hand, refused on reading
    streams, parts = [], []
    for stream in values:
        array = np.asarray(stream, dtype=np.int64)
        parts.append(adaptive.encode_columns(array[None, :], adaptive.sequence_order(array.size)))
        streams.append([len(stream), 0, len(parts[-1])])
    broken = {**params, "streams": streams}
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(b"".join(parts), broken, K, "FACE", adaptive_coding=True)
    assert raised.value.rule == "R46-adaptive-stream"
    assert raised.value.field == "FACE.streams.references"


@pytest.mark.parametrize("cut", ["short", "long", "damaged"])
def test_a_broken_adaptive_stream_is_r46_or_a_broken_walk(cut):
    params, payload = coded(FACES, K)
    table = [list(entry) for entry in params["streams"]]
    start, length = table[0][2], table[1][2]  # the degrees stream (empty: triangles)
    degrees = payload[start : start + length]
    changed = {"short": degrees[:-1], "long": degrees + b"\0", "damaged": b"\1" + degrees[1:]}
    table[1][2] = len(changed[cut])
    data = payload[:start] + changed[cut] + payload[start + length :]
    with pytest.raises(FormatError) as raised:
        traversal.decode_traversal(data, {**params, "streams": table}, K, "F", adaptive_coding=True)
    assert raised.value.rule == "R46-adaptive-stream"
    assert raised.value.field == "F.streams.degrees"


def test_a_count_the_payload_cannot_hold_is_r46_before_its_order_is_made():
    params, payload = coded(FACES, K)
    table = [list(entry) for entry in params["streams"]]
    table[1][2] += table[0][2]  # the ops stream's bytes given to the next one: none left
    table[0][2] = 0
    with pytest.raises(FormatError, match="cannot come from 0 bytes") as raised:
        traversal.decode_traversal(
            payload, {**params, "streams": table}, K, "F", adaptive_coding=True
        )
    assert raised.value.rule == "R46-adaptive-stream"
    assert raised.value.field == "F.streams.ops"


def test_the_limit_counts_32_bit_integers():
    params, payload = coded(FACES, K)
    need = 4 * sum(entry[0] for entry in params["streams"])
    limits = Limits(max_section_bytes=need - 1)
    with pytest.raises(LimitError):
        traversal.decode_traversal(payload, params, K, "F", limits, adaptive_coding=True)
    assert traversal.decode_traversal(
        payload, params, K, "F", Limits(max_section_bytes=need), adaptive_coding=True
    ).shape == (len(FACES), 3)


def test_a_file_whose_only_adaptive_section_is_face_sets_flag_bit_3():
    params, payload = coded(FACES, K)
    entry = {"id": "FACE", "critical": True, "codec": traversal.FACES_TRAVERSE, **params}
    data = pack_container({"vertices": K}, [(entry, payload)])
    container = parse_container(data)
    assert container.flags & adaptive.ADAPTIVE and container.minor == adaptive.ADAPTIVE_MINOR
    plain, plain_payload, _ = traversal.encode_traversal(FACES, K)
    entry = {"id": "FACE", "critical": True, "codec": traversal.FACES_TRAVERSE, **plain}
    assert not parse_container(pack_container({"vertices": K}, [(entry, plain_payload)])).flags & (
        adaptive.ADAPTIVE
    )
