"""Simulation data arrays (VTK's point and cell data, XDMF's ``<Attribute>``s) as a sequence's
static attributes and animated fields, for the series formats that store one file or grid per
time step, and back.

Reading (:func:`plan_arrays`, from the first step's arrays, then :meth:`ArrayPlan.fields` per
range of steps):

* an array of 1 to 4 components per point (domain ``vertex``) or per face (``face``); one of
  more components is skipped, with a note in :attr:`ArrayPlan.skipped`;
* a float32 or float64 array is an animated :class:`~tuckercodec.model.attributes.Field`,
  its type kept, except a normal or a UV (the role the source gives it, or its name), which is a
  static :class:`~tuckercodec.model.attributes.Attribute` of the first step's values, bit for
  bit: the normals of a moving mesh change with it, and the model keeps the first frame's (a
  writer recomputes the others). Deciding that another array is constant would need every step
  at opening, so every other float array is a field;
* an integer array (ids, material numbers, boundary markers, VTK's unsigned char colours) is a
  static int32 attribute of the first step's values, and each later step read must repeat them
  (an InputError names the step and the array where one does not: such an array would be lost);
  one whose values int32 cannot hold is skipped, with a note;
* a name used twice (a point and a cell array both called ``pressure``) keeps the point array's
  name; the cell array's becomes ``pressure (cell)``, with a note.

Roles: the source's (VTK's active ``Normals``/``TCoords``, XDMF's ``AttributeType``, or the tag
this package's writers add, :data:`ROLE_TAG`), else by name: ``Normals``/``normals`` a normal,
``TCoords``, ``Texture Coordinates``, ``UV``, ``st`` a UV, ``Colors``/``colors`` (3 or 4
components) a colour, ``velocity``/``velocities``/``Velocity`` a velocity field.

Writing (:func:`arrays_to_write`): vertex- and face-domain attributes and fields as point and
cell arrays (indexed attributes expanded to one value per element), each tagged with its role
and whether it is static, so that reading back gives the same attributes and fields; what an
array per point or cell cannot hold (corner-domain attributes, face sets) is listed by
:func:`cannot_keep_arrays`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from ...errors import InputError
from ...model.attributes import (
    COLOR,
    CORNER,
    FACE,
    GENERIC,
    NORMAL,
    ROLE_COMPONENTS,
    UV,
    VELOCITY,
    VERTEX,
    Attribute,
    Field,
)
from ...model.sequence import MeshSequence

#: The XML attribute this package's writers add to an array: the role of the attribute or
#: field it holds (``uv``, ``normal``, ``color``, ``velocity``, ``generic``).
ROLE_TAG = "tuckercodec_role"
#: The XML attribute that marks an array of a static attribute (``"1"``), repeated per step.
STATIC_TAG = "tuckercodec_static"

_NAMED_ROLES = {
    "normals": NORMAL,
    "normal": NORMAL,
    "tcoords": UV,
    "texture coordinates": UV,
    "texturecoordinates": UV,
    "uv": UV,
    "uvs": UV,
    "st": UV,
    "colors": COLOR,
    "color": COLOR,
    "colours": COLOR,
    "velocity": VELOCITY,
    "velocities": VELOCITY,
}
_INT32 = np.iinfo(np.int32)


@dataclass(frozen=True)
class SourceArray:
    """One array of one step as the source holds it.

    Attributes:
        name: the source's name.
        domain: ``vertex`` (point data) or ``face`` (cell data, one row per face).
        values: (N, c) array of the source's type.
        role: the role the source gives it (``normal``, ``uv``, ``color``, ``velocity``,
            ``generic``), or ``None``.
        static: whether the source marks it as a static attribute repeated per step.
    """

    name: str
    domain: str
    values: np.ndarray
    role: str | None = None
    static: bool = False


@dataclass(frozen=True)
class FieldSource:
    """Where a field's rows are: the array ``source`` of ``domain`` in every step."""

    name: str
    source: str
    domain: str
    role: str
    dtype: np.dtype
    components: int


