"""Whole-file sizes against two baselines in one run: the reference revision of the rate work and
the previous commit, on the shared sequences and on generated ones the encoder was never tuned on.

Each point is a sequence at a KG target (``--targets``, default 1 0.1 0.02), encoded by this
checkout and by the package at each ``--baselines`` revision (``git archive`` into a temporary
folder, run in a child Python: :func:`tools.bench.size.baseline_sizes`). Sizes are whole files
(everything: preamble, header, connectivity, names); encodes are deterministic on one machine,
so one run per point is the figure. The decoded KG (Karni-Gotsman, per-frame centroid, percent)
of this checkout's file is measured against the original.

``--generated`` adds sequences made by :mod:`tools.generate.sequence` (a skinned body and a
flag in the wind, at sizes like the held-out files of the rate issue), written once into
``~/.cache/tuckercodec-bench/generated/``.

Printed: a table of every point (bytes and bpfv per revision, the ratios, the decoded KG), the
median ratio per target against the first baseline, the largest ratio against each baseline,
and the connectivity (FACE) in bits per vertex.

    python -m tools.bench rate --generated
    python -m tools.bench rate ../shared/data/chicken.npz --targets 0.1 --baselines 338ced4
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
from pathlib import Path

from tools import common
from tools.bench import arguments
from tools.bench.size import baseline_sizes
from tuckercodec import Decoder, bpfv, encode, info, kg_error

DEFAULT_TARGETS = [1.0, 0.1, 0.02]
#: The revision the rate issue measures against, and the commit before this work.
DEFAULT_BASELINES = ["338ced4", "0be6db9"]
GENERATED_FOLDER = Path("~/.cache/tuckercodec-bench/generated").expanduser()
#: (kind, vertices, frames, seed): shapes like the held-out files of the rate issue.
GENERATED = [
    ("body", 7061, 201, 3),
    ("cloth", 2904, 204, 4),
    ("body", 10002, 150, 1),
    ("cloth", 10002, 175, 2),
]


def generated_sequences() -> list[Path]:
    """The generated sequences, made the first time they are asked for."""
    GENERATED_FOLDER.mkdir(parents=True, exist_ok=True)
    out = []
    for kind, vertices, frames, seed in GENERATED:
        path = GENERATED_FOLDER / f"{kind}-{vertices}x{frames}-seed{seed}.npz"
        if not path.exists():
            print(f"generating {path.name}...", flush=True)
            subprocess.run(
                [
                    *(sys.executable, "-m", "tools.generate.sequence", "--kind", kind),
                    *("--vertices", str(vertices), "--frames", str(frames)),
                    *("--seed", str(seed), "-o", str(path)),
                ],
                check=True,
                cwd=common.REPO,
                capture_output=True,
            )
        out.append(path)
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The rate suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument("--targets", type=float, nargs="+", default=DEFAULT_TARGETS)
    parser.add_argument("--baselines", nargs="+", default=DEFAULT_BASELINES, help="git revisions")
    parser.add_argument(
        "--generated", action="store_true", help="add generated sequences (body, cloth)"
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p).resolve() for p in args.sequences] or [
        common.SHARED_DATA / name for name in common.shared_sequences()
    ]
    if args.generated:
        paths += generated_sequences()
    if not paths:
        print(f"no sequences: {common.SHARED_DATA} is absent", file=sys.stderr)
        return 1
    jobs = [(str(path), list(args.targets)) for path in paths]
    before = {}
    for revision in args.baselines:
        print(f"baseline {revision}: encoding {len(paths)} sequences in a child process...")
        before[revision] = baseline_sizes(revision, jobs)
    heads = " | ".join(f"{r} bytes (bpfv) | now / {r}" for r in args.baselines)
    print(f"| sequence | K x F | target KG | now bytes (bpfv) | {heads} | decoded KG | FACE b/v |")
    print("|---|---|---|---|" + "---|---|" * len(args.baselines) + "---|---|")
    ratios: dict[str, dict[float, list[float]]] = {r: {} for r in args.baselines}
    faces: dict[str, float] = {}
    misses = []
    for path in paths:
        sequence = common.load(path)
        frames, vertices = sequence.frame_count, sequence.vertex_count
        for target in args.targets:
            data = encode(sequence, target_kg=target)
            measured = kg_error(sequence.vertices, Decoder(data).positions())
            if measured > target:
                misses.append(f"{path.name} KG {target:g}: decoded {measured:.5f}")
            face_bits = 8 * {s[0]: s[1] for s in info(data).sections}["FACE"] / vertices
            faces[path.name] = face_bits
            cells = []
            for revision in args.baselines:
                old = before[revision][f"{path}|{target}"]["bytes"]
                ratio = len(data) / old
                ratios[revision].setdefault(target, []).append(ratio)
                cells.append(f"{old} ({bpfv(old, frames, vertices):.3f}) | {ratio:.3f}")
            print(
                f"| {path.name} | {vertices} x {frames} | {target:g} | {len(data)} "
                f"({bpfv(len(data), frames, vertices):.3f}) | {' | '.join(cells)} | "
                f"{measured:.4f} | {face_bits:.1f} |",
                flush=True,
            )
    print()
    for revision in args.baselines:
        for target, values in ratios[revision].items():
            print(
                f"now / {revision} at KG {target:g}: median {statistics.median(values):.3f}, "
                f"largest {max(values):.3f} ({len(values)} sequences)"
            )
    print(f"connectivity, median bits per vertex: {statistics.median(faces.values()):.1f}")
    print(f"decoded KG above its target: {misses or 'none'}")
    return 0
