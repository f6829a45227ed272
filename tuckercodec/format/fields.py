"""§6.13 Codec ``field``: animated fields (format 1.5), per vertex or per face, beside the
positions.

Field number n is the ancillary section ``FLD.<n>`` (codec ``field``), whose parameters
describe it (name, role, domain, components, value type) and say how it is stored (``mode``):

* ``tucker``: each frame's per-component mean over the elements (MEAN, F x c) and a Tucker
  decomposition of the rest, the N x c x F tensor truncated to ranks (i, c, k): the qmat
  sections ``FLD.<n>.U1`` (N x i), ``FLD.<n>.U3`` (F x k), ``FLD.<n>.CORE`` (i*c*k x 1) and
  ``FLD.<n>.MEAN`` (F x c), with ``u2`` (c x c) in the parameters; the descriptor's payload is
  empty.
* ``grid``: integers q with value = q * step, and ``exact``: the ordered integers of the
  values' binary32 or binary64 bits (as §6.9 defines them). Both are predicted along time
  within chunks of ``chunk_frames`` frames, each chunk one zstd frame of zigzagged 64-bit
  integers in byte planes, the chunks back to back in the descriptor's payload; a decoder
  reads only the chunks of the frames it is asked for.

Every parameter is checked before anything is allocated; a bad one is R45-field, a size beyond
the decoder's limits R21-header-limit. The qmat sections' own parameters and streams are
checked as §6.3 checks U1, U3, CORE and CENT (R28, R30-R32), and the zstd frames as §6.1 does
(R29).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NoReturn, TypeGuard

import numpy as np

from ..errors import FormatError
from ..model.attributes import FACE, FIELD_DOMAINS, FIELD_ROLES, GENERIC, MAX_NAME_BYTES, Field
from ..model.topology import MeshPrediction
from . import qmat, streams
from .limits import Limits, check_limit
from .residual import FINITE32, FINITE64, from_ordered32, from_ordered64, ordered32, ordered64
from .sections import QMAT, Section, check_stream_size, section_shape

#: The codec of a field's descriptor section, and its ids' stem: ``FLD.<n>``.
FIELD_CODEC = "field"
FIELD_STEM = "FLD"
TUCKER, GRID, EXACT = "tucker", "grid", "exact"
MODES = (TUCKER, GRID, EXACT)
#: The ``type`` parameter: the dtype a decoder returns.
TYPES: dict[str, np.dtype[Any]] = {"f32": np.dtype(np.float32), "f64": np.dtype(np.float64)}
#: The qmat sections of a field in mode tucker, in the order a decoder reads them.
TUCKER_PARTS = ("U1", "U3", "CORE", "MEAN")
#: ``predict`` of the chunked modes: q itself, q[t] - q[t-1], q[t] - (2 q[t-1] - q[t-2]).
PREDICT_NONE, PREDICT_PREVIOUS, PREDICT_LINEAR = 0, 1, 2
PREDICTORS = (PREDICT_NONE, PREDICT_PREVIOUS, PREDICT_LINEAR)
#: A chunk's integers are 64-bit: up to 8 byte planes.
MAX_CHUNK_PLANES = 8
#: |q| allowed on a grid: q * step is then q's own value times step, q exact in binary64.
GRID_LARGEST = 2**53
#: The error definitions of the ``error`` map (informative).
RELATIVE_RMS, MAX_ABS, EXACT_DEFINITION = "relative-rms", "max-abs", "exact"
_CONTROL = frozenset(chr(n) for n in range(32)) | {"\x7f"}


def field_id(number: int) -> str:
    """The descriptor section's id of field ``number``: ``FLD.<n>``."""
    return f"{FIELD_STEM}.{number}"


def field_ids(params: Mapping[str, Any], number: int) -> list[str]:
    """The ids of the sub-sections the descriptor ``FLD.<number>`` with ``params`` needs beside
    itself: the four qmat sections in mode tucker, none otherwise (or for an unknown mode,
    which :func:`decode_field` refuses)."""
    if params.get("mode") != TUCKER:
        return []
    return [f"{field_id(number)}.{part}" for part in TUCKER_PARTS]


def is_field_section(section_id: str) -> bool:
    """Whether ``section_id`` is a field's descriptor or one of its sub-sections."""
    parts = section_id.split(".")
    return (
        parts[0] == FIELD_STEM
        and len(parts) in (2, 3)
        and parts[1].isdigit()
        and (len(parts) == 2 or parts[2] in TUCKER_PARTS)
    )


