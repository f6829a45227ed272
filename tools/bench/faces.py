"""Benchmark of faces-traverse (spec §6.8) on fans: M triangles that all share one edge.

Why fans: the reference encoder looks across a gate for the first unvisited face, in the input's
order, with the gate's edge; on an edge of very many faces a search that starts from the first
face each time was quadratic (5,000 faces took 1.1 s, 50,000 faces 115 s). For each M of
``--faces`` (default 5000 50000) and each fan (``same``: every face (0, 1, v); ``alternating``:
every other face turned over, (1, 0, v)), the tool prints the median of ``--repeat`` runs of

* the FACE encode (``traversal.encode_traversal``: the walk with the mesh known, then both
  corner orders packed at zstd level 19, a small share here);
* the decode (``traversal.decode_traversal``) of what it wrote.

Linear code takes about ten times as long for ten times the faces.

A third table times the decoder on a crafted section (:func:`closed_fan`) that reads the newest
entry of into(0) (§6.8's PREV) ``count`` times after ``count`` entries behind the oldest were
removed: the reference decoder's ordered dicts passed over every removed entry at each read,
quadratic (4 * 160,000 faces, a 5 KB section, took 56 s); its stacks pop them once.

    python -m tools.bench faces
    python -m tools.bench faces --faces 5000 50000 --repeat 3
"""

from __future__ import annotations

import argparse
from typing import Any

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
    print()
    print("| crafted section | faces | section bytes | decode s |")
    print("|---|---|---|---|")
    for count in args.faces:
        print(closed_fan_row(count, args.repeat))
    return 0


def closed_fan_row(count: int, repeat: int) -> str:
    """The crafted section's row of one size."""
    params, payload, k = closed_fan(count)
    decode = common.timed(lambda: traversal.decode_traversal(payload, params, k, "FACE"), repeat)
    return f"| closed fan | {4 * count} | {len(payload)} | {common.spread(decode)} |"


def closed_fan(count: int) -> tuple[dict[str, Any], bytes, int]:
    """``(params, payload, K)`` of a faces-traverse section of 4 * ``count`` seeds (every gate
    reads nothing or NONE) around the hub 0: ``count`` faces (0, y, 1) open 1 -> 0 as many times;
    ``count`` faces (0, x, u) open u -> 0 behind it and (0, u, x) close each again; then ``count``
    faces (y, 0, 1) read 1 as PREV of 0 (the newest edge into 0), each closing a copy of 1 -> 0."""
    y = range(2, 2 + count)
    x = range(2 + count, 2 + 2 * count)
    u = range(2 + 2 * count, 2 + 3 * count)
    faces = [(0, v, 1) for v in y] + list(zip([0] * count, x, u, strict=True))
    faces += list(zip([0] * count, u, x, strict=True)) + [(v, 0, 1) for v in y]
    k = 2 + 3 * count
    open_edges: dict[int, int] = {}
    gates: list[int] = []
    seen: set[int] = set()
    ops: list[int] = []
    news: list[int] = []
    references: list[int] = []
    last = -1
    for number, face in enumerate(faces):
        while gates:  # an open gate reads NONE, a closed one nothing
            if open_edges.get(gates.pop()):
                ops.append(traversal.GATE_NONE)
        previous = 0
        for j, w in enumerate(face):
            if w not in seen:
                seen.add(w)
                ops.append(traversal.TIP_NEW)
                news.append(w - last - 1)
                last = w
            elif j == 2 and number >= 3 * count:
                ops.append(traversal.TIP_PREV)
            else:
                ops.append(traversal.TIP_FAR)
                references.append(w - previous)
            previous = w
        for a, b in zip(face, face[1:] + face[:1], strict=True):
            if open_edges.get(b * k + a):
                open_edges[b * k + a] -= 1
            else:
                open_edges[a * k + b] = open_edges.get(a * k + b, 0) + 1
            gates.append(a * k + b)
    params, payload = traversal.pack_streams([ops, [], news, references], len(faces), 3, 0, 19)
    return params, payload, k


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
