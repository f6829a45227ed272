"""Benchmark of the codec on the real sequences: rate against the reference, speed, memory.

For each sequence (default: every one of ../shared/data present) three tables:

1. Rate, one encode per KG target (``--targets``): the ranks chosen, the decoded KG error
   measured here, independently of the encoder, as ``kg_error(original, decode(data))`` and
   checked to be at most the target (FAIL otherwise), the whole-file bpfv (8 * file bytes /
   (F * K)), the connectivity's (FACE section) share, and the reference of ../shared/NOTES.md
   (geometry from the throwaway quantization script plus zstd on the plain triangle list).
   With ``select="bound"`` (the seed paper's rank choice; one more encode per point, skipped
   with ``--no-bound``): its ranks and bpfv.
2. Speed at one target (``--speed-target``, default KG 0.1), median of ``--repeat`` runs after
   one warm-up: end to end (``load_sequence`` of the file on disk, encode, bytes written to
   /tmp), encode alone from the sequence in memory, opening the file (``Decoder(data)``: header,
   faces and factor matrices), decoding every frame (open + ``positions()``), one frame from an
   opened decoder (median over ``--frames`` random frames) and one frame cold (open + frame).
3. Peak memory (tracemalloc) of one encode and of one decode of every frame (open +
   ``positions()``, the output array included), in MiB and over the float64 tensor
   K * 3 * F * 8 bytes. The input sequence is not counted; zstd's own buffers (C allocations)
   are invisible to tracemalloc.

Errors are KG errors (Karni-Gotsman, per-frame centroid), in percent.

    python -m tools.bench codec                    # every sequence in ../shared/data present
    python -m tools.bench codec ../shared/data/chicken.npz --repeat 1 --targets 1 0.1
"""

from __future__ import annotations

import argparse
import datetime
import os
import shutil
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import tuckercodec
from tools import common
from tools.bench import arguments
from tools.bench.arguments import UsageError
from tools.common import spread, timed, traced_peak
from tuckercodec import Decoder, bpfv, decode, encode_with_report, kg_error

DEFAULT_TARGETS = [1.0, 0.5, 0.1, 0.05, 0.02]

#: ../shared/NOTES.md: geometry-only bpfv of the throwaway script at KG 1, 0.5, 0.1, 0.05, 0.02.
REFERENCE_GEOMETRY = {
    "chicken": dict(zip(DEFAULT_TARGETS, [0.55, 0.76, 1.40, 1.74, 2.20], strict=True)),
    "samba": dict(zip(DEFAULT_TARGETS, [0.79, 1.36, 3.97, 5.77, 9.09], strict=True)),
    "horse": dict(zip(DEFAULT_TARGETS, [0.99, 1.65, 3.94, 5.26, 7.26], strict=True)),
}
#: ../shared/NOTES.md: zstd level 19 on the plain int32 triangle list, in bpfv.
REFERENCE_FACES = {"chicken": 0.13, "samba": 0.34, "horse": 1.11, "cloth": 1.40}

#: The codec's targets, for samba (the timings) and every sequence (the memory).
TARGET_END_TO_END_S = 3.0
TARGET_DECODE_ALL_S = 0.5
TARGET_ONE_FRAME_S = 0.005
TARGET_MEMORY_RATIO = 4.0


def reference_key(path: Path) -> str | None:
    """The name NOTES.md uses for a sequence (``horse-gallop`` -> ``horse``), if it has one."""
    name = path.name.lower()
    return next((key for key in REFERENCE_FACES if name.startswith(key)), None)


def fmt_target(target: float) -> str:
    return f"{target:g}"


# ------------------------------------------------------------------------------------------
# 1. rate


@dataclass
class RatePoint:
    sequence: str
    target: float
    ranks: tuple[int, int]
    kg: float  # measured here, on decode(data)
    encoder_kg: float  # what the encoder reports
    bpfv: float
    face_bpfv: float
    reference: tuple[float, float] | None  # (geometry, faces) from NOTES.md
    seconds: float
    #: the report's exact_ranks and bound_ranks
    truncation_picks: tuple[tuple[int, int], tuple[int, int]] | None = None
    bound_ranks: tuple[int, int] | None = None
    bound_bpfv: float | None = None
    bound_kg: float | None = None
    bound_seconds: float | None = None