@dataclass
class ArrayPlan:
    """What the arrays of the first step become: static :attr:`attributes`, the
    :attr:`field_sources` read per step, the integer arrays every step must repeat
    (:attr:`repeated`, by (domain, source name)) and the notes of arrays left out
    (:attr:`skipped`)."""

    attributes: list[Attribute] = field(default_factory=list)
    field_sources: list[FieldSource] = field(default_factory=list)
    repeated: dict[tuple[str, str], np.ndarray] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)

    @property
    def field_names(self) -> list[str]:
        """The fields' names, in order."""
        return [item.name for item in self.field_sources]

    def wanted(self) -> set[tuple[str, str]]:
        """The (domain, source name) of the arrays of the fields."""
        return {(item.domain, item.source) for item in self.field_sources}

    def check_repeated(self, arrays: dict[tuple[str, str], np.ndarray]) -> None:
        """Check that a later step (its arrays by (domain, source name), at least those of
        :attr:`repeated`) repeats the first step's integer arrays; InputError (without path or
        frame) names the array."""
        for key, first in self.repeated.items():
            values = arrays.get(key)
            if values is None:
                raise InputError(f"has no {_what(*key)}, which the first step has")
            if values.shape != first.shape or not np.array_equal(values, first):
                raise InputError(
                    f"its {_what(*key)} differs from the first step's: an integer array is "
                    "kept as a static attribute, so it must be the same at every step (convert "
                    "it to floats to keep it as an animated field, or drop it)"
                )

    def step_rows(
        self, arrays: dict[tuple[str, str], np.ndarray], counts: dict[str, int]
    ) -> list[np.ndarray]:
        """One step's rows of each field (in :attr:`field_sources`' order), checked; ``arrays``
        by (domain, source name), ``counts`` the elements per domain. InputError (without path
        or frame) names the array."""
        rows = []
        for item in self.field_sources:
            values = arrays.get((item.domain, item.source))
            label = _what(item.domain, item.source)
            if values is None:
                raise InputError(f"has no {label}, which the first step has")
            if values.dtype != item.dtype or values.shape != (counts[item.domain], item.components):
                raise InputError(
                    f"its {label} is {values.dtype} of shape {values.shape}; the first step's is "
                    f"{item.dtype} of shape {(counts[item.domain], item.components)}"
                )
            bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
            if bad.size:
                raise InputError(
                    f"its {label} has a non-finite value at {item.domain} {int(bad[0])}"
                )
            rows.append(values)
        return rows

    def fields(self, steps: list[list[np.ndarray]]) -> list[Field]:
        """The fields of consecutive steps' rows (:meth:`step_rows`)."""
        return [
            Field(item.name, np.stack([rows[number] for rows in steps]), item.domain, item.role)
            for number, item in enumerate(self.field_sources)
        ]


def _what(domain: str, name: str) -> str:
    return f"{'point' if domain == VERTEX else 'cell'} array {name!r}"


def named_role(name: str) -> str | None:
    """The role an array's name suggests (``Normals``: normal...), or ``None``."""
    return _NAMED_ROLES.get(name.strip().lower())


def plan_arrays(arrays: Iterable[SourceArray]) -> ArrayPlan:
    """What the first step's arrays become (see the module docstring)."""
    plan = ArrayPlan()
    taken: dict[str, set[str]] = {"attribute": set(), "field": set()}
    for array in sorted(arrays, key=lambda item: item.domain != VERTEX):  # point arrays first
        label = _what(array.domain, array.name)
        values = array.values
        components = values.shape[1]
        if not 1 <= components <= 4:
            plan.skipped.append(f"{label}: {components} components (1 to 4 are kept)")
            continue
        role = array.role or named_role(array.name) or GENERIC
        allowed: tuple[str, ...]
        if values.dtype.kind == "f" and values.dtype.itemsize in (4, 8):
            static = array.static or role in (NORMAL, UV)
            kind = "attribute" if static else "field"
            allowed = (NORMAL, UV, COLOR, GENERIC) if static else (VELOCITY, COLOR, GENERIC)
        elif values.dtype.kind in "iu":
            if values.size and (values.min() < _INT32.min or values.max() > _INT32.max):
                plan.skipped.append(f"{label}: {values.dtype} values beyond int32")
                continue
            values = values.astype(np.int32)
            kind, allowed = "attribute", (COLOR, GENERIC)
        else:
            plan.skipped.append(f"{label}: {values.dtype} values (numbers are kept)")
            continue
        if role not in allowed or components not in ROLE_COMPONENTS.get(role, (1, 2, 3, 4)):
            role = GENERIC
        name = _unique_name(array.name, array.domain, taken[kind], plan.skipped, label)
        if kind == "field":
            plan.field_sources.append(
                FieldSource(name, array.name, array.domain, role, values.dtype, components)
            )
            continue
        plan.attributes.append(Attribute(name, array.domain, values, None, role))
        if values.dtype.kind != "f" and not array.static:
            plan.repeated[array.domain, array.name] = array.values
    return plan


