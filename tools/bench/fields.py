"""Fields: the animated fields' codec (§6.13) in each mode, against SZ3 and zfp at the same
bound on every value.

The fields measured:

* of an ``.npz`` sequence (default: samba and the cloth of ../shared/data), two made from its
  positions: the velocity (finite differences of the positions times 24 frames a second, three
  components, float32) and the speed (its length, one component, float32);
* of any other sequence the reader takes (a ``.pvd``, an ``.xdmf``...), its own fields: the
  point and cell data as :func:`tuckercodec.load_sequence` gives them;
* with ``--simulation``, those of a real solver's run, SfePy's elastodynamics example (point
  data ``u``, ``du``, ``ddu``, cell data ``cauchy_strain``, ``cauchy_stress``, float64), made by
  :mod:`tools.generate.simulation` into :data:`SIMULATION` (a message says how when absent).

Each field is coded

* by tuckercodec (:func:`tuckercodec.internal.encode_field`) at relative-rms 1 and 0.1 % (mode
  tucker), at bounds of 1e-3 and 1e-4 of the field's range (max - min over every value) on every
  value (mode grid) and lossless (mode exact);
* by SZ3 (pysz, absolute mode) and zfp (zfpy, fixed accuracy) at the same bounds, the values
  laid out component, element, frame (time fastest); with ``--peer-grid``, also with the
  elements as a square grid (component, row, column, frame) where their count is a square, for
  a series numbered row by row on a square grid, as the simulation's vertices and cells are:
  the layout in which those coders see the grid's neighbours.

Every file is decoded (tuckercodec's sections as a file's would be) and its error measured with
numpy in float64 against the input; a coder that misses its target is marked. Sizes are the
coded bytes and bits per value (bytes * 8 / (F * N * c)); times the medians of ``--repeats``
encodes and decodes (tuckercodec's encode includes the decodes it checks itself with).

    python -m tools.bench fields
    python -m tools.bench fields ../shared/data/cloth-vellum.npz --frames 30
    python -m tools.bench fields --simulation --peer-grid
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

import tuckercodec
from tools import common
from tuckercodec import internal

DEFAULT_SEQUENCES = ("cloth-vellum.npz", "samba.npz")
#: The real simulation's series, as :mod:`tools.generate.simulation` writes it by default.
SIMULATION = Path("~/.cache/tuckercodec-bench/sfepy-elastodynamic/elastodynamic.pvd").expanduser()
SIMULATION_HOWTO = (
    "make it with SfePy and meshio in a scratch environment: see tools/generate/simulation.py"
)
FRAME_RATE = 24.0
RELATIVE_TARGETS = (1.0, 0.1)
BOUNDS_OF_RANGE = (1e-3, 1e-4)
PEERS = ("sz3", "zfp")

Result = TypeVar("Result")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The fields suite's options."""
    parser.add_argument(
        "sequences",
        nargs="*",
        help="the sequences: .npz (fields made from the positions) or any format with fields, "
        f"e.g. .pvd (default: {', '.join(DEFAULT_SEQUENCES)} of {common.SHARED_DATA})",
    )
    parser.add_argument(
        "--simulation",
        action="store_true",
        help=f"measure the real simulation's series ({SIMULATION}) instead of the defaults",
    )
    parser.add_argument(
        "--frames", type=int, default=None, help="only the first FRAMES frames of each"
    )
    parser.add_argument(
        "--coders",
        default="tuckercodec,sz3,zfp",
        help="a comma-separated subset of tuckercodec, sz3, zfp (default: all)",
    )
    parser.add_argument(
        "--repeats", type=int, default=3, help="encodes and decodes timed (median; default 3)"
    )
    parser.add_argument(
        "--peer-grid",
        action="store_true",
        help="also SZ3 and zfp on the elements as a square grid, where their count is a square",
    )


@dataclass
class Measure:
    """One coded field: what was asked, what came out, and whether it met the target."""

    coder: str
    target: str
    mode: str
    size: int
    error: str
    met: bool
    encode_seconds: float
    decode_seconds: float


