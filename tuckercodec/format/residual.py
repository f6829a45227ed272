"""§6.9 Codec ``residual`` (corrections) and §8.1 the exact reconstruction (format 1.3).

A file whose preamble sets flag bit 2 corrects every decoded coordinate by an integer ``e``: on a
grid (``P + step * e``, a bound on every vertex), or on the ordered integers of binary32 or
binary64 values (lossless). Every decoder must correct the same binary64 values, so such a file
is reconstructed in one normative order (:func:`exact_frames`), one rounded operation at a time.

The integers are stored per chunk of frames (:class:`ResidualLayout`), each chunk one zstd frame
of 64-bit zigzagged integers in byte planes (§6.1 on 64 bits), optionally as differences from
the frame before within the chunk; or (format 1.7, flag bit 4) each chunk one adaptive stream
of §6.14 (:mod:`.adaptive`), a column per frame and axis, the vertices in ascending order.

An axis whose values are few (format 1.8, flag bit 5) may have a *codebook*: the sorted ordered
integers its values take. Its corrections are then differences of positions in that list
(:func:`from_codebooks`), small where the values repeat across frames and vertices.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, NoReturn

import msgpack
import numpy as np

from ..errors import FormatError, InternalError
from ..system import native
from . import adaptive, streams
from .limits import DEFAULT_LIMITS, Limits, check_limit

#: Preamble flag bit 2 (critical, format 1.3): the file has corrections (§6.9).
CORRECTIONS = 0x0004
#: The minor version of a file that sets :data:`CORRECTIONS`.
CORRECTIONS_MINOR = 3
#: Preamble flag bit 4 (critical, format 1.7): a RESD section stores its chunks as adaptive
#: streams (``coder`` 1, §6.9).
ADAPTIVE_CORRECTIONS = 0x0010
#: The minor version of a file that sets :data:`ADAPTIVE_CORRECTIONS`.
ADAPTIVE_CORRECTIONS_MINOR = 7
#: The adaptive coding is kept only where it makes the section smaller by more than this share:
#: its chunks decode about four times slower than zstd's, so a percent or two is not worth it.
ADAPTIVE_GAIN = 0.03
#: Preamble flag bit 5 (critical, format 1.8): a RESD section may have codebooks (§6.9).
CODEBOOKS = 0x0020
#: The minor version of a file that sets :data:`CODEBOOKS`.
CODEBOOKS_MINOR = 8
#: An axis gets a codebook tried when its distinct values are at most this share of its values.
CODEBOOK_SHARE = 0.5
#: The codec id of RESD sections.
RESIDUAL = "residual"
SECTION_STEM = "RESD"
GRID, FLOAT32, FLOAT64 = "grid", "float32", "float64"
#: Lossless domains for values that are decimals as text gave them: k / 10**places, or
#: numbers of ``digits`` significant digits (§6.9).
PLACES, DIGITS = "decimal-places", "decimal-digits"
#: binary32 values read from decimals of ``digits`` significant digits (a float32 cache
#: written from text): the decimal's binary64 value rounded to binary32.
DIGITS32 = "decimal-digits-float32"
DOMAINS = (GRID, FLOAT32, FLOAT64, PLACES, DIGITS, DIGITS32)
#: The parameter each decimal domain takes, and its range.
SCALES = {PLACES: ("places", 0, 22), DIGITS: ("digits", 1, 15), DIGITS32: ("digits", 1, 15)}


@dataclass(frozen=True)
class Domain:
    """How integers correct values (§6.9): its name, and a grid's step or a decimal domain's
    places or digits."""

    name: str
    step: float | None = None
    scale: int | None = None

    def params(self) -> dict[str, Any]:
        """The section parameters that name it."""
        params: dict[str, Any] = {"domain": self.name}
        if self.name == GRID:
            params["step"] = float(self.step)  # type: ignore[arg-type]
        elif self.name in SCALES:
            params[SCALES[self.name][0]] = self.scale
        return params

    def describe(self) -> str:
        """Its name, with its step, places or digits."""
        if self.name == GRID:
            return f"{GRID} (step {self.step:.6g})"
        if self.name in SCALES:
            return f"{self.name} ({self.scale} {SCALES[self.name][0]})"
        return self.name


MAX_PLANES = 8

#: The ordered integers of the finite values (§6.9): +max and -max.
FINITE32 = (-2139095040, 2139095039)
FINITE64 = (-9218868437227405312, 9218868437227405311)
#: |e| allowed: grid values must widen to binary64 exactly; float32 ones stay within 33 bits.
GRID_LARGEST = 2**53
FLOAT32_LARGEST = 2**32


# -- the ordered integers (§6.9) ---------------------------------------------------------------


def ordered32(values: np.ndarray) -> np.ndarray:
    """The ordered integer (int64) of each binary32 value."""
    bits = np.ascontiguousarray(values, dtype=np.float32).view(np.int32).astype(np.int64)
    return np.where(bits >= 0, bits, -(2**31) - bits - 1)


def from_ordered32(ordered: np.ndarray) -> np.ndarray:
    """The binary32 values of ordered integers within :data:`FINITE32` (the map is its own
    inverse)."""
    bits = np.where(ordered >= 0, ordered, -(2**31) - ordered - 1).astype(np.int32)
    return bits.view(np.float32)


def ordered64(values: np.ndarray) -> np.ndarray:
    """The ordered integer (int64) of each binary64 value."""
    bits = np.ascontiguousarray(values, dtype=np.float64).view(np.int64)
    # -2**63 - w - 1 is ~w with the sign bit cleared... computed as (-w - 1) ^ (1 << 63) wraps
    # nowhere: for w < 0, -w - 1 = ~w >= 0, and subtracting 2**63 is flipping the top bit.
    flipped = np.bitwise_xor(np.invert(bits), np.int64(-(2**63)))
    return np.where(bits >= 0, bits, flipped)


def from_ordered64(ordered: np.ndarray) -> np.ndarray:
    """The binary64 values of ordered integers (the map is its own inverse)."""
    return ordered64(ordered.view(np.float64)).view(np.float64)


# -- decimals (§6.9) -----------------------------------------------------------------------------

#: 10**n, exact in binary64 for n <= 22.
TEN = tuple(float(10**n) for n in range(23))
LARGEST_PLACES_INTEGER = 2**53


def places_ordered(values: np.ndarray, places: int) -> np.ndarray:
    """k = the integer nearest values * 10**places (one binary64 product, then rounded half
    to even), within +-2**53."""
    with np.errstate(over="ignore", invalid="ignore"):
        scaled = np.rint(values * TEN[places])
    limit = float(LARGEST_PLACES_INTEGER)
    return np.clip(np.nan_to_num(scaled, posinf=limit, neginf=-limit), -limit, limit).astype(
        np.int64
    )


def places_values(ordered: np.ndarray, places: int) -> np.ndarray:
    """k / 10**places, one correctly rounded binary64 division: the value of the decimal."""
    return ordered.astype(np.float64) / TEN[places]


def _digit_constants(digits: int) -> tuple[int, int, int, np.ndarray]:
    """E_min, the integers per decade B = 9 * 10**(p-1), the lowest significand 10**(p-1),
    and the binary64 nearest 10**E for E = E_min .. E_min + 44."""
    low = 10 ** (digits - 1)
    lowest_exponent = digits - 23
    powers = np.array([float(f"1e{e}") for e in range(lowest_exponent, lowest_exponent + 45)])
    return lowest_exponent, 9 * low, low, powers


def digits_ordered(values: np.ndarray, digits: int) -> np.ndarray:
    """The ordered decimal integer of each value rounded to ``digits`` significant digits
    (§6.9): +0 is 0, -0 is -1, a positive value 1 + (E - E_min) * B + (m - 10**(p-1)) and a
    negative one -1 minus that of its magnitude. E is the decade the table of binary64
    powers of ten places |value| in, m the significand rounded half to even, kept in its
    decade's range."""
    lowest_exponent, per_decade, low, powers = _digit_constants(digits)
    magnitude = np.abs(values)
    decade = np.searchsorted(powers, magnitude, side="right")
    decade -= 1
    np.clip(decade, 0, len(powers) - 1, out=decade)
    shift = (digits - 1 - lowest_exponent) - decade  # within -22 .. 22
    tens = np.asarray(TEN)
    with np.errstate(over="ignore", invalid="ignore"):
        scaled = magnitude * tens[np.maximum(shift, 0)]  # the usual case: values below 10**p
        above = shift < 0
        if above.any():
            scaled[above] = magnitude[above] / tens[-shift[above]]
    np.rint(scaled, out=scaled)
    np.clip(scaled, low, 10 * low - 1, out=scaled)
    ordered = decade.astype(np.int64)
    ordered *= per_decade
    ordered += scaled.astype(np.int64)
    ordered += 1 - low
    ordered[magnitude == 0] = 0
    negative = np.signbit(values)
    ordered[negative] = -1 - ordered[negative]
    return ordered


