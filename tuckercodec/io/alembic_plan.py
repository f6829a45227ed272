"""Where each attribute, field and face set of a sequence goes in an Alembic PolyMesh, decided
in the caller's process before the writing child runs (:func:`plan`), and what cannot go
anywhere (:func:`cannot_keep`, the format's registry hook).

* The first float32 ``uv`` attribute: the schema's UVs (``uv``, indexed when the attribute is,
  its name as ``sourceName`` where it is not ``uv``).
* The first float32 ``normal`` attribute: the schema's normals ``N``. An animated mesh gets
  normals per sample: frame 0's are the attribute's (bit for bit, which the reader takes back),
  every later frame's are recomputed from its positions with the attribute's layout and
  hard edges (:func:`per_frame_normals`).
* The first float32 vertex ``velocity`` field of 3 components: the schema's ``.velocities``.
* Every other attribute and field: an arbitrary geom param of its name and type (float32 of 1
  to 4 components, float64 or int32 of 1 to 3; :data:`WRITE_CLASSES`), its role in its metadata
  (``tuckercodec_role``; ``isUV`` for a UV); a field gets a sample per frame.
* Face sets: FaceSet children named as the set, their family (where it is not materialBind) in
  a user property.

Per-corner values are written in Alembic's corner order: the faces are written reversed
(clockwise), and the values and indices follow (:func:`~.common.polygons.reversed_corners`).
Names of the schema's params (``N``, ``velocities``) that are not the usual ones are kept in the
mesh's user property :data:`~.alembic_attached.NAMES_KEY`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..model.attributes import (
    COLOR,
    CORNER,
    NORMAL,
    UV,
    VELOCITY,
    VERTEX,
    Attribute,
    FaceSet,
)
from ..model.normals import recomputed_normals
from ..model.sequence import MeshSequence
from .common.polygons import reversed_corners

#: The geom param class written for each value type and components (``C3f`` for a float32
#: colour, ``N3f``/``N3d`` for a normal instead of ``V3f``/``V3d``).
WRITE_CLASSES = {
    ("float32", 1): "Float",
    ("float32", 2): "V2f",
    ("float32", 3): "V3f",
    ("float32", 4): "C4f",
    ("float64", 1): "Double",
    ("float64", 2): "V2d",
    ("float64", 3): "V3d",
    ("int32", 1): "Int32",
    ("int32", 2): "V2i",
    ("int32", 3): "V3i",
}
_ROLE_CLASSES = {("V3f", COLOR): "C3f", ("V3f", NORMAL): "N3f", ("V3d", NORMAL): "N3d"}


@dataclass
class Param:
    """One geom param to write: where (``uv``, ``N``, ``velocities`` or ``arb``), its name,
    class (``V2f``...), domain and role; values (N, c), or (F, N, c) when animated, and indices,
    per corner in Alembic's corner order."""

    target: str
    name: str
    kind: str
    domain: str
    role: str
    values: np.ndarray
    indices: np.ndarray | None = None

    @property
    def animated(self) -> bool:
        return self.values.ndim == 3


@dataclass
class Plan:
    """What the writer writes beside positions, and what it leaves out (in words)."""

    params: list[Param] = field(default_factory=list)
    face_sets: list[FaceSet] = field(default_factory=list)
    names: dict[str, str] = field(default_factory=dict)
    dropped: list[str] = field(default_factory=list)


def cannot_keep(sequence: MeshSequence) -> list[str]:
    """What an Alembic archive written of ``sequence`` leaves out, one sentence each."""
    return plan(sequence, values=False).dropped


def plan(sequence: MeshSequence, values: bool = True) -> Plan:
    """Where everything goes (module docstring); ``values=False`` only says what is dropped
    (no normals recomputed, no values reordered)."""
    result = Plan()
    taken: set[str] = set()  # the arbitrary params' names: attributes and fields share them
    order = reversed_corners(sequence.faces)
    remaining = list(sequence.attributes)
    uv = _first(remaining, UV)
    if uv is not None:
        remaining.remove(uv)
        result.params.append(_static("uv", "V2f", uv, order))
    normal = _first(remaining, NORMAL)
    if normal is not None:
        remaining.remove(normal)
        normals = per_frame_normals(sequence, normal) if values else normal.values
        result.params.append(_static("N", "N3f", normal, order, normals))
        if normal.name != "N":
            result.names["N"] = normal.name
    for attribute in remaining:
        kind = _arbitrary_kind(
            attribute.name,
            attribute.values.dtype,
            attribute.components,
            attribute.role,
            taken,
            "attribute",
            result.dropped,
        )
        if kind is not None:
            result.params.append(_static("arb", kind, attribute, order))
    _plan_fields(sequence, taken, result)
    _plan_face_sets(sequence, result)
    return result


