"""§6.2 Prediction: each entry of a quantized column minus its *parent*'s entry.

A column of U1 holds one coefficient per vertex, smooth over the surface; a column of U3 or of
the centroids is smooth in time. Storing each entry minus its parent's entry leaves small
residuals that compress far better. Parents always come earlier in the order, so the decoder
restores the values by summing residuals along the parent chain.

Two parent relations exist (§6.6 says which section uses which):

* mesh parents (U1): the breadth-first spanning forest of the face edges,
  :func:`tuckercodec.model.topology.mesh_parents` (it lives with the other rules of the face table);
* previous-row parents (U3, CENT): frame f's parent is frame f - 1, written ``parents=None``
  here.
"""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np

from ..model.topology import MeanSteps
from ..system import native


def residuals(values: np.ndarray, parents: np.ndarray | None) -> np.ndarray:
    """Each row minus its parent's row; ``parents=None`` means the previous row (time)."""
    if parents is None:
        return np.diff(values, axis=0, prepend=np.zeros((1, *values.shape[1:]), values.dtype))
    out = values.copy()
    has = parents >= 0
    out[has] -= values[parents[has]]
    return out


def accumulate(
    residual: np.ndarray, parents: np.ndarray | None, *, in_place: bool = False
) -> np.ndarray:
    """The inverse of :func:`residuals`: each row plus all its ancestors' residuals.

    Along a tree the rows are restored a level at a time, from the roots down: a row's parent,
    one level up, is final by then, so each level costs one gather and one add, and the whole
    tree costs about one pass over the array (a 200,000-vertex mesh about 450 levels deep: 0.05 s
    for 70 columns, against 0.4 s by pointer jumping). A tree so deep that a Python loop over its
    levels would cost more (a long strip of faces) is restored by pointer jumping instead: after
    pass p every row holds the sum over its 2**p nearest ancestors, about log2(depth) passes.
    With ``in_place`` the residuals are overwritten (no copy of a large U1).
    """
    core = native.core()
    if core is not None and residual.ndim == 2 and residual.dtype == np.int64:
        total = residual if in_place else residual.copy()
        if total.flags.c_contiguous:  # the same wrapping int64 sums, in one pass
            if parents is None:
                core.accumulate_rows(total)
            else:
                core.accumulate_tree(total, np.ascontiguousarray(parents, dtype=np.int64))
            return total
    if parents is None:
        return np.cumsum(residual, axis=0, out=residual if in_place else None)
    depth = tree_depths(parents)
    levels = int(depth.max(initial=0)) + 1
    total = residual if in_place else residual.copy()
    if levels > MAX_LEVELS:
        return _pointer_jumping(total, parents)
    order = np.argsort(depth, kind="stable")
    ends = np.cumsum(np.bincount(depth, minlength=levels))
    for level in range(1, levels):
        rows = order[ends[level - 1] : ends[level]]
        total[rows] += total[parents[rows]]
    return total


#: The deepest tree restored level by level; deeper ones are restored by pointer jumping.
MAX_LEVELS = 4096


def tree_depths(parents: np.ndarray) -> np.ndarray:
    """Each row's distance from its root (0 for a root): the sum of one per ancestor edge."""
    edges = (parents >= 0).astype(np.int64)[:, None]
    depths: np.ndarray = _pointer_jumping(edges, parents)[:, 0]
    return depths


def _pointer_jumping(total: np.ndarray, parents: np.ndarray) -> np.ndarray:
    """Restores ``total`` in place."""
    ancestor = parents.copy()
    live = np.flatnonzero(ancestor >= 0)
    while live.size:
        jump = ancestor[live]
        total[live] += total[jump]  # the right side is read before any row is written
        ancestor[live] = ancestor[jump]
        live = live[ancestor[live] >= 0]
    return total


# -- predictor 2: the mean of a vertex's decoded neighbours, extrapolated ----------------------

