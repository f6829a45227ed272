"""Benchmark of faces-traverse (spec §6.8) on fans: M triangles that all share one edge.

Issue 22: the reference encoder looks across a gate for the first unvisited face, in the input's
order, with the gate's edge; on an edge of very many faces a search that starts from the first
face each time was quadratic (5,000 faces took 1.1 s, 50,000 faces 115 s). For each M of
``--faces`` (default 5000 50000) and each fan (``same``: every face (0, 1, v); ``alternating``:
every other face turned over, (1, 0, v)), the tool prints the median of ``--repeat`` runs of

* the FACE encode (``traversal.encode_traversal``: the walk with the mesh known, then both
  corner orders packed at zstd level 19, a small share here);
* the decode (``traversal.decode_traversal``) of what it wrote.

Linear code takes about ten times as long for ten times the faces.

    python -m tools.bench faces
    python -m tools.bench faces --faces 5000 50000 --repeat 3
"""

from __future__ import annotations

import argparse

import numpy as np

from tools import common
from tools.bench import arguments
from tuckercodec.internal import traversal

DEFAULT_FACES = [5000, 50000]
FANS = ("same", "alternating")


def fan(count: int, kind: str) -> np.ndarray:
    """``count`` triangles (0, 1, v) on the edge 0-1, v = 2 ...; ``alternating`` turns every
    other one over to (1, 0, v)."""
    tips = np.arange(2, count + 2, dtype=np.int64)
    faces = np.stack([np.zeros_like(tips), np.ones_like(tips), tips], axis=1)
    if kind == "alternating":
        faces[1::2, :2] = faces[1::2, 1::-1]
    return faces


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The faces suite's options."""
    parser.add_argument(
        "--faces",
        type=arguments.positive_int,
        nargs="+",
        default=DEFAULT_FACES,
        help=f"the fans' sizes (default: {' '.join(map(str, DEFAULT_FACES))})",
    )
    arguments.repeat(parser, 1)


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print(f"times in seconds, median of {args.repeat} run(s) [min-max] after one warm-up")
    print("| fan | faces | encode s | decode s | payload bytes |")
    print("|---|---|---|---|---|")
    for count in args.faces:
        for kind in FANS:
            print(row(count, kind, args.repeat))
    return 0


def row(count: int, kind: str, repeat: int) -> str:
    """The table's row of one fan."""
    faces = fan(count, kind)
    k = count + 2
    params, payload, _ = traversal.encode_traversal(faces, k)  # the warm-up
    encode = common.timed(lambda: traversal.encode_traversal(faces, k), repeat, warmup=0)
    decode = common.timed(lambda: traversal.decode_traversal(payload, params, k, "FACE"), repeat)
    return (
        f"| {kind} | {count} | {common.spread(encode)} | {common.spread(decode)} | {len(payload)} |"
    )
