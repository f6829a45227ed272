"""Would context coding pay? zstd byte planes against adaptive arithmetic coding of the factors.

For each sequence and KG target the file is encoded as the codec does today,
its U1, U3, CORE and CENT sections are taken apart into the integers they stream (§6.3: a
predicted column's residuals, else its values, column after column) and each section's integers
are sized by:

* ``zstd``: the section as stored (byte planes, zstd level 19);
* ``H0``: the static order-0 entropy per column (no table cost): the bound of any context-free
  coder, adaptive or not;
* ``A0``: an adaptive arithmetic coder (ideal code length, a count per symbol starting at 1/2),
  one model per column;
* ``A1``: A0 with a context: the magnitude class of the same column's residual of the row's
  parent (U1: mesh parent; U3, CENT: previous frame; CORE: the previous entry) -- the
  neighbour-magnitude context;
* ``A2``: A1 and the magnitude class of the same row's residual in the previous column (the
  vertex's, or frame's, "activity", already decoded when columns are coded one after another);
* ``A3``: few contexts shared by all columns: the column's class (bit length of its mean
  zigzag value, a parameter the file could carry) and the class of the mean of the parent's
  and the previous column's zigzag values;
* ``A4``: A3 without the parent: the column's class and the previous column's class, so a
  decoder could decode a whole column in one vectorised call (no row-by-row dependency);
* ``S4``: A4's contexts with static tables sent in the file (about 12 bits per non-zero count),
  the kind of model a batch decoder (constriction's Categorical arrays) can use;
* ``zctx``: pure zstd: the same integers split by A2's context into separate byte-plane zstd
  frames (one per context class, sizes summed, plus 3 bytes per frame for lengths).

Symbols: a zigzag value below 16 is its own symbol; a larger one codes its bit length as a
symbol and the bits under the leading one raw. The adaptive sizes are ideal code lengths
(sum of -log2 p); ``--verify`` codes U1 of each file with constriction's range coder
(``pip install constriction``) using the same probabilities, to show that a real coder reaches
them within a few bytes. Nothing here is part of the codec.

``--rdo`` measures the quantizer instead: each file encoded with nearest rounding and with the
encoder's rate-distortion optimized quantization (:mod:`tuckercodec.encoder.rdo`), at the same
KG target (each encode meets it, measured with the decoder's reconstruction): sizes, the decoded
KG and the encode time.

    python -m tools.bench entropy                       # the four shared sequences, KG 1 0.1 0.02
    python -m tools.bench entropy --rdo
    python -m tools.bench entropy --targets 0.1 --verify ../shared/data/chicken.npz
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np

from tools.bench import arguments
from tools.common import REAL_SEQUENCES, in_shared_data, load
from tuckercodec import Decoder, encode_with_report, internal
from tuckercodec.internal import (
    adaptive,
    mesh_parents,
    parse_container,
    qmat,
    rdo,
    streams,
    tree_depths,
)

SECTIONS = ("U1", "U3", "CORE", "CENT")
DIRECT = 16  # zigzag values below this are symbols of their own
ALPHABET = DIRECT + 64
CLASSES = 8  # magnitude classes of a context: bit length of the neighbour's zigzag, capped
COLUMNS = ("zstd", "H0", "A0", "A1", "A2", "A3", "A4", "S4", "zctx")


def bit_length(values: np.ndarray) -> np.ndarray:
    """Bit length of non-negative int64 values (0 for 0)."""
    out = np.zeros(values.shape, dtype=np.int64)
    v = values.copy()
    while (v > 0).any():
        out += v > 0
        v >>= 1
    return out


def symbols(zig: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(symbol, raw bits) of each zigzag value."""
    length = bit_length(zig)
    big = zig >= DIRECT
    symbol = np.where(big, DIRECT + length - 5, zig)
    raw = np.where(big, length - 1, 0)
    return symbol, raw


