"""Seeds for the compiled core's libFuzzer targets (``tuckercodec/native/fuzz``), from the
conformance vectors: ``python -m tools.fuzz.native_seeds``.

Each vector is decoded by the package's own reader while the calls into the loops the core runs
are recorded (the faces-traverse streams as :func:`tuckercodec.format.traversal.read_stream_arrays`
reads them, valid or broken), and each recorded call, each decoded mesh and its OBJ text is
written as an input in its target's framing (``tuckercodec_core::fuzzing``, whose doc comments
are the reference for the framings). The seeds go to ``tests/fuzz/native/<target>/`` (committed,
kept small), which ``cargo test -p tuckercodec-core`` replays and the fuzz runs start from.
"""

from __future__ import annotations

import argparse
import hashlib
import struct
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from .paths import FUZZ_DIR, VECTORS

NATIVE_SEEDS = FUZZ_DIR / "native"
#: A seed larger than this is left out (libFuzzer's default -max_len is 4096 for new inputs).
MAX_SEED_BYTES = 16 * 1024
#: The line-length limit the text_check seeds use (what the OBJ reader allows, and a tight one).
TEXT_LIMITS = (1 << 20, 40)


def varint(value: int) -> bytes:
    """LEB128 of ``value >= 0`` (``Framing::varint``)."""
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def signed(value: int) -> bytes:
    """Zigzag varint of an int64 (``Framing::signed``)."""
    return varint(((value << 1) ^ (value >> 63)) & ((1 << 64) - 1))


def signed_values(values: Iterable[int]) -> bytes:
    return b"".join(signed(int(v)) for v in values)


def traversal_decode_input(
    arrays: list[np.ndarray], count: int, width: int, k: int, corner_order: int
) -> bytes:
    """A ``traversal_decode`` input: corner order, width, count, k, four lengths, the values."""
    head = bytes([corner_order & 1, (width - 1) % 8]) + varint(count) + signed(k)
    head += b"".join(varint(len(values)) for values in arrays)
    return head + b"".join(signed_values(values.tolist()) for values in arrays)


def traversal_roundtrip_input(faces: np.ndarray, k: int) -> bytes:
    """A ``traversal_roundtrip`` input: width, k, the table's entries row-major."""
    width = faces.shape[1]
    return bytes([(width - 3) % 6]) + varint(k) + signed_values(faces.reshape(-1).tolist())


def text_check_input(text: bytes, limit: int, cuts: list[int]) -> bytes:
    """A ``text_check`` input: the line limit, the cut positions, the text."""
    return varint(limit) + bytes([len(cuts)]) + b"".join(varint(c) for c in cuts) + text


