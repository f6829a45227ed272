"""One chunk in and out: the work both codecs share, with neither numcodecs nor zarr imported.

A chunk is an array of shape (frames, vertices, 3) of floats. :func:`encode_chunk` makes it a
.tkc file (``spec/FORMAT.md``) of a sequence without faces, or, for a chunk with no shape to
measure an error against, a lossless *point chunk* (below); :func:`decode_chunk` gives either
back in the dtype asked for. With a fitted basis (:mod:`.fitted`), a chunk is that .tkc without
its U1 section's payload, which the codec's configuration holds (or, if the basis cannot serve
it, a whole .tkc of its own).

A point chunk is one in which every frame is a single point to float64's precision (a chunk of
one vertex, a constant chunk): its KG denominator is zero, so no error is allowed in it, and the
encoder refuses it (there is no shape for the KG error to measure). It is stored exactly:

===========  ===========================================================
bytes 0..7   :data:`POINT_MAGIC`
bytes 8..15  frames, vertices: two little-endian u32
bytes 16..   one zstd frame of the positions as little-endian float64, C order
===========  ===========================================================
"""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..decoder import decode
from ..decomposition.analysis import SMALLEST_COORDINATE, SMALLEST_RELATIVE_SHAPE
from ..encoder import EncodeOptions, Encoder
from ..errors import InputError, LimitError, UnreachableTargetError
from ..format.limits import DEFAULT_LIMITS, Limits
from ..format.streams import ZstdFrameProblem, compress, zstd_exact
from ..measures.distortion import kg_error
from ..model.sequence import MeshSequence
from .fitted import BASIS_KEYS, FittedBasis, complete_file, fit_array

#: The first bytes of a point chunk; never those of a .tkc file, which start with 0x89 "TKC".
POINT_MAGIC = b"TKCpoint"
_POINT_HEAD = struct.Struct("<8sII")
#: A chunk whose spread is below this many times the encoder's own floor is a point chunk: the
#: margin keeps a chunk at the floor (the two centrings round differently) from being refused.
POINT_MARGIN = 4.0
#: How many times a chunk stored below float64 is re-encoded at a tighter target before giving up
#: (rounding to float32 rarely needs one; float16 may need a few).
MAX_TIGHTENING = 8

_NO_FACES = np.zeros((0, 3), dtype=np.int64)


@dataclass(frozen=True)
class ChunkMode:
    """How each chunk is encoded: one of the encoder's three modes, checked.

    Exactly one of the three is set; :func:`chunk_mode` builds it, with a KG error of
    :data:`~tuckercodec.encoder.DEFAULT_TARGET_KG` when none is given.
    """

    target_kg: float | None = None
    ranks: tuple[int, int] | None = None
    target_bpfv: float | None = None

    @property
    def options(self) -> EncodeOptions:
        """The encoder's options for a chunk."""
        return EncodeOptions(
            target_kg=self.target_kg, ranks=self.ranks, target_bpfv=self.target_bpfv
        )

    def config(self) -> dict[str, Any]:
        """The one key of the mode in use, JSON-safe (``ranks`` as a list)."""
        if self.ranks is not None:
            return {"ranks": list(self.ranks)}
        if self.target_bpfv is not None:
            return {"target_bpfv": self.target_bpfv}
        return {"target_kg": self.target_kg}


def chunk_mode(target_kg: Any = None, ranks: Any = None, target_bpfv: Any = None) -> ChunkMode:
    """Check a codec's configuration (values as they come from JSON) and return its mode.

    Raises:
        ValueError: two modes at once, a target that is not a positive finite number, or ranks
            that are not two integers >= 1.
    """
    options = EncodeOptions(  # checks the mode and the targets
        target_kg=target_kg,
        ranks=None if ranks is None else _checked_ranks(ranks),
        target_bpfv=target_bpfv,
    )
    if options.mode == "kg":
        return ChunkMode(target_kg=options.kg_target)
    return ChunkMode(ranks=options.ranks, target_bpfv=options.target_bpfv)