def rate_point(sequence, path: Path, target: float, with_bound: bool) -> RatePoint:
    frames, vertices = sequence.frame_count, sequence.vertex_count
    key = reference_key(path)
    geometry = REFERENCE_GEOMETRY.get(key or "", {}).get(target)
    faces = REFERENCE_FACES.get(key or "")
    reference = (geometry, faces) if geometry is not None and faces is not None else None

    result = encode_with_report(sequence, target_kg=target)
    report = result.report
    exact, bound_ranks = report.exact_ranks, report.bound_ranks  # None for fixed ranks
    point = RatePoint(
        sequence=path.name,
        target=target,
        ranks=report.ranks,
        kg=kg_error(sequence, decode(result.data)),
        encoder_kg=report.kg,
        bpfv=bpfv(len(result.data), frames, vertices),
        face_bpfv=report.connectivity_bpfv,
        reference=reference,
        seconds=report.seconds,
        truncation_picks=(
            (exact, bound_ranks) if exact is not None and bound_ranks is not None else None
        ),
    )
    if with_bound:
        bound = encode_with_report(sequence, target_kg=target, select="bound")
        point.bound_ranks = bound.report.ranks
        point.bound_bpfv = bpfv(len(bound.data), frames, vertices)
        point.bound_kg = kg_error(sequence, decode(bound.data))
        point.bound_seconds = bound.report.seconds
    return point


def rate_row(p: RatePoint, with_bound: bool) -> str:
    check = "ok" if p.kg <= p.target else "**FAIL**"
    if p.reference is not None:
        geometry, faces = p.reference
        total = geometry + faces
        reference = f"{geometry:.2f} + {faces:.2f} = {total:.2f}"
        gap = 100.0 * (p.bpfv / total - 1.0)
        verdict = f"yes ({gap:+.0f} %)" if p.bpfv <= total else f"**NO** ({gap:+.0f} %)"
    else:
        reference, verdict = "-", "-"
    cells = [
        p.sequence,
        fmt_target(p.target),
        f"({p.ranks[0]}, {p.ranks[1]})",
        f"{p.kg:.4f}",
        check,
        f"{p.bpfv:.3f}",
        f"{p.face_bpfv:.3f}",
        f"{p.bpfv - p.face_bpfv:.3f}",
        reference,
        verdict,
    ]
    if with_bound:
        assert p.bound_kg is not None and p.bound_ranks is not None and p.bound_bpfv is not None
        bound_check = "" if p.bound_kg <= p.target else " **FAIL**"
        cells += [
            f"({p.bound_ranks[0]}, {p.bound_ranks[1]})",
            f"{p.bound_bpfv:.3f} ({100.0 * (p.bound_bpfv / p.bpfv - 1.0):+.1f} %){bound_check}",
        ]
    if p.truncation_picks is None:
        cells.append("-")
    else:
        (ei, ek), (bi, bk) = p.truncation_picks
        cells.append(f"({ei}, {ek}) / ({bi}, {bk})")
    cells.append(f"{p.seconds:.2f}" + (f" / {p.bound_seconds:.2f}" if with_bound else ""))
    return "| " + " | ".join(cells) + " |"


# ------------------------------------------------------------------------------------------
# 2. speed and 3. memory


@dataclass
class SpeedResult:
    sequence: str
    vertices: int
    frames: int
    bpfv: float
    end_to_end: list[float]
    encode: list[float]
    open: list[float]
    decode_all: list[float]
    one_frame: list[float]
    one_frame_cold: list[float]
    encode_peak: int
    decode_peak: int

    @property
    def tensor_bytes(self) -> int:
        return self.vertices * 3 * self.frames * 8


