"""Benchmark of the zarr codec: a sequence as a zarr array chunked over frames, against one .tkc.

For each KG target: the sequence written as a zarr format 3 array (frames chunked by
``--frames-per-chunk``, the codec named in zarr.json and found through its entry point), its
chunks' bytes and the whole store's, the decoded KG over the whole array, and the ratio to the
.tkc of the whole sequence at the same target, with its faces (what ``tuckercodec encode``
writes) and without (like for like: the zarr array has no faces). Then each chunk: its ranks and
how much of it is U1, the per-vertex basis that every chunk stores for itself. Timings are
medians of ``--repeat`` runs after one untimed run. Prints Markdown.

    python -m tools.bench_zarr                                # chicken, 100 frames a chunk
    python -m tools.bench_zarr sample --frames-per-chunk 20 --targets 0.1 --repeat 1
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tools import common
from tuckercodec import MeshSequence, encode_with_report, info, kg_error

DEFAULT_INPUT = common.SHARED_DATA / "chicken.npz"
#: The issue's target: the zarr array within this many times the .tkc's size.
TARGET_RATIO = 1.3


@dataclass(frozen=True)
class ChunkFigures:
    """One stored chunk: its frames, ranks, bytes and the bytes of its U1 section."""

    frames: int
    ranks: tuple[int, int]
    total_bytes: int
    u1_bytes: int


@dataclass(frozen=True)
class Result:
    """One target's measurements."""

    target: float
    tkc_bytes: int  # the whole sequence's .tkc, faces included
    tkc_bytes_without_faces: int
    tkc_seconds: list[float]  # encoding the .tkc without faces
    chunk_bytes: int  # the chunks' objects in the store
    store_bytes: int  # every object of the store (zarr.json too)
    kg: float  # decoded from the store, over the whole array
    write_seconds: list[float]
    read_seconds: list[float]
    chunks: list[ChunkFigures]

    @property
    def ratio(self) -> float:
        """The chunks' bytes over the .tkc's (faces included)."""
        return self.chunk_bytes / self.tkc_bytes

    @property
    def ratio_without_faces(self) -> float:
        """The chunks' bytes over the .tkc's without faces (like for like)."""
        return self.chunk_bytes / self.tkc_bytes_without_faces


def _write(path: Path, positions: np.ndarray, frames_per_chunk: int, target: float) -> None:
    import zarr

    array = zarr.create_array(
        str(path),
        shape=positions.shape,
        chunks=(frames_per_chunk, positions.shape[1], 3),
        dtype=positions.dtype,
        # by name: zarr finds the codec through its entry point, no tuckercodec import
        serializer={"name": "tuckercodec", "configuration": {"target_kg": target}},
        compressors=None,
        overwrite=True,
    )
    array[:] = positions


def _read(path: Path) -> np.ndarray:
    import zarr

    return np.asarray(zarr.open_array(str(path), mode="r")[:])


def _chunk_objects(path: Path) -> list[Path]:
    """The chunks of a zarr format 3 array, in frame order (keys c/<frame chunk>/0/0)."""
    return sorted((path / "c").glob("*/*/*"), key=lambda p: int(p.parts[-3]))


def measure(
    sequence: MeshSequence, target: float, frames_per_chunk: int, repeat: int, folder: Path
) -> Result:
    """Write and read the sequence as a zarr array at ``target``; encode the .tkc beside it."""
    positions = sequence.vertices
    with_faces = encode_with_report(sequence, target_kg=target).data
    bare = MeshSequence(positions, np.zeros((0, 3), dtype=np.int64))
    tkc_seconds = common.timed(lambda: encode_with_report(bare, target_kg=target), repeat)
    without_faces = encode_with_report(bare, target_kg=target).data

    path = folder / f"kg{target:g}.zarr"
    write_seconds = common.timed(lambda: _write(path, positions, frames_per_chunk, target), repeat)
    read_seconds = common.timed(lambda: _read(path), repeat)
    decoded = _read(path)

    chunks = []
    for item in _chunk_objects(path):
        header = info(item.read_bytes())
        sizes = {name: size for name, size, _, _ in header.sections}
        chunks.append(ChunkFigures(header.frames, header.ranks, header.total_bytes, sizes["U1"]))
    store = [p for p in path.rglob("*") if p.is_file()]
    return Result(
        target=target,
        tkc_bytes=len(with_faces),
        tkc_bytes_without_faces=len(without_faces),
        tkc_seconds=tkc_seconds,
        chunk_bytes=sum(c.total_bytes for c in chunks),
        store_bytes=sum(p.stat().st_size for p in store),
        kg=kg_error(positions, decoded),
        write_seconds=write_seconds,
        read_seconds=read_seconds,
        chunks=chunks,
    )


