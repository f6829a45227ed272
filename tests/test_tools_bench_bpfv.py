"""tools.bench bpfv: the size target's table on the built-in sample, untimed."""

from __future__ import annotations

from tools import bench
from tools.bench import bpfv as bench_bpfv


def test_the_sample_row_reports_a_filled_budget_and_the_kg_definition(capsys):
    assert bench.main(["bpfv", "sample", "--bpfv", "1", "0.001"]) == 0
    out = capsys.readouterr().out
    assert "Karni-Gotsman" in out
    row = next(line for line in out.splitlines() if line.startswith("| sample | 1 |"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert float(cells[2]) <= 1.0 and float(cells[3]) >= bench_bpfv.LEAST_FILL
    assert "unreachable: no file fits 0.001 bpfv" in out
    assert "files over their budget: none" in out
