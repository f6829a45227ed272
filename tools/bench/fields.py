"""Fields: the animated fields' codec (§6.13) in each mode, against SZ3 and zfp at the same
bound on every value.

For each sequence (default: samba and the cloth of ../shared/data), two fields made from its
positions: the velocity (finite differences of the positions times 24 frames a second, three
components, float32) and the speed (its length, one component, float32). Each is coded

* by tuckercodec (:func:`tuckercodec.internal.encode_field`) at relative-rms 1 and 0.1 (mode
  tucker), at a bound of 1e-3 of the field's range on every value (mode grid) and lossless
  (mode exact), every file decoded and its error measured;
* by SZ3 (pysz, absolute mode) and zfp (zfpy, fixed accuracy) at the same bound, the values
  laid out component, element, frame (time fastest), each file decoded and its largest error
  measured (a coder that breaks its bound is marked).

Sizes are the coded bytes and bits per value (bytes * 8 / (F * N * c)).

    python -m tools.bench fields
    python -m tools.bench fields ../shared/data/cloth-vellum.npz --frames 30
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

import tuckercodec
from tools import common
from tuckercodec import internal

DEFAULT_SEQUENCES = ("cloth-vellum.npz", "samba.npz")
FRAME_RATE = 24.0
RELATIVE_TARGETS = (1.0, 0.1)
BOUND_OF_RANGE = 1e-3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The fields suite's options."""
    parser.add_argument(
        "sequences",
        nargs="*",
        help="the .npz sequences (default: "
        f"{', '.join(DEFAULT_SEQUENCES)} of {common.SHARED_DATA})",
    )
    parser.add_argument(
        "--frames", type=int, default=None, help="only the first FRAMES frames of each"
    )
    parser.add_argument(
        "--coders",
        default="tuckercodec,sz3,zfp",
        help="a comma-separated subset of tuckercodec, sz3, zfp (default: all)",
    )


def fields_of(path: Path, frames: int | None) -> tuple[list[tuckercodec.Field], Any]:
    """The velocity and speed fields of the sequence at ``path``, and its mesh prediction."""
    with np.load(path, allow_pickle=False) as data:
        vertices, faces = data["V"][:frames], data["F"].astype(np.int64)
    velocity = (np.diff(vertices, axis=0, prepend=vertices[:1]) * FRAME_RATE).astype(np.float32)
    speed = np.linalg.norm(velocity, axis=2).astype(np.float32)
    mesh = internal.mesh_prediction(faces, vertices.shape[1])
    return [
        tuckercodec.Field("velocity", velocity, "vertex", "velocity"),
        tuckercodec.Field("speed", speed, "vertex"),
    ], mesh


def _row(
    sequence: str,
    item: tuckercodec.Field,
    coder: str,
    target: str,
    mode: str,
    size: int,
    error: str,
    seconds: float,
) -> str:
    bpv = 8.0 * size / item.values.size
    return (
        f"| {sequence} | {item.name} | {coder} | {target} | {mode} | {size:,} | {bpv:.3f} | "
        f"{error} | {seconds:.1f} |"
    )


def tucker_rows(sequence: str, item: tuckercodec.Field, mesh: Any, bound: float) -> list[str]:
    """tuckercodec's rows: each relative target, the bound and lossless."""
    rows = []
    targets = [f"rel:{t:g}" for t in RELATIVE_TARGETS] + [f"max:{bound:.6g}", "lossless"]
    for text in targets:
        start = time.perf_counter()
        encoded = internal.encode_field(item, 0, internal.FieldTarget.parse(text), mesh)
        seconds = time.perf_counter() - start
        report = encoded.report
        if report.definition == "relative-rms":
            measured = internal.relative_rms(item.values, encoded.values)
            error = f"relative-rms {measured:.4g} %"
        else:
            error = f"max-abs {internal.max_abs(item.values, encoded.values):.4g}"
        rows.append(
            _row(sequence, item, "tuckercodec", text, report.mode, report.bytes, error, seconds)
        )
    return rows


def peer_row(sequence: str, item: tuckercodec.Field, coder: str, bound: float) -> str:
    """SZ3's or zfp's row at ``bound`` on every value, laid out time fastest."""
    arranged = np.ascontiguousarray(item.values.transpose(2, 1, 0))
    start = time.perf_counter()
    if coder == "sz3":
        from pysz import sz, szConfig, szErrorBoundMode

        config = szConfig(arranged.shape)
        config.errorBoundMode = szErrorBoundMode.ABS
        config.absErrorBound = bound
        payload, _ = sz.compress(arranged, config)
        data = payload.tobytes()
        back, _ = sz.decompress(np.frombuffer(data, dtype=np.uint8), arranged.dtype, arranged.shape)
    else:
        import zfpy

        data = zfpy.compress_numpy(arranged, tolerance=bound)
        back = zfpy.decompress_numpy(data)
    seconds = time.perf_counter() - start
    worst = float(
        np.abs(
            np.asarray(back, dtype=np.float64).reshape(arranged.shape) - arranged.astype(np.float64)
        ).max()
    )
    mark = "" if worst <= bound else " (over the bound)"
    return _row(
        sequence,
        item,
        coder,
        f"max:{bound:.6g}",
        "abs",
        len(data),
        f"max-abs {worst:.4g}{mark}",
        seconds,
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p) for p in args.sequences] or [
        common.SHARED_DATA / name for name in DEFAULT_SEQUENCES
    ]
    coders = [c.strip() for c in args.coders.split(",") if c.strip()]
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print(
        "bpv: bits per value; seconds: encode (tuckercodec, with its checking decodes) or "
        "encode and decode (peers)"
    )
    print("| sequence | field | coder | target | mode | bytes | bpv | error measured | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        if not path.exists():
            print(f"| {path.name} | absent | | | | | | | |")
            continue
        items, mesh = fields_of(path, args.frames)
        for item in items:
            bound = BOUND_OF_RANGE * float(item.values.max() - item.values.min())
            if "tuckercodec" in coders:
                for row in tucker_rows(path.stem, item, mesh, bound):
                    print(row, flush=True)
            for coder in ("sz3", "zfp"):
                if coder in coders:
                    print(peer_row(path.stem, item, coder, bound), flush=True)
    return 0
