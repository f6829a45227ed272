"""Error and rate measures of the dynamic-mesh compression literature.

Every function says which definition it computes. The default error is the KG error of
Karni and Gotsman (2004), the one every published comparison uses::

    KG = 100 * ||A - A~|| / ||A - E(A)||

where ||.|| is the Frobenius norm over all frames, vertices and axes, and E(A) holds each
frame's mean vertex position (the per-frame, per-axis mean over vertices). The seed paper's
formula reads as if E(A) held each vertex's mean position over time; that variant gives
different numbers and is available only by name (``mean="temporal"``).

The perception-correlated STED error of Váša and Skala (2011) is in :mod:`tuckercodec.perceptual`;
the rate measure bpfv in :mod:`tuckercodec.rate`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .errors import InputError
from .sequence import MeshSequence

KG_DEFINITION = "KG (Karni-Gotsman 2004): 100*||A-B||_F / ||A - per-frame vertex mean of A||_F"

MeanKind = Literal["frame", "temporal"]


def _positions(x: MeshSequence | np.ndarray) -> np.ndarray:
    array = x.vertices if isinstance(x, MeshSequence) else np.asarray(x, dtype=np.float64)
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"expected positions of shape (frames, vertices, 3), got {array.shape}")
    return array


def _pair(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    a, b = _positions(original), _positions(approx)
    if a.shape != b.shape:
        raise InputError(f"the sequences differ in shape: {a.shape} against {b.shape}")
    return a, b


def kg_denominator(original: MeshSequence | np.ndarray, *, mean: MeanKind = "frame") -> float:
    """||A - E(A)||_F: the norm the KG error divides by (see the module docstring)."""
    a = _positions(original)
    if mean == "frame":
        centred = a - a.mean(axis=1, keepdims=True)
    elif mean == "temporal":
        centred = a - a.mean(axis=0, keepdims=True)
    else:
        raise ValueError(f"mean must be 'frame' or 'temporal', got {mean!r}")
    norm = float(np.linalg.norm(centred))
    if norm == 0.0:
        if mean == "frame":
            raise InputError(
                "the KG error is undefined: every frame collapses to a single point, so the "
                "Karni-Gotsman denominator is zero"
            )
        raise InputError(
            "the temporal-mean KG error is undefined: no vertex ever moves, so its denominator "
            "is zero (the Karni-Gotsman definition, mean='frame', is defined here)"
        )
    return norm


def kg_error(
    original: MeshSequence | np.ndarray,
    approx: MeshSequence | np.ndarray,
    *,
    mean: MeanKind = "frame",
) -> float:
    """The KG error of ``approx`` against ``original``, in percent.

    ``mean="frame"`` (default) is the Karni-Gotsman definition; ``mean="temporal"`` divides by
    the distance from each vertex's temporal mean instead.
    """
    a, b = _pair(original, approx)
    return 100.0 * float(np.linalg.norm(a - b)) / kg_denominator(a, mean=mean)


def relative_error(original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray) -> float:
    """||A - B||_F / ||A||_F, uncentred (depends on where the scene's origin is)."""
    a, b = _pair(original, approx)
    norm = float(np.linalg.norm(a))
    if norm == 0.0:
        raise InputError("the relative error is undefined: every position of the original is 0")
    return float(np.linalg.norm(a - b)) / norm


@dataclass(frozen=True)
class Displacement:
    """The largest Euclidean distance between matching vertices, and where it occurs."""

    distance: float
    frame: int
    vertex: int


def max_vertex_displacement(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> Displacement:
    """The largest ||a_fk - b_fk||_2 over all frames f and vertices k, in scene units."""
    a, b = _pair(original, approx)
    distances = np.linalg.norm(a - b, axis=2)
    frame, vertex = np.unravel_index(int(np.argmax(distances)), distances.shape)
    return Displacement(float(distances[frame, vertex]), int(frame), int(vertex))


def per_frame_max_displacement(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> np.ndarray:
    """Each frame's worst vertex: max over k of ||a_fk - b_fk||_2, in scene units, shape (F,)."""
    a, b = _pair(original, approx)
    return np.sqrt(np.max(np.einsum("fkx,fkx->fk", a - b, a - b), axis=1))


def per_frame_kg(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> np.ndarray:
    """Each frame's share of the KG error: 100*||A_f - B_f|| / ||A - E(A)|| (whole-sequence
    Karni-Gotsman denominator), so that the squares of these values sum to KG**2."""
    a, b = _pair(original, approx)
    return 100.0 * np.linalg.norm((a - b).reshape(a.shape[0], -1), axis=1) / kg_denominator(a)
