"""§6.14 Adaptive coding: integers through a binary range coder with context models.

``spec/FORMAT.md`` §6.14 defines it; this is the reference, one binary decision at a time in
pure Python (the compiled core has the same coder, giving the same bytes, and is what runs where
it is installed). A stream section with ``coder`` 1 (format 1.6) stores its integers this way
instead of zstd over byte planes (§6.1).

The coder is the range coder of LZMA (32-bit range, a carry propagated through a cached byte)
with 15-bit probabilities that adapt after every decision, quickly for a model's first
decisions and then at a fixed rate. Each integer is binarized as: is it zero; its sign; the
bit length of its magnitude in unary; the two bits under the leading one, modelled; the rest
of the bits at even odds. Every model belongs to a *context*, a number in ``0..CONTEXTS-1``
computed from integers already coded: how large the integer's earlier neighbours are (the
mesh sources of §6.2 for U1, the two rows before it otherwise) and how large the same row was
in the two columns before. Integers of similar expected size so share their statistics.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NoReturn

import numpy as np

from ..errors import FormatError
from ..system import native

#: Preamble flag bit 3 (critical): some section stores its integers with ``coder`` 1 (§6.14).
ADAPTIVE = 0x0008
#: The minor version of a file that sets :data:`ADAPTIVE`.
ADAPTIVE_MINOR = 6
#: The ``coder`` values of a qmat section: §6.1's zstd frame, or this module's stream.
CODER_ZSTD, CODER_ADAPTIVE = 0, 1
#: The qmat section stems that may use the adaptive coder (and their segment forms, ``U1.3``);
#: a FACE section of codec faces-traverse may too (§6.8).
ADAPTIVE_STEMS = ("U1", "U3", "CORE", "CENT")

#: Probabilities are PROB_BITS-bit integers: the chance that a decision is 0, times 2**15.
PROB_BITS = 15
PROB_INIT = 1 << (PROB_BITS - 1)
#: The adaptation shift of a model's n-th update is min(n + FIRST_SHIFT, LAST_SHIFT).
FIRST_SHIFT = 2
LAST_SHIFT = 6
TOP = 1 << 24  # the range is renormalized (a byte shifted in) whenever it falls below this
MASK32 = 0xFFFFFFFF

#: Contexts: NEIGHBOUR_CLASSES classes of the earlier neighbours times LEFT_CLASSES classes of
#: the same row in the columns before.
NEIGHBOUR_CLASSES = 16
LEFT_CLASSES = 6
CONTEXTS = NEIGHBOUR_CLASSES * LEFT_CLASSES
#: Models per context: zero, sign, EXPONENT_MODELS unary bits, the first bit under the leading
#: one per exponent, the second per exponent and first bit.
EXPONENT_MODELS = 32
ZERO, SIGN, EXPONENT = 0, 1, 2
FIRST_BIT = EXPONENT + EXPONENT_MODELS
SECOND_BIT = FIRST_BIT + EXPONENT_MODELS
MODELS_PER_CONTEXT = SECOND_BIT + 2 * EXPONENT_MODELS
#: The largest bit length of a magnitude, less one: integers stay within -2**62..2**62.
MAX_EXPONENT = 62
#: No stream of N integers takes fewer than N / this many bytes (each decision costs at least
#: -log2(1 - 2**-9) bits with LAST_SHIFT 6 and 15-bit probabilities); the same bound as §6.1's.
MAX_EXPANSION = 32768


def _broken(message: str, where: str) -> NoReturn:
    """R46, the one rule of an adaptive stream: from the reference's checks and the core's."""
    raise FormatError(message, rule="R46-adaptive-stream", field=where) from None


def refuse(message: str, where: str) -> NoReturn:
    """R46 with ``message``, for a caller that decodes an adaptive stream in the compiled core
    by another route (:func:`.qmat.decode_values`)."""
    _broken(message, where)


class RangeEncoder:
    """LZMA's range encoder: decisions in, bytes out."""

    def __init__(self) -> None:
        self.low = 0
        self.range = MASK32
        self.cache = 0
        self.cache_size = 1
        self.out = bytearray()

    def _shift_low(self) -> None:
        if self.low < 0xFF000000 or self.low > MASK32:
            carry = self.low >> 32
            temp = self.cache
            while True:
                self.out.append((temp + carry) & 0xFF)
                temp = 0xFF
                self.cache_size -= 1
                if self.cache_size == 0:
                    break
            self.cache = (self.low >> 24) & 0xFF
        self.cache_size += 1
        self.low = (self.low & 0x00FFFFFF) << 8

    def bit(self, probs: list[int], counts: list[int], model: int, bit: int) -> None:
        """Code ``bit`` with the adaptive model ``model``, then update it."""
        p = probs[model]
        bound = (self.range >> PROB_BITS) * p
        shift = counts[model]
        if bit:
            self.low += bound
            self.range -= bound
            probs[model] = p - (p >> shift)
        else:
            self.range = bound
            probs[model] = p + (((1 << PROB_BITS) - p) >> shift)
        if shift < LAST_SHIFT:
            counts[model] = shift + 1
        while self.range < TOP:
            self.range = (self.range << 8) & MASK32
            self._shift_low()

    def direct(self, bit: int) -> None:
        """Code ``bit`` at even odds, with no model."""
        self.range >>= 1
        if bit:
            self.low += self.range
        while self.range < TOP:
            self.range = (self.range << 8) & MASK32
            self._shift_low()

    def finish(self) -> bytes:
        for _ in range(5):
            self._shift_low()
        return bytes(self.out)