def measure_speed(
    path: Path,
    sequence,
    target: float,
    repeat: int,
    frame_samples: int,
    out_dir: Path,
    rng: np.random.Generator,
) -> SpeedResult:
    output = out_dir / f"{path.stem}.tkc"

    def end_to_end() -> None:
        loaded = common.load(path)
        output.write_bytes(encode_with_report(loaded, target_kg=target).data)

    end_to_end_times = timed(end_to_end, repeat)
    encode_times = timed(lambda: encode_with_report(sequence, target_kg=target), repeat)
    data = output.read_bytes()
    open_times = timed(lambda: Decoder(data), repeat)
    decode_all_times = timed(lambda: Decoder(data).positions(), repeat)

    decoder = Decoder(data)
    frames = rng.integers(0, sequence.frame_count, size=frame_samples)
    one_frame_times = []
    decoder.frame(int(frames[0]))  # warm-up
    for n in frames:
        start = time.perf_counter()
        decoder.frame(int(n))
        one_frame_times.append(time.perf_counter() - start)
    cold_frames = iter(rng.integers(0, sequence.frame_count, size=repeat + 1))
    cold_times = timed(lambda: Decoder(data).frame(int(next(cold_frames))), repeat)

    encode_peak = traced_peak(lambda: encode_with_report(sequence, target_kg=target))
    decode_peak = traced_peak(lambda: Decoder(data).positions())
    return SpeedResult(
        sequence=path.name,
        vertices=sequence.vertex_count,
        frames=sequence.frame_count,
        bpfv=bpfv(len(data), sequence.frame_count, sequence.vertex_count),
        end_to_end=end_to_end_times,
        encode=encode_times,
        open=open_times,
        decode_all=decode_all_times,
        one_frame=one_frame_times,
        one_frame_cold=cold_times,
        encode_peak=encode_peak,
        decode_peak=decode_peak,
    )


def verdict(value: float, limit: float) -> str:
    return "met" if value <= limit else "**NOT met**"


