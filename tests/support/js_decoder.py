"""Runs the JavaScript decoder (tuckercodec/web/tkc/) in node, for the tests that compare it with
the Python decoder, and judges what it makes of the conformance vectors (in node or in a browser:
tests/js/conformance_observe.mjs). Test modules import it as
``from tests.support.js_decoder import run_node``; a test that calls it where node (18 or newer)
is missing is skipped, naming what is missing. The decoder needs no npm package (its two
dependencies are vendored), so nothing is installed.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

JS = Path(__file__).resolve().parents[1] / "js"
VECTORS = Path(__file__).resolve().parents[2] / "spec" / "vectors"
#: every vector's JSON (spec/FORMAT.md §12), by file name
EXPECTED = {p.name: json.loads(p.read_text()) for p in sorted(VECTORS.glob("*.json"))}
VALID = [name for name, e in EXPECTED.items() if e["valid"]]
INVALID = [name for name, e in EXPECTED.items() if not e["valid"]]
MIN_NODE = 18
RUN_TIMEOUT = 300.0


def node() -> str:
    """node's path, or skip the test saying what is missing."""
    path = shutil.which("node")
    if path is None:
        pytest.skip("node not found on PATH: the JavaScript decoder's tests run it")
    try:
        version = subprocess.run(
            [path, "--version"], capture_output=True, text=True, timeout=30, check=True
        ).stdout.strip()
        major = int(version.lstrip("v").split(".")[0])
    except (OSError, subprocess.SubprocessError, ValueError):
        major = 0
    if major < MIN_NODE:
        pytest.skip(f"node {MIN_NODE} or newer is needed (found {path}, {major or '?'})")
    return path


def run_node(script: str, *args: str | Path) -> Any:
    """Runs ``tests/js/<script>`` with ``args`` and returns the JSON it prints."""
    done = subprocess.run(
        [node(), str(JS / script), *map(str, args)],
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
        check=False,
    )
    assert done.returncode == 0, f"node {script} failed:\n{done.stderr[-3000:]}"
    return json.loads(done.stdout)


def decoded_file(
    data: bytes, tmp_path: Path, name: str
) -> tuple[dict[str, Any], np.ndarray, np.ndarray]:
    """What the JavaScript decoder gives of the whole file ``data`` (decode_file.mjs): its
    facts, the faces (M, n) int32 and every frame (F, K, 3) float64."""
    source, output = tmp_path / f"{name}.tkc", tmp_path / f"{name}.bin"
    source.write_bytes(data)
    facts = run_node("decode_file.mjs", source, output)
    assert facts["accepted"], facts["message"]
    raw = output.read_bytes()
    face_bytes = facts["faces"] * facts["face_width"] * 4
    faces = np.frombuffer(raw[:face_bytes], "<i4").reshape(facts["faces"], facts["face_width"])
    frames = np.frombuffer(raw[face_bytes:], "<f8").reshape(facts["frames"], facts["vertices"], 3)
    return facts, faces, frames


def decoded_frames(data: bytes, tmp_path: Path, name: str) -> np.ndarray:
    """Every frame the JavaScript decoder gives of the file ``data``, (F, K, 3) float64."""
    return decoded_file(data, tmp_path, name)[2]


def check_every_vector_observed(observed: dict[str, Any]) -> None:
    """One observation per vector, and none a crash (anything but a TkcError)."""
    assert sorted(observed) == sorted(EXPECTED)
    crashed = {name: o["message"] for name, o in observed.items() if o.get("crashed")}
    assert not crashed, f"the decoder threw something other than a TkcError: {crashed}"


def check_valid_observation(observed: dict[str, Any], name: str) -> None:
    """A valid vector: the digests, header facts, names, segment index and reconstruction its
    JSON gives."""
    expected, got = EXPECTED[name], observed[name]
    assert got["accepted"], got.get("message")
    for key, value in expected["header"].items():
        assert got["header"][key] == value, key
    assert got["frame_names"] == expected["frame_names"]
    assert got["segments"] == expected.get("segments", [])
    assert got["sha256"] == expected["sha256"]  # bit for bit (§6.3)
    assert got.get("residual") == expected.get("residual")  # 1.3: the corrections' integers
    reference = got["reference"]
    relative = expected["tolerance"]["relative_to_max_abs"]
    if relative == 0:  # a file with corrections: the same bits (§8.1)
        assert reference["identical"], (
            f"positions differ by up to {reference['max_abs_difference']}"
        )
        return
    tolerance = relative * reference["max_abs_reference"]
    assert reference["max_abs_difference"] <= tolerance + 1e-12  # §8


def check_invalid_observation(observed: dict[str, Any], name: str) -> None:
    """An invalid vector: refused with its rule and error class."""
    expected, got = EXPECTED[name], observed[name]
    assert not got["accepted"], f"accepted a file that breaks {expected['rule']}"
    assert (got["rule"], got["kind"]) == (expected["rule"], expected["error"]), got["message"]
    assert got["message"].endswith(f"[{expected['rule']}]")


def python_verdict(data: bytes) -> dict[str, Any]:
    """The reference decoder's verdict on a whole file, as ``outcomes.mjs`` gives the
    JavaScript one: accepted, or the rule and error class it refused with."""
    import tuckercodec

    from .compressed import deadline

    with deadline():
        try:
            tuckercodec.decode(data)
        except tuckercodec.FormatError as error:
            return {"accepted": False, "rule": error.rule, "kind": type(error).__name__}
    return {"accepted": True}


def compare_verdicts(
    files: list[bytes], folder: Path, zstd_strictness: Any
) -> tuple[list[Any], list[str], list[dict[str, Any]]]:
    """Each file decoded by both decoders (none may crash): the files whose verdicts differ,
    those that differ only as ``zstd_strictness(python, javascript)`` allows, and the
    reference's verdict on each file."""
    paths = []
    for n, data in enumerate(files):
        path = folder / f"case{n:04d}.tkc"
        path.write_bytes(data)
        paths.append(path)
    javascript = run_node("outcomes.mjs", *paths)
    crashed = [
        (p.name, o["message"]) for p, o in zip(paths, javascript, strict=True) if o.get("crashed")
    ]
    assert not crashed, crashed
    differ: list[Any] = []
    zstd_only: list[str] = []
    verdicts: list[dict[str, Any]] = []
    for path, data, js in zip(paths, files, javascript, strict=True):
        python = python_verdict(data)
        verdicts.append(python)
        mine = {k: js.get(k) for k in python}
        if mine == python:
            continue
        if zstd_strictness(python, js):
            zstd_only.append(path.name)
        else:
            differ.append((path.name, python, js))
    return differ, zstd_only, verdicts
