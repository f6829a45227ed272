"""TTHRESH (a general Tucker compressor) on the centred tensor when a ``tthresh`` binary is on
the PATH; never vendored or built here. Its ``-e`` is the relative Frobenius error of the
tensor, which on the centred tensor is exactly KG / 100."""

from __future__ import annotations

import atexit
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from tools.bench.peers.base import Context, Trial, search_targets
from tuckercodec import MeshSequence


def run_tthresh(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    """TTHRESH through its command line, on the centred tensor written as raw float64."""
    binary = shutil.which("tthresh")
    if binary is None:
        return []
    k, three, frames = context.tensor.shape
    # Not a with-block: the trials' re-timing runs TTHRESH again after this function returns.
    folder = tempfile.mkdtemp(prefix="tkc-tthresh-")
    atexit.register(shutil.rmtree, folder, True)
    raw = Path(folder) / "tensor.raw"
    compressed = Path(folder) / "tensor.tthresh"
    restored = Path(folder) / "restored.raw"
    context.tensor.tofile(raw)  # C order, time fastest: TTHRESH's first size varies fastest

    def compress(bound: float) -> bytes:
        sizes = [str(frames), str(three), str(k)]
        arguments = ["-i", str(raw), "-t", "double", "-s", *sizes, "-e", repr(bound)]
        subprocess.run(
            [binary, *arguments, "-c", str(compressed)],
            check=True,
            capture_output=True,
            timeout=3600,
        )
        return compressed.read_bytes()

    def decompress(payload: bytes) -> np.ndarray:
        compressed.write_bytes(payload)
        subprocess.run(
            [binary, "-c", str(compressed), "-o", str(restored)],
            check=True,
            capture_output=True,
            timeout=3600,
        )
        return np.fromfile(restored, dtype=np.float64).reshape(context.tensor.shape)

    def guess(target: float) -> float:  # -e is the relative error of the centred tensor
        return target / 100.0

    return search_targets(
        "tthresh", targets, context, guess, compress, decompress, lambda b: f"-e {b:.3g}"
    )
