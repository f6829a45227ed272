"""Benchmark of reading a large sequence a range of frames at a time (``open_frames``).

Writes a float32 sequence of about ``--gigabytes`` (default 1) as each of ``--formats``
(``.npy`` by default; ``pc2``, ``npz`` stored, ``npz-deflated``, ``zarr``; made once in
``--workdir`` and kept), then reads it whole in ranges of ``--frames`` frames (default 64), in
a fresh Python each run, and reports the MB/s of float32 input (F x K x 3 x 4 bytes over the
time from ``open_frames`` to the last range), the resident memory after ``import tuckercodec``
and the process's peak (``ru_maxrss``), and the peak less what one range's float64 array
(the result the caller asked for) takes. "warm" runs read a file the page cache holds (it was
just read); "cold" ones first ask the kernel to drop the file's pages
(``posix_fadvise(DONTNEED)``), so they read from the disk. Each figure is the median of
``--repeat`` runs, with [min-max]. Prints Markdown for BENCHMARKS.md. Linux (``ru_maxrss`` in
KiB, ``posix_fadvise``).

With ``--isolated``, it measures instead what reading USD and Alembic range by range costs,
their files read in a child process that serves the reads (``tuckercodec.io.isolation``):
the built-in cloth sample (or ``--sequence``, any file ``load_sequence`` reads) is written as
``.usdc`` and ``.abc``, then a fresh Python opens it (``open_frames``: the child starts and
opens the file), reads each frame alone, then every frame in one range, and for comparison
loads it whole (``load_sequence``: one child for one read).

    python -m tools.bench streaming                                 # 1 GB .npy, 64 frames
    python -m tools.bench streaming --formats npy pc2 npz zarr --repeat 3
    python -m tools.bench streaming --isolated --sequence ../shared/data/horse-gallop
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import struct
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from tools.bench import arguments

FORMATS = ("npy", "pc2", "npz", "npz-deflated", "zarr")
SUFFIXES = {"npy": ".npy", "pc2": ".pc2", "npz": ".npz", "npz-deflated": ".npz", "zarr": ".zarr"}
#: What a run does in its fresh Python: open, read every range, report (as JSON).
CHILD = """
import json, os, resource, sys, time
def rss():
    with open("/proc/self/status") as status:
        return next(int(l.split()[1]) * 1024 for l in status if l.startswith("VmRSS:"))
import tuckercodec
after_import = rss()
path, frames, cold = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "cold"
if cold:
    for root, _, names in os.walk(path) if os.path.isdir(path) else [("", [], [path])]:
        for name in names:
            fd = os.open(os.path.join(root, name), os.O_RDONLY)
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
            os.close(fd)
start = time.perf_counter()
with tuckercodec.open_frames(path) as source:
    for first in range(0, source.frame_count, frames):
        block = source.read(first, min(first + frames, source.frame_count))
        del block
    elapsed = time.perf_counter() - start
    print(json.dumps({
        "seconds": elapsed, "input_bytes": source.input_bytes, "after_import": after_import,
        "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,
        "range_bytes": frames * source.vertex_count * 24, "kind": type(source).__name__,
    }))
"""


#: What an ``--isolated`` run does in its fresh Python.
ISOLATED = """
import json, sys, time
import tuckercodec
path = sys.argv[1]
start = time.perf_counter()
source = tuckercodec.open_frames(path)
opened = time.perf_counter()
for frame in range(source.frame_count):
    source.read(frame, frame + 1)
