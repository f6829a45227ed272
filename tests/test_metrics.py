"""Error measures (tuckercodec/metrics.py): the Karni-Gotsman error and its temporal variant,
the relative error and the largest vertex displacement, on cases whose value is known by hand."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import wave_sequence
from tuckercodec import InputError, MeshSequence
from tuckercodec.metrics import (
    kg_denominator,
    kg_error,
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
