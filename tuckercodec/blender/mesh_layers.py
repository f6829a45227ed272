"""A Blender mesh's layers from a file and back: UV maps, colour attributes, generic
attributes, custom normals, material slots and animated fields (imported and exported by the
add-on). Runs only inside Blender (it imports ``bpy``); the array work is :mod:`.layers`.

Names are the file's: an attribute whose name the mesh already holds (Blender's own
``position``, or a second attribute of a name) is not imported, and a note says so.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import bpy
import numpy as np

from ..model.attributes import (
    COLOR,
    CORNER,
    MATERIAL_FAMILY,
    NORMAL,
    UV,
    VERTEX,
    Attribute,
    FaceSet,
    Field,
)
from .layers import (
    BLENDER_BOOLEANS,
    BLENDER_DOMAINS,
    BLENDER_TYPES,
    DOMAINS_OF_BLENDER,
    KEPT_OTHERWISE,
    NORMALS_NAME,
    as_float32,
    blender_type,
    loop_values,
    material_face_sets,
    material_slots,
    maybe_indexed,
    rgba,
    role_of,
)

# ------------------------------------------------------------------------------------------
# import


def put_layers(
    mesh: Any, attributes: Sequence[Attribute], face_sets: Sequence[FaceSet], faces: np.ndarray
) -> list[str]:
    """Give ``mesh`` (made from ``faces``, in order) the file's attributes and face sets: a
    UV map per ``uv`` attribute, a colour attribute per ``color`` one, the first ``normal``
    attribute as custom split normals, the rest as generic attributes; material slots from
    the sets of family ``materialBind``, other sets as boolean face attributes. The faces are
    smooth unless the file says which are flat (a ``sharp_face`` attribute, as an export
    writes it): a cache's surface is meant smooth, and normals, if the file has them, say
    where it is not. Returns notes on what was not imported, or changed."""
    notes: list[str] = []
    mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), dtype=np.bool_))
    if "sharp_face" in mesh.attributes:
        mesh.attributes.remove(mesh.attributes["sharp_face"])
    normals_set = False
    for attribute in attributes:
        if attribute.role == NORMAL and not normals_set:
            normals = as_float32(loop_values(attribute, faces))
            mesh.normals_split_custom_set(normals)
            normals_set = True
            continue
        if attribute.name in mesh.attributes:
            notes.append(f"attribute {attribute.name!r}: the mesh has one of that name already")
            continue
        if attribute.role == UV:
            notes += _put_uv(mesh, attribute, faces)
        elif attribute.role == COLOR:
            _put_colour(mesh, attribute, faces)
        else:
            notes += _put_generic(mesh, attribute)
    _put_materials(mesh, face_sets)
    for face_set in face_sets:
        if face_set.family != MATERIAL_FAMILY:
            notes += _put_face_group(mesh, face_set)
    return notes


def _put_uv(mesh: Any, attribute: Attribute, faces: np.ndarray) -> list[str]:
    layer = mesh.uv_layers.new(name=attribute.name, do_init=False)
    if layer is None:  # Blender holds at most 8 UV maps
        return [f"UV map {attribute.name!r}: the mesh holds no more UV maps"]
    layer.uv.foreach_set("vector", as_float32(loop_values(attribute, faces)).ravel())
    return []


def _put_colour(mesh: Any, attribute: Attribute, faces: np.ndarray) -> None:
    # a colour attribute is per point or per corner: a face's colour goes on its corners
    on_points = attribute.domain == VERTEX
    values = attribute.element_values() if on_points else loop_values(attribute, faces)
    layer = mesh.color_attributes.new(
        attribute.name, "FLOAT_COLOR", "POINT" if on_points else "CORNER"
    )
    layer.data.foreach_set("color", rgba(values).ravel())


def _put_generic(mesh: Any, attribute: Attribute) -> list[str]:
    values = attribute.element_values()
    data_type = blender_type(attribute.name, values)
    kind = BLENDER_TYPES[data_type]
    layer = mesh.attributes.new(attribute.name, data_type, BLENDER_DOMAINS[attribute.domain])
    buffer = values != 0 if kind.buffer is np.bool_ else values.astype(kind.buffer)
    layer.data.foreach_set(kind.prop, np.ascontiguousarray(buffer).ravel())
    if values.dtype == np.float64 or (values.dtype == np.int32 and kind.buffer is np.float32):
        return [f"attribute {attribute.name!r}: {values.dtype} held as float32 in Blender"]
    return []


def _put_materials(mesh: Any, face_sets: Sequence[FaceSet]) -> None:
    """Material slots, each the material of the set's name (made if the .blend has none)."""
    names, slot_of_face = material_slots(face_sets, len(mesh.polygons))
    if not names:
        return
    for name in names:
        material = None
        if name is not None:
            material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
        mesh.materials.append(material)
    mesh.polygons.foreach_set("material_index", slot_of_face)


