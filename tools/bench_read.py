"""Benchmark of reading a folder of OBJ frames with ``load_sequence`` (default: horse gallop).

Times the whole ``load_sequence(folder)`` call (finding and sorting the files, parsing every
frame, checking vertex counts and faces against the first frame, building the MeshSequence).
One untimed warm-up run first puts the files in the operating system's cache, so the timings
measure parsing, not the disk. Prints Markdown ready to paste into BENCHMARKS.md.

    python -m tools.bench_read                        # ../shared/data/horse-gallop
    python -m tools.bench_read path/to/frames --repeat 9
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

from tools import common
from tuckercodec import load_sequence

DEFAULT_FOLDER = common.SHARED_DATA / "horse-gallop"
TARGET_SECONDS = 1.5  # the goal for horse gallop (48 frames, 32 MB) on a 2-core machine


def time_loads(folder: Path, repeat: int) -> list[float]:
    """Wall times of ``repeat`` calls of ``load_sequence(folder)``, after one warm-up call."""
    return common.timed(lambda: load_sequence(folder, progress=False), repeat)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the result; returns the process exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench_read", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "folder", nargs="?", type=Path, default=DEFAULT_FOLDER, help="folder of OBJ frames"
    )
    parser.add_argument("--repeat", type=int, default=5, help="timed runs (median reported)")
    args = parser.parse_args(argv)
    if not args.folder.is_dir():
        print(
            f"{args.folder} is not a folder (the default data lives in {common.SHARED_DATA})",
            file=sys.stderr,
        )
        return 2
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")

    sequence = common.load(args.folder)
    size = sum((args.folder / name).stat().st_size for name in sequence.frame_names)
    times = time_loads(args.folder, args.repeat)
    median = statistics.median(times)

    print(f"machine: {common.machine()}")
    print(f"command: {common.command('tools.bench_read', argv)}")
    print()
    print("| sequence | frames | vertices | faces | MB | median s | min s | max s | MB/s | runs |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print(
        f"| {args.folder.name} | {sequence.frame_count} | {sequence.vertex_count} | "
        f"{len(sequence.faces)} | {size / 1e6:.1f} | {median:.3f} | {min(times):.3f} | "
        f"{max(times):.3f} | {size / 1e6 / median:.0f} | {args.repeat} |"
    )
    if args.folder.resolve() == DEFAULT_FOLDER.resolve():
        verdict = "met" if median <= TARGET_SECONDS else "NOT met"
        print(f"\ntarget: at most {TARGET_SECONDS} s for horse gallop: {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