class RangeDecoder:
    """LZMA's range decoder: bytes in, decisions out; every byte must be used, none invented."""

    def __init__(self, payload: bytes | memoryview, where: str) -> None:
        self.data = bytes(payload)
        self.where = where
        if len(self.data) < 5 or self.data[0] != 0:
            self._broken("an adaptive stream starts with a zero byte and holds at least 5 bytes")
        self.code = int.from_bytes(self.data[1:5], "big")
        self.position = 5
        self.range = MASK32

    def _broken(self, message: str) -> NoReturn:
        _broken(message, self.where)

    def _next(self) -> int:
        if self.position >= len(self.data):
            self._broken("the adaptive stream ends before its last integer")
        byte = self.data[self.position]
        self.position += 1
        return byte

    def bit(self, probs: list[int], counts: list[int], model: int) -> int:
        p = probs[model]
        bound = (self.range >> PROB_BITS) * p
        shift = counts[model]
        if self.code < bound:
            self.range = bound
            probs[model] = p + (((1 << PROB_BITS) - p) >> shift)
            bit = 0
        else:
            self.code -= bound
            self.range -= bound
            probs[model] = p - (p >> shift)
            bit = 1
        if shift < LAST_SHIFT:
            counts[model] = shift + 1
        while self.range < TOP:
            self.range = (self.range << 8) & MASK32
            self.code = ((self.code << 8) | self._next()) & MASK32
        return bit

    def direct(self) -> int:
        self.range >>= 1
        bit = 0
        if self.code >= self.range:
            self.code -= self.range
            bit = 1
        while self.range < TOP:
            self.range = (self.range << 8) & MASK32
            self.code = ((self.code << 8) | self._next()) & MASK32
        return bit

    def finish(self) -> None:
        if self.position != len(self.data):
            self._broken(
                f"the adaptive stream holds {len(self.data) - self.position} bytes after its "
                "last integer"
            )
        if self.code >= self.range:
            self._broken("the adaptive stream's last bytes are not a range coder's ending")


def fresh_models() -> tuple[list[int], list[int]]:
    """Every model at even odds, before its first update (shift FIRST_SHIFT next)."""
    count = CONTEXTS * MODELS_PER_CONTEXT
    return [PROB_INIT] * count, [FIRST_SHIFT] * count


