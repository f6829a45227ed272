"""Benchmark of the zarr codec: a sequence as a zarr array chunked over frames, against one .tkc.

For each KG target: the sequence written as a zarr format 3 array (frames chunked by
``--frames-per-chunk``, the codec named in zarr.json and found through its entry point), its
chunks' bytes and the whole store's, the decoded KG over the whole array and of its worst chunk,
and the ratio to the .tkc of the whole sequence at the same target, with its faces (what
``tuckercodec encode`` writes) and without (like for like: the zarr array has no faces). Then
each chunk: its ranks and how much of it is U1, the per-vertex basis that every chunk stores for
itself.

Then the fitted mode (``TuckerZarrCodec.fit``): one basis fitted to the array, held by the
codec's configuration, each chunk its .tkc without it. Its sizes are given two ways: the chunks
plus the binary basis (what the data costs), and the store on disk (zarr.json holds the basis
as base64, 4/3 of its binary size), each over the .tkc. Timings are medians of ``--repeat`` runs
after one untimed run; the load average before and after is printed (timings taken on a busy
machine are not figures). Prints Markdown.

    python -m tools.bench zarr                                # chicken, 100 frames a chunk
    python -m tools.bench zarr sample --frames-per-chunk 20 --targets 0.1 --repeat 1
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tools import common
from tools.bench import arguments
from tuckercodec import MeshSequence, encode_with_report, info, kg_error
from tuckercodec.internal import parse_container

DEFAULT_INPUT = common.SHARED_DATA / "chicken.npz"
#: The target: the zarr array within this many times the .tkc's size.
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
    worst_chunk_kg: float  # the largest of the chunks' own decoded KG errors
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


@dataclass(frozen=True)
class FittedResult:
    """One target's measurements of the fitted mode."""

    target: float
    basis_bytes: int  # the binary basis: the U1 section's payload
    basis_text_bytes: int  # its base64 in zarr.json
    basis_columns: int
    chunk_bytes: int
    store_bytes: int  # every object of the store: zarr.json (with the basis) too
    kg: float
    worst_chunk_kg: float
    fit_seconds: list[float]
    write_seconds: list[float]
    read_seconds: list[float]
    chunks: list[ChunkFigures]  # u1_bytes: 0 for a fitted chunk, its own U1 for a whole one
    whole_chunks: int  # chunks the basis could not serve, stored with their own U1

    @property
    def data_bytes(self) -> int:
        """The chunks and the binary basis: what the array's data costs."""
        return self.chunk_bytes + self.basis_bytes


def _write(
    path: Path, positions: np.ndarray, frames_per_chunk: int, serializer: dict[str, object]
) -> None:
    import zarr

    array = zarr.create_array(
        str(path),
        shape=positions.shape,
        chunks=(frames_per_chunk, positions.shape[1], 3),
        dtype=positions.dtype,
        # by name: zarr finds the codec through its entry point, no tuckercodec import
        serializer=serializer,
        compressors=None,
        overwrite=True,
    )
    array[:] = positions


def _by_target(target: float) -> dict[str, object]:
    return {"name": "tuckercodec", "configuration": {"target_kg": target}}


def _worst_chunk_kg(positions: np.ndarray, decoded: np.ndarray, frames_per_chunk: int) -> float:
    return max(
        kg_error(positions[a : a + frames_per_chunk], decoded[a : a + frames_per_chunk])
        for a in range(0, len(positions), frames_per_chunk)
    )


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
    serializer = _by_target(target)
    write_seconds = common.timed(
        lambda: _write(path, positions, frames_per_chunk, serializer), repeat
    )
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
        worst_chunk_kg=_worst_chunk_kg(positions, decoded, frames_per_chunk),
        write_seconds=write_seconds,
        read_seconds=read_seconds,
        chunks=chunks,
    )


