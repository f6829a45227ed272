"""What a UsdGeomMesh carries beside its points, read with pxr (in the reading child of
:mod:`.usd`): primvars and normals as :class:`~tuckercodec.model.attributes.Attribute`\\ s,
GeomSubsets of faces as :class:`~tuckercodec.model.attributes.FaceSet`\\ s, and time-sampled
primvars and ``velocities`` as :class:`~tuckercodec.model.attributes.Field`\\ s, read a range
of frames at a time.

The rules (the module docstring of :mod:`.usd` repeats them for users):

* Interpolation gives the domain: ``vertex`` and ``varying`` a vertex attribute, ``faceVarying``
  a corner attribute, ``uniform`` a face attribute. ``constant`` primvars (one value for the
  whole mesh: ``displayColor`` of a plain asset) are not read, nor primvars whose
  ``elementSize`` is not 1, nor value types other than float, double and int scalars and
  vectors of 2 to 4 (bool, half, strings, matrices...).
* An indexed primvar (``primvars:st:indices``) is an indexed attribute: its values and indices
  as the file has them.
* The name is the primvar's without ``primvars:`` (``st``, ``displayColor``). The role comes from
  the value type's role (texCoord, color, normal), else from USD's names (``st`` a uv,
  ``displayColor`` a colour, ``normals`` a normal); else ``generic``. A mesh's normals are
  ``primvars:normals`` if authored (it wins, as UsdGeom says), else its ``normals`` attribute.
* A primvar with time samples (other than normals) whose domain is vertex or face is a field,
  read at each frame's time (indexed ones flattened): values that change over time are what a
  field is for, and one whose samples happen to be equal compresses to almost nothing. Normals,
  and time-sampled corner primvars (no field has corners), are read at frame 0's time.
* ``velocities`` is a field of role ``velocity`` (vertex domain), whether time-sampled or not.
* GeomSubsets of faces (``elementType`` face) under the mesh are face sets named as the
  subset's prim, of its ``familyName`` (``materialBind`` for materials), read at frame 0's time.
* A left-handed mesh's faces are reversed (:mod:`.usd`): its corner attributes follow, corner
  for corner.
* A primvar whose element count does not fit its interpolation, an index outside its values,
  a subset naming a face the mesh lacks, or a field whose count changes at a frame is an
  InputError naming the file, the prim, the primvar and the frame.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import InputError
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
    FaceSet,
    Field,
    corner_faces,
    element_count,
    face_corner_starts,
)

#: A primvar's interpolation -> the domain of its values (``constant`` has none: not read).
INTERPOLATION_DOMAINS = {
    "vertex": VERTEX,
    "varying": VERTEX,
    "faceVarying": CORNER,
    "uniform": FACE,
}
#: The value types read, by their C++ name: scalar (float, double, int) or GfVec2-4 of them.
_VALUE_TYPE = re.compile(r"VtArray<(?:(float|double|int)|GfVec([234])([fdi]))>")
_SCALARS = {"float": np.float32, "double": np.float64, "int": np.int32}
_VECTOR_SCALARS = {"f": np.float32, "d": np.float64, "i": np.int32}
#: The value type roles that give an attribute's role, and the components each allows.
_TYPE_ROLES = {"TextureCoordinate": (UV, (2,)), "Color": (COLOR, (3, 4)), "Normal": (NORMAL, (3,))}
#: USD's names that mean a role where the value type has none (``float2 primvars:st``).
_NAMED_ROLES = {"st": (UV, (2,)), "displayColor": (COLOR, (3, 4)), "normals": (NORMAL, (3,))}
_PLURALS = {VERTEX: "vertices", CORNER: "corners", FACE: "faces"}
NORMALS, VELOCITIES = "normals", "velocities"
#: The mesh's own ``velocities`` attribute (a primvar of that name is not it).
_VELOCITIES_LABEL = "attribute velocities"


def value_type(type_name: Any) -> tuple[np.dtype, int] | None:
    """The numpy type and components of an Sdf array value type, or ``None`` if not read."""
    found = _VALUE_TYPE.fullmatch(str(type_name.cppTypeName))
    if found is None or not type_name.isArray:
        return None
    scalar, components, vector = found.groups()
    if scalar:
        return np.dtype(_SCALARS[scalar]), 1
    return np.dtype(_VECTOR_SCALARS[vector]), int(components)


def attribute_role(name: str, type_role: str, components: int, dtype: np.dtype) -> str:
    """An attribute's role: its value type's, else its USD name's, else ``generic``; a role
    only for floating-point values of the components it allows."""
    if dtype.kind != "f":
        return GENERIC
    for found in (_TYPE_ROLES.get(type_role), _NAMED_ROLES.get(name)):
        if found is not None and components in found[1]:
            return found[0]
    return GENERIC


@dataclass
class _Primvar:
    """One per-element value of the mesh: a primvar, or the mesh's ``normals``/``velocities``
    attribute (interpolation, no indices)."""

    name: str
    label: str  # "primvar 'st'" or "attribute velocities", for errors
    values: Any  # Usd.Attribute
    indices: Any  # Usd.Attribute, or None when not indexed
    interpolation: str
    dtype: np.dtype
    components: int
    role: str

    def animated(self) -> bool:
        return bool(self.values.GetNumTimeSamples() or self.values.ValueMightBeTimeVarying())


@dataclass
class FieldPlan:
    """How a field is read at each frame: its primvar, domain and role."""

    primvar: _Primvar
    domain: str
    role: str


class MeshReading:
    """What a mesh carries beside its points, found when the mesh is opened.

    Args:
        pxr: the pxr modules.
        mesh: the UsdGeom.Mesh.
        faces: its face table as read (reversed if left-handed).
        left_handed: whether the faces were reversed.
        where: "prim /Root/mesh", for errors; path: the file.
    """

    def __init__(
        self,
        pxr: SimpleNamespace,
        mesh: Any,
        vertex_count: int,
        faces: np.ndarray,
        left_handed: bool,
        where: str,
        path: Path,
    ):
        self._pxr, self._mesh, self._where, self._path = pxr, mesh, where, path
        self._vertex_count, self._faces, self._left_handed = vertex_count, faces, left_handed
        self.attributes: list[Attribute] = []
        self.face_sets: list[FaceSet] = []
        self.fields: list[FieldPlan] = []

    def read(self, first_time: Any) -> None:
        """Find the attributes, face sets and fields; read the static ones at ``first_time``
        (frame 0's time code)."""
        for primvar in self._primvars():
            domain = INTERPOLATION_DOMAINS[primvar.interpolation]
            if primvar.label == _VELOCITIES_LABEL:
                self.fields.append(FieldPlan(primvar, VERTEX, VELOCITY))
            elif primvar.role != NORMAL and domain != CORNER and primvar.animated():
                role = COLOR if primvar.role == COLOR else GENERIC
                self.fields.append(FieldPlan(primvar, domain, role))
            else:
                attribute = self._attribute(primvar, domain, first_time)
                self.attributes += [attribute] if attribute is not None else []
        self.face_sets = self._face_sets(first_time)

    def _primvars(self) -> list[_Primvar]:
        """The per-element primvars read (in the file's order), then the mesh's ``normals`` if
        no ``primvars:normals`` is, and its ``velocities`` if authored."""
        pxr, mesh = self._pxr, self._mesh
        found = []
        for primvar in pxr.UsdGeom.PrimvarsAPI(mesh).GetPrimvarsWithValues():
            name = str(primvar.GetPrimvarName())
            if primvar.GetElementSize() != 1:
                continue
            indices = primvar.GetIndicesAttr() if primvar.IsIndexed() else None
            item = self._described(
                name, f"primvar {name!r}", primvar.GetAttr(), indices, primvar.GetInterpolation()
            )
            if item is not None:
                found.append(item)
        names = {item.name for item in found}
        if NORMALS not in names:
            normals = mesh.GetNormalsAttr()
            if normals.HasAuthoredValue():
                interpolation = str(mesh.GetNormalsInterpolation())
                item = self._described(NORMALS, "attribute normals", normals, None, interpolation)
                found += [item] if item is not None else []
        velocities = mesh.GetVelocitiesAttr()
        # beside a static primvars:velocities (an attribute) it is a field of the same name
        fields = {item.name for item in found if item.animated()}
        if VELOCITIES not in fields and velocities.HasAuthoredValue():
            item = self._described(VELOCITIES, _VELOCITIES_LABEL, velocities, None, "vertex")
            found += [item] if item is not None else []
        return found

    @staticmethod
    def _described(
        name: str, label: str, values: Any, indices: Any, interpolation: object
    ) -> _Primvar | None:
        interpolation = str(interpolation)
        typed = value_type(values.GetTypeName())
        if interpolation not in INTERPOLATION_DOMAINS or typed is None:
            return None
        dtype, components = typed
        type_role = str(values.GetTypeName().role)
        role = attribute_role(name, type_role, components, dtype)
        return _Primvar(name, label, values, indices, interpolation, dtype, components, role)

    def _expected(self, domain: str) -> int:
        return element_count(domain, self._vertex_count, self._faces)

    def _values(self, primvar: _Primvar, time: Any, frame: int | None) -> np.ndarray | None:
        """The primvar's values at ``time``, as (N, c) of its type; ``None`` if blocked."""
        value = primvar.values.Get(time)
        if value is None:
            return None
        array = np.asarray(value)
        if array.ndim == 1:
            array = array[:, None]
        if array.dtype != primvar.dtype or array.ndim != 2 or array.shape[1] != primvar.components:
            raise InputError(
                f"{self._where}: {primvar.label} holds {array.dtype} values of shape "
                f"{array.shape}, not its declared type",
                path=self._path,
                frame=frame,
            )
        return array

    def _attribute(self, primvar: _Primvar, domain: str, time: Any) -> Attribute | None:
        """A static attribute: the primvar's values (and indices) at ``time``; ``None`` if
        blocked there."""
        values = self._values(primvar, time, None)  # static: the file's, not a frame's
        if values is None:
            return None
        indices = None
        if primvar.indices is not None:
            indices = np.asarray(primvar.indices.Get(time) or [], dtype=np.int64)
        count = len(values) if indices is None else len(indices)
        self._check_count(primvar, domain, count, None)
        if domain == CORNER and self._left_handed:  # the corners as the reversed faces have them
            order = reversed_corners(self._faces)
            if indices is not None:
                indices = indices[order]
            else:
                values = values[order]
        try:
            return Attribute(primvar.name, domain, values, indices, primvar.role)
        except InputError as error:
            raise InputError(
                f"{self._where}: {primvar.label}: {error.reason}", path=self._path
            ) from None

    def _check_count(self, primvar: _Primvar, domain: str, count: int, frame: int | None) -> None:
        expected = self._expected(domain)
        if count != expected:
            kind = "indices" if primvar.indices is not None else "values"
            raise InputError(
                f"{self._where}: {primvar.label} ({primvar.interpolation}) has {count} {kind}, "
                f"where the mesh has {expected} {_PLURALS[domain]}",
                path=self._path,
                frame=frame,
            )

    def read_fields(self, frame_times: list[Any], start: int) -> list[Field]:
        """The fields at ``frame_times`` (the times of frames ``start``, ``start + 1``...)."""
        fields = []
        for plan in self.fields:
            primvar = plan.primvar
            rows = []
            for offset, time in enumerate(frame_times):
                frame = start + offset
                values = self._values(primvar, time, frame)
                if values is None:
                    raise InputError(
                        f"{self._where}: {primvar.label} has no value at frame {frame}'s time "
                        "(blocked)",
                        path=self._path,
                        frame=frame,
                    )
                if primvar.indices is not None:
                    values = self._flattened(primvar, values, time, frame)
                self._check_count(primvar, plan.domain, len(values), frame)
                rows.append(values)
            try:
                fields.append(Field(primvar.name, np.stack(rows), plan.domain, plan.role))
            except InputError as error:
                raise InputError(
                    f"{self._where}: {primvar.label}: {error.reason}",
                    path=self._path,
                    frame=None if error.frame is None else start + error.frame,
                ) from None
        return fields

    def _flattened(self, primvar: _Primvar, values: np.ndarray, time: Any, frame: int) -> Any:
        """An indexed primvar's value per element at ``time``."""
        indices = np.asarray(primvar.indices.Get(time) or [], dtype=np.int64)
        bad = np.flatnonzero((indices < 0) | (indices >= len(values)))
        if bad.size:
            raise InputError(
                f"{self._where}: {primvar.label}: element {int(bad[0])} has index "
                f"{int(indices[bad[0]])}, outside the {len(values)} values",
                path=self._path,
                frame=frame,
            )
        return values[indices]

    def _face_sets(self, time: Any) -> list[FaceSet]:
        """The mesh's GeomSubsets of faces."""
        pxr, face_count = self._pxr, len(self._faces)
        subsets = pxr.UsdGeom.Subset.GetAllGeomSubsets(pxr.UsdGeom.Imageable(self._mesh))
        face_sets = []
        for subset in subsets:
            if str(subset.GetElementTypeAttr().Get()) != "face":
                continue
            name = str(subset.GetPrim().GetName())
            family = str(subset.GetFamilyNameAttr().Get() or "")
            faces = np.asarray(subset.GetIndicesAttr().Get(time) or [], dtype=np.int64)
            outside = faces[(faces < 0) | (faces >= face_count)]
            if outside.size:
                raise InputError(
                    f"{self._where}: GeomSubset {name!r} names face {int(outside[0])}, where "
                    f"the mesh has {face_count} faces",
                    path=self._path,
                )
            try:
                face_sets.append(FaceSet(name, faces, family))
            except InputError as error:
                raise InputError(f"{self._where}: {error.reason}", path=self._path) from None
        return face_sets


def reversed_corners(faces: np.ndarray) -> np.ndarray:
    """For each corner of ``faces`` (in corner order), the corner it was before each face's
    corners were reversed: a corner attribute's rows taken in this order follow the faces of
    :func:`~.common.polygons.reverse_winding` (the order is its own inverse)."""
    starts = face_corner_starts(faces)
    owner = corner_faces(faces)
    position = np.arange(owner.size, dtype=np.int64) - starts[owner]
    degree = starts[owner + 1] - starts[owner]
    return starts[owner] + degree - 1 - position
