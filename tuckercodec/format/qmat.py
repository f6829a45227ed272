"""§6.3 Codec ``qmat``: quantized matrices (U1, U3, CORE and CENT).

A float matrix of shape (rows, cols) is stored as integers ``q`` with one step per column:
``value = step[c] * q[r, c]``. Each column either stores ``q`` itself (predictor 0), each
entry minus its parent's entry (predictor 1), or, in U1 of a file with the coding tools of
format 1.2, each entry minus the mean of its vertex's decoded neighbours (predictor 2); see
:mod:`.prediction`. The residuals go column after column into one integer stream
(:mod:`.streams`).

The section entry carries ``shape`` [rows, cols], ``planes``, ``steps`` (cols float32,
little-endian, as bytes) and ``predict`` (cols uint8, as bytes).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple, NoReturn

import numpy as np

from ..errors import FormatError, UnreachableTargetError
from ..model.topology import MAX_MEAN_LEVELS, MeanSteps, MeshPrediction
from ..system import native
from . import adaptive, streams
from .prediction import (
    LINEAR_LIMIT,
    LINEAR_STEP_LIMIT,
    PUSH,
    PUSHES,
    accumulate,
    linear_accumulate,
    linear_residuals,
    mean_accumulate,
    mean_accumulate_columns,
    mean_residuals,
    pushes_of,
    residuals,
)
from .sections import section_shape

PREDICT_NONE, PREDICT_PARENT, PREDICT_MEAN, PREDICT_LINEAR = 0, 1, 2, 3
#: The largest predictor of format 1.0 and 1.1; a larger one needs the coding tools flag.
LAST_PLAIN_PREDICTOR = PREDICT_PARENT
#: What a U1 section is restored with: the mesh parents alone, or the mesh's whole structure.
Mesh = np.ndarray | MeshPrediction
#: Largest |q| the encoder forms: exact in float64. What is streamed (q, or its residual from
#: the parent) must also fit 32 bits, which :func:`.streams.pack_integers` checks.
MAX_QUANTIZED = 2**52


@dataclass
class QuantizedMatrix:
    """Integers and the per-column steps that turn them back into floats."""

    q: np.ndarray  # (rows, cols) int64
    steps: np.ndarray  # (cols,) float32

    def values(self) -> np.ndarray:
        """The dequantized matrix, float64: ``step[c] * q[r, c]`` (§6.3)."""
        out = np.empty(self.q.shape)  # C order, whatever q's: the products of §8 read it so
        np.multiply(self.q, self.steps.astype(np.float64)[None, :], out=out)  # one pass
        return out


def quantize(values: np.ndarray, steps: np.ndarray) -> QuantizedMatrix:
    """Round ``values / step`` per column. Steps are rounded to float32 first, because the file
    stores them so and the decoder must multiply by exactly the same number."""
    steps32 = np.asarray(steps, dtype=np.float32)
    if not (np.isfinite(steps32).all() and (steps32 > 0).all()):
        raise ValueError("quantization steps must be positive finite float32 numbers")
    q = values / steps32.astype(np.float64)[None, :]
    np.rint(q, out=q)
    if q.size and np.abs(q).max() > MAX_QUANTIZED:
        raise UnreachableTargetError(
            "the error target is too small for the format's integer range: a quantized value "
            f"would need {int(np.abs(q).max())} > {MAX_QUANTIZED}"
        )
    return QuantizedMatrix(q.astype(np.int64), steps32)


def _cost(columns: np.ndarray, block: int = 16) -> np.ndarray:
    """A cheap per-column proxy for the bits of an integer column: mean log2(1 + 2|x|),
    ``block`` columns at a time (its float temporaries stay small beside a wide U1)."""
    out = np.zeros(columns.shape[1])
    if columns.shape[0]:
        for start in range(0, columns.shape[1], block):
            part = np.abs(columns[:, start : start + block]).astype(np.float64)
            part *= 2.0
            part += 1.0
            np.log2(part, out=part)
            out[start : start + block] = part.mean(axis=0)
    return out


def encode_matrix(
    matrix: QuantizedMatrix,
    parents: np.ndarray | MeshPrediction | None,
    *,
    allow_predict: bool = True,
    coding_tools: bool = True,
    level: int = streams.DEFAULT_LEVEL,
    adaptive_coding: bool = False,
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the section, choosing per column the predictor whose residuals
    look cheapest.

    ``parents`` as in :func:`.prediction.residuals` (``None``: the previous row), or a mesh's
    :class:`~tuckercodec.model.topology.MeshPrediction`, which also offers predictor 2 (the mean of
    the decoded neighbours) when ``coding_tools`` allows it and the mesh is not too deep
    (:data:`~tuckercodec.model.topology.MAX_MEAN_LEVELS`). :func:`.sections.uses_coding_tools` tells
    from the section entries whether the file needs the coding tools flag.

    With ``adaptive_coding`` (a position factor of a file that may be of format 1.6), the
    integers are also coded by §6.14's adaptive coder, and the smaller payload is kept: a
    section never grows by it. Where the adaptive stream is clearly smaller than zstd's fast
    level, zstd's slow level (seconds on a large U1, about 1 % smaller) is not run.
    """
    q = matrix.q
    stream, predict, push = section_stream(q, parents, allow_predict, coding_tools, adaptive_coding)
    columns = np.ascontiguousarray(stream.T)
    del stream
    coded = None
    if adaptive_coding and columns.size:
        coded = adaptive.encode_columns(columns, coding_order(parents, q.shape[0]))
        payload, planes = streams.pack_integers(columns, min(level, streams.SEARCH_LEVEL))
        if len(coded) >= ADAPTIVE_CLEARLY_SMALLER * len(payload) and level > streams.SEARCH_LEVEL:
            payload, planes = streams.pack_integers(columns, level)
    else:
        payload, planes = streams.pack_integers(columns, level)
    params: dict[str, Any] = {
        "shape": [int(q.shape[0]), int(q.shape[1])],
        "planes": planes,
        "steps": matrix.steps.astype("<f4").tobytes(),
        "predict": predict.tobytes(),
    }
    if ((push != PUSH) & (predict == PREDICT_MEAN)).any():  # format 1.6, like coder 1
        params["mean_push"] = (
            np.where(predict == PREDICT_MEAN, push, PUSH).astype(np.uint8).tobytes()
        )
    if coded is not None and len(coded) < len(payload):
        params["coder"] = adaptive.CODER_ADAPTIVE
        payload = coded
    return params, payload