def timed(action: Callable[[], Result], repeats: int) -> tuple[Result, float]:
    """``action``'s last result and the median of its ``repeats`` (at least 1) run times."""
    seconds = []
    result = None
    for _ in range(max(1, repeats)):
        start = time.perf_counter()
        result = action()
        seconds.append(time.perf_counter() - start)
    assert result is not None
    return result, statistics.median(seconds)


def _velocity_fields(path: Path, frames: int | None) -> tuple[list[tuckercodec.Field], Any]:
    with np.load(path, allow_pickle=False) as data:
        vertices, faces = data["V"][:frames], data["F"].astype(np.int64)
    velocity = (np.diff(vertices, axis=0, prepend=vertices[:1]) * FRAME_RATE).astype(np.float32)
    speed = np.linalg.norm(velocity, axis=2).astype(np.float32)
    mesh = internal.mesh_prediction(faces, vertices.shape[1])
    return [
        tuckercodec.Field("velocity", velocity, "vertex", "velocity"),
        tuckercodec.Field("speed", speed, "vertex"),
    ], mesh


def fields_of(path: Path, frames: int | None) -> tuple[list[tuckercodec.Field], Any]:
    """The fields of the sequence at ``path`` (made from the positions of an ``.npz``, else
    its own), each of its first ``frames`` frames, and its mesh prediction."""
    if path.suffix == ".npz":
        return _velocity_fields(path, frames)
    sequence = tuckercodec.load_sequence(path)
    items = [
        tuckercodec.Field(f.name, f.values[:frames], f.domain, f.role) for f in sequence.fields
    ]
    return items, internal.mesh_prediction(sequence.faces, sequence.vertices.shape[1])


def bounds_of(item: tuckercodec.Field) -> list[float]:
    """The bounds on every value measured: :data:`BOUNDS_OF_RANGE` of the field's range (none
    for a constant field, which has no range to take a fraction of)."""
    span = float(item.values.max() - item.values.min())
    return [fraction * span for fraction in BOUNDS_OF_RANGE] if span > 0 else []


def tucker_targets(bounds: list[float]) -> list[str]:
    """tuckercodec's targets: each relative one, each bound, lossless."""
    return [f"rel:{t:g}" for t in RELATIVE_TARGETS] + [f"max:{b!r}" for b in bounds] + ["lossless"]


def _judged(
    item: tuckercodec.Field, target: internal.FieldTarget, back: np.ndarray
) -> tuple[str, bool]:
    """(error text, target met) of decoded values ``back``."""
    if target.lossless:
        exact = back.dtype == item.values.dtype and np.array_equal(
            back.view(np.uint8), item.values.view(np.uint8)
        )
        return ("bit-exact" if exact else "differs"), exact
    if target.relative is not None:
        measured = internal.relative_rms(item.values, back)
        return f"relative-rms {measured:.4g} %", measured <= target.relative
    worst = internal.max_abs(item.values, back)
    assert target.max_error is not None
    return f"max-abs {worst:.4g}", worst <= target.max_error


def measure_tucker(item: tuckercodec.Field, mesh: Any, text: str, repeats: int) -> Measure:
    """tuckercodec at target ``text`` (``rel:P``, ``max:E`` or ``lossless``)."""
    target = internal.FieldTarget.parse(text)
    encoded, encode_seconds = timed(lambda: internal.encode_field(item, 0, target, mesh), repeats)
    back, decode_seconds = timed(
        lambda: internal.decoded_field(encoded.sections, 0, item, mesh), repeats
    )
    error, met = _judged(item, target, back)
    report = encoded.report
    return Measure(
        "tuckercodec", text, report.mode, report.bytes, error, met, encode_seconds, decode_seconds
    )


def peer_layout(values: np.ndarray, grid: bool) -> np.ndarray | None:
    """(F, N, c) values as (c, N, F), time fastest; with ``grid``, as (c, s, s, F) when N = s * s
    (None when N is no square)."""
    arranged = values.transpose(2, 1, 0)
    if grid:
        side = math.isqrt(values.shape[1])
        if side * side != values.shape[1]:
            return None
        arranged = arranged.reshape(values.shape[2], side, side, values.shape[0])
    return np.ascontiguousarray(arranged)


