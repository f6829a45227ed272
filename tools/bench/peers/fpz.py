"""fpzip (Lindstrom and Isenburg 2006) at precision 0, lossless, on the positions in their own
precision (float32 where exact, else float64) in each layout of
:data:`~tools.bench.peers.base.LAYOUTS` (fpzip's predictor is three-dimensional: the layout
decides which neighbours predict a value), the faces once: a peer of the lossless suite."""

from __future__ import annotations

import numpy as np

from tools.bench.peers.base import LAYOUTS, Trial, lossless_trial
from tuckercodec import MeshSequence


def run_fpzip(sequence: MeshSequence, values: np.ndarray) -> list[Trial]:
    import fpzip

    def compress(arranged: np.ndarray) -> bytes:
        return bytes(fpzip.compress(arranged, precision=0, order="C"))

    def decompress(payload: bytes, like: np.ndarray) -> np.ndarray:
        return np.asarray(fpzip.decompress(payload, order="C"))

    return [
        lossless_trial("fpzip", "precision 0", sequence, values, layout, compress, decompress)
        for layout in LAYOUTS
    ]