def encode_integer(
    coder: RangeEncoder, probs: list[int], counts: list[int], context: int, value: int
) -> None:
    """Binarize one integer (§6.14) and code its decisions with ``context``'s models."""
    base = context * MODELS_PER_CONTEXT
    if value == 0:
        coder.bit(probs, counts, base + ZERO, 0)
        return
    coder.bit(probs, counts, base + ZERO, 1)
    coder.bit(probs, counts, base + SIGN, 1 if value < 0 else 0)
    magnitude = -value if value < 0 else value
    exponent = magnitude.bit_length() - 1
    for i in range(exponent):
        coder.bit(probs, counts, base + EXPONENT + min(i, EXPONENT_MODELS - 1), 1)
    coder.bit(probs, counts, base + EXPONENT + min(exponent, EXPONENT_MODELS - 1), 0)
    if exponent >= 1:
        slot = min(exponent, EXPONENT_MODELS - 1)
        first = (magnitude >> (exponent - 1)) & 1
        coder.bit(probs, counts, base + FIRST_BIT + slot, first)
        if exponent >= 2:
            second = (magnitude >> (exponent - 2)) & 1
            coder.bit(probs, counts, base + SECOND_BIT + 2 * slot + first, second)
            for shift in range(exponent - 3, -1, -1):
                coder.direct((magnitude >> shift) & 1)


def decode_integer(coder: RangeDecoder, probs: list[int], counts: list[int], context: int) -> int:
    """The inverse of :func:`encode_integer`."""
    base = context * MODELS_PER_CONTEXT
    if not coder.bit(probs, counts, base + ZERO):
        return 0
    negative = coder.bit(probs, counts, base + SIGN)
    exponent = 0
    while coder.bit(probs, counts, base + EXPONENT + min(exponent, EXPONENT_MODELS - 1)):
        exponent += 1
        if exponent > MAX_EXPONENT:
            coder._broken(f"an integer of the adaptive stream has more than {MAX_EXPONENT} bits")
    magnitude = 1
    if exponent >= 1:
        slot = min(exponent, EXPONENT_MODELS - 1)
        first = coder.bit(probs, counts, base + FIRST_BIT + slot)
        magnitude = 2 | first
        if exponent >= 2:
            magnitude = (magnitude << 1) | coder.bit(
                probs, counts, base + SECOND_BIT + 2 * slot + first
            )
            for _ in range(exponent - 2):
                magnitude = (magnitude << 1) | coder.direct()
    return -magnitude if negative else magnitude


def magnitude_class(value: int) -> int:
    """1 + the bit length of ``value`` (>= 0), at most NEIGHBOUR_CLASSES - 1."""
    return 1 + min(value.bit_length(), NEIGHBOUR_CLASSES - 2)


def left_class(row_before: int, row_two_before: int) -> int:
    """The class of a row's magnitudes in the two columns before: the bit length of
    2 |x[r, c-1]| + |x[r, c-2]|, at most LEFT_CLASSES - 1."""
    return min((2 * row_before + row_two_before).bit_length(), LEFT_CLASSES - 1)


@dataclass(frozen=True)
class CodingOrder:
    """The order rows are coded in within a column and each row's earlier neighbours.

    ``order`` lists every row once. ``sources[ends[j]:ends[j + 1]]`` are the earlier neighbours
    of ``order[j]`` (rows coded before it); a row without any has neighbour class 0. ``mesh``
    says how their magnitudes are combined: the mean of the mesh sources (U1, §6.2), or the two
    rows before (``mesh`` False: ``order`` is ascending and each row's sources are the one or two
    rows before it, the one just before counted twice).
    """

    order: np.ndarray
    sources: np.ndarray
    ends: np.ndarray
    mesh: bool


