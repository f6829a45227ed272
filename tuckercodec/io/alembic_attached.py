"""What an Alembic PolyMesh carries beside its positions, read in the reading child for
:class:`.alembic.ArchiveFrames`: UVs, normals, arbitrary geom params, face sets and velocities
as :class:`~tuckercodec.model.attributes.Attribute`, :class:`FaceSet` and :class:`Field`.

* Scopes: facevarying is the ``corner`` domain, vertex and varying the ``vertex`` domain,
  uniform the ``face`` domain. Constant-scope params (one value for the whole mesh) are not
  read (a sequence has no per-mesh values); nor are params of another type than float32,
  float64 or int32 of 1 to 3 components, or float32 of 4 (half, unsigned, 16-bit, string,
  boolean, 4 float64, matrices...), nor SubD-only data.
* Corners: Alembic's faces wind clockwise and the reader reverses each face
  (:func:`~.common.polygons.reverse_winding`); per-corner values and indices follow the same
  permutation (:func:`~.common.polygons.reversed_corners`), so every corner keeps its value.
  Indexed params keep their value table and indices (indices per corner, 0-based).
* ``uv`` (the schema's UVs): role ``uv``, named by its ``sourceName`` (Maya's UV set name, which
  :meth:`OPolyMeshSchema.setUVSourceName` writes), else ``uv``; ``N``: role ``normal``, named
  ``N``; both static, from frame 0 (animated normals: frame 0's; the writer recomputes them
  per frame). ``.velocities``: a field of role ``velocity`` named ``velocities``. tuckercodec's
  own names for these, where the writer kept them (user property :data:`NAMES_KEY`), win.
* ``.arbGeomParams``: each param under its own name; a param whose samples are all the same
  (Alembic's ``isConstant``) is a static attribute from frame 0, others are fields read at each
  frame's time (vertex or face scope; an animated per-corner param has no field to be, and is
  read as a static attribute from frame 0). Role: the ``tuckercodec_role`` the writer put in
  its metadata, else ``color`` for an ``rgb``/``rgba`` interpretation, ``uv`` for a 2-component
  param marked ``isUV`` (Maya's extra UV sets), else ``generic``. A name already taken by the
  schema's UVs or normals is read as ``.arbGeomParams/<name>``.
* Face sets (the mesh's FaceSet children): named as the object, family ``materialBind`` (the
  use Alembic's face sets have in every DCC) or the one tuckercodec kept (user property
  :data:`FAMILY_KEY` of the face set); the faces of its first sample.

A param whose values do not fit the mesh (counts, indices out of range, values that are not
numbers) is an :class:`InputError` naming the file, the object, the param and the frame.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import InputError
from ..model.attributes import (
    CORNER,
    FACE,
    FIELD_ROLES,
    GENERIC,
    MATERIAL_FAMILY,
    NORMAL,
    ROLE_COMPONENTS,
    UV,
    VELOCITY,
    VERTEX,
    Attribute,
    FaceSet,
    Field,
    element_count,
)
from .common.polygons import reversed_corners

#: The mesh's user property (a JSON string) with tuckercodec's names of the schema's params:
#: ``{"N": "normals", "velocities": "v"}``.
NAMES_KEY = "tuckercodec_names"
#: A face set's user property with its tuckercodec family, where it is not materialBind.
FAMILY_KEY = "tuckercodec_family"
#: The metadata key of an arbitrary geom param that holds its tuckercodec role.
ROLE_KEY = "tuckercodec_role"

#: The geom param class read for each type (POD, components); any interpretation.
READ_CLASSES = {
    ("float32_t", 1): "Float",
    ("float32_t", 2): "V2f",
    ("float32_t", 3): "V3f",
    ("float32_t", 4): "C4f",
    ("float64_t", 1): "Double",
    ("float64_t", 2): "V2d",
    ("float64_t", 3): "V3d",
    ("int32_t", 1): "Int32",
    ("int32_t", 2): "V2i",
    ("int32_t", 3): "V3i",
}
#: The values' type of each POD.
POD_TYPES = {"float32_t": np.float32, "float64_t": np.float64, "int32_t": np.int32}
_POD_NAMES = {"kFloat32POD": "float32_t", "kFloat64POD": "float64_t", "kInt32POD": "int32_t"}
#: Where the elements of each scope are (constant and unknown scopes are not read).
SCOPE_DOMAINS = {
    "kVertexScope": VERTEX,
    "kVaryingScope": VERTEX,
    "kFacevaryingScope": CORNER,
    "kUniformScope": FACE,
}


@dataclass
class Mesh:
    """What the params are checked against and named with: the file, the object, the faces
    (ours, counter-clockwise), the vertex count, each frame's sample selector."""

    path: Path
    where: str
    faces: np.ndarray
    vertex_count: int
    selectors: list[Any]

    def error(self, param: str, reason: str, frame: int | None = None) -> InputError:
        return InputError(f"{self.where}: param {param}: {reason}", path=self.path, frame=frame)