def _first(attributes: list[Attribute], role: str) -> Attribute | None:
    """The first float32 attribute of ``role`` (the schema's own param takes float32 only)."""
    for attribute in attributes:
        if attribute.role == role and attribute.values.dtype == np.float32:
            return attribute
    return None


def _static(
    target: str,
    kind: str,
    attribute: Attribute,
    order: np.ndarray,
    values: np.ndarray | None = None,
) -> Param:
    """A static (or per-frame normals') param of ``attribute``, corners in Alembic's order."""
    values = attribute.values if values is None else values
    indices = attribute.indices
    if attribute.domain == CORNER:
        if indices is not None:
            indices = indices[order]
        else:
            values = values[..., order, :]
    return Param(target, attribute.name, kind, attribute.domain, attribute.role, values, indices)


def _arbitrary_kind(
    name: str,
    dtype: np.dtype[Any],
    components: int,
    role: str,
    taken: set[str],
    what: str,
    dropped: list[str],
) -> str | None:
    """The class of an arbitrary param for these values, or ``None`` (said in ``dropped``)."""
    kind = WRITE_CLASSES.get((dtype.name, components))
    if kind is None:
        dropped.append(
            f"{what} {name!r}: Alembic's geom params hold float32 of 1 to 4 components, "
            f"float64 or int32 of 1 to 3, not {dtype.name} of {components}"
        )
    elif "/" in name:
        dropped.append(f"{what} {name!r}: an Alembic property's name cannot hold '/'")
        kind = None
    elif name in taken:
        dropped.append(f"{what} {name!r}: an attribute or field of the same name is written")
        kind = None
    else:
        taken.add(name)
        kind = _ROLE_CLASSES.get((kind, role), kind)
    return kind


def _plan_fields(sequence: MeshSequence, taken: set[str], result: Plan) -> None:
    """The velocities, then every other field as an animated arbitrary param."""
    velocity = next(
        (
            item
            for item in sequence.fields
            if item.role == VELOCITY
            and item.domain == VERTEX
            and item.components == 3
            and item.values.dtype == np.float32
        ),
        None,
    )
    for item in sequence.fields:
        if item is velocity:
            result.params.append(
                Param("velocities", item.name, "V3f", VERTEX, VELOCITY, item.values)
            )
            if item.name != "velocities":
                result.names["velocities"] = item.name
            continue
        kind = _arbitrary_kind(
            item.name, item.values.dtype, item.components, item.role, taken, "field", result.dropped
        )
        if kind is not None:
            result.params.append(Param("arb", item.name, kind, item.domain, item.role, item.values))


def _plan_face_sets(sequence: MeshSequence, result: Plan) -> None:
    """The face sets an Alembic mesh can hold: named as objects (no '/'), each name once."""
    names: set[str] = set()
    for face_set in sequence.face_sets:
        label = f"face set {face_set.name!r} (family {face_set.family!r})"
        if "/" in face_set.name:
            result.dropped.append(f"{label}: an Alembic object's name cannot hold '/'")
        elif face_set.name in names:
            result.dropped.append(
                f"{label}: Alembic keeps one face set of a name, and one of another family "
                "is written"
            )
        else:
            names.add(face_set.name)
            result.face_sets.append(face_set)


# ------------------------------------------------------------------------------------------
# normals per frame


def per_frame_normals(sequence: MeshSequence, attribute: Attribute) -> np.ndarray:
    """The normal attribute's values for each frame, (F, rows, 3) of its type: frame 0's as
    stored, later frames' recomputed from their positions in the attribute's layout
    (:func:`~tuckercodec.model.normals.recomputed_normals`)."""
    later = [
        recomputed_normals(positions, sequence.faces, attribute)
        for positions in sequence.vertices[1:]
    ]
    return np.stack([attribute.values, *later])
