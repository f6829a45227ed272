"""The morph animation's numbers as the file stores them, rounded within an error budget.

The budget: the glTF may add an error of at most :data:`BUDGET_SHARE` (0.32) times the
compressed file's recorded KG error, measured against the file's own decode. Rounding noise is
independent of the truncation error the file already has, so the two add in quadrature: the
viewer's KG error against the original is then about ``KG · sqrt(1 + 0.32²) = 1.05 · KG``
(0.105 for a file at KG 0.1), whatever the sequence; the benchmark measures it against the
original. A file that records no KG error gets a budget of :data:`FALLBACK_BUDGET_KG`.

Frame f as a viewer shows it (world units): ``t_f + o + S · (b + Σ_b w_fb · q_b / 32767)``,
``t_f`` the root's translation track, ``o`` and ``S`` the child node's translation and uniform
scale (KHR_mesh_quantization's dequantization), ``b`` the base mesh in local units, ``q_b`` the
targets as normalized 16-bit integers, ``w_fb`` the weights. What keeps the numbers small:

* Offsets: target b is stored shifted by a constant per axis ``lo_b`` (its minimum with
  ``filters``, so every integer is >= 0, which EXT_meshopt_compression's byte-wise deltas
  compress about 10% better than signed ones; else its mid-range, so the finest step fits).
  The shift moves the whole mesh rigidly by ``Σ_b w_fb lo_b`` at frame f, which the translation
  track takes: ``t_f = c_f + Σ_b w_fb lo_b``.
* Compensation: the base is fitted after the targets and weights are rounded, as the
  least-squares base of the frames they then give, ``mean_f(decoded_f - t_f - Σ_b w_fb T_b)``.
  The part of each target's rounding error carried by its weight's mean (weights in 0..1
  average about one half) goes into the base; only the part that varies with the weights
  remains: ``Σ_b var(w_b)`` instead of ``Σ_b mean(w_b²)``, a tenth on chicken and a third on
  the cloth sample.
* Shares (``filters``, for the meshopt variant): at high rate the stored numbers are smallest
  for a given error when each adds the same error (reverse water-filling), so each of the N
  numbers gets ``1/N`` of the budget. The weights of target b, the base and the translation
  are float32 with meshopt's EXPONENTIAL filter, rounded to the power-of-two step that meets
  their share (a weight's error moves every vertex by its target, ``||T_b||²``; the base's is
  in every frame, ``F``; the translation's moves every vertex, ``K``). The targets share one
  step (the node's scale), the coarsest whose exact rounding error, weighted by each weight's
  variance over time, fits what the others left.

Without ``filters`` (the quantize variant, whose size does not depend on the values) the
targets and base take the finest 16-bit step, and the weights the narrowest normalized type
(UNSIGNED_BYTE, UNSIGNED_SHORT, else float32) that keeps the whole within the budget.

Either way the result is checked by evaluating the animation exactly as a viewer does, in
float64 from the stored numbers (float32 weights and translations); the targets' allowance
shrinks until it fits. If the finest 16-bit step misses, the caller keeps float32 positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..measures.distortion import kg_denominator

#: The glTF's own quantization error may be this share of the file's recorded KG error: added
#: in quadrature, it makes the viewer's error 1.05 times the file's.
BUDGET_SHARE = math.sqrt(1.05**2 - 1)
#: The budget (KG, percent) when the file records no KG error.
FALLBACK_BUDGET_KG = 0.03
_LIMIT = 32767  # normalized SHORT: q / 32767
_MANTISSA = 1 << 23  # the EXPONENTIAL filter's signed 24-bit mantissa
_TINY = float(np.finfo(np.float64).tiny)
_CHECKS = 8  # exact evaluations before giving up on 16 bits
#: The normalized weight types without filters, narrowest first: (numpy type, largest code).
_WEIGHT_TYPES = ((np.uint8, 255), (np.uint16, 65535))


@dataclass(frozen=True)
class QuantizedAnimation:
    """The numbers of a quantized morph animation, as stored.

    ``targets`` (k, K, 3) int16, normalized. ``base`` (K, 3) in local units: int16 normalized,
    or float32 multiples of ``2**base_exponents`` (per axis) for the EXPONENTIAL filter.
    ``weights`` (F, k): uint8 or uint16 normalized, or float32 (multiples of
    ``2**weight_exponents`` per target when filtered). ``translation`` (F, 3) float32, the
    root's track (multiples of ``2**translation_exponents`` when filtered). ``offset`` and
    ``scale``: the child node's translation and uniform scale; ``step``: the targets' step in
    scene units (``scale / 32767``)."""

    base: np.ndarray
    targets: np.ndarray
    weights: np.ndarray
    translation: np.ndarray
    offset: np.ndarray
    scale: float
    step: float
    budget_kg: float
    kg: float  # the error of the stored animation against the decode, as checked
    base_exponents: np.ndarray | None = None
    weight_exponents: np.ndarray | None = None
    translation_exponents: np.ndarray | None = None


def budget(recorded_kg: float | None) -> float:
    """The KG error the glTF's quantization may add, from the file's recorded KG error."""
    if recorded_kg is None or not math.isfinite(recorded_kg) or recorded_kg <= 0:
        return FALLBACK_BUDGET_KG
    return BUDGET_SHARE * recorded_kg


def quantize_animation(
    base: np.ndarray,
    targets: np.ndarray,
    weights: np.ndarray,
    centroids: np.ndarray,
    decoded: np.ndarray,
    recorded_kg: float | None,
    *,
    filters: bool = False,
) -> QuantizedAnimation | None:
    """The stored numbers of frame ``f = centroids[f] + base + Σ_b weights[f, b] · targets[b]``
    within the budget against ``decoded`` (module docstring), or ``None`` if 16 bits cannot.

    ``filters``: the meshopt variant's rules (EXPONENTIAL filter, coarsest target step);
    without, the quantize variant's (finest step, normalized weights)."""
    allowed = budget(recorded_kg)
    denominator = kg_denominator(decoded)
    problem = _Problem(base, targets, weights, centroids, decoded, allowed, denominator)
    for stored, exponents in problem.weight_options(filters):
        fitted = problem.fit(stored, exponents, filters)
        if fitted is not None:
            return fitted
    return None