def codec_settings(
    target_kg: Any = None,
    ranks: Any = None,
    target_bpfv: Any = None,
    basis: Any = None,
    basis_sha256: Any = None,
) -> tuple[ChunkMode, FittedBasis | None]:
    """Check a codec's configuration, fitted or not: its mode and its basis (or ``None``).

    Raises:
        ValueError: as :func:`chunk_mode`; a basis with ranks or a size (it serves a KG
            target), or a basis that :meth:`.FittedBasis.parse` refuses.
    """
    mode = chunk_mode(target_kg, ranks, target_bpfv)
    if basis is None and basis_sha256 is None:
        return mode, None
    if mode.target_kg is None:
        raise ValueError(
            "a fitted basis serves a KG target: give target_kg with it, not ranks or target_bpfv"
        )
    return mode, FittedBasis.parse(basis, basis_sha256)


#: The configuration keys :func:`codec_settings` takes, both codecs': the mode's and a basis's.
SETTINGS_KEYS = frozenset({"target_kg", "ranks", "target_bpfv", *BASIS_KEYS})


def describe_settings(mode: ChunkMode, basis: FittedBasis | None) -> str:
    """A codec's settings as its repr shows them, ``target_kg=0.1, basis=...``: the mode's key,
    and what a fitted basis is (its text is hundreds of kB), not all of it."""
    settings = ", ".join(f"{key}={value!r}" for key, value in mode.config().items())
    if basis is not None:
        settings += f", basis={basis.describe()}"
    return settings


def fit_settings(
    array: Any, target_kg: Any, chunk_frames: Any, max_memory: int | None
) -> dict[str, Any]:
    """The configuration of a codec fitted to ``array`` (:func:`.fitted.fit_array`):
    ``target_kg``, ``basis`` and ``basis_sha256``."""
    mode = chunk_mode(target_kg)
    assert mode.target_kg is not None
    fitted = fit_array(
        array, target_kg=mode.target_kg, chunk_frames=chunk_frames, max_memory=max_memory
    )
    return {"target_kg": mode.target_kg, **fitted.config()}


def _checked_ranks(ranks: Any) -> tuple[int, int]:
    if (
        isinstance(ranks, (list, tuple))
        and len(ranks) == 2
        and all(isinstance(r, (int, np.integer)) and not isinstance(r, bool) for r in ranks)
        and all(r >= 1 for r in ranks)
    ):
        return int(ranks[0]), int(ranks[1])
    raise ValueError(f"ranks must be two integers >= 1, as [i, k], got {ranks!r}")


def checked_dtype(dtype: Any) -> np.dtype[Any]:
    """``dtype`` as a numpy floating dtype, or a ValueError naming it."""
    try:
        parsed = np.dtype(dtype)
    except TypeError as error:
        raise ValueError(f"not a numpy dtype: {dtype!r} ({error})") from None
    if parsed.kind != "f":
        raise ValueError(f"the tuckercodec codec stores floating-point positions, not {parsed}")
    return parsed


def chunk_positions(chunk: Any) -> np.ndarray:
    """The chunk as an array of shape (frames, vertices, 3) of floats, or an InputError that
    names the shape or dtype it has."""
    array = np.asarray(chunk)
    if array.ndim != 3 or array.shape[2] != 3 or array.shape[0] < 1 or array.shape[1] < 1:
        raise InputError(
            "the tuckercodec codec encodes chunks of shape (frames, vertices, 3), at least one "
            f"frame and one vertex; this chunk has shape {array.shape} (chunk the array over "
            "frames and vertices only, with its last axis whole)"
        )
    if array.dtype.kind != "f":
        raise InputError(
            f"the tuckercodec codec encodes floating-point positions; this chunk is {array.dtype}"
        )
    return array


def is_point_chunk(positions: np.ndarray) -> bool:
    """Whether every frame is a single point to float64's precision (the encoder's test, with a
    margin): such a chunk has a zero KG denominator and is stored exactly."""
    largest = float(np.abs(positions).max())
    if largest < POINT_MARGIN * SMALLEST_COORDINATE:
        return True
    spread = float(np.abs(positions - positions.mean(axis=1, keepdims=True)).max())
    return spread < POINT_MARGIN * SMALLEST_RELATIVE_SHAPE * largest


