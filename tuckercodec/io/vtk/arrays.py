"""The data arrays of VTK XML files (``<DataArray>``), decoded and encoded in plain numpy.

What VTK and ParaView write, all read here:

* ``format="ascii"``: numbers separated by white space;
* ``format="binary"``: base64 text in the element;
* ``format="appended"``: the array sits at ``offset`` in the file's ``<AppendedData>`` after its
  ``_`` marker, as raw bytes (``encoding="raw"``, ParaView's default) or base64 text.

A binary array starts with a block header of integers of the file's ``header_type`` (UInt32,
the default, or UInt64) in its ``byte_order``: uncompressed, one integer, the size in bytes;
compressed (``compressor="vtkZLibDataCompressor"``), the block count ``n``, the block size, the
size of the last block (0: a full one) and the ``n`` compressed sizes, followed by the ``n``
zlib streams. In base64 the header may be encoded on its own (ending in ``=`` padding, as VTK
does for compressed data and meshio for all) or together with the data (VTK, uncompressed).

Every size is checked before anything is allocated: an uncompressed size against the bytes the
file holds and against the array's declared length (``NumberOfPoints``, ``NumberOfCells``);
compressed sizes likewise, and each block's inflated size against :data:`MAX_INFLATION` times
its compressed size (no zlib stream expands further); the array's inflated size is then taken
from what the read may still decompress (:class:`~tuckercodec.io.common.budget.Inflation`, of
``--max-memory``), before anything is inflated: a 467 KB file that declares, consistently,
1 GB of zeros is refused there. Each block is inflated into its place with its declared size as
the limit, so a stream that would expand beyond what its header declares is refused after at
most that many bytes. LZ4 and LZMA compression (VTK's other compressors) are refused by name.
"""

from __future__ import annotations

import binascii
import zlib
from dataclasses import dataclass
from typing import Literal
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ..common.budget import Inflation

#: The VTK type names of data arrays and their numpy types (byte order added per file).
TYPES = {
    "Int8": "i1",
    "UInt8": "u1",
    "Int16": "i2",
    "UInt16": "u2",
    "Int32": "i4",
    "UInt32": "u4",
    "Int64": "i8",
    "UInt64": "u8",
    "Float32": "f4",
    "Float64": "f8",
}
#: Deflate encodes at most 258 bytes in 2 bits: no zlib stream inflates beyond 1032 times.
MAX_INFLATION = 1032
ZLIB = "vtkZLibDataCompressor"
_ORDERS: dict[str, Literal["<", ">"]] = {"LittleEndian": "<", "BigEndian": ">"}


@dataclass(frozen=True)
class Encoding:
    """How one file stores its binary arrays, from its ``<VTKFile>`` and ``<AppendedData>``.

    Attributes:
        order: ``"<"`` or ``">"`` (``byte_order``).
        header: the numpy type of block header integers (``header_type``), in that order.
        compressed: zlib blocks (``compressor="vtkZLibDataCompressor"``) or plain bytes.
        appended: the bytes after the ``_`` of ``<AppendedData>`` (``None``: there is none).
        appended_base64: whether those bytes are base64 text (``encoding="base64"``).
        inflation: what the file's compressed arrays may still inflate to, together.
    """

    order: str
    header: np.dtype
    compressed: bool
    appended: memoryview | None
    appended_base64: bool
    inflation: Inflation


def file_encoding(
    root: ElementTree.Element, appended: memoryview | None, base64: bool, inflation: Inflation
) -> Encoding:
    """The :class:`Encoding` that a ``<VTKFile>`` element declares; its compressed arrays
    inflate within ``inflation``."""
    order = _ORDERS.get(root.get("byte_order", "LittleEndian"))
    if order is None:
        raise InputError(f"has byte_order {root.get('byte_order')!r}, not LittleEndian/BigEndian")
    header = root.get("header_type", "UInt32")  # VTK's default, for version 0.1 files
    if header not in ("UInt32", "UInt64"):
        raise InputError(f"has header_type {header!r}, not UInt32 or UInt64")
    compressor = root.get("compressor", "")
    if compressor not in ("", ZLIB):
        raise InputError(
            f"is compressed with {compressor}, which is not read here: save it with ZLib "
            "compression or none (ParaView: Save Data, Compressor Type)"
        )
    return Encoding(
        order,
        np.dtype(order + TYPES[header]),
        bool(compressor),
        appended,
        appended is not None and base64,
        inflation,
    )


