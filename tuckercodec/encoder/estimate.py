"""Sizes of trial files from their integers, without packing them, for the search's speed.

The search's trials only rank truncations against each other, so they need a size that moves
as the packed size moves, not the packed size itself. Packing a trial (predicting every column
three ways, choosing, zigzag, byte planes, zstd) cost about half a second on a 10,000-vertex U1
of 300 columns; most of it was choosing the predictors. Here a trial is sized by the order-0
entropy of each column's residuals (the column's own histogram of zigzag integers; a value past
:data:`TABLE_SIZE` is priced as its escape plus twice its bits over the table's), which is within
a few percent of what zstd makes of the byte planes (``python -m tools.bench entropy``), and the
same on every trial, so the ranking holds.

U1's predictors (§6.2) are chosen once, on the first trial that needs a column, and kept for the
trials after: a column's predictor depends on its shape, not much on its step, and a trial's
integers are then predicted only the way the column will most likely be stored.
"""

from __future__ import annotations

import numpy as np

from ..format import qmat
from ..format.prediction import mean_residuals, residuals
from ..model.topology import MeshPrediction
from ..system import native
from .trial import QuantizedSegment

#: Zigzag residuals counted by their own histogram entry; larger ones are escapes.
TABLE_SIZE = 4095


def entropy_bits(stream: np.ndarray) -> float:
    """The order-0 entropy of each column of ``stream`` (rows, cols) of integers, in bits,
    summed over the columns."""
    rows, cols = stream.shape
    if stream.size == 0:
        return 0.0
    core = native.core()
    if core is not None and stream.dtype == np.int64:
        counts, escaped = core.entropy_counts(np.ascontiguousarray(stream), TABLE_SIZE)
    else:
        counts, escaped = _entropy_counts(stream)
    seen = counts.astype(np.float64)
    # sum over columns of -sum c log2(c / rows) = rows log2(rows) per column - sum c log2 c
    bits = cols * rows * np.log2(rows) - float(seen @ np.log2(seen))
    if escaped.size:
        bits += float(2.0 * np.log2(escaped / TABLE_SIZE).sum())
    return float(bits)


def _entropy_counts(stream: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The integers :func:`entropy_bits` sums: the nonzero counts of the columns' histograms
    (column after column) and the zigzag values past the table, in row-major order."""
    cols = stream.shape[1]
    zig = (stream << 1) ^ (stream >> 63)  # streams.zigzag, kept signed
    clipped = np.minimum(zig, TABLE_SIZE)
    clipped += np.arange(cols, dtype=np.int64)[None, :] * (TABLE_SIZE + 1)
    counts = np.bincount(clipped.reshape(-1), minlength=cols * (TABLE_SIZE + 1))
    return counts[counts > 0], zig[zig >= TABLE_SIZE]


class U1Predictors:
    """U1's predictor per column, chosen once by :func:`.format.qmat.encode_matrix`'s rule and
    reused by later trials."""

    def __init__(self, mesh: MeshPrediction) -> None:
        self.mesh = mesh
        self.predict = np.zeros(0, dtype=np.uint8)

    def stream(self, q: np.ndarray) -> np.ndarray:
        """The residuals ``q`` (rows, cols) would be streamed as under the predictors kept
        (chosen now for columns not seen before)."""
        cols, known = q.shape[1], self.predict.size
        if cols > known:  # choose for the new columns, as the file would (each on its own)
            new = qmat.predicted_stream(q[:, known:], self.mesh, True)[1]
            self.predict = np.concatenate([self.predict, new])
        predict = self.predict[:cols]
        out = q.copy()
        parent = np.flatnonzero(predict == qmat.PREDICT_PARENT)
        if parent.size:
            out[:, parent] = residuals(q[:, parent], self.mesh.parents)
        mean = np.flatnonzero(predict == qmat.PREDICT_MEAN)
        if mean.size:
            predicted = mean_residuals(q[:, mean], self.mesh.mean_steps)
            # a column too large for predictor 2 falls back to its parent, as the file would
            out[:, mean] = (
                predicted if predicted is not None else residuals(q[:, mean], self.mesh.parents)
            )
        return out


def segment_bits(segment: QuantizedSegment, u1_predictors: U1Predictors | None) -> float:
    """The estimated bits of a decomposition's quantized sections: its own U1 (if it has one,
    under ``u1_predictors``), then U3 and CENT predicted and CORE as it is, each chosen as
    :func:`.format.qmat.encode_matrix` chooses (:func:`.format.qmat.section_stream`)."""
    bits = 0.0
    if segment.u1 is not None:
        assert u1_predictors is not None  # an own U1 is sized under its kept predictors
        bits += entropy_bits(u1_predictors.stream(segment.u1.q))
    for matrix, predict in ((segment.u3, True), (segment.core, False), (segment.centroids, True)):
        bits += entropy_bits(qmat.section_stream(matrix.q, None, predict, True)[0])
    return bits
