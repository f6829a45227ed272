"""Lossless: tuckercodec's lossless mode against fpzip, pcodec, zstd 19 and Blosc2,
every file checked bit for bit, and how fast tuckercodec decodes.

For each sequence (default: every one of ../shared/data present), every coder of ``--coders``
codes the positions in the sequence's own precision: float32 where every value is a float32
exactly (samba, the cloth), else float64 (chicken's 17-digit text, horse gallop's OBJ). The
coders:

* ``tuckercodec``: ``Encoder(EncodeOptions(lossless=True)).encode_with_report``;
* ``fpzip``: precision 0 (lossless);
* ``pcodec``: standalone ``simple_compress`` at level 12, the flattened array;
* ``zstd-19``: zstd level 19 on the raw bytes;
* ``blosc2``: zstd clevel 9 behind a byte shuffle, a bit shuffle, or a byte shuffle and
  bytedelta, typesize the values' itemsize.

Each peer is tried in three layouts of the positions (F x K x 3 as stored, 3 x K x F with time
fastest, 3 x F x K; the layout decides what each one's predictor sees next to a value) and at
each of its settings, and is represented by its smallest file. Sizes are whole files in bytes and
bpfv, the connectivity included: tuckercodec's own, the faces with zstd 19 for the peers (as the
peers suite counts them).

Every file is decoded and compared with the input bit for bit: a peer's values as they come
back, tuckercodec's float64 positions narrowed to the input's precision first (and whether the
float64 values themselves are the input's is said too). Decoding speed: megabytes per second of
float32-equivalent output (F * K * 3 * 4 bytes over the decode's time), the decode of
tuckercodec being :func:`tuckercodec.decode` of the whole file (faces and float64 positions);
encode and decode times are medians of ``--repeat`` runs of each coder's smallest file.

Then tuckercodec's decode part by part (``--no-parts`` leaves it out): opening the file
(``Decoder(data)``: header, faces, factor matrices), ``positions()`` (§8.1's reconstruction and
the corrections) and the whole ``decode``, medians of ``--repeat`` runs, for the lossless file
and for the plain file at KG 0.1 beside it: what the lossless mode adds to a decode.

Last, the misses against the targets: every file bit-exact; tuckercodec's smaller than
the smallest peer's on every sequence; tuckercodec decoding at least ``TARGET_MB_S``.

``--quantized`` adds quantized caches the encoder was never tuned on: two of the rate suite's
generated sequences (:mod:`tools.generate.sequence`) with each axis quantized over the sequence's
bounding box to 16 and 14 bits and dequantized to float32 as a quantized-mesh loader does
(``min + q * scale``, KHR_mesh_quantization style), made the first time in
``~/.cache/tuckercodec-bench/quantized/``.

Output: lossless.md (what is printed) and results.json (every file tried) in ``--out``.

    python -m tools.bench lossless                           # everything present
    python -m tools.bench lossless --repeat 5                # medians of 5 (BENCHMARKS.md)
    python -m tools.bench lossless sample --coders fpzip,zstd-19
    python -m tools.bench lossless --quantized ../shared/data/chicken.npz
"""

from __future__ import annotations

import argparse
import datetime
import json
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

import tuckercodec
from tools import common
from tools.bench import arguments, rate
from tools.bench.bounds import sequence_name
from tools.bench.peers import base
from tools.bench.peers.blosc import run_blosc2
from tools.bench.peers.fpz import run_fpzip
from tools.bench.peers.pco import run_pcodec
from tools.bench.peers.tkc import run_with_options
from tools.bench.peers.zstd import run_zstd_lossless
from tuckercodec import (
    Decoder,
    EncodeOptions,
    Encoder,
    MeshSequence,
    TuckerCodecError,
    bpfv,
    decode,
)

#: Target: tuckercodec decodes at least this many MB (1e6 bytes) of float32 output a second.
TARGET_MB_S = 50.0
#: The plain file whose decode the lossless file's is compared with, part by part.
REFERENCE_KG = 0.1


def _tuckercodec(sequence: MeshSequence, values: np.ndarray) -> list[base.Trial]:
    trial, _ = run_with_options(sequence, EncodeOptions(lossless=True), "lossless")
    return [trial]


#: The coders, by name: what each needs (for the skip message) and its trials.
CODERS: dict[str, tuple[str, Callable[[MeshSequence, np.ndarray], list[base.Trial]]]] = {
    "tuckercodec": ("", _tuckercodec),
    "fpzip": ("fpzip", run_fpzip),
    "pcodec": ("pcodec", run_pcodec),
    "zstd-19": ("", run_zstd_lossless),
    "blosc2": ("blosc2", run_blosc2),
}