def read_array(
    element: ElementTree.Element,
    encoding: Encoding,
    what: str,
    *,
    components: int = 1,
    count: int | None = None,
) -> np.ndarray:
    """The values of a ``<DataArray>`` as a 1-D array of its own type, in native byte order.

    Args:
        element: the ``<DataArray>``.
        encoding: the file's :class:`Encoding`.
        what: the array's name for messages ("Points", "Polys offsets"...).
        components: the ``NumberOfComponents`` it must have.
        count: the tuples it must hold (``None``: any number, as for cell connectivity).

    Raises :class:`InputError` (without a path: the caller adds the file) naming ``what``.
    """
    kind = element.get("type", "")
    if kind not in TYPES:
        raise InputError(f"{what}: DataArray type {kind!r} is not a number type VTK writes")
    given = element.get("NumberOfComponents", "1").strip()
    if given != str(components):
        raise InputError(f"{what}: has NumberOfComponents={given!r}, not {components}")
    dtype = np.dtype(encoding.order + TYPES[kind])
    expected = None if count is None else count * components
    layout = element.get("format", "")
    if layout == "ascii":
        values = _ascii(element.text or "", dtype, expected, what)
    elif layout == "binary":
        text = "".join((element.text or "").split()).encode("ascii", "replace")
        values = _binary(_Base64(text, 0), encoding, dtype, expected, what)
    elif layout == "appended":
        values = _binary(_appended(element, encoding, what), encoding, dtype, expected, what)
    else:
        raise InputError(f"{what}: has format {layout!r}, not ascii, binary or appended")
    return values.astype(values.dtype.newbyteorder("="), copy=False)


def _ascii(text: str, dtype: np.dtype, expected: int | None, what: str) -> np.ndarray:
    """Numbers written as text, checked against the expected count before conversion."""
    tokens = text.split()
    if expected is not None and len(tokens) != expected:
        raise InputError(f"{what}: holds {len(tokens)} numbers, not the {expected} declared")
    try:
        if dtype.kind == "f":
            return np.array(tokens, dtype=np.float64).astype(dtype)
        wide = np.uint64 if dtype == np.uint64 else np.int64  # holds any value of dtype
        values = np.array(tokens, dtype=wide)
    except (ValueError, OverflowError) as error:
        raise InputError(f"{what}: a value is not a {dtype.name} number ({error})") from None
    info = np.iinfo(dtype)
    if values.size and (values.min() < info.min or values.max() > info.max):
        raise InputError(f"{what}: a value is out of the range of {dtype.name}")
    return values.astype(dtype)


def _appended(element: ElementTree.Element, encoding: Encoding, what: str) -> _Source:
    """Where an appended array starts in the file's appended data."""
    if encoding.appended is None:
        raise InputError(f"{what}: is appended, but the file has no <AppendedData> with _")
    text = element.get("offset", "").strip()
    if not text.isdigit():
        raise InputError(f"{what}: an appended DataArray needs an offset, got {text!r}")
    offset = int(text)
    if offset > len(encoding.appended):
        raise InputError(
            f"{what}: its offset {offset} is beyond the {len(encoding.appended)} bytes of "
            "appended data: the file is truncated"
        )
    if encoding.appended_base64:
        return _Base64(encoding.appended, offset)
    return _Raw(encoding.appended, offset)


class _Source:
    """One binary record (a block header, then data) at ``start`` of a file's bytes."""

    def __init__(self, data: bytes | memoryview, start: int) -> None:
        self.data, self.start = data, start

    def available(self) -> int:
        """The most bytes the rest of the file can hold (decoded)."""
        raise NotImplementedError

    def prefix(self, size: int, what: str) -> bytes | memoryview:
        """The record's first ``size`` bytes (its header)."""
        raise NotImplementedError

    def body(self, skip: int, size: int, what: str) -> bytes | memoryview:
        """The ``size`` bytes after the ``skip`` bytes of its header."""
        raise NotImplementedError


