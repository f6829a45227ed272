"""Encoder edge cases (issue 5): either a correct file whose decoded error meets the target, or a
clear, typed error. Never a wrong file, never an untyped exception."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import tuckercodec as tc
from tuckercodec import MeshSequence


def _strip(frames: int = 10, vertices: int = 30, seed: int = 0) -> MeshSequence:
    """A small moving triangle strip."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, frames)[:, None, None]
    positions = rng.random((1, vertices, 3)) + 0.1 * np.sin(6 * t + 3 * rng.random((1, vertices, 3)))
    faces = np.array([[i, i + 1, i + 2] for i in range(vertices - 2)], dtype=np.int64).reshape(-1, 3)
    return MeshSequence(positions, faces)


def _assert_meets(sequence: MeshSequence, data: bytes, target: float) -> None:
    decoded = tc.decode(data)
    assert decoded.vertices.shape == sequence.vertices.shape
    np.testing.assert_array_equal(decoded.faces, sequence.faces)
    assert tc.kg_error(sequence, decoded) <= target


def _variants() -> dict[str, MeshSequence]:
    base = _strip()
    duplicated = base.vertices.copy()
    duplicated[:, 5] = duplicated[:, 4]
    return {
        "one frame": _strip(frames=1),
        "two vertices": MeshSequence(_strip(vertices=2).vertices, np.zeros((0, 3), dtype=np.int64)),
        "identical frames": MeshSequence(np.repeat(base.vertices[:1], 10, axis=0), base.faces),
        "duplicate vertices": MeshSequence(duplicated, base.faces),
        "coordinates near 1e30": MeshSequence(base.vertices * 1e30, base.faces),
        "coordinates near 1e-30": MeshSequence(base.vertices * 1e-30, base.faces),
        "ten sizes off the origin": MeshSequence(base.vertices + 10.0, base.faces),
    }


@pytest.mark.parametrize("name", list(_variants()))
@pytest.mark.parametrize("target", [1.0, 0.01, 1e-6])
def test_unusual_sequences_meet_the_target(name, target):
    sequence = _variants()[name]
    result = tc.encode_with_report(sequence, target_kg=target)
    assert result.report.kg <= target
    _assert_meets(sequence, result.data, target)


@pytest.mark.parametrize("name", list(_variants()))
def test_unusual_sequences_with_fixed_ranks_and_sizes(name):
    sequence = _variants()[name]
    r1, r3 = tc.analyze(sequence).max_ranks
    full = tc.encode_with_report(sequence, ranks=(r1, r3))
    assert full.report.kg <= 1e-3  # full ranks lose nothing: only quantization, kept tiny
    sized = tc.encode_with_report(sequence, target_bpfv=8 * len(full.data) / (sequence.frame_count * sequence.vertex_count))
    assert len(sized.data) <= len(full.data)


def test_absurdly_loose_target_gives_the_coarsest_valid_file():
    sequence = _strip()
    result = tc.encode_with_report(sequence, target_kg=1e9)
    assert result.report.ranks == (1, 1)
    _assert_meets(sequence, result.data, 1e9)


@pytest.mark.parametrize("target", [0, -1, -0.0, math.inf, math.nan, "0.1", True])
def test_targets_that_are_not_positive_numbers_are_refused(target):
    with pytest.raises(ValueError, match="target_kg must be a positive finite number"):
        tc.encode(_strip(), target_kg=target)


@pytest.mark.parametrize("ranks", [(0, 1), (1, 0), (31, 1), (1, 11), (-1, 2), (1.5, 2), ("a", 2), (1,), 7])
def test_ranks_beyond_the_tensor_are_refused(ranks):
    with pytest.raises(ValueError, match="ranks must be two integers with 1 <= i <= 30 and 1 <= k <= 10"):
        tc.encode(_strip(), ranks=ranks)


def test_a_size_no_file_can_meet_is_refused_with_the_smallest_size():
    with pytest.raises(ValueError, match="no file fits 0.001 bpfv: even the coarsest one needs"):
        tc.encode(_strip(), target_bpfv=0.001)


@pytest.mark.parametrize(
    "positions, message",
    [
        (np.repeat(np.ones((4, 1, 3)), 5, axis=1), "denominator is zero"),  # every frame a point
        (np.ones((4, 1, 3)), "denominator is zero"),  # one vertex
        # a shape 1e-14 across, 1 from the origin: float64 rounding, not a shape
        (1.0 + 1e-14 * np.random.default_rng(1).random((4, 30, 3)), "single point to float64's precision"),
        (np.random.default_rng(2).random((4, 6, 3)) * 1e300, "too large"),
        (np.random.default_rng(3).random((4, 6, 3)) * 1e-300, "too small"),
    ],
)
def test_sequences_without_a_measurable_shape_are_refused(positions, message):
    sequence = MeshSequence(positions, np.zeros((0, 3), dtype=np.int64))
    for kwargs in ({"target_kg": 0.1}, {"ranks": (1, 1)}, {"target_bpfv": 100.0}):
        with pytest.raises(tc.InputError, match=message):
            tc.encode(sequence, **kwargs)


def test_far_from_the_origin_a_tight_target_is_refused_with_what_is_reachable():
    base = _strip()
    far = MeshSequence(base.vertices + 1e7, base.faces)  # 1e7 times the strip's size
    with pytest.raises(tc.UnreachableTargetError, match="too far from the origin") as refused:
        tc.encode(far, target_kg=0.1)
    floor = float(re.search(r"already costs a KG error of ([0-9.]+)\. ", str(refused.value)).group(1))
    assert 0.1 < floor < 10
    # just above the floor it can be met, with the centroids at their coarsest usable step
    target = 1.1 * floor
    _assert_meets(far, tc.encode(far, target_kg=target), target)
    # and a size target falls back to the smallest reachable error instead of failing
    sized = tc.encode_with_report(far, target_bpfv=50.0)
    assert floor <= sized.report.kg * 1.01
    _assert_meets(far, sized.data, sized.report.kg * (1 + 1e-9))