def encode_chunk(chunk: Any, mode: ChunkMode, basis: FittedBasis | None = None) -> bytes:
    """Encode one chunk: a .tkc file of its positions without faces (a point chunk, stored
    exactly, when every frame is a single point).

    With a KG target, the positions decoded and rounded to the chunk's own dtype meet it: a
    chunk stored below float64 is checked after that rounding and re-encoded at a tighter
    target if the rounding took it over.

    With a fitted ``basis`` (a KG target only), the .tkc is encoded with it as its U1 and
    stored without it (:mod:`.fitted`); a chunk it cannot serve gets a whole .tkc of its own.

    Raises:
        InputError: a chunk of another shape or dtype, or with a non-finite position (the
            message names the chunk's shape; for a partial edge chunk it also names zarr's
            fill value, which pads it); with a basis, a chunk of other vertices than its.
        UnreachableTargetError: a target the format cannot meet for this chunk.
    """
    positions = chunk_positions(chunk)
    values = positions.astype(np.float64, copy=False)  # float16 would measure the spread coarsely
    if np.isfinite(values).all() and is_point_chunk(values):
        return _pack_points(values)
    sequence = _sequence(values)
    if basis is not None:
        if mode.target_kg is None:
            raise ValueError("a fitted basis serves a KG target, not ranks or a size")
        if sequence.vertex_count != basis.vertices:
            raise InputError(
                f"a chunk of shape {positions.shape}: the codec's basis was fitted to "
                f"{basis.vertices} vertices; chunk the array over frames only, every chunk "
                "holding all the vertices"
            )
        fitted = _encode_fitted(sequence, positions.dtype, mode.target_kg, basis)
        if fitted is not None:
            return fitted
    if mode.ranks is not None:
        i, k = mode.ranks
        # a short edge chunk may not have that many columns: its ranks are capped at its own
        ranks = (
            min(i, sequence.vertex_count, 3 * sequence.frame_count),
            min(k, sequence.frame_count, 3 * sequence.vertex_count),
        )
        return _encode(sequence, EncodeOptions(ranks=ranks))
    if mode.target_bpfv is not None:
        return _encode(sequence, mode.options)
    assert mode.target_kg is not None  # chunk_mode sets exactly one
    return _encode_kg(sequence, positions.dtype, mode.target_kg)


def _sequence(positions: np.ndarray) -> MeshSequence:
    try:
        return MeshSequence(positions, _NO_FACES)
    except InputError as error:
        raise _in_chunk(error, positions.shape) from None


def _encode(sequence: MeshSequence, options: EncodeOptions) -> bytes:
    try:
        return Encoder(options).encode(sequence)
    except (InputError, UnreachableTargetError) as error:
        raise _in_chunk(error, sequence.vertices.shape) from None


def _encode_fitted(
    sequence: MeshSequence, dtype: np.dtype[Any], target: float, basis: FittedBasis
) -> bytes | None:
    """The fitted chunk (the .tkc without the basis's payload), or ``None`` when the basis
    cannot meet the target for it."""
    try:
        data = _encode_kg(sequence, dtype, target, basis.encode)
    except UnreachableTargetError:
        return None
    return basis.cut(data)


def _encode_kg(
    sequence: MeshSequence,
    dtype: np.dtype[Any],
    target: float,
    encode: Callable[[MeshSequence, float], bytes] | None = None,
) -> bytes:
    """Meet ``target`` for the positions as they will be read back: rounded to ``dtype``.
    ``encode(sequence, goal)`` makes a whole .tkc (default: the encoder, with its errors said
    to concern a chunk)."""
    goal = target
    for _ in range(MAX_TIGHTENING):
        if encode is None:
            data = _encode(sequence, EncodeOptions(target_kg=goal))
        else:
            data = encode(sequence, goal)
        if dtype.itemsize >= 8:
            return data  # float64 (or wider) holds the decoded positions exactly: no rounding
        read_back = decode(data).vertices.astype(dtype).astype(np.float64)
        error = kg_error(sequence.vertices, read_back)
        if error <= target:
            return data
        goal *= min(0.95, target / error)
    raise UnreachableTargetError(
        f"a chunk of shape {sequence.vertices.shape}: after {MAX_TIGHTENING} tighter encodings, "
        f"rounding the decoded positions to {dtype} still gives a KG error above {target}"
    )


