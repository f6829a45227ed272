"""Tools nobody here wrote, run from the tests: the Khronos glTF-Validator and three.js's
GLTFLoader, both in node, from the npm packages pinned in tests/js/package-lock.json.

Test modules import it as ``from tests.support.js_interop import validate_gltf``. The first call
installs the packages with ``npm ci`` into tests/js/node_modules, once (a file lock makes parallel
runs wait for it; a marker holding the lockfile's hash makes an interrupted or outdated install run
again); a test that calls either function where node or npm is missing, too old, or the install
fails is skipped with a message naming what is missing.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

JS = Path(__file__).resolve().parents[1] / "js"
NODE_MODULES = JS / "node_modules"
MARKER = NODE_MODULES / ".tuckercodec-installed"
LOCK = JS / ".install.lock"
MIN_NODE = 18
INSTALL_TIMEOUT = 600.0
RUN_TIMEOUT = 300.0

# the validator's severities
ERROR, WARNING, INFO, HINT = 0, 1, 2, 3


class JsToolError(RuntimeError):
    """A node script crashed or refused its input (a test failure, not a skip)."""


def _lock_hash() -> str:
    return hashlib.sha256((JS / "package-lock.json").read_bytes()).hexdigest()


def _node_version(node: str) -> int:
    try:
        done = subprocess.run(
            [node, "--version"], capture_output=True, text=True, timeout=30, check=True
        )
        return int(done.stdout.strip().lstrip("v").split(".")[0])
    except (OSError, subprocess.SubprocessError, ValueError):
        return 0


@functools.cache
def _setup() -> tuple[str | None, str]:
    """(node's path, "") once the packages are installed, else (None, what is missing)."""
    node = shutil.which("node")
    npm = shutil.which("npm")
    if node is None or npm is None:
        missing = " and ".join(name for name, path in (("node", node), ("npm", npm)) if not path)
        return None, f"{missing} not found on PATH"
    major = _node_version(node)
    if major < MIN_NODE:
        return None, f"node {MIN_NODE} or newer (found {node}, major version {major or '?'})"
    wanted = _lock_hash()
    with LOCK.open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another run installing: wait for it, then reuse
        if MARKER.exists() and MARKER.read_text() == wanted:
            return node, ""
        try:
            done = subprocess.run(
                [npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"],
                cwd=JS,
                capture_output=True,
                text=True,
                timeout=INSTALL_TIMEOUT,
                env={**os.environ, "npm_config_update_notifier": "false"},
            )
        except (OSError, subprocess.TimeoutExpired) as error:
            return None, f"`npm ci` in {JS} to install the pinned packages: {error}"
        if done.returncode != 0:
            said = [line for line in (done.stderr or done.stdout).splitlines() if line.strip()]
            return None, f"`npm ci` in {JS} failed: " + " | ".join(said[:3])
        MARKER.write_text(wanted)
    return node, ""


def node_path() -> str:
    """node's path, with tests/js's packages installed, or skip the calling test saying what is
    missing."""
    node, missing = _setup()
    if node is None:
        pytest.skip(
            f"the glTF interop tests need node and npm (the Khronos glTF-Validator and three.js, "
            f"pinned in tests/js/package-lock.json): {missing}"
        )
    return node


def _run(script: str, args: list[str], stdin: str | None = None) -> Any:
    done = subprocess.run(
        [node_path(), str(JS / script), *args],
        cwd=JS,
        input=stdin,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
    )
    if done.returncode != 0:
        raise JsToolError(f"node {script} {' '.join(args)} failed: {done.stderr.strip()}")
    return json.loads(done.stdout)


def validate_gltf_files(paths: list[Path]) -> list[dict[str, Any]]:
    """The Khronos glTF-Validator's reports on several .glb/.gltf files, in one node process.

    Each report: ``numErrors``, ``numWarnings``, ``numInfos``, ``numHints``, ``messages`` (each
    ``code``, ``message``, ``pointer``, ``severity``: 0 error, 1 warning, 2 info, 3 hint),
    ``info`` (the validator's summary of the asset) and ``validatorVersion``. Raises JsToolError
    where the validator refuses a file outright (unreadable, neither glTF nor GLB)."""
    reports: list[dict[str, Any]] = _run("validate.mjs", [str(Path(p).resolve()) for p in paths])
    for report in reports:
        if "fatal" in report:
            raise JsToolError(f"the glTF-Validator refused {report['uri']}: {report['fatal']}")
    return reports


def validate_gltf(path: Path) -> dict[str, Any]:
    """The Khronos glTF-Validator's report on one file (see :func:`validate_gltf_files`)."""
    return validate_gltf_files([path])[0]


def issues(report: dict[str, Any], max_severity: int = WARNING) -> list[str]:
    """The report's messages of that severity or worse, as "CODE pointer: message" lines (an
    assertion's message shows them all)."""
    return [
        f"{m['code']} {m['pointer']}: {m['message']}"
        for m in report["messages"]
        if m["severity"] <= max_severity
    ]


def three_evaluate(path: Path, times: Any, clip: int = 0) -> dict[str, Any]:
    """three.js's GLTFLoader playing animation ``clip`` of a .glb/.gltf at each time (seconds):
    every mesh's vertices in world space as three.js evaluates them (morph targets, node
    transforms, de-normalized quantized attributes, meshopt decoding).

    Returns evaluate.mjs's summary (``meshes`` with ``name``, ``node``, ``mesh``, ``primitive``,
    ``vertexCount``, ``morphTargets``; ``clip``; ``warnings``, what three.js warned about)
    with each mesh's ``positions`` as a float64 array (len(times), vertexCount, 3)."""
    times = [float(t) for t in np.asarray(times, dtype=np.float64).ravel()]
    with tempfile.TemporaryDirectory(prefix="tuckercodec-three-") as scratch:
        out = Path(scratch) / "positions.bin"
        summary: dict[str, Any] = _run(
            "evaluate.mjs",
            [str(Path(path).resolve()), "--times", "-", "--clip", str(clip), "--out", str(out)],
            stdin=json.dumps(times),
        )
        data = out.read_bytes()
    for mesh in summary["meshes"]:
        count = mesh["vertexCount"]
        mesh["positions"] = np.frombuffer(
            data, dtype="<f8", count=len(times) * count * 3, offset=mesh["offset"]
        ).reshape(len(times), count, 3)
    return summary


def three_positions(path: Path, times: Any, clip: int = 0) -> np.ndarray:
    """The vertices (len(times), K, 3), float64, of the file's animated mesh as three.js plays
    it: the first mesh with morph targets, else the only mesh. Fails the test if three.js
    warned while loading (an ignored extension or attribute would go unseen otherwise)."""
    summary = three_evaluate(path, times, clip)
    assert not summary["warnings"], f"three.js warned on {path}: {summary['warnings']}"
    meshes = summary["meshes"]
    morphing = [m for m in meshes if m["morphTargets"]]
    if morphing:
        return morphing[0]["positions"]
    assert len(meshes) == 1, f"{path}: {len(meshes)} meshes and none with morph targets"
    return meshes[0]["positions"]
