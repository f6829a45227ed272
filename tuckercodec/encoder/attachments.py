"""The sections of format 1.5 an encode adds (:mod:`tuckercodec.format.attachments`): whether
the faces keep their given order, and the static attributes and face sets, coded once for the
whole file. Animated fields are coded by :mod:`.fields`, with their targets.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..format import attributes, face_order, face_sets, faces
from ..model.attributes import CORNER, FACE, Attribute, FaceSet, Field
from .versions import NEWEST, Features

Coded = tuple[dict[str, Any], bytes]


def keeps_face_order(
    choice: str, attributes_: Sequence[Attribute], sets: Sequence[FaceSet], fields: Sequence[Field]
) -> bool:
    """Whether the file keeps the faces in their given order: always for ``"given"``, never for
    ``"walk"``, and for ``"auto"`` when data per corner or per face would otherwise be reordered
    (a user who re-attaches data to the original topology needs the order)."""
    if choice != "auto":
        return choice == "given"
    per_face = any(a.domain in (CORNER, FACE) for a in attributes_)
    return per_face or bool(sets) or any(f.domain == FACE for f in fields)


def keeps_corners(attributes_: Sequence[Attribute]) -> bool:
    """Whether each face's first corner must stay as given: when data per corner follows it."""
    return any(a.domain == CORNER for a in attributes_)


def smallest_corner_first(given_faces: np.ndarray) -> np.ndarray:
    """Each face rotated (its winding kept) so that its smallest vertex is its first corner, the
    padding (-1) left at the end. Where the decoder returns the faces in the walk's order and
    no data follows their corners, the first corner carries nothing, and a canonical one costs
    faces-traverse no rotation (§6.8, corner order 1): about 3 bits per vertex less."""
    table = np.asarray(given_faces, dtype=np.int64)
    if table.size == 0:
        return table
    width = table.shape[1]
    real = (table >= 0).sum(axis=1)
    first = np.where(table >= 0, table, np.iinfo(np.int64).max).argmin(axis=1)
    column = np.arange(width)[None, :]
    source = (first[:, None] + column) % np.maximum(real, 1)[:, None]
    rotated = np.take_along_axis(table, source, axis=1)
    return np.where(column < real[:, None], rotated, table)


def walk_ordered(
    given_faces: np.ndarray,
    order: np.ndarray,
    attributes_: Sequence[Attribute],
    sets: Sequence[FaceSet],
) -> tuple[list[Attribute], list[FaceSet]]:
    """The attributes and face sets moved onto the faces in the walk's order (face t of the walk
    is given face ``order[t]``), for a file that does not keep the given order."""
    moved = [a.reordered_faces(given_faces, order) for a in attributes_]
    new_number = np.empty_like(order)
    new_number[order] = np.arange(order.size)
    return moved, [FaceSet(s.name, np.sort(new_number[s.faces]), s.family) for s in sets]


def static_sections(
    attributes_: Sequence[Attribute],
    sets: Sequence[FaceSet],
    mesh: attributes.Mesh,
    order: Coded | None,
    level: int,
) -> list[Coded]:
    """The entries and payloads of ORDER, ATTR.0, ATTR.1... and FSET (those that apply), the
    attributes and sets numbered as ``mesh`` (the faces as the decoder returns them)."""
    out: list[Coded] = []
    if order is not None:
        out.append((_entry(face_order.SECTION_ID, face_order.CODEC, order[0]), order[1]))
    for number, attribute in enumerate(attributes_):
        params, payload = attributes.encode_attribute(attribute, mesh, level)
        out.append((_entry(attributes.section_id(number), attributes.CODEC, params), payload))
    if sets:
        params, payload = face_sets.encode_face_sets(sets, level)
        out.append((_entry(face_sets.SECTION_ID, face_sets.CODEC, params), payload))
    return out


def _entry(section_id: str, codec: str, params: dict[str, Any]) -> dict[str, Any]:
    return {"id": section_id, "critical": False, "codec": codec, **params}


def coded_faces(
    given_faces: np.ndarray,
    vertex_count: int,
    attributes_: Sequence[Attribute],
    sets: Sequence[FaceSet],
    fields: Sequence[Field],
    level: int,
    choice: str = "auto",
    features: Features = NEWEST,
) -> tuple[faces.FaceSection, list[Coded]]:
    """The FACE section, and the sections of 1.5 coded once (ORDER, ATTR.n, FSET) with the
    attributes and sets numbered as the decoder will return the faces: in the given order when
    :func:`keeps_face_order` says so, else in the order FACE decodes them, each then starting
    at its smallest vertex unless data per corner follows its corners. Only the codecs
    ``features`` allow: below 1.2 faces-delta, the faces as given; faces kept in their order
    below 1.5 too, which needs no ORDER then (the caller has refused attachments there)."""
    keep_order = keeps_face_order(choice, attributes_, sets, fields)
    traverse = features.coding_tools and (features.attachments or not keep_order)
    if traverse and not keep_order and not keeps_corners(attributes_):
        given_faces = smallest_corner_first(given_faces)
    face, order, walk = faces.encode_face_sections(
        given_faces,
        vertex_count,
        level,
        keep_order=keep_order,
        adaptive_coding=features.adaptive,
        uniform_ranks=features.uniform_ranks,
        traverse=traverse,
    )
    decoded = face.faces
    if order is not None or not (attributes_ or sets):
        decoded = given_faces if order is not None else decoded
    elif walk is not None:
        attributes_, sets = walk_ordered(given_faces, walk, attributes_, sets)
    mesh = attributes.Mesh(vertex_count, decoded)
    return face, static_sections(attributes_, sets, mesh, order, level)
