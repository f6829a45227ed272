"""The rate (tuckercodec/measures/rate.py): bits per frame per vertex, from whole bytes."""

from __future__ import annotations

import pytest

from tuckercodec.measures.rate import bpfv


def test_bpfv_counts_whole_bytes():
    assert bpfv(1000, frames=10, vertices=100) == pytest.approx(8.0)
    with pytest.raises(ValueError, match="must be positive"):
        bpfv(10, frames=0, vertices=5)
