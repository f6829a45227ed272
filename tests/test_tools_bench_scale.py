"""tools.bench scale's measuring instruments, so that its tables can be trusted: the memory of a
whole process tree, the kill that protects the machine, and the streamed KG check. The
benchmark itself is never run here (its figures are timings)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from tools.bench import scale as bench_scale
from tools.generate import sequence as make_sequence
from tuckercodec import MeshSequence, decode, encode, kg_error

pytestmark = pytest.mark.skipif(
    sys.platform != "linux", reason="the scale suite reads Linux's /proc"
)

MB = 1 << 20
# A child that holds 120 MB and starts a grandchild holding 200 MB, both for a moment (bytes
# made by repetition are written, so resident; no numpy, so they start fast).
_HOLD = "import time; a = b'x' * {n}; time.sleep({s})"
_TREE = (
    "import subprocess, sys\n"
    f"grandchild = subprocess.Popen([sys.executable, '-c', {_HOLD.format(n=200 * MB, s=0.5)!r}])\n"
    f"a = b'x' * {120 * MB}\n"
    "grandchild.wait()\n"
)


def test_the_memory_of_children_and_grandchildren_is_summed(tmp_path):
    run = bench_scale.run_measured([sys.executable, "-c", _TREE], cwd=tmp_path, interval=0.02)
    assert run.ok, run.stderr
    assert run.main_rss > 120 * MB  # the child's own 120 MB
    assert run.tree_rss > 320 * MB  # and its grandchild's 200 MB with it
    assert run.tree_anon > 300 * MB
    assert run.largest_hwm > 200 * MB  # the kernel's mark: the largest single process
    assert run.seconds > 0.4


def test_a_tree_that_passes_the_limit_is_killed_and_said_to_be(tmp_path):
    command = [sys.executable, "-c", _HOLD.format(n=480 * MB, s=600)]
    run = bench_scale.run_measured(command, cwd=tmp_path, interval=0.02, limit=100 * MB)
    assert not run.ok and run.killed_above == 100 * MB
    assert run.seconds < 300  # not left to sleep its 600 s (a hang guard, any machine)
    assert "passed 0.1 GB" in run.failure()


def test_the_streamed_kg_is_the_kg_error(tmp_path, monkeypatch):
    sequence = make_sequence.make("body", 500, 30)
    npy = tmp_path / "b.npy"
    make_sequence.write(npy, sequence)
    positions = np.load(npy).astype(np.float64)
    compressed = tmp_path / "b.tkc"
    compressed.write_bytes(encode(MeshSequence(positions, sequence.faces), target_kg=0.5))
    expected = kg_error(positions, decode(compressed).vertices)
    # blocks of 7 frames: the sums over blocks must give the whole sequence's error
    assert bench_scale.streamed_kg(npy, compressed, block_values=7 * 3 * 500) == pytest.approx(
        expected, rel=1e-9
    )


def test_the_cpu_time_of_the_tree_is_counted(tmp_path):
    # a grandchild that spins: its CPU time reaches the child's, which reaps it
    spin = "import time\nend = time.process_time() + 0.3\nwhile time.process_time() < end: pass\n"
    tree = f"import subprocess, sys\nsubprocess.run([sys.executable, '-c', {spin!r}])\n"
    run = bench_scale.run_measured([sys.executable, "-c", tree], cwd=tmp_path, interval=0.02)
    assert run.ok, run.stderr
    assert run.cpu_seconds >= 0.3


def test_the_jobs_table_sets_the_workers_against_the_run_in_process(tmp_path):
    data = bench_scale.Input(tmp_path / "b.npy", tmp_path / "b.obj", tmp_path / "b.npy", 10, 100)
    results = []
    for label, seconds, content in (
        ("--jobs 1", 8.0, b"same"),
        ("--jobs 2", 4.0, b"same"),
        ("in process", 5.0, b"other"),
    ):
        output = tmp_path / f"{seconds}.tkc"
        output.write_bytes(content)
        result = bench_scale.EncodeResult(label, output=output)
        result.runs.append(bench_scale.Run([], seconds, 0, "", "", 2 * MB, cpu_seconds=9.5))
        results.append(result)
    text = "\n".join(bench_scale.jobs_table(results, data))
    assert "| in process | 1 | 5.0 | 9.5 |" in text
    assert "speed-up of --jobs 2 over --jobs 1 2.00" in text and "byte-identical files: yes" in text
    assert "--jobs 2 against in process: 1.25 times as fast" in text
