"""The encoder's faster paths against the slower ones they replace or the definitions they
implement: a speed-up must not change an answer, so each must give the same answer, or the one
its docstring says."""

from __future__ import annotations

from typing import Any, cast
from unittest import mock

import numpy as np
import pytest

from tuckercodec import load_sequence
from tuckercodec.decomposition.hosvd import orthonormal_columns
from tuckercodec.encoder import estimate, rdo, search
from tuckercodec.format import adaptive, qmat
from tuckercodec.io.samples import sample_path
from tuckercodec.measures.distortion import ErrorAccumulator, WorstVertex
from tuckercodec.model.topology import MeshPrediction


def _householder(columns: np.ndarray) -> np.ndarray:
    q, r = np.linalg.qr(columns)
    signs = np.sign(np.diag(r))
    signs[signs == 0] = 1.0
    return q * signs


def test_cholesky_qr_is_householder_qr_with_a_positive_diagonal():
    rng = np.random.default_rng(3)
    # orthogonal columns of very different norms, as X1 V is, normalised as U1 normalises them
    base = np.linalg.qr(rng.standard_normal((500, 40)))[0] * np.logspace(0, -6, 40)
    columns = base / np.linalg.norm(base, axis=0) + 1e-9 * rng.standard_normal((500, 40))
    q = orthonormal_columns(columns)
    assert np.abs(q.T @ q - np.eye(40)).max() < 1e-13
    assert np.abs(q - _householder(columns)).max() < 1e-9


def test_dependent_columns_fall_back_to_householder():
    rng = np.random.default_rng(4)
    columns = rng.standard_normal((200, 10))
    columns[:, 7] = columns[:, 2]  # exactly dependent: Cholesky QR cannot make it orthonormal
    with mock.patch("numpy.linalg.qr", wraps=np.linalg.qr) as householder:
        q = orthonormal_columns(columns)
    assert householder.called
    np.testing.assert_array_equal(q, _householder(columns))


def test_a_trial_is_sized_by_the_adaptive_coder_the_file_uses():
    rng = np.random.default_rng(5)
    stream = np.stack(
        [rng.integers(-3, 4, 1000), np.zeros(1000, dtype=np.int64), rng.geometric(0.001, 1000)],
        axis=1,
    ).astype(np.int64)
    order = adaptive.sequence_order(stream.shape[0])
    coded = adaptive.encode_columns(np.ascontiguousarray(stream.T), order)
    assert estimate.coded_bits(stream, order) == 8 * len(coded)
    assert estimate.coded_bits(np.zeros((0, 3), dtype=np.int64), order) == 0.0


def test_u1_predictors_give_the_stream_the_file_would_store():
    sequence = load_sequence(sample_path())
    mesh = MeshPrediction(sequence.faces, sequence.vertex_count)
    rng = np.random.default_rng(6)
    smooth = np.cumsum(rng.standard_normal((sequence.vertex_count, 12)), axis=0)
    q = np.rint(smooth * 20).astype(np.int64)
    predictors = estimate.U1Predictors(mesh)
    # first the leading columns, then all of them: the new ones chosen as the file would
    np.testing.assert_array_equal(
        predictors.stream(q[:, :5]), qmat.predicted_stream(q[:, :5], mesh, True, True).stream
    )
    stream, predict, push = qmat.predicted_stream(q, mesh, True, True)
    np.testing.assert_array_equal(predictors.stream(q), stream)
    np.testing.assert_array_equal(predictors.predict, predict)
    np.testing.assert_array_equal(predictors.push, push)
    # and a narrower trial reuses them
    np.testing.assert_array_equal(predictors.stream(q[:, :8]), stream[:, :8])


@pytest.mark.parametrize(
    "sizes",
    [
        [9, 8, 7, 6, 5, 6, 7, 8],
        [5, 6, 7, 8, 9, 10, 11, 12],
        [12, 11, 10, 9, 8, 7, 6, 5],
        [7, 6, 5, 6, 7, 8, 9, 10],
        [4],
        [6, 5],
    ],
)
def test_the_valley_is_the_least_of_sizes_that_fall_then_rise(sizes):
    asked: list[int] = []

    def size(index: int) -> int:
        asked.append(index)
        return sizes[index]

    best = search._valley(size, len(sizes))
    assert sizes[best] == min(sizes)
    assert len(set(asked)) <= max(1, len(sizes) // 2 + 2)


def test_rdo_blocks_of_any_width_choose_the_same_integers():
    rng = np.random.default_rng(7)
    values = np.cumsum(rng.standard_normal((300, 70)), axis=0)
    steps = np.full(70, 0.7)
    levels = rdo.Levels.chain(300)
    wide = rdo.quantize(values, steps, levels)
    with mock.patch.object(rdo, "BLOCK_VALUES", 1):  # every block COLUMN_BLOCK columns
        narrow = rdo.quantize(values, steps, levels)
    np.testing.assert_array_equal(wide.q, narrow.q)


def test_the_worst_vertex_is_the_accumulators():
    rng = np.random.default_rng(8)
    original = rng.standard_normal((7, 50, 3))
    decoded = original + 1e-3 * rng.standard_normal((7, 50, 3))
    decoded[4, 17] += 0.5  # the worst
    decoded[5, 3] = original[5, 3] + (decoded[4, 17] - original[4, 17])  # equal: the first wins
    accumulator = ErrorAccumulator(block_frames=2)
    accumulator.add(original, decoded)
    worst = WorstVertex()
    for start in range(0, 7, 3):  # other blocks, the other sign
        worst.add(decoded[start : start + 3] - original[start : start + 3], start)
    assert (
        worst.found()
        == (accumulator.worst.distance, accumulator.worst.at)
        == (
            accumulator.worst.distance,
            (4, 17),
        )
    )


class _Trials:
    """A workspace whose trials rank three truncations one way and whose met files rank them
    the other: (a, b, c) trial sizes 100, 101, 120 and met sizes 110, 104, 90."""

    denominator2 = 1.0
    floor_error2 = 0.0
    late_shares = ()

    def __init__(self, meets_finalists: bool) -> None:
        self.meets_finalists = meets_finalists
        self.trial = {"a": 101, "b": 100, "c": 120}
        self.met = {"a": 104, "b": 110, "c": 90}

    def check_reachable(self, limit2):
        pass

    def ranks_for(self, target, share):
        return {0.1: "a", 0.15: "b", 0.2: "c"}.get(share)

    def prepare(self, choices):
        pass

    def truncation_error2(self, choice):
        return 0.0

    def initial_step(self, choice, room):
        return 1.0

    def quantize(self, choice, step, trial=False):
        return (choice, "trial" if trial else "met")

    def trial_bytes(self, quantized):
        choice, kind = quantized
        return (self.trial if kind == "trial" else self.met)[choice]


@pytest.mark.parametrize(("meets_finalists", "chosen"), [(True, "a"), (False, "b")])
def test_the_valleys_close_neighbours_are_met_too(monkeypatch, meets_finalists, chosen):
    """Trials are quantized at their first step; the valley's neighbour within 3 % of it is met
    as well, and the smaller met file wins (a workspace whose measures are passes over the input
    meets the valley alone)."""
    work = _Trials(meets_finalists)

    def met(work, choice, step, limit2):
        return work.quantize(choice, step), 0.0, 1

    monkeypatch.setattr(search, "meet", met)
    quantized: Any = search.search_kg(cast(Any, work), 0.1)[0]
    assert quantized[0] == chosen