#: Every value of a column with predictor 2 lies within +-this (§6.2): a decoder rejects the
#: file otherwise, and the encoder does not choose predictor 2 for such a column.
MEAN_LIMIT = 2**32
#: Below this many sources per row, the sums of (4 q[w] - q[anchor]) (each within 5 * 2**32
#: while the values are within MEAN_LIMIT) stay below 2**53: exact in float64.
_FLOAT_SOURCES = 2**17
#: The same for any other push: ((6 + a) q[w] - a q[anchor]) is within 24 * 2**32, and the sum
#: plus 3c must stay below 2**52 for its floored quotient to be exact.
_PUSHED_FLOAT_SOURCES = 2**15
#: Predictor 2's push where a file gives none (§6.2): a third of a step, 2/6.
PUSH = 2
#: The pushes a file may give (format 1.6): 0..9 sixths of a step.
PUSHES = range(10)


def mean_predictions(
    q: np.ndarray, steps: MeanSteps, start: int = 0, stop: int | None = None, push: int = PUSH
) -> np.ndarray:
    """Predictor 2's prediction of rows ``steps.rows[start:stop]`` (§6.2) from ``q`` (int64,
    every value within +-MEAN_LIMIT), exactly: with V the sum over the row's c sources w of
    ((6 + a) q[w] - a q[anchor(w)]), a the push, ``floor((2 V + 6 c) / (12 c))``, that is
    V / (6 c) rounded half up: the sources' mean, moved on by a/6 of each source's own step
    from its anchor. (|2 V + 6 c| < 2**39 c: int64 holds it for any c below 2**24.)"""
    stop = steps.rows.size if stop is None else stop
    first, last = int(steps.source_ends[start]), int(steps.source_ends[stop])
    counts = np.diff(steps.source_ends[start : stop + 1])[:, None]
    terms = q[steps.sources[first:last]]
    terms *= 6 + push
    terms -= push * q[steps.anchors[first:last]]
    total: np.ndarray = np.add.reduceat(terms, steps.source_ends[start:stop] - first, axis=0)
    total *= 2
    total += 6 * counts
    np.floor_divide(total, 12 * counts, out=total)
    return total


def pushes_of(push: np.ndarray | None, cols: int) -> np.ndarray:
    """Each column's push (§6.2, format 1.6): ``push`` as uint8, or PUSH for every column."""
    if push is None:
        return np.full(cols, PUSH, dtype=np.uint8)
    return np.asarray(push, dtype=np.uint8)


