"""§6.2 Prediction: each entry of a quantized column minus its *parent*'s entry.

A column of U1 holds one coefficient per vertex, smooth over the surface; a column of U3 or of
the centroids is smooth in time. Storing each entry minus its parent's entry leaves small
residuals that compress far better. Parents always come earlier in the order, so the decoder
restores the values by summing residuals along the parent chain.

Two parent relations exist (§6.6 says which section uses which):

* mesh parents (U1): the breadth-first spanning forest of the face edges,
  :func:`tuckercodec.topology.mesh_parents` (it lives with the other rules of the face table);
* previous-row parents (U3, CENT): frame f's parent is frame f - 1, written ``parents=None``
  here.
"""

from __future__ import annotations

import numpy as np


def residuals(values: np.ndarray, parents: np.ndarray | None) -> np.ndarray:
    """Each row minus its parent's row; ``parents=None`` means the previous row (time)."""
    if parents is None:
        return np.diff(values, axis=0, prepend=np.zeros((1, *values.shape[1:]), values.dtype))
    out = values.copy()
    has = parents >= 0
    out[has] -= values[parents[has]]
    return out


def accumulate(residual: np.ndarray, parents: np.ndarray | None) -> np.ndarray:
    """The inverse of :func:`residuals`: each row plus all its ancestors' residuals.

    Along a tree this is done by pointer jumping: after pass p every row holds the sum over its
    2**p nearest ancestors, so a chain of depth d takes about log2(d) whole-array passes however
    the vertices are ordered.
    """
    if parents is None:
        return np.cumsum(residual, axis=0)
    total = residual.copy()
    ancestor = parents.copy()
    live = np.flatnonzero(ancestor >= 0)
    while live.size:
        jump = ancestor[live]
        total[live] += total[jump]  # the right side is read before any row is written
        ancestor[live] = ancestor[jump]
        live = live[ancestor[live] >= 0]
    return total
