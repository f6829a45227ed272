"""The peers suite of tools.bench and its coders: sizes, errors and plumbing, untimed.

The peers that need optional packages (Draco, meshoptimizer, SZ3, zfp: ``pip install
'.[bench]'``) are tested only where those are installed, and skip saying so elsewhere.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import numpy as np
import pytest

from tools import bench, common
from tools.bench import peers
from tools.bench.peers import base, draco, pca, tkc, tthresh, zstd
from tuckercodec import kg_error


@pytest.fixture(scope="module")
def sample():
    return common.load(common.SAMPLE)


@pytest.fixture(scope="module")
def context(sample):
    return base.Context.of(sample, [10, 14])


def _decoded_kg(trial, sample) -> float:
    return kg_error(sample.vertices, trial.decoded)


def _size_again(trial: base.Trial) -> int:
    """The total bytes of the trial's encode run again, as --repeat runs it."""
    assert trial.retime is not None
    return trial.retime()[2]


def test_pca_baseline_meets_each_target_and_decodes_from_its_bytes(sample, context):
    trials = pca.run_pca(sample, [1.0, 0.1], context)
    assert [t.target for t in trials] == [1.0, 0.1]
    for trial in trials:
        assert trial.target is not None and trial.connectivity_bytes is not None
        assert _decoded_kg(trial, sample) <= trial.target
        assert trial.connectivity_bytes > 0
    assert trials[1].total_bytes > trials[0].total_bytes  # a tighter target costs more
    # re-timing runs the same encode (each trial keeps its own target, not the loop's last)
    assert [_size_again(t) for t in trials] == [t.total_bytes for t in trials]


def test_tuckercodec_trial_counts_the_whole_file(sample, context):
    trial, tighter = tkc.run_tuckercodec(sample, [0.5, 0.1], context)
    assert _size_again(trial) == trial.total_bytes < tighter.total_bytes
    assert _decoded_kg(trial, sample) <= 0.5
    assert trial.connectivity_bytes is not None
    assert 0 < trial.connectivity_bytes < trial.total_bytes
    assert trial.encode_seconds > 0 and trial.decode_seconds > 0


def test_lossless_reference_is_float32_exact(sample, context):
    (trial,) = zstd.run_zstd(sample, [], context)
    np.testing.assert_array_equal(trial.decoded, sample.vertices.astype(np.float32))
    assert trial.connectivity_bytes is not None
    assert trial.total_bytes > trial.connectivity_bytes > 0


def test_bound_search_keeps_the_smallest_file_that_meets_the_target(sample, context):
    # A toy compressor: uniform quantization of the centred tensor with step = bound.
    import zlib

    def compress(bound: float) -> bytes:
        q = np.rint(context.tensor / bound).astype(np.int32)
        return np.float64(bound).tobytes() + zlib.compress(q.tobytes())

    def decompress(payload: bytes) -> np.ndarray:
        step = np.frombuffer(payload[:8], np.float64)[0]
        q = np.frombuffer(zlib.decompress(payload[8:]), np.int32)
        return q.reshape(context.tensor.shape) * step

    trial = base.search_bound("toy", 0.3, context, 1e-6, compress, decompress, str)
    assert trial is not None and trial.kg <= 0.3
    assert abs(_decoded_kg(trial, sample) - trial.kg) < 1e-9
    # the search got close to the target, from below: a coarser step would fail
    assert trial.kg > 0.3 / 2


def test_vertex_matching_undoes_a_permutation_of_lattice_points():
    rng = np.random.default_rng(3)
    original = rng.random((500, 3))
    lattice = np.rint(original * 255) / 255  # what a quantizing coder decodes
    order = rng.permutation(500)
    matched = base.match_vertices(original, lattice[order], "test")
    np.testing.assert_array_equal(matched, lattice)
    with pytest.raises(RuntimeError, match="drops vertices"):
        base.match_vertices(original, lattice[:-1], "test")