def measure_fitted(
    sequence: MeshSequence, target: float, frames_per_chunk: int, repeat: int, folder: Path
) -> FittedResult:
    """Fit a codec to the sequence's positions, write and read the array with it."""
    import zarr

    codec_class = zarr.registry.get_codec_class("tuckercodec")  # found by its entry point
    positions = sequence.vertices

    def fit() -> Any:  # TuckerZarrCodec, from zarr's registry
        return codec_class.fit(positions, target_kg=target, chunk_frames=frames_per_chunk)

    fit_seconds = common.timed(fit, repeat)
    codec = fit()
    path = folder / f"fitted-kg{target:g}.zarr"
    write_seconds = common.timed(
        lambda: _write(path, positions, frames_per_chunk, codec.to_dict()), repeat
    )
    read_seconds = common.timed(lambda: _read(path), repeat)
    decoded = _read(path)

    chunks, whole_chunks = [], 0
    for item in _chunk_objects(path):
        data = item.read_bytes()
        is_whole = parse_container(data, whole=False).total_length == len(data)
        whole_chunks += is_whole
        header = info(codec.basis.complete(data))  # the chunk's .tkc, basis put back
        sizes = {name: size for name, size, _, _ in header.sections}
        own_u1 = sizes["U1"] if is_whole else 0
        # a fitted chunk is one segment: its ranks, not the basis's columns (header.ranks)
        ranks = header.segments[0].ranks if header.segments else header.ranks
        chunks.append(ChunkFigures(header.frames, ranks, len(data), own_u1))
    store = [p for p in path.rglob("*") if p.is_file()]
    return FittedResult(
        target=target,
        basis_bytes=len(codec.basis.payload),
        basis_text_bytes=len(codec.basis.text),
        basis_columns=codec.basis.columns,
        chunk_bytes=sum(c.total_bytes for c in chunks),
        store_bytes=sum(p.stat().st_size for p in store),
        kg=kg_error(positions, decoded),
        worst_chunk_kg=_worst_chunk_kg(positions, decoded, frames_per_chunk),
        fit_seconds=fit_seconds,
        write_seconds=write_seconds,
        read_seconds=read_seconds,
        chunks=chunks,
        whole_chunks=whole_chunks,
    )


