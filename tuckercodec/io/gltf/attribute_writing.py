"""A sequence's attributes as glTF vertex attributes: which semantic each is written under, the
numbers glTF can store for it, and what of a sequence a glTF cannot keep.

Semantics: an attribute named as a semantic its role allows keeps it (``TEXCOORD_0``,
``NORMAL``, ``COLOR_0``, ``TANGENT`` for a float32 VEC4 beside a NORMAL, ``_ANYTHING``);
otherwise a UV takes the next free ``TEXCOORD_n``, the (first) normal ``NORMAL``, a colour the
next free ``COLOR_n``, anything else ``_`` + its name (characters other than letters, digits
and ``_`` as ``_``). The sequence's names, and roles and value types glTF does not imply, are
recorded in the mesh's ``extras`` (``{"tuckercodec": {"attributes": {semantic: {"name",
"role", "type"}}}}``), which :mod:`.scene_attributes` reads back.

Numbers: float32 as they are; float64 rounded to float32 (glTF has no double); int32 as
signed bytes or shorts where they fit (a generic attribute), else as float32 (exact within
±2^24) recorded as ``int32``.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...model.attributes import (
    COLOR,
    CORNER,
    FACE,
    GENERIC,
    MATERIAL_FAMILY,
    NORMAL,
    UV,
    Attribute,
)
from ...model.sequence import MeshSequence
from .vertex_attributes import role_of

_SEMANTIC = re.compile(r"(TEXCOORD_\d+|NORMAL|COLOR_\d+|TANGENT|_[A-Za-z0-9_]+)\Z")
_NOT_NAME = re.compile(r"[^A-Za-z0-9_]")
#: The integers float32 holds exactly.
FLOAT32_INTEGERS = 2**24


@dataclass
class Semantics:
    """The semantic each attribute is written under, by name, and the record of what the
    semantics do not say (:mod:`.scene_attributes` reads it)."""

    by_name: dict[str, str] = field(default_factory=dict)
    record: dict[str, dict[str, str]] = field(default_factory=dict)


def semantics(attributes: Sequence[Attribute]) -> Semantics:
    """The semantics of ``attributes`` (module docstring), each used once."""
    result = Semantics()
    taken: set[str] = set()
    has_normal = any(a.role == NORMAL for a in attributes)
    for attribute in attributes:  # names that are semantics first: they keep them
        if _keeps_name(attribute, has_normal) and attribute.name not in taken:
            result.by_name[attribute.name] = attribute.name
            taken.add(attribute.name)
    for attribute in attributes:
        if attribute.name in result.by_name:
            continue
        semantic = _free(attribute, taken)
        result.by_name[attribute.name] = semantic
        taken.add(semantic)
    for attribute in attributes:
        semantic = result.by_name[attribute.name]
        entry: dict[str, str] = {}
        if attribute.name != semantic:
            entry["name"] = attribute.name
        if attribute.role != role_of(semantic):
            entry["role"] = attribute.role
        if attribute.values.dtype == np.int32 and not _small_integers(attribute):
            entry["type"] = "int32"
        if entry:
            result.record[semantic] = {"name": attribute.name, **entry}
    return result


def _keeps_name(attribute: Attribute, has_normal: bool) -> bool:
    name = attribute.name
    if not _SEMANTIC.match(name) or role_of(name) != attribute.role:
        return False
    if name == "TANGENT":
        return has_normal and attribute.components == 4 and attribute.values.dtype != np.int32
    return True


def _free(attribute: Attribute, taken: set[str]) -> str:
    """The first free semantic for ``attribute`` by its role."""
    if attribute.role == NORMAL and "NORMAL" not in taken:
        return "NORMAL"
    if attribute.role in (UV, COLOR):
        stem = "TEXCOORD_" if attribute.role == UV else "COLOR_"
        number = 0
        while f"{stem}{number}" in taken:
            number += 1
        return f"{stem}{number}"
    semantic = "_" + _NOT_NAME.sub("_", attribute.name)
    while semantic in taken or semantic == "_":
        semantic += "_"
    return semantic


def _small_integers(attribute: Attribute) -> bool:
    """Whether a generic int32 attribute fits in signed shorts (written as integers)."""
    values = attribute.values
    return (
        attribute.role == GENERIC
        and values.dtype == np.int32
        and bool(values.size == 0 or np.abs(values.astype(np.int64)).max() <= 2**15 - 1)
    )


def stored_values(attribute: Attribute, values: np.ndarray) -> np.ndarray:
    """``values`` (an attribute's, one row per written vertex) in a type glTF stores."""
    if values.dtype == np.int32:
        if _small_integers(attribute):
            small = np.abs(values.astype(np.int64)).max(initial=0) <= 127
            return values.astype(np.int8 if small else np.int16)
        return values.astype(np.float32)
    with np.errstate(over="ignore"):
        return values.astype(np.float32)


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What a glTF written from ``seq`` does not keep, one line each (empty: all of it)."""
    lines = []
    split = [a.name for a in seq.attributes if a.domain in (CORNER, FACE)]
    if split:
        lines.append(
            "corner-domain attributes become split vertices (one glTF vertex per vertex and "
            f"value): {', '.join(split)}; reading the file back gives more vertices"
        )
    indexed = [a.name for a in seq.attributes if a.indices is not None]
    if indexed:
        lines.append(f"indexed attributes are written one value per vertex: {', '.join(indexed)}")
    doubles = [a.name for a in seq.attributes if a.values.dtype == np.float64]
    if doubles:
        lines.append(f"float64 attributes are written as float32: {', '.join(doubles)}")
    wide = [
        a.name
        for a in seq.attributes
        if a.values.dtype == np.int32 and np.abs(a.values.astype(np.int64)).max(initial=0) > 2**24
    ]
    if wide:
        lines.append(f"int32 values beyond ±2^24 are rounded to float32: {', '.join(wide)}")
    others = [f"{s.family or '(no family)'}/{s.name}" for s in seq.face_sets if not _material(s)]
    if others:
        lines.append(f"face sets other than materials are not written: {', '.join(others)}")
    if _overlapping_materials(seq):
        lines.append("a face in several materials is written in the first one only")
    if seq.fields:
        names = ", ".join(f.name for f in seq.fields)
        lines.append(f"fields (animated values) are not written: glTF cannot keep them: {names}")
    return lines


def _material(face_set: Any) -> bool:
    return bool(face_set.family == MATERIAL_FAMILY)


def _overlapping_materials(seq: MeshSequence) -> bool:
    sets = [s.faces for s in seq.face_sets if _material(s)]
    total = sum(len(faces) for faces in sets)
    return bool(sets) and np.unique(np.concatenate(sets)).size < total
