"""Benchmark of the exact rate-distortion table against plain SVDs, on the real sequences.

For each sequence: the wall time of ``analyze`` (centring, HOSVD, the exact table of every
(i, 3, k) and the bound), median of several runs on the array already in memory; in the same
run, the wall time of numpy's SVDs of the mode-1 and mode-3 unfoldings (all singular vectors
of the thin problem, the plain way to get the same factors); and the peak memory that
``analyze`` allocates, as a multiple of the float64 tensor (K * 3 * F * 8 bytes).

    python tools/bench_analysis.py                 # every sequence in ../shared/data present
    python tools/bench_analysis.py path/to/seq.npz --repeat 7
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from tuckercodec import load_sequence
from tuckercodec.analysis import analyze
from tuckercodec.hosvd import reconstruct

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
DEFAULT_SEQUENCES = ["samba.npz", "chicken.npz", "horse-gallop", "cloth-vellum.npz"]


def median_time(function, repeat: int) -> tuple[float, float, float]:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times), max(times)


def plain_svds(vertices: np.ndarray) -> None:
    """The reference: numpy's SVD of each unfolding of the centred tensor, all vectors kept."""
    centred = vertices - vertices.mean(axis=1, keepdims=True)
    tensor = np.ascontiguousarray(centred.transpose(1, 2, 0))
    k, _, f = tensor.shape
    np.linalg.svd(tensor.reshape(k, 3 * f), full_matrices=False)
    np.linalg.svd(tensor.transpose(2, 0, 1).reshape(f, 3 * k), full_matrices=False)


def peak_memory(vertices: np.ndarray) -> int:
    """Bytes allocated at the peak of one ``analyze`` call, beyond what existed before."""
    tracemalloc.start()
    tracemalloc.reset_peak()
    before = tracemalloc.get_traced_memory()[0]
    result = analyze(vertices)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    del result
    return peak - before


def accuracy(analysis, targets=(1.0, 0.1, 0.02, 0.005)) -> str:
    """Relative gap between the table and an explicit reconstruction at the cheapest ranks."""
    parts = []
    tensor = analysis.decomposition.tensor
    for target in targets:
        choice = analysis.cheapest(target)
        core, u1, u2, u3 = analysis.truncate(choice.i, choice.k)
        explicit = float(np.sum((tensor - reconstruct(core, u1, u2, u3)) ** 2))
        gap = abs(analysis.error_table()[choice.i, choice.k] - explicit) / explicit
        parts.append(f"KG {choice.kg:.3g} ({choice.i},{choice.k}): {gap:.0e}")
    return "; ".join(parts)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequences", nargs="*", help="npz files or OBJ folders (default: shared data)")
    parser.add_argument("--repeat", type=int, default=5, help="runs per timing (median reported)")
    parser.add_argument("--svd-repeat", type=int, default=3, help="runs of the plain SVDs")
    args = parser.parse_args(argv)

    paths = [Path(p) for p in args.sequences] or [
        SHARED_DATA / name for name in DEFAULT_SEQUENCES if (SHARED_DATA / name).exists()
    ]
    if not paths:
        print(f"no sequences given and none found in {SHARED_DATA}", file=sys.stderr)
        return 2

    print(f"machine: {platform.platform()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}")
    print(f"command: python tools/bench_analysis.py {' '.join(argv or sys.argv[1:])}".rstrip())
    print()
    print("| sequence | K | F | table (i x k) | analyze median [min-max] s | first call s "
          "| plain SVDs median s | speed-up | peak memory / tensor |")
    print("|---|---|---|---|---|---|---|---|---|")
    gaps: list[str] = []
    for path in paths:
        sequence = load_sequence(path, progress=False)
        vertices = sequence.vertices
        frames, count, _ = vertices.shape
        start = time.perf_counter()
        analysis = analyze(vertices)  # the first call of the process, as the CLI sees it
        first = time.perf_counter() - start
        r1, r3 = analysis.max_ranks
        fast = median_time(lambda v=vertices: analyze(v), args.repeat)
        slow = median_time(lambda v=vertices: plain_svds(v), args.svd_repeat)
        peak = peak_memory(vertices)
        gaps.append(f"- {path.name}: {accuracy(analysis)}")
        tensor_bytes = count * 3 * frames * 8
        print(
            f"| {path.name} | {count} | {frames} | {r1 + 1} x {r3 + 1} | "
            f"{fast[0]:.3f} [{fast[1]:.3f}-{fast[2]:.3f}] | {first:.3f} | {slow[0]:.3f} | {slow[0] / fast[0]:.1f}x | "
            f"{peak / tensor_bytes:.2f}x ({peak / 2**20:.0f} MiB) |"
        )
    print()
    print("Table against explicit reconstruction, relative gap in the squared error:")
    print("\n".join(gaps))
    return 0


if __name__ == "__main__":
    sys.exit(main())
