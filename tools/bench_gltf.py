"""Benchmark of the glTF output (default: chicken at KG 0.1) and of reading a .glb sequence.

1. Encodes the sequence at ``--kg`` and writes its decomposition as a glTF morph animation in
   each variant (none, quantize, meshopt): the .tkc's size and KG error; each .glb's size, the
   KG error a viewer shows (the morph formula evaluated from the written file at every frame's
   time) against the .tkc decode and against the original, and, where node and tests/js's
   packages are installed, the largest difference between three.js's GLTFLoader and that
   evaluation at every keyframe. Target: viewer KG against the original at most 1.05 x --kg.
2. Converts ``--read`` (default horse gallop) to a .glb morph animation and times
   ``load_sequence`` on it (median of ``--repeat``, after a warm-up). Target: 1.0 s.

Every KG figure uses the Karni-Gotsman definition (printed). Prints Markdown.

    python -m tools.bench_gltf                         # chicken, horse gallop
    python -m tools.bench_gltf sample --read sample
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from tools import common
from tuckercodec import Decoder, MeshSequence, encode, kg_error, load_sequence, save_sequence
from tuckercodec.internal import KG_DEFINITION, sample_gltf, write_decomposition_gltf

JS = common.REPO / "tests" / "js"
VARIANTS = ("none", "quantize", "meshopt")
READ_TARGET_SECONDS = 1.0


def three_positions(path: Path, times: np.ndarray) -> np.ndarray | None:
    """three.js's positions of the file's morphing mesh at ``times``, or None without node or
    tests/js's packages (``npm ci`` in tests/js installs them)."""
    node = shutil.which("node")
    if node is None or not (JS / "node_modules" / "three").is_dir():
        return None
    with tempfile.TemporaryDirectory() as scratch:
        out = Path(scratch) / "positions.bin"
        done = subprocess.run(
            [node, str(JS / "evaluate.mjs"), str(path), "--times", "-", "--out", str(out)],
            input=json.dumps([float(t) for t in times]),
            capture_output=True,
            text=True,
            cwd=JS,
            check=True,
        )
        summary = json.loads(done.stdout)
        mesh = next(m for m in summary["meshes"] if m["morphTargets"])
        count = mesh["vertexCount"]
        return np.frombuffer(
            out.read_bytes(), dtype="<f8", count=len(times) * count * 3, offset=mesh["offset"]
        ).reshape(len(times), count, 3)


def _load(source: str) -> MeshSequence:
    """A name of ../shared/data (chicken.npz, horse-gallop...), a path, or "sample"."""
    shared = common.SHARED_DATA / source
    return common.load(shared if shared.exists() else source)


def bench_variants(source: str, target_kg: float, folder: Path) -> None:
    """Part 1: the decomposition's glTF variants."""
    sequence = _load(source)
    tkc = folder / "sequence.tkc"
    tkc.write_bytes(encode(sequence, target_kg=target_kg))
    decoder = Decoder(str(tkc))
    decoded = decoder.positions()
    print(
        f"{source}: {sequence.frame_count} frames, {sequence.vertex_count} vertices; .tkc at "
        f"--kg {target_kg:g}: {tkc.stat().st_size} bytes, ranks {decoder.info.ranks}, KG "
        f"{kg_error(sequence, decoded):.5f}"
    )
    print()
    print(
        "| variant | .glb bytes | x .tkc | viewer KG vs decode | viewer KG vs original "
        "| three.js max abs diff | write s |"
    )
    print("|---|---|---|---|---|---|---|")
    for variant in VARIANTS:
        path = folder / f"{variant}.glb"
        seconds = common.timed(
            lambda v=variant, p=path: write_decomposition_gltf(  # type: ignore[misc]
                decoder, p, compress=v, overwrite=True
            ),
            1,
            warmup=0,
        )[0]
        report = write_decomposition_gltf(
            decoder,
            path,
            compress=variant,
            overwrite=True,
            reference=sequence,  # type: ignore[arg-type]
        )
        times = sample_gltf(path).times
        shown = three_positions(path, times)
        ours = sample_gltf(path, times).positions
        agreement = "not run" if shown is None else f"{np.abs(shown - ours).max():.2e}"
        print(
            f"| {variant} | {report.size} | {report.size / tkc.stat().st_size:.1f} | "
            f"{report.viewer_kg:.5f} | {report.viewer_kg_reference:.5f} | {agreement} | "
            f"{seconds:.2f} |"
        )
    print()
    print(f"KG: {KG_DEFINITION}")


def bench_read(source: str, repeat: int, folder: Path) -> None:
    """Part 2: reading a sequence converted to .glb."""
    sequence = _load(source)
    path = folder / "read.glb"
    save_sequence(sequence, path, overwrite=True)
    times = common.timed(lambda: load_sequence(path), repeat)
    median = statistics.median(times)
    verdict = "meets" if median <= READ_TARGET_SECONDS else "misses"
    print()
    print(
        f"reading {source} as .glb ({path.stat().st_size} bytes, {sequence.frame_count - 1} "
        f"morph targets): median {median:.3f} s of {repeat} (min {min(times):.3f}, max "
        f"{max(times):.3f}); {verdict} the {READ_TARGET_SECONDS:g} s target"
    )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print the result; returns the process exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.bench_gltf", description=__doc__.splitlines()[0]
    )
    parser.add_argument("source", nargs="?", default="chicken.npz", help="sequence to encode")
    parser.add_argument("--kg", type=float, default=0.1, help="target KG of the .tkc")
    parser.add_argument("--read", default="horse-gallop", help="sequence to read back as .glb")
    parser.add_argument("--repeat", type=int, default=5, help="timed reads (median reported)")
    args = parser.parse_args(argv)
    print(f"machine: {common.machine()}")
    print(f"command: {common.command('tools.bench_gltf', argv)}")
    print()
    with tempfile.TemporaryDirectory(prefix="bench-gltf-") as scratch:
        bench_variants(args.source, args.kg, Path(scratch))
        bench_read(args.read, args.repeat, Path(scratch))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
