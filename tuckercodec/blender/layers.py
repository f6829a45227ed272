"""The add-on's translation between a sequence's attributes, face sets and fields and Blender's
mesh layers (UV maps, colour attributes, generic attributes, custom normals, material slots),
as arrays, without ``bpy``: what :mod:`.mesh_layers` puts into a Blender mesh and reads back.

Blender's loops are our corners: each polygon's loops in polygon order, its corners in face
order (:func:`~tuckercodec.model.attributes.corner_vertices`), so a corner-domain attribute is
one value per loop as it stands, and a vertex- or face-domain one is expanded to the loops.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..model.attributes import (
    COLOR,
    CORNER,
    FACE,
    GENERIC,
    MATERIAL_FAMILY,
    UV,
    VELOCITY,
    VERTEX,
    Attribute,
    FaceSet,
    Field,
    corner_faces,
    corner_vertices,
)

#: Our domains as Blender names them, and back.
BLENDER_DOMAINS = {VERTEX: "POINT", CORNER: "CORNER", FACE: "FACE"}
DOMAINS_OF_BLENDER = {value: key for key, value in BLENDER_DOMAINS.items()}

#: Blender's own attributes that are booleans: a file's int32 attribute of one of these names
#: (as an export writes them) becomes the boolean again, so that flat shading comes back.
BLENDER_BOOLEANS = frozenset({"sharp_face"})

#: Attributes an export leaves out because they are kept another way: the positions, the
#: material slots (face sets), the custom normals (a ``normal`` attribute from the corner
#: normals Blender computes) and Blender's required topology.
KEPT_OTHERWISE = frozenset({"position", "material_index", "custom_normal"})

#: The name an export gives the custom normals (USD's).
NORMALS_NAME = "normals"

#: An indexed attribute is written when its distinct values are at most this share of its
#: elements (UVs shared by a vertex's corners): fewer values, indices that follow the vertices.
INDEXED_SHARE = 0.75


class BlenderType(NamedTuple):
    """How Blender holds an attribute type: the property ``foreach_get`` and ``foreach_set``
    read, the components, the buffer's dtype, and the dtype a file keeps."""

    prop: str
    components: int
    buffer: type
    stored: type


#: The Blender attribute types an export keeps, and how (a byte colour as the linear float
#: colour Blender renders with; booleans and 8-bit integers as int32).
BLENDER_TYPES = {
    "FLOAT": BlenderType("value", 1, np.float32, np.float32),
    "FLOAT2": BlenderType("vector", 2, np.float32, np.float32),
    "FLOAT_VECTOR": BlenderType("vector", 3, np.float32, np.float32),
    "FLOAT_COLOR": BlenderType("color", 4, np.float32, np.float32),
    "BYTE_COLOR": BlenderType("color", 4, np.float32, np.float32),
    "QUATERNION": BlenderType("value", 4, np.float32, np.float32),
    "INT": BlenderType("value", 1, np.int32, np.int32),
    "INT32_2D": BlenderType("value", 2, np.int32, np.int32),
    "INT8": BlenderType("value", 1, np.int8, np.int32),
    "BOOLEAN": BlenderType("value", 1, np.bool_, np.int32),
}
_FLOAT_TYPES = {1: "FLOAT", 2: "FLOAT2", 3: "FLOAT_VECTOR", 4: "FLOAT_COLOR"}


def blender_type(attribute_name: str, values: np.ndarray) -> str:
    """The Blender type an attribute of ``values`` ((N, c)) is imported as: int32 of 1 or 2
    components stays integer (a :data:`BLENDER_BOOLEANS` name a boolean), the rest float32."""
    components = int(values.shape[1])
    if values.dtype == np.int32 and components <= 2:
        if components == 1:
            return "BOOLEAN" if attribute_name in BLENDER_BOOLEANS else "INT"
        return "INT32_2D"
    return _FLOAT_TYPES[components]


def loop_values(attribute: Attribute, faces: np.ndarray) -> np.ndarray:
    """One row per corner (Blender's loops, in order) of ``attribute`` on ``faces``: a vertex's
    or a face's value repeated on each of its corners."""
    values = attribute.element_values()
    if attribute.domain == VERTEX:
        return values[corner_vertices(faces)]
    if attribute.domain == FACE:
        return values[corner_faces(faces)]
    return values


def as_float32(values: np.ndarray) -> np.ndarray:
    """``values`` as float32 (Blender holds no float64 attribute)."""
    return np.ascontiguousarray(values, dtype=np.float32)


