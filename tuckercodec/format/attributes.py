"""§6.11 Sections ATTR.n (codec ``attribute``, format 1.5): static attributes, bit for bit.

An attribute is a table of N rows of c values (float32, float64 or int32) and, when *indexed*,
an index per element (vertex, corner or face) into the table. Both are lossless:

* The values become the *ordered integers* of their bit patterns (§6.9: consecutive integers in
  the values' order, so that close values give close integers; an int32 is its own), taken
  component by component (all first components, then all second...), and with ``predict`` 1
  each replaced by its difference from the row before (wrapping in the type's width). UVs,
  normals and colours of neighbouring rows are close, so the differences are small.
* The indices are predicted: a corner's, by the index its vertex used last (a vertex has one UV
  except along seams); the first use of an index, by one more than the largest so far (tables
  are written in order of first use); a face's by the face before. The differences are mostly 0.

Both streams are §6.1's zigzag byte planes in a Zstandard frame, with up to 8 planes for the
64-bit ordered integers of float64 values.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple, NoReturn

import numpy as np

from ..errors import FormatError
from ..model.attributes import CORNER, DOMAINS, FACE, GENERIC, ROLES, Attribute
from . import streams
from .limits import Limits, check_limit

CODEC = "attribute"
STEM = "ATTR"

#: The value types and their names in the file.
TYPES = {"f32": np.dtype("<f4"), "f64": np.dtype("<f8"), "i32": np.dtype("<i4")}
TYPE_NAMES = {np.dtype(np.float32): "f32", np.dtype(np.float64): "f64", np.dtype(np.int32): "i32"}
#: Predictors of the values: none, or the difference from the row before.
PREDICT_NONE, PREDICT_PREVIOUS = 0, 1


def section_id(number: int) -> str:
    """The id of attribute ``number``: ``ATTR.0``, ``ATTR.1``..."""
    return f"{STEM}.{number}"


class Mesh(NamedTuple):
    """What an attribute's elements are: the vertex count and the faces as decoded (in the
    given order, §6.10), whose corners are the faces' real entries in C order."""

    vertex_count: int
    faces: np.ndarray

    @property
    def corner_vertices(self) -> np.ndarray:
        return self.faces[self.faces >= 0]

    def element_count(self, domain: str) -> int:
        if domain == FACE:
            return int(self.faces.shape[0])
        if domain == CORNER:
            return int((self.faces >= 0).sum())
        return self.vertex_count


# -- the ordered integers and their wrapping differences --------------------------------------


def _ordered(values: np.ndarray) -> np.ndarray:
    """Each value's ordered integer (§6.9; an int32 is its own), as int64, in C order."""
    if values.dtype.kind == "i":
        return values.astype(np.int64).reshape(-1)
    bits = values.dtype.itemsize * 8
    signed = values.view(f"<i{bits // 8}").astype(np.int64).reshape(-1)
    return np.where(signed >= 0, signed, -(1 << (bits - 1)) - signed - 1)


