"""tools.bench read --formats: every writable format is written, read back and compared (untimed
claims only: the timings themselves belong in BENCHMARKS.md)."""

from __future__ import annotations

from tools import bench
from tuckercodec import formats


def test_every_writable_format_reads_the_sample_back(capsys):
    # the exit status says whether every read met its time target: timing is the benchmark's
    # business, not a unit test's (a loaded machine would fail it)
    assert bench.main(["read", "sample", "--formats", "--repeat", "1"]) in (0, 1)
    out = capsys.readouterr().out
    rows = {line.split("|")[1].strip(): line for line in out.splitlines() if line.count("|") > 8}
    for found in formats():
        if found.write is None:
            continue
        row = rows[found.name]
        if "skipped" in row:  # an extra that is not installed says so
            assert "pip install" in row
        elif found.name == "gltf":  # morph targets: within the float32 rounding of base + target
            assert "max deviation" in row and "same faces" in row
        else:
            assert "exact" in row and "same faces" in row, row
