"""The in-memory sequence (tuckercodec/sequence.py): MeshSequence checks its arrays as the
readers check a file's."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec import InputError, MeshSequence


def test_the_api_checks_what_the_npz_reader_checks() -> None:
    vertices = np.zeros((1, 3, 3))
    with pytest.raises(InputError, match=r"outside 0\.\.2"):  # not read as -1 padding
        MeshSequence(vertices, np.array([[0, 1, 2, 2**64 - 1]], dtype=np.uint64))
    if np.finfo(np.longdouble).max > np.finfo(np.float64).max:
        huge = np.full((1, 3, 3), np.finfo(np.longdouble).max, dtype=np.longdouble)
        with pytest.raises(InputError, match="non-finite"):  # and no RuntimeWarning
            MeshSequence(huge, np.zeros((0, 3), dtype=int))