@dataclass(frozen=True)
class FieldHeader:
    """A descriptor's checked parameters common to every mode."""

    name: str
    role: str
    domain: str
    components: int
    dtype: np.dtype[Any]
    mode: str
    elements: int  # N: the vertex count, or the face count
    frames: int

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.frames, self.elements, self.components


@dataclass(frozen=True)
class ChunkLayout:
    """The checked parameters of a field in mode grid or exact."""

    step: float | None
    predict: int
    chunk_frames: int
    planes: tuple[int, ...]
    offsets: tuple[int, ...]  # len(planes) + 1 byte offsets into the payload
    frames: int

    def chunk_range(self, chunk: int) -> tuple[int, int]:
        start = chunk * self.chunk_frames
        return start, min(self.frames, start + self.chunk_frames)


def check_unique_names(names: list[str]) -> None:
    """No two fields share a name (R45)."""
    for number, name in enumerate(names):
        if name in names[:number]:
            refuse(f"two fields are named {name!r}", f"section FLD.{number}.name")


def refuse(message: str, where: str) -> NoReturn:
    """R45-field: a field's parameter or value is not as §6.13 says."""
    raise FormatError(message, rule="R45-field", field=where)


def _is_int(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool)


def read_header(
    params: Mapping[str, Any], where: str, vertices: int, faces: int, frames: int, limits: Limits
) -> FieldHeader:
    """The descriptor's parameters common to every mode, in §6.13's order: ``name``, ``role``,
    ``domain``, ``components``, ``type``, ``mode`` (R45-field), then the values' count against
    the limits (R21-header-limit)."""
    name = params.get("name")
    if not (
        isinstance(name, str)
        and 1 <= len(name.encode("utf-8", "surrogatepass")) <= MAX_NAME_BYTES
        and not (_CONTROL & set(name))
        and not any(0xD800 <= ord(char) <= 0xDFFF for char in name)
    ):
        refuse(f"name must be 1 to {MAX_NAME_BYTES} UTF-8 bytes, no control character", where)
    role = params.get("role")
    if not isinstance(role, str):
        refuse(f"role must be a str, got {role!r}", f"{where}.role")
    domain = params.get("domain")
    if domain not in FIELD_DOMAINS:
        refuse(f"domain must be vertex or face, got {domain!r}", f"{where}.domain")
    components = params.get("components")
    if not (_is_int(components) and 1 <= components <= 4):
        refuse(f"components must be an int from 1 to 4, got {components!r}", f"{where}.components")
    kind = params.get("type")
    if not isinstance(kind, str) or kind not in TYPES:
        refuse(f"type must be f32 or f64, got {kind!r}", f"{where}.type")
    mode = params.get("mode")
    if mode not in MODES:
        refuse(f"mode must be one of {', '.join(MODES)}, got {mode!r}", f"{where}.mode")
    elements = faces if domain == FACE else vertices
    # a position is 3 values: a field may decode as many values as max_positions positions
    check_limit(
        math.ceil(frames * elements * components / 3),
        limits,
        "max_positions",
        what=f"{frames} x {elements} x {components} field values (as positions of 3)",
        field=where,
    )
    return FieldHeader(
        name,
        role if role in FIELD_ROLES else GENERIC,
        domain,
        components,
        TYPES[kind],
        mode,
        elements,
        frames,
    )


def read_ranks(
    params: Mapping[str, Any], header: FieldHeader, limits: Limits, where: str
) -> tuple[int, int, np.ndarray]:
    """Mode tucker's ``ranks`` [i, k] (1 <= i <= N, 1 <= k <= F) and ``u2`` (c*c floats, all
    finite), R45-field; then the factors' values against ``max_factor_values`` (R21)."""
    ranks = params.get("ranks")
    n, frames, c = header.elements, header.frames, header.components
    if not (
        isinstance(ranks, list)
        and len(ranks) == 2
        and all(_is_int(rank) for rank in ranks)
        and 1 <= ranks[0] <= n
        and 1 <= ranks[1] <= frames
    ):
        refuse(f"ranks must be [i, k], 1 <= i <= {n}, 1 <= k <= {frames}", f"{where}.ranks")
    u2 = params.get("u2")
    if not (
        isinstance(u2, list)
        and len(u2) == c * c
        and all(isinstance(x, float) and math.isfinite(x) for x in u2)
    ):
        refuse(f"u2 must be {c * c} finite floats", f"{where}.u2")
    i, k = ranks
    check_limit(
        n * i + frames * k + c * i * k + c * frames,
        limits,
        "max_factor_values",
        what=f"the factors of ranks ({i}, {c}, {k}) on {n} elements and {frames} frames",
        field=f"{where}.ranks",
    )
    return i, k, np.array(u2, dtype=np.float64).reshape(c, c)


