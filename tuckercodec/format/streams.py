"""§6.1 Integer streams: zigzag integers split into byte planes, compressed with zstd.

``spec/FORMAT.md`` §6.1 defines the layout: n integers (already in stream order) are mapped to
unsigned by zigzag (0, -1, 1, -2 ... -> 0, 1, 2, 3 ...), then written as ``planes`` byte planes:
first the least significant byte of every value, then the next byte of every value, and so on.
Small integers then leave the high planes almost all zero, which zstd's entropy coder and match
finder squeeze to nearly nothing. The whole is one zstd frame that declares its content size.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import zstandard

from ..errors import FormatError, UnreachableTargetError
from ..system import native

#: zstd level of the final file; the size is entropy-coder bound, so higher levels gain little.
DEFAULT_LEVEL = 19
#: zstd level for trial packings while the encoder searches (sizes within ~1 % of level 19).
SEARCH_LEVEL = 3
MAX_PLANES = 4  # integers of at most 32 bits after zigzag: |value| <= 2**31
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"  # a zstd data frame (skippable frames have other magics)
#: No zstd frame decompresses to more than this many bytes per byte of frame (RFC 8878): a
#: block regenerates at most Block_Maximum_Size = 128 KiB and takes at least 4 bytes (a
#: 3-byte header and, for the densest kind, RLE, one byte), and the frame header adds more.
#: Level 19 on 256 MiB of zeros reaches 32696.
ZSTD_MAX_EXPANSION = (128 << 10) // 4


def zigzag(values: np.ndarray) -> np.ndarray:
    """Signed to unsigned: 0, -1, 1, -2, 2 ... -> 0, 1, 2, 3, 4 ..."""
    values = values.astype(np.int64, copy=False)
    out = np.left_shift(values, 1)
    np.bitwise_xor(out, np.right_shift(values, 63), out=out)  # in place: one scratch array
    return out.view(np.uint64)


def unzigzag(values: np.ndarray) -> np.ndarray:
    """The inverse of :func:`zigzag`."""
    values = values.astype(np.uint64, copy=False)
    return ((values >> np.uint64(1)).astype(np.int64)) ^ -((values & np.uint64(1)).astype(np.int64))


def planes_needed(unsigned: np.ndarray) -> int:
    """The fewest byte planes (at least 1) that hold every value."""
    largest = int(unsigned.max()) if unsigned.size else 0
    return max(1, (largest.bit_length() + 7) // 8)


def to_planes(unsigned: np.ndarray, planes: int) -> bytes:
    """Byte planes of unsigned values, least significant plane first (§6.1)."""
    little = np.ascontiguousarray(unsigned, dtype="<u8").reshape(-1)
    as_bytes = little.view(np.uint8).reshape(-1, 8)[:, :planes]
    return np.ascontiguousarray(as_bytes.T).tobytes()


def from_planes(raw: bytes | memoryview, count: int, planes: int) -> np.ndarray:
    """Unsigned values (uint64) from ``planes`` byte planes of ``count`` values each."""
    grid = np.frombuffer(raw, dtype=np.uint8).reshape(planes, count)
    out = np.zeros(count, dtype="<u8")
    # each plane copied into its byte of the little-endian values: no 8-byte scratch per value
    # (a large U1's values are the largest array a decoder makes)
    as_bytes = out.view(np.uint8).reshape(count, 8)
    for plane in range(planes):
        as_bytes[:, plane] = grid[plane]
    return out.astype(np.uint64, copy=False)


def compress(raw: bytes, level: int = DEFAULT_LEVEL) -> bytes:
    """One zstd frame holding ``raw``, with its content size declared."""
    return zstandard.ZstdCompressor(level=level, write_content_size=True).compress(raw)


class ZstdFrameProblem(ValueError):
    """Why a payload is not one zstd frame of exactly the size wanted (§6.1 step 3):
    :func:`decompress_exact` reports it as R29, the zarr codec's point chunks as damage."""


def decompress_exact(payload: bytes | memoryview, size: int, where: str) -> bytes:
    """Decompress one zstd frame that must hold exactly ``size`` bytes (§6.1 step 3).

    The frame's declared content size is checked before anything is allocated, and bytes after
    the frame are an error (R29-zstd-content-size).
    """
    try:
        return zstd_exact(payload, size)
    except ZstdFrameProblem as problem:
        raise FormatError(str(problem), rule="R29-zstd-content-size", field=where) from None


