"""Benchmark of the exact rate-distortion table against plain SVDs, on the real sequences.

For each sequence: the wall time of ``analyze`` (centring, HOSVD, the exact table of every
(i, 3, k) and the bound), median of several runs on the array already in memory; in the same
run, the wall time of numpy's SVDs of the mode-1 and mode-3 unfoldings (all singular vectors
of the thin problem, the plain way to get the same factors); and the peak memory that
``analyze`` allocates, as a multiple of the float64 tensor (K * 3 * F * 8 bytes).

    python -m tools.bench analysis                 # every sequence in ../shared/data present
    python -m tools.bench analysis path/to/seq.npz --repeat 7
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path
from statistics import median

import numpy as np

from tools import common
from tools.bench import arguments
from tuckercodec import analyze
from tuckercodec.internal import reconstruct


def plain_svds(vertices: np.ndarray) -> None:
    """The reference: numpy's SVD of each unfolding of the centred tensor, all vectors kept."""
    centred = vertices - vertices.mean(axis=1, keepdims=True)
    tensor = np.ascontiguousarray(centred.transpose(1, 2, 0))
    k, _, f = tensor.shape
    np.linalg.svd(tensor.reshape(k, 3 * f), full_matrices=False)
    np.linalg.svd(tensor.transpose(2, 0, 1).reshape(f, 3 * k), full_matrices=False)


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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The analysis suite's options."""
    arguments.sequences(parser, "the real sequences of ../shared/data present")
    arguments.repeat(parser, 5, "runs per timing, the median reported")
    parser.add_argument(
        "--svd-repeat", type=arguments.positive_int, default=3, help="runs of the plain SVDs"
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""

    paths = [Path(p) for p in args.sequences] or common.in_shared_data(common.REAL_SEQUENCES)[0]
    if not paths:
        print(f"no sequences given and none found in {common.SHARED_DATA}", file=sys.stderr)
        return 2

    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print()
    print(
        "| sequence | K | F | table (i x k) | analyze median [min-max] s | first call s "
        "| plain SVDs median s | speed-up | peak memory / tensor |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    gaps: list[str] = []
    for path in paths:
        sequence = common.load(path)
        vertices = sequence.vertices
        frames, count, _ = vertices.shape
        start = time.perf_counter()
        analysis = analyze(vertices)  # the first call of the process, as the CLI sees it
        first = time.perf_counter() - start
        r1, r3 = analysis.max_ranks
        fast = common.timed(functools.partial(analyze, vertices), args.repeat, warmup=0)
        slow = common.timed(functools.partial(plain_svds, vertices), args.svd_repeat, warmup=0)
        peak = common.traced_peak(functools.partial(analyze, vertices))
        gaps.append(f"- {path.name}: {accuracy(analysis)}")
        tensor_bytes = count * 3 * frames * 8
        print(
            f"| {path.name} | {count} | {frames} | {r1 + 1} x {r3 + 1} | "
            f"{median(fast):.3f} [{min(fast):.3f}-{max(fast):.3f}] | {first:.3f} | "
            f"{median(slow):.3f} | {median(slow) / median(fast):.1f}x | "
            f"{peak / tensor_bytes:.2f}x ({peak / 2**20:.0f} MiB) |"
        )
    print()
    print("Table against explicit reconstruction, relative gap in the squared error:")
    print("\n".join(gaps))
    return 0