#: The adaptive stream wins outright when below this share of zstd's fast level: zstd's slow
#: level makes these integers about 1 % smaller than its fast one (streams.SEARCH_LEVEL), so
#: it could not win, and is not run.
ADAPTIVE_CLEARLY_SMALLER = 0.9


def coding_order(parents: Mesh | None, rows: int) -> adaptive.CodingOrder:
    """The order §6.14 codes a section's rows in: a mesh's for U1, ascending otherwise."""
    if isinstance(parents, MeshPrediction):
        steps = parents.mean_steps
        return adaptive.mesh_order(rows, steps.rows, steps.sources, steps.source_ends)
    return adaptive.sequence_order(rows)


class Predicted(NamedTuple):
    """The integers a section streams, each column's predictor and each column's push of
    predictor 2 (PUSH where it has none)."""

    stream: np.ndarray
    predict: np.ndarray
    push: np.ndarray


def section_stream(
    q: np.ndarray,
    parents: Mesh | None,
    allow_predict: bool,
    coding_tools: bool,
    pushes: bool = False,
) -> Predicted:
    """:func:`predicted_stream` where prediction is allowed and there is a row to predict from,
    else ``q`` itself."""
    if allow_predict and q.shape[0] > 1:
        # in a function of its own: the other predictors' residuals are freed before packing
        return predicted_stream(q, parents, coding_tools, pushes)
    return Predicted(q, np.zeros(q.shape[1], dtype=np.uint8), pushes_of(None, q.shape[1]))


