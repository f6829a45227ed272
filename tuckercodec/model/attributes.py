"""What a cache carries beside positions and faces: static attributes (UVs, normals, colours,
any per-vertex, per-corner or per-face values), face sets (materials, groups) and animated
fields (velocities, simulation scalars and vectors, one value per vertex or face per frame).

Conventions every reader, writer and codec shares:

* A *corner* is one entry of a face: the corners of a mesh are the face table's real entries in
  C order (face 0's corners, then face 1's...), padding skipped. :func:`corner_vertices` gives
  the vertex of every corner. This is USD's ``faceVertexIndices`` order and Alembic's.
* An attribute's values are a table of N rows of 1 to 4 components. Without ``indices`` it
  has one row per element of its domain (vertex, corner or face). With ``indices`` (an
  *indexed* attribute, as USD and Alembic store UVs and as OBJ's ``vt``/``vn`` are), element e's
  value is ``values[indices[e]]``; rows no element uses are kept.
* Values are stored bit for bit: float32, float64 or int32, as the source gave them.
* The ``role`` says what an attribute is for the formats that name it (OBJ's ``vt`` is a UV,
  glTF's ``NORMAL`` a normal); ``generic`` is anything else, kept under its name.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError

VERTEX, CORNER, FACE = "vertex", "corner", "face"
#: Where an attribute's elements are.
DOMAINS = (VERTEX, CORNER, FACE)
#: Where an animated field's elements are (a field per corner has no format that stores it).
FIELD_DOMAINS = (VERTEX, FACE)

UV, NORMAL, COLOR, GENERIC = "uv", "normal", "color", "generic"
#: What an attribute is, for the formats that name it.
ROLES = (UV, NORMAL, COLOR, GENERIC)
#: Components each role allows (``generic``: any of 1 to 4).
ROLE_COMPONENTS = {UV: (2,), NORMAL: (3,), COLOR: (3, 4), GENERIC: (1, 2, 3, 4)}

VELOCITY = "velocity"
#: What a field is: ``velocity`` (USD's ``velocities``), ``color``, or ``generic``.
FIELD_ROLES = (VELOCITY, COLOR, GENERIC)

#: The value types stored bit for bit.
VALUE_TYPES = (np.dtype(np.float32), np.dtype(np.float64), np.dtype(np.int32))
#: The field value types (a field is compressed, so it is a real number).
FIELD_TYPES = (np.dtype(np.float32), np.dtype(np.float64))

#: The longest name, in UTF-8 bytes, of an attribute, face set or field.
MAX_NAME_BYTES = 255

#: Face-set families with a meaning: ``materialBind`` as USD's GeomSubset family of materials
#: (OBJ's ``usemtl``, glTF's primitives, Alembic's face sets bound to materials); ``group``:
#: OBJ's ``g`` groups; any other family (or none, ``""``) is kept as it is.
MATERIAL_FAMILY, GROUP_FAMILY = "materialBind", "group"

_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def corner_vertices(faces: np.ndarray) -> np.ndarray:
    """The vertex of every corner of ``faces`` ((M, n) padded with -1), in corner order."""
    table = np.asarray(faces)
    return np.ascontiguousarray(table[table >= 0], dtype=np.int64)


def corner_faces(faces: np.ndarray) -> np.ndarray:
    """The face of every corner, in corner order."""
    table = np.asarray(faces)
    rows = np.broadcast_to(np.arange(table.shape[0])[:, None], table.shape)
    return np.ascontiguousarray(rows[table >= 0], dtype=np.int64)


def face_corner_starts(faces: np.ndarray) -> np.ndarray:
    """Where each face's corners start in corner order, M + 1 offsets (the last is the count)."""
    table = np.asarray(faces)
    degrees = (table >= 0).sum(axis=1)
    starts = np.zeros(table.shape[0] + 1, dtype=np.int64)
    np.cumsum(degrees, out=starts[1:])
    return starts


def element_count(domain: str, vertex_count: int, faces: np.ndarray) -> int:
    """How many elements ``domain`` has on a mesh of ``vertex_count`` vertices and ``faces``."""
    if domain == VERTEX:
        return vertex_count
    if domain == FACE:
        return int(np.asarray(faces).shape[0])
    return int((np.asarray(faces) >= 0).sum())


def checked_name(name: object, what: str) -> str:
    """A name of 1 to :data:`MAX_NAME_BYTES` UTF-8 bytes without control characters."""
    if not isinstance(name, str) or not name:
        raise InputError(f"{what} needs a name (a non-empty string), got {name!r}")
    if len(name.encode("utf-8", "surrogatepass")) > MAX_NAME_BYTES:
        raise InputError(f"{what} {name[:40]!r}... has a name longer than {MAX_NAME_BYTES} bytes")
    if _CONTROL.search(name):
        raise InputError(f"{what} {name!r} has a control character in its name")
    try:
        name.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(f"{what} {name!r} has a name that is not valid Unicode") from None
    return name