def _unique_name(name: str, domain: str, taken: set[str], notes: list[str], label: str) -> str:
    """``name``, or ``name (cell)`` (then numbered) when a point array has it already."""
    unique = name
    number = 1
    while unique in taken:
        unique = f"{name} (cell)" if number == 1 else f"{name} (cell {number})"
        number += 1
    if unique != name:
        notes.append(f"{label}: named {unique!r}, a point array has its name")
    taken.add(unique)
    return unique


# ------------------------------------------------------------------------------------------
# writing


@dataclass(frozen=True)
class TargetArray:
    """One array to write at every step: a static attribute's values (``rows`` None) or a
    field's (``rows``: (F, N, c))."""

    name: str
    domain: str
    role: str
    values: np.ndarray | None
    rows: np.ndarray | None

    @property
    def static(self) -> bool:
        """Whether it is a static attribute's, repeated per step."""
        return self.rows is None

    def at(self, frame: int) -> np.ndarray:
        """Its (N, c) values at ``frame``."""
        if self.rows is not None:
            return self.rows[frame]
        assert self.values is not None
        return self.values


def arrays_to_write(seq: MeshSequence) -> list[TargetArray]:
    """The vertex- and face-domain attributes (indexed ones expanded) and the fields of
    ``seq`` as arrays per step; corner-domain attributes are left out
    (:func:`cannot_keep_arrays` names them). Two arrays of one domain named alike are an
    InputError: a file holds one array per name."""
    targets: list[TargetArray] = []
    faceless = len(seq.faces) == 0  # a point sequence's file has a vertex cell per point
    for attribute in seq.attributes:
        if attribute.domain == VERTEX or (attribute.domain == FACE and not faceless):
            values = attribute.element_values()
            targets.append(
                TargetArray(attribute.name, attribute.domain, attribute.role, values, None)
            )
    targets.extend(
        TargetArray(item.name, item.domain, item.role, None, item.values)
        for item in seq.fields
        if item.domain == VERTEX or not faceless
    )
    seen: set[tuple[str, str]] = set()
    for target in targets:
        if (target.domain, target.name) in seen:
            raise InputError(
                f"an attribute and a field are both named {target.name!r} on the "
                f"{target.domain}s: a file holds one {_what(target.domain, target.name)}"
            )
        seen.add((target.domain, target.name))
    return targets


def cannot_keep_arrays(seq: MeshSequence) -> list[str]:
    """What a series of point and cell arrays cannot keep of ``seq``: corner-domain
    attributes, the index structure of indexed attributes (written one value per element)
    and face sets."""
    lost = []
    faceless = len(seq.faces) == 0
    for attribute in seq.attributes:
        if attribute.domain == CORNER:
            lost.append(f"attribute {attribute.name!r}: per face corner")
        elif attribute.domain == FACE and faceless:
            lost.append(f"attribute {attribute.name!r}: per face, of a mesh without faces")
        elif attribute.indices is not None:
            lost.append(
                f"attribute {attribute.name!r}: its indices (written one value per "
                f"{attribute.domain})"
            )
    lost.extend(
        f"field {item.name!r}: per face, of a mesh without faces"
        for item in seq.fields
        if item.domain == FACE and faceless
    )
    lost.extend(
        f"face set {face_set.name!r}" + (f" ({face_set.family})" if face_set.family else "")
        for face_set in seq.face_sets
    )
    return lost
