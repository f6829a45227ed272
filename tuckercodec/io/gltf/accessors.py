"""glTF accessors: typed arrays read out of buffer views, and written into one binary buffer.

Reading follows the glTF 2.0 rules: a buffer view's ``byteStride`` (or tight packing), an
accessor's ``byteOffset``, normalized integers mapped to floats by the spec's formulas
(``max(c / 127, -1)`` for a signed byte, ``c / 255`` for an unsigned one...), sparse
substitutions, and buffer views compressed with EXT_meshopt_compression (:mod:`.meshopt`).
Every size is checked against the bytes that exist before an array is allocated: an accessor
whose ``count x stride`` runs past its buffer view, or a view past its buffer, is an error
naming the accessor.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.sources import as_float64
from .container import Document, integer

#: componentType -> numpy dtype (little-endian, as glTF stores them).
COMPONENT_TYPES: dict[int, np.dtype[Any]] = {
    5120: np.dtype("<i1"),
    5121: np.dtype("<u1"),
    5122: np.dtype("<i2"),
    5123: np.dtype("<u2"),
    5125: np.dtype("<u4"),
    5126: np.dtype("<f4"),
}
CODE_OF: dict[np.dtype[Any], int] = {dtype: code for code, dtype in COMPONENT_TYPES.items()}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
TYPE_OF = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def read_accessor(doc: Document, index: Any, what: str, *, width: int | None = None) -> np.ndarray:
    """Accessor ``index`` as an array (count, components): floats as float64 (normalized
    integers converted), other integers as int64. ``width``: the number of components the
    caller needs (3 for positions); ``what`` names the referrer for messages."""
    accessor = doc.item("accessors", index, what)
    name = f"accessors[{index}] ({what})"
    code = accessor.get("componentType")
    # a JSON integer: a list is unhashable, and 5126.0 or true would match a key
    plain = isinstance(code, int) and not isinstance(code, bool)
    dtype = COMPONENT_TYPES.get(code) if isinstance(code, int) and plain else None
    if dtype is None:
        raise doc.fail(f"{name}: componentType {accessor.get('componentType')!r} is not glTF's")
    kind = accessor.get("type")
    if kind not in ("SCALAR", "VEC2", "VEC3", "VEC4"):
        raise doc.fail(f"{name}: type {kind!r} is not read here (only scalars and vectors)")
    components = WIDTHS[kind]
    if width is not None and components != width:
        raise doc.fail(f"{name}: a {kind}, where a {TYPE_OF.get(width, width)} is needed")
    count = integer(doc, accessor, "count", name, minimum=1)
    offset = integer(doc, accessor, "byteOffset", name, default=0)
    element = components * dtype.itemsize
    if "bufferView" in accessor:
        raw = _strided(doc, accessor["bufferView"], offset, count, element, dtype.itemsize, name)
        values = raw.view(dtype).reshape(count, components).copy()
    else:
        # all zeros (a sparse morph target's base): only as much as the file's data, the
        # bytes its buffers hold, not the byteLength they declare
        if count * element > _data_bytes(doc):
            raise doc.fail(
                f"{name}: {count} elements without a buffer view, more than the "
                f"{_data_bytes(doc)} bytes of data the file holds"
            )
        values = np.zeros((count, components), dtype=dtype)
    if "sparse" in accessor:
        _apply_sparse(doc, accessor["sparse"], values, name)
    normalized = accessor.get("normalized", False)
    if normalized is True:
        if dtype.kind == "f" or dtype.itemsize == 4:
            raise doc.fail(f"{name}: normalized is only for 8- and 16-bit integers")
        return _denormalize(values)
    if dtype.kind == "f":
        result = as_float64(values)
        if not np.isfinite(result).all():
            row = int(np.argwhere(~np.isfinite(result))[0, 0])
            raise doc.fail(f"{name}: element {row} is not finite (NaN or infinity)")
        return result
    return values.astype(np.int64)


def _denormalize(values: np.ndarray) -> np.ndarray:
    """The glTF 2.0 mapping of normalized integers to floats."""
    info = np.iinfo(values.dtype)
    result = values.astype(np.float64) / info.max
    return np.maximum(result, -1.0) if info.min < 0 else result


def _data_bytes(doc: Document) -> int:
    """The bytes the file's buffers hold: each loaded (once, kept for the reads to come);
    one that cannot be (absent, a compression extension's fallback) holds none, and buffers
    of one file count its bytes once. A declared byteLength is not data: a few hundred bytes of
    JSON can declare gigabytes, or name one file a thousand times."""
    if "data bytes" not in doc.cache:
        held: dict[int, int] = {}  # the longest view of each object of bytes
        for index in range(len(doc.array("buffers"))):
            with contextlib.suppress(InputError):
                view = doc.buffer(index, "the file's data")
                held[id(view.obj)] = max(held.get(id(view.obj), 0), len(view))
        doc.cache["data bytes"] = sum(held.values())
    return int(doc.cache["data bytes"])


def _strided(
    doc: Document, view_index: Any, offset: int, count: int, element: int, align: int, name: str
) -> np.ndarray:
    """The bytes of ``count`` elements of ``element`` bytes, (count, element) uint8, checked."""
    view = doc.item("bufferViews", view_index, name)
    where = f"bufferViews[{view_index}]"
    data = view_bytes(doc, view_index)
    stride = view.get("byteStride", element)
    if not isinstance(stride, int) or isinstance(stride, bool) or stride < element:
        raise doc.fail(
            f"{where}.byteStride {stride!r} is less than {name}'s {element}-byte element"
        )
    if offset % align:
        raise doc.fail(f"{name}: byteOffset {offset} is not a multiple of {align}")
    needed = offset + stride * (count - 1) + element  # Python ints: no overflow
    if needed > len(data):
        raise doc.fail(
            f"{name}: {count} elements of {element} bytes every {stride} from byte {offset} need "
            f"{needed} bytes, but {where} has {len(data)}: the file is damaged"
        )
    raw = np.frombuffer(data, dtype=np.uint8, count=needed - offset, offset=offset)
    if stride == element:
        return raw.reshape(count, element)
    return np.lib.stride_tricks.as_strided(raw, shape=(count, element), strides=(stride, 1))


def view_bytes(doc: Document, view_index: Any) -> memoryview:
    """The bytes of a buffer view, decompressed if it uses EXT_meshopt_compression."""
    view = doc.item("bufferViews", view_index, "an accessor")
    where = f"bufferViews[{view_index}]"
    extensions = view.get("extensions")
    extension = extensions.get("EXT_meshopt_compression") if isinstance(extensions, dict) else None
    if extension is not None:
        from .meshopt import decode_view  # meshoptimizer, only for files that need it

        return decode_view(doc, view_index, view, extension)
    length = integer(doc, view, "byteLength", where, minimum=1)
    offset = integer(doc, view, "byteOffset", where, default=0)
    buffer = doc.buffer(integer(doc, view, "buffer", where), where)
    if offset + length > len(buffer):
        raise doc.fail(
            f"{where}: bytes {offset}..{offset + length} run past its buffer's {len(buffer)}"
        )
    return buffer[offset : offset + length]


def _apply_sparse(doc: Document, sparse: Any, values: np.ndarray, name: str) -> None:
    where = f"{name}.sparse"
    if not isinstance(sparse, dict):
        raise doc.fail(f"{where} must be an object")
    count = integer(doc, sparse, "count", where, minimum=1)
    if count > len(values):
        raise doc.fail(f"{where}: {count} substitutions for {len(values)} elements")
    indices, substitutes = sparse.get("indices"), sparse.get("values")
    if not isinstance(indices, dict) or not isinstance(substitutes, dict):
        raise doc.fail(f"{where} needs 'indices' and 'values' objects")
    index_type = COMPONENT_TYPES.get(indices.get("componentType"))  # type: ignore[arg-type]
    if index_type is None or index_type.kind != "u":
        raise doc.fail(f"{where}.indices: componentType must be an unsigned integer type")
    positions = _strided(
        doc,
        indices.get("bufferView"),
        integer(doc, indices, "byteOffset", f"{where}.indices", default=0),
        count,
        index_type.itemsize,
        index_type.itemsize,
        f"{where}.indices",
    )
    rows = positions.view(index_type).reshape(count).astype(np.int64)
    if (np.diff(rows) <= 0).any() or rows[-1] >= len(values):
        raise doc.fail(f"{where}.indices must increase strictly and stay below {len(values)}")
    element = values.shape[1] * values.dtype.itemsize
    replaced = _strided(
        doc,
        substitutes.get("bufferView"),
        integer(doc, substitutes, "byteOffset", f"{where}.values", default=0),
        count,
        element,
        values.dtype.itemsize,
        f"{where}.values",
    )
    values[rows] = replaced.view(values.dtype).reshape(count, values.shape[1])


@dataclass
class BufferBuilder:
    """Collects arrays into one binary buffer, with their buffer views and accessors.

    Each array gets its own buffer view, aligned to 4 bytes (vertex attributes: rows padded to
    a multiple of 4 bytes and the view given that ``byteStride``, as glTF requires).
    """

    accessors: list[dict[str, Any]] = field(default_factory=list)
    views: list[dict[str, Any]] = field(default_factory=list)
    chunks: list[bytes] = field(default_factory=list)
    view_data: list[bytes] = field(default_factory=list)  # each view's bytes, for compression
    view_elements: list[int] = field(default_factory=list)  # each view's element size
    #: how EXT_meshopt_compression should encode each view, where the writer says (its
    #: ``stride`` and, for the EXPONENTIAL filter, the ``exponents`` of its float32 values)
    view_codecs: list[dict[str, Any] | None] = field(default_factory=list)
    size: int = 0

    def add_view(
        self, data: bytes, element: int = 4, codec: dict[str, Any] | None = None, **fields: Any
    ) -> int:
        """Append ``data`` as a new buffer view (at a 4-byte boundary) of elements of
        ``element`` bytes; returns its index. ``codec``: see :attr:`view_codecs`."""
        self.size += self._pad()
        self.views.append({"buffer": 0, "byteOffset": self.size, "byteLength": len(data), **fields})
        self.chunks.append(data)
        self.view_data.append(data)
        self.view_elements.append(element)
        self.view_codecs.append(codec)
        self.size += len(data)
        return len(self.views) - 1

    def _pad(self) -> int:
        padding = -self.size % 4
        if padding:
            self.chunks.append(b"\0" * padding)
        return padding

    def add_accessor(
        self,
        values: np.ndarray,
        *,
        target: int | None = None,
        normalized: bool = False,
        bounds: bool = False,
        vertex_attribute: bool = False,
        view: int | None = None,
        byte_offset: int = 0,
        codec: dict[str, Any] | None = None,
    ) -> int:
        """Append ``values`` (count, components) in their dtype; returns the accessor index.

        ``vertex_attribute`` pads each row to 4 bytes and sets ``byteStride``; ``bounds``
        writes ``min``/``max`` (required for positions and animation inputs). ``view``: an
        existing buffer view to point at instead of writing the data (the caller wrote it,
        several accessors in one view for example), from its byte ``byte_offset``. ``codec``:
        how EXT_meshopt_compression should encode the new view (:attr:`view_codecs`).
        """
        values = np.ascontiguousarray(values)
        if values.ndim == 1:
            values = values[:, None]
        count, components = values.shape
        element = components * values.dtype.itemsize
        if view is None:
            stride = -(-element // 4) * 4 if vertex_attribute else element
            data = padded_rows(values, stride)
            fields: dict[str, Any] = {}
            if stride != element:
                fields["byteStride"] = stride
            if target is not None:
                fields["target"] = target
            view = self.add_view(data, element, codec, **fields)
        accessor: dict[str, Any] = {
            "bufferView": view,
            "componentType": CODE_OF[values.dtype.newbyteorder("<")],
            "count": count,
            "type": TYPE_OF[components],
        }
        if byte_offset:
            accessor["byteOffset"] = byte_offset
        if normalized:
            accessor["normalized"] = True
        if bounds:
            accessor["min"] = _json_numbers(values.min(axis=0))
            accessor["max"] = _json_numbers(values.max(axis=0))
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def binary(self) -> bytes:
        """The whole buffer, padded to 4 bytes."""
        self._pad()
        return b"".join(self.chunks)


def padded_rows(values: np.ndarray, stride: int) -> bytes:
    """The rows of ``values`` as little-endian bytes, each padded with zeros to ``stride``."""
    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<"))
    rows = values.view(np.uint8).reshape(len(values), -1)
    if rows.shape[1] == stride:
        return rows.tobytes()
    out = np.zeros((len(values), stride), dtype=np.uint8)
    out[:, : rows.shape[1]] = rows
    return out.tobytes()


def _json_numbers(values: np.ndarray) -> list[float | int]:
    """Bounds as JSON numbers of the accessor's own type (floats exactly as float32)."""
    if values.dtype.kind == "f":
        return [float(v) for v in values.astype(np.float32)]
    return [int(v) for v in values]