def digits_largest(digits: int) -> int:
    """The largest ordered decimal integer of ``digits`` digits (its negative is -1 - this)."""
    return 45 * 9 * 10 ** (digits - 1)


def digits_values(ordered: np.ndarray, digits: int) -> np.ndarray:
    """The binary64 value of each ordered decimal integer: m / 10**s or m * 10**-s, one
    correctly rounded operation, so the value nearest the decimal."""
    lowest_exponent, per_decade, low, _ = _digit_constants(digits)
    negative = ordered < 0
    magnitude = ordered.copy()
    magnitude[negative] = -1 - magnitude[negative]
    zero = magnitude == 0
    magnitude -= 1
    np.maximum(magnitude, 0, out=magnitude)
    decade, offset = np.divmod(magnitude, per_decade)
    offset += low
    value = offset.astype(np.float64)
    shift = (digits - 1 - lowest_exponent) - decade
    tens = np.asarray(TEN)
    below = shift > 0  # the usual case: a division by an exact power of ten
    value[below] /= tens[shift[below]]
    rest = ~below
    if rest.any():
        value[rest] *= tens[-shift[rest]]
    value[zero] = 0.0
    value[negative] = -value[negative]
    return value


# -- §8.1 the exact reconstruction -------------------------------------------------------------


def exact_basis(core: np.ndarray, u2: np.ndarray) -> np.ndarray:
    """``B[a, x, b]`` of §8.1, (i, 3, k): the three products added left to right."""
    parts = [core[:, c, None, :] * u2[None, :, c, None] for c in range(3)]
    return (parts[0] + parts[1]) + parts[2]


#: The largest |S| of §8.1 (and |sum of |q1| |w_hat||): every partial sum is then an exact binary64
#: integer, so any order, BLAS's included, gives the same S.
EXACT_LIMIT = 2**53
#: The range of a RESD section's ``exponent``: 2**e and 2**-e are normal binary64 numbers.
EXPONENTS = (-1022, 1022)


@dataclass(frozen=True)
class ExactU1:
    """What §8.1 takes of U1: its integers q1 as binary64 (exact), its steps, and
    R = max over v of sum over a of |q1[v, a]| (an exact integer)."""

    integers: np.ndarray  # (K, i) float64
    steps: np.ndarray  # (i,) float64, the stored f32 widened
    row_sum: int

    @classmethod
    def of(cls, q: np.ndarray, steps: np.ndarray) -> ExactU1:
        row_sum = int(np.abs(q).sum(axis=1).max()) if q.size else 0
        return cls(
            q.astype(np.float64), np.asarray(steps, dtype=np.float32).astype(np.float64), row_sum
        )


def scaled_weights(u1: ExactU1, basis: np.ndarray, u3_rows: np.ndarray) -> np.ndarray:
    """y[f, a, x] = step[a] x W_f[a, x] of §8.1, (n, i, 3): W summed over b left to right,
    then one product with U1's step (every operation one binary64 rounding)."""
    weights = basis[None, :, :, 0] * u3_rows[:, 0, None, None]  # (n, i, 3)
    for b in range(1, u3_rows.shape[1]):
        weights = weights + basis[None, :, :, b] * u3_rows[:, b, None, None]
    return u1.steps[None, :, None] * weights


