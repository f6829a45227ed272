"""EXT_meshopt_compression: buffer views compressed with meshoptimizer's codecs.

Decoding (reading any file that uses the extension) and encoding (the ``meshopt`` variant of
the decomposition writer) both go through the ``meshoptimizer`` package, the optional extra
``gltf``; without it a :class:`DependencyError` names the extra. The extension's vertex codec is
version 0 (what EXT_meshopt_compression defines; version 1 is KHR_meshopt_compression's), set
before every encoding since the library keeps it as global state.

A view decodes to at most 64 times its bytes (:data:`_MAX_RATIO`), and the views a file decodes,
which it keeps, within ``--max-memory`` together (the document's
:class:`~tuckercodec.io.common.budget.Inflation`), each checked before it is decoded.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any

import numpy as np

from ...errors import InputError
from ...system.optional import import_optional
from .container import Document, integer

EXTENSION = "EXT_meshopt_compression"
#: The most bytes one compressed byte can become: the attribute codec spends at least 2 bits on
#: each 16-byte group (64:1 on zeros), the index codecs at least a byte per triangle or index
#: (12:1 and 4:1); a view that claims more is refused before anything is allocated.
_MAX_RATIO = 64
_SLACK = 4096  # the codecs' headers and tails


def _library(purpose: str) -> ModuleType:
    return import_optional("meshoptimizer", "gltf", purpose)


def decode_view(doc: Document, index: Any, view: dict[str, Any], ext: Any) -> memoryview:
    """The decompressed bytes of buffer view ``index`` (``count x byteStride``)."""
    if index in doc.decoded_views:
        return doc.decoded_views[index]
    where = f"bufferViews[{index}].extensions.{EXTENSION}"
    if not isinstance(ext, dict):
        raise doc.fail(f"{where} must be an object")
    count = integer(doc, ext, "count", where, minimum=1)
    stride = integer(doc, ext, "byteStride", where, minimum=1)
    length = integer(doc, ext, "byteLength", where, minimum=1)
    offset = integer(doc, ext, "byteOffset", where, default=0)
    mode, kind = ext.get("mode"), ext.get("filter", "NONE")
    if mode == "ATTRIBUTES":
        if stride % 4 or stride > 256:
            raise doc.fail(f"{where}: byteStride {stride} must be a multiple of 4 up to 256")
    elif mode in ("TRIANGLES", "INDICES"):
        if stride not in (2, 4) or (mode == "TRIANGLES" and count % 3):
            raise doc.fail(f"{where}: {mode} needs byteStride 2 or 4 (and whole triangles)")
    else:
        raise doc.fail(f"{where}: mode {mode!r} is not ATTRIBUTES, TRIANGLES or INDICES")
    if kind not in ("NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL") or (
        kind != "NONE" and mode != "ATTRIBUTES"
    ):
        raise doc.fail(f"{where}: filter {kind!r} is not one the extension defines for {mode}")
    declared = integer(doc, view, "byteLength", f"bufferViews[{index}]", minimum=1)
    if count * stride != declared or count * stride > _MAX_RATIO * length + _SLACK:
        raise doc.fail(
            f"{where}: {count} elements of {stride} bytes from {length} compressed bytes, for a "
            f"view of {declared}: impossible, the file is damaged"
        )
    buffer = doc.buffer(integer(doc, ext, "buffer", where), where)
    if offset + length > len(buffer):
        raise doc.fail(f"{where}: bytes {offset}..{offset + length} run past the buffer")
    try:  # the views are kept once decoded: together within what the file may inflate
        doc.inflation.take(count * stride, where)
    except InputError as error:
        raise doc.fail(error.reason) from None
    source = np.frombuffer(buffer[offset : offset + length], dtype=np.uint8)
    meshopt = _library("reading a glTF compressed with EXT_meshopt_compression")
    try:
        if mode == "ATTRIBUTES":
            out = meshopt.decode_vertex_buffer(count, stride, source).view(np.uint8).reshape(-1)
            out = _unfilter(meshopt, kind, out, count, stride)
        elif mode == "TRIANGLES":
            decoded = meshopt.decode_index_buffer(count, stride, source)
            out = decoded.view(np.uint8)[: count * stride]
        else:
            decoded = meshopt.decode_index_sequence(count, stride, source)
            out = decoded.view(np.uint8)[: count * stride]
    except (ValueError, RuntimeError) as error:
        raise doc.fail(f"{where}: the compressed data cannot be decoded ({error})") from None
    result = memoryview(np.ascontiguousarray(out).tobytes())
    doc.decoded_views[index] = result
    return result


def _unfilter(meshopt: ModuleType, kind: str, data: np.ndarray, count: int, stride: int) -> Any:
    if kind == "NONE":
        return data
    decode = {
        "OCTAHEDRAL": meshopt.decode_filter_oct,
        "QUATERNION": meshopt.decode_filter_quat,
        "EXPONENTIAL": meshopt.decode_filter_exp,
    }[kind]
    return np.asarray(decode(data, count, stride)).view(np.uint8).reshape(-1)


def encode_attributes(rows: bytes, count: int, stride: int) -> bytes:
    """``count`` vertices of ``stride`` bytes (a multiple of 4) with the attribute codec, v0."""
    meshopt = _library("writing EXT_meshopt_compression")
    meshopt.encode_vertex_version(0)
    data = np.frombuffer(rows, dtype=np.uint8).reshape(count, stride)
    return bytes(meshopt.encode_vertex_buffer(data, count, stride))


def exponential_words(values: bytes, exponents: np.ndarray) -> bytes:
    """float32 ``values``, each a multiple of ``2**exponent`` (``exponents``: one per value of
    a row, the rows following each other), as the EXPONENTIAL filter stores them: a signed
    8-bit exponent in the top byte over a signed 24-bit mantissa, ``value = mantissa ·
    2**exponent`` (what the filter decodes)."""
    flat = np.asarray(exponents, dtype=np.int64).reshape(-1)
    floats = np.frombuffer(values, dtype="<f4").astype(np.float64).reshape(-1, flat.size)
    exponents = np.broadcast_to(flat, floats.shape)
    mantissas = np.round(np.ldexp(floats, -exponents)).astype(np.int64)
    if np.abs(mantissas).max(initial=0) >= 1 << 23 or not np.array_equal(
        np.ldexp(mantissas.astype(np.float64), exponents), floats
    ):
        raise ValueError("the values are not 24-bit multiples of their power-of-two steps")
    words = (mantissas & 0xFFFFFF) | ((exponents & 0xFF) << 24)
    return words.astype("<u4").tobytes()


def encode_triangles(indices: np.ndarray) -> bytes:
    """A triangle list (flat) with the index codec (decoded with any index size)."""
    meshopt = _library("writing EXT_meshopt_compression")
    flat = np.ascontiguousarray(indices, dtype=np.uint32).reshape(-1)
    return bytes(meshopt.encode_index_buffer(flat, len(flat), int(flat.max()) + 1))


def vertex_cache_order(triangles: np.ndarray, vertices: int) -> np.ndarray:
    """The triangles (T, 3) reordered for the GPU's vertex cache (meshoptimizer's
    optimize_vertex_cache): the index codec then takes about half the bytes. The vertices keep
    their order, and so their correspondence with the sequence's."""
    if len(triangles) == 0:
        return triangles
    meshopt = _library("writing EXT_meshopt_compression")
    flat = np.ascontiguousarray(triangles, dtype=np.uint32).reshape(-1)
    ordered = np.zeros_like(flat)
    meshopt.optimize_vertex_cache(ordered, flat, len(flat), vertices)
    return ordered.reshape(-1, 3).astype(triangles.dtype)