def read_chunks(
    params: Mapping[str, Any], header: FieldHeader, payload_length: int, limits: Limits, where: str
) -> ChunkLayout:
    """Mode grid's ``step`` (a finite float > 0), then ``predict`` (0, 1 or 2),
    ``chunk_frames`` (an int >= 1), ``chunks`` (ceil(F / chunk_frames) [planes 1..8, length
    >= 0], the lengths adding up to the payload's), all R45-field; then each chunk's size
    against ``max_section_bytes`` and, for a chunk of more than one frame, its integers against
    ``max_chunk_values`` (R21)."""
    step = None
    if header.mode == GRID:
        step = params.get("step")
        if not (isinstance(step, float) and math.isfinite(step) and step > 0):
            refuse(f"step must be a finite float > 0, got {step!r}", f"{where}.step")
    predict = params.get("predict")
    if not (_is_int(predict) and predict in PREDICTORS):
        refuse(f"predict must be 0, 1 or 2, got {predict!r}", f"{where}.predict")
    chunk_frames = params.get("chunk_frames")
    if not (_is_int(chunk_frames) and chunk_frames >= 1):
        refuse(f"chunk_frames must be an int >= 1, got {chunk_frames!r}", f"{where}.chunk_frames")
    chunk_frames = min(chunk_frames, max(1, header.frames))  # a larger one is one chunk
    count = -(-header.frames // chunk_frames)
    chunks = params.get("chunks")
    if not (isinstance(chunks, list) and len(chunks) == count):
        refuse(f"chunks must be an array of {count} [planes, length]", f"{where}.chunks")
    offsets = [0]
    for number, entry in enumerate(chunks):
        if not (
            isinstance(entry, list)
            and len(entry) == 2
            and all(_is_int(value) for value in entry)
            and 1 <= entry[0] <= MAX_CHUNK_PLANES
            and entry[1] >= 0
        ):
            refuse(
                f"a chunk is [planes 1..{MAX_CHUNK_PLANES}, length >= 0], got {entry!r}",
                f"{where}.chunks[{number}]",
            )
        offsets.append(offsets[-1] + entry[1])
    if offsets[-1] != payload_length:
        refuse(
            f"the chunks' lengths add up to {offsets[-1]} bytes, the payload has {payload_length}",
            f"{where}.chunks",
        )
    layout = ChunkLayout(
        step,
        predict,
        chunk_frames,
        tuple(entry[0] for entry in chunks),
        tuple(offsets),
        header.frames,
    )
    _check_chunk_sizes(layout, header, limits, where)
    return layout


def _check_chunk_sizes(
    layout: ChunkLayout, header: FieldHeader, limits: Limits, where: str
) -> None:
    per_frame = header.elements * header.components
    for number, planes in enumerate(layout.planes):
        start, stop = layout.chunk_range(number)
        count = (stop - start) * per_frame
        field = f"{where}.chunks[{number}]"
        check_limit(
            count * planes,
            limits,
            "max_section_bytes",
            what=f"chunk {number}'s {count} integers of {planes} bytes",
            field=field,
        )
        if stop - start > 1:  # a frame costs its whole chunk: held to a size of its own
            check_limit(
                count,
                limits,
                "max_chunk_values",
                what=f"chunk {number}'s {count} integers ({stop - start} frames)",
                field=field,
            )


# -- the chunks' integers ---------------------------------------------------------------------


def predicted(values: np.ndarray, predict: int) -> np.ndarray:
    """A chunk's integers (n, N, c) as stored: q, or its first or second difference along
    frames (frames before the chunk count as 0), int64 arithmetic wrapping."""
    out = np.array(values, dtype=np.int64)
    for _ in range(predict):
        out[1:] -= out[:-1].copy()
    return out


def restored(values: np.ndarray, predict: int) -> np.ndarray:
    """The inverse of :func:`predicted`, in place: ``predict`` running sums along frames."""
    for _ in range(predict):
        np.cumsum(values, axis=0, out=values)  # int64 addition wraps, as the encoder's did
    return values


def pack_chunk(values: np.ndarray, predict: int, level: int) -> tuple[int, bytes]:
    """``(planes, zstd frame)`` of one chunk's integers (n, N, c) (§6.1 on 64 bits)."""
    unsigned = streams.zigzag(predicted(values, predict).reshape(-1))
    planes = streams.planes_needed(unsigned)
    return planes, streams.compress(streams.to_planes(unsigned, planes), level)


def pack_chunks(
    integers: np.ndarray, predict: int, chunk_frames: int, level: int
) -> tuple[list[list[int]], bytes]:
    """``(chunks, payload)`` of a chunked field's integers (F, N, c)."""
    chunks: list[list[int]] = []
    pieces: list[bytes] = []
    for start in range(0, integers.shape[0], chunk_frames):
        planes, piece = pack_chunk(integers[start : start + chunk_frames], predict, level)
        chunks.append([planes, len(piece)])
        pieces.append(piece)
    return chunks, b"".join(pieces)


def _chunk_integers(
    payload: memoryview, layout: ChunkLayout, header: FieldHeader, chunk: int, where: str
) -> np.ndarray:
    start, stop = layout.chunk_range(chunk)
    count = (stop - start) * header.elements * header.components
    piece = payload[layout.offsets[chunk] : layout.offsets[chunk + 1]]
    values = streams.unpack_integers(piece, count, layout.planes[chunk], f"{where}.chunks[{chunk}]")
    values = values.reshape(stop - start, header.elements, header.components)
    return restored(values, layout.predict)


def grid_values(q: np.ndarray, step: float, dtype: np.dtype[Any]) -> np.ndarray:
    """A grid's values: q * step in binary64, rounded to ``dtype`` (nearest, ties to even)."""
    # a product beyond float64 is a property of the file, refused as R45 by the caller
    with np.errstate(over="ignore", invalid="ignore"):
        return (q.astype(np.float64) * step).astype(dtype)


def exact_integers(values: np.ndarray) -> np.ndarray:
    """The ordered integers (int64) of float32 or float64 values (§6.9's maps)."""
    return ordered32(values) if values.dtype == np.float32 else ordered64(values)


def _chunk_values(
    integers: np.ndarray, layout: ChunkLayout, header: FieldHeader, where: str
) -> np.ndarray:
    """A chunk's decoded values from its restored integers, or R45-field for one out of range."""
    if header.mode == GRID:
        assert layout.step is not None
        if integers.size and np.abs(integers).max() > GRID_LARGEST:
            refuse("a grid integer is beyond +-2**53", where)
        values = grid_values(integers, layout.step, header.dtype)
        if not np.isfinite(values).all():
            refuse("a grid value is not finite", where)
        return values
    low, high = FINITE32 if header.dtype == np.float32 else FINITE64
    if integers.size and (integers.min() < low or integers.max() > high):
        refuse(f"an exact integer is not the ordered integer of a finite {header.dtype}", where)
    if header.dtype == np.float32:
        return from_ordered32(integers)
    return from_ordered64(integers)


def _decode_chunked(
    header: FieldHeader,
    layout: ChunkLayout,
    payload: memoryview,
    frames_wanted: np.ndarray,
    where: str,
) -> np.ndarray:
    out = np.empty((frames_wanted.size, header.elements, header.components), dtype=header.dtype)
    chunk_of = frames_wanted // layout.chunk_frames
    for chunk in np.unique(chunk_of).tolist():
        start, _ = layout.chunk_range(chunk)
        integers = _chunk_integers(payload, layout, header, chunk, where)
        values = _chunk_values(integers, layout, header, f"{where}.chunks[{chunk}]")
        rows = np.flatnonzero(chunk_of == chunk)
        out[rows] = values[frames_wanted[rows] - start]
    return out


# -- mode tucker ------------------------------------------------------------------------------


def reconstruct_field(
    u1: np.ndarray, core: np.ndarray, u2: np.ndarray, u3_rows: np.ndarray, mean_rows: np.ndarray
) -> np.ndarray:
    """values[f, e, x] = sum_{a,d,b} U1[e, a] CORE[a, d, b] U2[x, d] U3[f, b] + MEAN[f, x], in
    binary64, shape (n, N, c) for the n rows of U3 and MEAN given."""
    basis = np.einsum("adb,xd->axb", core, u2)  # (i, c, k)
    i, c, _ = basis.shape
    weights = basis @ u3_rows.T  # (i, c, n)
    flat = u1 @ weights.reshape(i, -1)  # (N, c n)
    frames = flat.reshape(u1.shape[0], c, len(u3_rows)).transpose(2, 0, 1)
    return frames + mean_rows[:, None, :]


def _tucker_sections(
    number: int,
    section: Callable[[str], Section | None],
    header: FieldHeader,
    ranks: tuple[int, int],
    limits: Limits,
) -> dict[str, Section]:
    """The four qmat sections, present, ancillary, of codec qmat (R45-field), each of the
    shape the ranks give (R28-shape) and within ``max_section_bytes`` (R21)."""
    i, k = ranks
    n, frames, c = header.elements, header.frames, header.components
    shapes = {"U1": (n, i), "U3": (frames, k), "CORE": (i * c * k, 1), "MEAN": (frames, c)}
    found: dict[str, Section] = {}
    for part in TUCKER_PARTS:
        section_id = f"{field_id(number)}.{part}"
        where = f"section {section_id}"
        entry = section(section_id)
        if entry is None:
            refuse("a field in mode tucker needs this section; it is missing", where)
        if entry.critical or entry.codec != QMAT:
            refuse(f"must be an ancillary section of codec {QMAT}", where)
        rows, cols = section_shape(entry.params, where, expected=shapes[part])
        check_stream_size(rows, cols, limits, where)
        found[part] = entry
    return found


def _decode_tucker(
    number: int,
    header: FieldHeader,
    ranks: tuple[int, int, np.ndarray],
    section: Callable[[str], Section | None],
    payload: Callable[[str], memoryview],
    mesh: MeshPrediction | None,
    frames_wanted: np.ndarray,
    limits: Limits,
) -> np.ndarray:
    i, k, u2 = ranks
    parts = _tucker_sections(number, section, header, (i, k), limits)
    on_mesh = header.domain != FACE

    def matrix(part: str, parents: MeshPrediction | None, predict: bool) -> np.ndarray:
        section_id = f"{field_id(number)}.{part}"
        # the qmat predictors of 1.2 are always known to a decoder of fields (1.5)
        return qmat.decode_matrix(
            payload(section_id),
            parts[part].params,
            parents,
            f"section {section_id}",
            allow_predict=predict,
            coding_tools=True,
        ).values()

    if on_mesh and mesh is None:
        raise ValueError("a vertex field in mode tucker needs the mesh's MeshPrediction")
    u1 = matrix("U1", mesh if on_mesh else None, on_mesh)
    u3 = matrix("U3", None, True)
    core = matrix("CORE", None, False).reshape(i, header.components, k)
    mean = matrix("MEAN", None, True)
    with np.errstate(over="ignore", invalid="ignore"):
        values = reconstruct_field(u1, core, u2, u3[frames_wanted], mean[frames_wanted])
        values = values.astype(header.dtype)
    if not np.isfinite(values).all():
        refuse("a reconstructed value is not finite", f"section {field_id(number)}")
    return values


# -- the one entry point ----------------------------------------------------------------------


def _wanted(frames_wanted: np.ndarray | None, frames: int) -> np.ndarray:
    if frames_wanted is None:
        return np.arange(frames, dtype=np.int64)
    wanted = np.asarray(frames_wanted)
    if wanted.ndim != 1 or (wanted.size and not np.issubdtype(wanted.dtype, np.integer)):
        raise ValueError("frames_wanted must be a 1-D array of frame numbers")
    wanted = wanted.astype(np.int64)
    if wanted.size and (wanted.min() < 0 or wanted.max() >= frames):
        raise ValueError(f"frames_wanted must be frame numbers in 0..{frames - 1}")
    return wanted


def decode_field(
    number: int,
    section: Callable[[str], Section | None],
    payload: Callable[[str], memoryview],
    vertices: int,
    faces: int,
    frames: int,
    mesh: MeshPrediction | None,
    limits: Limits,
    frames_wanted: np.ndarray | None = None,
) -> Field:
    """Field ``number`` of a file (§6.13): its descriptor ``FLD.<n>`` from ``section`` (the
    section-table entry of an id, or None), the CRC-checked bytes of a section from
    ``payload``. ``mesh``: the file's U1 mesh prediction (needed for a vertex field in mode
    tucker). ``frames_wanted``: decode only those frames, in that order (default: all).

    Every parameter is checked before anything is allocated (R45-field, R21-header-limit),
    then the qmat sections (R28, R30-R32) or the chunks asked for (R29, R45-field)."""
    wanted = _wanted(frames_wanted, frames)
    descriptor_id = field_id(number)
    where = f"section {descriptor_id}"
    descriptor = section(descriptor_id)
    if descriptor is None:
        refuse("the field's descriptor section is missing", where)
    if descriptor.critical or descriptor.codec != FIELD_CODEC:
        refuse(f"must be an ancillary section of codec {FIELD_CODEC}", where)
    params = descriptor.params
    header = read_header(params, where, vertices, faces, frames, limits)
    if header.mode == TUCKER:
        ranks = read_ranks(params, header, limits, where)
        if descriptor.length != 0:
            refuse("a field in mode tucker has an empty payload", where)
        values = _decode_tucker(number, header, ranks, section, payload, mesh, wanted, limits)
    else:
        layout = read_chunks(params, header, descriptor.length, limits, where)
        values = _decode_chunked(header, layout, payload(descriptor_id), wanted, where)
    return Field(header.name, values, header.domain, header.role)
