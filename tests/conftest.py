"""Shared fixtures: synthetic sequences, and the real sequences of ../shared/data when present."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def shared_file(name: str) -> Path:
    """A file of ../shared/data, or skip the test saying why it is not there."""
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(f"{path} is absent: the real test sequences live in ../shared/data beside the repo")
    return path


def load_shared_npz(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(V, F) of a sequence in ../shared/data, or skip."""
    with np.load(shared_file(name), allow_pickle=False) as data:
        return data["V"], data["F"]


def wave_sequence(frames: int = 24, grid: int = 9, seed: int = 0) -> np.ndarray:
    """A real-looking synthetic animation: a grid sheet with travelling waves, drifting and
    turning, plus a little noise so that no rank is exactly zero. Shape (frames, grid*grid, 3)."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, grid), np.linspace(0, 1, grid), indexing="ij")
    u, v = u.ravel(), v.ravel()
    out = np.empty((frames, u.size, 3))
    for f in range(frames):
        t = f / frames
        z = 0.2 * np.sin(2 * np.pi * (u + t)) * np.cos(np.pi * (v - 0.5 * t))
        angle = 0.5 * t
        x = u * np.cos(angle) - v * np.sin(angle) + 0.3 * t
        y = u * np.sin(angle) + v * np.cos(angle)
        out[f] = np.stack([x, y, z], axis=1)
    return out + 1e-4 * rng.standard_normal(out.shape)


def grid_faces(grid: int = 9) -> np.ndarray:
    """Triangles of the grid sheet used by :func:`wave_sequence`."""
    index = np.arange(grid * grid).reshape(grid, grid)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