@dataclass
class FieldReader:
    """An animated param read a range of frames at a time."""

    name: str
    domain: str
    role: str
    read_frame: Callable[[int], np.ndarray]
    mesh: Mesh
    label: str

    def read(self, start: int, stop: int) -> Field:
        values = np.stack([self.read_frame(frame) for frame in range(start, stop)])
        try:
            return Field(self.name, values, self.domain, self.role)
        except InputError as error:
            frame = None if error.frame is None else start + error.frame
            raise self.mesh.error(self.label, error.reason, frame) from None


@dataclass
class Attached:
    """What a mesh carries beside positions: static attributes, face sets, field readers."""

    attributes: list[Attribute]
    face_sets: list[FaceSet]
    fields: list[FieldReader]


def read_attached(abc: SimpleNamespace, item: Any, schema: Any, mesh: Mesh) -> Attached:
    """Everything the module docstring lists, of the mesh object ``item`` (its ``schema``)."""
    names = _kept_names(abc, schema)
    attributes, fields = [], []
    uvs = schema.getUVsParam()
    if uvs.valid():
        name = uvs.getMetaData().get("sourceName") or "uv"
        attributes += _static(_Param(uvs, name, "uv", "float32_t", 2, UV), mesh)
    normals = schema.getNormalsParam() if hasattr(schema, "getNormalsParam") else None  # SubD
    if normals is not None and normals.valid():
        name = names.get("N", "N")
        attributes += _static(_Param(normals, name, "N", "float32_t", 3, NORMAL), mesh)
    velocities = schema.getVelocitiesProperty()
    if velocities.valid() and velocities.getNumSamples():
        fields.append(_velocities(velocities, names.get("velocities", "velocities"), mesh))
    taken = {attribute.name for attribute in attributes}
    for param in _arbitrary(abc, schema.getArbGeomParams(), mesh, taken):
        if param.param.isConstant() or param.domain == CORNER:
            attributes += _static(param, mesh)
        else:
            fields.append(_field(param, mesh))
    return Attached(attributes, _face_sets(abc, item, mesh), fields)


def _kept_names(abc: SimpleNamespace, schema: Any) -> dict[str, str]:
    """tuckercodec's names of the schema's params, where the writer kept them (else none)."""
    user = schema.getUserProperties()
    header = user.getPropertyHeader(NAMES_KEY) if user.valid() else None
    if header is None or not abc.Abc.IStringProperty.matches(header):
        return {}
    try:
        kept = json.loads(abc.Abc.IStringProperty(user, NAMES_KEY).getValue())
    except ValueError:
        return {}  # foreign or damaged: the usual names
    if not isinstance(kept, dict):
        return {}
    return {key: value for key, value in kept.items() if isinstance(value, str) and value}


@dataclass
class _Param:
    """A geom param to read: the library's object, our name, its name in the file (for
    errors), its POD and components, and its role."""

    param: Any
    name: str
    label: str
    pod: str
    components: int
    role: str

    @property
    def domain(self) -> str | None:
        return SCOPE_DOMAINS.get(self.param.getScope().name)


def _arbitrary(abc: SimpleNamespace, compound: Any, mesh: Mesh, taken: set[str]) -> list[_Param]:
    """The arbitrary geom params the module docstring says are read, in the file's order."""
    if not compound.valid():
        return []
    no_matching = abc.Abc.Argument(abc.Abc.SchemaInterpMatching.kNoMatching)
    found = []
    for number in range(compound.getNumProperties()):
        header = compound.getPropertyHeader(number)
        pod, components = _pod(header)
        kind = READ_CLASSES.get((pod, components))
        if kind is None or header.isScalar():
            continue
        name, metadata = header.getName(), header.getMetaData()
        param = getattr(abc.AbcGeom, f"I{kind}GeomParam")(compound, name, no_matching)
        read = _Param(param, name, name, pod, components, _role(metadata, components))
        if read.domain is None:
            continue  # constant or unknown scope: no per-element values
        if name in taken:
            read.name = f".arbGeomParams/{name}"
        found.append(read)
    return found


def _pod(header: Any) -> tuple[str, int]:
    """A param's POD name (``float32_t``) and components, from its metadata (an indexed
    param's compound keeps them there) or its data type."""
    metadata = header.getMetaData()
    pod, extent = metadata.get("podName"), metadata.get("podExtent")
    if not header.isCompound():
        data_type = header.getDataType()
        pod, extent = _POD_NAMES.get(data_type.getPod().name), data_type.getExtent()
    try:
        return str(pod or ""), int(extent)
    except (TypeError, ValueError):
        return "", 0


def _role(metadata: Any, components: int) -> str:
    """The role of an arbitrary param (module docstring)."""
    kept = metadata.get(ROLE_KEY)  # an attribute's or a field's: checked by what it becomes
    if kept in ROLE_COMPONENTS or kept in FIELD_ROLES:
        return str(kept)
    if metadata.get("interpretation") in ("rgb", "rgba"):
        return "color"
    if components == 2 and metadata.get("isUV") in ("1", "true"):
        return UV
    return GENERIC