def _by_push(push: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """The columns of each push value, for the paths that take one push at a time."""
    return [(int(a), np.flatnonzero(push == a)) for a in np.unique(push)]


#: Columns whose predictor-2 residuals the encoder forms at once.
_MEAN_COLUMN_BLOCK = 16


def _beyond(values: np.ndarray, limit: int) -> bool:
    """Whether a value is outside -limit..limit (by its extremes: abs() of -2**63 wraps to
    itself, and would pass)."""
    return bool(values.size) and (int(values.min()) < -limit or int(values.max()) > limit)


def _checked(block: np.ndarray | None) -> np.ndarray:
    assert block is not None  # the whole was checked against MEAN_LIMIT before the blocks
    return block


def mean_residuals(
    values: np.ndarray, steps: MeanSteps, push: np.ndarray | None = None
) -> np.ndarray | None:
    """Each row minus predictor 2's prediction of it (rows of depth 0 as they are), each column
    with its push (``push``: one per column, format 1.6; ``None``: PUSH for every column), or
    ``None`` if a value leaves +-MEAN_LIMIT (predictor 2 cannot hold such a column)."""
    core = native.core()
    pushes = pushes_of(push, values.shape[1])
    if core is not None:  # the same floats and integers, no temporaries
        plan = steps.native_plan()
        contiguous = np.ascontiguousarray(values, dtype=np.int64)
        result: np.ndarray | None = (
            plan.residuals(contiguous)
            if (pushes == PUSH).all()
            else plan.residuals(contiguous, pushes)
        )
        return result
    if _beyond(values, MEAN_LIMIT):
        return None
    out = values.copy()
    for a, columns in _by_push(pushes):
        for start in range(0, columns.size, _MEAN_COLUMN_BLOCK):  # small float temporaries
            block = columns[start : start + _MEAN_COLUMN_BLOCK]
            out[:, block] = _pushed_residuals(values[:, block], steps, a)
    return out


def mean_residual_columns(
    values: np.ndarray, steps: MeanSteps, push: np.ndarray | None = None
) -> np.ndarray | None:
    """:func:`mean_residuals` column after column, a (cols, rows) C-contiguous array, as a
    section streams them: the compiled core lays them out so as it reads the columns, where
    a transposition would be a pass of its own."""
    core = native.core()
    if core is not None:
        contiguous = np.ascontiguousarray(values, dtype=np.int64)
        pushes = pushes_of(push, values.shape[1])
        columns: np.ndarray | None = steps.native_plan().residuals(
            contiguous, None if (pushes == PUSH).all() else pushes, columns=True
        )
        return columns
    residual = mean_residuals(values, steps, push)
    return None if residual is None else np.ascontiguousarray(residual.T)


def _pushed_residuals(values: np.ndarray, steps: MeanSteps, push: int) -> np.ndarray:
    """:func:`mean_residuals` of columns that share one push (every value within the range)."""
    out = values.copy()
    if steps.rows.size:
        if int(steps.counts.max()) >= _float_sources(push):  # only a crafted mesh
            out[steps.rows] -= mean_predictions(values, steps, push=push)
        else:  # all rows at once: the same exact floats as mean_accumulate's
            out[steps.rows] -= _float_predictions(
                values.astype(np.float64), steps, 0, steps.rows.size, push
            ).astype(np.int64)
    return out


def _float_sources(push: int) -> int:
    """The fewest sources per row for which a push's float sums are no longer exact."""
    return _FLOAT_SOURCES if push == PUSH else _PUSHED_FLOAT_SOURCES


def _float_weights(
    steps: MeanSteps, push: int
) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], float, float]:
    """The matrix of a push's sums, and per source count the offset and the divisor whose
    floored quotient is the prediction: (U + 1.5c) / 3c for PUSH (weights 4 and -1), else
    (V + 3c) / 6c (weights 6 + a and -a); both V / 6c rounded half up."""
    if push == PUSH:
        return steps.matrix, 1.5, 3.0
    return steps.pushed_matrix(push), 3.0, 6.0


def mean_accumulate(
    residual: np.ndarray, steps: MeanSteps, push: np.ndarray | None = None
) -> np.ndarray:
    """The inverse of :func:`mean_residuals`, a step (a depth and phase) at a time, each row's
    sources restored before it. Raises ``ValueError`` if a restored value leaves +-MEAN_LIMIT.

    The sums run in float64, through the sparse matrix of the sources (``steps.matrix``):
    about three times faster than int64 gathers, and exact. Each value is computed once, from
    values computed before it; while all of those are within MEAN_LIMIT every sum is an
    integer below 2**52, and (2U + 3c) / 6c equals (U + 1.5c) / 3c, one correctly rounded
    division whose floor is exact below 2**52. So the first value that leaves the limit is
    itself exact, and one check of the whole result at the end finds it.
    """
    core = native.core()
    pushes = pushes_of(push, residual.shape[1] if residual.ndim == 2 else 1)
    if core is not None and residual.ndim == 2:  # column after column, in place in a copy
        columns = np.array(residual.T, dtype=np.int64, order="C")
        _native_restore(steps, columns, pushes)
        restored: np.ndarray = columns.T
        return restored
    out = np.empty(residual.shape, dtype=np.int64)
    for a, chosen in _by_push(pushes):
        out[:, chosen] = _pushed_accumulate(residual[:, chosen], steps, a)
    return out


