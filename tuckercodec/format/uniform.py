"""Uniform streams (format 1.9, spec/FORMAT.md §6.8): integers each spread evenly over a range
the decoder knows, as truncated binary in the direct bits of §6.14's range coder.

The i-th integer (from 0) of a stream of ``count`` over ``total`` lies in ``0..total - i - 1``:
the places among the unseen vertices of a walk's new vertices, one fewer to choose from after
each. With n = total - i, k = floor(log2 n) and u = 2**(k + 1) - n, a value below u takes k
direct bits and any other the k + 1 bits of value + u, so that a vertex order with no relation
to the walk costs log2(total!) bits and a few hundredths of a bit a value more, where the
adaptive coder's sign, exponent and bits under the leading one take about 1.4 bits a value more
(measured on the cloth). The compiled core codes and decodes where it is installed; the
functions here are the reference, and give the same bytes and integers.
"""

from __future__ import annotations

import numpy as np

from ..system import native
from .adaptive import RangeDecoder, RangeEncoder, check_expansion, refuse

#: The largest ``total`` a uniform stream may have: its integers are 32-bit ones, as an
#: adaptive stream's (§6.8).
MAX_TOTAL = 1 << 31


def _sizes(n: int) -> tuple[int, int]:
    """``(k, u)`` of a value in ``0..n - 1`` (n >= 1): its short length and the count of short
    values."""
    k = n.bit_length() - 1
    return k, (1 << (k + 1)) - n


def encode_uniform(values: np.ndarray, total: int) -> bytes:
    """The uniform stream of ``values`` (value i in ``0..total - i - 1``, ``total`` at most
    :data:`MAX_TOTAL`)."""
    flat = np.asarray(values, dtype=np.int64).reshape(-1)
    if not 0 <= total <= MAX_TOTAL or flat.size > total:
        raise ValueError(f"{flat.size} values over {total} do not make a uniform stream")
    core = native.core()
    if core is not None:
        payload: bytes = core.uniform_encode(np.ascontiguousarray(flat), total)
        return payload
    coder = RangeEncoder()
    for i, value in enumerate(flat.tolist()):
        n = total - i
        if not 0 <= value < n:
            raise ValueError(f"value {i} is {value}, outside 0..{n - 1}")
        k, u = _sizes(n)
        code, length = (value, k) if value < u else (value + u, k + 1)
        for shift in range(length - 1, -1, -1):
            coder.direct((code >> shift) & 1)
    return coder.finish()


def decode_uniform(payload: bytes | memoryview, count: int, total: int, where: str) -> np.ndarray:
    """The ``count`` integers (int64) of a uniform stream over ``total``; R46-adaptive-stream
    for one that is not exactly their coding (the stream's start and end as §6.14's). The
    caller has checked ``count <= total <= MAX_TOTAL``; the payload's bound (at most
    :data:`.adaptive.MAX_EXPANSION` integers a byte) is checked here, before anything is
    allocated."""
    check_expansion(count, len(payload), where)
    core = native.core()
    if core is not None:
        try:
            values: np.ndarray = core.uniform_decode(bytes(payload), count, total)
        except core.Broken as error:
            refuse(error.args[1], where)
        return values
    coder = RangeDecoder(payload, where)
    out = np.empty(count, dtype=np.int64)
    for i in range(count):
        k, u = _sizes(total - i)
        value = 0
        for _ in range(k):
            value = (value << 1) | coder.direct()
        if value >= u:
            value = ((value << 1) | coder.direct()) - u
        out[i] = value
    coder.finish()
    return out


__all__ = ["MAX_TOTAL", "decode_uniform", "encode_uniform"]