def sequence_order(rows: int) -> CodingOrder:
    """Rows in ascending order, each after the (up to) two before it."""
    order = np.arange(rows, dtype=np.int64)
    # row r's sources end at 2r - 3 (none for row 0, one for row 1, two for each after)
    ends = np.maximum(2 * np.arange(rows + 1, dtype=np.int64) - 3, 0)
    sources = np.zeros(int(ends[-1]), dtype=np.int64)  # row 1's: row 0
    pairs = sources[1:].reshape(-1, 2)  # rows 2, 3, ...: the row before, then the one before
    pairs[:, 0] = order[1 : rows - 1]
    pairs[:, 1] = order[: max(rows - 2, 0)]
    return CodingOrder(order, sources, ends, mesh=False)


def mesh_order(
    rows: int, mean_rows: np.ndarray, sources: np.ndarray, source_ends: np.ndarray
) -> CodingOrder:
    """U1's order (§6.14): the rows predictor 2 does not predict (depth 0) in ascending order,
    then predictor 2's rows in its order, each with its sources."""
    predicted = np.zeros(rows, dtype=bool)
    predicted[mean_rows] = True
    roots = np.flatnonzero(~predicted).astype(np.int64)
    order = np.concatenate([roots, mean_rows.astype(np.int64)])
    ends = np.concatenate([np.zeros(roots.size, dtype=np.int64), source_ends.astype(np.int64)])
    return CodingOrder(order, sources.astype(np.int64), ends, mesh=True)


