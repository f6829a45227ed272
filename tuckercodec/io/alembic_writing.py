"""The writing child's side of an Alembic mesh's attributes, fields and face sets: the
:class:`~.alembic_plan.Plan` made in the caller crosses the pipe as arrays and JSON
(:func:`pack_plan`, :func:`unpack_plan`), and is written with alembic3d (:class:`ParamWriter`)
as :mod:`.alembic_plan` says.
"""

from __future__ import annotations

import json
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..model.attributes import CORNER, FACE, UV, FaceSet
from .alembic_attached import FAMILY_KEY, NAMES_KEY, ROLE_KEY
from .alembic_plan import Param, Plan

#: The geometry scope of each domain.
DOMAIN_SCOPES = {CORNER: "kFacevaryingScope", FACE: "kUniformScope"}  # else kVertexScope


def pack_plan(plan: Plan) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The JSON values and arrays that carry ``plan`` to the writing child."""
    arrays: dict[str, np.ndarray] = {}
    for number, param in enumerate(plan.params):
        arrays[f"param.{number}.values"] = param.values
        if param.indices is not None:
            arrays[f"param.{number}.indices"] = param.indices
    for number, face_set in enumerate(plan.face_sets):
        arrays[f"face_set.{number}"] = face_set.faces
    listed = [
        {"target": p.target, "name": p.name, "kind": p.kind, "domain": p.domain, "role": p.role}
        for p in plan.params
    ]
    sets = [{"name": s.name, "family": s.family} for s in plan.face_sets]
    return {"params": listed, "face_sets": sets, "names": plan.names}, arrays


def unpack_plan(values: dict[str, Any], arrays: dict[str, np.ndarray]) -> Plan:
    """The plan :func:`pack_plan` packed."""
    params = [
        Param(
            entry["target"],
            entry["name"],
            entry["kind"],
            entry["domain"],
            entry["role"],
            arrays[f"param.{number}.values"],
            arrays.get(f"param.{number}.indices"),
        )
        for number, entry in enumerate(values.get("params", []))
    ]
    face_sets = [
        FaceSet(entry["name"], arrays[f"face_set.{number}"], entry["family"])
        for number, entry in enumerate(values.get("face_sets", []))
    ]
    return Plan(params, face_sets, dict(values.get("names", {})))


class ParamWriter:
    """Writes a plan's params into a PolyMesh schema: the schema's own (UVs, normals,
    velocities) into each position sample (:meth:`name_uvs` first, then :meth:`fill`), the
    arbitrary ones and the face sets beside (:meth:`write_beside`)."""

    def __init__(self, abc: SimpleNamespace, plan: Plan):
        self.abc, self.plan = abc, plan
        self.own = {param.target: param for param in plan.params if param.target != "arb"}

    def name_uvs(self, schema: Any) -> None:
        """Name the UVs (before the first sample, which makes their param)."""
        if "uv" in self.own and self.own["uv"].name != "uv":
            schema.setUVSourceName(self.own["uv"].name)

    def fill(self, sample: Any, frame: int) -> None:
        """Set the UVs (frame 0; later samples repeat them), normals and velocities of
        ``frame``'s position sample."""
        uv, normals = self.own.get("uv"), self.own.get("N")
        velocities = self.own.get("velocities")
        if uv is not None and frame == 0:
            sample.setUVs(self._sample(uv, uv.values))
        if normals is not None and (frame == 0 or normals.animated):
            values = normals.values[frame] if normals.animated else normals.values
            sample.setNormals(self._sample(normals, values))
        if velocities is not None:
            sample.setVelocities(self._values("V3f", velocities.values[frame]))

    def write_beside(self, schema: Any, sampling: int, frames: int) -> None:
        """The arbitrary params (a field: a sample per frame, in the mesh's time sampling
        ``sampling``), the kept names and the face sets."""
        abc = self.abc
        if self.plan.names:
            kept = abc.Abc.OStringProperty(schema.getUserProperties(), NAMES_KEY)
            kept.setValue(json.dumps(self.plan.names))
        for param in self.plan.params:
            if param.target == "arb":
                self._arbitrary(schema.getArbGeomParams(), param, sampling, frames)
        for face_set in self.plan.face_sets:
            written = schema.createFaceSet(face_set.name).getSchema()
            faces = face_set.faces.astype(np.int32)
            written.set(abc.AbcGeom.OFaceSetSchemaSample(abc.imath.IntArrayFromBuffer(faces)))
            if face_set.family != "materialBind":
                family = abc.Abc.OStringProperty(written.getUserProperties(), FAMILY_KEY)
                family.setValue(face_set.family)

    def _arbitrary(self, compound: Any, param: Param, sampling: int, frames: int) -> None:
        """One arbitrary param, its role in its metadata, one sample or one per frame."""
        abc = self.abc
        metadata = abc.AbcA.MetaData()
        metadata.set(ROLE_KEY, param.role)
        if param.role == UV:
            metadata.set("isUV", "1")
        scope = getattr(abc.AbcGeom.GeometryScope, DOMAIN_SCOPES.get(param.domain, "kVertexScope"))
        cls = getattr(abc.AbcGeom, f"O{param.kind}GeomParam")
        arguments = [abc.Abc.Argument(metadata)]
        if param.animated:
            arguments.append(abc.Abc.Argument(sampling))
        written = cls(compound, param.name, param.indices is not None, scope, 1, *arguments)
        for frame in range(frames if param.animated else 1):
            values = param.values[frame] if param.animated else param.values
            written.set(self._sample(param, values))

    def _sample(self, param: Param, values: np.ndarray) -> Any:
        """A geom param sample of ``values`` (and the param's indices) in its scope."""
        abc = self.abc
        scope = getattr(abc.AbcGeom.GeometryScope, DOMAIN_SCOPES.get(param.domain, "kVertexScope"))
        cls = getattr(abc.AbcGeom, f"O{param.kind}GeomParamSample")
        vals = self._values(param.kind, values)
        if param.indices is None:
            return cls(vals, scope)
        wide = abc.imath.DoubleArrayFromBuffer(param.indices.astype(np.float64))  # exact
        return cls(vals, abc.imath.UnsignedIntArray(wide), scope)

    def _values(self, kind: str, values: np.ndarray) -> Any:
        """``values`` as the imath array a ``kind`` param takes (a copy)."""
        imath = self.abc.imath
        if kind in ("Float", "Double", "Int32"):
            base = {"Float": "Float", "Double": "Double", "Int32": "Int"}[kind]
            return getattr(imath, f"{base}ArrayFromBuffer")(np.ascontiguousarray(values[:, 0]))
        if kind == "C3f":
            return imath.C3fArray(imath.V3fArrayFromBuffer(np.ascontiguousarray(values)))
        if kind == "C4f":  # no conversion from a buffer: value by value
            colours = imath.C4fArray(len(values))
            for number, row in enumerate(values.tolist()):
                colours[number] = imath.Color4f(*row)
            return colours
        vector = "V" + kind[1:]  # N3f: a V3f array
        return getattr(imath, f"{vector}ArrayFromBuffer")(np.ascontiguousarray(values))
