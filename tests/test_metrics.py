"""Error measures (tuckercodec/measures/distortion.py): the Karni-Gotsman error and its temporal
variant, the relative error and the largest vertex displacement, on cases whose value is known by
hand; the worst vertex (max_distance) against a brute-force numpy computation, with ties, in blocks
and a range at a time (ErrorAccumulator)."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import wave_sequence
from tuckercodec import InputError, MeshSequence
from tuckercodec.measures import distortion as metrics
from tuckercodec.measures.distortion import (
    kg_denominator,
    kg_error,
    max_distance,
    max_vertex_displacement,
    per_frame_kg,
    per_frame_max_displacement,
    relative_error,
)


def two_frames() -> np.ndarray:
    # frame 0: a unit square at the origin; frame 1: the same square moved by (10, 0, 0)
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    return np.stack([square, square + np.array([10, 0, 0])])


def test_kg_uses_the_per_frame_centroid():
    original = two_frames()
    # each frame's distance from its centroid: 4 corners at distance sqrt(0.5) -> 2 per frame
    assert kg_denominator(original) == pytest.approx(2.0)
    approx = original.copy()
    approx[1, 2, 2] += 0.02  # one coordinate off by 0.02
    assert kg_error(original, approx) == pytest.approx(100 * 0.02 / 2.0)


def test_temporal_variant_is_different_and_named():
    original = two_frames()
    approx = original.copy()
    approx[0, 0, 0] += 0.1
    # temporal mean of each vertex is its position shifted by 5: every vertex is 5 away, twice
    assert kg_denominator(original, mean="temporal") == pytest.approx(np.sqrt(8 * 25))
    assert kg_error(original, approx, mean="temporal") == pytest.approx(100 * 0.1 / np.sqrt(200))
    assert kg_error(original, approx) != pytest.approx(kg_error(original, approx, mean="temporal"))
    with pytest.raises(ValueError, match="mean must be"):
        kg_error(original, approx, mean="vertex")  # type: ignore[arg-type]  # refused


def test_zero_denominators_are_clear_errors():
    points = np.zeros((3, 5, 3)) + np.arange(3)[:, None, None]  # every frame a single point
    with pytest.raises(InputError, match="single point"):
        kg_error(points, points)
    still = np.repeat(wave_sequence(1, 3), 4, axis=0)  # identical frames: nothing moves
    assert kg_error(still, still) == 0.0
    with pytest.raises(InputError, match="no vertex ever moves"):
        kg_error(still, still, mean="temporal")


def test_relative_error_and_displacement():
    original = two_frames()
    approx = original.copy()
    approx[1, 3] += [0.3, 0.4, 0.0]
    assert relative_error(original, approx) == pytest.approx(0.5 / np.linalg.norm(original))
    worst = max_vertex_displacement(original, approx)
    assert worst.distance == pytest.approx(0.5) and (worst.frame, worst.vertex) == (1, 3)
    assert per_frame_max_displacement(original, approx).tolist() == [0.0, pytest.approx(0.5)]


def test_per_frame_kg_squares_add_up_to_kg():
    original = wave_sequence(8, 4)
    approx = original + 0.001 * np.random.default_rng(1).standard_normal(original.shape)
    parts = per_frame_kg(original, approx)
    assert parts.shape == (8,)
    assert np.sqrt(np.sum(parts**2)) == pytest.approx(kg_error(original, approx))


def test_accepts_sequences_and_refuses_mismatched_shapes():
    positions = wave_sequence(4, 3)
    seq = MeshSequence(positions, np.zeros((0, 3), dtype=np.int64))
    assert kg_error(seq, positions) == 0.0
    with pytest.raises(InputError, match="differ in shape"):
        kg_error(positions, positions[:3])


# ------------------------------------------------------------------------------------------
# the worst vertex (max_distance) and the one-pass ErrorAccumulator


def brute_force_worst(a: np.ndarray, b: np.ndarray) -> tuple[float, int, int]:
    """The definition, whole-array: norms of every vertex, the first largest in C order."""
    distances = np.linalg.norm(a - b, axis=2)
    frame, vertex = np.unravel_index(int(np.argmax(distances)), distances.shape)
    return float(distances[frame, vertex]), int(frame), int(vertex)


@pytest.mark.parametrize("block_frames", [None, 1, 2, 3, 7, 50])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_max_distance_is_the_brute_force_one_in_any_blocks(seed, block_frames):
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((13, 21, 3))
    b = a + rng.standard_normal(a.shape) * rng.uniform(0, 1e-3, size=(13, 21, 1))
    worst = max_distance(a, b, block_frames=block_frames)
    assert (worst.distance, worst.frame, worst.vertex) == brute_force_worst(a, b)
    assert worst.at == (worst.frame, worst.vertex)
    assert max_vertex_displacement(a, b) == worst  # the public name, the same measure


@pytest.mark.parametrize("block_frames", [None, 1, 2, 3])
def test_ties_go_to_the_first_in_frame_major_order(block_frames):
    # dyadic positions and displacements: every difference below is exact, so ties are ties
    a = np.round(wave_sequence(6, 4) * 64) / 64  # 6 frames of 16 vertices
    b = a + 2.0**-20
    # the same distance at frame 4 vertex 0, frame 2 vertex 9, frame 2 vertex 3 and (signs
    # flipped: the same squares) frame 5 vertex 5
    for frame, vertex, move in ((4, 0, 1), (2, 9, 1), (2, 3, 1), (5, 5, -1)):
        b[frame, vertex] = a[frame, vertex] + np.array([0.25, 0.5, 1.0]) * move
    distances = np.linalg.norm(a - b, axis=2)
    assert np.sum(distances == distances.max()) == 4  # a real four-way tie
    expected = brute_force_worst(a, b)
    assert expected == (1.3125**0.5, 2, 3)
    worst = max_distance(a, b, block_frames=block_frames)
    assert (worst.distance, worst.frame, worst.vertex) == expected
    # a tie between frames in different blocks (with blocks of 1 to 3 frames): the earlier
    c = a.copy()
    c[0, 7] += [0.0, 0.0, 2.0]
    c[3, 1] += [0.0, 0.0, 2.0]
    assert brute_force_worst(a, c) == (2.0, 0, 7)
    assert max_distance(a, c, block_frames=block_frames) == metrics.Displacement(2.0, 0, 7)
    # identical sequences: every distance is 0, and the first vertex of the first frame is it
    assert max_distance(a, a, block_frames=block_frames) == metrics.Displacement(0.0, 0, 0)


def test_a_nan_is_the_worst_vertex_as_argmax_has_it():
    a = wave_sequence(5, 3)
    b = a.copy()
    b[1, 2, 0] += 10.0
    b[3, 4, 1] = np.nan
    b[4, 0, 2] = np.nan
    worst = max_distance(a, b, block_frames=2)
    assert np.isnan(worst.distance) and worst.at == (3, 4) == brute_force_worst(a, b)[1:]


def test_the_accumulator_gives_kg_and_worst_vertex_from_one_pass():
    original = wave_sequence(17, 5)
    rng = np.random.default_rng(7)
    approx = original + 0.002 * rng.standard_normal(original.shape)
    whole = metrics.compare(original, approx)
    assert whole.kg == pytest.approx(kg_error(original, approx), rel=1e-12)
    assert whole.relative_error == pytest.approx(relative_error(original, approx), rel=1e-12)
    np.testing.assert_allclose(whole.per_frame_kg(), per_frame_kg(original, approx), rtol=1e-12)
    brute = np.linalg.norm(original - approx, axis=2).max(axis=1)
    np.testing.assert_array_equal(whole.per_frame_max_distance(), brute)
    np.testing.assert_array_equal(per_frame_max_displacement(original, approx), brute)
    # the same frames in uneven ranges, float32 among them, blocks of 2 inside each call
    pieces = metrics.ErrorAccumulator(block_frames=2)
    for start, stop in ((0, 1), (1, 8), (8, 8), (8, 17)):
        pieces.add(original[start:stop].astype(np.float32), approx[start:stop])
    a32 = original.astype(np.float32).astype(np.float64)
    assert pieces.frame_count == 17
    assert (pieces.worst.distance, *pieces.worst.at) == brute_force_worst(a32, approx)
    assert pieces.kg == pytest.approx(kg_error(a32, approx), rel=1e-12)
    np.testing.assert_array_equal(pieces.frame_numbers, np.arange(17))


def test_frames_of_a_range_are_named_by_their_numbers():
    original = wave_sequence(10, 4)
    approx = original.copy()
    approx[6, 11] += [0.0, 0.5, 0.0]
    measured = metrics.ErrorAccumulator(block_frames=3)
    measured.add(original[5:8], approx[5:8], frames=range(5, 8))  # frames 5, 6, 7 of the file
    assert measured.worst == metrics.Displacement(0.5, 6, 11)
    measured.add(original[8:], approx[8:])  # numbered on from the last: 8, 9
    np.testing.assert_array_equal(measured.frame_numbers, [5, 6, 7, 8, 9])
    with pytest.raises(ValueError, match="2 frame numbers given for 3 frames"):
        measured.add(original[:3], approx[:3], frames=[0, 1])


def test_the_accumulator_refuses_what_it_cannot_compare():
    positions = wave_sequence(4, 3)
    empty = metrics.ErrorAccumulator()
    with pytest.raises(ValueError, match="no frames have been compared"):
        _ = empty.worst
    with pytest.raises(ValueError, match="no frames have been compared"):
        _ = empty.kg
    with pytest.raises(ValueError, match="block_frames"):
        metrics.ErrorAccumulator(block_frames=0)
    with pytest.raises(InputError, match="differ in shape"):
        empty.add(positions, positions[:3])
    with pytest.raises(ValueError, match="frames, vertices, 3"):
        empty.add(positions[0], positions[0])
    empty.add(positions, positions)
    with pytest.raises(InputError, match="the frames before 9"):
        empty.add(positions[:, :4], positions[:, :4])
    points = np.zeros((3, 5, 3)) + np.arange(3)[:, None, None]  # each frame a single point
    with pytest.raises(InputError, match="single point"):
        _ = metrics.compare(points, points).kg
    assert metrics.compare(points, points).worst.distance == 0.0  # defined all the same


def test_memory_is_a_block_not_the_sequence():
    """A long float32 sequence is compared a block of frames at a time: the traced peak stays
    far below one float64 difference array of the whole (deterministic: no timing)."""
    import tracemalloc

    frames, vertices = 240, 2000
    original = np.zeros((frames, vertices, 3), dtype=np.float32)
    original[:, :, 0] = np.arange(vertices, dtype=np.float32)
    approx = original.copy()
    approx[200, 1234, 1] = 0.25
    whole_difference = frames * vertices * 3 * 8  # 11.5 MB
    tracemalloc.start()
    try:
        worst = max_distance(original, approx, block_frames=8)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert worst == metrics.Displacement(0.25, 200, 1234)
    assert peak < whole_difference / 4, peak
