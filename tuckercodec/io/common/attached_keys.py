"""A sequence's attributes, face sets and fields as named arrays and one JSON description, the
layout of the array stores (an ``.npz`` archive's members, a zarr group's arrays):

* ``attribute/<i>/values`` and, for an indexed attribute, ``attribute/<i>/indices`` (int64):
  attribute ``i`` of the sequence, its values in their own type (float32, float64 or int32);
* ``face_set/<i>``: face set ``i``'s face numbers (int64);
* ``field/<i>``: field ``i``'s values (frames, elements, components), in their own type;
* :data:`DESCRIPTION` (``attached``): JSON text,
  ``{"attributes": [{"name", "domain", "role", "indexed"}...], "face_sets": [{"name",
  "family"}...], "fields": [{"name", "domain", "role"}...]}``, in the sequence's order.

Names live in the JSON, never in the keys: a key is only numbers, whatever the names hold. A
store without :data:`DESCRIPTION` has none of them (the stores written before they existed).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.attributes import Attribute, FaceSet, Field
from ...model.sequence import MeshSequence

#: The key of the JSON description.
DESCRIPTION = "attached"
#: The longest description read: 64 MiB of JSON, far beyond any list of names.
MAX_DESCRIPTION_BYTES = 64 * 1024 * 1024


def attribute_key(index: int, part: str) -> str:
    """The key of attribute ``index``'s ``values`` or ``indices``."""
    return f"attribute/{index}/{part}"


def face_set_key(index: int) -> str:
    """The key of face set ``index``'s faces."""
    return f"face_set/{index}"


def field_key(index: int) -> str:
    """The key of field ``index``'s values."""
    return f"field/{index}"


def attached_arrays(seq: MeshSequence) -> tuple[str, dict[str, np.ndarray]]:
    """The JSON description and the arrays by key of ``seq``'s attributes, face sets and
    fields (``("", {})`` when it has none)."""
    if not seq.attached:
        return "", {}
    arrays: dict[str, np.ndarray] = {}
    attributes = []
    for index, attribute in enumerate(seq.attributes):
        arrays[attribute_key(index, "values")] = attribute.values
        if attribute.indices is not None:
            arrays[attribute_key(index, "indices")] = attribute.indices
        attributes.append(
            {
                "name": attribute.name,
                "domain": attribute.domain,
                "role": attribute.role,
                "indexed": attribute.indices is not None,
            }
        )
    face_sets = []
    for index, face_set in enumerate(seq.face_sets):
        arrays[face_set_key(index)] = face_set.faces
        face_sets.append({"name": face_set.name, "family": face_set.family})
    fields = []
    for index, item in enumerate(seq.fields):
        arrays[field_key(index)] = item.values
        fields.append({"name": item.name, "domain": item.domain, "role": item.role})
    text = json.dumps(
        {"attributes": attributes, "face_sets": face_sets, "fields": fields}, ensure_ascii=False
    )
    return text, arrays


@dataclass(frozen=True)
class FieldEntry:
    """A field as the description names it: its key, name, domain and role."""

    key: str
    name: str
    domain: str
    role: str

    def field(self, values: np.ndarray) -> Field:
        """The field of ``values`` read from :attr:`key`."""
        return Field(self.name, values, self.domain, self.role)


@dataclass(frozen=True)
class Attached:
    """What a description and its arrays give: the static attributes and face sets, read
    whole, and the fields' entries (their values read a range of frames at a time)."""

    attributes: list[Attribute]
    face_sets: list[FaceSet]
    fields: list[FieldEntry]


def read_attached(text: str, array: Callable[[str], np.ndarray]) -> Attached:
    """The attributes and face sets of a description (``text``), reading their arrays with
    ``array(key)``, and its fields' entries. InputError (without a path) names the key."""
    if len(text.encode("utf-8", "surrogatepass")) > MAX_DESCRIPTION_BYTES:
        raise InputError(f"key {DESCRIPTION!r} is larger than {MAX_DESCRIPTION_BYTES} bytes")
    try:
        description = json.loads(text)
    except ValueError as error:
        raise InputError(f"key {DESCRIPTION!r} is not JSON ({error})") from None
    if not isinstance(description, dict):
        raise InputError(f"key {DESCRIPTION!r} is not a JSON object")
    attributes = []
    for index, entry in enumerate(_entries(description, "attributes")):
        key = attribute_key(index, "values")
        indexed = entry.get("indexed", False)
        try:
            values = array(key)
            indices = array(attribute_key(index, "indices")) if indexed is True else None
            attributes.append(
                Attribute(
                    entry.get("name"),  # type: ignore[arg-type]  # checked by Attribute
                    entry.get("domain"),  # type: ignore[arg-type]
                    values,
                    indices,
                    entry.get("role", "generic"),
                )
            )
        except InputError as error:
            raise InputError(f"key {key!r}: {error.reason}") from None
    face_sets = []
    for index, entry in enumerate(_entries(description, "face_sets")):
        key = face_set_key(index)
        try:
            faces = array(key)
            if faces.dtype.kind not in "iu":
                raise InputError(f"holds {faces.dtype} values, not face numbers")
            face_sets.append(FaceSet(entry.get("name"), faces, entry.get("family", "")))  # type: ignore[arg-type]
        except InputError as error:
            raise InputError(f"key {key!r}: {error.reason}") from None
    fields = []
    for index, entry in enumerate(_entries(description, "fields")):
        found = FieldEntry(
            field_key(index),
            entry.get("name", ""),
            entry.get("domain", ""),
            entry.get("role", "generic"),
        )
        try:  # its name, domain and role checked now, its values when read
            found.field(np.zeros((0, 0, 1)))
        except InputError as error:
            raise InputError(f"key {found.key!r}: {error.reason}") from None
        fields.append(found)
    return Attached(attributes, face_sets, fields)


def _entries(description: dict[str, Any], name: str) -> list[dict[str, Any]]:
    """The list ``name`` of a description, each entry an object."""
    entries = description.get(name, [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise InputError(f"key {DESCRIPTION!r}: {name!r} is not a list of objects")
    return entries


def everything_attached(seq: MeshSequence) -> list[str]:
    """Every attribute, face set and field of ``seq``, one line each: what a format that
    holds positions only cannot keep."""
    return (
        [f"attribute {a.name!r}" for a in seq.attributes]
        + [f"face set {s.name!r}" + (f" ({s.family})" if s.family else "") for s in seq.face_sets]
        + [f"field {f.name!r}" for f in seq.fields]
    )