@dataclass(eq=False)
class Attribute:
    """Static values per vertex, per face corner or per face, stored bit for bit.

    Attributes:
        name: unique among the sequence's attributes (``st``, ``UVMap``, ``normals``...).
        domain: ``vertex``, ``corner`` or ``face`` (:data:`DOMAINS`).
        values: (N, c) array of float32, float64 or int32, c in 1..4.
        indices: ``None``, or an int64 index per element into ``values``' rows.
        role: ``uv``, ``normal``, ``color`` or ``generic`` (:data:`ROLES`).
    """

    name: str
    domain: str
    values: np.ndarray = field(repr=False)
    indices: np.ndarray | None = field(default=None, repr=False)
    role: str = GENERIC

    def __post_init__(self) -> None:
        self.name = checked_name(self.name, "an attribute")
        label = f"attribute {self.name!r}"
        if self.domain not in DOMAINS:
            raise InputError(
                f"{label}: domain must be one of {', '.join(DOMAINS)}, got {self.domain!r}"
            )
        if self.role not in ROLES:
            raise InputError(f"{label}: role must be one of {', '.join(ROLES)}, got {self.role!r}")
        values = np.asarray(self.values)
        if values.ndim == 1:
            values = values[:, None]
        if values.ndim != 2 or not 1 <= values.shape[1] <= 4:
            raise InputError(f"{label}: values must have shape (N, 1 to 4), got {values.shape}")
        if values.dtype.newbyteorder("=") not in VALUE_TYPES:
            raise InputError(
                f"{label}: values must be float32, float64 or int32, got {values.dtype}"
            )
        self.values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
        if values.shape[1] not in ROLE_COMPONENTS[self.role]:
            raise InputError(
                f"{label}: a {self.role} has {' or '.join(map(str, ROLE_COMPONENTS[self.role]))} "
                f"components, got {values.shape[1]}"
            )
        if self.indices is not None:
            indices = np.asarray(self.indices)
            if indices.ndim != 1 or not np.issubdtype(indices.dtype, np.integer):
                raise InputError(f"{label}: indices must be one integer per element")
            indices = np.ascontiguousarray(indices, dtype=np.int64)
            bad = np.flatnonzero((indices < 0) | (indices >= values.shape[0]))
            if bad.size:
                raise InputError(
                    f"{label}: element {int(bad[0])} has index {int(indices[bad[0]])}, "
                    f"outside the {values.shape[0]} values"
                )
            self.indices = indices

    @property
    def components(self) -> int:
        """c, the values' components."""
        return int(self.values.shape[1])

    @property
    def element_count(self) -> int:
        """The number of elements this attribute gives a value to."""
        return int(self.values.shape[0] if self.indices is None else self.indices.shape[0])

    def element_values(self) -> np.ndarray:
        """One row per element: ``values[indices]`` when indexed, else ``values``."""
        return self.values if self.indices is None else self.values[self.indices]

    def same_as(self, other: Attribute) -> bool:
        """Whether ``other`` holds the same name, domain, role, values (bit for bit) and indices."""
        return (
            self.name == other.name
            and self.domain == other.domain
            and self.role == other.role
            and self.values.dtype == other.values.dtype
            and self.values.shape == other.values.shape
            and self.values.tobytes() == other.values.tobytes()
            and (self.indices is None) == (other.indices is None)
            and (
                self.indices is None
                or (other.indices is not None and np.array_equal(self.indices, other.indices))
            )
        )

    def reordered_faces(self, faces: np.ndarray, order: np.ndarray) -> Attribute:
        """This attribute on the faces ``faces[order]`` (same corners, faces permuted)."""
        if self.domain == VERTEX:
            return self
        if self.domain == FACE:
            picked = order
        else:  # each face's corners, faces in the new order
            starts = face_corner_starts(faces)
            degrees = (starts[1:] - starts[:-1])[order]
            offsets = np.arange(int(degrees.sum())) - np.repeat(
                np.cumsum(degrees) - degrees, degrees
            )
            picked = np.repeat(starts[:-1][order], degrees) + offsets
        if self.indices is not None:
            return Attribute(self.name, self.domain, self.values, self.indices[picked], self.role)
        return Attribute(self.name, self.domain, self.values[picked], None, self.role)