def zstd_exact(payload: bytes | memoryview, size: int) -> bytes:
    """The content of the one zstd frame ``payload``, which must declare and hold exactly
    ``size`` bytes, checked before anything is allocated; ZstdFrameProblem otherwise."""
    if bytes(payload[:4]) != ZSTD_MAGIC:
        raise ZstdFrameProblem("the payload does not start with a zstd frame header")
    try:
        declared = zstandard.frame_content_size(payload)
    except zstandard.ZstdError:
        raise ZstdFrameProblem("the payload does not start with a zstd frame header") from None
    if declared != size:
        what = "no content size" if declared == -1 else f"{declared} bytes"
        raise ZstdFrameProblem(
            f"the zstd frame declares {what}, but the section's shape needs {size}"
        )
    if size > ZSTD_MAX_EXPANSION * len(payload):
        # zstandard allocates the declared size before it reads a block: a 20-byte frame
        # header declaring 4 GiB would cost 4 GiB (or a MemoryError) although no frame this
        # short can hold that much. So the claim is checked against the payload first.
        raise ZstdFrameProblem(
            f"the zstd frame declares {size} bytes, more than a {len(payload)}-byte frame can "
            f"hold (at most {ZSTD_MAX_EXPANSION} bytes per byte)"
        )
    try:
        if size == 0:
            # one-shot decompression stops at a header declaring 0 bytes: read the frame to its end
            reader = zstandard.ZstdDecompressor().decompressobj()
            raw = reader.decompress(payload)
            if not reader.eof or reader.unused_data:
                raise zstandard.ZstdError("the frame is incomplete or followed by other data")
        else:
            raw = zstandard.ZstdDecompressor().decompress(
                payload, max_output_size=size, allow_extra_data=False
            )
    except zstandard.ZstdError as error:
        raise ZstdFrameProblem(f"the zstd frame does not decompress: {error}") from None
    if len(raw) != size:
        raise ZstdFrameProblem(f"the zstd frame holds {len(raw)} bytes, not {size}")
    return raw


def checked_planes(params: Mapping[str, Any], where: str, *, adaptive: bool = False) -> int:
    """The ``planes`` parameter of a stream section: an int in 1..MAX_PLANES, or 0 for a
    faces-traverse stream of ``coder`` 1 (``adaptive``, §6.8), which has no planes
    (R30-planes)."""
    planes = params.get("planes")
    low, high = (0, 0) if adaptive else (1, MAX_PLANES)
    if not isinstance(planes, int) or isinstance(planes, bool) or not low <= planes <= high:
        allowed = "0 with coder 1" if adaptive else f"1..{MAX_PLANES}"
        raise FormatError(
            f"planes must be {allowed}, got {planes!r}",
            rule="R30-planes",
            field=f"{where}.planes",
        )
    return planes


def pack_integers(values: np.ndarray, level: int = DEFAULT_LEVEL) -> tuple[bytes, int]:
    """``(payload, planes)`` for integers in stream order."""
    core = native.core()
    if core is not None:  # zigzag and planes in one pass
        planes, raw = core.pack_planes(np.ascontiguousarray(values.reshape(-1), dtype=np.int64))
    else:
        unsigned = zigzag(values.reshape(-1))
        planes = planes_needed(unsigned)
    if planes > MAX_PLANES:
        raise UnreachableTargetError(
            f"a quantized value of {int(np.abs(values).max())} does not fit the format's 32-bit "
            "range: the error target is too small for the size of the coordinates"
        )
    if core is None:
        raw = to_planes(unsigned, planes)
    return compress(raw, level), planes


def unpack_integers(payload: bytes | memoryview, count: int, planes: int, where: str) -> np.ndarray:
    """``count`` signed integers (int64) from a payload written by :func:`pack_integers` (or of
    §6.9, whose 64-bit integers take up to 8 planes)."""
    raw = decompress_exact(payload, count * planes, where)
    core = native.core()
    if core is not None and 1 <= planes <= 8:  # planes and unzigzag in one pass, no scratch
        # raw holds count * planes bytes (checked above): the core has nothing to refuse
        values: np.ndarray = core.unpack_planes(raw, count, planes)
        return values
    unsigned = from_planes(raw, count, planes)
    del raw
    # unzigzag in place, a block at a time: the stream's integers are the largest array the
    # decoder holds before the positions, and a whole-size sign array beside them was a third
    # copy of a large U1 at the decoder's peak
    sign = np.empty(min(count, _UNZIGZAG_BLOCK), dtype=np.int64)
    for start in range(0, count, _UNZIGZAG_BLOCK):
        block = unsigned[start : start + _UNZIGZAG_BLOCK]
        part = sign[: block.size]
        np.bitwise_and(block, np.uint64(1), out=part.view(np.uint64))
        np.negative(part, out=part)  # 0 or -1
        block >>= np.uint64(1)
        block.view(np.int64)[:] ^= part
    return unsigned.view(np.int64)


#: Values unzigzagged at once by :func:`unpack_integers` (8 MB of scratch).
_UNZIGZAG_BLOCK = 1 << 20
