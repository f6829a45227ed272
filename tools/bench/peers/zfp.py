"""zfp (zfpy, absolute tolerance, K x 3 x F) on the centred float64 tensor, with the per-frame
centroids as float32 and the faces once; the tolerance is searched so that the decoded KG error
meets each target."""

from __future__ import annotations

import numpy as np

from tools.bench.peers.base import Context, Trial, rms_error, search_targets
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
