"""How well a size target uses its budget: ``encode(seq, target_bpfv=B)``.

For each sequence (default: every one of ../shared/data present; ``sample`` is the built-in
cloth) and each budget B (``--bpfv``, default 0.5 1 2 4), the file is encoded from scratch (the
analysis included, as ``tuckercodec encode --bpfv B`` does) and the tool prints:

* the asked B and the whole file's bpfv (every byte: preamble, header, every section), and
  their ratio, the fill; the target is 0.98 <= fill <= 1 wherever B is reachable;
* the decoded KG error: Karni-Gotsman, in percent, each frame centred on its own centroid
  (``tuckercodec.kg_error``), measured here on the decoder's positions;
* the encode time, the median of ``--repeat`` encodes (and their range), and for comparison the
  median time of ``encode(seq, target_kg=K)`` at the KG error K the size target reached, with
  the ratio of the two (the brief: a size target within about twice a KG target's time).

A budget below the coarsest file is reported as unreachable (the codec's own message). A file
larger than B is a bug: the tool then exits with 1. ``--segment-frames N`` measures the
segmented encoder's size target instead (format 1.1/1.2 segments of N frames).

    python -m tools.bench bpfv
    python -m tools.bench bpfv sample --bpfv 1 2 --repeat 3
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

from tools import common
from tools.bench import arguments
from tuckercodec import (
    Decoder,
    MeshSequence,
    UnreachableTargetError,
    bpfv,
    encode,
    encode_with_report,
    kg_error,
)

DEFAULT_BUDGETS = [0.5, 1.0, 2.0, 4.0]
#: Target: the whole file between this share of B and B, wherever B is reachable.
LEAST_FILL = 0.98


def _timed(function: Callable[[], bytes], runs: int) -> tuple[bytes, list[float]]:
    """The result of the last call and the wall time of each of ``runs`` calls."""
    times = []
    data = b""
    for _ in range(runs):
        start = time.perf_counter()
        data = function()
        times.append(time.perf_counter() - start)
    return data, times


def measure(
    sequence: MeshSequence, budget: float, runs: int, segment_frames: int | None
) -> dict[str, float] | str:
    """One row's figures, or the reason the budget cannot be met."""
    try:
        data, times = _timed(
            lambda: encode_sized(sequence, budget, segment_frames),
            runs,
        )
    except UnreachableTargetError as error:
        return f"unreachable: {error}"
    size = bpfv(len(data), sequence.frame_count, sequence.vertex_count)
    kg = kg_error(sequence.vertices, Decoder(data).positions())
    _, kg_times = _timed(lambda: encode_kg(sequence, kg, segment_frames), runs)
    return {
        "bytes": len(data),
        "bpfv": size,
        "fill": size / budget,
        "kg": kg,
        "seconds": statistics.median(times),
        "low": min(times),
        "high": max(times),
        "kg_seconds": statistics.median(kg_times),
    }


def encode_sized(sequence: MeshSequence, budget: float, segment_frames: int | None) -> bytes:
    if segment_frames is None:
        return encode(sequence, target_bpfv=budget)
    return encode_with_report(sequence, target_bpfv=budget, segment_frames=segment_frames).data


def encode_kg(sequence: MeshSequence, kg: float, segment_frames: int | None) -> bytes:
    if segment_frames is None:
        return encode(sequence, target_kg=kg)
    return encode_with_report(sequence, target_kg=kg, segment_frames=segment_frames).data


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The bpfv suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument("--bpfv", type=float, nargs="+", default=DEFAULT_BUDGETS)
    arguments.repeat(parser, 1, "encodes timed per point, the median reported")
    parser.add_argument("--segment-frames", type=int, default=None)


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    sources = args.sequences or common.shared_sequences()
    if not sources:
        print(f"no sequences: {common.SHARED_DATA} is absent", file=sys.stderr)
        return 1
    mode = "" if args.segment_frames is None else f", segments of {args.segment_frames} frames"
    print(
        f"size targets{mode}; decoded KG: Karni-Gotsman, per-frame centroid, percent "
        f"(tuckercodec.kg_error); times: median of {args.repeat} encode(s) from scratch"
    )
    print(
        "| sequence | asked bpfv | file bpfv | fill | bytes | decoded KG | encode s "
        "| --kg encode s at that KG | ratio |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    over, short = [], []
    for source in sources:
        name = common.SAMPLE if source == common.SAMPLE else Path(source).name
        sequence = common.load(source)
        for budget in args.bpfv:
            row = measure(sequence, budget, args.repeat, args.segment_frames)
            if isinstance(row, str):
                print(f"| {name} | {budget:g} | {row} | | | | | | |")
                continue
            if row["fill"] > 1.0:
                over.append(f"{name} B={budget:g}: {row['bpfv']:.4f}")
            elif row["fill"] < LEAST_FILL:
                short.append(f"{name} B={budget:g}: fill {row['fill']:.4f}")
            spread = f"{row['seconds']:.2f}"
            if args.repeat > 1:
                spread += f" [{row['low']:.2f}-{row['high']:.2f}]"
            print(
                f"| {name} | {budget:g} | {row['bpfv']:.4f} | {row['fill']:.4f} "
                f"| {int(row['bytes'])} | {row['kg']:.5f} | {spread} "
                f"| {row['kg_seconds']:.2f} | {row['seconds'] / row['kg_seconds']:.2f} |"
            )
    print(f"fills below {LEAST_FILL}: {', '.join(short) or 'none'}")
    print(f"files over their budget: {', '.join(over) or 'none'}")
    return 1 if over else 0
