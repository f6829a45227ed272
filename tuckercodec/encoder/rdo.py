"""Rate-distortion optimized quantization: each factor entry rounded to the cheaper neighbour.

Plain quantization rounds ``x / step`` to the nearest integer. Either neighbour of ``x / step``
(its floor or its ceiling) is a valid integer for the file; the nearer one has the smaller error,
but the other may be much cheaper to code: its residual after prediction (§6.2: the mesh parent's
integer for U1, the previous frame's for U3, zero for the core) may be smaller. :func:`quantize`
chooses, entry by entry, the neighbour that minimises

    J = (x / step - q) ** 2 + lam * bits(q - prediction)

(the error in units of step**2, the rate in bits). ``bits`` is a per-column model: minus log2 of
the frequency of each residual in the nearest rounding's residuals, then in the previous pass's.
With no prediction the rule is a dead zone whose width follows the column's statistics: a value
just over 0.5 steps goes to 0 when a 1 there costs enough bits more than a 0.

Because parents (or the previous frame) are final before their children are chosen, rows are
chosen a tree level at a time, as the decoder restores them (:func:`tuckercodec.format
.prediction.accumulate`): each level is one vectorised choice over all its rows and columns.

The choice moves only between the two integers either side of ``x / step``, so each entry's
error is below one step; the extra error is paid for by the encoder's search, which measures the
decoded error after quantizing and lowers D until the target holds (the closed loop of
:func:`tuckercodec.encoder.search.meet` is unchanged). ``lam`` near 2 ln 2 / 12 ~ 0.116 is the
slope of the high-rate rate-distortion curve D(R) = step**2 / 12, where trading error for bits at
this price is break-even; the measurements in ``python -m tools.bench entropy --rdo`` chose
:data:`DEFAULT_LAMBDA`.

U1's columns that the file predicts with predictor 2 (the mean of a vertex's decoded neighbours,
pushed on, §6.2: most of them) are chosen against that prediction instead (:func:`quantize_mesh`),
a step of the decoder's order at a time, so that the rate model prices the residuals the file
really codes rather than those of the mesh parent's prediction, which the file does not use.

Nothing here changes the format: the file stores the same kind of integers, chosen differently.
The result is deterministic (ties to the nearest integer); the compiled core's loops, where
installed, give the same integers as the numpy reference here.
"""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..format import qmat
from ..format.prediction import mean_residuals, tree_depths
from ..format.qmat import PREDICT_MEAN, QuantizedMatrix
from ..model.topology import MAX_MEAN_LEVELS, MeanSteps, MeshPrediction
from ..system import native

#: Rate weight (step**2 per bit) used by the encoder; ``None`` in :class:`Settings` turns RDO off.
DEFAULT_LAMBDA = 0.05
#: Passes of choose-then-remodel (a second pass, which sees the statistics RDO itself makes,
#: gained nothing measurable and costs as much again).
DEFAULT_PASSES = 1
#: Residuals coded by their own table entry; larger ones share a log-scale escape cost.
TABLE_SIZE = 512


@dataclass(frozen=True)
class Settings:
    """How the encoder quantizes: ``lam`` None is plain nearest rounding (qmat.quantize)."""

    lam: float | None = DEFAULT_LAMBDA
    passes: int = DEFAULT_PASSES
    #: Whether U1's predictor-2 columns are chosen against predictor 2 (:func:`quantize_mesh`);
    #: if not, as the others are, against the mesh parent's prediction.
    mean: bool = True
    #: A fixed dead zone instead of the rate model: the residual from the prediction,
    #: r = x / step - prediction, becomes sign(r) * floor(|r| + 1 - dead_zone) (0.5: nearest).
    dead_zone: float | None = None


#: The encoder's default (read when a Workspace is made, so a benchmark can patch it).
DEFAULT = Settings()
#: Nearest rounding, as before RDO.
NEAREST = Settings(lam=None)


class Levels:
    """The rows of a prediction tree grouped by depth: rows at one depth depend only on rows
    above them, so each group is chosen at once. ``parents`` as in
    :mod:`tuckercodec.format.prediction` (``parents[r] < 0``: a root, predicted by 0)."""

    def __init__(self, parents: np.ndarray) -> None:
        self.parents = np.asarray(parents, dtype=np.int64)
        depth = tree_depths(self.parents)
        order = np.argsort(depth, kind="stable")
        #: every row once, the levels one after the other: each row after its parent
        self.order = np.ascontiguousarray(order, dtype=np.int64)
        ends = np.cumsum(np.bincount(depth, minlength=int(depth.max(initial=0)) + 1))
        self.groups = [
            order[start:end] for start, end in zip(np.r_[0, ends[:-1]], ends, strict=True)
        ]

    @classmethod
    def chain(cls, rows: int) -> Levels:
        """Previous-row prediction (U3, CENT): row r's parent is r - 1."""
        return cls(np.arange(-1, rows - 1, dtype=np.int64))

    @classmethod
    def flat(cls, rows: int) -> Levels:
        """No prediction (CORE): every row a root."""
        return cls(np.full(rows, -1, dtype=np.int64))


