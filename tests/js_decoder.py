"""Runs the JavaScript decoder (tuckercodec/web/tkc/) in node, for the tests that compare it with
the Python decoder. Test modules import it as ``from js_decoder import run_node``; a test that
calls it where node (18 or newer) is missing is skipped, naming what is missing. The decoder
needs no npm package (its two dependencies are vendored), so nothing is installed.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest

JS = Path(__file__).resolve().parent / "js"
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
