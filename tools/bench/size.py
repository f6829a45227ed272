"""File sizes now against a baseline revision of the package, side by side in one run.

For each sequence (default: every one of ../shared/data present) and each KG target
(``--targets``, default 2 1 0.5 0.1 0.05 0.02), the file is encoded by this checkout and by the
package as it was at ``--baseline`` (a git revision, default the last commit before the work on
smaller files), extracted with ``git archive`` into a temporary folder and run in a child
Python whose ``PYTHONPATH`` puts it first. Both encode the same sequence with
``encode(seq, target_kg=t)``. Sizes are whole files (preamble, header, connectivity, names:
everything); encodes are deterministic on one machine, so one run per point is the figure.

Printed per point: both sizes in bytes and bpfv, the change, the connectivity (section FACE) in
bits per vertex before and after, the decoded KG error of the new file measured here with
``kg_error`` (Karni-Gotsman, per-frame centroid, in percent) against the target, and the new
file's format version. Then the absolute targets.

    python -m tools.bench size
    python -m tools.bench size ../shared/data/chicken.npz --targets 0.1
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path
from typing import Any

from tools import common
from tools.bench import arguments
from tuckercodec import Decoder, bpfv, encode, info, internal, kg_error

DEFAULT_TARGETS = [2.0, 1.0, 0.5, 0.1, 0.05, 0.02]
#: The last commit before the work on smaller files: format 1.1, faces-delta, mesh-parent
#: prediction.
DEFAULT_BASELINE = "c4b76d8"
#: The absolute targets of the work on smaller files: (sequence stem, KG target) -> largest
#: whole-file bpfv.
ABSOLUTE_TARGETS = {
    ("cloth-vellum", 1.0): 0.75,
    ("horse-gallop", 1.0): 0.85,
    ("chicken", 0.1): 1.15,
    ("samba", 0.1): 2.6,
}
#: Target: connectivity of at most this many bits per vertex, vertex order kept.
CONNECTIVITY_BITS_PER_VERTEX = 12.0
#: Target: at least this much smaller than the baseline at every target.
LEAST_GAIN = 0.10

_CHILD = """
import json, sys
import tuckercodec as tc
jobs = json.loads(sys.argv[1])
out = {}
for path, targets in jobs:
    sequence = tc.load_sequence(path)
    for target in targets:
        data = tc.encode(sequence, target_kg=target)
        sections = {s[0]: s[1] for s in tc.info(data).sections}
        out[f"{path}|{target}"] = {"bytes": len(data), "sections": sections}
print(json.dumps(out))
"""


def baseline_sizes(revision: str, jobs: list[tuple[str, list[float]]]) -> dict[str, dict[str, Any]]:
    """``"path|target" -> {"bytes", "sections"}`` from the package at ``revision``."""
    archive = subprocess.run(
        ["git", "-C", str(common.REPO), "archive", revision, "tuckercodec"],
        check=True,
        capture_output=True,
    ).stdout
    with tempfile.TemporaryDirectory(prefix="tuckercodec-baseline-") as folder:
        with tarfile.open(fileobj=BytesIO(archive)) as tar:
            tar.extractall(folder, filter="data")
        environment = common.package_environment(folder)
        result = subprocess.run(
            [sys.executable, "-c", _CHILD, json.dumps(jobs)],
            check=True,
            capture_output=True,
            text=True,
            env=environment,
            cwd=folder,  # not the checkout: its tuckercodec must not shadow the baseline's
        )
    sizes: dict[str, dict[str, Any]] = json.loads(result.stdout)
    return sizes


def face_row(path: Path) -> str:
    """One table row: the FACE section of ``path`` encoded at KG 1, in bits per vertex, whole
    and per stream of faces-traverse (§6.8)."""
    sequence = common.load(path)
    data = encode(sequence, target_kg=1.0)
    container = internal.parse_container(data)
    entry = container.section("FACE")
    assert entry is not None
    per_vertex = 8.0 / sequence.vertex_count
    cells = [f"{entry.length * per_vertex:.1f}"]
    if entry.codec == internal.sections.FACES_TRAVERSE:
        cells += [f"{length * per_vertex:.1f}" for _, _, length in entry.params["streams"]]
    else:
        cells += ["-"] * 4
    return f"| {path.name} | {entry.codec} | " + " | ".join(cells) + " |"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The size suite's options."""
    arguments.sequences(parser, "every sequence of ../shared/data")
    parser.add_argument("--targets", type=float, nargs="+", default=DEFAULT_TARGETS)
    parser.add_argument("--baseline", default=DEFAULT_BASELINE, help="a git revision")


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    paths = [Path(p).resolve() for p in args.sequences] or [
        common.SHARED_DATA / name for name in common.shared_sequences()
    ]
    if not paths:
        print(f"no sequences: {common.SHARED_DATA} is absent", file=sys.stderr)
        return 1
    jobs = [(str(path), list(args.targets)) for path in paths]
    print(f"baseline {args.baseline}: encoding {len(paths)} sequences in a child process...")
    before = baseline_sizes(args.baseline, jobs)
    print(
        "| sequence | target KG | baseline bytes (bpfv) | now bytes (bpfv) | change | "
        "FACE bits/vertex before -> now | decoded KG now | <= target | format |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    missed_gain, missed_absolute, face_bits = [], [], {}
    for path in paths:
        sequence = common.load(path)
        frames, vertices = sequence.frame_count, sequence.vertex_count
        for target in args.targets:
            data = encode(sequence, target_kg=target)
            old = before[f"{path}|{target}"]
            now_sections = {s[0]: s[1] for s in info(data).sections}
            measured = kg_error(sequence.vertices, Decoder(data).positions())
            change = len(data) / old["bytes"] - 1.0
            face_old = 8 * old["sections"]["FACE"] / vertices
            face_now = 8 * now_sections["FACE"] / vertices
            face_bits[path.stem] = face_now
            if change > -LEAST_GAIN:
                missed_gain.append(f"{path.stem} KG {target:g}: {change:+.1%}")
            limit = ABSOLUTE_TARGETS.get((path.stem, target))
            now_bpfv = bpfv(len(data), frames, vertices)
            if limit is not None and now_bpfv > limit:
                missed_absolute.append(f"{path.stem} KG {target:g}: {now_bpfv:.3f} > {limit}")
            print(
                f"| {path.name} | {target:g} | {old['bytes']} "
                f"({bpfv(old['bytes'], frames, vertices):.3f}) | {len(data)} ({now_bpfv:.3f}) | "
                f"{change:+.1%} | {face_old:.1f} -> {face_now:.1f} | {measured:.4f} | "
                f"{'ok' if measured <= target else 'FAIL'} | {info(data).format_version} |"
            )
    print()
    print("Connectivity (section FACE of the last file of each sequence), bits per vertex:")
    print("| sequence | codec | total | ops (gates, tips, rotations) | degrees | order map | far |")
    print("|---|---|---|---|---|---|---|")
    for path in paths:
        print(face_row(path))
    print()
    for (stem, target), limit in ABSOLUTE_TARGETS.items():
        print(f"target: {stem} at KG {target:g} at most {limit} bpfv")
    print(f"missed absolute targets: {missed_absolute or 'none'}")
    print(f"points less than {LEAST_GAIN:.0%} smaller than the baseline: {missed_gain or 'none'}")
    over = {s: round(b, 1) for s, b in face_bits.items() if b > CONNECTIVITY_BITS_PER_VERTEX}
    print(f"connectivity above {CONNECTIVITY_BITS_PER_VERTEX:g} bits per vertex: {over or 'none'}")
    return 0
