"""What :mod:`.usd` writes of a sequence beside its points: attributes as primvars, face sets as
GeomSubsets, fields as time-sampled primvars (``velocities`` as the mesh's own attribute), and
:func:`cannot_keep`, what a USD file loses of a sequence.

* An attribute is ``primvars:NAME``: its interpolation from its domain (vertex -> ``vertex``,
  corner -> ``faceVarying``, face -> ``uniform``), its indices as ``primvars:NAME:indices``,
  its value type from its role and dtype (a float32 uv ``texCoord2f[]``, a colour
  ``color3f[]``/``color4f[]``, a normal ``normal3f[]``, float64 the ``d`` types, else
  ``float``/``double``/``int`` and their vectors), its values bit for bit, as the default
  (unanimated) value. The mesh's normals are ``primvars:normals``, which UsdGeom prefers to the
  ``normals`` attribute and which, unlike it, may be indexed (the hard edges).
* On an animated mesh (two or more frames) a normal attribute is time-sampled: frame 0's sample
  is its stored values, bit for bit (what a reader takes), each later frame's is recomputed from
  that frame's positions with the same indices
  (:func:`~tuckercodec.model.normals.recomputed_normals`): the normals turn with the surface.
  A single frame's are written as they are.
* A field is ``primvars:NAME`` sampled at every frame's time code (interpolation ``vertex`` or
  ``uniform``), except a float32 3-component vertex field of role velocity named
  ``velocities``, which is the mesh's ``velocities`` attribute (``vector3f[]``), sampled so.
* A face set is a GeomSubset of faces under the mesh, named as the set, of its family
  (``familyName``; none for a set without one); each family's type is ``partition`` when its
  sets cover every face once, ``nonOverlapping`` when they share no face, else
  ``unrestricted``.
* A name that is not a USD identifier (letters, digits, underscores, namespaces joined by
  ``:``) is made one (other characters become ``_``), and one taken already gets ``_2``,
  ``_3``...: :func:`cannot_keep` lists these, and what reads back otherwise (a role the USD
  type cannot say).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..model.attributes import (
    COLOR,
    CORNER,
    FACE,
    GENERIC,
    NORMAL,
    UV,
    VELOCITY,
    VERTEX,
    Attribute,
    Field,
)
from ..model.normals import recomputed_normals
from ..model.sequence import MeshSequence
from .usd_primvars import VELOCITIES, attribute_role

#: A domain -> the interpolation of its primvar.
DOMAIN_INTERPOLATIONS = {VERTEX: "vertex", CORNER: "faceVarying", FACE: "uniform"}
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_SCALAR_NAMES = {"f": "float", "d": "double", "i": "int"}
_LETTERS = {np.dtype(np.float32): "f", np.dtype(np.float64): "d", np.dtype(np.int32): "i"}


@dataclass
class Naming:
    """The USD names a sequence's attributes, fields and face sets are written under, and
    what a file loses of them (:func:`cannot_keep`)."""

    attributes: list[str] = field(default_factory=list)
    fields: list[str] = field(default_factory=list)
    face_sets: list[str] = field(default_factory=list)
    losses: list[str] = field(default_factory=list)


def naming(seq: MeshSequence) -> Naming:
    """The names to write under (see the module docstring), and the losses."""
    named = Naming()
    taken: set[str] = set()
    for attribute in seq.attributes:
        name = _free(_property_name(attribute.name), taken)
        named.attributes.append(name)
        if name != attribute.name:
            named.losses.append(f"attribute {attribute.name!r} is written as primvars:{name}")
        back = _read_role(name, attribute.role, attribute.values.dtype, attribute.components)
        if back != attribute.role:
            named.losses.append(
                f"attribute {attribute.name!r} ({attribute.role}, {attribute.values.dtype}) reads "
                f"back as a {back}: USD's value types and names say so"
            )
    for item in seq.fields:
        if _is_velocities(item):
            named.fields.append(VELOCITIES)
            continue
        name = _free(_property_name(item.name), taken)
        named.fields.append(name)
        if name != item.name:
            named.losses.append(f"field {item.name!r} is written as primvars:{name}")
        type_role = _field_type_role(item)
        back = attribute_role(name, type_role, item.components, item.values.dtype)
        if back == NORMAL:
            named.losses.append(
                f"field {item.name!r} reads back as the mesh's normals (frame 0's), not a field"
            )
        elif (COLOR if back == COLOR else GENERIC) != item.role:
            back = COLOR if back == COLOR else GENERIC
            why = (
                f"only a float32 3-component vertex field named {VELOCITIES!r} is USD's velocities"
                if item.role == VELOCITY
                else "USD's value types and names say so"
            )
            named.losses.append(
                f"field {item.name!r} ({item.role}, {item.components} components) reads back "
                f"as a {back} field: {why}"
            )
    prims: set[str] = set()
    for face_set in seq.face_sets:
        name = _free(_identifier(face_set.name), prims)
        named.face_sets.append(name)
        if name != face_set.name:
            named.losses.append(f"face set {face_set.name!r} is written as GeomSubset {name}")
    return named


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What a USD file written from ``seq`` does not keep as it is (names USD refuses, roles
    its types cannot say): one sentence each, empty when it keeps everything."""
    return naming(seq).losses


