"""The in-memory sequence (tuckercodec/model/sequence.py): MeshSequence checks its arrays (shape,
finite positions, the face rule of tuckercodec/model/topology.py, frame names) as the readers check
a file's."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec import InputError, MeshSequence


def test_sequence_checks_its_arrays():
    vertices = np.zeros((2, 4, 3))
    quads = np.array([[0, 1, 2, 3], [0, 1, 2, -1]])
    seq = MeshSequence(vertices, quads)
    assert seq.frame_names == ["frame_00000", "frame_00001"]
    assert seq.triangles().tolist() == [[0, 1, 2], [0, 1, 2], [0, 2, 3]]
    with pytest.raises(InputError, match=r"outside 0\.\.3"):
        MeshSequence(vertices, np.array([[0, 1, 4]]))
    with pytest.raises(InputError, match="padded before its end"):
        MeshSequence(vertices, np.array([[0, -1, 1, 2]]))
    bad = vertices.copy()
    bad[1, 2, 0] = np.inf
    with pytest.raises(InputError, match="frame 1: vertex 2 has a non-finite"):
        MeshSequence(bad, quads)
    with pytest.raises(InputError, match="shape"):
        MeshSequence(np.zeros((4, 3)), quads)
    with pytest.raises(InputError, match="frame names"):
        MeshSequence(vertices, quads, frame_names=["a"])


def test_the_api_checks_what_the_npz_reader_checks() -> None:
    vertices = np.zeros((1, 3, 3))
    with pytest.raises(InputError, match=r"outside 0\.\.2"):  # not read as -1 padding
        MeshSequence(vertices, np.array([[0, 1, 2, 2**64 - 1]], dtype=np.uint64))
    if np.finfo(np.longdouble).max > np.finfo(np.float64).max:
        huge = np.full((1, 3, 3), np.finfo(np.longdouble).max, dtype=np.longdouble)
        with pytest.raises(InputError, match="non-finite"):  # and no RuntimeWarning
            MeshSequence(huge, np.zeros((0, 3), dtype=int))