def compress_views(
    views: list[dict[str, Any]],
    data: list[bytes],
    elements: list[int],
    codecs: list[dict[str, Any] | None] | None = None,
) -> tuple[list[dict[str, Any]], bytes, int]:
    """Buffer views compressed with EXT_meshopt_compression: (the new views, buffer 0's bytes,
    the byte length of buffer 1, the uncompressed fallback that holds no data).

    Index views (``target`` 34963) use the TRIANGLES codec, vertex and animation views whose
    elements are a multiple of 4 bytes the ATTRIBUTES codec; a view neither fits (2-byte
    elements) stays uncompressed in buffer 0. ``codecs`` (one per view, or None) may set a
    view's codec ``stride`` (animation data has none of its own: a stride of one keyframe lets
    the codec take differences over time) and, with ``exponents``, the EXPONENTIAL filter.
    """
    compressed: list[dict[str, Any]] = []
    real = bytearray()
    fallback = 0
    for index, (view, raw, element) in enumerate(zip(views, data, elements, strict=True)):
        codec = (codecs[index] if codecs else None) or {}
        stride = codec.get("stride", view.get("byteStride", element))
        kind = "NONE"
        if view.get("target") == 34963:
            item = element
            payload = encode_triangles(np.frombuffer(raw, dtype=f"<u{item}"))
            mode, stride = "TRIANGLES", item
        elif stride % 4 == 0 and len(raw) % stride == 0:
            rows = raw
            if "exponents" in codec:
                rows, kind = exponential_words(raw, codec["exponents"]), "EXPONENTIAL"
            payload = encode_attributes(rows, len(raw) // stride, stride)
            mode = "ATTRIBUTES"
        else:
            real += b"\0" * (-len(real) % 4)
            compressed.append({**view, "buffer": 0, "byteOffset": len(real)})
            real += raw
            continue
        real += b"\0" * (-len(real) % 4)
        fallback += -fallback % 4
        extension = {
            "buffer": 0,
            "byteOffset": len(real),
            "byteLength": len(payload),
            "byteStride": stride,
            "count": len(raw) // stride,
            "mode": mode,
        }
        if kind != "NONE":
            extension["filter"] = kind
        compressed.append(
            {
                **view,
                "buffer": 1,
                "byteOffset": fallback,
                "extensions": {EXTENSION: extension},
            }
        )
        real += payload
        fallback += len(raw)
    real += b"\0" * (-len(real) % 4)
    return compressed, bytes(real), fallback
