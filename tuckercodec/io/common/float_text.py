"""Python's ``repr`` of many floats at once: OBJ's ``v x y z`` lines made by array operations.

``repr`` of a float is the shortest decimal that reads back to the very same float64, the
closest to it when several are as short (CPython's ``dtoa`` in mode 0), written positionally
from 1e-4 up to 1e16 and with an exponent outside. Called once per value it costs about a
microsecond, most of the time of decoding a file to a folder of OBJ frames. :func:`vertex_text`
makes the same text with numpy, a frame at a time, several times faster.

The digits come from the Ryū algorithm (Ulf Adams, "Ryū: fast float-to-string conversion",
PLDI 2018), in numpy: the interval of reals that round to the float, scaled by a power of ten
(an exact 55 x 135-bit product in 32-bit limbs for its middle, its ends from the product's
fraction), and digits removed while the interval's ends still differ in what is left. Only
Ryū's common case is done here: a normal float below 2**49 in magnitude whose scaled value is
not an integer (Ryū's tie rules are not needed there), written positionally, with at most 18
digits after the point; and zeros. Every other value (written with an exponent, huge,
subnormal, non-finite, exact enough to need the tie rules, or an interval end too near an
integer to decide in float64) is left to ``repr`` itself, a line at a time, so that the text
is ``repr``'s for every float; the tests compare the two on millions of values, edge values
included.

Where the compiled core is installed, :func:`vertex_text` is the core's (Ryū's digits from the
``ryu`` crate, laid out as ``repr`` lays them out); this module is then the reference it is
tested against.

Our power of five for a binary exponent is 5**i * 2**(128 - q) rounded down, at least 132
bits (Ryū's table keeps 125, its shift being 118 to 121 where ours is 128): it lies between
Ryū's value and the exact one, so its products round down to the same integers Ryū proves
exact.
"""

from __future__ import annotations

import numpy as np

from ...system import native

_U64 = np.uint64
_LOW32 = _U64(0xFFFFFFFF)
_SHIFT = 128
_LIMBS = 5