def _identifier(name: str) -> str:
    text = re.sub(r"[^A-Za-z0-9_]", "_", name)
    return "_" + text if text[:1].isdigit() or not text else text


def _property_name(name: str) -> str:
    """A primvar name: identifiers joined by ``:``, the last not ``indices`` (USD's suffix)."""
    if all(_IDENTIFIER.fullmatch(part) for part in name.split(":")):
        parts = name.split(":")
    else:
        parts = [_identifier(name)]
    if parts[-1] == "indices":
        parts[-1] = "indices_"
    return ":".join(parts)


def _free(name: str, taken: set[str]) -> str:
    found, number = name, 2
    while found in taken:
        found, number = f"{name}_{number}", number + 1
    taken.add(found)
    return found


def _read_role(name: str, role: str, dtype: np.dtype, components: int) -> str:
    """The role the reader gives back to what :func:`value_type_name` writes."""
    return attribute_role(name, _type_role(role, dtype), components, dtype)


def _type_role(role: str, dtype: np.dtype) -> str:
    """The Sdf role of the value type written for ``role`` (none for integers)."""
    if dtype.kind != "f":
        return ""
    return {UV: "TextureCoordinate", COLOR: "Color", NORMAL: "Normal"}.get(role, "")


def _field_type_role(item: Field) -> str:
    return _type_role(COLOR if item.role == COLOR else GENERIC, item.values.dtype)


def value_type_name(role: str, dtype: np.dtype, components: int) -> str:
    """The Sdf array type (``texCoord2f[]``...) an attribute of ``role`` is written as."""
    letter = _LETTERS[np.dtype(dtype)]
    if letter != "i":
        if role == UV and components == 2:
            return f"texCoord2{letter}[]"
        if role == COLOR and components in (3, 4):
            return f"color{components}{letter}[]"
        if role == NORMAL and components == 3:
            return f"normal3{letter}[]"
        if role == VELOCITY and components == 3:
            return f"vector3{letter}[]"
    scalar = _SCALAR_NAMES[letter]
    return f"{scalar}[]" if components == 1 else f"{scalar}{components}[]"


def _is_velocities(item: Field) -> bool:
    return (
        item.name == VELOCITIES
        and item.role == VELOCITY
        and item.domain == VERTEX
        and item.components == 3
        and item.values.dtype == np.float32
    )