def _native_restore(steps: MeanSteps, columns: np.ndarray, pushes: np.ndarray) -> None:
    plan = steps.native_plan()
    if (pushes == PUSH).all():
        plan.restore_columns(columns)
    else:
        plan.restore_columns(columns, pushes)


def _pushed_accumulate(residual: np.ndarray, steps: MeanSteps, push: int) -> np.ndarray:
    """:func:`mean_accumulate` of columns that share one push."""
    rows, ends = steps.rows, steps.step_ends
    if rows.size and int(steps.counts.max()) >= _float_sources(push):  # only a crafted mesh
        total = residual.copy()
        for step in range(ends.size - 1):
            start, stop = int(ends[step]), int(ends[step + 1])
            if start < stop:
                total[rows[start:stop]] += mean_predictions(total, steps, start, stop, push)
                if _beyond(total[rows[start:stop]], MEAN_LIMIT):
                    raise ValueError("a restored value leaves the range of predictor 2")
        return total
    work = np.array(residual, dtype=np.float64, order="C")  # C: the product reads it flat
    if rows.size:
        _float_restore(work, steps, push)
    if work.size and not (work.min() >= -MEAN_LIMIT and work.max() <= MEAN_LIMIT):  # NaN fails
        raise ValueError("a restored value leaves the range of predictor 2")
    return work.astype(np.int64)


#: Values of U1 that :func:`mean_accumulate_columns` restores at once (32 MB of float64): a
#: block of columns (they do not depend on each other), as few blocks as this allows, since
#: each block pays every step's few numpy calls again.
MEAN_RESTORE_VALUES = 1 << 22


