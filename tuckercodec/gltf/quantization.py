"""Positions as normalized 16-bit integers (KHR_mesh_quantization), with the step chosen from
an error budget.

The budget: the glTF may add an error of at most :data:`BUDGET_SHARE` (0.32) times the
compressed file's recorded KG error, measured against the file's own decode. Rounding noise is
independent of the truncation error the file already has, so the two add in quadrature: the
viewer's KG error against the original is then about ``KG · sqrt(1 + 0.32²) = 1.05 · KG``
(0.105 for a file at KG 0.1), whatever the sequence. (The triangle inequality alone would
guarantee it only with a share of 0.05, which 16-bit positions cannot meet on long sequences
with many targets such as chicken; the benchmark measures the result against the original.)
A file that records no KG error gets a budget of :data:`FALLBACK_BUDGET_KG`.

One step ``Δ`` serves the three axes, the mesh and every morph target (they share the node's
dequantization): ``x = offset + Δ · q`` for the mesh, ``T = Δ · q`` for a target. The finest
step that fits every value in ±32767 is used, or with ``coarse`` (for EXT_meshopt_compression,
whose codec gains from fewer significant bits) the coarsest the budget allows, predicted from
uniform rounding noise (variance Δ²/12 per stored number, weighted by the frames' weights)
and then checked: the animation is evaluated exactly as a viewer will, in float64 from the
stored integers and float32 weights, and the step is shrunk until the error is within budget.
If even the finest 16-bit step misses it, the caller keeps float32 positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..metrics import kg_denominator

#: The glTF's own quantization error may be this share of the file's recorded KG error: added
#: in quadrature, it makes the viewer's error 1.05 times the file's.
BUDGET_SHARE = math.sqrt(1.05**2 - 1)
#: The budget (KG, percent) when the file records no KG error.
FALLBACK_BUDGET_KG = 0.03
_LIMIT = 32767  # normalized SHORT: q / 32767


@dataclass(frozen=True)
class Quantized:
    """The mesh (K, 3) and targets (k, K, 3) as int16; dequantized by the child node's
    ``translation`` (``offset``) and uniform ``scale`` (``step x 32767``)."""

    base: np.ndarray
    targets: np.ndarray
    offset: np.ndarray
    scale: float
    step: float
    budget_kg: float
    kg: float  # the error of the quantized animation against the decode, as checked


def budget(recorded_kg: float | None) -> float:
    """The KG error the glTF's quantization may add, from the file's recorded KG error."""
    if recorded_kg is None or not math.isfinite(recorded_kg) or recorded_kg <= 0:
        return FALLBACK_BUDGET_KG
    return BUDGET_SHARE * recorded_kg


def quantize_positions(
    base: np.ndarray,
    targets: np.ndarray,
    weights: np.ndarray,
    centroids: np.ndarray,
    decoded: np.ndarray,
    recorded_kg: float | None,
    *,
    coarse: bool = False,
) -> Quantized | None:
    """Quantize the mesh and targets within the budget, or ``None`` if 16 bits cannot."""
    allowed = budget(recorded_kg)
    denominator = kg_denominator(decoded)
    offset = (base.min(axis=0) + base.max(axis=0)) / 2
    extent = max(float(np.abs(base - offset).max()), float(np.abs(targets).max(initial=0.0)))
    finest = max(extent, np.finfo(np.float64).tiny) / _LIMIT
    step = finest
    if coarse:
        noise = np.sqrt(base.size / 12 * np.sum(1 + np.sum(weights**2, axis=1)))
        step = max(finest, allowed / 100 * denominator / noise)
    weights32 = weights.astype(np.float32).astype(np.float64)
    moved = decoded - centroids.astype(np.float32).astype(np.float64)[:, None, :]
    while True:
        scale = float(step * _LIMIT)
        q_base = np.clip(np.round((base - offset) / step), -_LIMIT, _LIMIT).astype(np.int16)
        q_targets = np.clip(np.round(targets / step), -_LIMIT, _LIMIT).astype(np.int16)
        kg = _error(q_base, q_targets, weights32, offset, scale, moved, denominator)
        if kg <= allowed:
            return Quantized(q_base, q_targets, offset, scale, step, allowed, kg)
        if step <= finest:
            return None
        step = max(finest, step * 0.7)


def _error(
    q_base: np.ndarray,
    q_targets: np.ndarray,
    weights: np.ndarray,
    offset: np.ndarray,
    scale: float,
    moved: np.ndarray,
    denominator: float,
) -> float:
    """The KG error of the quantized animation against the decode, evaluated as the reader
    evaluates the file (normalized integers over 32767, then the node's scale and offset)."""
    local = q_base / _LIMIT + (weights @ (q_targets / _LIMIT).reshape(len(q_targets), -1)).reshape(
        len(weights), *q_base.shape
    )
    shown = offset + scale * local
    return 100.0 * float(np.linalg.norm(shown - moved)) / denominator
