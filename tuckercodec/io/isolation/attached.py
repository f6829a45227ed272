"""Attributes, face sets and fields across the pipe of a child process: each becomes a JSON
entry (its name, domain, role...) in a result header and raw arrays beside it (the protocol of
:mod:`.child`), and back. The same packing carries a writer's attributes to a writing child
(:mod:`.writing`). What comes back is built again through the model's own classes, so it is
checked as any reader's output is.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ...model.attributes import Attribute, FaceSet, Field


def pack_attached(
    attributes: Sequence[Attribute], face_sets: Sequence[FaceSet]
) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header entries and arrays that carry ``attributes`` and ``face_sets``."""
    arrays: dict[str, np.ndarray] = {}
    listed_attributes = []
    for number, attribute in enumerate(attributes):
        arrays[f"attribute.{number}.values"] = attribute.values
        if attribute.indices is not None:
            arrays[f"attribute.{number}.indices"] = attribute.indices
        listed_attributes.append(
            {"name": attribute.name, "domain": attribute.domain, "role": attribute.role}
        )
    listed_sets = []
    for number, face_set in enumerate(face_sets):
        arrays[f"face_set.{number}"] = face_set.faces
        listed_sets.append({"name": face_set.name, "family": face_set.family})
    return {"attributes": listed_attributes, "face_sets": listed_sets}, arrays


def unpack_attached(
    header: dict[str, Any], arrays: dict[str, np.ndarray]
) -> tuple[list[Attribute], list[FaceSet]]:
    """The attributes and face sets :func:`pack_attached` packed."""
    attributes = [
        Attribute(
            entry["name"],
            entry["domain"],
            arrays[f"attribute.{number}.values"],
            arrays.get(f"attribute.{number}.indices"),
            entry["role"],
        )
        for number, entry in enumerate(header.get("attributes", []))
    ]
    face_sets = [
        FaceSet(entry["name"], arrays[f"face_set.{number}"], entry["family"])
        for number, entry in enumerate(header.get("face_sets", []))
    ]
    return attributes, face_sets


def pack_fields(fields: Sequence[Field]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The header entry and arrays that carry ``fields`` (a range of frames of each)."""
    listed = [{"name": item.name, "domain": item.domain, "role": item.role} for item in fields]
    arrays = {f"field.{number}": item.values for number, item in enumerate(fields)}
    return {"fields": listed}, arrays


def unpack_fields(header: dict[str, Any], arrays: dict[str, np.ndarray]) -> list[Field]:
    """The fields :func:`pack_fields` packed."""
    return [
        Field(entry["name"], arrays[f"field.{number}"], entry["domain"], entry["role"])
        for number, entry in enumerate(header.get("fields", []))
    ]