@dataclass(eq=False)
class FaceSet:
    """A named set of faces: a material's faces, an OBJ group, a GeomSubset.

    Attributes:
        name: the set's name (unique within its family).
        faces: the face numbers, strictly increasing int64.
        family: :data:`MATERIAL_FAMILY`, :data:`GROUP_FAMILY`, or any other family name, or
            ``""``.
    """

    name: str
    faces: np.ndarray = field(repr=False)
    family: str = ""

    def __post_init__(self) -> None:
        self.name = checked_name(self.name, "a face set")
        if self.family:
            self.family = checked_name(self.family, f"face set {self.name!r}'s family")
        faces = np.asarray(self.faces)
        if faces.size == 0:
            faces = np.zeros(0, dtype=np.int64)
        if faces.ndim != 1 or not np.issubdtype(faces.dtype, np.integer):
            raise InputError(f"face set {self.name!r}: faces must be a list of face numbers")
        faces = np.ascontiguousarray(faces, dtype=np.int64)
        if faces.size and (faces[0] < 0 or np.any(np.diff(faces) <= 0)):
            faces = np.unique(faces)
            if faces[0] < 0:
                raise InputError(f"face set {self.name!r}: face {int(faces[0])} is negative")
        self.faces = faces

    def same_as(self, other: FaceSet) -> bool:
        """Whether ``other`` has the same name, family and faces."""
        return (
            self.name == other.name
            and self.family == other.family
            and np.array_equal(self.faces, other.faces)
        )


@dataclass(eq=False)
class Field:
    """An animated field: c values per vertex (or face) per frame, compressed with the positions.

    Attributes:
        name: unique among the sequence's fields (``velocities``, ``pressure``...).
        values: (F, N, c) float32 or float64, N the vertex (or face) count, c in 1..4; finite.
        domain: ``vertex`` or ``face``.
        role: ``velocity``, ``color`` or ``generic`` (:data:`FIELD_ROLES`).
    """

    name: str
    values: np.ndarray = field(repr=False)
    domain: str = VERTEX
    role: str = GENERIC

    def __post_init__(self) -> None:
        self.name = checked_name(self.name, "a field")
        label = f"field {self.name!r}"
        if self.domain not in FIELD_DOMAINS:
            raise InputError(f"{label}: domain must be vertex or face, got {self.domain!r}")
        if self.role not in FIELD_ROLES:
            raise InputError(
                f"{label}: role must be one of {', '.join(FIELD_ROLES)}, got {self.role!r}"
            )
        values = np.asarray(self.values)
        if values.ndim == 2:
            values = values[:, :, None]
        if values.ndim != 3 or not 1 <= values.shape[2] <= 4:
            raise InputError(
                f"{label}: values must have shape (frames, elements, 1 to 4), got {values.shape}"
            )
        if values.dtype.newbyteorder("=") not in FIELD_TYPES:
            if not np.issubdtype(values.dtype, np.number) or np.iscomplexobj(values):
                raise InputError(f"{label}: values must be real numbers, got {values.dtype}")
            values = values.astype(np.float64)
        self.values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
        bad = ~np.isfinite(self.values)
        if bad.any():
            f, e, _ = np.argwhere(bad)[0]
            raise InputError(
                f"{label}: {self.domain} {int(e)} has a non-finite value", frame=int(f)
            )

    @property
    def components(self) -> int:
        """c, the values' components."""
        return int(self.values.shape[2])


def check_attached(
    attributes: Sequence[Attribute],
    face_sets: Sequence[FaceSet],
    fields: Sequence[Field],
    frame_count: int,
    vertex_count: int,
    faces: np.ndarray,
) -> None:
    """Check that every attribute, face set and field fits the mesh (element counts, face
    numbers, frame counts) and that names are unique; an InputError names the one at fault."""
    _unique((a.name for a in attributes), "attribute")
    _unique((f.name for f in fields), "field")
    _unique((f"{s.family}/{s.name}" for s in face_sets), "face set (in its family)")
    for attribute in attributes:
        expected = element_count(attribute.domain, vertex_count, faces)
        if attribute.element_count != expected:
            raise InputError(
                f"attribute {attribute.name!r} has {attribute.element_count} "
                f"{attribute.domain} values, the mesh has {expected} {attribute.domain}s"
            )
    face_count = int(np.asarray(faces).shape[0])
    for face_set in face_sets:
        if face_set.faces.size and face_set.faces[-1] >= face_count:
            raise InputError(
                f"face set {face_set.name!r} names face {int(face_set.faces[-1])}, "
                f"the mesh has {face_count} faces"
            )
    for item in fields:
        expected = element_count(item.domain, vertex_count, faces)
        if item.values.shape[:2] != (frame_count, expected):
            raise InputError(
                f"field {item.name!r} has shape {item.values.shape[:2]} (frames, {item.domain}s), "
                f"the sequence has {frame_count} frames of {expected} {item.domain}s"
            )


def _unique(names: Iterable[str], what: str) -> None:
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise InputError(f"two of the sequence's {what}s are named {name!r}")
        seen.add(name)
