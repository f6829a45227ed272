"""What one frame of a file costs the decoder, and the declared sizes that could make it cost
more (format 1.3's corrections, spec §6.9 and §7)."""

from __future__ import annotations

import tracemalloc
from collections.abc import Callable

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.compressed import chunked_file, vector
from tuckercodec import Decoder, Limits
from tuckercodec.errors import LimitError
from tuckercodec.format.limits import DEFAULT_LIMITS

# -- chunk_frames beyond int64 (§6.9: any int >= 1; above the frames, one chunk) -------------


def test_chunk_frames_of_two_to_the_64_minus_one_decodes_as_one_chunk():
    data = vector("v1.3-chunk-frames-u64")
    decoder = Decoder(data)
    decoder.check()
    same = Decoder(vector("v1.3-lossless-float32")).positions()
    assert np.array_equal(decoder.positions().view(np.int64), same.view(np.int64))
    assert np.array_equal(decoder.positions(frames=[7]), same[[7]])
    assert tc.info(data).frames == same.shape[0]


# -- one frame costs its chunk, and a chunk of several frames is bounded (§6.9, §7) -----------


def _peak(work: Callable[[], object]) -> int:
    """The bytes Python and numpy allocate at most while ``work`` runs (no clock: the next
    machine may be slower, the memory is the point)."""
    tracemalloc.start()
    try:
        work()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


#: 4096 vertices, 512 frames: 6.3 million integers in one chunk, 48 MiB as int64
BIG = (4096, 512)


@pytest.fixture(scope="module")
def one_chunk() -> bytes:
    vertices, frames = BIG
    return chunked_file(vertices, frames, chunk_frames=frames, predict=1)


def test_a_chunk_of_every_frame_does_not_inflate_frame_0(one_chunk):
    """A few KB that declare every frame in one chunk: frame 0 is refused at once with the limit
    named, before its chunk is decompressed, rather than decoded with the whole chunk."""
    assert len(one_chunk) < 20_000

    def frame_0() -> None:
        with pytest.raises(LimitError, match="max_chunk_values") as caught:
            Decoder(one_chunk).positions(frames=[0])
        assert caught.value.rule == "R21-header-limit"

    peak = _peak(frame_0)
    frame_bytes = BIG[0] * 3 * 8
    assert peak < 64 * frame_bytes + (4 << 20), f"{peak / 2**20:.1f} MiB for frame 0"


def test_a_chunk_beyond_the_default_decodes_with_the_limit_raised(one_chunk):
    vertices, frames = BIG
    limits = Limits(max_chunk_values=frames * vertices * 3)
    decoder = Decoder(one_chunk, limits=limits)
    assert not decoder.positions(frames=[0, frames - 1]).any()


def test_frame_memory_is_bounded_by_the_chunk_limit_not_the_file():
    """Chunks at the default limit: frame 0 of a file of many costs one chunk, whatever F."""
    vertices = 4096
    per_chunk = DEFAULT_LIMITS.max_chunk_values // (3 * vertices)  # 170 frames
    data = chunked_file(vertices, 4 * per_chunk, chunk_frames=per_chunk, predict=1)
    decoder = Decoder(data)
    peak = _peak(lambda: decoder.positions(frames=[0]))
    chunk_bytes = 8 * per_chunk * vertices * 3  # the chunk's int64 integers, 16 MiB
    assert peak < 2.5 * chunk_bytes, f"{peak / 2**20:.1f} MiB for frame 0"


def test_a_chunk_of_one_frame_is_never_refused_by_the_chunk_limit():
    """N_c = 3K above max_chunk_values, but one frame: the chunk costs the frame."""
    data = chunked_file(4096, 3, chunk_frames=1)
    limits = Limits(max_chunk_values=1000)
    assert not Decoder(data, limits=limits).positions().any()
    with pytest.raises(LimitError, match="max_chunk_values"):
        Decoder(chunked_file(4096, 3, chunk_frames=2), limits=limits)
