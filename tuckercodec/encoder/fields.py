"""The encoder of animated fields (§6.13): one field's sections for a relative-error target
(mode tucker), a bound on every value (mode grid) or lossless (mode exact).

Every choice is measured on what a decoder returns: the sections are decoded with
:func:`~tuckercodec.format.fields.decode_field` and compared with the input, and a step that
misses its target is made finer until it meets it.

* tucker: ranks from the exact truncation errors (:mod:`.field_tucker`), for a few shares of
  the error between truncation and quantization; each share's quantization step from the
  rounding model (a step s adds about s**2 / 12 a value, as the positions' encoder assumes),
  tightened until the decoded field meets the target; the smallest file wins. A field
  constant over its elements in every frame (nothing to decompose) is stored exact.
* grid: q = round(x / step), step just under 2e; every decoded value is checked, and a q off
  by float rounding moved by one.
* exact: the ordered integers of the values' bits.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import zstandard

from ..errors import UnreachableTargetError
from ..format import fields as fmt
from ..format import qmat, streams
from ..format.limits import Limits
from ..format.residual import CHUNK_VALUES
from ..format.sections import QMAT, Section
from ..model.attributes import FACE, Field
from ..model.topology import MeshPrediction
from .field_tucker import FieldDecomposition, cheapest_ranks, decompose
from .whole import column_steps

#: The shares of the error budget given to truncation, one trial each.
TRUNCATION_SHARES = (0.5, 0.7, 0.85)
#: Tries per share at ever finer steps before giving the share up.
STEP_TRIES = 5
#: How far under 2e the grid's step is at least (room for the rounding of q * step; an ulp
#: of the largest value if that is more).
GRID_ROOM = 2.0**-20
#: A value within this fraction of e of the bound counts as over it (float64's subtraction
#: may round the difference by far less).
BOUND_MARGIN = 2.0**-40

Sections = list[tuple[dict[str, Any], bytes]]


@dataclass
class FieldTarget:
    """What a field must meet: exactly one of ``relative`` (the relative-rms error, in percent,
    mode tucker), ``max_error`` (a bound on every value, in the field's units, mode grid) and
    ``lossless`` (mode exact)."""

    relative: float | None = None
    max_error: float | None = None
    lossless: bool = False

    def __post_init__(self) -> None:
        given = (self.relative is not None) + (self.max_error is not None) + bool(self.lossless)
        if given != 1:
            raise ValueError("a field target is one of relative, max_error or lossless")
        for name in ("relative", "max_error"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ValueError(f"a field's {name} target must be a finite number > 0")

    @classmethod
    def parse(cls, text: str) -> FieldTarget:
        """``rel:0.1`` (relative-rms, percent), ``max:0.001`` (every value within 0.001) or
        ``lossless``."""
        kind, _, number = text.strip().partition(":")
        if kind == "lossless" and not number:
            return cls(lossless=True)
        if kind in ("rel", "max"):
            try:
                value = float(number)
            except ValueError:
                value = math.nan
            if math.isfinite(value) and value > 0:
                return cls(relative=value) if kind == "rel" else cls(max_error=value)
        raise ValueError(
            f"a field target is rel:PERCENT (relative-rms error), max:BOUND (every value within "
            f"BOUND) or lossless, with a number > 0; got {text!r}"
        )


@dataclass
class FieldReport:
    """What one field's encode chose and measured."""

    name: str
    mode: str
    definition: str
    error: float
    target: float
    bytes: int


@dataclass
class EncodedField:
    """A field's sections (section-table entries without offset, length and CRC, and their
    payloads; the descriptor first) and its report."""

    sections: Sections
    report: FieldReport
    values: np.ndarray = field(repr=False)  # what a decoder returns


def relative_rms(original: np.ndarray, decoded: np.ndarray) -> float:
    """100 ||A - B|| / ||A - E(A)||, E(A) each frame's per-component mean over the elements
    (Karni and Gotsman's error, generalised to c components); 0 for B == A, inf when the
    denominator is 0 and B differs."""
    a = np.asarray(original, dtype=np.float64)
    error2 = float(np.square(a - np.asarray(decoded, dtype=np.float64)).sum())
    denominator2 = float(np.square(a - a.mean(axis=1, keepdims=True)).sum())
    if error2 == 0.0:
        return 0.0
    return math.inf if denominator2 == 0.0 else 100.0 * math.sqrt(error2 / denominator2)


def max_abs(original: np.ndarray, decoded: np.ndarray) -> float:
    """The largest |decoded - original|, in binary64."""
    if original.size == 0:
        return 0.0
    return float(np.abs(decoded.astype(np.float64) - original.astype(np.float64)).max())


def _type(values: np.ndarray) -> str:
    return "f32" if values.dtype == np.float32 else "f64"


def _descriptor(
    item: Field, number: int, mode: str, error: dict[str, Any], **params: object
) -> dict[str, Any]:
    return {
        "id": fmt.field_id(number),
        "critical": False,
        "codec": fmt.FIELD_CODEC,
        "name": item.name,
        "role": item.role,
        "domain": item.domain,
        "components": item.components,
        "type": _type(item.values),
        "mode": mode,
        "error": error,
        **params,
    }


def section_lookup(
    sections: Sections,
) -> tuple[Callable[[str], Section | None], Callable[[str], memoryview]]:
    """A field's sections as a decoder finds them in a file: its section by id (``None`` where
    there is none) and its payload by id."""
    table = {
        entry["id"]: Section(
            entry["id"],
            0,
            len(payload),
            0,
            entry["critical"],
            entry["codec"],
            {k: v for k, v in entry.items() if k not in ("id", "critical", "codec")},
        )
        for entry, payload in sections
    }
    payloads = {entry["id"]: memoryview(payload) for entry, payload in sections}
    return table.get, payloads.__getitem__


def decoded(
    sections: Sections, number: int, item: Field, mesh: MeshPrediction | None
) -> np.ndarray:
    """What a decoder returns for ``sections``: decoded as a file's would be."""
    section_of, payload_of = section_lookup(sections)
    frames, count, _ = item.values.shape
    return fmt.decode_field(
        number,
        section_of,
        payload_of,
        count,
        count,
        frames,
        mesh,
        Limits(
            max_positions=1 << 62,
            max_factor_values=1 << 62,
            max_section_bytes=1 << 62,
            max_chunk_values=1 << 62,
        ),
    ).values


# -- grid and exact ---------------------------------------------------------------------------


def _chunk_frames(item: Field) -> int:
    frames, count, components = item.values.shape
    return max(1, min(frames, CHUNK_VALUES // max(1, count * components)))


def _cheapest_predictor(integers: np.ndarray) -> int:
    """The predictor whose residuals look cheapest (mean log2(1 + 2|r|) over a sample of
    elements), ties to the lower one."""
    sample = integers[:, :: max(1, integers.shape[1] // 4096)]
    costs = []
    for predict in fmt.PREDICTORS:
        residual = np.abs(fmt.predicted(sample, predict).astype(np.float64))
        costs.append(float(np.log2(1.0 + 2.0 * residual).mean()) if residual.size else 0.0)
    return int(np.argmin(costs))


def _chunked_sections(
    item: Field,
    number: int,
    integers: np.ndarray,
    mode: str,
    error: dict[str, Any],
    level: int,
    **params: object,
) -> Sections:
    predict = _cheapest_predictor(integers)
    chunk_frames = _chunk_frames(item)
    chunks, payload = fmt.pack_chunks(integers, predict, chunk_frames, level)
    entry = _descriptor(
        item,
        number,
        mode,
        error,
        **params,
        predict=predict,
        chunk_frames=chunk_frames,
        chunks=chunks,
    )
    return [(entry, payload)]


def encode_exact(item: Field, number: int, level: int) -> EncodedField:
    """Mode exact: the values bit for bit."""
    error = {"definition": fmt.EXACT_DEFINITION, "value": 0.0, "target": 0.0}
    integers = fmt.exact_integers(item.values)
    sections = _chunked_sections(item, number, integers, fmt.EXACT, error, level)
    back = decoded(sections, number, item, None)
    if back.tobytes() != item.values.tobytes():
        raise AssertionError("mode exact did not decode bit for bit")
    return _result(item, sections, fmt.EXACT, fmt.EXACT_DEFINITION, 0.0, 0.0, back)


def grid_integers(values: np.ndarray, bound: float) -> tuple[float, np.ndarray] | None:
    """``(step, q)`` keeping every decoded value within ``bound`` of ``values``, each q checked
    and moved by one where float rounding took it over; None when the values are too large
    for the bound (float64 or the values' own type cannot resolve it)."""
    largest = float(np.abs(values).max()) if values.size else 0.0
    ulp = float(np.spacing(np.array(largest, dtype=values.dtype)))
    if largest and bound <= 64 * ulp:
        return None
    # room for q * step's rounding to the values' type: half an ulp, and a little more
    step = 2.0 * (bound - max(GRID_ROOM * bound, ulp))
    x = values.astype(np.float64)
    q = np.rint(x / step)
    if q.size and np.abs(q).max() > fmt.GRID_LARGEST:
        return None
    q = q.astype(np.int64)
    limit = bound * (1.0 - BOUND_MARGIN)
    over = np.abs(fmt.grid_values(q, step, values.dtype).astype(np.float64) - x) > limit
    for nudge in (-1, 1):  # the rare q that rounding put over: its neighbours
        if not over.any():
            break
        moved = q[over] + nudge
        fits = np.abs(fmt.grid_values(moved, step, values.dtype).astype(np.float64) - x[over])
        fits = fits <= limit
        index = np.flatnonzero(over)[fits]
        q.reshape(-1)[index] = moved[fits]
        over.reshape(-1)[index] = False
    return None if over.any() else (step, q)


def encode_grid(item: Field, number: int, bound: float, level: int) -> EncodedField:
    """Mode grid: every value within ``bound``; mode exact where the values are too large for
    the bound to be resolved."""
    found = grid_integers(item.values, bound)
    if found is None:
        return encode_exact(item, number, level)
    step, q = found
    error = {"definition": fmt.MAX_ABS, "value": 0.0, "target": bound}
    sections = _chunked_sections(item, number, q, fmt.GRID, error, level, step=step)
    back = decoded(sections, number, item, None)
    achieved = max_abs(item.values, back)
    if achieved > bound:
        raise AssertionError(f"mode grid decoded {achieved} beyond its bound {bound}")
    sections[0][0]["error"]["value"] = achieved
    return _result(item, sections, fmt.GRID, fmt.MAX_ABS, achieved, bound, back)


def _result(
    item: Field,
    sections: Sections,
    mode: str,
    definition: str,
    error: float,
    target: float,
    back: np.ndarray,
) -> EncodedField:
    size = sum(len(payload) for _, payload in sections)
    report = FieldReport(item.name, mode, definition, error, target, size)
    return EncodedField(sections, report, back)


# -- tucker -----------------------------------------------------------------------------------


@dataclass
class _Trial:
    sections: Sections
    error: float
    size: int
    values: np.ndarray


def _tucker_sections(
    item: Field,
    number: int,
    decomposition: FieldDecomposition,
    ranks: tuple[int, int],
    step: float,
    mesh: MeshPrediction | None,
    level: int,
) -> Sections:
    """The descriptor and the four qmat sections of ranks (i, k) quantized with the single
    parameter D = ``step`` (each value adds about D / 12 to the squared error)."""
    i, k = ranks
    u1, u3, core = decomposition.factors(i, k)
    root = math.sqrt(step)
    count = item.values.shape[1]
    quantized = {
        "U1": qmat.quantize(u1, column_steps(root, np.sqrt(np.square(core).sum(axis=(1, 2))))),
        "U3": qmat.quantize(u3, column_steps(root, np.sqrt(np.square(core).sum(axis=(0, 1))))),
        "CORE": qmat.quantize(core.reshape(-1, 1), np.array([root])),
        # a mean's error moves all N elements
        "MEAN": qmat.quantize(
            decomposition.mean, np.full(item.components, root / math.sqrt(count))
        ),
    }
    on_mesh = item.domain != FACE and mesh is not None
    relation: dict[str, tuple[MeshPrediction | None, bool]] = {
        "U1": (mesh if on_mesh else None, on_mesh),
        "U3": (None, True),
        "CORE": (None, False),
        "MEAN": (None, True),
    }
    entry = _descriptor(
        item, number, fmt.TUCKER, {}, ranks=[i, k], u2=decomposition.u2.reshape(-1).tolist()
    )
    sections: Sections = [(entry, b"")]
    for part in fmt.TUCKER_PARTS:
        parents, predict = relation[part]
        params, payload = qmat.encode_matrix(
            quantized[part], parents, allow_predict=predict, coding_tools=True, level=level
        )
        part_entry = {"id": f"{entry['id']}.{part}", "critical": False, "codec": QMAT, **params}
        sections.append((part_entry, payload))
    return sections


def _ranks_trial(
    item: Field,
    number: int,
    decomposition: FieldDecomposition,
    ranks: tuple[int, int],
    target: float,
    mesh: MeshPrediction | None,
) -> _Trial | None:
    """``ranks`` at the coarsest step tried that meets the target (packed at the search
    level), the first step the one the rest of the budget allows; None if no step of
    :data:`STEP_TRIES` meets it."""
    limit2 = (target / 100.0) ** 2 * decomposition.energy
    n, c, f = decomposition.tensor.shape
    stored = n * ranks[0] + f * ranks[1] + c * ranks[0] * ranks[1] + c * f
    room2 = limit2 - decomposition.truncation_error2(*ranks)
    if room2 <= 0:
        return None
    step = 12.0 * room2 / stored
    for _ in range(STEP_TRIES):
        try:
            sections = _tucker_sections(
                item, number, decomposition, ranks, step, mesh, streams.SEARCH_LEVEL
            )
        except UnreachableTargetError:
            return None
        back = decoded(sections, number, item, mesh)
        error = relative_rms(item.values, back)
        if error <= target:
            size = sum(len(payload) for _, payload in sections)
            return _Trial(sections, error, size, back)
        # the squared error scales about as the step: aim a little under
        step *= 0.9 * (target / error) ** 2 if math.isfinite(error) and error > 0 else 0.25
    return None


def encode_tucker(
    item: Field, number: int, target: float, mesh: MeshPrediction | None, level: int
) -> EncodedField:
    """Mode tucker meeting ``target`` (relative-rms, percent) on the decoded field, the
    smallest of the trials; mode exact for a field with nothing to decompose (constant over
    its elements) or when no trial meets the target."""
    if item.domain != FACE and mesh is None:
        raise ValueError("a vertex field in mode tucker needs the mesh's MeshPrediction")
    frames, count, _ = item.values.shape
    if frames == 0 or count == 0:
        return encode_exact(item, number, level)
    decomposition = decompose(item.values)
    if decomposition.energy == 0.0:
        return encode_exact(item, number, level)
    limit2 = (target / 100.0) ** 2 * decomposition.energy
    choices = [cheapest_ranks(decomposition, share * limit2) for share in TRUNCATION_SHARES]
    decomposition.prepare(choices)
    best: _Trial | None = None
    for ranks in dict.fromkeys(choices):  # each distinct choice once
        trial = _ranks_trial(item, number, decomposition, ranks, target, mesh)
        if trial is not None and (best is None or trial.size < best.size):
            best = trial
    if best is None:
        return encode_exact(item, number, level)
    truncation = 100.0 * math.sqrt(
        decomposition.truncation_error2(*best.sections[0][0]["ranks"]) / decomposition.energy
    )
    error = {
        "definition": fmt.RELATIVE_RMS,
        "value": best.error,
        "target": target,
        "truncation": truncation,
    }
    sections = _repacked(best.sections, level)
    sections[0][0]["error"] = error
    return _result(item, sections, fmt.TUCKER, fmt.RELATIVE_RMS, best.error, target, best.values)


def _repacked(sections: Sections, level: int) -> Sections:
    """The same sections with every stream compressed again at ``level``: the same integers,
    so the same decoded values."""
    out: Sections = []
    for entry, payload in sections:
        if payload:
            raw = streams.zstd_exact(payload, _content_size(payload))
            payload = streams.compress(raw, level)
        out.append((dict(entry), payload))
    return out


def _content_size(payload: bytes) -> int:
    return int(zstandard.frame_content_size(payload))


# -- the entry point --------------------------------------------------------------------------


def encode_field(
    item: Field,
    number: int,
    target: FieldTarget,
    mesh: MeshPrediction | None,
    level: int = streams.DEFAULT_LEVEL,
) -> EncodedField:
    """Field ``item`` as the sections of field ``number`` (``FLD.<number>`` and, in mode tucker,
    its four qmat sections), meeting ``target`` on the values a decoder returns. ``mesh``: the
    file's U1 mesh prediction, which a vertex field in mode tucker predicts its U1 with."""
    if target.lossless:
        return encode_exact(item, number, level)
    if target.max_error is not None:
        return encode_grid(item, number, target.max_error, level)
    assert target.relative is not None
    return encode_tucker(item, number, target.relative, mesh, level)


#: The encoder of each mode, for the benchmarks and tests that force one.
ENCODERS: dict[str, Callable[..., EncodedField]] = {
    fmt.EXACT: encode_exact,
    fmt.GRID: encode_grid,
    fmt.TUCKER: encode_tucker,
}