singles = time.perf_counter()
source.read(0, source.frame_count)
whole = time.perf_counter()
source.close()
tuckercodec.load_sequence(path)
loaded = time.perf_counter()
print(json.dumps({
    "open": opened - start, "frame": (singles - opened) / source.frame_count,
    "range": whole - singles, "load": loaded - whole, "frames": source.frame_count,
    "vertices": source.vertex_count,
}))
"""


def isolated(sequence: Path | None, workdir: Path, runs: int) -> None:
    """Print what reading USD and Alembic range by range costs (see the module docstring)."""
    from tuckercodec import load_sequence, save_sequence
    from tuckercodec.internal import sample_path

    seq = load_sequence(sequence or sample_path(), progress=False)
    name = (sequence or sample_path()).stem
    print(f"{name}: {seq.frame_count} frames of {seq.vertex_count} vertices; {runs} runs each\n")
    print(
        "| file | open_frames (s) | read of one frame (ms) | read of every frame at once (s) "
        "| load_sequence (s) |"
    )
    print("|---|---|---|---|---|")
    for suffix in (".usdc", ".abc"):
        path = workdir / f"{name}{suffix}"
        save_sequence(seq, path, overwrite=True)
        results = []
        for _ in range(runs):
            done = subprocess.run(
                [sys.executable, "-c", ISOLATED, str(path)],
                capture_output=True,
                text=True,
                check=True,
            )
            results.append(json.loads(done.stdout))
        print(
            f"| {suffix} | {spread([r['open'] for r in results], 1, 2)} "
            f"| {spread([r['frame'] for r in results], 1e-3, 2)} "
            f"| {spread([r['range'] for r in results], 1, 3)} "
            f"| {spread([r['load'] for r in results], 1, 2)} |"
        )


def positions(vertices: int, frames: int, block: int = 16) -> Iterator[np.ndarray]:
    """A deterministic float32 animation (a rippling sheet), ``block`` frames at a time."""
    side = int(np.ceil(np.sqrt(vertices)))
    grid: np.ndarray = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(
        -1, 2
    )
    grid = grid[:vertices].astype(np.float32) / side
    for start in range(0, frames, block):
        t = np.arange(start, min(start + block, frames), dtype=np.float32)[:, None] / 30
        out = np.empty((len(t), vertices, 3), dtype=np.float32)
        out[:, :, 0] = grid[:, 0]
        out[:, :, 1] = grid[:, 1]
        out[:, :, 2] = 0.05 * np.sin(6.0 * grid[:, 0] + 2.0 * t) * np.cos(4.0 * grid[:, 1] - t)
        yield out


def write(kind: str, path: Path, vertices: int, frames: int) -> None:
    """The sequence as ``kind``, written block by block (never whole in memory)."""
    shape = (frames, vertices, 3)
    temporary = path.with_name(path.name + ".partial")
    if kind == "zarr":
        import zarr  # the [zarr] extra

        group = zarr.create_group(store=str(temporary), zarr_format=3, overwrite=True)
        array = group.create_array("vertices", shape=shape, chunks=(100, vertices, 3), dtype="f4")
        done = 0
        for block in positions(vertices, frames, 100):
            array[done : done + len(block)] = block
            done += len(block)
    elif kind in ("npz", "npz-deflated"):
        method = zipfile.ZIP_DEFLATED if kind == "npz-deflated" else zipfile.ZIP_STORED
        with (
            zipfile.ZipFile(temporary, "w", method, allowZip64=True) as archive,
            archive.open("V.npy", "w", force_zip64=True) as member,
        ):
            header = {"descr": "<f4", "fortran_order": False, "shape": shape}
            np.lib.format.write_array_header_1_0(member, header)
            for block in positions(vertices, frames):
                member.write(block.tobytes())
    else:
        with open(temporary, "wb") as stream:
            if kind == "npy":
                header = {"descr": "<f4", "fortran_order": False, "shape": shape}
                np.lib.format.write_array_header_1_0(stream, header)
            else:  # PC2: signature, version, points, start frame, sample rate, samples
                stream.write(struct.pack("<12siiffi", b"POINTCACHE2\0", 1, vertices, 0, 1, frames))
            for block in positions(vertices, frames):
                stream.write(block.tobytes())
            stream.flush()
            os.fsync(stream.fileno())  # clean pages, which DONTNEED can drop
    os.replace(temporary, path)


def read_once(path: Path, frames: int, mode: str) -> dict[str, float]:
    """One read of ``path`` in a fresh Python: what its CHILD reports."""
    done = subprocess.run(
        [sys.executable, "-c", CHILD, str(path), str(frames), mode],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout)


def spread(values: list[float], scale: float, digits: int = 0) -> str:
    """The median and [min-max] of ``values`` / ``scale``."""
    scaled = [value / scale for value in values]
    middle = statistics.median(scaled)
    if len(scaled) == 1:
        return f"{middle:.{digits}f}"
    return f"{middle:.{digits}f} [{min(scaled):.{digits}f}-{max(scaled):.{digits}f}]"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The streaming suite's options."""
    parser.add_argument("--gigabytes", type=float, default=1.0, help="float32 size (default 1)")
    parser.add_argument("--vertices", type=int, default=200_000, help="K (default 200000)")
    parser.add_argument("--frames", type=int, default=64, help="frames per range (default 64)")
    parser.add_argument("--formats", nargs="+", choices=FORMATS, default=["npy"])
    arguments.repeat(parser, 3, "runs of each, the median reported")
    parser.add_argument("--modes", nargs="+", choices=("warm", "cold"), default=["warm", "cold"])
    parser.add_argument("--workdir", type=Path, default=Path("/tmp/tuckercodec-bench-streaming"))
    parser.add_argument("--isolated", action="store_true", help="measure USD and Alembic instead")
    parser.add_argument("--sequence", type=Path, help="with --isolated: the sequence to write")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    if args.isolated:
        args.workdir.mkdir(parents=True, exist_ok=True)
        isolated(args.sequence, args.workdir, args.repeat)
        return 0
    count = max(1, round(args.gigabytes * 1e9 / (args.vertices * 12)))
    args.workdir.mkdir(parents=True, exist_ok=True)
    mib = 2**20
    print(
        f"{count} frames of {args.vertices} vertices ({count * args.vertices * 12 / 1e9:.2f} GB "
        f"as float32), read in ranges of {args.frames} frames; {args.repeat} runs each\n"
    )
    print(
        "| format | source | page cache | MB/s | RSS after import (MiB) | peak RSS (MiB) "
        "| peak less one range's float64 (MiB) |"
    )
    print("|---|---|---|---|---|---|---|")
    for kind in args.formats:
        path = args.workdir / f"sequence-{args.vertices}x{count}-{kind}{SUFFIXES[kind]}"
        if not path.exists():
            print(f"(writing {path})", file=sys.stderr)
            write(kind, path, args.vertices, count)
        for mode in args.modes:
            if mode == "warm":
                read_once(path, args.frames, "warm")  # into the page cache
            results = [read_once(path, args.frames, mode) for _ in range(args.repeat)]
            rates = [r["input_bytes"] / r["seconds"] for r in results]
            beyond = [r["peak"] - r["range_bytes"] for r in results]
            print(
                f"| {kind} | {results[0]['kind']} | {mode} | {spread(rates, 1e6)} "
                f"| {spread([r['after_import'] for r in results], mib)} "
                f"| {spread([r['peak'] for r in results], mib)} | {spread(beyond, mib)} |"
            )
    return 0
