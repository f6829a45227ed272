"""The decoder's random access (spec/FORMAT.md §8): any range or selection of frames decodes to
the same positions as the whole sequence, and a selection that names no frame is refused."""

from __future__ import annotations

import numpy as np
import pytest

import tuckercodec as tc
from tuckercodec import decode, encode
from tuckercodec.format.reconstruction import reconstruct_frames


def test_frame_ranges_match_the_whole(cloth):
    data = encode(cloth, target_kg=0.5)
    whole = decode(data).vertices
    decoder = tc.Decoder(data)
    np.testing.assert_allclose(
        decode(data, frames=range(10, 20)).vertices, whole[10:20], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(
        decode(data, frames=slice(50, None)).vertices, whole[50:], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(decoder.frame(7), whole[7], rtol=0, atol=1e-12)
    partial = decode(data, frames=[3, 1])
    assert partial.frame_names == [cloth.frame_names[3], cloth.frame_names[1]]
    with pytest.raises(ValueError, match="frame 60 does not exist"):
        decode(data, frames=[60])


def test_frame_selections(cloth):
    decoder = tc.Decoder(encode(cloth, target_kg=1.0))
    assert decoder.frame_indices(-1).tolist() == [59]  # negative numbers count from the end
    assert decoder.frame_indices(slice(-3, None)).tolist() == [57, 58, 59]
    for bad in ([1.5], "12", np.array([True, False])):
        with pytest.raises(TypeError):
            decoder.positions(bad)  # type: ignore[arg-type]  # what is refused
    with pytest.raises(ValueError, match="names no frame"):
        decoder.positions(slice(5, 2))
    with pytest.raises(ValueError, match="does not exist"):
        decoder.positions([2**70])


def test_a_run_of_frames_written_in_place_is_bit_for_bit_the_frames_made_apart(cloth):
    """positions() writes a run of one segment's frames straight into its output
    (reconstruct_frames(out=)); any other selection is made apart and copied in: the same
    bits as reconstruct_frames returns for those frames. (Frames decoded in different groups
    can differ in the last bits: BLAS sums a product of another shape in another order.)"""
    decoder = tc.Decoder(encode(cloth, target_kg=0.5))
    part = decoder.segment_factors(0)
    for frames in (range(60), range(10, 20), [19, 3, 11], [5, 6, 8]):
        chosen = np.asarray(frames)
        apart = reconstruct_frames(part.u1, part.basis, part.u3[chosen], part.centroids[chosen])
        assert np.array_equal(decoder.positions(frames), apart)
