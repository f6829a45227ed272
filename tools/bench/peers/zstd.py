"""zstd level 19 on the plain positions: the lossless reference.

For the peers suite, the positions as float32 (exact for float32 input only). For the lossless
suite, the positions in their own precision (float32 where exact, else float64) in
each layout of :data:`~tools.bench.peers.base.LAYOUTS`, bit-exact by construction.
"""

from __future__ import annotations

import numpy as np
import zstandard

from tools.bench.peers.base import (
    LAYOUTS,
    Context,
    Trial,
    faces_once,
    lossless_trial,
    timed_trial,
    zstd_bytes,
)
from tuckercodec import MeshSequence


def run_zstd(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    faces = faces_once(sequence)

    def encode() -> tuple[int, int, bytes]:
        payload = zstd_bytes(sequence.vertices.astype("<f4").tobytes())
        return len(payload) + len(faces), len(faces), payload

    def decode_(payload: bytes) -> np.ndarray:
        raw = zstandard.ZstdDecompressor().decompress(payload)
        return np.frombuffer(raw, dtype="<f4").reshape(sequence.vertices.shape).astype(np.float64)

    return [timed_trial("zstd-f32", "lossless float32", encode, decode_)]


def run_zstd_lossless(sequence: MeshSequence, values: np.ndarray) -> list[Trial]:
    """zstd 19 on ``values`` (the positions in their own precision) in every layout."""

    def compress(arranged: np.ndarray) -> bytes:
        return zstd_bytes(arranged.tobytes())

    def decompress(payload: bytes, like: np.ndarray) -> np.ndarray:
        raw = zstandard.ZstdDecompressor().decompress(payload)
        return np.frombuffer(raw, dtype=like.dtype)

    return [
        lossless_trial("zstd-19", "level 19", sequence, values, layout, compress, decompress)
        for layout in LAYOUTS
    ]
