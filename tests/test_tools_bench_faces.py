"""tools.bench faces: the fans it measures and its table, untimed."""

from __future__ import annotations

import numpy as np

from tools import bench
from tools.bench import faces as bench_faces
from tuckercodec.format import traversal


def test_a_fan_shares_one_edge_in_one_or_both_orientations():
    same = bench_faces.fan(5, "same")
    assert same.tolist() == [[0, 1, v] for v in range(2, 7)]
    turned = bench_faces.fan(5, "alternating")
    assert np.array_equal(turned[::2], same[::2])
    assert turned[1::2, :2].tolist() == [[1, 0], [1, 0]]


def test_the_table_has_a_row_per_fan_and_size(capsys):
    assert bench.main(["faces", "--faces", "20", "40"]) == 0
    out = capsys.readouterr().out
    assert "machine:" in out and "command: python -m tools.bench faces --faces 20 40" in out
    rows = [line for line in out.splitlines() if line.startswith(("| same", "| alternating"))]
    assert [row.split("|")[1:3] for row in rows] == [
        [" same ", " 20 "],
        [" alternating ", " 20 "],
        [" same ", " 40 "],
        [" alternating ", " 40 "],
    ]
    crafted = [line.split("|")[1:4] for line in out.splitlines() if line.startswith("| closed")]
    assert [row[:2] for row in crafted] == [[" closed fan ", " 80 "], [" closed fan ", " 160 "]]


def test_the_closed_fan_reads_its_oldest_edge_after_the_closed_ones():
    params, payload, k = bench_faces.closed_fan(3)
    decoded = traversal.decode_traversal(payload, params, k, "FACE")
    y, x, u = [2, 3, 4], [5, 6, 7], [8, 9, 10]
    assert decoded.tolist() == (
        [[0, v, 1] for v in y]
        + [[0, a, b] for a, b in zip(x, u, strict=True)]
        + [[0, b, a] for a, b in zip(x, u, strict=True)]
        + [[v, 0, 1] for v in y]
    )
    assert (
        k == 11
        and traversal.TIP_PREV in traversal.read_streams(payload, params, 12, 3, k, "FACE")[0][0]
    )
