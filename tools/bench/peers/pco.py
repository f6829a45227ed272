"""pcodec (pco) standalone, lossless, at its strongest level (12; the default 8 is up to 20 %
larger on chicken), on the flattened positions in their own precision (float32 where exact,
else float64) in each layout of :data:`~tools.bench.peers.base.LAYOUTS` (pco predicts along one
dimension, so the layout decides what is next to what), the faces once: a peer of the lossless
suite."""

from __future__ import annotations

import numpy as np

from tools.bench.peers.base import LAYOUTS, Trial, lossless_trial
from tuckercodec import MeshSequence

LEVEL = 12


def run_pcodec(sequence: MeshSequence, values: np.ndarray) -> list[Trial]:
    from pcodec import ChunkConfig, standalone

    def compress(arranged: np.ndarray) -> bytes:
        config = ChunkConfig(compression_level=LEVEL)
        return bytes(standalone.simple_compress(arranged.reshape(-1), config))

    def decompress(payload: bytes, like: np.ndarray) -> np.ndarray:
        return np.asarray(standalone.simple_decompress(payload))

    return [
        lossless_trial("pcodec", f"level {LEVEL}", sequence, values, layout, compress, decompress)
        for layout in LAYOUTS
    ]
