"""Benchmark of reading a sequence from each file format (default: horse gallop).

The sequence is written once in every whole-sequence format the registry knows, with each of
its suffixes (USD, Alembic,
PC2, MDD, glTF, VTK...; a format whose extra is not installed is listed as skipped), then each
file is read back with ``load_sequence`` ``--repeat`` times after one untimed warm-up that puts
it in the operating system's cache. Point caches (PC2, MDD) carry no faces and take them from an
OBJ of the first frame (``--faces``), whose reading is part of the time. Each row also says
whether the positions came back bit for bit as float32 and the faces unchanged. Prints Markdown
ready to paste into BENCHMARKS.md.

    python -m tools.bench_formats                      # ../shared/data/horse-gallop
    python -m tools.bench_formats sample --repeat 9
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

from tools import common
from tuckercodec import DependencyError, MeshSequence, formats, load_sequence, save_sequence

DEFAULT_SOURCE = common.SHARED_DATA / "horse-gallop"
TARGET_SECONDS = 1.0  # issue 11: reading horse gallop from each format, on a 2-core machine


def _fidelity(original: MeshSequence, back: MeshSequence) -> str:
    """How the read-back sequence compares with what was written."""
    if back.vertices.shape != original.vertices.shape:
        return f"shape {back.vertices.shape}"
    faces = "same faces" if np.array_equal(back.faces, original.faces) else "faces differ"
    written = original.vertices.astype(np.float32)
    if np.array_equal(back.vertices, original.vertices):
        return f"exact (float64), {faces}"
    if np.array_equal(back.vertices.astype(np.float32), written):
        return f"exact (float32), {faces}"
    worst = float(np.abs(back.vertices - written).max())
    return f"max deviation {worst:.2g}, {faces}"


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the result; returns the process exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench_formats", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "source",
        nargs="?",
        default=str(DEFAULT_SOURCE),
        help="a sequence (folder of OBJ files, .npz...) or 'sample'",
    )
    parser.add_argument("--repeat", type=int, default=5, help="timed runs (median reported)")
    args = parser.parse_args(argv)
    if args.source != common.SAMPLE and not Path(args.source).exists():
        print(f"{args.source} does not exist (data lives in {common.SHARED_DATA})", file=sys.stderr)
        return 2
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")

    sequence = common.load(args.source)
    name = Path(args.source).name
    print(f"machine: {common.machine()}")
    print(f"command: {common.command('tools.bench_formats', argv)}")
    print(
        f"\n{name}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
        f"{len(sequence.faces)} faces\n"
    )
    print("| format | file | MB | median s | min s | max s | read back | target |")
    print("|---|---|---|---|---|---|---|---|")
    missed = 0
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        first_frame = MeshSequence(sequence.vertices[:1], sequence.faces)
        save_sequence(first_frame, folder / "faces", progress=False)
        faces_file = next((folder / "faces").glob("*.obj"))
        # every suffix: some name another encoding (.usda text, .usdc crate; .gltf JSON, .glb)
        written = [(f, suffix) for f in formats() if f.write is not None for suffix in f.suffixes]
        for found, suffix in written:
            home = folder / suffix.lstrip(".")  # a folder each: what the format writes is all
            home.mkdir()  # that is in it (a VTK series' frames, XDMF's .h5 beside the .xdmf)
            path = home / f"{name}{suffix}"
            try:
                save_sequence(sequence, path, progress=False)
            except DependencyError as error:
                print(f"| {found.name} | skipped: {error} | | | | | | |")
                continue
            options = {"faces": faces_file} if "faces" in found.read_options else {}
            times = common.timed(
                lambda path=path, options=options: load_sequence(path, **options), args.repeat
            )
            back = load_sequence(path, **options)
            size = sum(p.stat().st_size for p in home.rglob("*") if p.is_file())
            median = statistics.median(times)
            verdict = "met" if median <= TARGET_SECONDS else "NOT met"
            missed += median > TARGET_SECONDS
            print(
                f"| {found.name} | {path.name} | {size / 1e6:.1f} | {median:.3f} | "
                f"{min(times):.3f} | {max(times):.3f} | {_fidelity(sequence, back)} | "
                f"≤ {TARGET_SECONDS} s: {verdict} |"
            )
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
