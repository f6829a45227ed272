"""The positions as float32 with zstd 19: the lossless reference."""

from __future__ import annotations

import numpy as np
import zstandard

from tools.bench.peers.base import Context, Trial, faces_once, timed_trial, zstd_bytes
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