def _put_face_group(mesh: Any, face_set: FaceSet) -> list[str]:
    """A face set that is not a material as a boolean face attribute of its name."""
    if face_set.name in mesh.attributes:
        return [f"face set {face_set.name!r}: the mesh has an attribute of that name already"]
    inside = np.zeros(len(mesh.polygons), dtype=np.bool_)
    inside[face_set.faces] = True
    layer = mesh.attributes.new(face_set.name, "BOOLEAN", "FACE")
    layer.data.foreach_set("value", inside)
    return []


def put_fields(mesh: Any, fields: Sequence[Field]) -> list[str]:
    """Set each field's values of one frame (``values[0]``) in a float attribute of its name
    and domain, made the first time; notes on a field whose name the mesh holds otherwise."""
    notes = []
    for item in fields:
        values = as_float32(item.values[0])
        data_type = blender_type(item.name, values)
        domain = BLENDER_DOMAINS[item.domain]
        layer = mesh.attributes.get(item.name)
        if layer is None:
            layer = mesh.attributes.new(item.name, data_type, domain)
        elif (layer.data_type, layer.domain) != (data_type, domain):
            notes.append(f"field {item.name!r}: the mesh has another attribute of that name")
            continue
        layer.data.foreach_set(BLENDER_TYPES[data_type].prop, values.ravel())
    return notes


# ------------------------------------------------------------------------------------------
# export


class Layers(NamedTuple):
    """What an export keeps of a mesh beside its positions and faces, and what it cannot."""

    attributes: list[Attribute]
    face_sets: list[FaceSet]
    dropped: list[str]


def read_layers(mesh: Any, material_names: Sequence[str | None]) -> Layers:
    """``mesh``'s UV maps (indexed where corners share values), colour and generic
    attributes on points, corners and faces, custom normals (Blender's corner normals,
    indexed), and material slots ``material_names`` (``None``: an empty slot) as face sets;
    and the attributes it cannot keep (edge domain, other types), named."""
    uv_names = {layer.name for layer in mesh.uv_layers}
    colour_names = {layer.name for layer in mesh.color_attributes}
    attributes, dropped = [], []
    for layer in mesh.attributes:
        name = layer.name
        if layer.is_internal or layer.is_required or name.startswith(".") or name in KEPT_OTHERWISE:
            continue
        if layer.domain not in DOMAINS_OF_BLENDER:
            dropped.append(f"attribute {name!r} ({layer.domain.lower()} domain)")
            continue
        if layer.data_type not in BLENDER_TYPES:
            dropped.append(f"attribute {name!r} ({layer.data_type} values)")
            continue
        values = read_values(layer)
        if name in BLENDER_BOOLEANS and not values.any():
            continue  # Blender's default (smooth faces): nothing to keep
        role = role_of(layer.data_type, name in uv_names, name in colour_names)
        domain = DOMAINS_OF_BLENDER[layer.domain]
        if role == UV:
            attributes.append(maybe_indexed(name, domain, values, UV))
        else:
            attributes.append(Attribute(name, domain, values, None, role))
    if mesh.has_custom_normals:
        if NORMALS_NAME in {a.name for a in attributes}:
            dropped.append(f"custom normals (an attribute is named {NORMALS_NAME!r})")
        else:
            normals = np.empty(len(mesh.loops) * 3, dtype=np.float32)
            mesh.corner_normals.foreach_get("vector", normals)
            attributes.append(maybe_indexed(NORMALS_NAME, CORNER, normals.reshape(-1, 3), NORMAL))
    slot_of_face = np.zeros(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("material_index", slot_of_face)
    return Layers(attributes, material_face_sets(material_names, slot_of_face), dropped)


def read_values(layer: Any) -> np.ndarray:
    """A Blender attribute's values, (N, c) of the type a file keeps (:data:`BLENDER_TYPES`)."""
    kind = BLENDER_TYPES[layer.data_type]
    buffer: np.ndarray = np.empty(len(layer.data) * kind.components, dtype=kind.buffer)
    layer.data.foreach_get(kind.prop, buffer)
    return buffer.astype(kind.stored, copy=False).reshape(-1, kind.components)