def choose_exponent(u1: ExactU1, largest: float) -> int:
    """The encoder's e: the smallest that keeps R * max|w_hat| within 2**53 for weights up to
    ``largest`` (with a step of room for the rounding), so that S keeps the most precision."""
    if not (largest > 0 and u1.row_sum > 0):
        return 0
    exponent = math.ceil(math.log2(u1.row_sum * largest)) - 52
    return int(min(max(exponent, EXPONENTS[0]), EXPONENTS[1]))


def integer_weights(scaled: np.ndarray, exponent: int) -> np.ndarray:
    """w_hat = y x 2**-e, rounded to the nearest integer (ties to even), as binary64."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.rint(scaled * (2.0**-exponent))


def weights_fit(u1: ExactU1, weights: np.ndarray) -> bool:
    """R * max|w_hat| <= 2**53 (and every w_hat finite): S is then exact in any order."""
    if not weights.size:
        return True
    largest = float(np.abs(weights).max())
    if not math.isfinite(largest):
        return False
    return u1.row_sum * int(largest) <= EXACT_LIMIT


def exact_frames(
    u1: ExactU1,
    basis: np.ndarray,
    u3_rows: np.ndarray,
    centroid_rows: np.ndarray,
    exponent: int,
    where: str = "section RESD",
) -> np.ndarray:
    """P (n, K, 3) of §8.1 for the frames of ``u3_rows`` (n, k) and ``centroid_rows`` (n, 3).

    S = q1 . w_hat is a product of integers whose every partial sum stays within 2**53 (R41
    otherwise), so BLAS computes it exactly, whatever its order or fused operations; then
    P = S x 2**e + CENT, two rounded operations.
    """
    n = u3_rows.shape[0]
    weights = integer_weights(scaled_weights(u1, basis, u3_rows), exponent)
    if not weights_fit(u1, weights):
        _value_error(
            f"{where}.exponent",
            f"U1's integers times the frames' weights at exponent {exponent} exceed 2**53: "
            "the exact reconstruction of §8.1 would round",
        )
    i = u1.integers.shape[1]
    product = u1.integers @ weights.transpose(1, 0, 2).reshape(i, 3 * n)  # (K, 3n), exact
    positions = product.reshape(-1, n, 3).transpose(1, 0, 2)
    out = np.empty(positions.shape)  # frame-major, so that a run of frames is a view
    with np.errstate(over="ignore", invalid="ignore"):
        np.multiply(positions, 2.0**exponent, out=out)
        out += centroid_rows[:, None, :]
    return out


# -- the section's layout (§6.9 parameters) ----------------------------------------------------


@dataclass(frozen=True)
class ResidualLayout:
    """A RESD section's checked parameters: its domain (and grid step), whether frames are
    stored as differences, and each chunk's planes and byte range in the payload."""

    domain: str
    step: float | None  # a grid's spacing
    predict: int
    chunk_frames: int
    planes: tuple[int, ...]
    offsets: tuple[int, ...]  # len(planes) + 1 byte offsets into the payload
    frames: int
    scale: int | None = None  # decimal-places' places, decimal-digits' digits
    exponent: int = 0  # e of §8.1: S x 2**e
    coder: int = adaptive.CODER_ZSTD  # 1: each chunk is an adaptive stream (format 1.7)
    #: per axis (format 1.8) the codebook's (count, planes, start, stop) in the payload, count
    #: 0 for none; empty when the section has none
    codebooks: tuple[tuple[int, int, int, int], ...] = ()

    @property
    def kind(self) -> Domain:
        """Its domain, with the grid's step or the decimals' places or digits."""
        return Domain(self.domain, self.step, self.scale)

    @property
    def span(self) -> int:
        """L as a decoder uses it: ``chunk_frames``, or F' when the file declares more (any
        int >= 1 is valid, up to 2**64 - 1: then the section is one chunk), so that it fits
        the int64 of frame numbers."""
        return min(self.chunk_frames, self.frames)

    def chunk_range(self, chunk: int) -> tuple[int, int]:
        start = chunk * self.span
        return start, min(self.frames, start + self.span)