def report(
    name: str,
    sequence: MeshSequence,
    frames_per_chunk: int,
    results: list[Result],
    fitted: list[FittedResult] | None = None,
) -> str:
    """The Markdown tables of :func:`main`."""
    lines = [
        f"{name}: {sequence.frame_count} frames of {sequence.vertex_count} vertices, "
        f"{sequence.faces.shape[0]} faces, zarr chunks of {frames_per_chunk} frames; "
        f"sizes in bytes; seconds are median [min-max]",
        "",
        "| target KG | .tkc | .tkc without faces | zarr chunks | zarr store | chunks / .tkc "
        "| chunks / .tkc without faces | decoded KG (whole array) | worst chunk KG "
        "| .tkc encode s | zarr write s | zarr read s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    lines.extend(
        f"| {r.target:g} | {r.tkc_bytes} | {r.tkc_bytes_without_faces} | {r.chunk_bytes} "
        f"| {r.store_bytes} | {r.ratio:.2f} | {r.ratio_without_faces:.2f} | {r.kg:.4f} "
        f"| {r.worst_chunk_kg:.4f} | {common.spread(r.tkc_seconds, digits=2)} "
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
    if fitted:
        lines += ["", _fitted_report(results, fitted)]
    return "\n".join(lines)


def _fitted_report(results: list[Result], fitted: list[FittedResult]) -> str:
    """The fitted mode's tables: sizes against the same target's .tkc, then each chunk."""
    tkc = {r.target: r for r in results}
    lines = [
        "Fitted mode (one basis in the codec's configuration): sizes in bytes; ratios over the "
        ".tkc with faces (without faces in brackets)",
        "",
        "| target KG | chunks | basis columns | basis (binary) | basis (base64) | chunks + basis "
        "| store on disk | (chunks + basis) / .tkc | store / .tkc | chunks stored whole "
        "| decoded KG (whole array) | worst chunk KG | fit s | zarr write s | zarr read s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for f in fitted:
        r = tkc[f.target]
        lines.append(
            f"| {f.target:g} | {f.chunk_bytes} | {f.basis_columns} | {f.basis_bytes} "
            f"| {f.basis_text_bytes} "
            f"| {f.data_bytes} | {f.store_bytes} "
            f"| {f.data_bytes / r.tkc_bytes:.2f} ({f.data_bytes / r.tkc_bytes_without_faces:.2f}) "
            f"| {f.store_bytes / r.tkc_bytes:.2f} "
            f"({f.store_bytes / r.tkc_bytes_without_faces:.2f}) "
            f"| {f.whole_chunks} of {len(f.chunks)} | {f.kg:.4f} | {f.worst_chunk_kg:.4f} "
            f"| {common.spread(f.fit_seconds, digits=2)} "
            f"| {common.spread(f.write_seconds, digits=2)} "
            f"| {common.spread(f.read_seconds, digits=3)} |"
        )
    lines += [
        "",
        "| target KG | chunk | frames | ranks (i, k) | bytes | own U1 bytes |",
        "|---|---|---|---|---|---|",
    ]
    for f in fitted:
        for number, c in enumerate(f.chunks):
            lines.append(
                f"| {f.target:g} | {number} | {c.frames} | {c.ranks} | {c.total_bytes} "
                f"| {c.u1_bytes} |"
            )
    return "\n".join(lines)


def _load() -> str:
    """The load average over 1, 5 and 15 minutes, where the system says."""
    try:
        return " ".join(f"{value:.2f}" for value in os.getloadavg())
    except OSError:
        return "unknown"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The zarr suite's options."""
    arguments.sequence(parser, str(DEFAULT_INPUT), "chicken")
    parser.add_argument("--frames-per-chunk", type=arguments.positive_int, default=100)
    parser.add_argument("--targets", type=float, nargs="+", default=[0.1, 1.0])
    arguments.repeat(parser, 3)
    parser.add_argument(
        "--no-fitted", action="store_true", help="measure the usual mode only, not the fitted"
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    if args.sequence != common.SAMPLE and not Path(args.sequence).exists():
        print(
            f"{args.sequence} is absent (the real sequences live in {common.SHARED_DATA})",
            file=sys.stderr,
        )
        return 2
    try:
        import zarr  # noqa: F401
    except ImportError:
        print("the zarr benchmark needs zarr: pip install '.[zarr]'", file=sys.stderr)
        return 2

    sequence = common.load(args.sequence)
    name = common.SAMPLE if args.sequence == common.SAMPLE else Path(args.sequence).stem
    load_before = _load()
    with tempfile.TemporaryDirectory(prefix="bench_zarr-") as folder:
        results = [
            measure(sequence, target, args.frames_per_chunk, args.repeat, Path(folder))
            for target in args.targets
        ]
        fitted = [
            measure_fitted(sequence, target, args.frames_per_chunk, args.repeat, Path(folder))
            for target in ([] if args.no_fitted else args.targets)
        ]
    print(f"machine: {common.machine()}")
    print(f"load average (1, 5, 15 min) before: {load_before}; after: {_load()}")
    print(f"command: {args.command}")
    print()
    print(report(name, sequence, args.frames_per_chunk, results, fitted))
    print()
    worst = max(r.ratio for r in results)
    verdict = "meets" if worst <= TARGET_RATIO else "misses"
    print(
        f"largest chunks / .tkc: {worst:.2f} ({verdict} the target of {TARGET_RATIO}); "
        f"median .tkc encode {statistics.median(results[0].tkc_seconds):.2f} s"
    )
    if fitted:
        by_target = {r.target: r for r in results}
        data = max(f.data_bytes / by_target[f.target].tkc_bytes for f in fitted)
        store = max(f.store_bytes / by_target[f.target].tkc_bytes for f in fitted)
        print(
            f"fitted: largest (chunks + basis) / .tkc {data:.2f} "
            f"({'meets' if data <= TARGET_RATIO else 'misses'} the target); largest store on "
            f"disk / .tkc {store:.2f} ({'meets' if store <= TARGET_RATIO else 'misses'} it)"
        )
    return 0