def adaptive_bits(symbol: np.ndarray, context: np.ndarray) -> float:
    """Ideal code length of an adaptive frequency model per context (KT-style counts of 1/2),
    symbols coded in the order given."""
    key = context * ALPHABET + symbol
    before_key = _count_before(key)
    before_ctx = _count_before(context)
    p = (before_key + 0.5) / (before_ctx + 0.5 * ALPHABET)
    return float(-np.log2(p).sum())


def adaptive_probabilities(symbol: np.ndarray, context: np.ndarray) -> np.ndarray:
    """The model's full distribution at each symbol (for --verify): (n, ALPHABET) float64."""
    counts: dict[int, np.ndarray] = {}
    out = np.empty((symbol.size, ALPHABET))
    for n, (s, c) in enumerate(zip(symbol.tolist(), context.tolist(), strict=True)):
        table = counts.setdefault(c, np.full(ALPHABET, 0.5))
        out[n] = table / table.sum()
        table[s] += 1.0
    return out


def _count_before(key: np.ndarray) -> np.ndarray:
    """For each position, how many earlier positions hold the same key."""
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.r_[0, np.flatnonzero(np.diff(sorted_key)) + 1]
    group_start = np.repeat(starts, np.diff(np.r_[starts, key.size]))
    rank = np.empty(key.size, dtype=np.int64)
    rank[order] = np.arange(key.size) - group_start
    return rank


def order0_bits(symbol: np.ndarray, column: np.ndarray) -> float:
    key = column * ALPHABET + symbol
    counts = np.bincount(key)
    totals = np.bincount(column)
    p = counts[key] / totals[column]
    return float(-np.log2(p).sum())


def depth_order(parents: np.ndarray) -> np.ndarray:
    """Rows in an order where each parent comes before its children (by tree depth)."""
    return np.argsort(tree_depths(parents), kind="stable")


def section_streams(data: bytes) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    """Per section: (the integers it stores, as (rows, cols): residuals of whichever predictor
    each column uses; the parent of each row, for the contexts; their bytes in a zstd frame,
    as stored, or packed here where the file codes them adaptively, §6.14)."""
    container = parse_container(data)
    decoder = Decoder(data)
    mesh = mesh_parents(decoder.faces, decoder.info.vertices)
    out = {}
    for section_id in SECTIONS:
        entry = container.section(section_id)
        if entry is None:
            continue
        rows, cols = entry.params["shape"]
        payload = container.payload(data, entry)
        if entry.params.get("coder") == adaptive.CODER_ADAPTIVE:
            order = qmat.coding_order(
                internal.mesh_prediction(decoder._coded_faces, decoder.info.vertices)
                if section_id == "U1"
                else None,
                rows,
            )
            columns = adaptive.decode_columns(payload, cols, rows, order, section_id)
            length = len(streams.pack_integers(columns)[0])
        else:
            columns = streams.unpack_integers(
                payload, rows * cols, entry.params["planes"], section_id
            ).reshape(cols, rows)
            length = entry.length
        stream = np.ascontiguousarray(columns.T)
        parents = mesh if section_id == "U1" else np.arange(-1, rows - 1)
        out[section_id] = (stream, parents, length)
    return out