def _is_int(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def read_layout(
    params: Mapping[str, Any],
    payload_length: int,
    frames: int,
    vertices: int,
    limits: Limits,
    where: str,
    *,
    adaptive_corrections: bool = False,
    codebooks: bool = False,
) -> ResidualLayout:
    """§5 step 18: the parameters in order (R40; ``coder`` R46, read only in a file with flag
    bit 4, ``adaptive_corrections``; ``codebooks`` only with flag bit 5, ``codebooks``), then
    each codebook's and chunk's size against the decoder's ``max_section_bytes`` (R21). The
    CRC, the codebooks and the chunks themselves are checked later."""
    domain = params.get("domain")
    if domain not in DOMAINS:
        _parameter_error(
            f"{where}.domain", f"domain must be one of {', '.join(DOMAINS)}, got {domain!r}"
        )
    step = params.get("step")
    if domain == GRID:
        if not (isinstance(step, float) and math.isfinite(step) and step > 0):
            _parameter_error(
                f"{where}.step", f"a grid's step must be a finite float > 0, got {step!r}"
            )
    else:
        step = None
    scale = None
    if domain in SCALES:
        key, least, most = SCALES[domain]
        scale = params.get(key)
        if not (isinstance(scale, int) and not isinstance(scale, bool) and least <= scale <= most):
            _parameter_error(
                f"{where}.{key}", f"{key} must be an int from {least} to {most}, got {scale!r}"
            )
    exponent = params.get("exponent")
    if not (
        isinstance(exponent, int)
        and not isinstance(exponent, bool)
        and EXPONENTS[0] <= exponent <= EXPONENTS[1]
    ):
        _parameter_error(
            f"{where}.exponent",
            f"exponent must be an int from {EXPONENTS[0]} to {EXPONENTS[1]}, got {exponent!r}",
        )
    predict = params.get("predict")
    if not (isinstance(predict, int) and not isinstance(predict, bool) and predict in (0, 1)):
        _parameter_error(f"{where}.predict", f"predict must be 0 or 1, got {predict!r}")
    coder = adaptive.CODER_ZSTD  # before 1.7 (without flag bit 4) an unknown parameter: ignored
    if adaptive_corrections:
        coder = adaptive.checked_coder(params.get("coder", adaptive.CODER_ZSTD), where, True)
    books = _read_codebooks(params, domain, frames * vertices, where) if codebooks else []
    chunk_frames = params.get("chunk_frames")
    if not (isinstance(chunk_frames, int) and not isinstance(chunk_frames, bool)):
        chunk_frames = 0
    if chunk_frames < 1:
        _parameter_error(
            f"{where}.chunk_frames",
            f"chunk_frames must be an int >= 1, got {params.get('chunk_frames')!r}",
        )
    chunks = params.get("chunks")
    count = -(-frames // chunk_frames)
    if not (isinstance(chunks, list) and len(chunks) == count):
        got = f"{len(chunks)} entries" if isinstance(chunks, list) else repr(chunks)
        _parameter_error(
            f"{where}.chunks",
            f"chunks must be an array of {count} [planes, length] entries "
            f"({frames} frames, {chunk_frames} a chunk), got {got}",
        )
    planes: list[int] = []
    placed: list[tuple[int, int, int, int]] = []
    start = 0
    for count, book_planes, length in books:
        placed.append((count, book_planes, start, start + length))
        start += length
    offsets = [start]
    for number, entry in enumerate(chunks):
        if not (
            isinstance(entry, list)
            and len(entry) == 2
            and all(_is_int(value) for value in entry)
            and 1 <= entry[0] <= MAX_PLANES
            and entry[1] >= 0
        ):
            _parameter_error(
                f"{where}.chunks[{number}]",
                f"each chunk is [planes 1..{MAX_PLANES}, length >= 0], got {entry!r}",
            )
        planes.append(entry[0])
        offsets.append(offsets[-1] + entry[1])
    if offsets[-1] != payload_length:
        what = "the codebooks' and the chunks'" if placed else "the chunks'"
        _parameter_error(
            f"{where}.chunks",
            f"{what} lengths add up to {offsets[-1]} bytes, the payload has {payload_length}",
        )
    layout = ResidualLayout(
        domain,
        step,
        predict,
        chunk_frames,
        tuple(planes),
        tuple(offsets),
        frames,
        scale,
        exponent,
        coder,
        tuple(placed),
    )
    _check_sizes(layout, vertices, limits, where)
    return layout


def _read_codebooks(
    params: Mapping[str, Any], domain: str, values: int, where: str
) -> list[tuple[int, int, int]]:
    """``codebooks`` (format 1.8, R40): absent (none), or three ``[count, planes, length]``,
    ``[0, 0, 0]`` for an axis without one, a count of at most ``values`` (K x F') and none in
    the grid domain."""
    books = params.get("codebooks")
    if books is None and "codebooks" not in params:
        return []
    if not (isinstance(books, list) and len(books) == 3):
        _parameter_error(
            f"{where}.codebooks",
            f"codebooks must be an array of 3 [count, planes, length] entries, got {books!r}",
        )
    found: list[tuple[int, int, int]] = []
    for axis, entry in enumerate(books):
        field = f"{where}.codebooks[{axis}]"
        if not (isinstance(entry, list) and len(entry) == 3 and all(map(_is_int, entry))):
            _parameter_error(
                field, f"each codebook is [count, planes, length] of ints, got {entry!r}"
            )
        count, planes, length = entry
        if entry != [0, 0, 0] and not (
            1 <= count <= values and 1 <= planes <= MAX_PLANES and length >= 0
        ):
            _parameter_error(
                field,
                f"a codebook is [0, 0, 0] or [count 1..{values}, planes 1..{MAX_PLANES}, "
                f"length >= 0], got {entry!r}",
            )
        if count and domain == GRID:
            _parameter_error(field, "the grid domain has no codebooks")
        found.append((count, planes, length))
    return found


def _check_sizes(layout: ResidualLayout, vertices: int, limits: Limits, where: str) -> None:
    """§5 step 18's limits (R21): each codebook's decompressed size against
    ``max_section_bytes`` and its entries against ``max_chunk_values`` (format 1.8), then
    chunk by chunk, its decompressed size against ``max_section_bytes`` and, for a chunk of
    more than one frame, its integers against ``max_chunk_values``."""
    for axis, (count, book_planes, _, _) in enumerate(layout.codebooks):
        field = f"{where}.codebooks[{axis}]"
        what = f"axis {axis}'s codebook of {count} integers of {book_planes} bytes"
        check_limit(count * book_planes, limits, "max_section_bytes", what=what, field=field)
        # every frame needs the whole codebook: held, like a chunk, to a size of its own
        what = f"axis {axis}'s codebook of {count} entries"
        check_limit(count, limits, "max_chunk_values", what=what, field=field)
    for number, chunk_planes in enumerate(layout.planes):
        start, stop = layout.chunk_range(number)
        count = (stop - start) * vertices * 3
        check_limit(
            count * chunk_planes,
            limits,
            "max_section_bytes",
            what=f"chunk {number}'s {count} integers of {chunk_planes} bytes",
            field=f"{where}.chunks[{number}]",
        )
        if stop - start > 1:
            # a frame is decoded with its whole chunk (its byte planes are plane-major, and
            # with predict 1 it sums every frame before it): a chunk of several frames is held
            # to a size that does not grow with the file, one of a single frame costs the frame
            check_limit(
                count,
                limits,
                "max_chunk_values",
                what=f"chunk {number}'s {count} integers ({stop - start} frames of {vertices} "
                "vertices)",
                field=f"{where}.chunks[{number}]",
            )


def decode_chunk(
    payload: bytes | memoryview, layout: ResidualLayout, chunk: int, vertices: int, where: str
) -> np.ndarray:
    """The restored integers e of one chunk, (n_c, K, 3) int64 (R29 for its zstd frame, R46 for
    its adaptive stream)."""
    start, stop = layout.chunk_range(chunk)
    count = (stop - start) * vertices * 3
    planes = layout.planes[chunk]
    piece = payload[layout.offsets[chunk] : layout.offsets[chunk + 1]]
    field = f"{where}.chunks[{chunk}]"
    if layout.coder == adaptive.CODER_ADAPTIVE:
        return _adaptive_chunk(piece, layout.predict, stop - start, vertices, planes, field)
    core = native.core()
    if core is not None:  # the planes, the zigzag and the prediction in one pass
        raw = streams.decompress_exact(piece, count * planes, field)
        try:
            restored = core.residual_restore_chunk(
                raw, count, planes, layout.predict == 1, vertices * 3
            )
        except core.Broken as error:  # the frame held count * planes bytes: unreachable
            raise InternalError(f"{field}: {error.args[1]}") from None
        return restored.reshape(stop - start, vertices, 3)
    # in place, a block at a time: the chunk's integers are the one array of its size
    values = streams.unpack_integers(piece, count, planes, field)
    values = values.reshape(stop - start, vertices, 3)
    if layout.predict == 1:
        np.cumsum(values, axis=0, out=values)  # int64 addition wraps, as §6.9 wraps
    return values


def _adaptive_chunk(
    piece: bytes | memoryview, predict: int, frames: int, vertices: int, planes: int, field: str
) -> np.ndarray:
    """:func:`decode_chunk` of an adaptive chunk (format 1.7): its stream holds a column per
    frame and axis, (t, x) in order, of the K vertices in ascending order."""
    columns = adaptive.decode_within_planes(
        piece, 3 * frames, vertices, planes, adaptive.sequence_order(vertices), field
    )
    values = np.ascontiguousarray(columns.reshape(frames, 3, vertices).transpose(0, 2, 1))
    if predict == 1:
        np.cumsum(values, axis=0, out=values)  # int64 addition wraps, as §6.9 wraps
    return values


# -- codebooks (format 1.8) ---------------------------------------------------------------------

#: Each axis's codebook (sorted int64 ordered integers), or None for an axis without one.
Codebooks = tuple[np.ndarray | None, ...]


def domain_range(domain: Domain) -> tuple[int, int]:
    """The ordered integers a lossless domain's values have (R41, R47): the least and the
    largest."""
    if domain.name == FLOAT32:
        return FINITE32
    if domain.name == FLOAT64:
        return FINITE64
    if domain.name == PLACES:
        return -LARGEST_PLACES_INTEGER, LARGEST_PLACES_INTEGER
    assert domain.scale is not None
    largest = digits_largest(domain.scale)
    return -1 - largest, largest


def decode_codebooks(payload: bytes | memoryview, layout: ResidualLayout, where: str) -> Codebooks:
    """Each axis's codebook of a section (format 1.8), in axis order: its zstd frame (R29),
    then its entries, strictly increasing and within the domain's ordered integers (R47)."""
    books: list[np.ndarray | None] = []
    for axis, (count, planes, start, stop) in enumerate(layout.codebooks):
        if count == 0:  # no codebook (the only kind a grid section may declare)
            books.append(None)
            continue
        low, high = domain_range(layout.kind)
        field = f"{where}.codebooks[{axis}]"
        steps = streams.unpack_integers(payload[start:stop], count, planes, field)
        entries = np.cumsum(steps)  # int64 addition wraps, as §6.9 wraps
        if not bool(np.all(entries[1:] > entries[:-1])):
            raise FormatError(
                "a codebook's entries must increase", rule="R47-codebook", field=field
            )
        if int(entries[0]) < low or int(entries[-1]) > high:
            raise FormatError(
                f"a codebook's entries must be {layout.domain}'s ordered integers, "
                f"{low}..{high}; it holds {int(entries[0])}..{int(entries[-1])}",
                rule="R47-codebook",
                field=field,
            )
        books.append(entries)
    return tuple(books)


def midpoints(book: np.ndarray) -> np.ndarray:
    """``floor((C[m] + C[m+1]) / 2)`` for each pair of neighbours of a codebook, exactly: b is
    nearer ``C[m+1]`` than ``C[m]`` (§6.9, a tie keeping ``C[m]``) exactly when ``2b > C[m] +
    C[m+1]``, that is when b is above this midpoint."""
    # the gap is in 1 .. 2**64 - 1: exact as uint64 (subtraction mod 2**64), its half fits int64
    gaps = book[1:].astype(np.uint64) - book[:-1].astype(np.uint64)
    return book[:-1] + (gaps // np.uint64(2)).astype(np.int64)


def nearest_entries(
    book: np.ndarray, base: np.ndarray, middles: np.ndarray | None = None
) -> np.ndarray:
    """j of §6.9: for each ordered integer b, the index of the entry of ``book`` nearest it (the
    lower on a tie; the first entry below them all, the last above): how many midpoints lie
    below b (``middles``: :func:`midpoints` of ``book``, computed if not given)."""
    if middles is None:
        middles = midpoints(book)
    return np.searchsorted(middles, base, side="left")


def codebook_base(exact: np.ndarray, domain: Domain) -> tuple[np.ndarray, np.ndarray | None]:
    """b of §6.9 for each value of ``exact`` (P) and, outside binary32, which P are finite (the
    others' b is that of 0: their position is not finite, whatever e is)."""
    if domain.name == FLOAT32:
        return ordered_in(exact, domain), None
    finite = np.isfinite(exact)
    return ordered_in(np.where(finite, exact, 0.0), domain), finite


def from_codebooks(
    exact: np.ndarray,
    stored: np.ndarray,
    domain: Domain,
    books: Codebooks,
    where: str,
    middles: tuple[np.ndarray | None, ...] = (),
) -> np.ndarray:
    """The corrections e that ``stored`` (F', K, 3) means on each axis: on one with a codebook
    C, ``C[j + s] - b`` (R41 for j + s outside C), so that :func:`correct` gives ``C[j + s]``'s
    value; elsewhere ``stored`` itself. ``middles``: each codebook's :func:`midpoints`, if
    kept."""
    if not any(book is not None for book in books):
        return stored
    out = np.array(stored, dtype=np.int64)
    core = native.core()
    for axis, book in enumerate(books):
        if book is None:
            continue
        if core is not None:  # the same integers, through an index of the midpoints
            middle = middles[axis] if middles else None
            out[..., axis] = _native_codebook_corrections(
                core, exact[..., axis], out[..., axis], domain, book, middle, axis, where
            )
            continue
        base, finite = codebook_base(exact[..., axis], domain)
        steps = out[..., axis]
        nearest = nearest_entries(book, base, middles[axis] if middles else None)
        outside = (steps < -nearest) | (steps > (len(book) - 1) - nearest)  # no overflow
        if finite is not None:
            outside &= finite
        if outside.any():
            _beyond_codebook(where, axis, book)
        positions = nearest + steps
        if finite is not None:
            positions[~finite] = 0
        with np.errstate(over="ignore"):
            corrections = book[positions] - base  # int64: wraps as b + e does
        if finite is not None:
            corrections[~finite] = 0  # not finite: R36, whatever e says
        out[..., axis] = corrections
    return out


def _native_codebook_corrections(
    core: Any,
    exact: np.ndarray,
    stored: np.ndarray,
    domain: Domain,
    book: np.ndarray,
    middles: np.ndarray | None,
    axis: int,
    where: str,
) -> np.ndarray:
    """:func:`from_codebooks` for one axis (``exact`` and ``stored`` of shape (F', K)) in the
    compiled core: the same integers, and the same R41."""
    flat = np.ascontiguousarray(exact, dtype=np.float64).reshape(-1)
    steps = np.ascontiguousarray(stored, dtype=np.int64).reshape(-1)
    middles = midpoints(book) if middles is None else middles
    try:
        out: np.ndarray = core.residual_codebook_corrections(
            flat, steps, domain.name, int(domain.scale or 0), book, middles
        )
    except core.Broken:  # the one refusal it has: a position outside the codebook
        _beyond_codebook(where, axis, book)
    return out.reshape(exact.shape)


def _beyond_codebook(where: str, axis: int, book: np.ndarray) -> NoReturn:
    """R41 for a stored integer that moves past either end of axis ``axis``'s codebook."""
    _value_error(where, f"a correction moves beyond axis {axis}'s codebook of {len(book)} entries")


def correct(exact: np.ndarray, residual: np.ndarray, domain: Domain, where: str) -> np.ndarray:
    """The decoded positions (float64) of §6.9: ``exact`` (P of §8.1) corrected by
    ``residual`` (e), R41 checked. In the domains grid and float64 a P that is not finite
    stays so (the decoder reports it as R36, as for any file); in float32 it rounds to
    +-infinity, which e may bring back."""
    core = native.core()
    if core is not None and exact.shape == residual.shape:
        return _native_correct(core, exact, residual, domain, where)
    with np.errstate(over="ignore", invalid="ignore"):
        if domain.name == FLOAT32:
            if _beyond(residual, FLOAT32_LARGEST):
                _value_error(where, f"a correction is beyond +-2**32 in domain {FLOAT32}")
            ordered = ordered32(exact.astype(np.float32)) + residual
            if ordered.size and (ordered.min() < FINITE32[0] or ordered.max() > FINITE32[1]):
                _value_error(where, "a corrected value is not a finite binary32")
            return from_ordered32(ordered).astype(np.float64)
        finite = np.isfinite(exact)
        if domain.name in SCALES:
            return _decimal(exact, residual, domain, finite, where)
        if domain.name == GRID:
            if _beyond(residual, GRID_LARGEST):
                _value_error(where, f"a correction is beyond +-2**53 in domain {GRID}")
            assert domain.step is not None
            out = exact + domain.step * residual.astype(np.float64)
            if not np.isfinite(out)[finite].all():
                _value_error(where, "a corrected position is not finite")
            return out
        ordered = ordered64(np.where(finite, exact, 0.0)) + residual  # int64 addition wraps
        ordered = ordered[finite]
        if ordered.size and (ordered.min() < FINITE64[0] or ordered.max() > FINITE64[1]):
            _value_error(where, "a corrected value is not a finite binary64")
        out = np.full(exact.shape, np.nan)
        out[finite] = from_ordered64(ordered)
        return out


def _native_correct(
    core: Any, exact: np.ndarray, residual: np.ndarray, domain: Domain, where: str
) -> np.ndarray:
    """:func:`correct` in the compiled core: the same values, and the same R41 first."""
    name, step, scale = domain.name, float(domain.step or 0.0), int(domain.scale or 0)
    try:
        return _in_memory_order(
            lambda flat, integers: core.residual_correct(flat, integers, name, step, scale),
            exact,
            residual,
        )
    except core.Broken as error:
        _value_error(where, error.args[1])


def _in_memory_order(compute: Any, values: np.ndarray, *more: np.ndarray) -> np.ndarray:
    """``compute`` (a map of the compiled core, value by value, on flat contiguous arrays) on
    ``values`` (float64) and ``more`` (int64, of the same shape), taken in the order of
    ``values``' memory: positions made by a transposed product would cost a transposed copy
    in C order. The result has the shape, and the layout, of ``values``."""
    axes = np.argsort([-abs(stride) for stride in values.strides], kind="stable")
    permuted = values.transpose(axes)
    flats: list[np.ndarray] = [np.ascontiguousarray(permuted, dtype=np.float64).reshape(-1)]
    flats += [np.ascontiguousarray(m.transpose(axes), dtype=np.int64).reshape(-1) for m in more]
    result: np.ndarray = compute(*flats).reshape(permuted.shape).transpose(np.argsort(axes))
    return result


def _beyond(values: np.ndarray, limit: int) -> bool:
    """Whether a value is outside -limit..limit (by its extremes: abs() of -2**63 overflows)."""
    return bool(values.size) and (int(values.min()) < -limit or int(values.max()) > limit)


def _decimal(
    exact: np.ndarray,
    residual: np.ndarray,
    domain: Domain,
    finite: np.ndarray,
    where: str,
) -> np.ndarray:
    """The decimal domains of §6.9: P's ordered decimal integer (of the finite P; the others
    stay not finite, for R36), corrected by e, back to the value of its decimal."""
    assert domain.scale is not None
    scale = domain.scale
    every = bool(finite.all())  # the usual case: no copies for the non-finite
    base = exact if every else np.where(finite, exact, 0.0)
    if domain.name == PLACES:
        limit = LARGEST_PLACES_INTEGER
        if _beyond(residual, 2 * limit):
            _value_error(where, f"a correction is beyond +-2**54 in domain {PLACES}")
        ordered = places_ordered(base, scale) + residual
        if not every:
            ordered[~finite] = 0  # not finite: R36, whatever e says
        if _beyond(ordered, limit):
            _value_error(where, f"a corrected integer is beyond +-2**53 in domain {PLACES}")
        values = places_values(ordered, scale)
    else:
        limit = digits_largest(scale)
        if _beyond(residual, 2 * limit + 1):
            _value_error(where, f"a correction is beyond the decimals of {scale} digits")
        ordered = digits_ordered(base, scale)
        ordered += residual
        if not every:
            ordered[~finite] = 0  # not finite: R36, whatever e says
        if ordered.size and (ordered.min() < -1 - limit or ordered.max() > limit):
            _value_error(where, f"a corrected integer is not a decimal of {scale} digits")
        values = digits_values(ordered, scale)
        if domain.name == DIGITS32:  # rounded once more, to binary32
            values = values.astype(np.float32).astype(np.float64)
    return values if every else np.where(finite, values, np.nan)


def _parameter_error(field: str, problem: str) -> NoReturn:
    raise FormatError(problem, rule="R40-residual", field=field)


def _value_error(where: str, problem: str) -> NoReturn:
    raise FormatError(problem, rule="R41-residual-value", field=where)


# -- the encoder's side ------------------------------------------------------------------------

#: Integers per chunk the encoder aims at: a frame read costs at most about this many.
CHUNK_VALUES = 1 << 20


def ordered_in(values: np.ndarray, domain: Domain) -> np.ndarray:
    """The ordered integers of a lossless domain: what e is a difference of (§6.9)."""
    core = native.core()
    if core is not None:
        name, scale = domain.name, int(domain.scale or 0)
        return _in_memory_order(
            lambda flat: core.residual_ordered(flat, name, scale), np.asarray(values)
        )
    if domain.name == FLOAT32:
        with np.errstate(over="ignore"):
            return ordered32(values.astype(np.float32))
    if domain.name == PLACES:
        assert domain.scale is not None
        return places_ordered(values, domain.scale)
    if domain.name in (DIGITS, DIGITS32):
        assert domain.scale is not None
        return digits_ordered(values, domain.scale)
    return ordered64(values)


def residuals_of(exact: np.ndarray, original: np.ndarray, domain: Domain) -> np.ndarray:
    """The integers e that take ``exact`` to ``original`` exactly (lossless domains), or to
    the nearest grid point (grid: the encoder then keeps e only where it needs it)."""
    if domain.name == GRID:
        assert domain.step is not None
        return np.rint((original - exact) / domain.step).astype(np.int64)
    return ordered_in(original, domain) - ordered_in(exact, domain)  # int64: wraps as e does


def codebooks_of(ordered: np.ndarray, share: float = CODEBOOK_SHARE) -> Codebooks | None:
    """Per axis, the sorted distinct ordered integers of ``ordered`` (F', K, 3) where they are
    at most ``share`` of its values and within the default ``max_chunk_values`` (a decoder
    holds a codebook whole, §7), None elsewhere; None when no axis has few enough."""
    values = ordered.shape[0] * ordered.shape[1]
    most = min(share * values, DEFAULT_LIMITS.max_chunk_values)
    books: list[np.ndarray | None] = []
    for axis in range(3):
        values_sorted = np.sort(ordered[..., axis], axis=None)  # np.unique's hash: far slower
        first = np.ones(values_sorted.size, dtype=bool)
        np.not_equal(values_sorted[1:], values_sorted[:-1], out=first[1:])
        distinct = values_sorted[first]
        books.append(distinct if len(distinct) <= most else None)
    return tuple(books) if any(book is not None for book in books) else None


def codebook_integers(
    plain: np.ndarray,
    ordered: np.ndarray,
    books: Codebooks,
    positions: tuple[np.ndarray | None, ...],
    middles: tuple[np.ndarray | None, ...] = (),
) -> np.ndarray:
    """The integers a section with ``books`` stores to take the exact positions to the input:
    on an axis with a codebook, the input's ``positions`` in it less the entry nearest each b;
    elsewhere the domain's corrections ``plain`` (:func:`residuals_of`). b, the ordered
    integers of the exact positions, is the input's ``ordered`` less ``plain`` (wrapping, as
    ``plain`` was made), not computed again. ``middles``: each codebook's :func:`midpoints`,
    if kept."""
    integers = np.array(plain, dtype=np.int64)
    core = native.core()
    for axis, book in enumerate(books):
        at = positions[axis]
        if book is None or at is None:
            continue
        with np.errstate(over="ignore"):
            base = ordered[..., axis] - plain[..., axis]
        middle = middles[axis] if middles else None
        if core is not None:  # the same j, found through an index of the midpoints
            middle = midpoints(book) if middle is None else middle
            flat = np.ascontiguousarray(base, dtype=np.int64).reshape(-1)
            nearest = core.residual_nearest_entries(middle, flat)
            nearest = nearest.reshape(base.shape)
        else:
            nearest = nearest_entries(book, base, middle)
        integers[..., axis] = at - nearest
    return integers


def _packed_codebooks(books: Codebooks | None, level: int) -> tuple[list[list[int]], bytes]:
    """The ``codebooks`` parameter and the payload's head for ``books``: each axis's entries as
    differences from the one before (the first as itself), zigzagged, in byte planes, one zstd
    frame at ``level``."""
    if books is None:
        return [], b""
    entries: list[list[int]] = []
    parts: list[bytes] = []
    for book in books:
        if book is None:
            entries.append([0, 0, 0])
            continue
        with np.errstate(over="ignore"):
            steps = np.diff(book, prepend=np.int64(0))  # wraps as the decoder's sums do
        unsigned = streams.zigzag(steps)
        planes = streams.planes_needed(unsigned)
        data = streams.compress(streams.to_planes(unsigned, planes), level)
        entries.append([len(book), planes, len(data)])
        parts.append(data)
    return entries, b"".join(parts)


def encode_section(
    residual: np.ndarray,
    domain: Domain,
    level: int,
    *,
    exponent: int = 0,
    chunk_frames: int | None = None,
    predict: int | None = None,
    adaptive_coding: bool = False,
    adaptive_gain: float = ADAPTIVE_GAIN,
    codebooks: Codebooks | None = None,
) -> tuple[dict[str, Any], bytes]:
    """A RESD section's parameters and payload for the integers ``residual`` (F', K, 3).

    ``chunk_frames`` defaults to about :data:`CHUNK_VALUES` integers a chunk; ``predict`` to
    whichever of the two stores the smaller payload. With ``adaptive_coding`` (a file that may
    set flag bit 4, format 1.7) the chunks are also coded as adaptive streams, with the same
    predict options, and that coding is kept where it is smaller by more than
    ``adaptive_gain`` (a share of the zstd payload). With ``codebooks`` (format 1.8) the
    section holds them, and ``residual`` is :func:`codebook_integers`'s."""
    frames, vertices, _ = residual.shape
    if chunk_frames is None:
        chunk_frames = max(1, min(frames, CHUNK_VALUES // (3 * vertices)))
    options = (0, 1) if predict is None else (predict,)
    books = _packed_codebooks(codebooks, level)
    best: tuple[dict[str, Any], bytes] | None = None
    for choice in options:
        section = _packed_section(
            residual, domain, level, exponent, chunk_frames, choice, books=books
        )
        assert section is not None  # zstd planes take every int64
        if best is None or len(section[1]) < len(best[1]):
            best = section
    assert best is not None
    if adaptive_coding:
        best = with_adaptive_chunks(
            best, residual, domain, exponent=exponent, predict=predict, adaptive_gain=adaptive_gain
        )
    return best


def with_adaptive_chunks(
    section: tuple[dict[str, Any], bytes],
    residual: np.ndarray,
    domain: Domain,
    *,
    exponent: int = 0,
    predict: int | None = None,
    adaptive_gain: float = ADAPTIVE_GAIN,
) -> tuple[dict[str, Any], bytes]:
    """``section`` (:func:`encode_section`'s zstd chunks of ``residual``), or the same
    integers in the same chunks as adaptive streams (format 1.7), with ``predict`` (or either),
    where that section, its parameters counted, is smaller by more than ``adaptive_gain`` (a
    share of ``section``'s): so that the file never grows for it."""
    chunk_frames = int(section[0]["chunk_frames"])
    options = (0, 1) if predict is None else (predict,)
    entries = section[0].get("codebooks", [])
    books = (entries, section[1][: sum(entry[2] for entry in entries)])  # the same codebooks
    best: tuple[dict[str, Any], bytes] | None = None
    for choice in options:
        coded = _packed_section(
            residual, domain, 0, exponent, chunk_frames, choice, adaptive.CODER_ADAPTIVE, books
        )
        if coded is not None and (best is None or _section_size(coded) < _section_size(best)):
            best = coded
    if best is not None and _section_size(best) < (1.0 - adaptive_gain) * _section_size(section):
        return best
    return section


def _section_size(section: tuple[dict[str, Any], bytes]) -> int:
    """A section's bytes in the file: its payload and its parameters in the header."""
    return len(section[1]) + len(msgpack.packb(section[0]))


def _packed_section(
    residual: np.ndarray,
    domain: Domain,
    level: int,
    exponent: int,
    chunk_frames: int,
    predict: int,
    coder: int = adaptive.CODER_ZSTD,
    books: tuple[list[list[int]], bytes] = ([], b""),
) -> tuple[dict[str, Any], bytes] | None:
    """The section of :func:`encode_section` with this ``predict`` and ``coder`` (``level``:
    zstd's) and the packed codebooks ``books`` (:func:`_packed_codebooks`), or, for the
    adaptive coder, None when a stored integer is -2**63 (§6.14 codes bit lengths up to 63)."""
    frames = residual.shape[0]
    chunks: list[list[int]] = []
    payloads: list[bytes] = [books[1]]
    for start in range(0, frames, chunk_frames):
        block = residual[start : start + chunk_frames]
        if coder == adaptive.CODER_ADAPTIVE:
            packed = _adaptive_chunk_payload(block, predict)
            if packed is None:
                return None
            planes, payload = packed
        else:
            planes, raw = _chunk_planes(block, predict)
            payload = streams.compress(raw, level)
        chunks.append([planes, len(payload)])
        payloads.append(payload)
    params = domain.params()
    params.update(exponent=exponent)
    params.update(predict=predict)
    if coder == adaptive.CODER_ADAPTIVE:  # absent means 0: a zstd section is as before 1.7
        params.update(coder=coder)
    if books[0]:  # absent means none: a section without is as before 1.8
        params.update(codebooks=books[0])
    params.update(chunk_frames=chunk_frames, chunks=chunks)
    return params, b"".join(payloads)


def _adaptive_chunk_payload(values: np.ndarray, predict: int) -> tuple[int, bytes] | None:
    """A chunk's integers (n_c, K, 3) as one adaptive stream (format 1.7): ``(planes, payload)``,
    the planes the zstd coding would declare, or None where a stored integer is -2**63."""
    stored = np.array(values, dtype=np.int64)
    if predict == 1:
        stored[1:] -= values[:-1]  # wraps like e
    if stored.size and int(stored.min()) == np.iinfo(np.int64).min:
        return None
    planes = streams.planes_needed(streams.zigzag(stored.reshape(-1)))
    frames, vertices, _ = stored.shape
    columns = np.ascontiguousarray(stored.transpose(0, 2, 1)).reshape(3 * frames, vertices)
    return planes, adaptive.encode_columns(columns, adaptive.sequence_order(vertices))


def _chunk_planes(values: np.ndarray, predict: int) -> tuple[int, bytes]:
    """A chunk's integers (n_c, K, 3) as §6.9 stores them before zstd: with ``predict`` 1 each
    frame less the one before, zigzagged, in the fewest byte planes; ``(planes, bytes)``."""
    core = native.core()
    if core is not None:
        frame_values = int(np.prod(values.shape[1:]))
        flat = np.ascontiguousarray(values, dtype=np.int64).reshape(-1)
        packed: tuple[int, bytes] = core.residual_pack_chunk(flat, predict == 1, frame_values)
        return packed
    if predict == 1:
        values = values.copy()
        values[1:] -= values[:-1].copy()  # wraps like e
    unsigned = streams.zigzag(values.reshape(-1))
    planes = streams.planes_needed(unsigned)
    return planes, streams.to_planes(unsigned, planes)
