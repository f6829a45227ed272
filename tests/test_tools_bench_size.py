"""tools.bench size: this checkout against the package at a baseline revision, untimed."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from tools import bench, common
from tools.bench import size as bench_size
from tuckercodec.io.samples import sample_path


def _has_baseline() -> bool:
    if shutil.which("git") is None:
        return False
    found = subprocess.run(
        ["git", "-C", str(common.REPO), "cat-file", "-e", bench_size.DEFAULT_BASELINE],
        capture_output=True,
    )
    return found.returncode == 0


@pytest.mark.skipif(not _has_baseline(), reason="needs git and the repository's history")
def test_the_sample_is_compared_with_the_baseline_revision(capsys):
    assert bench.main(["size", str(sample_path()), "--targets", "1"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith(f"| {sample_path().name} |"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    before, now = (int(cell.split()[0]) for cell in cells[2:4])
    assert now < before  # the sample (the cloth) is far smaller with faces-traverse
    assert cells[7] == "ok"  # decoded KG at most the target, measured by the tool
    assert "missed absolute targets" in out