@dataclass
class Entry:
    """One file of one coder on one sequence, measured."""

    sequence: str
    dtype: str
    coder: str
    setting: str = ""
    bytes: int | None = None
    bpfv: float | None = None
    connectivity_bpfv: float | None = None
    exact: bool | None = None  # every value's bits, in the input's precision
    #: tuckercodec: values whose float64 output is not the input's value (0 when all are)
    float64_differences: int | None = None
    encode_seconds: float | None = None
    decode_seconds: float | None = None
    decode_mb_s: float | None = None
    chosen: bool = False  # the coder's smallest file, the one in the tables
    error: str | None = None


def bit_exact(values: np.ndarray, decoded: np.ndarray) -> bool:
    """Whether ``decoded``, narrowed to the type of ``values``, has every value's bits."""
    unsigned = np.dtype(f"<u{values.dtype.itemsize}")
    narrowed = np.ascontiguousarray(np.asarray(decoded).astype(values.dtype, copy=False))
    return decoded.shape == values.shape and np.array_equal(
        narrowed.view(unsigned), np.ascontiguousarray(values).view(unsigned)
    )


def measure(
    name: str,
    coder: str,
    run: Callable[[MeshSequence, np.ndarray], list[base.Trial]],
    sequence: MeshSequence,
    values: np.ndarray,
    repeat: int,
) -> list[Entry]:
    """Every file of one coder on one sequence; its smallest re-timed and marked chosen."""
    try:
        trials = run(sequence, values)
    except (TuckerCodecError, NotImplementedError, ValueError) as error:
        return [Entry(name, str(values.dtype), coder, error=f"{type(error).__name__}: {error}")]
    frames, vertices = sequence.frame_count, sequence.vertex_count
    entries = []
    for trial in trials:
        decoded = trial.decoded
        assert decoded is not None  # timed_trial keeps what it decoded
        entry = Entry(name, str(values.dtype), coder, trial.setting, trial.total_bytes)
        entry.bpfv = bpfv(trial.total_bytes, frames, vertices)
        entry.connectivity_bpfv = bpfv(trial.connectivity_bytes or 0, frames, vertices)
        entry.exact = bit_exact(values, decoded)
        if decoded.dtype == np.float64 and values.dtype != np.float64:
            entry.float64_differences = int(np.count_nonzero(decoded != values))
        trial.decoded = None
        entries.append(entry)
    smallest = min(range(len(trials)), key=lambda i: trials[i].total_bytes)
    base.retime_median(trials[smallest], repeat)
    chosen = entries[smallest]
    chosen.chosen = True
    chosen.encode_seconds = trials[smallest].encode_seconds
    chosen.decode_seconds = trials[smallest].decode_seconds
    chosen.decode_mb_s = frames * vertices * 12 / 1e6 / trials[smallest].decode_seconds
    return entries


@dataclass
class DecodeParts:
    """Where tuckercodec's decode of one file spends its time: medians of ``repeat`` runs."""

    sequence: str
    file: str  # "lossless", or the plain KG file it is compared with
    bytes: int
    open_seconds: float  # Decoder(data): header, faces, factor matrices
    positions_seconds: float  # positions() of an opened decoder: §8.1 and the corrections
    decode_seconds: float  # decode(data): the whole file, as the speed of the tables
    megabytes: float  # float32-equivalent output, F * K * 12 / 1e6

    @property
    def mb_s(self) -> float:
        return self.megabytes / self.decode_seconds


def decode_parts(name: str, sequence: MeshSequence, repeat: int) -> list[DecodeParts]:
    """tuckercodec's decode in its parts, for the lossless file and, for comparison, the
    plain file at the default KG target: what the decode speed of the lossless mode adds."""
    megabytes = sequence.frame_count * sequence.vertex_count * 12 / 1e6
    parts = []
    for label, options in (
        ("lossless", EncodeOptions(lossless=True)),
        (f"KG {REFERENCE_KG:g}", EncodeOptions(target_kg=REFERENCE_KG)),
    ):
        data = Encoder(options).encode(sequence)
        open_times, positions, whole = [], [], []
        for _ in range(repeat):  # a new decoder each time: it keeps what it has decoded
            start = time.perf_counter()
            decoder = Decoder(data)
            middle = time.perf_counter()
            decoder.positions()
            open_times.append(middle - start)
            positions.append(time.perf_counter() - middle)
            start = time.perf_counter()
            decode(data)
            whole.append(time.perf_counter() - start)
        parts.append(
            DecodeParts(
                name,
                label,
                len(data),
                statistics.median(open_times),
                statistics.median(positions),
                statistics.median(whole),
                megabytes,
            )
        )
    return parts


# ------------------------------------------------------------------------------------------
# tables