# ------------------------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The codec suite's options."""
    arguments.sequences(parser, "the real sequences of ../shared/data present")
    parser.add_argument(
        "--targets",
        type=float,
        nargs="+",
        default=DEFAULT_TARGETS,
        help="KG targets of the rate table, in percent",
    )
    arguments.repeat(parser, 5, "runs per timing, the median reported")
    parser.add_argument(
        "--speed-target", type=float, default=0.1, help="KG target of the speed and memory tables"
    )
    parser.add_argument(
        "--frames",
        type=int,
        default=50,
        help="random frames timed one by one from an opened decoder",
    )
    parser.add_argument(
        "--no-bound",
        action="store_true",
        help="skip the extra encode per point with the paper's bound (select='bound')",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the random frame choice")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    if args.frames < 1:
        raise UsageError("--frames must be at least 1")
    if any(not (t > 0) for t in [*args.targets, args.speed_target]):
        raise UsageError("KG targets must be positive")
    with_bound = not args.no_bound

    given = [Path(name) for name in args.sequences]
    if given:
        found = [path for path in given if path.exists() or str(path) == common.SAMPLE]
        skipped = [f"{path}: not found" for path in given if path not in found]
    else:
        found, absent = common.in_shared_data(common.REAL_SEQUENCES)
        skipped = [f"{path.name}: not in {common.SHARED_DATA}" for path in absent]
    paths = found
    for message in skipped:
        print(f"skipped {message}", file=sys.stderr)
    if not paths:
        where = "none of the paths given exists" if given else f"none found in {common.SHARED_DATA}"
        print(f"no sequences to measure: {where}", file=sys.stderr)
        return 2

    started = time.perf_counter()
    load_before = os.getloadavg()
    print(f"machine: {common.machine()}, tuckercodec {tuckercodec.__version__}")
    print(f"command: {args.command}")
    print(f"date: {datetime.datetime.now().astimezone().isoformat(timespec='seconds')}")
    print(f"load average at start (1, 5, 15 min): {', '.join(f'{x:.2f}' for x in load_before)}")
    for message in skipped:
        print(f"skipped {message}")
    print()

    sequences = [(path, common.load(path)) for path in paths]

    # 1. rate ------------------------------------------------------------------------------
    print("## Rate: decoded KG error and whole-file size")
    print()
    print(
        "Decoded KG measured here as kg_error(original, decode(data)); bpfv counts the whole "
        "file; geometry = bpfv - FACE. Reference (NOTES.md) = geometry of the throwaway "
        "script + zstd-19 on the plain triangle list. Bound = encode with select='bound' "
        "(the paper's rank choice). Truncation only = the cheapest ranks whose truncation alone "
        "meets the whole target, by the exact table / by the bound (the report's exact_ranks, "
        "bound_ranks)."
    )
    print()
    header = (
        "| sequence | target KG | ranks (i, k) | decoded KG | <= target | bpfv | FACE bpfv "
        "| geometry bpfv | reference bpfv | at or under reference |"
    )
    rule = "|---|---|---|---|---|---|---|---|---|---|"
    if with_bound:
        header += " bound: ranks | bound: bpfv (vs exact) |"
        rule += "---|---|"
    header += " truncation only: exact / bound |"
    header += " encode s" + (" (exact / bound)" if with_bound else "") + " |"
    rule += "---|---|"
    print(header)
    print(rule)
    failures: list[str] = []
    notes: list[str] = []
    for path, sequence in sequences:
        for target in args.targets:
            point = rate_point(sequence, path, target, with_bound)
            print(rate_row(point, with_bound), flush=True)
            if point.kg > point.target:
                failures.append(
                    f"{path.name} at KG {fmt_target(target)}: decoded KG {point.kg:.6f} "
                    f"is above the target"
                )
            if point.bound_kg is not None and point.bound_kg > point.target:
                failures.append(
                    f"{path.name} at KG {fmt_target(target)} (select='bound'): decoded KG "
                    f"{point.bound_kg:.6f} is above the target"
                )
            if abs(point.kg - point.encoder_kg) > 1e-6 * max(point.kg, 1e-12):
                notes.append(
                    f"{path.name} at KG {fmt_target(target)}: the encoder reports KG "
                    f"{point.encoder_kg:.8f}, measured here {point.kg:.8f}"
                )
            if point.bound_bpfv is not None and point.bound_bpfv < point.bpfv:
                notes.append(
                    f"{path.name} at KG {fmt_target(target)}: select='bound' gives a smaller "
                    f"file than 'exact' ({point.bound_bpfv:.3f} < {point.bpfv:.3f} bpfv)"
                )
    print()
    if failures:
        print("**FAIL** decoded error above the target:")
        for failure in failures:
            print(f"- **FAIL** {failure}")
            print(f"FAIL {failure}", file=sys.stderr)
    else:
        print("Every decoded KG error is at most its target.")
    if notes:
        print()
        print("Notes:")
        print("\n".join(f"- {note}" for note in notes))
    print()

    # 2. speed, 3. memory ---------------------------------------------------------------------
    out_dir = Path(tempfile.mkdtemp(prefix="bench_codec_", dir="/tmp"))
    rng = np.random.default_rng(args.seed)
    results: list[SpeedResult] = []
    try:
        for path, sequence in sequences:
            results.append(
                measure_speed(
                    path, sequence, args.speed_target, args.repeat, args.frames, out_dir, rng
                )
            )
    finally:
        shutil.rmtree(out_dir, ignore_errors=True)

    print(f"## Speed at KG {fmt_target(args.speed_target)}")
    print()
    print(
        f"Median [min-max] of {args.repeat} runs after one warm-up. End to end = load_sequence "
        "from disk + encode + bytes written to /tmp; encode = from the sequence in memory; open = "
        "Decoder(data); decode all = open + positions(); one frame = from an opened decoder, "
        f"median [min-max] over {args.frames} random frames; cold = open + frame()."
    )
    print()
    print(
        "| sequence | K | F | bpfv | end to end s | encode s | open ms | decode all s "
        "| one frame ms | one frame cold ms |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in results:
        print(
            f"| {r.sequence} | {r.vertices} | {r.frames} | {r.bpfv:.3f} | "
            f"{spread(r.end_to_end, digits=2)} | "
            f"{spread(r.encode, digits=2)} | {spread(r.open, 1e3, 1)} | {spread(r.decode_all)} | "
            f"{spread(r.one_frame, 1e3, 2)} | {spread(r.one_frame_cold, 1e3, 1)} |"
        )
    print()

    print(f"## Peak memory at KG {fmt_target(args.speed_target)}")
    print()
    print(
        "tracemalloc peak of one call beyond what existed before (the input sequence not "
        "counted; decode all includes its output array, 1x), over the float64 tensor K*3*F*8 bytes."
    )
    print()
    print(
        f"| sequence | tensor MiB | encode peak MiB | encode / tensor | decode all peak MiB "
        f"| decode all / tensor | both <= {TARGET_MEMORY_RATIO:g}x |"
    )
    print("|---|---|---|---|---|---|---|")
    for r in results:
        worst = max(r.encode_peak, r.decode_peak) / r.tensor_bytes
        print(
            f"| {r.sequence} | {r.tensor_bytes / 2**20:.1f} | {r.encode_peak / 2**20:.1f} | "
            f"{r.encode_peak / r.tensor_bytes:.3f}x | {r.decode_peak / 2**20:.1f} | "
            f"{r.decode_peak / r.tensor_bytes:.3f}x | {verdict(worst, TARGET_MEMORY_RATIO)} |"
        )
    print()

    print("## Targets")
    print()
    samba = next((r for r in results if reference_key(Path(r.sequence)) == "samba"), None)
    if samba is not None:
        e2e = statistics.median(samba.end_to_end)
        dec = statistics.median(samba.decode_all)
        one = statistics.median(samba.one_frame)
        cold = statistics.median(samba.one_frame_cold)
        print(
            f"- samba end to end <= {TARGET_END_TO_END_S:g} s: {e2e:.2f} s, "
            f"{verdict(e2e, TARGET_END_TO_END_S)}"
        )
        print(
            f"- samba decode all frames <= {TARGET_DECODE_ALL_S:g} s: {dec:.3f} s, "
            f"{verdict(dec, TARGET_DECODE_ALL_S)}"
        )
        print(
            f"- samba one frame <= {TARGET_ONE_FRAME_S * 1e3:g} ms: {one * 1e3:.2f} ms from an "
            f"opened decoder, {verdict(one, TARGET_ONE_FRAME_S)}; cold (open + frame) "
            f"{cold * 1e3:.1f} ms, "
            f"{verdict(cold, TARGET_ONE_FRAME_S)}"
        )
    else:
        print("- samba not measured: the timing targets are not checked")
    worst_encode = max(results, key=lambda r: r.encode_peak / r.tensor_bytes)
    worst_decode = max(results, key=lambda r: r.decode_peak / r.tensor_bytes)
    ratio_e = worst_encode.encode_peak / worst_encode.tensor_bytes
    ratio_d = worst_decode.decode_peak / worst_decode.tensor_bytes
    print(
        f"- peak memory <= {TARGET_MEMORY_RATIO:g}x the tensor: encode at most {ratio_e:.3f}x "
        f"({worst_encode.sequence}), {verdict(ratio_e, TARGET_MEMORY_RATIO)}; decode all at most "
        f"{ratio_d:.3f}x ({worst_decode.sequence}), {verdict(ratio_d, TARGET_MEMORY_RATIO)}"
    )
    print(
        f"- decoded KG error <= target at every point: "
        f"{'met' if not failures else f'**NOT met** ({len(failures)} FAIL)'}"
    )
    print()
    load_after = os.getloadavg()
    print(
        f"load average at end (1, 5, 15 min): {', '.join(f'{x:.2f}' for x in load_after)}; "
        f"benchmark wall time {time.perf_counter() - started:.0f} s"
    )
    return 1 if failures else 0
