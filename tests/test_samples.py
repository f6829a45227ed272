"""The built-in sample (tuckercodec/io/samples.py): the cloth the package ships is the shared cloth
sequence, unchanged, with its licence."""

from __future__ import annotations

import numpy as np

import tuckercodec
from tests.support.sequences import load_shared_npz
from tuckercodec.io.samples import sample_path


def test_builtin_sample_is_the_shared_cloth_unchanged():
    shipped = tuckercodec.load_sequence(sample_path(), progress=False)
    vertices, faces = load_shared_npz("cloth-vellum.npz")
    np.testing.assert_array_equal(shipped.vertices, vertices.astype(np.float64))
    np.testing.assert_array_equal(shipped.faces, faces)
    assert (sample_path().parent / "cloth-vellum.LICENSE.txt").read_text().count("MIT License") == 1