def obj_text(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """One frame as OBJ text, as the package's writer lays it out (Python's ``repr`` of each
    coordinate, 1-based faces without the padding)."""
    lines = ["v " + " ".join(repr(float(x)) for x in xyz) for xyz in vertices.tolist()]
    lines += ["f " + " ".join(str(v + 1) for v in row if v >= 0) for row in faces.tolist()]
    return "".join(line + "\n" for line in lines).encode()


def walked_inputs(faces: np.ndarray, k: int) -> list[bytes]:
    """``traversal_decode`` inputs of the streams the encoder's walk writes for ``faces``, for
    both corner orders."""
    from tuckercodec.internal import traversal

    walk = traversal._walked(faces, len(faces), k)
    coded = [walk.degrees, walk.new_residuals, walk.references]
    return [
        traversal_decode_input(
            [np.asarray(s, dtype=np.int64) for s in (walk.ops[order], *coded)],
            len(faces),
            faces.shape[1],
            k,
            order,
        )
        for order in (0, 1)
    ]


@contextmanager
def recorded_traversals(calls: list[tuple[Any, ...]]) -> Iterator[None]:
    """Records the streams of every faces-traverse FACE section decoded inside the block."""
    from tuckercodec.internal import traversal

    walk = traversal.walk_streams

    def recording(
        arrays: list[np.ndarray], count: int, width: int, k: int, corner_order: int, where: str
    ) -> np.ndarray:
        calls.append((arrays, count, width, k, corner_order))
        return walk(arrays, count, width, k, corner_order, where)

    traversal.walk_streams = recording
    try:
        yield
    finally:
        traversal.walk_streams = walk


#: The domains of §6.9 in the order of the residual_correct framing's first byte.
DOMAINS = (
    "grid",
    "float32",
    "float64",
    "decimal-places",
    "decimal-digits",
    "decimal-digits-float32",
)
#: The most (P, e) pairs a residual_correct seed keeps.
MAX_PAIRS = 256


def residual_restore_input(raw: bytes, count: int, planes: int, predict: bool, frame: int) -> bytes:
    """A ``residual_restore`` input: flags, planes, count, frame values, the chunk's bytes."""
    return bytes([int(predict), planes]) + varint(count) + varint(frame) + raw


def residual_correct_input(exact: np.ndarray, residual: np.ndarray, domain: Any) -> bytes:
    """A ``residual_correct`` input: the domain, its scale and step, (P, e) pairs."""
    head = bytes([DOMAINS.index(domain.name), domain.scale or 0])
    if domain.name == "grid":
        head += struct.pack("<d", domain.step)
    exact, residual = exact.reshape(-1)[:MAX_PAIRS], residual.reshape(-1)[:MAX_PAIRS]
    pairs = zip(exact.tolist(), residual.tolist(), strict=True)
    return head + b"".join(struct.pack("<d", p) + signed(e) for p, e in pairs)


@contextmanager
def recorded_corrections(seeds: dict[str, list[bytes]]) -> Iterator[None]:
    """Records every chunk of corrections restored and every correction made inside the
    block, as seeds of ``residual_restore`` and ``residual_correct``."""
    from tuckercodec import internal

    format_residual, streams = internal.residual, internal.streams
    decode_chunk, correct = format_residual.decode_chunk, format_residual.correct

    def recording_chunk(
        payload: bytes | memoryview, layout: Any, chunk: int, vertices: int, where: str
    ) -> np.ndarray:
        start, stop = layout.chunk_range(chunk)
        count, planes = (stop - start) * vertices * 3, layout.planes[chunk]
        piece = payload[layout.offsets[chunk] : layout.offsets[chunk + 1]]
        raw = streams.decompress_exact(piece, count * planes, where)
        seeds.setdefault("residual_restore", []).append(
            residual_restore_input(raw, count, planes, layout.predict == 1, vertices * 3)
        )
        return decode_chunk(payload, layout, chunk, vertices, where)

    def recording_correct(
        exact: np.ndarray, residual: np.ndarray, domain: internal.residual.Domain, where: str
    ) -> np.ndarray:
        seeds.setdefault("residual_correct", []).append(
            residual_correct_input(exact, residual, domain)
        )
        return correct(exact, residual, domain, where)

    format_residual.decode_chunk, format_residual.correct = recording_chunk, recording_correct
    try:
        yield
    finally:
        format_residual.decode_chunk, format_residual.correct = decode_chunk, correct


def streams_unpack_input(raw: bytes, count: int, planes: int) -> bytes:
    """A ``streams_unpack`` input: flags, planes, count, the decompressed stream."""
    return bytes([0, planes]) + varint(count) + raw


@contextmanager
def recorded_streams(seeds: dict[str, list[bytes]]) -> Iterator[None]:
    """Records every integer stream unpacked inside the block (those that decompress), as
    seeds of ``streams_unpack``."""
    import tuckercodec
    from tuckercodec import internal

    streams = internal.streams
    unpack = streams.unpack_integers

    def recording(payload: bytes | memoryview, count: int, planes: int, where: str) -> np.ndarray:
        try:
            raw = streams.decompress_exact(payload, count * planes, where)
        except tuckercodec.FormatError:
            raw = None
        if raw is not None and 0 <= planes < 256:
            seeds.setdefault("streams_unpack", []).append(streams_unpack_input(raw, count, planes))
        return unpack(payload, count, planes, where)

    streams.unpack_integers = recording
    try:
        yield
    finally:
        streams.unpack_integers = unpack


def adaptive_decode_input(payload: bytes, cols: int, order: Any) -> bytes:
    """An ``adaptive_decode`` input with the order's arrays as they are (kind 2, bit 2 for a
    mesh's): the rows, the three arrays, the column count, the payload."""
    head = bytes([2 | (4 if order.mesh else 0)]) + varint(order.order.size)
    for array in (order.order, order.sources, order.ends):
        head += varint(array.size) + signed_values(array.tolist())
    return head + varint(cols) + bytes(payload)


@contextmanager
def recorded_adaptive(seeds: dict[str, list[bytes]]) -> Iterator[None]:
    """Records every adaptive stream (§6.14) decoded inside the block, as seeds of
    ``adaptive_decode``."""
    from tuckercodec.internal import adaptive

    decode = adaptive.decode_columns

    def recording(
        payload: bytes | memoryview, cols: int, rows: int, order: Any, where: str
    ) -> np.ndarray:
        if rows == order.order.size:
            seeds.setdefault("adaptive_decode", []).append(
                adaptive_decode_input(bytes(payload), cols, order)
            )
        return decode(payload, cols, rows, order, where)

    adaptive.decode_columns = recording
    try:
        yield
    finally:
        adaptive.decode_columns = decode


def prediction_inputs(faces: np.ndarray, vertices: np.ndarray) -> list[bytes]:
    """``prediction_restore`` inputs of a mesh: predictor 2 over its faces with its first
    frame's positions in thousandths as the columns, and predictors 1 and 3 along its
    breadth-first forest (``mesh_parents``) with the same values."""
    from tuckercodec import internal

    k, width = len(vertices), faces.shape[1]
    values = np.rint(vertices * 1000).astype(np.int64)
    mean = bytes([0, (width - 3) % 6]) + varint(k) + varint(len(faces))
    mean += signed_values(faces.reshape(-1).tolist()) + bytes([2])
    mean += signed_values(values.reshape(-1).tolist())
    parents = internal.mesh_parents(faces, k)
    tree = bytes([2]) + varint(k) + bytes([2]) + signed_values(parents.tolist())
    tree += signed_values(values.reshape(-1).tolist())
    return [mean, tree]


def vector_seeds(path: Path) -> dict[str, list[bytes]]:
    """The seeds of one vector, by target."""
    import tuckercodec

    seeds: dict[str, list[bytes]] = {}
    calls: list[tuple[Any, ...]] = []
    with (
        recorded_traversals(calls),
        recorded_corrections(seeds),
        recorded_streams(seeds),
        recorded_adaptive(seeds),
    ):
        try:
            mesh = tuckercodec.decode(path)
        except (tuckercodec.TuckerCodecError, ValueError):
            mesh = None  # a broken vector: its recorded calls are seeds all the same
    seeds["traversal_decode"] = [traversal_decode_input(*call) for call in calls]
    if mesh is not None and mesh.faces.size:
        faces, k = np.asarray(mesh.faces, dtype=np.int64), int(mesh.vertex_count)
        seeds["traversal_roundtrip"] = [traversal_roundtrip_input(faces, k)]
        seeds["traversal_decode"] += walked_inputs(faces, k)
        vertices = np.asarray(mesh.vertices[0], dtype=np.float64)
        text = obj_text(vertices, faces)
        seeds["obj_parse"] = [text]
        # the tight limit for the small texts only: a long text is refused at its first line
        limit = TEXT_LIMITS[len(text) < 1024]
        seeds["text_check"] = [text_check_input(text, limit, [len(text) // 3, len(text) // 2])]
        seeds["prediction_restore"] = prediction_inputs(faces, vertices)
        values = vertices.reshape(-1)[:4].tolist()
        seeds["float_repr"] = [struct.pack("<d", v) for v in values]
    return seeds


def adaptive_seeds() -> dict[str, list[bytes]]:
    """``adaptive_decode`` and ``adaptive_roundtrip`` inputs: small matrices coded by the
    reference coder (§6.14) in ascending order (kind 0) and in U1's order over a grid of
    triangles (kind 1), and the stream of each cut short."""
    from tuckercodec.internal import adaptive, mesh_prediction, native, sheet_triangles

    rng = np.random.default_rng(46)
    faces = sheet_triangles(5)
    steps = mesh_prediction(faces, 25).mean_steps
    mesh = (
        bytes([1, 0]) + varint(25) + varint(len(faces)) + signed_values(faces.reshape(-1).tolist()),
        adaptive.mesh_order(25, steps.rows, steps.sources, steps.source_ends),
    )
    seeds: dict[str, list[bytes]] = {"adaptive_decode": [], "adaptive_roundtrip": []}
    for rows, scale in [(1, 3.0), (7, 40.0), (25, 2.0), (25, 1e6)]:
        orders = [(bytes([0]) + varint(rows), adaptive.sequence_order(rows))]
        if rows == 25:
            orders.append(mesh)
        for head, order in orders:
            columns = np.rint(rng.laplace(0, scale, (3, rows))).astype(np.int64)
            with native.pure_python():
                payload = adaptive.encode_columns(columns, order)
            framed = head + varint(3)
            seeds["adaptive_decode"] += [framed + payload, framed + payload[:-1]]
            seeds["adaptive_roundtrip"].append(framed + signed_values(columns.reshape(-1).tolist()))
    return seeds


def extra_seeds() -> dict[str, list[bytes]]:
    """Small hand-made inputs for the edges the vectors do not reach."""
    floats = [0.0, -0.0, 1e16, 1e-5, 0.0001, 5e-324, 1.7976931348623157e308, float("inf")]
    return {
        **adaptive_seeds(),
        "float_repr": [struct.pack("<d", v) for v in floats] + [b"\xff" * 8],
        "text_check": [
            text_check_input("é\r\nv 1 2 3\rf 1 2 3\n".encode(), 8, [1, 2, 10]),
            text_check_input(b"\xe2\x82", 100, []),
            text_check_input(b"a\x00b", 100, [1]),
        ],
        "obj_parse": [
            b"v 0 0 0\nv 1 0 0\\\n 0\nv 0 1 0 # c\nf -3 -2 -1\nf 1/1 2//2 3/3/3\n",
            b"v nan 0 0\n",
            b"f 1 2 3\n",
        ],
    }


def write_seeds(folder: Path, by_target: dict[str, list[bytes]]) -> dict[str, int]:
    """Writes each seed as ``<target>/seed-<sha1 prefix>`` (new folders' old seeds removed
    first); returns the count by target."""
    written: dict[str, int] = {}
    for target, seeds in sorted(by_target.items()):
        out = folder / target
        out.mkdir(parents=True, exist_ok=True)
        for old in out.glob("seed-*"):
            old.unlink()
        kept = {hashlib.sha1(s).hexdigest()[:16]: s for s in seeds if len(s) <= MAX_SEED_BYTES}
        for name, data in sorted(kept.items()):
            (out / f"seed-{name}").write_bytes(data)
        written[target] = len(kept)
    return written


def collect(
    vectors: Iterable[Path], each: Callable[[Path], dict[str, list[bytes]]]
) -> dict[str, list[bytes]]:
    """Every vector's seeds and the hand-made ones, by target."""
    by_target: dict[str, list[bytes]] = {}
    for path in vectors:
        for target, seeds in each(path).items():
            by_target.setdefault(target, []).extend(seeds)
    for target, seeds in extra_seeds().items():
        by_target.setdefault(target, []).extend(seeds)
    return by_target


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=NATIVE_SEEDS, help="the seed folder")
    args = parser.parse_args(argv)
    by_target = collect(sorted(VECTORS.glob("*.tkc")), vector_seeds)
    for target, count in write_seeds(args.out, by_target).items():
        size = sum(p.stat().st_size for p in (args.out / target).iterdir())
        print(f"{target}: {count} seeds, {size} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
