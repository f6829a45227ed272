"""tools/bench/streaming.py: the files it writes block by block (a zip64 .npz member among
them) read back through open_frames as the frames it generated, so that its figures measure
reading the data it claims."""

from __future__ import annotations

import numpy as np
import pytest

from tools.bench import streaming as bench_streaming
from tuckercodec import open_frames


@pytest.mark.parametrize("kind", bench_streaming.FORMATS)
def test_each_file_reads_back_as_generated(tmp_path, kind):
    if kind == "zarr":
        pytest.importorskip("zarr", reason="zarr (the [zarr] extra) is not installed")
    path = tmp_path / f"x{bench_streaming.SUFFIXES[kind]}"
    bench_streaming.write(kind, path, 50, 37)
    expected = np.concatenate(list(bench_streaming.positions(50, 37))).astype(np.float64)
    assert expected.shape == (37, 50, 3) and np.ptp(expected[:, :, 2]) > 0  # it moves
    with open_frames(path) as source:
        assert np.array_equal(source.read(0, 37), expected)
        assert np.array_equal(source.read(20, 30), expected[20:30])
    assert not list(tmp_path.glob("*.partial"))
