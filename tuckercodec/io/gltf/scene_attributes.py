"""What a glTF scene's chosen meshes carry beside positions, as the sequence's static attributes
and face sets.

* Vertex attributes (:mod:`.vertex_attributes`): one vertex-domain Attribute per semantic,
  named as the file names it (``TEXCOORD_0``, ``NORMAL``, ``COLOR_0``, ``_PRESSURE``...), or as
  the tuckercodec writer recorded the sequence's own names and value types (the mesh's
  ``extras``). Over several mesh nodes they are combined as over several primitives.
* NORMAL: frame 0's normals as the reader evaluates frame 0: the accessor's values bit for bit
  where frame 0 is the mesh as stored (no morph target's NORMAL deltas weighted in, no rotation
  or scale on the node); else the base normals plus the weighted NORMAL deltas, moved by the
  inverse transpose of the node's transform at frame 0 and made unit length, as float32. Later
  frames' normals are not kept (a writer recomputes them from the positions). Other attributes
  (TANGENT...) are kept as stored, not transformed.
* Materials: one FaceSet of family ``materialBind`` per material that primitives use, named
  after the material (``material_<index>`` when it has no name, or a name another material
  already has, or one that is not a valid name), holding the faces of its primitives.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError
from ...model.attributes import (
    MATERIAL_FAMILY,
    ROLE_COMPONENTS,
    VERTEX,
    Attribute,
    FaceSet,
    checked_name,
)
from .container import Document
from .primitives import Mesh
from .vertex_attributes import VertexValues, combined

#: The key of the tuckercodec writer's record in a mesh's ``extras``.
RECORD_KEY = "tuckercodec"


@dataclass
class PlacedMesh:
    """A chosen mesh node at frame 0: its mesh, morph weights (J,) and world transform (4, 4)."""

    mesh: Mesh
    extras: Any
    weights: np.ndarray
    world: np.ndarray


def scene_attributes(doc: Document, placed: list[PlacedMesh]) -> list[Attribute]:
    """The chosen meshes' vertex attributes, their vertices one after the other."""
    blocks = [_named(doc, item, _frame0(doc, item)) for item in placed]
    result = []
    for name, found in combined(blocks, [len(item.mesh.base) for item in placed]).items():
        try:
            result.append(Attribute(name, VERTEX, found.values, role=found.role))
        except InputError as error:
            raise doc.fail(f"vertex attribute {name}: {error.reason}") from None
    return result


def _frame0(doc: Document, item: PlacedMesh) -> dict[str, VertexValues]:
    """The mesh's attributes with NORMAL as frame 0 shows it (module docstring)."""
    attributes = dict(item.mesh.attributes)
    normal = attributes.get("NORMAL")
    if normal is None:
        return attributes
    values = normal.values.astype(np.float64)
    changed = False
    for j in np.flatnonzero(item.weights):  # the targets frame 0 shows, read only those
        delta = item.mesh.normal_delta(doc, int(j))
        if delta.any():
            values = values + item.weights[j] * delta
            changed = True
    linear = item.world[:3, :3]
    if not np.array_equal(linear, np.eye(3)):
        # normals move by the inverse transpose: as row vectors, n @ inverse(linear)
        with np.errstate(all="ignore"):
            values = values @ np.linalg.pinv(linear)
        changed = True
    if changed:
        with np.errstate(all="ignore"):
            length = np.linalg.norm(values, axis=1, keepdims=True)
            values = np.where(length > 0, values / np.where(length > 0, length, 1), 0.0)
        attributes["NORMAL"] = VertexValues(normal.role, values.astype(np.float32))
    return attributes


def _named(
    doc: Document, item: PlacedMesh, attributes: dict[str, VertexValues]
) -> dict[str, VertexValues]:
    """The attributes under the names (and value types) the tuckercodec writer recorded, where
    its record is there and sound; else under their semantics."""
    record = item.extras.get(RECORD_KEY) if isinstance(item.extras, dict) else None
    table = record.get("attributes") if isinstance(record, dict) else None
    if not isinstance(table, dict):
        return attributes
    renamed: dict[str, VertexValues] = {}
    for semantic, found in attributes.items():
        entry = table.get(semantic)
        recorded = entry.get("name") if isinstance(entry, dict) else None
        name = recorded if isinstance(recorded, str) and _usable(recorded) else semantic
        if name in renamed or (name in attributes and name != semantic):
            name = semantic
        renamed[name] = _recorded(entry, found) if isinstance(entry, dict) else found
    if len(renamed) != len(attributes):
        return attributes
    return renamed


def material_face_sets(doc: Document, materials: np.ndarray) -> list[FaceSet]:
    """One ``materialBind`` face set per material that faces use, by ``materials`` (each
    face's material index, -1 for none), in the order of the materials' first faces."""
    used = [m for m in dict.fromkeys(materials.tolist()) if m >= 0]
    names: set[str] = set()
    result = []
    for index in used:
        name = doc.item("materials", index, "a primitive").get("name")
        try:
            name = checked_name(name, "a material")
        except InputError:
            name = None
        if name is None or name in names:
            name = f"material_{index}"
            while name in names:  # a material named so already
                name += "_"
        names.add(name)
        result.append(FaceSet(name, np.flatnonzero(materials == index), MATERIAL_FAMILY))
    return result


def _recorded(entry: dict[str, Any], found: VertexValues) -> VertexValues:
    """``found`` with the role and value type the writer recorded, where they fit it."""
    role, values = found.role, found.values
    if entry.get("role") in ROLE_COMPONENTS and values.shape[1] in ROLE_COMPONENTS[entry["role"]]:
        role = entry["role"]
    if entry.get("type") == "int32" and values.dtype.kind == "f":
        whole = np.isfinite(values).all() and np.array_equal(values, np.round(values))
        if whole and np.abs(values).max(initial=0) <= 2**31 - 1:
            values = values.astype(np.int32)
    return VertexValues(role, values)


def _usable(name: object) -> bool:
    """Whether a recorded name is a valid attribute name."""
    try:
        checked_name(name, "an attribute")
    except InputError:
        return False
    return True
