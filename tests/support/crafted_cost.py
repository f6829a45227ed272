"""What small crafted files cost the decoders within their limits: the Blender add-on's import
(Python ``Decoder`` with ``BLENDER_LIMITS``) and ``TKCLoader.parse`` (node, ``WEB_LIMITS``).

    python -m tests.support.crafted_cost build DIR  # writes the crafted .tkc files into DIR
    python -m tests.support.crafted_cost python FILE [default|blender]  # one import
    python -m tests.support.crafted_cost measure DIR  # each file, 3 runs a case, medians

Each file is built part by part (as ``tests/test_decoder_memory.chunked_file``): rank (1, 1)
factors that decode to zeros, corrections of zeros one frame a chunk, and a face table of one
triangle repeated; zstd shrinks all of it to a few KB whatever it decodes to. Every file is
accepted by the decoder it is built for, at that decoder's limits. A measurement is a process of
its own; its peak resident memory is Linux's VmHWM (reset at exec)."""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from tests.support.compressed import chunked_file

ROOT = Path(__file__).resolve().parents[2]
JS = ROOT / "tests" / "js"

#: name: (vertices, frames, faces, later frame decoded, U1's rank), at the limits of the decoder
#: they target
FILES = {
    # BLENDER_LIMITS: 8 Mi vertices, K x F = 2^28 positions, 16 Mi faces
    "blender-vertices": (1 << 23, 32, 1, 31, 1),
    "blender-both": (1 << 23, 32, 1 << 24, 31, 1),
    # WEB_LIMITS: 256 Ki vertices, 512 Ki faces, 4 Mi factor values (U1 of rank 15: with U3,
    # the core and the centroids, 16 is over)
    "web-vertices": (1 << 18, 128, 1, 127, 1),
    "web-both": (1 << 18, 128, 1 << 19, 127, 1),
    "web-factors": (1 << 18, 128, 1 << 19, 127, 15),
}


def crafted(vertices: int, frames: int, face_count: int, rank: int) -> bytes:
    """A format 1.3 file of ``vertices`` x ``frames`` zeros, of U1 rank ``rank``, and
    ``face_count`` faces (0, 1, 2), a correction chunk per frame (so that ``max_chunk_values``
    never applies)."""
    return chunked_file(
        vertices, frames, chunk_frames=1, face_count=face_count, level=19, rank=rank
    )


def peak_resident_mib() -> float:
    """This process's peak resident memory (VmHWM), MiB."""
    status = Path("/proc/self/status").read_text()
    line = next(row for row in status.splitlines() if row.startswith("VmHWM:"))
    return int(line.split()[1]) / 1024


def python_import(path: Path, limits_name: str) -> dict[str, object]:
    """What the add-on's import decodes (addon.py: ``Decoder(path, limits=BLENDER_LIMITS)``, its
    faces as the arrays ``_mesh_of`` gives Blender (``loop_arrays``), frame 0 as
    float32, then a later frame as ``show_frame`` does), without Blender itself."""
    from tuckercodec import Decoder
    from tuckercodec.blender.meshes import BLENDER_LIMITS, loop_arrays
    from tuckercodec.errors import InputError
    from tuckercodec.format.limits import DEFAULT_LIMITS

    limits = BLENDER_LIMITS if limits_name == "blender" else DEFAULT_LIMITS
    later = FILES[path.stem][3]
    began = time.perf_counter()
    result: dict[str, object] = {"accepted": True}
    try:
        decoder = Decoder(path, limits=limits)
        starts, _ = loop_arrays(decoder.faces)
        decoder.frame(0).astype(np.float32)
        result["attributes"] = len(decoder.attributes)
        decoder.frame(later).astype(np.float32)
        result["faces"] = int(starts.size)
    except InputError as error:
        result.update(accepted=False, message=str(error)[:160])
    result["seconds"] = time.perf_counter() - began
    result["maxRssMiB"] = peak_resident_mib()
    return result


def _run(command: list[str], cwd: Path) -> dict[str, object]:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        return {"accepted": False, "message": done.stderr.strip()[-200:]}
    return dict(json.loads(done.stdout.strip().splitlines()[-1]))


def node_parse(path: Path, limits_name: str) -> dict[str, object]:
    """TKCLoader.parse (WEB_LIMITS) or openTkc at the decoder's defaults, frame 0 (memory.mjs)."""
    job = path.with_suffix(f".{limits_name}.json")
    via = "loader" if limits_name == "web" else "decoder"
    job.write_text(json.dumps({"path": str(path), "via": via, "frames": "first"}))
    command = ["node", "--expose-gc", "--import", "./three_from_vendor.mjs", "memory.mjs", str(job)]
    return _run(command, JS)


def measure(folder: Path, runs: int = 3) -> None:
    """Prints a Markdown row per file and case: medians of ``runs`` processes."""
    print("| file | size | case | accepted | seconds | peak RSS MiB |")
    print("|---|---|---|---|---|---|")
    for name in FILES:
        path = folder / f"{name}.tkc"
        cases = ["blender"] if name.startswith("blender") else ["web"]
        for case in cases:
            results = []
            for _ in range(runs):
                if case == "web" or (case == "default" and name.startswith("web")):
                    results.append(node_parse(path, case))
                else:
                    module = [sys.executable, "-m", "tests.support.crafted_cost"]
                    command = [*module, "python", str(path), case]
                    results.append(_run(command, ROOT))
            seconds = statistics.median(float(str(r.get("seconds", "nan"))) for r in results)
            rss = statistics.median(float(str(r.get("maxRssMiB", "nan"))) for r in results)
            accepted = results[0]["accepted"] or results[0].get("message", "")
            size = path.stat().st_size
            print(f"| {name} | {size:,} B | {case} | {accepted} | {seconds:.2f} | {rss:.0f} |")


def main(arguments: list[str]) -> None:
    action, target = arguments[0], Path(arguments[1])
    if action == "build":
        target.mkdir(parents=True, exist_ok=True)
        for name, (vertices, frames, face_count, _, rank) in FILES.items():
            data = crafted(vertices, frames, face_count, rank)
            (target / f"{name}.tkc").write_bytes(data)
            print(f"{name}: {len(data):,} bytes")
    elif action == "python":
        print(json.dumps(python_import(target, arguments[2] if len(arguments) > 2 else "default")))
    else:
        measure(target)


if __name__ == "__main__":
    main(sys.argv[1:])
