"""Connectivity, codec ``faces-delta`` (spec/FORMAT.md §6.4): faces round trip, and decoded
indices and padding are checked; tuckercodec/format/faces.py."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec import FormatError
from tuckercodec.format.faces import decode_faces, encode_faces


def test_faces_round_trip_and_checks():
    faces = np.array([[0, 1, 2, -1], [2, 1, 3, 4]])
    params, payload = encode_faces(faces)
    np.testing.assert_array_equal(decode_faces(payload, params, 5, "FACE"), faces)
    with pytest.raises(FormatError, match=r"outside 0\.\.3") as raised:
        decode_faces(payload, params, 4, "FACE")
    assert raised.value.rule == "R33-face-index"
    bad_params, bad_payload = encode_faces(np.array([[0, -1, 1, 2]]))
    with pytest.raises(FormatError, match="padded before its end") as raised:
        decode_faces(bad_payload, bad_params, 5, "FACE")
    assert raised.value.rule == "R34-face-padding"