def _in_chunk(error: InputError | UnreachableTargetError, shape: tuple[int, ...]) -> Exception:
    """The encoder's error, saying that it concerns a chunk and which shape it has."""
    message = f"a chunk of shape {shape}: {getattr(error, 'reason', str(error))}"
    if "non-finite" in message:
        message += (
            " (zarr pads a partial edge chunk with the array's fill_value: in zarr format 2 a "
            "NaN fill_value cannot be encoded, use a finite one such as 0; format 3 cuts trailing "
            "frames of fill_value, not others)"
        )
    if isinstance(error, InputError):
        return InputError(message, frame=error.frame)
    return UnreachableTargetError(message)


def _pack_points(positions: np.ndarray) -> bytes:
    frames, vertices, _ = positions.shape
    values = np.ascontiguousarray(positions, dtype="<f8").tobytes()
    return _POINT_HEAD.pack(POINT_MAGIC, frames, vertices) + compress(values)


def _unpack_points(data: bytes, limits: Limits, room: str) -> np.ndarray:
    if len(data) < _POINT_HEAD.size:
        raise ValueError(f"a point chunk of {len(data)} bytes is shorter than its 16-byte head")
    _, frames, vertices = _POINT_HEAD.unpack_from(data)
    if not (frames >= 1 and vertices >= 1 and frames * vertices <= DEFAULT_LIMITS.max_positions):
        raise ValueError(
            f"a point chunk declares {frames} frames of {vertices} vertices: outside 1.."
            f"{DEFAULT_LIMITS.max_positions} positions"
        )
    if not (
        frames <= limits.max_frames
        and vertices <= limits.max_vertices
        and frames * vertices <= limits.max_positions
    ):
        raise ValueError(  # before decompressing what the chunk declares
            f"a point chunk declares {frames} frames of {vertices} vertices, more than {room}"
        )
    try:
        raw = zstd_exact(data[_POINT_HEAD.size :], frames * vertices * 24)
    except ZstdFrameProblem as problem:
        raise ValueError(f"a point chunk's positions: {problem}") from None
    return np.frombuffer(raw, dtype="<f8").reshape(frames, vertices, 3)


def unpadded(positions: np.ndarray, fill_value: Any, *, vertices: bool = True) -> np.ndarray:
    """The chunk without its trailing frames and trailing vertices made only of ``fill_value``
    (NaN included): what zarr pads a partial edge chunk with, which needs no encoding, and which
    :func:`decode_chunk` puts back. A chunk made only of ``fill_value`` is returned whole.
    With ``vertices=False`` only frames are cut (a fitted basis needs every vertex)."""
    fill = np.asarray(fill_value, dtype=np.float64)
    if fill.shape != ():
        return positions
    is_fill = (np.isnan(positions) if np.isnan(fill) else positions == fill).all(axis=2)
    frames = np.flatnonzero(~is_fill.all(axis=1))
    if frames.size == 0:
        return positions  # zarr does not even store such a chunk unless asked to
    if not vertices:
        return positions[: frames[-1] + 1]
    kept = np.flatnonzero(~is_fill.all(axis=0))
    return positions[: frames[-1] + 1, : kept[-1] + 1]


def _fits(frames: int, vertices: int, shape: tuple[int, ...]) -> bool:
    """Whether a chunk of ``frames`` x ``vertices`` fits zarr's chunk ``shape`` (a smaller
    one is an edge chunk the encoder cut: :func:`unpadded`)."""
    return len(shape) == 3 and frames <= shape[0] and vertices <= shape[1]


def _bound(shape: tuple[int, ...] | None, positions: int | None) -> tuple[int, int, int] | None:
    """The most frames, vertices and positions a chunk may have: those of ``shape``, or at
    most ``positions`` positions (a destination's size); None where neither is known."""
    if shape is not None and len(shape) == 3:
        frames, vertices = max(1, int(shape[0])), max(1, int(shape[1]))
        return frames, vertices, frames * vertices
    if positions is not None:
        most = max(1, int(positions))
        return most, most, most
    return None


