"""What a file costs the JavaScript decoder and TKCLoader in node, in time and memory
(tests/js/memory.mjs, one process a job): one frame of a file whose corrections declare every
frame in one chunk (spec §6.9, §7 max_chunk_values), a segmented file played in a loop (the
decoded segments kept), and the loader's limits for a web page (WEB_LIMITS)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.compressed import chunked_file
from tests.support.js_decoder import JS, RUN_TIMEOUT, node
from tests.support.sequences import grid_faces, wave_sequence


def _measure(tmp_path: Path, data: bytes, **job: Any) -> dict[str, Any]:
    """Runs memory.mjs on ``data`` with ``job``, in a node of its own."""
    path = tmp_path / f"file{len(list(tmp_path.iterdir()))}.tkc"
    path.write_bytes(data)
    spec = path.with_suffix(".json")
    spec.write_text(json.dumps({"path": str(path), "via": "decoder", "frames": "first", **job}))
    done = subprocess.run(
        [node(), "--expose-gc", "--import", "./three_from_vendor.mjs", "memory.mjs", str(spec)],
        cwd=JS,
        capture_output=True,
        text=True,
        timeout=RUN_TIMEOUT,
        check=False,
    )
    assert done.returncode == 0, f"memory.mjs failed:\n{done.stderr[-3000:]}"
    return json.loads(done.stdout)


# -- one chunk of every frame (§6.9, max_chunk_values) ----------------------------------------


def test_a_chunk_of_every_frame_does_not_inflate_frame_0(tmp_path):
    """4 KB declaring 512 frames of 65,536 vertices in one chunk: 100 million integers, which
    frame 0 decoded whole (800 MiB of them, about 1 GB of node) before max_chunk_values."""
    data = chunked_file(65536, 512, chunk_frames=512, predict=1)
    assert len(data) < 8000
    got = _measure(tmp_path, data)
    assert not got["accepted"]
    assert got["rule"] == "R21-header-limit" and "max_chunk_values" in got["message"]
    assert got["maxRssMiB"] < 200, got


def test_a_chunk_beyond_the_limit_decodes_when_the_caller_raises_it(tmp_path):
    data = chunked_file(4096, 256, chunk_frames=256, predict=1)
    assert not _measure(tmp_path, data)["accepted"]
    raised = {"limits": {"max_chunk_values": 256 * 4096 * 3}}
    assert _measure(tmp_path, data, options=raised, frames="every")["accepted"]


# -- a segmented file played in a loop keeps two segments ---------------------------------------


@pytest.fixture(scope="module")
def many_segments() -> bytes:
    """24 segments of 2 frames, each its own U1 of 9,216 vertices x 12 columns (about 2 MiB
    decoded, with its SIMD copy)."""
    sequence = tc.MeshSequence(wave_sequence(48, 96, seed=1), grid_faces(96))
    return tc.encode(sequence, ranks=(12, 2), segment_frames=2, basis="own", level=3)


@pytest.mark.parametrize("via", ["decoder", "loader"])
def test_playing_every_frame_in_a_loop_keeps_memory_bounded(tmp_path, many_segments, via):
    """Every frame, three times over, as a looping page plays them: two segments are kept (as in
    the Python decoder), and what stays in memory after each loop is what frame 0 left (it grew
    by every segment's factors, about 10 MiB here and 700 MiB for a crafted 25 KB file, when all
    were kept)."""
    got = _measure(tmp_path, many_segments, via=via, frames="every", loops=3)
    assert got["accepted"], got
    assert got["segmentsKept"] == 2
    first, *loops = got["retained"]
    assert min(loops) - first < 5, got["retained"]


def test_the_segments_kept_are_the_callers_choice(tmp_path, many_segments):
    got = _measure(tmp_path, many_segments, frames="every", loops=1, options={"cachedSegments": 5})
    assert got["segmentsKept"] == 5
    decoded = tc.Decoder(many_segments).positions(frames=[0, 47]).astype(np.float32)
    assert decoded.shape == (2, 96 * 96, 3)


# -- TKCLoader's limits for a web page -----------------------------------------------------------


def test_the_loader_refuses_a_file_over_its_web_limits_and_accepts_it_when_raised(tmp_path):
    """A few KB declaring 2^18 + 4 vertices (one frame of 2 frames per chunk): within the
    decoder's defaults, over TKCLoader's WEB_LIMITS; refused at once, with the limit named, and
    played when the page raises it."""
    vertices = 2**18 + 4
    data = chunked_file(vertices, 2, chunk_frames=1)
    assert len(data) < 60_000
    refused = _measure(tmp_path, data, via="loader")
    assert not refused["accepted"]
    assert refused["rule"] == "R21-header-limit" and "max_vertices" in refused["message"]
    assert refused["maxRssMiB"] < 200, refused
    assert _measure(tmp_path, data, via="decoder")["accepted"]  # the decoder's own defaults
    raised = _measure(tmp_path, data, via="loader", options={"limits": {"max_vertices": 2**19}})
    assert raised["accepted"], raised
