"""The decomposition of a segmented encode, made in the sketch's r dimensions, and its choices.

After the passes, the whole sequence is known in r dimensions: W_t = Q' X_t (r x 3) for every
frame, with Q (K x r) orthonormal, and the exact energy ||X_t||^2 of every centred frame. From
there everything is small:

* **U1.** With a shared basis, U1 = Q V, where V holds the left singular vectors of W's mode-1
  unfolding (r x 3F): the HOSVD's U1 of the sequence as the sketch sees it. With a basis per
  segment, the same within each segment, from its own Q.
* **Each segment.** T_s = V' W_s (r x 3 x n) has its own U2 and U3 (the HOSVD of modes 2 and 3)
  and core G_s. The factors are orthonormal, so the squared error of keeping (i, k) is exact:
  the residual outside Q (||X_s||^2 - ||W_s||^2, from the passes) plus the core's energy outside
  G_s[:i, :, :k].
* **Ranks.** The cheapest ranks whose truncation errors add up to a budget: per segment a
  Lagrangian choice (stored numbers + lambda * error), lambda bisected to meet the budget, for
  every shared i (the shared basis) or jointly with each segment's own i.
* **The error model.** For quantized factors, the decoded error is computed in r dimensions
  from a few small products (:func:`model_error2`), exact but for one cross term between the
  residual outside Q and the quantization noise of U1, which is tiny and has no sign; the
  measuring pass then confirms it on the input itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...decomposition.analysis import discarded_energy

#: Bisection steps of the Lagrange multiplier (on its logarithm, from 1e-12 to 1e12).
LAMBDA_STEPS = 60


#: Directions of the sketch weaker than this, relative to its strongest (in squared norm), are
#: dropped: the Gram matrix's eigenvalues are exact only to about 1e-16 of the largest, so
#: weaker ones are rounding (the sequence's energy there is below 1e-13 of the total, far below
#: any KG target's square).
NEGLIGIBLE_DIRECTION = 1e-13
#: Rows of the sketch transformed at once (a small scratch array, whatever K).
ROWS_AT_ONCE = 8192


def orthonormal_columns(sketch: np.ndarray) -> np.ndarray:
    """Q with orthonormal columns spanning ``sketch``'s strong directions (K x r', C order; the
    sketch, in any order, is left unchanged).

    By the eigenvectors of the small Gram matrix, twice (CholeskyQR2 with the weak directions
    dropped): Q1 = Y V L^-1/2 keeps every direction above :data:`NEGLIGIBLE_DIRECTION`, and a
    second pass makes Q1 orthonormal to rounding. Every step is a matrix product (about 2 s in
    all for 200,000 x 256, against 10 s for Householder QR, whose panels are not), and the
    refinements transform Q's rows a block at a time in place: one K x r array beside the
    sketch, never two.
    """
    values, vectors = np.linalg.eigh(sketch.T @ sketch)
    keep = values > NEGLIGIBLE_DIRECTION * max(float(values.max(initial=0.0)), 1e-300)
    if not keep.any():  # a sketch of nothing: one column, any direction
        q = np.zeros((sketch.shape[0], 1))
        q[0, 0] = 1.0
        return q
    transform = vectors[:, keep] / np.sqrt(values[keep])
    q = sketch @ transform  # one product into a new C-order array: rows then change in place
    for _ in range(2):  # each pass squares the loss of orthogonality: two reach rounding
        try:
            factor = np.linalg.cholesky(q.T @ q)  # Q'Q = L L', and Q L^-T is orthonormal
        except np.linalg.LinAlgError:  # not expected once weak directions are gone
            import scipy.linalg  # here: 0.17 s at start-up that only this fallback needs

            householder: np.ndarray = scipy.linalg.qr(q, mode="economic", check_finite=False)[0]
            return householder
        q = _rows_times(q, np.linalg.inv(factor).T)
    return q


def _rows_times(matrix: np.ndarray, transform: np.ndarray) -> np.ndarray:
    """``matrix @ transform`` written over ``matrix``'s own rows, a block of rows at a time (each
    block is read whole before its rows are written), returned as a view of its first columns:
    the result has at most as many columns as ``matrix``."""
    columns = transform.shape[1]
    for start in range(0, matrix.shape[0], ROWS_AT_ONCE):
        rows = slice(start, start + ROWS_AT_ONCE)
        matrix[rows, :columns] = matrix[rows] @ transform
    return matrix[:, :columns]


@dataclass(eq=False)
class SegmentModel:
    """One segment's decomposition in the sketch's coordinates.

    Attributes:
        start, stop: the segment's frames.
        coefficients: W_s = Q' X_t, (r, 3, n), in the coordinates of the segment's Q.
        rotation: V (r, r'): U1 = Q V (the shared Q and V, or the segment's own).
        u2: (3, 3); u3: (n, k_max) orthonormal columns; core: G_s (r', 3, k_max).
        energies: ||X_t||^2 per frame; centroids: (n, 3).
        error_table: [i, k] the squared error of keeping (i, k), for i in 0..r', k in 0..k_max.
    """

    start: int
    stop: int
    coefficients: np.ndarray
    rotation: np.ndarray
    u2: np.ndarray
    u3: np.ndarray
    core: np.ndarray
    energies: np.ndarray
    centroids: np.ndarray
    error_table: np.ndarray

    @property
    def frames(self) -> int:
        return self.stop - self.start

    @property
    def energy(self) -> float:
        return float(self.energies.sum())


def mode1_rotation(coefficients: np.ndarray) -> np.ndarray:
    """V: the left singular vectors of the mode-1 unfolding (r x 3n) of ``coefficients``, by
    decreasing singular value (the eigenvectors of its r x r Gram matrix: the error table is
    measured on the projections themselves, so V need only be orthonormal and well ordered)."""
    return _descending_eigenvectors(coefficients.reshape(coefficients.shape[0], -1))


def _descending_eigenvectors(matrix: np.ndarray) -> np.ndarray:
    """The eigenvectors of ``matrix @ matrix.T``, largest eigenvalue first."""
    values, vectors = np.linalg.eigh(matrix @ matrix.T)
    order = np.argsort(values)[::-1]
    return np.ascontiguousarray(vectors[:, order])


def segment_model(
    start: int,
    coefficients: np.ndarray,
    rotation: np.ndarray,
    energies: np.ndarray,
    centroids: np.ndarray,
) -> SegmentModel:
    """The HOSVD of modes 2 and 3 of one segment, U1 = Q V fixed, and its exact error table."""
    tensor = np.einsum("ra,rxt->axt", rotation, coefficients)  # T_s = V' W_s, (r', 3, n)
    count = tensor.shape[2]
    u2 = _descending_eigenvectors(tensor.transpose(1, 0, 2).reshape(3, -1))
    u3 = _descending_eigenvectors(tensor.transpose(2, 0, 1).reshape(count, -1))
    core = np.einsum("axt,xc,tb->acb", tensor, u2, u3, optimize=True)
    residual = max(float(energies.sum()) - float(np.square(coefficients).sum()), 0.0)
    error_table = residual + discarded_energy(np.square(core).sum(axis=1))
    return SegmentModel(
        start,
        start + count,
        coefficients,
        rotation,
        u2,
        u3,
        core,
        energies,
        centroids,
        error_table,
    )


@dataclass(frozen=True)
class SegmentRanks:
    """Ranks for every segment: ``shared`` columns of a shared U1 (0 with a basis per segment)
    and each segment's (i, k)."""

    shared: int
    ranks: tuple[tuple[int, int], ...]
    truncation2: float
    stored: int  # the numbers the factors hold (the cost the choice minimised)


def _segment_tables(
    models: list[SegmentModel], vertices: int, shared: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Errors [s, i, k] and costs [s, i, k] padded to common sizes (inf where not possible; i and
    k from 1). With a shared basis the cost leaves out U1 (K i, paid once for all segments)."""
    largest_i = max(m.error_table.shape[0] for m in models)
    largest_k = max(m.error_table.shape[1] for m in models)
    errors = np.full((len(models), largest_i, largest_k), np.inf)
    costs = np.full_like(errors, np.inf)
    for s, model in enumerate(models):
        rows, cols = model.error_table.shape
        errors[s, 1:rows, 1:cols] = model.error_table[1:, 1:]
        i = np.arange(1, rows)[:, None]
        k = np.arange(1, cols)[None, :]
        costs[s, 1:rows, 1:cols] = (model.frames + 3 * i) * k + (0 if shared else vertices * i)
    return errors, costs


def _lagrange_choice(
    errors: np.ndarray, costs: np.ndarray, budget2: float
) -> tuple[np.ndarray, np.ndarray]:
    """For each row group (axis 1 of ``errors`` after the segment axis 0 is summed), the choice
    minimising cost + lambda * error along the last axis, lambda bisected (per group) to the
    smallest that keeps the summed error within ``budget2``. Returns the chosen indices
    [s, group] and whether each group can meet the budget at all."""
    scale = costs[np.isfinite(costs)].mean() / max(budget2, 1e-300)
    best = np.argmin(np.where(np.isfinite(errors), errors, np.inf), axis=2)
    feasible = np.take_along_axis(errors, best[..., None], axis=2)[..., 0].sum(axis=0) <= budget2
    low = np.full(errors.shape[1], -12.0)
    high = np.full(errors.shape[1], 12.0)
    safe_errors = np.where(np.isfinite(errors), errors, 0.0)
    for _ in range(LAMBDA_STEPS):
        middle = 0.5 * (low + high)
        objective = costs + (scale * 10.0**middle)[None, :, None] * safe_errors
        chosen = np.argmin(objective, axis=2)
        total = np.take_along_axis(errors, chosen[..., None], axis=2)[..., 0].sum(axis=0)
        fits = total <= budget2
        high = np.where(fits, middle, high)
        low = np.where(fits, low, middle)
    objective = costs + (scale * 10.0**high)[None, :, None] * safe_errors
    chosen = np.argmin(objective, axis=2)
    total = np.take_along_axis(errors, chosen[..., None], axis=2)[..., 0].sum(axis=0)
    chosen = np.where((total <= budget2)[None, :], chosen, best)
    return chosen, feasible


def cheapest_ranks(
    models: list[SegmentModel], vertices: int, shared: bool, budget2: float
) -> SegmentRanks | None:
    """The ranks that store the fewest numbers with a total truncation error within
    ``budget2``; ``None`` if even the largest ranks do not fit."""
    errors, costs = _segment_tables(models, vertices, shared)
    segments, largest_i, largest_k = errors.shape
    if shared:
        chosen_k, feasible = _lagrange_choice(errors, costs, budget2)  # per shared i
        k_of = chosen_k  # [s, i]
        picked_errors = np.take_along_axis(errors, k_of[..., None], axis=2)[..., 0]
        picked_costs = np.take_along_axis(costs, k_of[..., None], axis=2)[..., 0]
        totals = picked_costs.sum(axis=0) + vertices * np.arange(largest_i)
        totals[0] = np.inf  # i >= 1
        totals[~feasible] = np.inf
        if not np.isfinite(totals).any():
            return None
        i = int(np.argmin(totals))
        ranks = tuple((i, int(k_of[s, i])) for s in range(segments))
        return SegmentRanks(i, ranks, float(picked_errors[:, i].sum()), int(totals[i]))
    flat_errors = errors.reshape(segments, 1, -1)
    flat_costs = costs.reshape(segments, 1, -1)
    chosen, feasible = _lagrange_choice(flat_errors, flat_costs, budget2)
    if not feasible[0]:
        return None
    ranks = tuple(divmod(int(chosen[s, 0]), largest_k) for s in range(segments))
    error2 = sum(float(errors[s, i, k]) for s, (i, k) in enumerate(ranks))
    stored = sum(float(costs[s, i, k]) for s, (i, k) in enumerate(ranks))
    return SegmentRanks(0, ranks, error2, int(stored))


def fixed_ranks(models: list[SegmentModel], shared: bool, i: int, k: int) -> SegmentRanks:
    """Ranks (i, k) everywhere, each cut to what its segment can hold."""
    ranks = []
    for model in models:
        rows, cols = model.error_table.shape
        ranks.append((min(i, rows - 1), min(k, cols - 1)))
    error2 = sum(float(m.error_table[r]) for m, r in zip(models, ranks, strict=True))
    shared_columns = max(r[0] for r in ranks) if shared else 0
    return SegmentRanks(shared_columns, tuple(ranks), error2, 0)


def model_error2(
    model: SegmentModel,
    projection: np.ndarray,
    gram: np.ndarray,
    column_sums: np.ndarray,
    vertices: int,
    basis: np.ndarray,
    u3: np.ndarray,
    centroids: np.ndarray,
) -> float:
    """The decoded segment's squared error against the input, from r-dimensional products.

    With the decoded frame U~1 M_t + c~_t (M_t = B u3_t, i x 3) and the input X_t + c_t, where
    X_t = Q W_t + R_t and R_t is orthogonal to Q::

        ||error_t||^2 = ||X_t||^2 - 2 <W_t, A M_t> + <M_t, G M_t> + K ||dc_t||^2
                        - 2 (s' M_t) . dc_t  -  2 <R_t, U~1 M_t>

    with A = Q'U~1 (``projection``), G = U~1'U~1 (``gram``), s = U~1'1 (``column_sums``) and
    dc_t = c_t - c~_t. The last term is left out: it needs the input, and it is the inner
    product of the residual with quantization noise.
    """
    weights = np.einsum("axb,tb->tax", basis, u3)  # M_t, (n, i, 3)
    delta = model.centroids - centroids
    total = float(model.energies.sum())
    total -= 2.0 * float(np.einsum("rxt,ra,tax->", model.coefficients, projection, weights))
    total += float(np.einsum("tax,ab,tbx->", weights, gram, weights))
    total += vertices * float(np.square(delta).sum())
    total -= 2.0 * float(np.einsum("a,tax,tx->", column_sums, weights, delta))
    return max(total, 0.0)


def column_norms(
    models: list[SegmentModel], ranks: tuple[tuple[int, int], ...], rows: int
) -> np.ndarray:
    """sqrt(sum over segments of ||G_s[a, :, :k_s]||^2) for each of the ``rows`` basis columns a:
    how far an error in column a of a shared U1 reaches."""
    energy = np.zeros(rows)
    for model, (i, k) in zip(models, ranks, strict=True):
        energy[:i] += np.square(model.core[:i, :, :k]).sum(axis=(1, 2))
    return np.sqrt(energy)


__all__ = [
    "SegmentModel",
    "SegmentRanks",
    "cheapest_ranks",
    "column_norms",
    "fixed_ranks",
    "mode1_rotation",
    "model_error2",
    "orthonormal_columns",
    "segment_model",
]