def test_peak_memory_sees_a_large_allocation():
    if not Path("/proc/self/clear_refs").exists():
        pytest.skip("peak memory is measured from Linux's /proc only")
    with common.resident_peak() as memory:
        block = np.ones(64 * 1024 * 1024 // 8)  # 64 MiB, touched
        del block
    assert memory["peak"] is not None and memory["peak"] >= 48 * 1024 * 1024


def test_tthresh_plumbing_with_a_stand_in_binary(sample, context, tmp_path, monkeypatch):
    # A stand-in that stores the raw tensor unchanged: checks the arguments, the file layout
    # and the shapes without TTHRESH itself, which this project never builds or ships.
    script = tmp_path / "bin" / "tthresh"
    script.parent.mkdir()
    script.write_text(
        "#!/bin/sh\n"
        'case "$*" in\n'
        '  *"-i "*) while [ $# -gt 0 ]; do case $1 in -i) i=$2;; -c) c=$2;; esac; shift; done;\n'
        '    cp "$i" "$c";;\n'
        "  *) while [ $# -gt 0 ]; do case $1 in -c) c=$2;; -o) o=$2;; esac; shift; done;\n"
        '    cp "$c" "$o";;\n'
        "esac\n"
    )
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setenv("PATH", f"{script.parent}{os.pathsep}{os.environ['PATH']}")
    (trial,) = tthresh.run_tthresh(sample, [1.0], context)
    assert trial.kg < 1e-4  # lossless but for the float32 centroids (about 2e-6 here)
    assert trial.total_bytes > context.tensor.nbytes
    assert _size_again(trial) == trial.total_bytes  # --repeat runs it again, after run_tthresh


@pytest.mark.parametrize(
    ("coder", "module"),
    [
        ("draco-mesh", "DracoPy"),
        ("draco-points", "DracoPy"),
        ("meshopt", "meshoptimizer"),
        ("sz3", "pysz"),
        ("zfp", "zfpy"),
    ],
)
def test_optional_peers_round_trip(coder, module, sample, context):
    pytest.importorskip(module, reason=f"{module} is not installed (pip install '.[bench]')")
    run = next(c.run for c in peers.CODERS if c.name == coder)
    trials = run(sample, [1.0], context)
    assert trials
    assert _size_again(trials[0]) == trials[0].total_bytes
    for trial in trials:
        assert trial.decoded is not None
        assert trial.decoded.shape == sample.vertices.shape
        measured = _decoded_kg(trial, sample)
        if not np.isnan(trial.kg):
            assert abs(measured - trial.kg) < 1e-9
        assert measured < 5.0  # 10 bits or more, or a searched bound: a close approximation


def test_bench_writes_tables_plots_and_refuses_to_overwrite(sample, tmp_path, capsys):
    pytest.importorskip("matplotlib", reason="plots need matplotlib")
    out = tmp_path / "bench"
    coders = "tuckercodec,pca,zstd-f32"
    args = [
        "peers",
        "sample",
        "--coders",
        coders,
        "--targets",
        "1,0.2",
        "--repeat",
        "2",
        "--out",
        str(out),
    ]
    assert bench.main(args) == 0
    for name in ("summary.md", "sample.md", "sample.png", "results.json"):
        assert (out / name).stat().st_size > 0
    rows = json.loads((out / "results.json").read_text())
    assert {row["coder"] for row in rows} == {"tuckercodec", "pca", "zstd-f32"}
    for row in rows:
        if row["target"] is not None:
            assert row["kg"] <= row["target"]
        frames_vertices = sample.frame_count * sample.vertex_count
        assert row["bpfv"] == pytest.approx(8 * row["bytes"] / frames_vertices)
    summary = (out / "summary.md").read_text()
    assert "| sample | 1 |" in summary and "| sample | 0.2 |" in summary
    assert bench.main(args) == 2  # results are never replaced without --force
    assert "--force" in capsys.readouterr().err
    # forced, a cheaper run (one coder, one target, one timing) replaces every file
    cheaper = [*args[:2], "--coders", "zstd-f32", "--targets", "1", "--out", str(out)]
    before = {name: (out / name).read_bytes() for name in ("summary.md", "sample.md", "sample.png")}
    assert bench.main([*cheaper, "--force"]) == 0
    rows = json.loads((out / "results.json").read_text())
    assert {row["coder"] for row in rows} == {"zstd-f32"}
    assert all((out / name).read_bytes() != text for name, text in before.items())


def test_bench_runs_on_a_sequence_without_faces(tmp_path):
    points = tmp_path / "points.npz"
    sequence = common.load(common.SAMPLE)
    np.savez(points, V=sequence.vertices[:10], F=np.zeros((0, 3), dtype=np.int32))
    out = tmp_path / "bench"
    args = [
        "peers",
        str(points),
        "--coders",
        "tuckercodec,zstd-f32",
        "--targets",
        "1",
        "--out",
        str(out),
    ]
    assert bench.main(args) == 0
    rows = json.loads((out / "results.json").read_text())
    assert {row["coder"] for row in rows} == {"tuckercodec", "zstd-f32"}
    assert all("sted" not in row for row in rows)  # STED needs edges


def test_draco_points_keep_the_vertex_order(sample, context):
    pytest.importorskip("DracoPy", reason="DracoPy is not installed (pip install '.[bench]')")
    (trial,) = draco.run_draco_points(sample, [], base.Context.of(sample, [14]))
    # no matching was needed: every decoded vertex is within half a 14-bit step of its own
    extent = np.ptp(sample.vertices, axis=1).max()
    assert np.abs(trial.decoded - sample.vertices).max() <= extent / (2**14 - 1)