def write_attached(
    pxr: SimpleNamespace, mesh: Any, seq: MeshSequence, vertices: np.ndarray, codes: list[float]
) -> None:
    """Author ``seq``'s attributes, fields and face sets on ``mesh`` (a UsdGeom.Mesh whose
    points are ``vertices``, sampled at ``codes``)."""
    named = naming(seq)
    primvars = pxr.UsdGeom.PrimvarsAPI(mesh)
    for attribute, name in zip(seq.attributes, named.attributes, strict=True):
        _write_attribute(pxr, primvars, attribute, name, seq, vertices, codes)
    for item, name in zip(seq.fields, named.fields, strict=True):
        type_name = value_type_name(_field_role(item), item.values.dtype, item.components)
        if name == VELOCITIES and _is_velocities(item):
            target = mesh.CreateVelocitiesAttr()
        else:
            interpolation = DOMAIN_INTERPOLATIONS[item.domain]
            target = primvars.CreatePrimvar(name, _sdf_type(pxr, type_name), interpolation)
        for frame, code in enumerate(codes):
            target.Set(_vt_array(pxr, item.values[frame]), pxr.Usd.TimeCode(code))
    _write_face_sets(pxr, mesh, seq, named.face_sets)


def _field_role(item: Field) -> str:
    return item.role if item.role in (COLOR, VELOCITY) else GENERIC


def _write_attribute(
    pxr: SimpleNamespace,
    primvars: Any,
    attribute: Attribute,
    name: str,
    seq: MeshSequence,
    vertices: np.ndarray,
    codes: list[float],
) -> None:
    """One attribute as a primvar; a normal of an animated mesh sampled at every frame."""
    type_name = value_type_name(attribute.role, attribute.values.dtype, attribute.components)
    interpolation = DOMAIN_INTERPOLATIONS[attribute.domain]
    primvar = primvars.CreatePrimvar(name, _sdf_type(pxr, type_name), interpolation)
    if attribute.indices is not None:
        primvar.SetIndices(pxr.Vt.IntArray.FromNumpy(attribute.indices.astype(np.int32)))
    if attribute.role != NORMAL or seq.frame_count == 1:
        primvar.Set(_vt_array(pxr, attribute.values))
        return
    for frame, code in enumerate(codes):
        values = attribute.values
        if frame:  # frame 0's are the stored normals, bit for bit; all samples of one type
            fresh = recomputed_normals(vertices[frame], seq.faces, attribute)
            values = fresh.astype(attribute.values.dtype, copy=False)
        primvar.Set(_vt_array(pxr, values), pxr.Usd.TimeCode(code))


def _sdf_type(pxr: SimpleNamespace, type_name: str) -> Any:
    return pxr.Sdf.ValueTypeNames.Find(type_name)


def _vt_array(pxr: SimpleNamespace, values: np.ndarray) -> Any:
    """``values`` ((N, c) float32, float64 or int32) as the Vt array of their type."""
    letter = _LETTERS[values.dtype]
    if values.shape[1] == 1:
        scalar = {"f": pxr.Vt.FloatArray, "d": pxr.Vt.DoubleArray, "i": pxr.Vt.IntArray}
        return scalar[letter].FromNumpy(np.ascontiguousarray(values[:, 0]))
    return getattr(pxr.Vt, f"Vec{values.shape[1]}{letter}Array").FromNumpy(values)


def _write_face_sets(pxr: SimpleNamespace, mesh: Any, seq: MeshSequence, names: list[str]) -> None:
    """The face sets as GeomSubsets of faces, each family typed by how its sets overlap."""
    UsdGeom, Vt = pxr.UsdGeom, pxr.Vt
    families: dict[str, list[np.ndarray]] = {}
    for face_set, name in zip(seq.face_sets, names, strict=True):
        subset = UsdGeom.Subset.Define(mesh.GetPrim().GetStage(), mesh.GetPath().AppendChild(name))
        subset.CreateElementTypeAttr(UsdGeom.Tokens.face)
        subset.CreateIndicesAttr(Vt.IntArray.FromNumpy(face_set.faces.astype(np.int32)))
        if face_set.family:
            subset.CreateFamilyNameAttr(face_set.family)
            families.setdefault(face_set.family, []).append(face_set.faces)
    face_count = seq.faces.shape[0]
    for family, sets in families.items():
        joined = np.concatenate(sets)
        kind = UsdGeom.Tokens.unrestricted
        if np.unique(joined).size == joined.size:
            complete = joined.size == face_count
            kind = UsdGeom.Tokens.partition if complete else UsdGeom.Tokens.nonOverlapping
        UsdGeom.Subset.SetFamilyType(mesh, family, kind)