def _sample(param: _Param, mesh: Mesh, frame: int) -> tuple[np.ndarray, np.ndarray | None]:
    """A param's values (rows of its POD's type) and indices (``None`` if not indexed) at
    ``frame``'s time, as stored (the file's corner order), checked against the mesh."""
    label, domain = param.label, param.domain
    assert domain is not None
    try:
        sample = param.param.getIndexedValue(mesh.selectors[frame])
        values = np.array(np.asarray(sample.getVals()))
        indices = np.array(np.asarray(sample.getIndices())) if param.param.isIndexed() else None
    except (RuntimeError, UnicodeError, MemoryError, OverflowError, ValueError) as error:
        raise mesh.error(label, f"cannot read it: {error}", frame) from None
    if values.dtype.kind not in "fiu" or values.size % param.components:
        raise mesh.error(label, f"holds no numbers of {param.components} components", frame)
    values = values.reshape(-1, param.components).astype(POD_TYPES[param.pod])
    expected = element_count(domain, mesh.vertex_count, mesh.faces)
    count = len(values) if indices is None else len(indices)
    if count != expected:
        raise mesh.error(
            label, f"has {count} values for the mesh's {expected} {domain} elements", frame
        )
    if indices is not None:
        bad = np.flatnonzero((indices < 0) | (indices >= len(values)))
        if bad.size:
            raise mesh.error(
                label,
                f"index {int(indices[bad[0]])} of element {int(bad[0])} is outside its "
                f"{len(values)} values",
                frame,
            )
    return values, indices


def _static(param: _Param, mesh: Mesh) -> list[Attribute]:
    """A param as a static attribute, from frame 0, corners in our order; none for a scope
    that has no domain."""
    if param.domain is None:
        return []
    values, indices = _sample(param, mesh, 0)
    if param.domain == CORNER:
        order = reversed_corners(mesh.faces)
        if indices is None:
            values = values[order]
        else:
            indices = indices[order]
    role = param.role
    if param.components not in ROLE_COMPONENTS.get(role, ()):
        role = GENERIC  # a field's role, or a role foreign to its components
    try:
        return [Attribute(param.name, param.domain, values, indices, role)]
    except InputError as error:
        raise mesh.error(param.label, error.reason, 0) from None


def _field(param: _Param, mesh: Mesh) -> FieldReader:
    """An animated vertex or face param as a field (its values per element each frame)."""

    def read_frame(frame: int) -> np.ndarray:
        values, indices = _sample(param, mesh, frame)
        return values if indices is None else values[indices]

    role = param.role if param.role in FIELD_ROLES else GENERIC
    assert param.domain is not None
    return FieldReader(param.name, param.domain, role, read_frame, mesh, param.label)


def _velocities(velocities: Any, name: str, mesh: Mesh) -> FieldReader:
    """The schema's velocities, one per vertex, as a field of role velocity."""

    def read_frame(frame: int) -> np.ndarray:
        try:
            values = np.array(np.asarray(velocities.getValue(mesh.selectors[frame])))
        except (RuntimeError, UnicodeError, MemoryError, OverflowError) as error:
            raise mesh.error(".velocities", f"cannot read it: {error}", frame) from None
        if values.shape != (mesh.vertex_count, 3) or values.dtype.kind != "f":
            raise mesh.error(
                ".velocities",
                f"holds {values.shape} {values.dtype} values, not 3 per vertex for the mesh's "
                f"{mesh.vertex_count} vertices",
                frame,
            )
        return values

    return FieldReader(name, VERTEX, VELOCITY, read_frame, mesh, ".velocities")


def _face_sets(abc: SimpleNamespace, item: Any, mesh: Mesh) -> list[FaceSet]:
    """The mesh's face sets (its FaceSet children), faces of their first sample."""
    face_count = int(mesh.faces.shape[0])
    found = []
    for number in range(item.getNumChildren()):
        child = item.getChild(number)
        if not abc.AbcGeom.IFaceSet.matches(child.getHeader()):
            continue
        name = child.getName()
        schema = abc.AbcGeom.IFaceSet(child, abc.Abc.WrapExistingFlag.kWrapExisting).getSchema()
        faces = np.array(np.asarray(schema.getValue().getFaces()), dtype=np.int64)
        outside = np.flatnonzero((faces < 0) | (faces >= face_count))
        if outside.size:
            raise InputError(
                f"{mesh.where}: face set {name}: face {int(faces[outside[0]])} is not one of "
                f"the mesh's {face_count} faces",
                path=mesh.path,
            )
        try:
            found.append(FaceSet(name, faces, _family(abc, schema)))
        except InputError as error:
            raise InputError(f"{mesh.where}: {error.reason}", path=mesh.path) from None
    return found


def _family(abc: SimpleNamespace, schema: Any) -> str:
    """A face set's family: the one tuckercodec kept, else materialBind."""
    user = schema.getUserProperties()
    header = user.getPropertyHeader(FAMILY_KEY) if user.valid() else None
    if header is None or not abc.Abc.IStringProperty.matches(header):
        return MATERIAL_FAMILY
    return str(abc.Abc.IStringProperty(user, FAMILY_KEY).getValue())
