"""Sequences for the tests: synthetic animations, and the real sequences of ../shared/data
when present (a test that needs an absent one is skipped, saying why)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tuckercodec.samples import sheet_triangles, wave_sheet

SHARED_DATA = Path(__file__).resolve().parents[3] / "shared" / "data"


def shared_file(name: str) -> Path:
    """A file of ../shared/data, or skip the test saying why it is not there."""
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(
            f"{path} is absent: the real test sequences live in ../shared/data beside the repo"
        )
    return path


def load_shared_npz(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(V, F) of a sequence in ../shared/data, or skip."""
    with np.load(shared_file(name), allow_pickle=False) as data:
        return data["V"], data["F"]


def wave_sequence(frames: int = 24, grid: int = 9, seed: int = 0) -> np.ndarray:
    """A real-looking synthetic animation (:func:`tuckercodec.samples.wave_sheet`) plus a little
    noise so that no rank is exactly zero. Shape (frames, grid*grid, 3)."""
    rng = np.random.default_rng(seed)
    out = wave_sheet(frames, grid)
    return out + 1e-4 * rng.standard_normal(out.shape)


def grid_faces(grid: int = 9) -> np.ndarray:
    """Triangles of the grid sheet used by :func:`wave_sequence`."""
    return sheet_triangles(grid)