class _Problem:
    """One animation to store: its parts, the budget as a squared error, and the share of it
    each stored number may add (module docstring)."""

    def __init__(
        self,
        base: np.ndarray,
        targets: np.ndarray,
        weights: np.ndarray,
        centroids: np.ndarray,
        decoded: np.ndarray,
        allowed_kg: float,
        denominator: float,
    ) -> None:
        self.base, self.targets, self.weights = base, targets, weights
        self.centroids, self.decoded, self.denominator = centroids, decoded, denominator
        self.allowed_kg = allowed_kg
        self.energy = (allowed_kg / 100 * denominator) ** 2
        frames, count = weights.shape
        vertices = len(base)
        self.share = self.energy / (3 * vertices * (count + 1) + frames * (count + 3))
        # a weight's error moves every vertex by its target, less what the base takes
        self.norms = np.einsum("bvx,bvx->b", targets, targets) * (1 - 1 / frames)
        self.offset = (base.min(axis=0) + base.max(axis=0)) / 2

    def weight_options(self, filters: bool) -> list[tuple[np.ndarray, np.ndarray | None]]:
        """The weights as they may be stored, most compact first, with their exponents."""
        if filters:
            exponents = _exponents(self.weights, self.share / np.maximum(self.norms, _TINY), 0)
            return [(_round_to(self.weights, exponents).astype(np.float32), exponents)]
        options: list[tuple[np.ndarray, np.ndarray | None]] = []
        for kind, top in _WEIGHT_TYPES:
            stored = np.round(self.weights * top).astype(kind)
            if self._weight_error(stored) <= self.energy:  # else the check cannot pass
                options.append((stored, None))
        options.append((self.weights.astype(np.float32), None))
        return options

    def _weight_error(self, stored: np.ndarray) -> float:
        """The squared error the stored weights add, after the base takes its mean."""
        error = weight_values(stored) - self.weights
        error -= error.mean(axis=0)
        return float(np.einsum("fb,fb,b->", error, error, self.norms))

    def fit(
        self, stored: np.ndarray, exponents: np.ndarray | None, filters: bool
    ) -> QuantizedAnimation | None:
        """Targets, translation and the fitted base for these weights, checked; or None."""
        shown = weight_values(stored)
        spread = shown - shown.mean(axis=0)
        variance = np.einsum("fb,fb->b", spread, spread)  # what a target's error is worth
        targets = self.targets
        if filters:  # every integer >= 0
            lo = targets.min(axis=1)
            spans = targets.max(axis=1) - lo
            finest = max(float(spans.max(initial=0.0)), _TINY) / _LIMIT
        else:  # centred: the finest step fits
            lo = (targets.min(axis=1) + targets.max(axis=1)) / 2
            extent = 1.001 * float(np.abs(self.base - self.offset).max(initial=0.0))
            spans = targets.max(axis=1) - targets.min(axis=1)
            finest = max(2 * extent, float(spans.max(initial=0.0)), _TINY) / (2 * _LIMIT)
        frames, count = shown.shape
        vertices = len(self.base)
        others = self._weight_error(stored) + self.share * 3 * (vertices + frames)
        allowance = self.energy - others
        for _ in range(_CHECKS):
            step = self._coarsest(lo, variance, finest, allowance) if filters else finest
            scale = step * _LIMIT
            low = 0 if filters else -_LIMIT
            q = np.clip(np.round((targets - lo[:, None, :]) / step), low, _LIMIT).astype(np.int16)
            moves = shown @ (q.reshape(count, 3 * vertices) * (scale / _LIMIT))
            moves = moves.reshape(frames, vertices, 3)
            translation = (self.centroids + shown @ lo).astype(np.float32)
            t_exp = None
            if filters:
                t_exp = _exponents(translation, np.full(3, self.share / vertices), 127)
                translation = _round_to(translation, t_exp).astype(np.float32)
            placed = translation.astype(np.float64)[:, None, :] + moves
            fitted = (self.decoded - placed).mean(axis=0)  # the least-squares base
            local = (fitted - self.offset) / scale
            b_exp = None
            if filters:
                b_exp = _exponents(local, np.full(3, self.share / frames / scale**2), 127)
                base = _round_to(local, b_exp).astype(np.float32)
                base_local = base.astype(np.float64)
            else:
                base = np.clip(np.round(local * _LIMIT), -_LIMIT, _LIMIT).astype(np.int16)
                base_local = base / _LIMIT
            placed += self.offset + scale * base_local
            error = float(np.sum((placed - self.decoded) ** 2))
            if error <= self.energy:
                return QuantizedAnimation(
                    base=base,
                    targets=q,
                    weights=stored,
                    translation=translation,
                    offset=self.offset,
                    scale=scale,
                    step=step,
                    budget_kg=self.allowed_kg,
                    kg=100.0 * math.sqrt(error) / self.denominator,
                    base_exponents=b_exp,
                    weight_exponents=exponents,
                    translation_exponents=t_exp,
                )
            if not filters or step <= finest:
                return None
            allowance *= 0.9 * self.energy / error
        return None

    def _coarsest(
        self, lo: np.ndarray, variance: np.ndarray, finest: float, allowance: float
    ) -> float:
        """The coarsest step whose rounding error of the targets (each weighted by its weight's
        variance over time) is within ``allowance``, by bisection of its logarithm."""
        shifted = self.targets - lo[:, None, :]

        def error(step: float) -> float:
            residual = np.round(shifted / step) * step - shifted
            return float(np.einsum("bvx,bvx,b->", residual, residual, variance))

        if error(finest) > allowance:
            return finest
        low, high = math.log(finest), math.log(max(float(shifted.max(initial=0.0)), finest) * 2)
        for _ in range(14):
            middle = (low + high) / 2
            low, high = (middle, high) if error(math.exp(middle)) <= allowance else (low, middle)
        return math.exp(low)


