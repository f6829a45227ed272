"""The package installs on a machine without Rust: the compiled core is optional, and without
it the package is the pure-Python reference (README, "The compiled core")."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent


def _path_without_rust() -> str:
    """This PATH less every folder that holds cargo or rustc."""
    kept = [
        folder
        for folder in os.environ.get("PATH", "").split(os.pathsep)
        if folder and not any((Path(folder) / tool).exists() for tool in ("cargo", "rustc"))
    ]
    return os.pathsep.join(kept)


def test_a_machine_without_rust_builds_a_pure_python_wheel(tmp_path):
    source = tmp_path / "source"
    # the tracked files only, as a clean clone has them (no target/, no built module)
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=False)
    if listed.returncode != 0:
        pytest.skip("not a git checkout: the tracked files cannot be listed")
    for name in filter(None, listed.stdout.decode().split("\0")):
        if (REPO / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(REPO / name, source / name)
    environment = {**os.environ, "PATH": _path_without_rust(), "PIP_NO_COMPILE": "1"}
    environment.pop("CARGO", None)
    assert shutil.which("cargo", path=environment["PATH"]) is None
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(tmp_path), "."]
    done = subprocess.run(
        command, cwd=source, env=environment, capture_output=True, text=True, check=False
    )
    if done.returncode != 0 and "No matching distribution" in done.stdout + done.stderr:
        pytest.skip("pip cannot reach a package index for the build's own requirements")
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    (wheel,) = tmp_path.glob("tuckercodec-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert "tuckercodec/decoder.py" in names
    assert not [name for name in names if "_native" in name or name.endswith((".so", ".pyd"))]
    assert not [name for name in names if name.endswith(".rs")]