def detail_rows(entries: list[Entry]) -> list[str]:
    lines = [
        "| sequence | values | coder | setting (smallest) | bytes | bpfv (conn.) | bit-exact | "
        "enc s | dec s | decode MB/s (float32) |",
        "|" + "---|" * 10,
    ]
    for e in entries:
        if e.error is not None:
            lines.append(f"| {e.sequence} | {e.dtype} | {e.coder} | {e.error} | | | | | | |")
            continue
        if not e.chosen:
            continue
        exact = "yes" if e.exact else "**NO**"
        if e.float64_differences:
            exact += f" (float64 output: {e.float64_differences} values differ)"
        lines.append(
            f"| {e.sequence} | {e.dtype} | {e.coder} | {e.setting} | {e.bytes} | "
            f"{e.bpfv:.3f} ({e.connectivity_bpfv:.3f}) | {exact} | {e.encode_seconds:.2f} | "
            f"{e.decode_seconds:.3f} | {e.decode_mb_s:.0f} |"
        )
    return lines


def _chosen(entries: list[Entry], sequence: str, coder: str) -> Entry | None:
    return next(
        (e for e in entries if e.sequence == sequence and e.coder == coder and e.chosen), None
    )


def summary_rows(entries: list[Entry], names: list[str], coders: list[str]) -> list[str]:
    """bpfv of each coder's smallest file per sequence, the smallest peer, and tuckercodec's
    size over it."""
    peers = [c for c in coders if c != "tuckercodec"]
    lines = [
        "| sequence | values | "
        + " | ".join(coders)
        + " | smallest peer | tuckercodec / smallest peer | tuckercodec decode MB/s |",
        "|" + "---|" * (len(coders) + 5),
    ]
    for name in names:
        found = {c: _chosen(entries, name, c) for c in coders}
        dtype = next((e.dtype for e in entries if e.sequence == name), "")
        cells = []
        for coder in coders:
            e = found[coder]
            if e is None or e.bpfv is None:
                cells.append("no file")
            else:
                cells.append(f"{e.bpfv:.2f}" + ("" if e.exact else " (**not exact**)"))
        sized = {c: e for c in peers if (e := found[c]) is not None and e.bytes}
        smallest = min(sized, key=lambda c: sized[c].bytes or 0) if sized else None
        ours = found.get("tuckercodec")
        ratio = "n/a"
        speed = "n/a"
        if ours is not None and ours.bytes and smallest is not None:
            value = ours.bytes / (sized[smallest].bytes or 1)
            ratio = f"{value:.3f}" + ("" if value < 1 else " **not smaller**")
        if ours is not None and ours.decode_mb_s is not None:
            speed = f"{ours.decode_mb_s:.0f}" + (
                "" if ours.decode_mb_s >= TARGET_MB_S else " **under 50**"
            )
        lines.append(
            f"| {name} | {dtype} | "
            + " | ".join(cells)
            + f" | {smallest or 'n/a'} | {ratio} | {speed} |"
        )
    return lines


def parts_rows(parts: list[DecodeParts]) -> list[str]:
    return [
        "| sequence | file | bytes | open s (header, faces, factors) | positions s | "
        "whole decode s | MB/s (float32) |",
        "|" + "---|" * 7,
        *(
            f"| {p.sequence} | {p.file} | {p.bytes} | {p.open_seconds:.3f} | "
            f"{p.positions_seconds:.3f} | {p.decode_seconds:.3f} | {p.mb_s:.0f} |"
            for p in parts
        ),
    ]


def misses(entries: list[Entry], names: list[str]) -> list[str]:
    """What broke a promise or missed a target of the lossless mode."""
    found = []
    for e in entries:
        label = f"{e.sequence} {e.coder}"
        if e.error is not None:
            found.append(f"{label}: no file ({e.error})")
        elif not e.exact:
            found.append(f"{label} ({e.setting}): not bit-exact")
    for name in names:
        ours = _chosen(entries, name, "tuckercodec")
        if ours is None or ours.bytes is None:
            continue
        peers = [e for e in entries if e.sequence == name and e.chosen and e.coder != "tuckercodec"]
        best = min(peers, key=lambda e: e.bytes or 0, default=None)
        if best is not None and best.bytes is not None and ours.bytes >= best.bytes:
            found.append(
                f"{name} tuckercodec: {ours.bpfv:.2f} bpfv, not smaller than {best.coder}'s "
                f"{best.bpfv:.2f}"
            )
        if ours.decode_mb_s is not None and ours.decode_mb_s < TARGET_MB_S:
            found.append(
                f"{name} tuckercodec: decodes {ours.decode_mb_s:.0f} MB/s of float32 output "
                f"(target >= {TARGET_MB_S:g})"
            )
    return found


