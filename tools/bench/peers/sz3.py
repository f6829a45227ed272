"""SZ3 (pysz), two ways.

For the peers suite: the L2-norm error bound, on the 3 x K x F layout of the centred float64
tensor, with the per-frame centroids as float32 and the faces once; the bound is searched so
that the decoded KG error meets each target.

For the bounds suite: the absolute error bound D / sqrt(3) on every coordinate, so
that no vertex moves more than D (Euclidean), on the positions in their own precision (float32
where exact) in the 3 x K x F layout (time fastest: 1.3-2.2x smaller than F x K x 3 on the four
shared sequences at 1e-3 and 1e-4 of the diagonal), with the faces once.
"""

from __future__ import annotations

import math

import numpy as np

from tools.bench.peers.base import (
    Context,
    Trial,
    arrange,
    faces_once,
    restore,
    search_targets,
    timed_trial,
)
from tuckercodec import MeshSequence


def run_sz3(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    from pysz import sz, szConfig, szErrorBoundMode

    # Axis first (3 x K x F): about 10 % smaller than K x 3 x F on chicken at the same error.
    axis_first = np.ascontiguousarray(context.tensor.transpose(1, 0, 2))
    shape = axis_first.shape

    def compress(bound: float) -> bytes:
        config = szConfig(shape)
        config.errorBoundMode = szErrorBoundMode.L2NORM
        config.l2normErrorBound = bound
        payload, _ = sz.compress(axis_first, config)
        return payload.tobytes()

    def decompress(payload: bytes) -> np.ndarray:
        data, _ = sz.decompress(np.frombuffer(payload, dtype=np.uint8), np.float64, shape)
        return np.asarray(data).reshape(shape).transpose(1, 0, 2)

    def guess(target: float) -> float:  # the L2 norm of the error a KG target allows
        return target / 100.0 * context.centred_norm

    return search_targets(
        "sz3", targets, context, guess, compress, decompress, lambda b: f"L2 <= {b:.3g}"
    )


#: The layout of the bounds suite: time fastest (see the module's docstring).
ABS_LAYOUT = "3KF"


def run_sz3_abs(sequence: MeshSequence, values: np.ndarray, bound: float) -> Trial:
    """SZ3 in absolute mode at ``bound / sqrt(3)`` per coordinate on ``values`` (the positions
    in their own precision), the faces once: every vertex within ``bound`` if SZ3 keeps its
    promise (the caller measures it). The decoded positions come back as float64."""
    from pysz import sz, szConfig, szErrorBoundMode

    arranged = arrange(values, ABS_LAYOUT)
    faces = faces_once(sequence)
    per_coordinate = bound / math.sqrt(3.0)

    def encode() -> tuple[int, int, bytes]:
        config = szConfig(arranged.shape)
        config.errorBoundMode = szErrorBoundMode.ABS
        config.absErrorBound = per_coordinate
        payload, _ = sz.compress(arranged, config)
        data = payload.tobytes()
        return len(data) + len(faces), len(faces), data

    def decode_(payload: bytes) -> np.ndarray:
        data, _ = sz.decompress(
            np.frombuffer(payload, dtype=np.uint8), arranged.dtype, arranged.shape
        )
        return restore(np.asarray(data).reshape(arranged.shape), ABS_LAYOUT)

    return timed_trial(
        "sz3",
        f"ABS {per_coordinate:.3g} per coordinate, {values.dtype}, {ABS_LAYOUT}",
        encode,
        decode_,
        untimed=lambda decoded: decoded.astype(np.float64),
    )