def predicted_stream(
    q: np.ndarray, parents: Mesh | None, coding_tools: bool, pushes: bool = False
) -> Predicted:
    """The residuals to stream and each column's predictor: per column, the predictor whose
    residuals :func:`_cost` finds cheapest (ties to the lower one); with ``pushes`` (a U1 of
    format 1.6), predictor 2 with the push whose residuals are cheapest (ties to PUSH)."""
    choices, best, push = _predictor_choices(q, parents, coding_tools, pushes)
    predict = np.array([choices[j][0] for j in best], dtype=np.uint8)
    stream = choices[1][1]  # the parent's residuals: a fresh array
    for j, (value, columns) in enumerate(choices):
        if value != PREDICT_PARENT:
            chosen = np.flatnonzero(best == j)
            stream[:, chosen] = columns[:, chosen]  # in place: stream is a fresh array
    return Predicted(stream, predict, push)


def chosen_predictors(
    q: np.ndarray, parents: Mesh | None, coding_tools: bool, pushes: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`predicted_stream`'s predictors and pushes alone, without the stream it would
    assemble from the chosen residuals (the encoder's trials keep the predictors only)."""
    choices, best, push = _predictor_choices(q, parents, coding_tools, pushes)
    return np.array([choices[j][0] for j in best], dtype=np.uint8), push


def _predictor_choices(
    q: np.ndarray, parents: Mesh | None, coding_tools: bool, pushes: bool
) -> tuple[list[tuple[int, np.ndarray]], np.ndarray, np.ndarray]:
    """Each predictor's residuals (predictor 1's a fresh array, second), the index of each
    column's cheapest by :func:`_cost`, and each column's push."""
    mesh = parents if isinstance(parents, MeshPrediction) else None
    stream = residuals(q, parents.parents if isinstance(parents, MeshPrediction) else parents)
    choices = [(PREDICT_NONE, q), (PREDICT_PARENT, stream)]
    push = pushes_of(None, q.shape[1])
    if mesh is not None and coding_tools and mesh.levels <= MAX_MEAN_LEVELS:
        mean, push = _pushed_mean(q, mesh.mean_steps, pushes)
        if mean is not None:  # a column whose residuals would not fit 32 bits keeps to 0 or 1
            fits = np.abs(mean).max(axis=0) < 2**31
            choices.append((PREDICT_MEAN, mean if fits.all() else np.where(fits[None, :], mean, q)))
    elif parents is None and coding_tools and q.shape[0] > 2:
        linear = linear_residuals(q)  # along time: the second difference
        # a column may use 3 only if its residuals fit 32 bits and its values and running
        # differences stay in the ranges a decoder accepts (R32: 2**32 and 2**33)
        fits = (
            (np.abs(linear).max(axis=0) < 2**31)
            & (np.abs(q).max(axis=0) <= LINEAR_LIMIT)
            & (np.abs(np.cumsum(linear, axis=0)).max(axis=0) <= LINEAR_STEP_LIMIT)
        )
        if fits.any():
            choices.append((PREDICT_LINEAR, np.where(fits[None, :], linear, q)))
    costs = np.stack([_cost(columns) for _, columns in choices])
    best = costs.argmin(axis=0)  # ties go to the lower predictor
    return choices, best, push


def _pushed_mean(
    q: np.ndarray, steps: MeanSteps, choose: bool
) -> tuple[np.ndarray | None, np.ndarray]:
    """Predictor 2's residuals and each column's push: PUSH, or with ``choose`` the push of
    PUSHES whose residuals :func:`_cost` finds cheapest, PUSH first so that it wins ties (a
    few columns at a time, so that the candidates' residuals stay small beside a wide U1)."""
    push = pushes_of(None, q.shape[1])
    core = native.core()
    if choose and core is not None:
        return _native_pushed_mean(q, steps)
    mean = mean_residuals(q, steps)
    if not choose or mean is None:
        return mean, push
    best = _cost(mean)
    for start in range(0, q.shape[1], _PUSH_BLOCK):
        block = slice(start, start + _PUSH_BLOCK)
        width = mean[:, block].shape[1]
        for a in PUSHES:
            if a == PUSH:
                continue
            trial = mean_residuals(q[:, block], steps, np.full(width, a, dtype=np.uint8))
            if trial is None:
                continue
            cost = _cost(trial)
            better = np.flatnonzero(cost < best[block])
            if better.size:
                best[start + better] = cost[better]
                push[start + better] = a
                mean[:, start + better] = trial[:, better]
    return mean, push


#: Columns whose residuals :func:`_pushed_mean` tries at once for each push: a multiple of
#: :func:`_cost`'s block, so that each push's columns are priced in the same blocks as PUSH's.
_PUSH_BLOCK = 32
#: :func:`_cost`'s block of columns (its default).
_COST_BLOCK = 16
#: Residuals below this size are priced from :func:`_log2_table` by the compiled core.
_LOG2_TABLE_SIZE = 1 << 16


def _native_pushed_mean(q: np.ndarray, steps: MeanSteps) -> tuple[np.ndarray | None, np.ndarray]:
    """:func:`_pushed_mean` choosing, with the compiled core pricing every push of every
    column in one pass (:func:`_pushed_mean` forms ten matrices of residuals as large as
    ``q``): the same prices to the bit (numpy's log2 of each residual, from
    :func:`_log2_table`, summed in numpy's order), so the same pushes and residuals."""
    cols = q.shape[1]
    push = pushes_of(None, cols)
    contiguous = np.ascontiguousarray(q, dtype=np.int64)
    costs = steps.native_plan().push_costs(contiguous, _log2_table(), _COST_BLOCK)
    if costs is None:  # a value out of predictor 2's range
        return None, push
    unpriced = np.flatnonzero(np.isnan(costs[:, 0]))
    for start in np.unique(unpriced // _COST_BLOCK) * _COST_BLOCK:
        # a residual beyond the table: the block priced as the reference prices it
        block = slice(int(start), int(start) + _COST_BLOCK)
        width = contiguous[:, block].shape[1]
        for a in PUSHES:
            trial = mean_residuals(contiguous[:, block], steps, np.full(width, a, dtype=np.uint8))
            assert trial is not None  # the whole is within the range
            costs[block, a] = _cost(trial)
    best = costs[:, PUSH].copy()
    for a in PUSHES:  # PUSH first, then the others in order: a strictly lower price wins
        if a == PUSH:
            continue
        better = costs[:, a] < best
        best[better] = costs[better, a]
        push[better] = a
    return mean_residuals(contiguous, steps, push), push


@functools.cache
def _log2_table() -> np.ndarray:
    """``log2(1 + 2m)`` for m below :data:`_LOG2_TABLE_SIZE`, by the numpy operations that
    :func:`_cost` applies to each residual (the compiled core prices residuals from it)."""
    part = np.abs(np.arange(_LOG2_TABLE_SIZE, dtype=np.int64)).astype(np.float64)
    part *= 2.0
    part += 1.0
    np.log2(part, out=part)
    part.flags.writeable = False
    return part


def decode_matrix(
    payload: bytes | memoryview,
    params: dict[str, Any],
    parents: Mesh | Callable[[], Mesh] | None,
    where: str,
    *,
    allow_predict: bool = True,
    coding_tools: bool = False,
    adaptive_coding: bool = False,
) -> QuantizedMatrix:
    """The quantized matrix of a qmat section (§6.3). The caller has checked ``shape`` against
    the header and the limits. ``adaptive_coding``: the section may store its integers with
    §6.14's coder (a position factor of a file with flag bit 3).

    ``parents`` as in :func:`.prediction.accumulate`, a mesh's
    :class:`~tuckercodec.model.topology.MeshPrediction`, or a function that makes either: it is
    called only once the stream has decoded and only if a column is predicted, so that their
    cost (arrays of ``rows`` entries) is never paid for a payload that turns out bad.
    Predictor 2 (the mean of the decoded neighbours) is accepted only with ``coding_tools``
    (the preamble's flag bit 1, format 1.2) and a mesh (``parents`` not ``None``).
    """
    rows, cols, planes, steps, predict = _checked_params(
        params, where, parents is not None, allow_predict, coding_tools
    )
    pushes = _pushes(params, where, cols, adaptive_coding and parents is not None)
    if _coder(params, where, adaptive_coding) == adaptive.CODER_ADAPTIVE:
        if callable(parents):
            parents = parents()
        stream = _adaptive_stream(payload, rows, cols, planes, parents, where)
    else:
        stream = streams.unpack_integers(payload, rows * cols, planes, where)
    chosen = np.flatnonzero(predict == PREDICT_PARENT)
    meaned = np.flatnonzero(predict == PREDICT_MEAN)
    if cols and meaned.size == cols:  # U1's usual case: restored in the stream, no copy made
        mesh = parents() if callable(parents) else parents
        columns = stream.reshape(cols, rows)
        mesh = mesh if isinstance(mesh, MeshPrediction) else None
        _restore_mean(columns, mesh, pushes, where, True)
        return QuantizedMatrix(columns.T, steps)
    q = np.ascontiguousarray(stream.reshape(cols, rows).T)
    if chosen.size or meaned.size:
        if callable(parents):
            parents = parents()
        mesh = parents if isinstance(parents, MeshPrediction) else None
        tree = parents.parents if isinstance(parents, MeshPrediction) else parents
        if chosen.size == cols:  # every column (U1's usual case): restored where it lies
            accumulate(q, tree, in_place=True)
        elif chosen.size:
            q[:, chosen] = accumulate(q[:, chosen], tree)
        if meaned.size:
            q[:, meaned] = _restore_mean(q[:, meaned], mesh, pushes[meaned], where)
    linear = np.flatnonzero(predict == PREDICT_LINEAR)
    if linear.size:
        try:
            q[:, linear] = linear_accumulate(q[:, linear])
        except ValueError as error:
            _refuse_predictor(f"{error} (-2**33..2**33 for differences, -2**32..2**32)", where)
    return QuantizedMatrix(q, steps)


def _pushes(params: dict[str, Any], where: str, cols: int, allowed: bool) -> np.ndarray:
    """Each column's push of predictor 2 (§6.2, ``mean_push``, format 1.6; R32): PUSH where
    the section gives none; ``allowed``: a U1 section of a file with flag bit 3."""
    raw = params.get("mean_push")
    if raw is None:
        return pushes_of(None, cols)
    if not allowed:
        _refuse_predictor("mean_push is allowed only in U1 of a file with flag bit 3", where)
    if not isinstance(raw, bytes) or len(raw) != cols:
        _refuse_predictor(f"mean_push must be {cols} bytes", where)
    pushes = np.frombuffer(raw, dtype=np.uint8)
    if int(pushes.max(initial=0)) > PUSHES[-1]:
        _refuse_predictor(f"every mean_push byte must be 0..{PUSHES[-1]}", where)
    return pushes


def _checked_params(
    params: dict[str, Any], where: str, mesh_relation: bool, allow_predict: bool, coding_tools: bool
) -> tuple[int, int, int, np.ndarray, np.ndarray]:
    """``(rows, cols, planes, steps, predict)`` of a qmat section, checked in §5 step 16's
    order (R30, R31, R32); ``mesh_relation``: the rows follow a mesh (predictor 2's relation)."""
    rows, cols = section_shape(params, where)
    planes = streams.checked_planes(params, where)
    steps_raw, predict_raw = params.get("steps"), params.get("predict")
    # §5 step 16: the lengths and types of steps and predict, then their values
    if not isinstance(steps_raw, bytes) or len(steps_raw) != 4 * cols:
        raise FormatError(
            f"steps must be {cols} float32 values as {4 * cols} bytes",
            rule="R31-steps",
            field=f"{where}.steps",
        )
    if not isinstance(predict_raw, bytes) or len(predict_raw) != cols:
        _refuse_predictor(f"predict must be {cols} bytes", where)
    steps = np.frombuffer(steps_raw, dtype="<f4").astype(np.float32)
    if not (np.isfinite(steps).all() and (steps > 0).all()):
        raise FormatError(
            "every step must be a positive finite float32", rule="R31-steps", field=f"{where}.steps"
        )
    predict = np.frombuffer(predict_raw, dtype=np.uint8)
    # 2 (mesh mean) for a mesh relation, 3 (linear) for the previous row, both only in 1.2
    extra = PREDICT_MEAN if mesh_relation else PREDICT_LINEAR
    allowed = {PREDICT_NONE, PREDICT_PARENT} | ({extra} if coding_tools else set())
    if not allow_predict:
        allowed = {PREDICT_NONE}
    if not set(predict.tolist()) <= allowed:
        named = "0 (no parent relation here)" if not allow_predict else f"in {sorted(allowed)}"
        if allow_predict and not coding_tools and (predict == extra).any():
            named += f" ({extra} needs the coding tools flag of format 1.2)"
        _refuse_predictor(f"every predictor must be {named}", where)
    return rows, cols, planes, steps, predict


def _coder(params: dict[str, Any], where: str, adaptive_coding: bool) -> int:
    """The section's ``coder`` (§6.14): 0 when absent; 1 only where ``adaptive_coding``."""
    return adaptive.checked_coder(params.get("coder", adaptive.CODER_ZSTD), where, adaptive_coding)


def _adaptive_stream(
    payload: bytes | memoryview, rows: int, cols: int, planes: int, parents: Mesh | None, where: str
) -> np.ndarray:
    """The column-major integers of an adaptive stream, each within the section's planes."""
    order = coding_order(parents, rows)
    return adaptive.decode_within_planes(payload, cols, rows, planes, order, where).reshape(-1)


def decode_values(
    payload: bytes | memoryview,
    params: dict[str, Any],
    parents: Mesh | Callable[[], Mesh],
    where: str,
    *,
    coding_tools: bool = False,
    adaptive_coding: bool = False,
    beside: Callable[[], object] | None = None,
) -> np.ndarray:
    """``decode_matrix(...).values()`` of a section whose rows follow a mesh (U1), for a caller
    that needs no integers. When every column has predictor 2 (U1's usual case) the compiled
    core goes from the stream's bytes to the floats in one pass, its threads sharing the
    columns, without the int64 matrix (as large as the floats); from an adaptive stream
    (§6.14), which decodes a column after the other, one thread restores while another
    decodes. ``beside``, if given, is called once the compiled core is about to decode with
    the GIL released (after the Python work before it, which then waits for no other thread's
    GIL); it is not called where the matrix is decoded otherwise."""
    core = native.core()
    rows, cols, planes, steps, predict = _checked_params(params, where, True, True, coding_tools)
    pushes = _pushes(params, where, cols, adaptive_coding)
    zstd = _coder(params, where, adaptive_coding) == adaptive.CODER_ZSTD
    if core is None or not (rows and cols) or not (predict == PREDICT_MEAN).all():
        return decode_matrix(
            payload,
            params,
            parents,
            where,
            coding_tools=coding_tools,
            adaptive_coding=adaptive_coding,
        ).values()
    if not zstd:
        return _adaptive_values(
            core,
            payload,
            params,
            parents,
            where,
            coding_tools,
            (rows, planes, steps, pushes),
            beside,
        )
    raw = streams.decompress_exact(payload, rows * cols * planes, where)
    mesh = parents() if callable(parents) else parents
    plan = _mean_mesh(mesh if isinstance(mesh, MeshPrediction) else None, where).native_plan()
    if beside is not None:
        beside()
    try:
        values: np.ndarray = (
            plan.restore_values(raw, planes, rows, steps, 0)
            if (pushes == PUSH).all()
            else plan.restore_values(raw, planes, rows, steps, 0, pushes)
        )
    except ValueError:
        _refuse_predictor(MEAN_RANGE_MESSAGE, where)
    return values


def _adaptive_values(
    core: Any,
    payload: bytes | memoryview,
    params: dict[str, Any],
    parents: Mesh | Callable[[], Mesh],
    where: str,
    coding_tools: bool,
    checked: tuple[int, int, np.ndarray, np.ndarray],
    beside: Callable[[], object] | None = None,
) -> np.ndarray:
    """:func:`decode_values` of an adaptive stream (§6.14) whose every column has predictor 2:
    the compiled core decodes it and restores each block of columns on a second thread while
    the next ones decode. ``checked``: the section's rows, planes, steps and pushes;
    ``beside``: :func:`decode_values`'."""
    rows, planes, steps, pushes = checked
    mesh = parents() if callable(parents) else parents
    if not isinstance(mesh, MeshPrediction) or mesh.levels > MAX_MEAN_LEVELS:
        # the reference's order of errors: the stream's before the mesh's depth
        return decode_matrix(
            payload, params, mesh, where, coding_tools=coding_tools, adaptive_coding=True
        ).values()
    plan = _mean_mesh(mesh, where).native_plan()
    order = adaptive.order_arrays(coding_order(mesh, rows))
    push = None if (pushes == PUSH).all() else pushes
    stream = bytes(payload)
    if beside is not None:
        beside()
    try:
        values: np.ndarray = plan.restore_adaptive_values(
            stream, *order, planes, rows, steps, 0, push
        )
    except core.Broken as error:
        adaptive.refuse(error.args[1], where)
    except ValueError:
        _refuse_predictor(MEAN_RANGE_MESSAGE, where)
    return values


def _restore_mean(
    residual: np.ndarray,
    mesh: MeshPrediction | None,
    pushes: np.ndarray,
    where: str,
    in_columns: bool = False,
) -> np.ndarray:
    """Predictor 2's columns restored (§6.2), each with its push, or R32 when its conditions
    fail; with ``in_columns``, ``residual`` is (cols, rows) and restored in place."""
    steps = _mean_mesh(mesh, where)
    try:
        if in_columns:
            mean_accumulate_columns(residual, steps, pushes)
            return residual
        return mean_accumulate(residual, steps, pushes)
    except ValueError:
        _refuse_predictor(MEAN_RANGE_MESSAGE, where)


def _mean_mesh(mesh: MeshPrediction | None, where: str) -> MeanSteps:
    """The mesh's predictor-2 steps, or R32 when the mesh is too deep for predictor 2."""
    if mesh is None:
        raise ValueError("predictor 2 needs the mesh's MeshPrediction, not only its parents")
    if mesh.levels > MAX_MEAN_LEVELS:
        _refuse_predictor(
            f"predictor 2 is allowed only on a mesh whose breadth-first forest has at most "
            f"{MAX_MEAN_LEVELS} levels; this one has {mesh.levels}",
            where,
        )
    return mesh.mean_steps


#: R32's words for a value that predictor 2 restores out of range.
MEAN_RANGE_MESSAGE = "a value restored with predictor 2 is outside -2**32..2**32"


def _refuse_predictor(message: str, where: str) -> NoReturn:
    raise FormatError(message, rule="R32-predictor", field=f"{where}.predict")
