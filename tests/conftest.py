"""The fixtures the test modules share. Helpers they import live in :mod:`tests.support`."""

from __future__ import annotations

import pytest

import tuckercodec
from tuckercodec import MeshSequence
from tuckercodec.samples import sample_path


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    """The cloth that ships with the package (60 frames of 3101 vertices)."""
    return tuckercodec.load_sequence(sample_path(), progress=False)
