"""The built-in sample sequence, shipped inside the package so that the codec can be tried
on a real animated mesh right after installation."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

SAMPLE_NAME = "cloth-vellum"


def sample_path() -> Path:
    """Path of the built-in sample: a simulated cloth, 60 frames of 3101 vertices (MIT licence,
    see ``cloth-vellum.LICENSE.txt`` beside it)."""
    return Path(str(resources.files("tuckercodec") / "data" / f"{SAMPLE_NAME}.npz"))


def wave_sheet(frames: int = 24, grid: int = 9) -> np.ndarray:
    """A synthetic animation for tests and examples: a square sheet of grid x grid vertices with
    travelling waves, drifting and turning. Shape (frames, grid*grid, 3); faces from
    :func:`sheet_triangles`."""
    u_grid, v_grid = np.meshgrid(np.linspace(0, 1, grid), np.linspace(0, 1, grid), indexing="ij")
    u, v = u_grid.ravel(), v_grid.ravel()
    out = np.empty((frames, u.size, 3))
    for f in range(frames):
        t = f / frames
        z = 0.2 * np.sin(2 * np.pi * (u + t)) * np.cos(np.pi * (v - 0.5 * t))
        angle = 0.5 * t
        x = u * np.cos(angle) - v * np.sin(angle) + 0.3 * t
        y = u * np.sin(angle) + v * np.cos(angle)
        out[f] = np.stack([x, y, z], axis=1)
    return out


def sheet_triangles(grid: int = 9) -> np.ndarray:
    """The triangles of :func:`wave_sheet`'s grid, (2*(grid-1)**2, 3)."""
    index = np.arange(grid * grid).reshape(grid, grid)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