def mean_accumulate_columns(
    columns: np.ndarray, steps: MeanSteps, push: np.ndarray | None = None
) -> None:
    """:func:`mean_accumulate` of ``columns.T``, written back into ``columns`` (cols, rows),
    the residuals as the stream holds them, column after column: a block of columns at a time,
    so that a large U1 is never copied whole (each block's floats are the temporary). Raises
    ``ValueError`` as :func:`mean_accumulate` does, at the first block that leaves the range."""
    core = native.core()
    pushes = pushes_of(push, columns.shape[0])
    if core is not None and columns.dtype == np.int64 and columns.flags.c_contiguous:
        _native_restore(steps, columns, pushes)  # a column at a time: one column's floats
        return
    for a, chosen in _by_push(pushes):
        count = chosen.size
        blocks = max(1, -(-(count * columns.shape[1]) // MEAN_RESTORE_VALUES))
        width = max(1, -(-count // blocks))
        for start in range(0, count, width):
            block = chosen[start : start + width]
            columns[block] = _pushed_accumulate(columns[block].T, steps, a).T


def _float_restore(work: np.ndarray, steps: MeanSteps, push: int = PUSH) -> None:
    """:func:`mean_accumulate`'s steps on ``work`` (float64, C order), in place: each step the
    float products of :func:`_float_predictions`, with what does not change between steps (the
    counts, the matrix's arrays, the product) looked up once. A step costs a few numpy calls, and
    a mesh has eight per depth (samba: 929 steps)."""
    (ptr, idx, weights), offset, divisor = _float_weights(steps, push)
    counts = steps.counts.astype(np.float64)[:, None]
    half, thirds = offset * counts, divisor * counts
    product = _csr_matvecs()
    rows, ends = steps.rows, steps.step_ends.tolist()
    flat, width, height = work.reshape(-1), work.shape[1], work.shape[0]
    sums = np.empty((int(np.diff(steps.step_ends).max(initial=0)), width))
    for start, stop in itertools.pairwise(ends):
        if start == stop:
            continue
        part = sums[: stop - start]
        part[:] = half[start:stop]  # the sum plus its offset: the product below adds the sum
        # the whole matrix's columns and weights, addressed by this step's row pointers
        pointers = ptr[start : stop + 1]
        product(stop - start, height, width, pointers, idx, weights, flat, part.reshape(-1))
        part /= thirds[start:stop]
        np.floor(part, out=part)
        work[rows[start:stop]] += part


def _float_predictions(
    work: np.ndarray, steps: MeanSteps, start: int, stop: int, push: int = PUSH
) -> np.ndarray:
    """:func:`mean_predictions` in float64 (exact while ``work`` is within MEAN_LIMIT and each
    row has fewer sources than :func:`_float_sources` allows: every partial sum stays below
    2**52)."""
    (ptr, idx, weights), offset, divisor = _float_weights(steps, push)
    counts = steps.counts[start:stop, None]
    first, last = int(ptr[start]), int(ptr[stop])
    sums = np.empty((stop - start, work.shape[1]))
    sums[:] = offset * counts  # the sum plus its offset: the product below adds the sum
    _csr_matvecs()(
        stop - start,
        work.shape[0],
        work.shape[1],
        ptr[start : stop + 1] - first,
        idx[first:last],
        weights[first:last],
        work.reshape(-1),
        sums.reshape(-1),
    )
    sums /= divisor * counts
    np.floor(sums, out=sums)
    return sums


def _csr_matvecs() -> Any:
    """scipy's compiled y += A X for a CSR matrix A given as arrays (its ``@`` costs tens of
    microseconds per call in checks, and restoring runs one per step). It is private to scipy:
    should a release drop it, the same product is made through the public API, slower."""
    try:  # imported here: scipy.sparse is slow to import
        from scipy.sparse import _sparsetools

        return _sparsetools.csr_matvecs
    except (ImportError, AttributeError):  # pragma: no cover - scipy's layout of 1.11-1.16 has it
        return _public_csr_matvecs


def _public_csr_matvecs(
    rows: int,
    columns: int,
    vectors: int,
    ptr: np.ndarray,
    idx: np.ndarray,
    weights: np.ndarray,
    x: np.ndarray,
    y: np.ndarray,
) -> None:
    """``y += A x`` as :func:`_csr_matvecs` does it, with ``scipy.sparse.csr_matrix``."""
    import scipy.sparse as sparse

    matrix = sparse.csr_matrix((weights, idx, ptr), shape=(rows, columns))
    y.reshape(rows, vectors)[:] += matrix @ x.reshape(columns, vectors)


#: Predictor 3 (format 1.2, previous-row sections): the restored values and their first
#: differences must stay within these, so that int64 holds every running sum (§6.2).
LINEAR_LIMIT = 2**32
LINEAR_STEP_LIMIT = 2**33


def linear_residuals(values: np.ndarray) -> np.ndarray:
    """Predictor 3 along the rows (time): each row minus ``2 q[t-1] - q[t-2]`` (rows before the
    first count as 0), that is the second difference."""
    first = np.diff(values, axis=0, prepend=np.zeros((1, *values.shape[1:]), values.dtype))
    return np.diff(first, axis=0, prepend=np.zeros((1, *values.shape[1:]), values.dtype))


def linear_accumulate(residual: np.ndarray) -> np.ndarray:
    """The inverse of :func:`linear_residuals`: two running sums. Raises ``ValueError`` when a
    first difference leaves +-2**33 or a value +-2**32 (R32 for the caller): within those the
    int64 sums are exact (F <= 2**24 rows of at most 2**33)."""
    core = native.core()
    if core is not None and residual.ndim == 2 and residual.dtype == np.int64:
        restored = np.array(residual, order="C")
        core.linear_accumulate(restored)  # the same sums, checks and ValueError
        return restored
    first = np.cumsum(residual, axis=0)
    if _beyond(first, LINEAR_STEP_LIMIT):
        raise ValueError("a difference restored with predictor 3 leaves the range")
    values: np.ndarray = np.cumsum(first, axis=0)
    if _beyond(values, LINEAR_LIMIT):
        raise ValueError("a value restored with predictor 3 leaves the range")
    return values
