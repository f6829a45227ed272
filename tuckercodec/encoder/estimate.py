"""Sizes of trial files from their integers, for the search's choices.

The search's trials rank truncations against each other, so their sizes must move as the final
file's sizes move. A trial's sections are sized as the file codes them: each section's integers
through §6.14's adaptive coder (:func:`coded_bits`), in its coding order, without zstd's
alternative (which the file keeps only where it is smaller, by a few bytes, on short sections).
An order-0 entropy of each column (the estimate before format 1.6) could not see what the
coder's contexts gain, nor price a short column of wide integers. Choosing each column's
predictor (three predictions of every column) is what packing a trial costs most.

U1's predictors (§6.2) are chosen once, on the first trial that needs a column, and kept for the
trials after: a column's predictor depends on its shape, not much on its step, and a trial's
integers are then predicted only the way the column will most likely be stored.
"""

from __future__ import annotations

import numpy as np

from ..format import adaptive, qmat
from ..format.prediction import mean_residual_columns, mean_residuals, residuals
from ..model.topology import MeshPrediction
from .trial import QuantizedSegment


class U1Predictors:
    """U1's predictor per column and predictor 2's push, chosen once by
    :func:`.format.qmat.encode_matrix`'s rule and reused by later trials: among those of
    format 1.2 (``coding_tools``: predictor 2) and 1.6 (``pushes``) only where the file may
    use them."""

    def __init__(
        self, mesh: MeshPrediction, *, coding_tools: bool = True, pushes: bool = True
    ) -> None:
        self.mesh = mesh
        self.coding_tools, self.pushes = coding_tools, pushes
        self.predict = np.zeros(0, dtype=np.uint8)
        self.push = np.zeros(0, dtype=np.uint8)
        self._order: adaptive.CodingOrder | None = None

    def coding_order(self, rows: int) -> adaptive.CodingOrder:
        """U1's coding order (§6.14), made once."""
        if self._order is None:
            self._order = qmat.coding_order(self.mesh, rows)
        return self._order

    def bits(self, q: np.ndarray) -> float:
        """The bits of U1's integers ``q`` as the file codes them."""
        return coded_bits(self.stream(q), self.coding_order(q.shape[0]))

    def kept(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The predictor and push kept for each column of ``q`` (rows, cols), chosen now, from
        ``q``, for columns not seen before."""
        cols, known = q.shape[1], self.predict.size
        if cols > known:  # choose for the new columns, as the file would (each on its own)
            predict, push = qmat.chosen_predictors(
                q[:, known:], self.mesh, self.coding_tools, pushes=self.pushes
            )
            self.predict = np.concatenate([self.predict, predict])
            self.push = np.concatenate([self.push, push])
        return self.predict[:cols], self.push[:cols]

    def stream(self, q: np.ndarray) -> np.ndarray:
        """The residuals ``q`` (rows, cols) would be streamed as under the predictors kept
        (chosen now for columns not seen before)."""
        predict, push = self.kept(q)
        if (predict == qmat.PREDICT_MEAN).all():  # U1's usual case: no copy of q
            # made column after column, as coded_bits reads them: its transposition is a view
            columns = mean_residual_columns(q, self.mesh.mean_steps, push)
            return columns.T if columns is not None else residuals(q, self.mesh.parents)
        out = q.copy()
        parent = np.flatnonzero(predict == qmat.PREDICT_PARENT)
        if parent.size:
            out[:, parent] = residuals(q[:, parent], self.mesh.parents)
        mean = np.flatnonzero(predict == qmat.PREDICT_MEAN)
        if mean.size:
            predicted = mean_residuals(q[:, mean], self.mesh.mean_steps, self.push[mean])
            # a column too large for predictor 2 falls back to its parent, as the file would
            out[:, mean] = (
                predicted if predicted is not None else residuals(q[:, mean], self.mesh.parents)
            )
        return out


def coded_bits(stream: np.ndarray, order: adaptive.CodingOrder) -> float:
    """The bits of ``stream`` (rows, cols) through the adaptive coder in ``order``."""
    if stream.size == 0:
        return 0.0
    return 8.0 * len(adaptive.encode_columns(np.ascontiguousarray(stream.T), order))


def segment_bits(
    segment: QuantizedSegment, u1_predictors: U1Predictors | None, coding_tools: bool = True
) -> float:
    """The estimated bits of a decomposition's quantized sections: its own U1 (if it has one,
    under ``u1_predictors``), then U3 and CENT predicted and CORE as it is, each chosen as
    :func:`.format.qmat.encode_matrix` chooses (:func:`.format.qmat.section_stream`; predictor
    3 with ``coding_tools``, format 1.2)."""
    bits = 0.0
    if segment.u1 is not None:
        assert u1_predictors is not None  # an own U1 is sized under its kept predictors
        bits += u1_predictors.bits(segment.u1.q)
    for matrix, predict in ((segment.u3, True), (segment.core, False), (segment.centroids, True)):
        stream = qmat.section_stream(matrix.q, None, predict, coding_tools).stream
        bits += coded_bits(stream, adaptive.sequence_order(stream.shape[0]))
    return bits