def report(name: str, sequence: MeshSequence, frames_per_chunk: int, results: list[Result]) -> str:
    """The Markdown tables of :func:`main`."""
    lines = [
        f"{name}: {sequence.frame_count} frames of {sequence.vertex_count} vertices, "
        f"{sequence.faces.shape[0]} faces, zarr chunks of {frames_per_chunk} frames; "
        f"sizes in bytes; seconds are median [min-max]",
        "",
        "| target KG | .tkc | .tkc without faces | zarr chunks | zarr store | chunks / .tkc "
        "| chunks / .tkc without faces | decoded KG (whole array) | .tkc encode s "
        "| zarr write s | zarr read s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines.extend(
        f"| {r.target:g} | {r.tkc_bytes} | {r.tkc_bytes_without_faces} | {r.chunk_bytes} "
        f"| {r.store_bytes} | {r.ratio:.2f} | {r.ratio_without_faces:.2f} | {r.kg:.4f} "
        f"| {common.spread(r.tkc_seconds, digits=2)} "
        f"| {common.spread(r.write_seconds, digits=2)} "
        f"| {common.spread(r.read_seconds, digits=3)} |"
        for r in results
    )
    lines += ["", "| target KG | chunk | frames | ranks (i, k) | bytes | U1 bytes | U1 share |"]
    lines.append("|---|---|---|---|---|---|---|")
    for r in results:
        for number, c in enumerate(r.chunks):
            lines.append(
                f"| {r.target:g} | {number} | {c.frames} | {c.ranks} | {c.total_bytes} "
                f"| {c.u1_bytes} | {c.u1_bytes / c.total_bytes:.0%} |"
            )
        u1 = sum(c.u1_bytes for c in r.chunks)
        lines.append(
            f"| {r.target:g} | all | {sum(c.frames for c in r.chunks)} | | {r.chunk_bytes} "
            f"| {u1} | {u1 / r.chunk_bytes:.0%} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the result; returns the process exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench_zarr", description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "input",
        nargs="?",
        default=str(DEFAULT_INPUT),
        help="a sequence (.npz, OBJ folder...) or 'sample' (default: chicken)",
    )
    parser.add_argument("--frames-per-chunk", type=int, default=100)
    parser.add_argument("--targets", type=float, nargs="+", default=[0.1, 1.0])
    parser.add_argument("--repeat", type=int, default=3, help="timed runs (median reported)")
    args = parser.parse_args(argv)
    if args.repeat < 1 or args.frames_per_chunk < 1:
        parser.error("--repeat and --frames-per-chunk must be at least 1")
    if args.input != common.SAMPLE and not Path(args.input).exists():
        print(
            f"{args.input} is absent (the real sequences live in {common.SHARED_DATA})",
            file=sys.stderr,
        )
        return 2
    try:
        import zarr  # noqa: F401
    except ImportError:
        print("the zarr benchmark needs zarr: pip install '.[zarr]'", file=sys.stderr)
        return 2

    sequence = common.load(args.input)
    name = common.SAMPLE if args.input == common.SAMPLE else Path(args.input).stem
    with tempfile.TemporaryDirectory(prefix="bench_zarr-") as folder:
        results = [
            measure(sequence, target, args.frames_per_chunk, args.repeat, Path(folder))
            for target in args.targets
        ]
    print(f"machine: {common.machine()}")
    print(f"command: {common.command('tools.bench_zarr', argv)}")
    print()
    print(report(name, sequence, args.frames_per_chunk, results))
    print()
    worst = max(r.ratio for r in results)
    verdict = "meets" if worst <= TARGET_RATIO else "misses"
    print(
        f"largest chunks / .tkc: {worst:.2f} ({verdict} the target of {TARGET_RATIO}); "
        f"median .tkc encode {statistics.median(results[0].tkc_seconds):.2f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