def _truncated(what: str, size: int, got: int) -> InputError:
    return InputError(f"{what}: needs {size} bytes but the file ends after {got}: truncated")


class _Raw(_Source):
    """A record in raw appended data."""

    def available(self) -> int:
        return len(self.data) - self.start

    def prefix(self, size: int, what: str) -> bytes | memoryview:
        return self.body(0, size, what)

    def body(self, skip: int, size: int, what: str) -> bytes | memoryview:
        begin = self.start + skip
        found = self.data[begin : begin + size]
        if len(found) != size:
            raise _truncated(what, size, len(found))
        return found


def _chars(size: int) -> int:
    """The base64 characters that encode ``size`` bytes."""
    return -(-size // 3) * 4


class _Base64(_Source):
    """A record in base64 text: its header encoded on its own or with its data."""

    def available(self) -> int:
        return (len(self.data) - self.start) * 3 // 4

    def _decode(self, begin: int, size: int, what: str) -> bytes:
        text = self.data[begin : begin + _chars(size)]
        if len(text) < _chars(size):
            raise _truncated(what, size, len(text) * 3 // 4)
        try:
            found = binascii.a2b_base64(text, strict_mode=True)
        except binascii.Error as error:
            raise InputError(f"{what}: is not valid base64 ({error})") from None
        if len(found) < size:
            raise _truncated(what, size, len(found))
        return found

    def prefix(self, size: int, what: str) -> bytes:
        return self._decode(self.start, size, what)[:size]

    def body(self, skip: int, size: int, what: str) -> bytes:
        end = self.start + _chars(skip)
        if skip % 3 and self.data[end - 1 : end] == b"=":  # the header was encoded alone
            return self._decode(end, size, what)[:size]
        return self._decode(self.start, skip + size, what)[skip : skip + size]


def _binary(
    source: _Source, encoding: Encoding, dtype: np.dtype, expected: int | None, what: str
) -> np.ndarray:
    """The values of one binary record, every declared size checked before it is used."""
    unit = encoding.header.itemsize
    if not encoding.compressed:
        size = int(np.frombuffer(source.prefix(unit, what), encoding.header)[0])
        _check_size(size, dtype, expected, what)
        if size > source.available():
            raise _truncated(what, size, source.available())
        return np.frombuffer(source.body(unit, size, what), dtype)
    blocks = int(np.frombuffer(source.prefix(unit, what), encoding.header)[0])
    if (3 + blocks) * unit > source.available():
        raise InputError(
            f"{what}: declares {blocks} compressed blocks, whose sizes alone need "
            f"{(3 + blocks) * unit} bytes, but the file ends after {source.available()}: truncated"
        )
    header = np.frombuffer(source.prefix((3 + blocks) * unit, what), encoding.header).tolist()
    block_size, last, sizes = header[1], header[2], header[3:]
    if blocks and (block_size == 0 or last > block_size):
        raise InputError(f"{what}: has blocks of {block_size} bytes, the last of {last}")
    inflated = [block_size] * blocks
    if blocks and last:
        inflated[-1] = last
    _check_size(sum(inflated), dtype, expected, what)
    for number, (packed, size) in enumerate(zip(sizes, inflated, strict=True)):
        if size > MAX_INFLATION * packed:  # before inflating: zlib cannot expand this far
            raise InputError(
                f"{what}: compressed block {number} of {packed} bytes declares {size} bytes, "
                f"more than zlib can expand it to ({MAX_INFLATION}x): refused"
            )
    if sum(sizes) > source.available():
        raise _truncated(what, sum(sizes), source.available())
    encoding.inflation.take(sum(inflated), what)  # before a byte is inflated
    data = source.body((3 + blocks) * unit, sum(sizes), what)
    return np.frombuffer(_inflate(data, sizes, inflated, what), dtype)


def _check_size(size: int, dtype: np.dtype, expected: int | None, what: str) -> None:
    """A declared byte size must hold whole values, as many as the element declares."""
    if expected is not None and size != expected * dtype.itemsize:
        raise InputError(
            f"{what}: holds {size} bytes, not the {expected} {dtype.name} values "
            f"({expected * dtype.itemsize} bytes) its element declares"
        )
    if size % dtype.itemsize:
        raise InputError(f"{what}: holds {size} bytes, not whole {dtype.name} values")


def _inflate(
    data: bytes | memoryview, sizes: list[int], inflated: list[int], what: str
) -> bytearray:
    """Inflate each zlib block to exactly its declared size, and never beyond it, into its
    place in one buffer of the declared total."""
    out = bytearray(sum(inflated))
    start = end = 0
    for number, (packed, size) in enumerate(zip(sizes, inflated, strict=True)):
        block = data[start : start + packed]
        start += packed
        inflater = zlib.decompressobj()
        try:
            found = inflater.decompress(block, size)  # at most size bytes, whatever it holds
            complete = inflater.eof and not inflater.unconsumed_tail
        except zlib.error as error:
            raise InputError(f"{what}: compressed block {number} is damaged ({error})") from None
        if len(found) == size and not complete:
            raise InputError(
                f"{what}: compressed block {number} inflates beyond the {size} bytes its "
                "header declares: refused"
            )
        if len(found) != size or not complete:
            raise InputError(
                f"{what}: compressed block {number} inflates to {len(found)} bytes, not the "
                f"{size} its header declares (damaged or truncated)"
            )
        out[end : end + size] = found
        end += size
    return out


# ------------------------------------------------------------------------------------------
# writing


@dataclass(frozen=True)
class Layout:
    """How a written file stores its arrays (every layout VTK writes; the default is
    ParaView's: appended raw bytes, zlib blocks, UInt64 headers, little-endian).

    Attributes:
        format: ``"appended"``, ``"binary"`` (base64 in the element) or ``"ascii"``.
        base64: appended data as base64 text rather than raw bytes.
        compress: zlib blocks of ``block_size`` bytes (binary and appended only; a multiple
            of 8, since VTK swaps the byte order of each block on its own).
        header: ``"UInt64"`` or ``"UInt32"``.
        byte_order: ``"LittleEndian"`` or ``"BigEndian"``.
    """

    format: str = "appended"
    base64: bool = False
    compress: bool = True
    header: str = "UInt64"
    byte_order: str = "LittleEndian"
    block_size: int = 1 << 15  # VTK's own

    def __post_init__(self) -> None:
        # VTK swaps the byte order of each block on its own: blocks must hold whole values
        if self.block_size <= 0 or self.block_size % 8:
            raise ValueError(f"block_size must be a positive multiple of 8, not {self.block_size}")

    def header_type(self) -> np.dtype:
        """The numpy type of block header integers."""
        return np.dtype(_ORDERS[self.byte_order] + TYPES[self.header])


def type_name(dtype: np.dtype) -> str:
    """The VTK name of a numpy type ("Float32"...)."""
    code = dtype.kind + str(dtype.itemsize)
    return next(name for name, value in TYPES.items() if value == code)


def encode_array(values: np.ndarray, layout: Layout) -> bytes:
    """The encoded values of one array: its ASCII text, or its binary record (block header
    and data, base64-encoded unless appended raw), for :func:`read_array` to read back."""
    if layout.format == "ascii":
        numbers = values.tolist()
        # float32 values as the float64 they are exactly, so that reading back is exact
        text = " ".join(map(repr, numbers) if values.dtype.kind == "f" else map(str, numbers))
        return text.encode("ascii")
    data = values.astype(values.dtype.newbyteorder(_ORDERS[layout.byte_order])).tobytes()
    header_type = layout.header_type()
    if layout.compress:
        blocks = [data[i : i + layout.block_size] for i in range(0, len(data), layout.block_size)]
        packed = [zlib.compress(block, 6) for block in blocks]
        last = len(blocks[-1]) % layout.block_size if blocks else 0
        sizes = [len(blocks), layout.block_size, last, *map(len, packed)]
        header, body = np.array(sizes, header_type).tobytes(), b"".join(packed)
    else:
        header, body = np.array([len(data)], header_type).tobytes(), data
    if layout.format == "appended" and not layout.base64:
        return header + body
    if layout.compress:  # as VTK does: the header on its own, then the blocks
        return binascii.b2a_base64(header, newline=False) + binascii.b2a_base64(body, newline=False)
    return binascii.b2a_base64(header + body, newline=False)
