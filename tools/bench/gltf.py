"""Benchmark of the glTF output (default: chicken at KG 0.1) and of reading a .glb sequence.

1. Encodes the sequence at ``--kg`` and writes its decomposition as a glTF morph animation in
   each variant (none, quantize, meshopt): the .tkc's size and KG error; each .glb's size, the
   KG error a viewer shows (the morph formula evaluated from the written file at every frame's
   time) against the .tkc decode and against the original, and, where node and tests/js's
   packages are installed, the largest difference between three.js's GLTFLoader and that
   evaluation at every keyframe. Target: viewer KG against the original at most 1.05 x --kg.
   A peer in the same table: gltfpack (npm package ``gltfpack``, pinned below, installed by
   this tool with npm into ~/.cache/tuckercodec, skipped with a message where node or npm is
   missing or ``--no-gltfpack`` is given) run on the float32 ("none") file with its usual
   settings: ``-cc`` (14-bit positions, weights as normalized 8-bit, animations resampled at
   30 Hz), ``-cc -af 0`` (the keyframes kept) and ``-cc -vp 16 -af 0`` (16-bit positions).
   gltfpack reorders vertices and merges coincident ones, so each vertex of the sequence is
   matched to the gltfpack vertex with the nearest trajectory before the KG is taken.
2. Converts ``--read`` (default horse gallop) to a .glb morph animation and times
   ``load_sequence`` on it (median of ``--repeat``, after a warm-up). Target: 1.0 s.

Every KG figure uses the Karni-Gotsman definition (printed). Prints Markdown.

    python -m tools.bench gltf                         # chicken, horse gallop
    python -m tools.bench gltf sample --read sample
    python -m tools.bench gltf samba.npz --no-gltfpack
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from tools import common
from tools.bench import arguments
from tuckercodec import Decoder, MeshSequence, encode, kg_error, load_sequence, save_sequence
from tuckercodec.internal import (
    DEFAULT_TARGET_KG,
    KG_DEFINITION,
    sample_gltf,
    write_decomposition_gltf,
)

JS = common.REPO / "tests" / "js"
VARIANTS = ("none", "quantize", "meshopt")
READ_TARGET_SECONDS = 1.0
GLTFPACK_VERSION = "1.3.0"
GLTFPACK_RUNS = (("-cc",), ("-cc", "-af", "0"), ("-cc", "-vp", "16", "-af", "0"))
NPM_TIMEOUT = 600.0


def gltfpack_command() -> tuple[list[str] | None, str]:
    """(node and gltfpack's cli.js, "") with gltfpack installed by npm into the user's cache
    (once), or (None, why not)."""
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        return None, "node and npm are needed (not found on PATH)"
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder = cache / "tuckercodec" / f"gltfpack-{GLTFPACK_VERSION}"
    cli = folder / "node_modules" / "gltfpack" / "cli.js"
    if not cli.exists():
        folder.mkdir(parents=True, exist_ok=True)
        package = f"gltfpack@{GLTFPACK_VERSION}"
        quiet = ("--no-audit", "--no-fund", "--loglevel=error")
        try:
            done = subprocess.run(
                [npm, "install", "--prefix", str(folder), package, *quiet],
                capture_output=True,
                text=True,
                timeout=NPM_TIMEOUT,
            )
        except (OSError, subprocess.TimeoutExpired) as error:
            return None, f"npm install gltfpack@{GLTFPACK_VERSION} failed: {error}"
        if done.returncode != 0 or not cli.exists():
            said = (done.stderr or done.stdout).strip().splitlines()[:2]
            return None, f"npm install gltfpack@{GLTFPACK_VERSION} failed: {' | '.join(said)}"
    return [node, str(cli)], ""


def matched(ours: np.ndarray, theirs: np.ndarray, frames: int = 16) -> np.ndarray:
    """``theirs`` (F, K', 3) with its vertices matched to ``ours`` (F, K, 3): for each of our
    vertices the one whose trajectory (over ``frames`` frames spread over the sequence) is
    nearest, for files whose writer reordered or merged vertices."""
    picked = np.linspace(0, len(ours) - 1, min(frames, len(ours))).astype(int)
    a = ours[picked].transpose(1, 0, 2).reshape(ours.shape[1], -1)
    b = theirs[picked].transpose(1, 0, 2).reshape(theirs.shape[1], -1)
    nearest = np.empty(len(a), dtype=np.int64)
    squared = np.einsum("vi,vi->v", b, b)
    for start in range(0, len(a), 1024):
        distances = squared[None, :] - 2 * a[start : start + 1024] @ b.T
        nearest[start : start + 1024] = distances.argmin(axis=1)
    return theirs[:, nearest]


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


def bench_variants(source: str, target_kg: float, folder: Path, peer: bool) -> None:
    """Part 1: the decomposition's glTF variants, and gltfpack on the float32 one."""
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
    times = None
    for variant in VARIANTS:
        path = folder / f"{variant}.glb"
        seconds = common.timed(
            lambda v=variant, p=path: write_decomposition_gltf(  # type: ignore[misc]
                decoder, p, compress=v, overwrite=True
            ),
            1,
            warmup=0,
        )[0]
        write_decomposition_gltf(
            decoder,
            path,
            compress=variant,  # type: ignore[arg-type]
            overwrite=True,
        )
        times = sample_gltf(path).times
        _row(variant, path, times, decoded, sequence, tkc, seconds)
    assert times is not None
    if not peer:
        print("\ngltfpack: not run (--no-gltfpack)")
    else:
        command, missing = gltfpack_command()
        if command is None:
            print(f"\ngltfpack: skipped, {missing}")
        for options in GLTFPACK_RUNS if command else ():
            assert command is not None
            path = folder / f"gltfpack{''.join(options)}.glb"
            run = [*command, "-i", str(folder / "none.glb"), "-o", str(path), *options]
            seconds = common.timed(
                lambda r=run: subprocess.run(r, capture_output=True, check=True),  # type: ignore[misc]
                1,
                warmup=0,
            )[0]
            _row(f"gltfpack {' '.join(options)}", path, times, decoded, sequence, tkc, seconds)
    print()
    print(f"KG: {KG_DEFINITION}")


def _row(
    name: str,
    path: Path,
    times: np.ndarray,
    decoded: np.ndarray,
    sequence: MeshSequence,
    tkc: Path,
    seconds: float,
) -> None:
    """One line of the table: the file evaluated at the sequence's keyframe times."""
    ours = sample_gltf(path, times).positions
    shown = three_positions(path, times)
    agreement = "not run" if shown is None else f"{np.abs(shown - ours).max():.2e}"
    if ours.shape != decoded.shape or name.startswith("gltfpack"):
        ours = matched(decoded, ours)
    size = path.stat().st_size
    print(
        f"| {name} | {size} | {size / tkc.stat().st_size:.1f} | {kg_error(decoded, ours):.5f} "
        f"| {kg_error(sequence, ours):.5f} | {agreement} | {seconds:.2f} |"
    )


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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The glTF suite's options."""
    arguments.sequence(parser, "chicken.npz", "chicken.npz of ../shared/data")
    parser.add_argument(
        "--kg",
        type=float,
        default=DEFAULT_TARGET_KG,
        help="target KG of the .tkc (default: the encoder's)",
    )
    parser.add_argument("--read", default="horse-gallop", help="sequence to read back as .glb")
    arguments.repeat(parser, 5, "timed reads, the median reported")
    parser.add_argument(
        "--no-gltfpack", dest="gltfpack", action="store_false", help="leave out the gltfpack peer"
    )


def run(args: argparse.Namespace) -> int:
    """Measure and print; the exit status."""
    print(f"machine: {common.machine()}")
    print(f"command: {args.command}")
    print()
    with tempfile.TemporaryDirectory(prefix="bench-gltf-") as scratch:
        bench_variants(args.sequence, args.kg, Path(scratch), args.gltfpack)
        bench_read(args.read, args.repeat, Path(scratch))
    return 0
