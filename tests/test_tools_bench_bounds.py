"""tools.bench bounds: the worst vertex measured independently, the peers in absolute mode, and
the suite's tables, on the built-in sample (the cloth), untimed.

SZ3 and zfp (``pip install '.[bench]'``) are tested only where they are installed, and skip
saying so elsewhere.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tools import bench, common
from tools.bench import bounds
from tools.bench.peers import base, sz3, zfp


@pytest.fixture(scope="module")
def sample():
    return common.load(common.SAMPLE)


def test_the_worst_vertex_is_the_largest_euclidean_distance_and_where_it_is():
    rng = np.random.default_rng(5)
    original = rng.random((4, 50, 3))
    decoded = original + 1e-6 * rng.standard_normal(original.shape)
    decoded[2, 17] = original[2, 17] + [3e-3, 4e-3, 0.0]  # 5e-3 away, though no coordinate is
    worst, frame, vertex = base.worst_vertex(original, decoded.astype(np.float32))
    assert (frame, vertex) == (2, 17)
    assert worst == pytest.approx(5e-3, rel=1e-4)  # float32 decoded values are read as they are


def test_the_diagonal_spans_every_frame():
    vertices = np.zeros((2, 3, 3))
    vertices[0, 1] = [1.0, 0.0, 0.0]
    vertices[1, 2] = [0.0, 2.0, 2.0]  # the box of all frames, not of one
    assert base.bounding_box_diagonal(vertices) == pytest.approx(3.0)


@pytest.mark.parametrize(
    ("run", "module"), [(sz3.run_sz3_abs, "pysz"), (zfp.run_zfp_accuracy, "zfpy")]
)
def test_a_peer_in_absolute_mode_keeps_every_vertex_within_the_bound(run, module, sample):
    pytest.importorskip(module, reason=f"{module} is not installed (pip install '.[bench]')")
    values = base.own_precision(sample)
    assert values.dtype == np.float32  # the cloth is float32 exactly: coded as float32
    bound = 1e-3 * base.bounding_box_diagonal(sample.vertices)
    trial = run(sample, values, bound)
    worst, _, _ = base.worst_vertex(sample.vertices, trial.decoded)
    assert 0 < worst <= bound
    assert trial.decoded.dtype == np.float64 and trial.decoded.shape == sample.vertices.shape
    assert trial.connectivity_bytes == len(base.faces_once(sample))  # the faces, counted
    assert trial.total_bytes > trial.connectivity_bytes
    assert trial.retime is not None and trial.retime()[2] == trial.total_bytes


def test_the_suite_reports_sizes_bounds_and_misses(sample, tmp_path, capsys):
    pytest.importorskip("pysz", reason="pysz is not installed (pip install '.[bench]')")
    out = tmp_path / "bounds"
    args = ["bounds", "sample", "--bounds", "1e-3", "--plot-bounds", "3e-3"]
    args += ["--coders", "sz3", "--out", str(out)]
    assert bench.main(args) == 0
    text = capsys.readouterr().out
    row = next(line for line in text.splitlines() if line.startswith("| sample | 0.001 | 0.01"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[3] == "sz3" and cells[9] == "yes"
    rate = 8 * int(cells[5]) / (sample.frame_count * sample.vertex_count)
    assert float(cells[6].split()[0]) == pytest.approx(rate, abs=5e-4)
    assert "Misses: none." in text
    assert "| sequence | coder | 0.003 | 0.001 |" in text  # the plot's points, as a table
    points = next(line for line in text.splitlines() if line.startswith("| sample | sz3 |"))
    assert float(points.split("|")[3]) < float(points.split("|")[4])  # a looser D, a smaller file
    assert (out / "bounds.md").read_text() == text
    entries = json.loads((out / "results.json").read_text())
    assert sorted(e["relative"] for e in entries) == [1e-3, 3e-3]  # the plot's bound measured
    assert all(e["worst"] <= e["bound"] for e in entries)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        assert "plot skipped" in capsys.readouterr().err
    else:
        assert (out / "bounds.png").stat().st_size > 0
    assert bench.main(args) == 2  # results are never replaced without --force
    assert "--force" in capsys.readouterr().err


def test_a_vertex_over_the_bound_is_a_miss():
    over = bounds.Entry("s", 1e-3, 0.01, "sz3", "ABS", 100, 0.1, 1.0, 0.02, (0, 3), None, False)
    ours = bounds.Entry("s", 1e-3, 0.01, "tuckercodec", "", 60, 0.1, 0.6, 0.005, (0, 1))
    ours.within, ours.reported_worst = True, 0.004
    found = bounds.misses([over, ours], [], [1e-3])
    assert any("sz3" in m and "0.02 > D = 0.01" in m for m in found)
    assert any("reports a worst vertex of 0.004" in m for m in found)
    assert any("0.600 of SZ3's size" in m for m in found)
    assert math.isclose(over.ratio or 0, 2.0)


def test_bounds_that_are_not_fractions_of_the_diagonal_are_refused(capsys):
    with pytest.raises(SystemExit) as exit_:
        bench.main(["bounds", "sample", "--bounds", "2"])
    assert exit_.value.code == 2
    assert "fractions of the diagonal" in capsys.readouterr().err


def test_tuckercodec_keeps_every_vertex_within_the_bound_measured_here(sample):
    diagonal = base.bounding_box_diagonal(sample.vertices)
    values = base.own_precision(sample)
    entry = bounds.measure(
        "sample", "tuckercodec", bounds.CODERS["tuckercodec"][1], sample, values, 1e-3, diagonal, 1
    )
    assert entry.error is None and entry.worst is not None
    assert entry.within and entry.worst <= 1e-3 * diagonal
    # the encoder's own report agrees with the measure made here
    assert entry.reported_worst == pytest.approx(entry.worst, rel=bounds.REPORT_TOLERANCE)


def test_the_combined_row_bounds_the_kg_file_at_twice_its_worst_vertex(sample):
    row = bounds.combined("sample", sample, 1.0, 2.0)
    assert row.error is None and row.ratio is not None and row.worst is not None
    assert row.bound == pytest.approx(2.0 * row.plain_worst)
    assert row.worst <= row.bound
    assert row.measured_kg is not None and row.measured_kg <= 1.0
    assert row.ratio >= 1.0 or row.bytes == row.plain_bytes  # a bound never makes it smaller
