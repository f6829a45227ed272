"""§8 Reconstruction: the decoded positions from the dequantized factors.

::

    positions[f, v, x] = sum_{a,c,b} U1[v, a] * CORE[a, c, b] * U2[x, c] * U3[f, b] + CENT[f, x]

The encoder measures its error with these same functions, so that it measures exactly what a
decoder returns.
"""

from __future__ import annotations

import numpy as np


def factor_value_count(vertices: int, frames: int, i: int, k: int) -> int:
    """The numbers a file with ranks (i, k) stores: U1, U3, the core and the centroids (the
    ``max_factor_values`` limit of §7 counts these)."""
    return vertices * i + frames * k + 3 * i * k + 3 * frames


def reconstruction_basis(core: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """``B[a, x, b] = sum_c CORE[a, c, b] * U2[x, c]``, shape (i, 3, k): formed once, it leaves
    each frame one product with U3's row and one with U1."""
    return np.einsum("acb,xc->axb", core, u2)


def reconstruct_frames(
    u1: np.ndarray,
    basis: np.ndarray,
    u3_rows: np.ndarray,
    centroid_rows: np.ndarray,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Positions (n, K, 3) of the frames whose U3 rows (n, k) and centroids (n, 3) are given,
    written into ``out`` if given (the decoder's output array: no copy of every frame)."""
    i = u1.shape[1]
    weights = basis @ u3_rows.T  # (i, 3, n)
    flat = u1 @ weights.reshape(i, -1)  # (K, 3n)
    frames = flat.reshape(u1.shape[0], 3, len(u3_rows)).transpose(2, 0, 1)
    return np.add(frames, centroid_rows[:, None, :], out=out)
