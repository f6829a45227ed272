"""tools.paper on the built-in sample: it writes its figures and summary, the summary's numbers
agree with analyze() (recomputed here, never hard-coded), and it refuses to overwrite."""

from __future__ import annotations

import numpy as np
import pytest

from tools import common, paper
from tuckercodec import analyze

TARGETS = (0.5,)  # one target: the encode path is covered, the test stays quick


def _table(summary: str, heading: str) -> list[list[str]]:
    """Body rows of the first markdown table after the heading line that starts with ``heading``."""
    lines = summary.splitlines()
    start = next(n for n, line in enumerate(lines) if line.startswith(heading))
    rows, seen = [], False
    for line in lines[start + 1 :]:
        if line.startswith("|"):
            seen = True
            rows.append([cell.strip() for cell in line.strip("|").split("|")])
        elif seen:
            break
    return rows[2:]  # header and separator


def _ranks(cell: str) -> tuple[int, int]:
    i, k = cell.strip("()").split(",")
    return int(i), int(k)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    code = paper.main(["sample", "--out", str(out), "--targets", ",".join(map(str, TARGETS))])
    assert code == 0
    return out, (out / "summary.md").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def analysis():
    return analyze(common.load(common.SAMPLE))


def test_figures_and_summary_written(run):
    out, summary = run
    for name in ("sample-fig1-rd.png", "sample-fig2-psi.png", "sample-fig3-heatmaps.png"):
        data = (out / name).read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n") and len(data) > 1000, name
    assert "## sample" in summary and "command: `python -m tools.paper sample" in summary
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporary file


def test_targets_agree_with_analysis(run, analysis):
    _, summary = run
    claim_a = _table(summary, "### (a)")
    claim_d = _table(summary, "### (d)")
    assert len(claim_a) == len(claim_d) == len(TARGETS)
    pca = analysis.pca_curve()
    for target, row_a, row_d in zip(TARGETS, claim_a, claim_d, strict=True):
        exact, bound = analysis.cheapest(target), analysis.cheapest(target, select="bound")
        assert float(row_a[0]) == target
        assert _ranks(row_a[1]) == (exact.i, exact.k) and int(row_a[2]) == exact.floats
        assert float(row_a[3]) == pytest.approx(exact.kg, rel=1e-5)
        assert _ranks(row_a[7]) == (bound.i, bound.k) and int(row_a[8]) == bound.floats
        assert _ranks(row_d[1]) == (exact.i, exact.k)
        r = int(np.argmax(pca.kg <= target))  # smallest PCA rank meeting the target
        assert int(row_d[4]) == pca.i[r] and int(row_d[5]) == pca.floats[r]
        file_kg = float(row_d[8].split("KG")[1])
        assert 0 < file_kg <= target  # a real file, never above its target


def test_psi_boxes_agree_with_analysis(run, analysis):
    _, summary = run
    rows = _table(summary, "### Fig. 2: ψ by Θ window, every truncation")
    assert len(rows) == 10
    rate = analysis.rate_table()[1:, 1:].ravel()
    psi = analysis.psi_table()[1:, 1:].ravel()
    for w, row in enumerate(rows):
        inside = (rate > w / 10) & (rate <= (w + 1) / 10)
        assert int(row[1]) == inside.sum()
        expected = np.percentile(psi[inside], [0, 25, 50, 75, 100])
        got = np.array([float(v) for v in row[2:7]])
        np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-12)


def test_refuses_to_overwrite(run, capsys):
    out, summary = run
    assert paper.main(["sample", "--out", str(out), "--no-encode"]) == 1
    assert "already exists" in capsys.readouterr().err
    assert (out / "summary.md").read_text(encoding="utf-8") == summary


def test_a_point_cloud_has_no_sted_and_says_why(tmp_path):
    points = tmp_path / "points.npz"
    sequence = common.load(common.SAMPLE)
    np.savez(points, V=sequence.vertices[:12, :400], F=np.zeros((0, 3), dtype=np.int32))
    out = tmp_path / "out"
    assert paper.main([str(points), "--out", str(out), "--targets", "1"]) == 0
    rows = _table((out / "summary.md").read_text(encoding="utf-8"), "### (c)")
    assert rows
    for row in rows:
        assert row[6] == row[-1] == "n/a (STED needs a mesh: the faces have no edges)"