def _tables() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per biased binary exponent (0..2047): whether this module writes its floats, the power
    of five as five 32-bit limbs (low first), that power over 2**128 as a float, the decimal
    exponent of the scaled value (Ryū's e10), and the mask of the q - 1 low bits of mv that
    are all zero when the scaled value is an integer (Ryū's vrIsTrailingZeros)."""
    ours = np.zeros(2048, dtype=bool)
    limbs = np.zeros((_LIMBS, 2048), dtype=np.uint64)
    scale = np.zeros(2048, dtype=np.float64)
    e10 = np.zeros(2048, dtype=np.int64)
    trailing = np.zeros(2048, dtype=np.uint64)
    for exponent in range(1, 1023 + 49):  # normal, below 2**49
        e2 = exponent - 1077  # two more bits, for the interval's ends (as Ryū)
        q = max((-e2 * 732923 >> 20) - 1, 0)  # floor(-e2 log10 5) - 1
        if q < 2:
            continue
        i = -e2 - q
        shift = _SHIFT - q
        power = 5**i << shift if shift >= 0 else 5**i >> -shift
        if power.bit_length() > 32 * _LIMBS or power.bit_length() < 132:
            continue
        ours[exponent] = True
        for limb in range(_LIMBS):
            limbs[limb, exponent] = (power >> (32 * limb)) & 0xFFFFFFFF
        scale[exponent] = power / 2.0**_SHIFT
        e10[exponent] = q + e2
        trailing[exponent] = (1 << min(q - 1, 63)) - 1
    return ours, limbs, scale, e10, trailing


_OURS, _POWER_LIMBS, _POWER_SCALE, _E10, _TRAILING = _tables()
_POWERS_OF_TEN = np.array([10**n for n in range(20)], dtype=np.uint64)
#: Interval ends closer than this to an integer (in float64) are left to ``repr``.
_GUARD = 1e-7
#: Digits after the point that one uint64 holds with the marker digit before them.
_MOST_DECIMALS = 18


def _scaled(mv: np.ndarray, exponent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``mv * power >> 128`` (uint64) and the product's fraction over 2**128 (a float), both
    without the three products of the lowest limbs, which add less than 2**-31 to the
    quotient: exact unless the fraction is that close to 1, which the caller leaves to
    ``repr``."""
    m0, m1 = mv & _LOW32, mv >> _U64(32)
    # the 32-bit columns 2 to 5 of the product, as lists of parts (each a new array) to add;
    # what would carry out of column 5 is beyond the 64-bit quotient (zero), so not made
    parts: dict[int, list[np.ndarray]] = {2: [], 3: [], 4: [], 5: []}
    for y in range(1, _LIMBS):
        factor = np.take(_POWER_LIMBS[y], exponent)
        for x, mx in ((0, m0), (1, m1)):
            if x + y < 2:
                continue
            product = mx * factor  # below 2**64: both below 2**32
            parts[x + y].append(product & _LOW32)
            if x + y < 5:
                parts[x + y + 1].append(product >> _U64(32))
    columns: dict[int, np.ndarray] = {}
    carry = None
    for index, column_parts in parts.items():
        total = column_parts[0]
        for part in column_parts[1:]:
            total += part
        if carry is not None:
            total += carry
        carry = total >> _U64(32)
        columns[index] = total & _LOW32
    whole = columns[4] | (columns[5] << _U64(32))
    fraction = ((columns[3] << _U64(32)) | columns[2]).astype(np.float64) * 2.0**-64
    return whole, fraction


def _shortest(bits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """For float64 ``bits`` (uint64, 1-D), each value's shortest digits as an integer, their
    count, the decimal exponent of the first, and whether this module writes it: where it does
    not, the other three are meaningless (but harmless: bounded, no table read out of range)."""
    exponent = ((bits >> _U64(52)) & _U64(0x7FF)).astype(np.intp)
    mantissa = bits & _U64((1 << 52) - 1)
    mv = (mantissa | _U64(1 << 52)) << _U64(2)
    # the scaled value is an integer (Ryū's vrIsTrailingZeros) when mv has q - 1 zero bits
    ours = np.take(_OURS, exponent) & ((mv & np.take(_TRAILING, exponent)) != 0)
    vr, fraction = _scaled(mv, exponent)
    scale = np.take(_POWER_SCALE, exponent)
    narrow = (mantissa == 0) & (exponent > 1)  # the interval's lower half is half as wide
    twice = scale * 2.0
    above = fraction + twice
    below = fraction - twice
    below[narrow] = fraction[narrow] - scale[narrow]
    ours &= fraction < 1.0 - _GUARD  # the products left out cannot carry into the quotient
    ours &= np.abs(above - np.rint(above)) > _GUARD
    ours &= np.abs(below - np.rint(below)) > _GUARD
    vp = vr + np.floor(above).astype(np.int64).astype(np.uint64)
    vm = vr + np.floor(below).astype(np.int64).astype(np.uint64)  # modular: -1 wraps, exact
    vm[~ours] = 0
    length = np.searchsorted(_POWERS_OF_TEN, vp, side="right")
    ten = _U64(10)
    last = np.zeros(len(bits), dtype=np.uint64)
    p, m = vp // ten, vm // ten
    active = p > m  # the first digit removed, on every value at once
    quotient = vr // ten
    last = np.where(active, vr - quotient * ten, last)
    vr = np.where(active, quotient, vr)
    vp, vm = np.where(active, p, vp), np.where(active, m, vm)
    removed = active.astype(np.int64)
    index = np.flatnonzero(active)
    index = index[vp[index] // ten > vm[index] // ten]
    while index.size:
        r = vr[index]
        quotient = r // ten
        last[index] = r - quotient * ten
        vr[index] = quotient
        p, m = vp[index] // ten, vm[index] // ten
        vp[index], vm[index] = p, m
        removed[index] += 1
        index = index[p // ten > m // ten]
    output = vr + ((vr == vm) | (last >= _U64(5))).astype(np.uint64)
    count = length - removed
    first = np.take(_E10, exponent) + length - 1
    ours &= (first >= -4) & (first < 16) & (count >= 1) & (count <= 17)
    return output, count, first, ours


def _quads() -> np.ndarray:
    """Four digits as four ASCII bytes in one little-endian uint32 (the first digit first in
    memory): 0..9999 with leading zeros, then from 10000 the same numbers with blanks (0)
    for their leading zeros (10000 itself four blanks)."""
    numbers = np.arange(10000)
    digits = np.stack([numbers // 1000, numbers // 100 % 10, numbers // 10 % 10, numbers % 10])
    chars = (digits + ord("0")).astype(np.uint32)
    full = chars[0] | chars[1] << 8 | chars[2] << 16 | chars[3] << 24
    blank = np.stack([numbers < 1000, numbers < 100, numbers < 10, numbers < 1])
    chars[blank] = 0
    leading = chars[0] | chars[1] << 8 | chars[2] << 16 | chars[3] << 24
    return np.concatenate([full, leading]).astype(np.uint32)


_QUADS = _quads()
_LOW_DIGITS = 12
_TEN_TWELVE = _U64(10**_LOW_DIGITS)


def _write_digits(slots: np.ndarray, value: np.ndarray, places: int) -> None:
    """The decimal digits of ``value`` (flat, one per slot) right-aligned in the last
    ``places`` (a multiple of four) bytes of each slot of ``slots`` (uint8, (..., width a
    multiple of 4), each slot's bytes contiguous and 4-aligned), blanks (0) before the first
    digit."""
    quads = slots.view(np.uint32)
    columns = quads.shape[-1]
    ten_thousand = _U64(10000)
    for quad in range(places // 4):
        quotient = value // ten_thousand
        code = value - quotient * ten_thousand
        code += (quotient == 0).astype(np.uint64) * ten_thousand
        quads[..., columns - 1 - quad] = np.take(_QUADS, code).reshape(quads.shape[:-1])
        value = quotient


#: Rows made at a time, which bounds the dozens of temporary arrays of a large mesh (a block's
#: each 1.5 MB). Smaller blocks only add numpy calls: 2048 rows looked faster on its own (its
#: fresh heap faulted pages in for a whole frame's temporaries), but in a decode to OBJ, whose
#: heap is grown already, horse gallop's frames (8431 rows) whole took 0.33-0.46 s of CPU for
#: the 48 frames against 0.58-0.70 s in blocks of 2048 (4 fresh processes each, load 5-7).
BLOCK_ROWS = 65536


def vertex_text(vertices: np.ndarray) -> bytes:
    """The ``v x y z`` lines of a (K, 3) float64 array, each ended by a newline, every number as
    ``repr`` writes it."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    core = native.core()
    if core is not None and vertices.ndim == 2 and vertices.shape[1] == 3:
        return bytes(core.obj_vertex_text(vertices))
    if len(vertices) <= BLOCK_ROWS:
        return _block_text(vertices)
    blocks = range(0, len(vertices), BLOCK_ROWS)
    return b"".join([_block_text(vertices[start : start + BLOCK_ROWS]) for start in blocks])


def _block_text(vertices: np.ndarray) -> bytes:
    """:func:`vertex_text` of a block of rows (contiguous float64)."""
    rows = len(vertices)
    if not rows:
        return b""
    values = vertices.reshape(-1)
    bits = values.view(np.uint64)
    output, count, first, ours = _shortest(bits)
    zero = (bits << _U64(1)) == 0  # 0.0 and -0.0
    # the text without its sign as one integer: the integer part, a marker digit 1 where the
    # point goes, then the decimals (at least one); held as its high digits and its low 12,
    # since it may have 21
    count = np.where(ours, count, 1)
    first = np.where(ours, first, 0)
    decimals = np.maximum(count - first - 1, 1)
    integer_digits = np.maximum(first + 1, 0)
    cut = np.take(_POWERS_OF_TEN, np.maximum(count - integer_digits, 0))
    whole = output // cut
    part = output - whole * cut
    whole *= np.take(_POWERS_OF_TEN, np.maximum(integer_digits - count, 0))
    marked = whole * _U64(10) + _U64(1)
    long = decimals >= _LOW_DIGITS
    split = np.take(_POWERS_OF_TEN, np.abs(decimals - _LOW_DIGITS))
    high = np.where(long, marked * split + part // _TEN_TWELVE, marked // split)
    shifted = (marked % split) * np.take(_POWERS_OF_TEN, np.minimum(decimals, _LOW_DIGITS - 1))
    low = np.where(long, part % _TEN_TWELVE, shifted + part)
    high[zero], low[zero], decimals[zero] = 0, 10, 1  # "0" "." "0"
    ours |= zero
    high[~ours], low[~ours], decimals[~ours] = 0, 10, 1  # rows written by repr: any short text
    bare = (whole == 0) | zero  # a "0" before the point
    length = np.where(
        high > 0,
        _LOW_DIGITS + np.searchsorted(_POWERS_OF_TEN, high, side="right"),
        np.searchsorted(_POWERS_OF_TEN, low, side="right"),
    )
    places = int(length.max(initial=2)) + 3  # three more: a space, a sign, a "0"
    places = max(places + -places % 4, _LOW_DIGITS + 4)
    # each row's bytes: "v" and 3 blanks, the three numbers' slots (a space first in each,
    # the digits right-aligned), "\n" and 3 blanks; the blanks (0) are removed at the end
    width = 3 * places + 8
    line = np.zeros((rows, width), dtype=np.uint8)
    line[:, 0] = ord("v")
    line[:, -4] = ord("\n")
    fields = line[:, 4:-4].reshape(rows, 3, places)
    if not np.may_share_memory(fields, line):  # reshape made a view (it can), not a copy
        raise AssertionError("the slots of a line must be a view of it")
    _write_digits(fields, low + (high > 0) * _TEN_TWELVE, _LOW_DIGITS)
    _write_digits(fields[:, :, :-_LOW_DIGITS], high, places - _LOW_DIGITS)
    fields[:, :, 0] = ord(" ")  # over a blank the digits left
    flat = line.reshape(-1)
    # just past each value's slot
    end = (np.arange(rows) * width + 4)[:, None] + np.arange(1, 4) * places
    end = end.reshape(-1)
    flat[end - 1 - decimals] = ord(".")
    flat[(end - 1 - length)[bare]] = ord("0")
    negative = np.signbit(values)
    flat[(end - 1 - length - bare)[negative]] = ord("-")
    by_repr = np.flatnonzero(~ours.reshape(rows, 3).all(axis=1))
    made = line.tobytes().translate(None, b"\0")
    if not by_repr.size:
        return made
    characters = (length + bare + negative).reshape(rows, 3).sum(axis=1) + 5  # v, spaces, \n
    ends = np.cumsum(characters)
    # the rows holding a value left to repr: made again by repr, in place of what was made
    pieces, start_at = [], 0
    for row in by_repr.tolist():
        x, y, z = vertices[row].tolist()
        pieces.append(made[start_at : int(ends[row - 1]) if row else 0])
        pieces.append(f"v {x!r} {y!r} {z!r}\n".encode("ascii"))
        start_at = int(ends[row])
    pieces.append(made[start_at:])
    return b"".join(pieces)
