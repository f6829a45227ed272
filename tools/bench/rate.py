"""Whole-file sizes against two baselines in one run: the reference revision of the rate work and
the previous commit, on the shared sequences and on generated ones the encoder was never tuned on.

Each point is a sequence at a KG target (``--targets``, default 1 0.1 0.02), encoded by this
checkout and by the package at each ``--baselines`` revision (``git archive`` into a temporary
folder, run in a child Python: :func:`tools.bench.size.baseline_sizes`). Sizes are whole files
(everything: preamble, header, connectivity, names); encodes are deterministic on one machine,
so one run per point is the figure. The decoded KG (Karni-Gotsman, per-frame centroid, percent)
of this checkout's file is measured against the original.

``--generated`` adds sequences made by :mod:`tools.generate.sequence` (a skinned body and a
flag in the wind, at sizes like the held-out files of the rate issue, two of them with a rough
jitter per vertex), written once into
``~/.cache/tuckercodec-bench/generated/``. ``--scrambled`` adds each of them again with its
vertices renumbered at random and its faces shuffled (a fixed seed), as a remesher or an
exporter leaves a simulation's mesh: the walk of §6.8 then follows nothing of the vertex order.

Printed: a table of every point (bytes and bpfv per revision, the ratios, the decoded KG), the
median ratio per target against the first baseline, the largest ratio against each baseline,
and the connectivity (FACE) in bits per vertex.

``--speed`` measures the decoder instead, on each sequence's KG 0.1 file: the file as written
(its position factors through the adaptive coder of §6.14) against its twin with the same
integers in zstd frames (§6.1), both decoded by this checkout in one process, alternately,
``--repeat`` times after a warm-up (medians): ``Decoder(data)`` + ``frame(0)``, and
``positions()``. The twin isolates the coder: everything else is the same file.

    python -m tools.bench rate --generated
    python -m tools.bench rate --generated --scrambled --targets 1 0.1 --baselines c798db5
    python -m tools.bench rate ../shared/data/chicken.npz --targets 0.1 --baselines 338ced4
    python -m tools.bench rate --speed --repeat 7
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from tools import common
from tools.bench import arguments
from tools.bench.size import baseline_sizes
from tools.generate.vectors import scrambled
from tuckercodec import Decoder, bpfv, encode, info, internal, kg_error

DEFAULT_TARGETS = [1.0, 0.1, 0.02]
#: The revision the rate issue measures against, and the commit before this work.
DEFAULT_BASELINES = ["338ced4", "0be6db9"]
GENERATED_FOLDER = Path("~/.cache/tuckercodec-bench/generated").expanduser()
#: (kind, vertices, frames, seed, noise): shapes like the held-out files of the rate issue, and
#: two with each vertex's own jitter at 2e-3 of the model (rough, high-rank motion).
GENERATED = [
    ("body", 7061, 201, 3, 1e-4),
    ("cloth", 2904, 204, 4, 1e-4),
    ("body", 10002, 150, 1, 1e-4),
    ("cloth", 10002, 175, 2, 1e-4),
    ("body", 10002, 150, 5, 2e-3),
    ("cloth", 10002, 175, 6, 2e-3),
]


def generated_sequences() -> list[Path]:
    """The generated sequences, made the first time they are asked for."""
    GENERATED_FOLDER.mkdir(parents=True, exist_ok=True)
    out = []
    for kind, vertices, frames, seed, noise in GENERATED:
        rough = "" if noise == 1e-4 else f"-noise{noise:g}"
        path = GENERATED_FOLDER / f"{kind}-{vertices}x{frames}-seed{seed}{rough}.npz"
        if not path.exists():
            print(f"generating {path.name}...", flush=True)
            subprocess.run(
                [
                    *(sys.executable, "-m", "tools.generate.sequence", "--kind", kind),
                    *("--vertices", str(vertices), "--frames", str(frames)),
                    *("--seed", str(seed), "--noise", str(noise), "-o", str(path)),
                ],
                check=True,
                cwd=common.REPO,
                capture_output=True,
            )
        out.append(path)
    return out


def scrambled_sequences(paths: list[Path]) -> list[Path]:
    """Each of ``paths`` (generated ``.npz``) with its vertices renumbered and its faces
    shuffled, written beside it the first time it is asked for."""
    out = []
    for path in paths:
        target = path.with_name(f"{path.stem}-scrambled.npz")
        if not target.exists():
            print(f"scrambling {path.name}...", flush=True)
            with np.load(path) as stored:
                dtype, face_type = stored["V"].dtype, stored["F"].dtype
            mixed = scrambled(common.load(path), seed=11)
            np.savez(target, V=mixed.vertices.astype(dtype), F=mixed.faces.astype(face_type))
        out.append(target)
    return out


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The rate suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument("--targets", type=float, nargs="+", default=DEFAULT_TARGETS)
    parser.add_argument("--baselines", nargs="+", default=DEFAULT_BASELINES, help="git revisions")
    parser.add_argument(
        "--generated", action="store_true", help="add generated sequences (body, cloth)"
    )
    parser.add_argument(
        "--scrambled",
        action="store_true",
        help="with --generated, each generated sequence again with a random vertex order",
    )
    parser.add_argument(
        "--speed", action="store_true", help="decode speed: adaptive against zstd frames"
    )
    arguments.repeat(parser, 5)


def zstd_twin(data: bytes) -> bytes:
    """``data`` with every adaptively coded position factor's integers in a zstd frame instead
    (a FACE whose streams are adaptive, §6.8, stays as it is: the twin isolates the factors')."""
    container = internal.parse_container(data)
    entries: list[dict[str, Any]] = []
    payloads: list[bytes] = []
    for section in container.sections:
        entry = dict(container.header["sections"][len(entries)])
        payload = bytes(container.payload(data, section))
        if entry.get("coder") == internal.adaptive.CODER_ADAPTIVE and entry["codec"] == "qmat":
            rows, cols = entry["shape"]
            stem = str(entry["id"]).split(".")[0]
            mesh = None
            if stem == "U1":
                decoder = Decoder(data)
                mesh = internal.mesh_prediction(decoder._coded_faces, decoder.info.vertices)
            order = internal.qmat.coding_order(mesh, rows)
            columns = internal.adaptive.decode_columns(payload, cols, rows, order, stem)
            payload, entry["planes"] = internal.streams.pack_integers(columns.reshape(-1))
            del entry["coder"]
        for key in ("offset", "length", "crc32"):
            entry.pop(key)
        entries.append(entry)
        payloads.append(payload)
    header = {k: v for k, v in container.header.items() if k != "sections"}
    flags = container.flags
    if not internal.adaptive.uses_adaptive(entries):  # else kept for FACE's coder or the pushes
        flags &= ~internal.adaptive.ADAPTIVE
    return internal.pack_container(
        header, list(zip(entries, payloads, strict=True)), flags=flags, minor=container.minor
    )


def _median_seconds(calls: list[Callable[[], object]], repeat: int) -> list[float]:
    """Each call's median seconds over ``repeat`` rounds after a warm-up, the calls alternating."""
    times: list[list[float]] = [[] for _ in calls]
    for round_number in range(repeat + 1):
        for n, call in enumerate(calls):
            start = time.perf_counter()
            call()
            if round_number:
                times[n].append(time.perf_counter() - start)
    return [statistics.median(t) for t in times]


def _first_frame(data: bytes) -> object:
    return Decoder(data).frame(0)


def _all_frames(data: bytes) -> object:
    return Decoder(data).positions()


def speed(paths: list[Path], repeat: int) -> int:
    """The decoder on each file and its zstd twin; the exit status."""
    print(
        "| sequence | bytes adaptive / zstd | open + frame 0: zstd ms | adaptive ms "
        "| zstd/adaptive | all frames: zstd ms | adaptive ms | zstd/adaptive | same positions |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        data = encode(common.load(path), target_kg=0.1)
        twin = zstd_twin(data)
        same = np.array_equal(Decoder(data).positions(), Decoder(twin).positions())
        files = (twin, data)
        first = _median_seconds([partial(_first_frame, f) for f in files], repeat)
        every = _median_seconds([partial(_all_frames, f) for f in files], repeat)
        print(
            f"| {path.name} | {len(data)} / {len(twin)} | {1e3 * first[0]:.1f} | "
            f"{1e3 * first[1]:.1f} | {first[0] / first[1]:.2f} | {1e3 * every[0]:.1f} | "
            f"{1e3 * every[1]:.1f} | {every[0] / every[1]:.2f} | {'yes' if same else 'NO'} |",
            flush=True,
        )
        if not same:
            return 1
    return 0


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p).resolve() for p in args.sequences] or [
        common.SHARED_DATA / name for name in common.shared_sequences()
    ]
    if args.generated:
        generated = generated_sequences()
        paths += generated + (scrambled_sequences(generated) if args.scrambled else [])
    if not paths:
        print(f"no sequences: {common.SHARED_DATA} is absent", file=sys.stderr)
        return 1
    if args.speed:
        return speed(paths, args.repeat)
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