def weight_values(stored: np.ndarray) -> np.ndarray:
    """The weights a viewer animates with: normalized integers over their largest code, and
    like every animation value a float32 (three.js keeps them in a Float32Array)."""
    if stored.dtype == np.float32:
        return stored.astype(np.float64)
    top = float(np.iinfo(stored.dtype).max)
    return (stored / top).astype(np.float32).astype(np.float64)


def _exponents(values: np.ndarray, allowed: np.ndarray, largest: int) -> np.ndarray:
    """Per column of ``values`` (n, m): the exponent of the coarsest power-of-two step whose
    uniform rounding noise (step²/12) is at most ``allowed`` (m,), at most ``largest``; but
    never so fine that a value leaves the EXPONENTIAL filter's 24-bit mantissa, nor below
    float32's smallest normal exponent."""
    with np.errstate(divide="ignore"):
        wanted = np.floor(0.5 * np.log2(12 * np.maximum(allowed, _TINY)))
        magnitude = np.abs(values).max(axis=0, initial=0.0)
        least = np.ceil(np.log2(np.maximum(magnitude, _TINY) * 2 / _MANTISSA))
    return np.clip(np.maximum(wanted, least), -126, min(largest, 127)).astype(np.int64)


def _round_to(values: np.ndarray, exponents: np.ndarray) -> np.ndarray:
    """``values`` rounded to multiples of ``2**exponents`` (broadcast over the last axis)."""
    step = np.ldexp(1.0, exponents)
    return np.round(values / step) * step
