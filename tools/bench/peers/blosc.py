"""Blosc2, lossless: zstd at clevel 9 behind a byte shuffle, a bit shuffle, or a byte shuffle
and bytedelta (Blosc's suggestion for floats), typesize the values' itemsize, one chunk; on the
positions in their own precision (float32 where exact, else float64) in each layout of
:data:`~tools.bench.peers.base.LAYOUTS`, the faces once: a peer of the lossless suite."""

from __future__ import annotations

import numpy as np

from tools.bench.peers.base import LAYOUTS, Trial, lossless_trial
from tuckercodec import MeshSequence

CLEVEL = 9
#: The filter pipelines tried, by the name the table gives them.
FILTERS = ("shuffle", "bitshuffle", "shuffle+bytedelta")


def run_blosc2(sequence: MeshSequence, values: np.ndarray) -> list[Trial]:
    import blosc2

    pipelines = {
        "shuffle": [blosc2.Filter.SHUFFLE],
        "bitshuffle": [blosc2.Filter.BITSHUFFLE],
        "shuffle+bytedelta": [blosc2.Filter.SHUFFLE, blosc2.Filter.BYTEDELTA],
    }

    def trial(layout: str, name: str) -> Trial:
        def compress(arranged: np.ndarray) -> bytes:
            cparams = blosc2.CParams(
                codec=blosc2.Codec.ZSTD,
                clevel=CLEVEL,
                filters=pipelines[name],
                typesize=arranged.itemsize,
            )
            return bytes(blosc2.compress2(arranged, cparams=cparams))

        def decompress(payload: bytes, like: np.ndarray) -> np.ndarray:
            return np.frombuffer(blosc2.decompress2(payload), dtype=like.dtype)

        setting = f"zstd {CLEVEL} {name}"
        return lossless_trial("blosc2", setting, sequence, values, layout, compress, decompress)

    return [trial(layout, name) for layout in LAYOUTS for name in FILTERS]
