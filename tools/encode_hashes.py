"""The sha256 of encodes through the command line: to show that a change writes the same bytes.

A restructuring (code moved between modules) or a speed change must not move a byte of any
file. This encodes each sequence in each mode with ``python -m tuckercodec encode`` (one BLAS
thread, so that the sums are made in one order), prints and saves the digests as JSON, and with
``--compare`` says which differ from an earlier run's:

    python -m tools.encode_hashes --out /tmp/before.json           # on the old commit
    python -m tools.encode_hashes --out /tmp/after.json --compare /tmp/before.json

The sequences default to every one of ../shared/data present (chicken, samba, horse gallop's
OBJ folder, the cloth); ``sample`` names the built-in cloth. Two encodes run at a time.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

#: The modes of the restructuring's check, and the segmented ones beside them.
MODES: dict[str, list[str]] = {
    "kg0.1": ["--kg", "0.1"],
    "kg1": ["--kg", "1"],
    "bpfv1": ["--bpfv", "1"],
    "ranks20,10": ["--ranks", "20,10"],
    "bound0.5": ["--select", "bound", "--kg", "0.5"],
    "seg100": ["--segment-frames", "100"],
    "seg30kg1": ["--segment-frames", "30", "--kg", "1"],
    "seg30own": ["--segment-frames", "30", "--basis", "own", "--kg", "0.5"],
    "seg30bpfv": ["--segment-frames", "30", "--bpfv", "1"],
    "seg30ranks": ["--segment-frames", "30", "--ranks", "20,10"],
}
SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"
SEQUENCES = {
    "chicken": "chicken.npz",
    "samba": "samba.npz",
    "horse": "horse-gallop",
    "cloth": "cloth-vellum.npz",
}
ROOT = Path(__file__).resolve().parents[1]


def default_sequences() -> dict[str, str]:
    """The shared sequences present, by short name."""
    return {
        name: str(SHARED / file) for name, file in SEQUENCES.items() if (SHARED / file).exists()
    }


def encode_digest(source: str, mode: list[str]) -> str:
    """The sha256 of ``tuckercodec encode source mode``, or the error it ended with."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as folder:
        output = Path(folder) / "out.tkc"
        command = [sys.executable, "-m", "tuckercodec", "encode", source, "-o", str(output), *mode]
        done = subprocess.run(command, env=env, cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            return f"exit {done.returncode}: {done.stderr.strip().splitlines()[-1:]}"
        return hashlib.sha256(output.read_bytes()).hexdigest()


def digests(sequences: dict[str, str], modes: dict[str, list[str]]) -> dict[str, str]:
    """``sequence/mode`` to its digest, printed as each is known."""
    jobs = [(name, mode) for name in sequences for mode in modes]

    def run(job: tuple[str, str]) -> tuple[str, str]:
        name, mode = job
        return f"{name}/{mode}", encode_digest(sequences[name], modes[mode])

    out: dict[str, str] = {}
    with ThreadPoolExecutor(2) as pool:
        for key, digest in pool.map(run, jobs):
            print(f"{key:<20} {digest}", flush=True)
            out[key] = digest
    return out


def differences(before: dict[str, str], after: dict[str, str]) -> list[str]:
    """The keys whose digests differ, or that only one run has."""
    return sorted(key for key in before.keys() | after.keys() if before.get(key) != after.get(key))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m tools.encode_hashes", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "sequences", nargs="*", help="files or folders, or 'sample' (default: ../shared/data)"
    )
    parser.add_argument("--modes", nargs="+", choices=sorted(MODES), help="default: all")
    parser.add_argument("--out", type=Path, help="write the digests here as JSON")
    parser.add_argument("--compare", type=Path, help="an earlier run's JSON: exit 1 if any differ")
    args = parser.parse_args(argv)
    sequences = (
        {Path(s).stem if s != "sample" else s: s for s in args.sequences}
        if args.sequences
        else default_sequences()
    )
    if not sequences:
        parser.error(f"no sequence given and none in {SHARED}")
    modes = {name: MODES[name] for name in args.modes} if args.modes else MODES
    found = digests(sequences, modes)
    if args.out is not None:
        args.out.write_text(json.dumps(found, indent=1, sort_keys=True) + "\n")
    if args.compare is not None:
        changed = differences(json.loads(args.compare.read_text()), found)
        print(f"{len(found) - len(changed)} of {len(found)} the same; differ: {changed or 'none'}")
        return 1 if changed else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