def chunk_limits(shape: tuple[int, ...] | None, positions: int | None = None) -> Limits:
    """The decoder's limits for a chunk that must fit ``shape`` (zarr knows it), or hold at
    most ``positions`` positions: its frames, vertices and positions, the factors such a chunk
    can have and the bytes a section of them can take, so that a chunk declaring more is
    refused before anything is decompressed (spec/FORMAT.md §7). No faces: a chunk is a point
    sequence. The defaults where neither is known."""
    bound = _bound(shape, positions)
    if bound is None:
        return DEFAULT_LIMITS
    frames, vertices, most = bound
    # K*i + F*k + 3*i*k + 3*F with the ranks i <= K and k <= F, and K*F <= most
    factors = min(vertices * vertices + frames * frames, 2 * most * most) + 3 * most + 3 * frames
    bounded = {
        "max_vertices": vertices,
        "max_frames": frames,
        "max_positions": most,
        "max_faces": 0,
        "max_factor_values": factors,
        # a section holds values of up to four bytes (factors, or residuals per position),
        # or the frames' names: a margin for those
        "max_section_bytes": 4 * (factors + 3 * most) + 64 * frames + (64 << 10),
    }
    return dataclasses.replace(
        DEFAULT_LIMITS,
        **{name: min(value, getattr(DEFAULT_LIMITS, name)) for name, value in bounded.items()},
    )


def decode_chunk(
    data: Any,
    dtype: Any,
    shape: tuple[int, ...] | None = None,
    fill_value: Any = None,
    basis: FittedBasis | None = None,
    positions: int | None = None,
) -> np.ndarray:
    """Decode one chunk (a .tkc file, a fitted chunk or a point chunk) into a C-ordered array
    of ``dtype``.

    Args:
        data: the chunk's bytes (any object with the buffer protocol).
        dtype: the dtype to return (a floating dtype).
        shape: the shape the chunk must have, if known (zarr knows it).
        fill_value: with ``shape``, the value of the trailing frames and vertices that the
            encoder cut (:func:`unpadded`): a chunk smaller than ``shape`` gets them back.
        basis: the codec's fitted basis, which a fitted chunk's U1 is (:mod:`.fitted`).
        positions: without ``shape``, the most positions the chunk may hold (the size of
            the destination), if known. A chunk declaring more than ``shape`` or
            ``positions`` allow is refused before it is decompressed (:func:`chunk_limits`).

    Raises:
        FormatError: the bytes are a damaged .tkc file.
        ValueError: a damaged point chunk, a chunk that does not fit ``shape``, or a fitted
            chunk without its basis or with another (the message names the basis).
    """
    raw = bytes(memoryview(data).cast("B"))
    limits = chunk_limits(shape, positions)
    room = (
        f"the array's chunks hold (shape {tuple(shape)})"
        if shape is not None
        else f"the destination holds ({positions} positions)"
    )
    if raw[: len(POINT_MAGIC)] == POINT_MAGIC:
        decoded = _unpack_points(raw, limits, room)
    else:
        try:
            decoded = decode(complete_file(raw, basis), limits=limits).vertices
        except LimitError as error:
            if limits is DEFAULT_LIMITS:
                raise
            raise ValueError(f"the chunk declares more than {room}: {error}") from None
    dtype = checked_dtype(dtype)
    if shape is None or tuple(decoded.shape) == tuple(shape):
        with np.errstate(over="ignore"):  # float16: a position beyond its range was beyond it
            return np.ascontiguousarray(decoded, dtype=dtype)
    frames, vertices, _ = decoded.shape
    if fill_value is None or not _fits(frames, vertices, shape):
        raise ValueError(
            f"the chunk decodes to shape {decoded.shape}, but the array's chunks have shape "
            f"{tuple(shape)}"
        )
    out = np.full(shape, fill_value, dtype=dtype)
    with np.errstate(over="ignore"):
        out[:frames, :vertices] = decoded
    return out