def measure(stream: np.ndarray, parents: np.ndarray) -> dict[str, float]:
    """Bytes of one section's integers by each coder of the module docstring."""
    cols = stream.shape[1]
    zig = streams.zigzag(stream).astype(np.int64)
    # context classes: the parent's (same column) and the previous column's (same row)
    parent_class = np.full(zig.shape, CLASSES, dtype=np.int64)  # a root: its own class
    has = np.flatnonzero(parents >= 0)
    parent_class[has] = np.minimum(bit_length(zig[parents[has]]), CLASSES - 1)
    left_class = np.zeros(zig.shape, dtype=np.int64)
    left_class[:, 1:] = np.minimum(bit_length(zig[:, :-1]), CLASSES - 1)
    # coding order: column after column, rows by depth (parents first)
    order = depth_order(parents)
    column = np.broadcast_to(np.arange(cols), zig.shape)
    pick = (order[:, None], np.arange(cols)[None, :])
    flat = [a[pick].T.reshape(-1) for a in (zig, parent_class, left_class, column)]
    z, pc, lc, col = flat
    symbol, raw = symbols(z)
    raw_bits = float(raw.sum())
    sizes = {
        "H0": (order0_bits(symbol, col) + raw_bits) / 8,
        "A0": (adaptive_bits(symbol, col) + raw_bits) / 8,
        "A1": (adaptive_bits(symbol, col * (CLASSES + 1) + pc) + raw_bits) / 8,
        "A2": (adaptive_bits(symbol, (col * (CLASSES + 1) + pc) * CLASSES + lc) + raw_bits) / 8,
    }
    # A3: few contexts, shared by every column: the column's magnitude class (its mean, a
    # per-column parameter a file could carry) and the neighbours' mean magnitude class
    column_mean = np.maximum(zig.mean(axis=0), 0).astype(np.int64)
    col_class = np.minimum(bit_length(column_mean), 15)[col]
    parent_zig = np.zeros(zig.shape, dtype=np.int64)
    parent_zig[has] = zig[parents[has]]
    left_zig = np.zeros(zig.shape, dtype=np.int64)
    left_zig[:, 1:] = zig[:, :-1]
    mix = (parent_zig + left_zig + 1) // 2
    mc = np.minimum(bit_length(mix[pick].T.reshape(-1)), 15)
    sizes["A3"] = (adaptive_bits(symbol, col_class * 16 + mc) + raw_bits) / 8
    lc16 = np.minimum(bit_length(left_zig[pick].T.reshape(-1)), 15)
    sizes["A4"] = (adaptive_bits(symbol, col_class * 16 + lc16) + raw_bits) / 8
    # S4: A4's contexts with a static model (decodable a column at a time, vectorised); its
    # tables cost about 12 bits per non-zero count
    key4 = (col_class * 16 + lc16) * ALPHABET + symbol
    tables = 1.5 * np.count_nonzero(np.bincount(key4))
    sizes["S4"] = (order0_bits(symbol, col_class * 16 + lc16) + raw_bits) / 8 + tables
    context = pc * CLASSES + lc
    total = 0
    for c in np.unique(context):
        part = z[context == c]
        planes = streams.planes_needed(part.astype(np.uint64))
        total += len(streams.compress(streams.to_planes(part.astype(np.uint64), planes))) + 3
    sizes["zctx"] = float(total)
    return sizes


def verify(stream: np.ndarray, parents: np.ndarray) -> tuple[int, float]:
    """U1 coded for real with constriction's range coder under A2's adaptive model:
    (bytes, ideal bytes)."""
    import constriction

    cols = stream.shape[1]
    zig = streams.zigzag(stream).astype(np.int64)
    parent_class = np.full(zig.shape, CLASSES, dtype=np.int64)
    has = np.flatnonzero(parents >= 0)
    parent_class[has] = np.minimum(bit_length(zig[parents[has]]), CLASSES - 1)
    left_class = np.zeros(zig.shape, dtype=np.int64)
    left_class[:, 1:] = np.minimum(bit_length(zig[:, :-1]), CLASSES - 1)
    order = depth_order(parents)
    pick = (order[:, None], np.arange(cols)[None, :])
    column = np.broadcast_to(np.arange(cols), zig.shape)
    z, pc, lc, col = (a[pick].T.reshape(-1) for a in (zig, parent_class, left_class, column))
    symbol, raw = symbols(z)
    context = (col * (CLASSES + 1) + pc) * CLASSES + lc
    probabilities = adaptive_probabilities(symbol, context)
    encoder = constriction.stream.queue.RangeEncoder()
    family = constriction.stream.model.Categorical(perfect=False)
    encoder.encode(symbol.astype(np.int32), family, probabilities)
    coded = encoder.get_compressed().nbytes + int(raw.sum() + 7) // 8
    ideal = (adaptive_bits(symbol, context) + float(raw.sum())) / 8
    return coded, ideal