def _from_ordered(ordered: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """The values whose ordered integers are ``ordered`` (the map is its own inverse)."""
    if dtype.kind == "i":
        return ordered.astype(dtype)
    bits = dtype.itemsize * 8
    signed = np.where(ordered >= 0, ordered, -(1 << (bits - 1)) - ordered - 1)
    return signed.astype(f"<i{bits // 8}").view(dtype)


def _wrap(values: np.ndarray, bits: int) -> np.ndarray:
    """``values`` wrapped to signed ``bits``-bit integers (int64 arithmetic wraps at 64)."""
    if bits == 64:
        return values
    half = np.int64(1 << (bits - 1))
    return ((values + half) & np.int64((1 << bits) - 1)) - half


def _value_stream(attribute_values: np.ndarray, predict: int) -> np.ndarray:
    """The stream of the values: ordered integers, component-major, predicted."""
    bits = attribute_values.dtype.itemsize * 8
    ordered = _ordered(attribute_values).reshape(attribute_values.shape).T.copy()
    if predict == PREDICT_PREVIOUS and attribute_values.shape[0] > 1:
        with np.errstate(over="ignore"):
            ordered[:, 1:] = _wrap(ordered[:, 1:] - ordered[:, :-1], bits)
    return ordered.reshape(-1)


def _values_of(
    stream: np.ndarray, rows: int, cols: int, dtype: np.dtype, predict: int
) -> np.ndarray:
    bits = dtype.itemsize * 8
    ordered = stream.reshape(cols, rows)
    if predict == PREDICT_PREVIOUS:
        with np.errstate(over="ignore"):
            ordered = _wrap(np.cumsum(ordered, axis=1), bits)
    return np.ascontiguousarray(_from_ordered(ordered.T.reshape(-1), dtype).reshape(rows, cols))


# -- the index predictor ------------------------------------------------------------------------


def _index_residuals(indices: np.ndarray, domain: str, mesh: Mesh) -> np.ndarray:
    """Each index less its prediction (module docstring)."""
    if domain == FACE:
        return np.diff(indices, prepend=np.int64(0))
    residuals = np.empty_like(indices)
    last_used: dict[int, int] = {}
    corner_vertices = mesh.corner_vertices.tolist() if domain == CORNER else None
    largest = -1
    for element, index in enumerate(indices.tolist()):
        predicted = largest + 1
        if corner_vertices is not None:
            vertex = corner_vertices[element]
            predicted = last_used.get(vertex, predicted)
            last_used[vertex] = index
        residuals[element] = index - predicted
        largest = max(largest, index)
    return residuals


def _indices_of(
    residuals: np.ndarray, domain: str, mesh: Mesh, rows: int, where: str
) -> np.ndarray:
    """The indices from their residuals, each checked to name a row (R43)."""
    if domain == FACE:
        indices = np.cumsum(residuals)
    else:
        indices = np.empty_like(residuals)
        last_used: dict[int, int] = {}
        corner_vertices = mesh.corner_vertices.tolist() if domain == CORNER else None
        largest = -1
        for element, residual in enumerate(residuals.tolist()):
            predicted = largest + 1
            if corner_vertices is not None:
                predicted = last_used.get(corner_vertices[element], predicted)
            index = predicted + residual
            if not 0 <= index < rows:
                refuse(f"element {element} has index {index}, outside 0..{rows - 1}", where)
            if corner_vertices is not None:
                last_used[corner_vertices[element]] = index
            indices[element] = index
            largest = max(largest, index)
    bad = np.flatnonzero((indices < 0) | (indices >= rows))
    if bad.size:
        element = int(bad[0])
        index = int(indices[element])
        refuse(f"element {element} has index {index}, outside 0..{rows - 1}", where)
    return indices


# -- encoding -----------------------------------------------------------------------------------


def _pack(stream: np.ndarray, level: int) -> tuple[list[int], bytes]:
    """``[count, planes, length]`` and the payload of a stream of up to 64-bit integers."""
    unsigned = streams.zigzag(stream)
    planes = streams.planes_needed(unsigned)
    payload = streams.compress(streams.to_planes(unsigned, planes), level)
    return [int(stream.size), planes, len(payload)], payload


def encode_attribute(attribute: Attribute, mesh: Mesh, level: int) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of an ATTR section: the smaller of the two value predictors."""
    best: tuple[dict[str, Any], bytes] | None = None
    index_entry, index_payload = [0, 1, 0], b""
    if attribute.indices is not None:
        index_entry, index_payload = _pack(
            _index_residuals(attribute.indices, attribute.domain, mesh), level
        )
    for predict in (PREDICT_NONE, PREDICT_PREVIOUS):
        value_entry, value_payload = _pack(_value_stream(attribute.values, predict), level)
        params = {
            "name": attribute.name,
            "domain": attribute.domain,
            "role": attribute.role,
            "type": TYPE_NAMES[attribute.values.dtype],
            "shape": [int(attribute.values.shape[0]), attribute.components],
            "indexed": attribute.indices is not None,
            "predict": predict,
            "streams": [value_entry, index_entry],
        }
        if best is None or len(value_payload) + len(index_payload) < len(best[1]):
            best = params, value_payload + index_payload
    assert best is not None
    return best


# -- decoding -----------------------------------------------------------------------------------


def refuse(message: str, field: str) -> NoReturn:
    """R43-attribute: an attribute's parameter or value is not as §6.11 says."""
    raise FormatError(message, rule="R43-attribute", field=field)


def check_unique_names(decoded: list[Attribute], section_ids: list[str]) -> None:
    """No two attributes share a name (R43)."""
    seen: set[str] = set()
    for attribute, section_id in zip(decoded, section_ids, strict=True):
        if attribute.name in seen:
            refuse(f"two attributes are named {attribute.name!r}", f"section {section_id}.name")
        seen.add(attribute.name)


def _int_param(params: Mapping[str, Any], key: str, where: str) -> int:
    value = params.get(key)
    if not isinstance(value, int) or isinstance(value, bool):
        refuse(f"{key} must be an int, got {value!r}", f"{where}.{key}")
    return int(value)


def _str_param(params: Mapping[str, Any], key: str, where: str) -> str:
    value = params.get(key)
    if not isinstance(value, str) or not value:
        refuse(f"{key} must be a non-empty str, got {value!r}", f"{where}.{key}")
    return str(value)


def _checked_streams(params: Mapping[str, Any], payload_length: int, where: str) -> list[list[int]]:
    table = params.get("streams")
    if not isinstance(table, list) or len(table) != 2:
        refuse("streams must be an array of two [count, planes, length]", f"{where}.streams")
    for number, entry in enumerate(table):
        if (
            not isinstance(entry, list)
            or len(entry) != 3
            or not all(isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in entry)
            or not 1 <= entry[1] <= 8
        ):
            refuse(
                f"stream {number} must be [count, planes 1..8, length] of ints >= 0, got {entry!r}",
                f"{where}.streams",
            )
    if table[0][2] + table[1][2] != payload_length:
        refuse(
            f"the streams' lengths add up to {table[0][2] + table[1][2]}, the payload has "
            f"{payload_length} bytes",
            f"{where}.streams",
        )
    return [list(entry) for entry in table]


def check_attribute_params(
    params: Mapping[str, Any], mesh: Mesh, payload_length: int, limits: Limits, where: str
) -> dict[str, Any]:
    """§5 step 19 for one ATTR section's parameters, in the order of §6.11 (R43), then its
    sizes against the limits (R21): everything a decoder checks before it reads the payload."""
    name = _str_param(params, "name", where)
    domain = _str_param(params, "domain", where)
    if domain not in DOMAINS:
        refuse(f"domain must be one of {', '.join(DOMAINS)}, got {domain!r}", f"{where}.domain")
    role = params.get("role")
    role = role if isinstance(role, str) and role in ROLES else GENERIC
    type_name = _str_param(params, "type", where)
    if type_name not in TYPES:
        refuse(f"type must be one of {', '.join(TYPES)}, got {type_name!r}", f"{where}.type")
    shape = params.get("shape")
    if (
        not isinstance(shape, list)
        or len(shape) != 2
        or not all(isinstance(x, int) and not isinstance(x, bool) for x in shape)
        or shape[0] < 0
        or not 1 <= shape[1] <= 4
    ):
        refuse(f"shape must be [rows >= 0, components 1..4], got {shape!r}", f"{where}.shape")
    rows, cols = shape
    indexed = params.get("indexed")
    if not isinstance(indexed, bool):
        refuse(f"indexed must be a bool, got {indexed!r}", f"{where}.indexed")
    elements = mesh.element_count(domain)
    if not indexed and rows != elements:
        refuse(
            f"an attribute that is not indexed has one row per {domain}: {elements}, not {rows}",
            f"{where}.shape",
        )
    predict = _int_param(params, "predict", where)
    if predict not in (PREDICT_NONE, PREDICT_PREVIOUS):
        refuse(f"predict must be 0 or 1, got {predict}", f"{where}.predict")
    table = _checked_streams(params, payload_length, where)
    want = [rows * cols, elements if indexed else 0]
    for number, (entry, count) in enumerate(zip(table, want, strict=True)):
        if entry[0] != count:
            refuse(f"stream {number} must hold {count} values, not {entry[0]}", f"{where}.streams")
    role_components = {"uv": (2,), "normal": (3,), "color": (3, 4)}
    if cols not in role_components.get(role, (1, 2, 3, 4)):
        role = GENERIC  # a role that does not fit is only a hint: the values are still read
    for entry in table:
        check_limit(
            entry[0] * entry[1],
            limits,
            "max_section_bytes",
            what=f"{entry[0]} values of {entry[1]} bytes",
            field=f"{where}.streams",
        )
    return {
        "name": name,
        "domain": domain,
        "role": role,
        "dtype": TYPES[type_name],
        "rows": rows,
        "cols": cols,
        "indexed": indexed,
        "predict": predict,
        "streams": table,
    }


def decode_attribute(
    payload: bytes | memoryview, params: dict[str, Any], mesh: Mesh, where: str
) -> Attribute:
    """The attribute of an ATTR section whose parameters :func:`check_attribute_params` gave."""
    (value_count, value_planes, value_length), (index_count, index_planes, _) = params["streams"]
    value_stream = streams.unpack_integers(
        payload[:value_length], value_count, value_planes, f"{where} values"
    )
    values = _values_of(
        value_stream, params["rows"], params["cols"], params["dtype"], params["predict"]
    )
    indices = None
    if params["indexed"]:
        residuals = streams.unpack_integers(
            payload[value_length:], index_count, index_planes, f"{where} indices"
        )
        indices = _indices_of(residuals, params["domain"], mesh, params["rows"], where)
    try:
        return Attribute(
            params["name"],
            params["domain"],
            values.astype(values.dtype.newbyteorder("=")),
            indices,
            params["role"],
        )
    except ValueError as error:  # InputError: a name the model refuses
        refuse(f"{error}", f"{where}.name")