def _neighbour_class(magnitudes: list[int], order: CodingOrder, j: int) -> int:
    start, end = int(order.ends[j]), int(order.ends[j + 1])
    if start == end:
        return 0
    if order.mesh:
        total = sum(magnitudes[w] for w in order.sources[start:end].tolist())
        return magnitude_class(3 * total // (end - start))
    before = order.sources[start:end].tolist()
    if len(before) == 1:
        return magnitude_class(3 * magnitudes[before[0]])
    return magnitude_class(2 * magnitudes[before[0]] + magnitudes[before[1]])


def order_arrays(order: CodingOrder) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``order``'s arrays as the compiled core takes them: contiguous int64."""

    def contiguous(array: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(array, dtype=np.int64)

    return contiguous(order.order), contiguous(order.sources), contiguous(order.ends)


def encode_columns(columns: np.ndarray, order: CodingOrder) -> bytes:
    """The adaptive stream of ``columns`` (cols, rows) int64: column after column, each in
    ``order``. The compiled core codes it where it is installed, else
    :func:`_encode_columns_python` (the reference; the same bytes)."""
    core = native.core()
    if core is not None:
        values = np.ascontiguousarray(columns, dtype=np.int64)
        payload: bytes = core.adaptive_encode(values, *order_arrays(order), bool(order.mesh))
        return payload
    return _encode_columns_python(columns, order)


def _encode_columns_python(columns: np.ndarray, order: CodingOrder) -> bytes:
    """:func:`encode_columns` one decision at a time in Python: the reference."""
    coder = RangeEncoder()
    probs, counts = fresh_models()
    cols, rows = columns.shape
    before = [0] * rows
    two_before = [0] * rows
    sequence = order.order.tolist()
    for c in range(cols):
        column = columns[c].tolist()
        magnitudes = [abs(v) for v in column]
        for j, row in enumerate(sequence):
            context = _neighbour_class(magnitudes, order, j) * LEFT_CLASSES + left_class(
                before[row], two_before[row]
            )
            encode_integer(coder, probs, counts, context, column[row])
        two_before, before = before, magnitudes
    return coder.finish()


def decode_columns(
    payload: bytes | memoryview, cols: int, rows: int, order: CodingOrder, where: str
) -> np.ndarray:
    """The (cols, rows) int64 integers of an adaptive stream (§6.14); R46 for any stream that
    is not exactly the coding of cols x rows integers. The compiled core decodes it where it is
    installed, else :func:`_decode_columns_python` (the reference; the same integers, or the
    same error)."""
    check_expansion(cols * rows, len(payload), where)  # before anything is allocated
    core = native.core()
    if core is None:
        return _decode_columns_python(payload, cols, rows, order, where)
    try:
        values: np.ndarray = core.adaptive_decode(
            bytes(payload), cols, rows, *order_arrays(order), bool(order.mesh)
        )
    except core.Broken as error:
        _broken(error.args[1], where)
    return values


def check_expansion(count: int, length: int, where: str) -> None:
    """R46 unless ``count`` integers can come from ``length`` bytes (§6.14's bound): checked
    before anything is allocated for them."""
    if count > MAX_EXPANSION * length:
        _broken(
            f"{count} integers cannot come from {length} bytes (at most {MAX_EXPANSION} per byte)",
            where,
        )


def _decode_columns_python(
    payload: bytes | memoryview, cols: int, rows: int, order: CodingOrder, where: str
) -> np.ndarray:
    """:func:`decode_columns` one decision at a time in Python (after its size check): the
    reference."""
    coder = RangeDecoder(payload, where)
    probs, counts = fresh_models()
    out = np.zeros((cols, rows), dtype=np.int64)
    before = [0] * rows
    two_before = [0] * rows
    sequence = order.order.tolist()
    for c in range(cols):
        column = [0] * rows
        magnitudes = [0] * rows
        for j, row in enumerate(sequence):
            context = _neighbour_class(magnitudes, order, j) * LEFT_CLASSES + left_class(
                before[row], two_before[row]
            )
            value = decode_integer(coder, probs, counts, context)
            column[row] = value
            magnitudes[row] = -value if value < 0 else value
        out[c] = column
        two_before, before = before, magnitudes
    coder.finish()
    return out


def checked_coder(
    coder: object,
    where: str,
    adaptive_coding: bool,
    needs: str = "flag bit 3 and a position factor",
) -> int:
    """A section's ``coder`` parameter, checked (R46): 0, or 1 where ``adaptive_coding`` (a
    qmat position factor, or a faces-traverse FACE, of a file with flag bit 3); ``needs`` says
    what 1 needs, for the message."""
    allowed = (CODER_ZSTD, CODER_ADAPTIVE) if adaptive_coding else (CODER_ZSTD,)
    if not isinstance(coder, int) or isinstance(coder, bool) or coder not in allowed:
        note = "" if adaptive_coding else f" (1 needs {needs})"
        _broken(f"coder must be one of {list(allowed)} here, got {coder!r}{note}", f"{where}.coder")
    return int(coder)


def decode_within_planes(
    payload: bytes | memoryview, cols: int, rows: int, planes: int, order: CodingOrder, where: str
) -> np.ndarray:
    """:func:`decode_columns`, and R46 unless every integer zigzags below 2**(8 planes), the
    range its section's ``planes`` declares (§6.14)."""
    columns = decode_columns(payload, cols, rows, order, where)
    limit = 1 << (8 * planes - 1)  # zigzag below 2**(8P): -limit <= x < limit
    if columns.size and (int(columns.min()) < -limit or int(columns.max()) >= limit):
        _broken(f"an integer of the adaptive stream does not fit its {planes} planes", where)
    return columns


def uses_adaptive(entries: list[dict[str, object]]) -> bool:
    """Whether any of these section entries needs flag bit 3 (format 1.6): integers stored with
    ``coder`` 1 (a position factor's, or a faces-traverse FACE's streams, §6.8), or predictor
    2's pushes (``mean_push``, §6.2). A RESD section's ``coder`` 1 needs flag bit 4 instead
    (format 1.7, §6.9)."""
    return any(
        (item.get("coder") == CODER_ADAPTIVE and item.get("codec") != "residual")
        or "mean_push" in item
        for item in entries
    )
