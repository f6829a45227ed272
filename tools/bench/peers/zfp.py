"""zfp (zfpy, fixed-accuracy mode: an absolute tolerance), two ways.

For the peers suite: on the centred float64 tensor (K x 3 x F), with the per-frame centroids as
float32 and the faces once; the tolerance is searched so that the decoded KG error meets each
target.

For the bounds suite: the tolerance D / sqrt(3) on the positions in their own
precision (float32 where exact), 3 x K x F like SZ3 (zfp's size hardly depends on the layout:
within 3 % over four of them on the shared sequences), with the faces once. zfp rounds the
tolerance down to a power of two and its errors stay well under it: its worst vertex is 0.1-0.16
of D on the shared sequences, so it pays for an accuracy the bound does not ask for.
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
    rms_error,
    search_targets,
    timed_trial,
)
from tuckercodec import MeshSequence


def run_zfp(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    import zfpy

    def compress(bound: float) -> bytes:
        return zfpy.compress_numpy(context.tensor, tolerance=bound)

    def decompress(payload: bytes) -> np.ndarray:
        return zfpy.decompress_numpy(payload)

    def guess(target: float) -> float:
        return 4.0 * rms_error(context, target)

    return search_targets(
        "zfp", targets, context, guess, compress, decompress, lambda b: f"tol {b:.3g}"
    )


#: The layout of the bounds suite, the same as SZ3's.
ACCURACY_LAYOUT = "3KF"


def run_zfp_accuracy(sequence: MeshSequence, values: np.ndarray, bound: float) -> Trial:
    """zfp in fixed-accuracy mode at tolerance ``bound / sqrt(3)`` on ``values`` (the
    positions in their own precision), the faces once. The decoded positions come back as
    float64."""
    import zfpy

    arranged = arrange(values, ACCURACY_LAYOUT)
    faces = faces_once(sequence)
    tolerance = bound / math.sqrt(3.0)

    def encode() -> tuple[int, int, bytes]:
        payload = zfpy.compress_numpy(arranged, tolerance=tolerance)
        return len(payload) + len(faces), len(faces), payload

    def decode_(payload: bytes) -> np.ndarray:
        return restore(zfpy.decompress_numpy(payload), ACCURACY_LAYOUT)

    return timed_trial(
        "zfp",
        f"tolerance {tolerance:.3g}, {values.dtype}, {ACCURACY_LAYOUT}",
        encode,
        decode_,
        untimed=lambda decoded: decoded.astype(np.float64),
    )