def compare_rdo(paths: list[Path], targets: list[float]) -> int:
    """The RDO table: nearest rounding against the encoder's RDO at each KG target."""
    print(f"{'sequence':14} {'KG':>5} {'quantizer':9} {'file':>9} {'no FACE':>9} {'U1':>9}")
    print(f"{'':30}{'U3':>9} {'CORE':>8} {'gain':>7} {'gain*':>7} {'KG out':>8} {'s':>6}")
    for path in paths:
        sequence = load(path)
        for kg in targets:
            base: tuple[int, int] | None = None
            for name, settings in (("nearest", rdo.NEAREST), ("rdo", rdo.DEFAULT)):
                with mock.patch.object(rdo, "DEFAULT", settings):
                    start = time.perf_counter()
                    result = encode_with_report(sequence, target_kg=kg)
                    seconds = time.perf_counter() - start
                sizes = result.report.section_bytes
                total = len(result.data)
                rest = total - sizes.get("FACE", 0)
                base = base or (total, rest)
                print(
                    f"{path.stem:14} {kg:5g} {name:9} {total:9d} {rest:9d} {sizes['U1']:9d} "
                    f"{sizes['U3']:9d} {sizes['CORE']:8d} {100 * (total / base[0] - 1):+6.2f}% "
                    f"{100 * (rest / base[1] - 1):+6.2f}% {result.report.kg:8.5f} {seconds:6.2f}"
                )
    print("gain: whole file against nearest rounding; gain*: without FACE")
    return 0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The entropy suite's options."""
    arguments.sequences(parser, "the real sequences of ../shared/data present")
    parser.add_argument("--targets", type=float, nargs="+", default=[1.0, 0.1, 0.02])
    parser.add_argument("--verify", action="store_true", help="code U1 with constriction")
    parser.add_argument("--rdo", action="store_true", help="nearest rounding against RDO")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p) for p in args.sequences]
    if not paths:
        paths, absent = in_shared_data(REAL_SEQUENCES)
        for p in absent:
            print(f"skipped {p}: not present", file=sys.stderr)
    if args.rdo:
        return compare_rdo(paths, args.targets)
    print("bytes per section and coder; gains against zstd: A3 (the best) and S4 (one a fast")
    print("decoder could use), over the whole file and without FACE (which the lead replaces)\n")
    header = f"{'sequence':10} {'KG':>5} {'sect':5}" + "".join(f"{c:>10}" for c in COLUMNS)
    print(header)
    for path in paths:
        sequence = load(path)
        for kg in args.targets:
            result = encode_with_report(sequence, target_kg=kg)
            data = result.data
            face = result.report.section_bytes.get("FACE", 0)
            totals = dict.fromkeys(COLUMNS, 0.0)
            for section_id, (stream, parents, stored) in section_streams(data).items():
                sizes = {"zstd": float(stored), **measure(stream, parents)}
                for c in COLUMNS:
                    totals[c] += sizes[c]
                row = "".join(f"{sizes[c]:10.0f}" for c in COLUMNS)
                print(f"{path.stem:10} {kg:5g} {section_id:5}{row}")
                if args.verify and section_id == "U1":
                    coded, ideal = verify(stream, parents)
                    print(f"{'':22}constriction, A2 model: {coded} bytes (ideal {ideal:.0f})")
            gain = totals["zstd"] - totals["A3"]
            sgain = totals["zstd"] - totals["S4"]
            zgain = totals["zstd"] - totals["zctx"]
            print(
                f"{path.stem:10} {kg:5g} {'all':5}"
                + "".join(f"{totals[c]:10.0f}" for c in COLUMNS)
                + f"   file {len(data)} ({len(data) - face} without FACE): A3 saves "
                f"{100 * gain / len(data):.1f} % ({100 * gain / (len(data) - face):.1f} %), "
                f"S4 {100 * sgain / len(data):.1f} % ({100 * sgain / (len(data) - face):.1f} %), "
                f"zctx {100 * zgain / len(data):.1f} %"
            )
    return 0
