"""What one frame of a file costs the decoder, and the declared sizes that could make it cost
more (format 1.3's corrections, spec §6.9 and §7)."""

from __future__ import annotations

import numpy as np

import tuckercodec as tc
from tests.support.compressed import vector
from tuckercodec import Decoder

# -- chunk_frames beyond int64 (§6.9: any int >= 1; above the frames, one chunk) -------------


def test_chunk_frames_of_two_to_the_64_minus_one_decodes_as_one_chunk():
    data = vector("v1.3-chunk-frames-u64")
    decoder = Decoder(data)
    decoder.check()
    same = Decoder(vector("v1.3-lossless-float32")).positions()
    assert np.array_equal(decoder.positions().view(np.int64), same.view(np.int64))
    assert np.array_equal(decoder.positions(frames=[7]), same[[7]])
    assert tc.info(data).frames == same.shape[0]
