"""The pieces of the sections: integer streams, prediction forests, quantized matrices, faces."""

from __future__ import annotations

import collections

import numpy as np
import pytest

from tuckercodec import FormatError
from tuckercodec.format import streams
from tuckercodec.format.faces import decode_faces, encode_faces
from tuckercodec.format.prediction import accumulate, residuals
from tuckercodec.format.qmat import decode_matrix, encode_matrix, quantize
from tuckercodec.topology import face_edges, mesh_parents


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
    np.testing.assert_array_equal(streams.unpack_integers(payload, len(values), planes, "test"), values)


def test_integers_beyond_the_format_range_are_refused():
    with pytest.raises(ValueError, match="32-bit"):
        streams.pack_integers(np.array([2**31 + 5]))


def test_zstd_frames_are_checked_before_use():
    payload = streams.compress(b"x" * 100)
    assert streams.decompress_exact(payload, 100, "s") == b"x" * 100
    with pytest.raises(FormatError, match="declares 100 bytes, but the section's shape needs 99"):
        streams.decompress_exact(payload, 99, "s")
    with pytest.raises(FormatError, match="zstd frame header"):
        streams.decompress_exact(b"not zstd at all", 10, "s")
    with pytest.raises(FormatError, match="does not decompress"):
        streams.decompress_exact(payload + payload, 100, "s")  # trailing data
    with pytest.raises(FormatError, match="does not decompress"):
        streams.decompress_exact(payload[:-2], 100, "s")


def _queue_bfs_parents(faces: np.ndarray, count: int) -> np.ndarray:
    """The definition of spec/FORMAT.md §6.2, written as plainly as possible."""
    a, b = face_edges(faces)
    neighbours = [set() for _ in range(count)]
    for x, y in zip(a.tolist(), b.tolist()):
        if x != y:
            neighbours[x].add(y)
            neighbours[y].add(x)
    parents = [-1] * count
    reached = [False] * count
    for root in range(count):
        if reached[root]:
            continue
        reached[root] = True
        queue = collections.deque([root])
        while queue:
            u = queue.popleft()
            for w in sorted(neighbours[u]):
                if not reached[w]:
                    reached[w] = True
                    parents[w] = u
                    queue.append(w)
    return np.array(parents, dtype=np.int64)


def test_mesh_parents_follow_the_queue_walk_of_the_spec():
    rng = np.random.default_rng(7)
    for _ in range(300):
        count = int(rng.integers(1, 60))
        width = int(rng.integers(3, 6))
        faces = rng.integers(0, count, size=(int(rng.integers(0, 40)), width))
        if width > 3 and len(faces):
            faces[rng.random(len(faces)) < 0.4, -1] = -1  # padded polygons
        np.testing.assert_array_equal(mesh_parents(faces, count), _queue_bfs_parents(faces, count))


def test_polygon_edges_close_at_the_last_real_corner():
    a, b = face_edges(np.array([[0, 1, 2, -1], [3, 4, 5, 6]]))
    edges = set(zip(a.tolist(), b.tolist()))
    assert edges == {(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 6), (6, 3)}


def test_accumulate_inverts_residuals_on_any_forest():
    rng = np.random.default_rng(3)
    for count in (1, 2, 17, 500):
        # a random forest: parents anywhere (earlier or later), never a cycle
        order = rng.permutation(count)
        parents = np.full(count, -1)
        for position in range(1, count):
            if rng.random() < 0.9:
                parents[order[position]] = order[rng.integers(0, position)]
        values = rng.integers(-1000, 1000, size=(count, 4))
        np.testing.assert_array_equal(accumulate(residuals(values, parents), parents), values)
        np.testing.assert_array_equal(accumulate(residuals(values, None), None), values)
    # a chain 100 000 deep takes about 17 passes, not 100 000
    chain = np.arange(-1, 99_999)
    values = rng.integers(-5, 5, size=(100_000, 1))
    np.testing.assert_array_equal(accumulate(residuals(values, chain), chain), values)


def test_quantized_matrix_round_trip_with_prediction():
    rng = np.random.default_rng(0)
    smooth = np.cumsum(rng.standard_normal((200, 3)), axis=0)
    noisy = rng.standard_normal((200, 2))
    values = np.hstack([smooth, noisy])
    matrix = quantize(values, np.array([0.01, 0.02, 0.05, 0.1, 0.1]))
    params, payload = encode_matrix(matrix, None)
    assert np.frombuffer(params["predict"], np.uint8).tolist() == [1, 1, 1, 0, 0]
    decoded = decode_matrix(payload, params, None, "test")
    np.testing.assert_array_equal(decoded.q, matrix.q)
    assert np.abs(decoded.values() - values).max() <= 0.05 + 1e-12
    with pytest.raises(FormatError, match="predictor must be 0"):
        decode_matrix(payload, params, None, "test", allow_predict=False)
    with pytest.raises(FormatError, match="steps must be"):
        decode_matrix(payload, {**params, "steps": params["steps"][:-4]}, None, "test")


def test_quantization_refuses_steps_too_small_for_the_integers():
    with pytest.raises(ValueError, match="integer range"):
        quantize(np.array([[1.0]]), np.array([1e-20]))
    # within float64's exact integers, but not the 32-bit stream: refused when packed
    with pytest.raises(ValueError, match="32-bit"):
        encode_matrix(quantize(np.array([[1.0], [1.0]]), np.array([1e-12])), None)


def test_skippable_zstd_frames_are_not_payloads():
    import struct

    with pytest.raises(FormatError, match="zstd frame header"):
        streams.decompress_exact(struct.pack("<II", 0x184D2A50, 4) + b"abcd", 0, "s")


def test_faces_round_trip_and_checks():
    faces = np.array([[0, 1, 2, -1], [2, 1, 3, 4]])
    params, payload = encode_faces(faces)
    np.testing.assert_array_equal(decode_faces(payload, params, 5, "FACE"), faces)
    with pytest.raises(FormatError, match="outside 0..3"):
        decode_faces(payload, params, 4, "FACE")
    bad_params, bad_payload = encode_faces(np.array([[0, -1, 1, 2]]))
    with pytest.raises(FormatError, match="padded before its end"):
        decode_faces(bad_payload, bad_params, 5, "FACE")