# ------------------------------------------------------------------------------------------
# the suite


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The lossless suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument("--coders", default=",".join(CODERS), help="coders to run, comma-separated")
    arguments.repeat(parser, 1, "timings of each coder's smallest file, the medians kept")
    parser.add_argument(
        "--no-parts",
        action="store_true",
        help="leave out tuckercodec's decode part by part (two more encodes per sequence)",
    )
    parser.add_argument(
        "--quantized",
        action="store_true",
        help="add two generated sequences quantized to 16 and 14 bits per axis",
    )
    arguments.output(
        parser, "output folder (default results/bench-lossless)", "results/bench-lossless"
    )


#: (generated sequence, bits per axis) of ``--quantized``.
QUANTIZED = [("body-7061x201-seed3", 16), ("cloth-2904x204-seed4", 14)]
QUANTIZED_FOLDER = Path("~/.cache/tuckercodec-bench/quantized").expanduser()


def quantized_sequences() -> list[str]:
    """The quantized caches of ``--quantized``, made the first time they are asked for."""
    QUANTIZED_FOLDER.mkdir(parents=True, exist_ok=True)
    sources = {path.stem: path for path in rate.generated_sequences()}
    out = []
    for name, bits in QUANTIZED:
        path = QUANTIZED_FOLDER / f"{name}-q{bits}.npz"
        if not path.exists():
            with np.load(sources[name]) as source:
                positions, faces = source["V"].astype(np.float64), source["F"]
            np.savez(path.with_suffix(".part.npz"), V=quantized(positions, bits), F=faces)
            path.with_suffix(".part.npz").replace(path)
        out.append(str(path))
    return out


def quantized(positions: np.ndarray, bits: int) -> np.ndarray:
    """``positions`` (F, K, 3) quantized per axis to ``bits`` over their bounding box, as float32
    ``min + q * scale``: what a loader of a quantized mesh hands on."""
    low, high = positions.min(axis=(0, 1)), positions.max(axis=(0, 1))
    levels = 2**bits - 1
    steps = np.round((positions - low) / (high - low) * levels).astype(np.float32)
    scale = ((high - low) / levels).astype(np.float32)
    return low.astype(np.float32) + steps * scale


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    coders, skipped = arguments.available_coders(
        args.coders, CODERS, lambda coder: base.missing(CODERS[coder][0])
    )
    if args.quantized:
        args.sequences = [*(args.sequences or common.shared_sequences()), *quantized_sequences()]
    inputs = arguments.sequences_and_folder(args, "lossless.md")
    if inputs is None:
        return 2
    paths, out = inputs

    started = time.monotonic()
    entries: list[Entry] = []
    parts: list[DecodeParts] = []
    names: list[str] = []
    header: list[str] = []
    taken: set[str] = set()
    for path in paths:
        name = common.unique_name(sequence_name(path), taken)
        names.append(name)
        sequence = common.load(path)
        values = base.own_precision(sequence)
        header.append(
            f"- {name}: {sequence.frame_count} frames, {sequence.vertex_count} vertices, "
            f"{sequence.faces.shape[0]} faces, values {values.dtype}"
        )
        for coder in coders:
            print(f"{name}: {coder}...", file=sys.stderr)
            entries += measure(name, coder, CODERS[coder][1], sequence, values, args.repeat)
        if "tuckercodec" in coders and not args.no_parts:
            print(f"{name}: tuckercodec's decode, part by part...", file=sys.stderr)
            parts += decode_parts(name, sequence, args.repeat)

    found = misses(entries, names)
    versions = []
    for module in ("fpzip", "pcodec", "blosc2", "zstandard"):
        try:
            versions.append(f"{module} {__import__(module).__version__}")
        except (ImportError, AttributeError):
            continue
    text = [
        f"# Lossless ({datetime.date.today()}, tuckercodec {tuckercodec.__version__})",
        "",
        f"Machine: {common.machine()}; {', '.join(versions)}. Command: `{args.command}`. "
        f"Wall time {time.monotonic() - started:.0f} s.",
        "",
        *header,
        "",
        "bpfv of each coder's smallest file, whole file with the faces; every file decoded and "
        "compared bit for bit in the input's precision. Decode MB/s: float32-equivalent output "
        f"(F * K * 12 bytes) over the decode's time, medians of {args.repeat} run(s).",
        "",
        *summary_rows(entries, names, coders),
        "",
        *detail_rows(entries),
        "",
    ]
    if parts:
        text += [
            "tuckercodec's decode part by part, the lossless file beside the plain file at KG "
            f"{REFERENCE_KG:g} (medians of {args.repeat} run(s)):",
            "",
            *parts_rows(parts),
            "",
        ]
    text += [f"{coder}: skipped, {why}." for coder, why in skipped.items()]
    text += ["Misses:", *(f"- {m}" for m in found)] if found else ["Misses: none."]
    common.write_text(out / "lossless.md", "\n".join(text) + "\n", args.force)
    common.write_text(
        out / "results.json", json.dumps([asdict(e) for e in entries], indent=1), args.force
    )
    print("\n".join(text))
    return 0
