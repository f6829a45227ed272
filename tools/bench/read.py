"""Benchmark of reading a whole sequence with ``load_sequence`` (default: horse gallop), as it is
or written in every format.

As it is (a folder of OBJ frames): the whole ``load_sequence(folder)`` call is timed (finding
and sorting the files, parsing every frame, checking vertex counts and faces against the first
frame, building the MeshSequence).

With ``--formats``: the sequence (a folder of OBJ files, an .npz... or ``sample``) is written
once in every whole-sequence format the registry knows, with each of its suffixes (USD,
Alembic, PC2, MDD, glTF, VTK...; a format whose extra is not installed is listed as skipped),
then each file is read back. Point caches (PC2, MDD) carry no faces and take them from an OBJ of
the first frame, whose reading is part of the time. Each row also says whether the positions
came back bit for bit as float32 and the faces unchanged.

Either way, each read is timed ``--repeat`` times after one untimed warm-up that puts the files
in the operating system's cache, so the timings measure parsing, not the disk. Prints Markdown
ready to paste into BENCHMARKS.md.

    python -m tools.bench read                        # ../shared/data/horse-gallop
    python -m tools.bench read path/to/frames --repeat 9
    python -m tools.bench read --formats              # horse gallop in every format
    python -m tools.bench read sample --formats --repeat 9
"""

from __future__ import annotations

import argparse
import functools
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from tools import common
from tools.bench import arguments
from tuckercodec import DependencyError, MeshSequence, formats, load_sequence, save_sequence

DEFAULT_SOURCE = common.SHARED_DATA / "horse-gallop"
OBJ_TARGET_SECONDS = 1.5  # the goal for horse gallop (48 frames, 32 MB) on a 2-core machine
FORMAT_TARGET_SECONDS = 1.0  # the goal for horse gallop read from each format, on a 2-core machine


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The read suite's options."""
    arguments.sequence(parser, str(DEFAULT_SOURCE), "../shared/data/horse-gallop")
    arguments.repeat(parser, 5)
    parser.add_argument(
        "--formats",
        action="store_true",
        help="write the sequence in every format and read each back (default: read it as it is)",
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    return read_formats(args) if args.formats else read_as_it_is(args)


def time_loads(folder: Path, repeat: int) -> list[float]:
    """Wall times of ``repeat`` calls of ``load_sequence(folder)``, after one warm-up call."""
    return common.timed(lambda: load_sequence(folder, progress=False), repeat)


def read_as_it_is(args: argparse.Namespace) -> int:
    """The folder of OBJ frames read as it is."""
    folder = Path(args.sequence)
    if not folder.is_dir():
        print(
            f"{folder} is not a folder (the default data lives in {common.SHARED_DATA})",
            file=sys.stderr,
        )
        return 2

    sequence = common.load(folder)
    size = sum((folder / name).stat().st_size for name in sequence.frame_names)
    times = time_loads(folder, args.repeat)
    median = statistics.median(times)

    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print()
    print("| sequence | frames | vertices | faces | MB | median s | min s | max s | MB/s | runs |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print(
        f"| {folder.name} | {sequence.frame_count} | {sequence.vertex_count} | "
        f"{len(sequence.faces)} | {size / 1e6:.1f} | {median:.3f} | {min(times):.3f} | "
        f"{max(times):.3f} | {size / 1e6 / median:.0f} | {args.repeat} |"
    )
    if folder.resolve() == DEFAULT_SOURCE.resolve():
        verdict = "met" if median <= OBJ_TARGET_SECONDS else "NOT met"
        print(f"\ntarget: at most {OBJ_TARGET_SECONDS} s for horse gallop: {verdict}")
    return 0


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


def read_formats(args: argparse.Namespace) -> int:
    """The sequence written in every format and read back."""
    if args.sequence != common.SAMPLE and not Path(args.sequence).exists():
        print(
            f"{args.sequence} does not exist (data lives in {common.SHARED_DATA})", file=sys.stderr
        )
        return 2

    sequence = common.load(args.sequence)
    name = Path(args.sequence).name
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
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
            options: dict[str, Any] = {"faces": faces_file} if "faces" in found.read_options else {}
            times = common.timed(functools.partial(load_sequence, path, **options), args.repeat)
            back = load_sequence(path, **options)
            size = sum(p.stat().st_size for p in home.rglob("*") if p.is_file())
            median = statistics.median(times)
            verdict = "met" if median <= FORMAT_TARGET_SECONDS else "NOT met"
            missed += median > FORMAT_TARGET_SECONDS
            print(
                f"| {found.name} | {path.name} | {size / 1e6:.1f} | {median:.3f} | "
                f"{min(times):.3f} | {max(times):.3f} | {_fidelity(sequence, back)} | "
                f"≤ {FORMAT_TARGET_SECONDS} s: {verdict} |"
            )
    return 1 if missed else 0
