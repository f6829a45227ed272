"""§6.3 Codec ``qmat``: quantized matrices (U1, U3, CORE and CENT).

A float matrix of shape (rows, cols) is stored as integers ``q`` with one step per column:
``value = step[c] * q[r, c]``. Each column either stores ``q`` itself (predictor 0) or each
entry minus its parent's entry (predictor 1, see :mod:`.prediction`). The residuals go column
after column into one integer stream (:mod:`.streams`).

The section entry carries ``shape`` [rows, cols], ``planes``, ``steps`` (cols float32,
little-endian, as bytes) and ``predict`` (cols uint8, as bytes).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import FormatError, UnreachableTargetError
from . import streams
from .prediction import accumulate, residuals
from .sections import section_shape

PREDICT_NONE, PREDICT_PARENT = 0, 1
#: Largest |q| the encoder forms: exact in float64. What is streamed (q, or its residual from
#: the parent) must also fit 32 bits, which :func:`.streams.pack_integers` checks.
MAX_QUANTIZED = 2**52


@dataclass
class QuantizedMatrix:
    """Integers and the per-column steps that turn them back into floats."""

    q: np.ndarray  # (rows, cols) int64
    steps: np.ndarray  # (cols,) float32

    def values(self) -> np.ndarray:
        """The dequantized matrix, float64: ``step[c] * q[r, c]`` (§6.3)."""
        out = self.q.astype(np.float64)
        out *= self.steps.astype(np.float64)[None, :]  # in place: the same products, no scratch
        return out


def quantize(values: np.ndarray, steps: np.ndarray) -> QuantizedMatrix:
    """Round ``values / step`` per column. Steps are rounded to float32 first, because the file
    stores them so and the decoder must multiply by exactly the same number."""
    steps32 = np.asarray(steps, dtype=np.float32)
    if not (np.isfinite(steps32).all() and (steps32 > 0).all()):
        raise ValueError("quantization steps must be positive finite float32 numbers")
    q = values / steps32.astype(np.float64)[None, :]
    np.rint(q, out=q)
    if q.size and np.abs(q).max() > MAX_QUANTIZED:
        raise UnreachableTargetError(
            "the error target is too small for the format's integer range: a quantized value "
            f"would need {int(np.abs(q).max())} > {MAX_QUANTIZED}"
        )
    return QuantizedMatrix(q.astype(np.int64), steps32)


def _cost(columns: np.ndarray) -> np.ndarray:
    """A cheap per-column proxy for the bits of an integer column: mean log2(1 + 2|x|)."""
    return (
        np.log2(1.0 + 2.0 * np.abs(columns)).mean(axis=0)
        if columns.size
        else np.zeros(columns.shape[1])
    )


def encode_matrix(
    matrix: QuantizedMatrix,
    parents: np.ndarray | None,
    *,
    allow_predict: bool = True,
    level: int = streams.DEFAULT_LEVEL,
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the section, choosing per column whether prediction helps.

    ``parents`` as in :func:`.prediction.residuals` (``None``: the previous row).
    """
    q = matrix.q
    predict = np.zeros(q.shape[1], dtype=np.uint8)
    stream = q
    if allow_predict and q.shape[0] > 1:
        stream = residuals(q, parents)
        predict = (_cost(stream) < _cost(q)).astype(np.uint8)
        plain = np.flatnonzero(predict == PREDICT_NONE)
        stream[:, plain] = q[:, plain]  # in place: these columns store q itself
    payload, planes = streams.pack_integers(np.ascontiguousarray(stream.T), level)
    params = {
        "shape": [int(q.shape[0]), int(q.shape[1])],
        "planes": planes,
        "steps": matrix.steps.astype("<f4").tobytes(),
        "predict": predict.tobytes(),
    }
    return params, payload


def decode_matrix(
    payload: bytes | memoryview,
    params: dict[str, Any],
    parents: np.ndarray | Callable[[], np.ndarray] | None,
    where: str,
    *,
    allow_predict: bool = True,
) -> QuantizedMatrix:
    """The quantized matrix of a qmat section (§6.3). The caller has checked ``shape`` against
    the header and the limits.

    ``parents`` as in :func:`.prediction.accumulate`, or a function that makes them:
    it is called only once the stream has decoded and only if a column is predicted, so that
    their cost (an array of ``rows`` entries) is never paid for a payload that turns out bad.
    """
    rows, cols = section_shape(params, where)
    planes = streams.checked_planes(params, where)
    steps_raw, predict_raw = params.get("steps"), params.get("predict")
    # §5 step 16: the lengths and types of steps and predict, then their values
    if not isinstance(steps_raw, bytes) or len(steps_raw) != 4 * cols:
        raise FormatError(
            f"steps must be {cols} float32 values as {4 * cols} bytes",
            rule="R31-steps",
            field=f"{where}.steps",
        )
    if not isinstance(predict_raw, bytes) or len(predict_raw) != cols:
        raise FormatError(
            f"predict must be {cols} bytes", rule="R32-predictor", field=f"{where}.predict"
        )
    steps = np.frombuffer(steps_raw, dtype="<f4").astype(np.float32)
    if not (np.isfinite(steps).all() and (steps > 0).all()):
        raise FormatError(
            "every step must be a positive finite float32", rule="R31-steps", field=f"{where}.steps"
        )
    predict = np.frombuffer(predict_raw, dtype=np.uint8)
    if (predict > PREDICT_PARENT).any() or (not allow_predict and predict.any()):
        allowed = "0 or 1" if allow_predict else "0 (no parent relation here)"
        raise FormatError(
            f"every predictor must be {allowed}", rule="R32-predictor", field=f"{where}.predict"
        )
    stream = streams.unpack_integers(payload, rows * cols, planes, where)
    q = np.ascontiguousarray(stream.reshape(cols, rows).T)
    chosen = np.flatnonzero(predict == PREDICT_PARENT)
    if chosen.size:
        if callable(parents):
            parents = parents()
        if chosen.size == cols:  # every column (U1's usual case): restored where it lies
            accumulate(q, parents, in_place=True)
        else:
            q[:, chosen] = accumulate(q[:, chosen], parents)
    return QuantizedMatrix(q, steps)