def _peer_codec(
    coder: str, bound: float, arranged: np.ndarray
) -> tuple[Callable[[], bytes], Callable[[bytes], np.ndarray]]:
    """(compress () -> bytes, decompress bytes -> array) of ``coder`` at ``bound``."""
    if coder == "sz3":
        from pysz import sz, szConfig, szErrorBoundMode

        def sz3_compress() -> bytes:
            config = szConfig(arranged.shape)
            config.errorBoundMode = szErrorBoundMode.ABS
            config.absErrorBound = bound
            return bytes(sz.compress(arranged, config)[0].tobytes())

        def sz3_decompress(data: bytes) -> np.ndarray:
            payload = np.frombuffer(data, dtype=np.uint8)
            return np.asarray(sz.decompress(payload, arranged.dtype, arranged.shape)[0])

        return sz3_compress, sz3_decompress
    import zfpy

    return (
        lambda: bytes(zfpy.compress_numpy(arranged, tolerance=bound)),
        lambda data: np.asarray(zfpy.decompress_numpy(data)),
    )


def measure_peer(
    item: tuckercodec.Field, coder: str, bound: float, repeats: int, grid: bool = False
) -> Measure | None:
    """SZ3 or zfp at ``bound`` on every value, in :func:`peer_layout`'s layout (None: no grid)."""
    arranged = peer_layout(item.values, grid)
    if arranged is None:
        return None
    compress, decompress = _peer_codec(coder, bound, arranged)
    data, encode_seconds = timed(compress, repeats)
    back, decode_seconds = timed(lambda: decompress(data), repeats)
    worst = internal.max_abs(arranged, np.asarray(back).reshape(arranged.shape))
    return Measure(
        coder + (" (grid)" if grid else ""),
        f"max:{bound!r}",
        "abs",
        len(data),
        f"max-abs {worst:.4g}",
        worst <= bound,
        encode_seconds,
        decode_seconds,
    )


def row(sequence: str, item: tuckercodec.Field, measure: Measure) -> str:
    """One Markdown row of the table :func:`run` prints."""
    bpv = 8.0 * measure.size / item.values.size
    mark = "" if measure.met else " (misses its target)"
    target = measure.target
    if target.startswith("max:"):
        target = f"max:{float(target[4:]):.4g}"
    return (
        f"| {sequence} | {item.name} | {item.domain} ({item.values.shape[2]}, {item.values.dtype}) "
        f"| {measure.coder} | {target} | {measure.mode} | {measure.size:,} | {bpv:.3f} | "
        f"{measure.error}{mark} | {measure.encode_seconds:.3f} | {measure.decode_seconds:.3f} |"
    )


def measures(
    item: tuckercodec.Field, mesh: Any, coders: list[str], repeats: int, peer_grid: bool
) -> list[Measure]:
    """Every coder's measures of one field, in the table's order."""
    bounds = bounds_of(item)
    out = []
    if "tuckercodec" in coders:
        out += [measure_tucker(item, mesh, text, repeats) for text in tucker_targets(bounds)]
    for bound in bounds:
        for coder in PEERS:
            if coder not in coders:
                continue
            for grid in (False, True) if peer_grid else (False,):
                peer = measure_peer(item, coder, bound, repeats, grid)
                if peer is not None:
                    out.append(peer)
    return out


def _paths(args: argparse.Namespace) -> list[Path]:
    paths = [Path(p) for p in args.sequences]
    if args.simulation:
        paths.append(SIMULATION)
    return paths or [common.SHARED_DATA / name for name in DEFAULT_SEQUENCES]


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    coders = [c.strip() for c in args.coders.split(",") if c.strip()]
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print(
        "bpv: bits per value; encode and decode s: medians of "
        f"{max(1, args.repeats)} runs (tuckercodec's encode includes its checking decodes)"
    )
    print(
        "| sequence | field | values (domain, components, type) | coder | target | mode | bytes "
        "| bpv | error measured | encode s | decode s |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for path in _paths(args):
        if not path.exists():
            howto = f": {SIMULATION_HOWTO}" if path == SIMULATION else ""
            print(f"| {path.name} | absent{howto} | | | | | | | | | |")
            continue
        items, mesh = fields_of(path, args.frames)
        for item in items:
            for measure in measures(item, mesh, coders, args.repeats, args.peer_grid):
                print(row(path.stem, item, measure), flush=True)
    return 0
