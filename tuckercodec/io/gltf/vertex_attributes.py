"""glTF vertex attributes (TEXCOORD_n, NORMAL, COLOR_n, TANGENT, _CUSTOM...) read as the values
an :class:`~tuckercodec.model.attributes.Attribute` stores, and combined over several vertex
blocks (the primitives of a mesh, the meshes of a scene).

Values, by what the accessor holds:

* float32 stays float32, bit for bit.
* Normalized integers (colours and UVs as unsigned bytes or shorts, KHR_mesh_quantization's
  normals as signed ones) become float32 by glTF's own mapping (``c / 255``, ``c / 65535``,
  ``max(c / 127, -1)``, ``max(c / 32767, -1)``), rounded once to float32: exactly the float32
  of the value glTF defines.
* Other integers: as float32 for the semantics glTF defines as real numbers (a quantized
  TEXCOORD; exact for 8- and 16-bit integers), as int32 for the others (JOINTS_n, a _CUSTOM),
  float64 where an unsigned 32-bit value does not fit in int32.

Roles follow the semantics: TEXCOORD_n is a ``uv``, NORMAL a ``normal``, COLOR_n a ``color``,
everything else (TANGENT, JOINTS_n, WEIGHTS_n, _CUSTOM) ``generic``, named as the file names it.
An attribute of matrix type (a _CUSTOM MAT4) has no Attribute shape and is not read.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.attributes import COLOR, GENERIC, NORMAL, UV
from .accessors import COMPONENT_TYPES, read_accessor
from .container import Document

_TEXCOORD = re.compile(r"TEXCOORD_\d+\Z")
_COLOR = re.compile(r"COLOR_\d+\Z")
#: The semantics whose values glTF defines as real numbers: integers stored there are converted.
_REAL = re.compile(r"(TEXCOORD_\d+|NORMAL|COLOR_\d+|TANGENT|WEIGHTS_\d+)\Z")
#: Components each role's semantic must have, as glTF requires.
_WIDTHS = {UV: (2,), NORMAL: (3,), COLOR: (3, 4)}


@dataclass
class VertexValues:
    """One attribute's values over a block of vertices: its role and (count, c) values."""

    role: str
    values: np.ndarray


def role_of(semantic: str) -> str:
    """The attribute role of a glTF attribute semantic."""
    if _TEXCOORD.match(semantic):
        return UV
    if semantic == "NORMAL":
        return NORMAL
    if _COLOR.match(semantic):
        return COLOR
    return GENERIC


def read_vertex_attribute(
    doc: Document, accessor: Any, semantic: str, count: int, where: str
) -> VertexValues | None:
    """The attribute ``semantic`` of a primitive (accessor ``accessor``, ``count`` vertices), or
    None for a matrix-typed one; an InputError names the accessor where its type or count does
    not fit the semantic."""
    item = doc.item("accessors", accessor, f"{where} {semantic}")
    name = f"accessors[{accessor}] ({where} {semantic})"
    if item.get("type") in ("MAT2", "MAT3", "MAT4"):
        return None
    role = role_of(semantic)
    values = read_accessor(doc, accessor, f"{where} {semantic}")
    if role in _WIDTHS and values.shape[1] not in _WIDTHS[role]:
        raise doc.fail(f"{name}: {semantic} needs {_WIDTHS[role][0]} components per vertex")
    if len(values) != count:
        raise doc.fail(f"{name}: {len(values)} values for the {count} vertices of POSITION")
    stored = COMPONENT_TYPES[item["componentType"]]  # read_accessor checked it is one
    if values.dtype.kind == "f":  # float32, or a normalized integer glTF maps to a real
        return VertexValues(role, values.astype(np.float32))
    if _REAL.match(semantic):
        return VertexValues(role, values.astype(np.float32))
    fits = stored.kind == "i" or stored.itemsize < 4 or values.max(initial=0) <= 2**31 - 1
    return VertexValues(role, values.astype(np.int32 if fits else np.float64))


def combined(blocks: list[dict[str, VertexValues]], counts: list[int]) -> dict[str, VertexValues]:
    """The attributes of vertex blocks of ``counts`` vertices, one after the other: each name
    found in any block, in the order first met, its values over all the vertices. Where blocks
    differ, the values take the type that holds them all (float32 and int32: float64) and the
    most components; a block without the attribute, or with fewer components, gives zeros (a
    colour's missing alpha: 1), as a viewer shows a primitive without it."""
    names: dict[str, str] = {}
    for block in blocks:
        for name, found in block.items():
            names.setdefault(name, found.role)
    result: dict[str, VertexValues] = {}
    for name, role in names.items():
        present = [block[name].values for block in blocks if name in block]
        dtype = np.result_type(*present)
        width = max(values.shape[1] for values in present)
        parts = []
        for block, count in zip(blocks, counts, strict=True):
            part = np.zeros((count, width), dtype=dtype)
            if role == COLOR and width == 4:
                part[:, 3] = 1
            if name in block:
                values = block[name].values
                part[:, : values.shape[1]] = values
            parts.append(part)
        result[name] = VertexValues(role, np.concatenate(parts))
    return result