#: Columns chosen at once: each column is chosen alone, and a block bounds the temporaries
#: (a dozen arrays of rows x block floats) rather than letting them grow with U1's width.
#: A block holds about BLOCK_VALUES entries (4 MiB of float64 per array: wide enough that the
#: per-level loop's Python overhead is amortised, small enough to stay in cache), and at least
#: COLUMN_BLOCK columns. Columns are independent, so the width changes no integer.
COLUMN_BLOCK = 16
BLOCK_VALUES = 1 << 19


def quantize(
    values: np.ndarray, steps: np.ndarray, levels: Levels, settings: Settings = DEFAULT
) -> QuantizedMatrix:
    """Quantize ``values`` (rows, cols) with per-column ``steps`` (see the module docstring).

    ``levels`` gives the prediction the file will use for these rows; a column for which
    prediction would not pay (by the same proxy :func:`.format.qmat.encode_matrix` uses) is
    modelled without it. With ``settings.lam`` None this is :func:`.format.qmat.quantize`.
    """
    columns = values.shape[1]
    width = max(COLUMN_BLOCK, BLOCK_VALUES // max(values.shape[0], 1))
    if settings.lam is None or columns <= width:
        return _quantize_block(values, steps, levels, settings)
    steps = np.broadcast_to(np.asarray(steps), (columns,))
    blocks = [
        _quantize_block(
            values[:, start : start + width], steps[start : start + width], levels, settings
        )
        for start in range(0, columns, width)
    ]
    return QuantizedMatrix(
        np.concatenate([block.q for block in blocks], axis=1),
        np.concatenate([block.steps for block in blocks]),
    )


def _quantize_block(
    values: np.ndarray, steps: np.ndarray, levels: Levels, settings: Settings
) -> QuantizedMatrix:
    nearest = qmat.quantize(values, steps)  # checks the steps and the integer range
    if settings.lam is None or nearest.q.size == 0:
        return nearest
    core = native.core()
    if core is not None and settings.dead_zone is None:
        return QuantizedMatrix(
            _native_choice(core, values, nearest, levels, settings), nearest.steps
        )
    scaled = values / nearest.steps.astype(np.float64)[None, :]
    low = np.floor(scaled)
    error_low = np.square(scaled - low)
    error_high = np.square(low + 1.0 - scaled)
    q = nearest.q
    predicted = _predicted_columns(q, levels)
    if settings.dead_zone is not None:
        return QuantizedMatrix(
            _dead_zone(scaled, levels, predicted, settings.dead_zone), nearest.steps
        )
    for _ in range(settings.passes):
        table = _bit_table(_residuals(q, levels, predicted))
        q = _choose(low, error_low, error_high, table, levels, predicted, settings.lam)
    return QuantizedMatrix(q, nearest.steps)


def _native_choice(
    core: Any, values: np.ndarray, nearest: QuantizedMatrix, levels: Levels, settings: Settings
) -> np.ndarray:
    """The passes of :func:`_quantize_block` in the compiled core: the same integers (the
    bit tables, float sums whose order numpy decides, are made here from the core's counts)."""
    assert settings.lam is not None
    q = np.ascontiguousarray(nearest.q, dtype=np.int64)
    if q.shape[1] > 1:
        predicted = core.rdo_predicted_columns(q, levels.parents)
    else:  # numpy sums a single column pairwise: the reference decides it
        predicted = _predicted_columns(q, levels)
    predicted = np.ascontiguousarray(predicted, dtype=bool)
    values = np.ascontiguousarray(values, dtype=np.float64)
    steps = np.ascontiguousarray(nearest.steps, dtype=np.float64)
    for _ in range(settings.passes):
        table = _bits_of_counts(core.rdo_residual_counts(q, levels.parents, predicted, TABLE_SIZE))
        q = core.rdo_choose(
            values, steps, levels.parents, levels.order, predicted, table, settings.lam
        )
    return np.asarray(q)


def _dead_zone(
    scaled: np.ndarray, levels: Levels, predicted: np.ndarray, zone: float
) -> np.ndarray:
    q = np.empty(scaled.shape, dtype=np.int64)
    for rows in levels.groups:
        parents = levels.parents[rows]
        prediction = np.zeros((rows.size, scaled.shape[1]), dtype=np.int64)
        has = np.flatnonzero(parents >= 0)
        if has.size:
            prediction[has] = q[parents[has]] * predicted
        residual = scaled[rows] - prediction
        magnitude = np.floor(np.abs(residual) + (1.0 - zone))
        q[rows] = prediction + (np.copysign(magnitude, residual)).astype(np.int64)
    return q


def _residuals(q: np.ndarray, levels: Levels, predicted: np.ndarray) -> np.ndarray:
    out = q.copy()
    has = np.flatnonzero(levels.parents >= 0)
    out[has] -= q[levels.parents[has]] * predicted  # a column not predicted subtracts 0
    return out


def _proxy_cost(columns: np.ndarray) -> np.ndarray:
    # the rule of qmat.encode_matrix: mean log2(1 + 2|x|) per column
    return np.asarray(np.log2(1.0 + 2.0 * np.abs(columns)).mean(axis=0))


def _predicted_columns(q: np.ndarray, levels: Levels) -> np.ndarray:
    """Columns whose nearest rounding codes cheaper as residuals than as values."""
    if not (levels.parents >= 0).any():
        return np.zeros(q.shape[1], dtype=bool)
    everything = np.ones(q.shape[1], dtype=bool)
    return np.asarray(_proxy_cost(_residuals(q, levels, everything)) < _proxy_cost(q))


def _bit_table(residual: np.ndarray) -> np.ndarray:
    """(cols, TABLE_SIZE + 1) bits of each zigzag residual per column; the last entry is the
    escape's base cost, to which larger residuals add 2 log2 of their size over the table's."""
    return _bits_of_counts(_residual_counts(residual))


def _residual_counts(residual: np.ndarray) -> np.ndarray:
    """(cols, TABLE_SIZE + 1) counts of each column's zigzag residuals, clipped to the table."""
    cols = residual.shape[1]
    zig = np.minimum(_zigzag(residual), TABLE_SIZE)
    zig += np.arange(cols) * (TABLE_SIZE + 1)  # one histogram per column, side by side
    counts = np.bincount(zig.reshape(-1), minlength=cols * (TABLE_SIZE + 1))
    return counts.reshape(cols, TABLE_SIZE + 1)


def _bits_of_counts(counts: np.ndarray) -> np.ndarray:
    """:func:`_bit_table` from the histograms of :func:`_residual_counts`."""
    counts = counts.astype(np.float64)
    # Laplace-style smoothing keeps an unseen residual finite but dear
    counts += 0.05
    bits: np.ndarray = np.log2(counts.sum(axis=1, keepdims=True)) - np.log2(counts)
    return bits


def _zigzag(values: np.ndarray) -> np.ndarray:
    out: np.ndarray = (values << 1) ^ (values >> 63)  # as streams.zigzag, kept signed
    return out


def _bits(residual: np.ndarray, flat_table: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Each residual's bits by its column's table (``flat_table``: the tables one after the
    other, column c's at ``offsets[c]``), escapes priced as in :func:`_bit_table`."""
    zig = _zigzag(residual)
    index = np.minimum(zig, TABLE_SIZE)
    index += offsets
    bits: np.ndarray = flat_table.take(index)
    over = zig > TABLE_SIZE
    if over.any():
        bits = bits + np.where(over, 2.0 * np.log2(np.maximum(zig, 1) / TABLE_SIZE), 0.0)
    return bits


def _choose(
    low: np.ndarray,
    error_low: np.ndarray,
    error_high: np.ndarray,
    table: np.ndarray,
    levels: Levels,
    predicted: np.ndarray,
    lam: float,
) -> np.ndarray:
    q = np.empty(low.shape, dtype=np.int64)
    flat_table = np.ascontiguousarray(table).reshape(-1)
    offsets = (np.arange(low.shape[1]) * table.shape[1])[None, :]
    for rows in levels.groups:
        parents = levels.parents[rows]
        base = low[rows].astype(np.int64)
        residual = base.copy()
        has = np.flatnonzero(parents >= 0)
        if has.size:
            residual[has] -= q[parents[has]] * predicted
        below, above = error_low[rows], error_high[rows]
        cost_low = below + lam * _bits(residual, flat_table, offsets)
        cost_high = above + lam * _bits(residual + 1, flat_table, offsets)
        # ties go to the nearer integer (the plain rounding), so lam -> 0 is nearest rounding
        high = (cost_high < cost_low) | ((cost_high == cost_low) & (above < below))
        q[rows] = base + high
    return q


# -- U1 under predictor 2 -------------------------------------------------------------------------

#: Values of U1 that :func:`quantize_mesh` chooses at once: its cost is a few numpy calls per
#: step of predictor 2 (samba: 929 steps), so its blocks of columns are as wide as memory allows
#: (three arrays of this many float64 or int64 beside U1).
MEAN_BLOCK_VALUES = 1 << 22


def quantize_mesh(
    values: np.ndarray,
    steps: np.ndarray,
    levels: Levels,
    mesh: MeshPrediction,
    predict: np.ndarray,
    push: np.ndarray,
    settings: Settings = DEFAULT,
    nearest: QuantizedMatrix | None = None,
) -> QuantizedMatrix:
    """U1 ``values`` (vertices, cols) quantized with per-column ``steps``: as :func:`quantize`
    with ``levels`` (the mesh parents), except that the columns whose ``predict`` is predictor 2
    (the file's likely predictor, §6.2, with its ``push``) are chosen against predictor 2's own
    prediction, their bits from the nearest rounding's predictor-2 residuals. ``nearest``:
    ``qmat.quantize(values, steps)`` where the caller has it already."""
    if nearest is None:
        nearest = qmat.quantize(values, steps)  # checks the steps and the integer range
    meaned = np.flatnonzero(predict == PREDICT_MEAN)
    if (
        settings.lam is None
        or not settings.mean
        or settings.dead_zone is not None
        or meaned.size == 0
        or values.shape[0] < 2
        or mesh.levels > MAX_MEAN_LEVELS
    ):
        return quantize(values, steps, levels, settings)
    counts = _mean_residual_counts(nearest.q, meaned, mesh.mean_steps, push[meaned])
    if counts is None:  # a value too large for predictor 2: the file will not use it
        return quantize(values, steps, levels, settings)
    core = native.core()
    choice = _mean_choice if core is None else functools.partial(_native_mean_choice, core)
    width = max(COLUMN_BLOCK, MEAN_BLOCK_VALUES // values.shape[0])
    steps64 = nearest.steps.astype(np.float64)
    if meaned.size == values.shape[1] <= width:  # U1's usual case: one block, no copies
        chosen = choice(values, steps64, mesh.mean_steps, push[meaned], counts, settings.lam)
        return QuantizedMatrix(chosen, nearest.steps)
    q = np.empty(nearest.q.shape, dtype=np.int64)
    others = np.flatnonzero(predict != PREDICT_MEAN)
    if others.size:  # columns are chosen independently: a subset changes none of them
        q[:, others] = quantize(values[:, others], nearest.steps[others], levels, settings).q
    for start in range(0, meaned.size, width):
        block = slice(start, start + width)
        columns = meaned[block]
        q[:, columns] = choice(
            values[:, columns],
            steps64[columns],
            mesh.mean_steps,
            push[columns],
            counts[block],
            settings.lam,
        )
    return QuantizedMatrix(q, nearest.steps)


def _mean_residual_counts(
    q: np.ndarray, meaned: np.ndarray, steps: MeanSteps, push: np.ndarray
) -> np.ndarray | None:
    """:func:`_residual_counts` of predictor 2's residuals of the columns ``meaned`` of ``q``,
    each with its push, or ``None`` if a value leaves predictor 2's range. The compiled core
    counts them without handing the residuals (a matrix as large as U1) back."""
    columns = q if meaned.size == q.shape[1] else q[:, meaned]  # meaned: ascending indices
    core = native.core()
    if core is not None:
        counts: np.ndarray | None = steps.native_plan().residual_counts(
            np.ascontiguousarray(columns, dtype=np.int64), push, TABLE_SIZE
        )
        return counts
    residual = mean_residuals(columns, steps, push)
    return None if residual is None else _residual_counts(residual)


#: :func:`_mean_choice` prices residuals within +-this by a table indexed by the residual itself
#: (the same bits as :func:`_bits`); a larger one is priced as the table's edge, where a step
#: more or less changes the escape's price by a few thousandths of a bit.
VALUE_TABLE_HALF = 2048


def _mean_choice(
    values: np.ndarray,
    steps: np.ndarray,
    mean: MeanSteps,
    push: np.ndarray,
    counts: np.ndarray,
    lam: float,
) -> np.ndarray:
    """Each entry the floor or the ceiling of ``values / steps``, whichever minimises J (the
    module docstring) against predictor 2's prediction from the integers chosen before it,
    in the decoder's order: the roots (predicted by 0), then each step of ``mean``. The bits
    are each column's table of the residuals ``counts`` counts (:func:`_residual_counts` of
    the nearest rounding's predictor-2 residuals).
    A mesh has eight steps per depth (samba: 929), so each step is a few numpy calls: what
    does not change between steps is made once."""
    half = VALUE_TABLE_HALF
    flat_table = _value_table(_bits_of_counts(counts)).reshape(-1)
    offsets = (np.arange(values.shape[1]) * (2 * half + 1) + half)[None, :]
    scaled = values / steps[None, :]
    low = np.floor(scaled)
    error_low = np.square(scaled - low)
    error_high = np.square(low + 1.0 - scaled)
    below = low.astype(np.int64)
    del scaled, low
    q = np.empty(values.shape, dtype=np.int64)

    def choose(rows: np.ndarray, prediction: np.ndarray | int) -> None:
        index = below[rows] - prediction
        np.clip(index, -half, half - 1, out=index)
        index += offsets
        below_error, above_error = error_low[rows], error_high[rows]
        cost_low = below_error + lam * flat_table.take(index)
        index += 1
        cost_high = above_error + lam * flat_table.take(index)
        # ties go to the nearer integer, as in _choose
        high = (cost_high < cost_low) | ((cost_high == cost_low) & (above_error < below_error))
        q[rows] = below[rows] + high

    roots = np.ones(values.shape[0], dtype=bool)
    roots[mean.rows] = False
    choose(np.flatnonzero(roots), 0)
    # predictor 2 (§6.2): V / 6c rounded half up, V the sum over the c sources w of
    # (6 + a) q[w] - a q[anchor(w)], a the column's push; exact in int64
    weight = push.astype(np.int64)[None, :]
    source_weight = 6 + weight
    counts = np.diff(mean.source_ends)[:, None]
    offset, divisor = 6 * counts, 12 * counts
    ends, source_ends = mean.step_ends.tolist(), mean.source_ends
    for start, stop in itertools.pairwise(ends):
        if start == stop:
            continue
        first, last = int(source_ends[start]), int(source_ends[stop])
        terms = q[mean.sources[first:last]] * source_weight
        terms -= weight * q[mean.anchors[first:last]]
        total = np.add.reduceat(terms, source_ends[start:stop] - first, axis=0)
        total *= 2
        total += offset[start:stop]
        np.floor_divide(total, divisor[start:stop], out=total)
        choose(mean.rows[start:stop], total)
    return q


def _native_mean_choice(
    core: Any,
    values: np.ndarray,
    steps: np.ndarray,
    mean: MeanSteps,
    push: np.ndarray,
    counts: np.ndarray,
    lam: float,
) -> np.ndarray:
    """:func:`_mean_choice` in the compiled core: the same integers (the value table, whose
    float sums numpy orders, is made here as the reference makes it)."""
    table = _value_table(_bits_of_counts(counts))
    q = core.rdo_mean_choice(
        np.ascontiguousarray(values, dtype=np.float64),
        np.ascontiguousarray(steps, dtype=np.float64),
        *(
            np.ascontiguousarray(array, dtype=np.int64)
            for array in (mean.rows, mean.step_ends, mean.sources, mean.anchors, mean.source_ends)
        ),
        np.ascontiguousarray(push, dtype=np.int64),
        table,
        VALUE_TABLE_HALF,
        lam,
    )
    return np.asarray(q)


def _value_table(table: np.ndarray) -> np.ndarray:
    """(cols, 2 VALUE_TABLE_HALF + 1) bits of each residual -VALUE_TABLE_HALF..VALUE_TABLE_HALF
    by the zigzag tables of :func:`_bit_table`, escapes priced as :func:`_bits` prices them."""
    residual = np.arange(-VALUE_TABLE_HALF, VALUE_TABLE_HALF + 1, dtype=np.int64)
    zig = _zigzag(residual)
    bits: np.ndarray = table[:, np.minimum(zig, TABLE_SIZE)]
    over = zig > TABLE_SIZE
    bits[:, over] += 2.0 * np.log2(zig[over] / TABLE_SIZE)
    return np.ascontiguousarray(bits)


__all__ = [
    "DEFAULT",
    "DEFAULT_LAMBDA",
    "NEAREST",
    "Levels",
    "Settings",
    "quantize",
    "quantize_mesh",
]