def rgba(values: np.ndarray) -> np.ndarray:
    """Colours as (N, 4) float32: an RGB colour gets an alpha of 1."""
    colours = as_float32(values)
    if colours.shape[1] == 4:
        return colours
    return np.concatenate([colours, np.ones((len(colours), 1), dtype=np.float32)], axis=1)


def maybe_indexed(name: str, domain: str, values: np.ndarray, role: str = GENERIC) -> Attribute:
    """An attribute of ``values`` (one row per element), indexed when its distinct rows are at
    most :data:`INDEXED_SHARE` of them. Rows are compared bit for bit (``-0.0`` is not ``0.0``)
    and the table keeps them in order of first use, so the values decoded are the same bits."""
    values = np.ascontiguousarray(values)
    if len(values) == 0:
        return Attribute(name, domain, values, None, role)
    rows = values.view(np.dtype((np.void, values.dtype.itemsize * values.shape[1]))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    if len(first) > INDEXED_SHARE * len(values):
        return Attribute(name, domain, values, None, role)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return Attribute(name, domain, values[first[order]], rank[inverse.ravel()], role)


def material_slots(
    face_sets: Sequence[FaceSet], face_count: int
) -> tuple[list[str | None], np.ndarray]:
    """The material slots (names, ``None`` for an empty slot) and each face's slot for the
    sets of family ``materialBind``, in the file's order; faces in no set get an empty first
    slot. No such set: no slots, every face at 0."""
    materials = [item for item in face_sets if item.family == MATERIAL_FAMILY]
    slot_of_face = np.full(face_count, -1, dtype=np.int32)
    for slot, item in enumerate(materials):
        slot_of_face[item.faces] = slot
    names: list[str | None] = [item.name for item in materials]
    if materials and bool((slot_of_face < 0).any()):
        names.insert(0, None)
        slot_of_face += 1
    return names, np.maximum(slot_of_face, 0)


def material_face_sets(slot_names: Sequence[str | None], slot_of_face: np.ndarray) -> list[FaceSet]:
    """The face sets (family ``materialBind``, one per material, named after it) of material
    slots ``slot_names`` and each face's slot (Blender's ``material_index``, beyond the last
    slot read as the last, as Blender renders it). Slots of one material make one set; an
    empty slot makes none; a material on no face is a set without faces."""
    if not slot_names:
        return []
    slots = np.clip(np.asarray(slot_of_face, dtype=np.int64), 0, len(slot_names) - 1)
    parts: dict[str, list[np.ndarray]] = {}
    for slot, name in enumerate(slot_names):
        if name is not None:
            parts.setdefault(name, []).append(np.flatnonzero(slots == slot))
    return [
        FaceSet(name, np.sort(np.concatenate(found)), MATERIAL_FAMILY)
        for name, found in parts.items()
    ]


def role_of(data_type: str, is_uv: bool, is_colour: bool) -> str:
    """The role an exported Blender attribute takes: its UV maps ``uv``, its colour attributes
    and colour-typed attributes ``color``, the rest ``generic``."""
    if is_uv:
        return UV
    if is_colour or data_type in ("FLOAT_COLOR", "BYTE_COLOR"):
        return COLOR
    return GENERIC


#: The velocity names Blender (Cycles' motion blur reads ``velocity``) and USD use: such a
#: 3-component animated attribute is a field of role ``velocity``.
VELOCITY_NAMES = frozenset({"velocity", "velocities"})


def may_animate(attribute: Attribute) -> bool:
    """Whether an exported attribute may become an animated field: real values per vertex or
    per face (a field has no corner domain)."""
    return attribute.domain in (VERTEX, FACE) and attribute.values.dtype == np.float32


def split_animated(
    attributes: Sequence[Attribute], frames: dict[str, list[np.ndarray]]
) -> tuple[list[Attribute], list[Field]]:
    """The attributes that stay static and the fields of those that change: ``frames`` holds,
    by name, an attribute's values at every exported frame (frame 0 first). An attribute whose
    values are the same bits at every frame stays a static attribute (frame 0's values);
    one that changes is a field of every frame's values (role ``color`` for a colour,
    ``velocity`` for a velocity)."""
    static, fields = [], []
    for attribute in attributes:
        values = frames.get(attribute.name)
        first = attribute.values.tobytes()
        if values is None or all(frame.tobytes() == first for frame in values):
            static.append(attribute)
            continue
        role = GENERIC
        if attribute.role == COLOR:
            role = COLOR
        elif attribute.name in VELOCITY_NAMES and attribute.components == 3:
            role = VELOCITY
        fields.append(Field(attribute.name, np.stack(values), attribute.domain, role))
    return static, fields
