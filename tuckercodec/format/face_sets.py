"""§6.12 Section FSET (codec ``face-sets``, format 1.5): named sets of faces.

Materials, groups and GeomSubsets. Each set's face numbers (in the given order, §6.10) are
strictly increasing; the stream holds, set after set, the first number less the one after the
previous set's last, and then each number's difference from the one before less one: a
material's faces are usually a run, and materials follow each other, so a partition into runs
is a stream of zeros.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, NoReturn

import numpy as np

from ..errors import FormatError
from ..model.attributes import FaceSet
from . import streams
from .limits import Limits, check_limit

SECTION_ID = "FSET"
CODEC = "face-sets"


def encode_face_sets(sets: Sequence[FaceSet], level: int) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of FSET."""
    parts, following = [], 0
    for face_set in sets:
        parts.append(np.diff(face_set.faces, prepend=np.int64(following - 1)) - 1)
        if face_set.faces.size:
            following = int(face_set.faces[-1]) + 1
    stream = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)
    payload, planes = streams.pack_integers(stream, level)
    table = [[s.name, s.family, int(s.faces.size)] for s in sets]
    return {"sets": table, "planes": planes}, payload


def _refuse(message: str, field: str) -> NoReturn:
    raise FormatError(message, rule="R44-face-sets", field=field)


def _checked_table(
    params: Mapping[str, Any], face_count: int, limits: Limits, where: str
) -> list[tuple[str, str, int]]:
    table = params.get("sets")
    if not isinstance(table, list):
        _refuse(f"sets must be an array, got {type(table).__name__}", f"{where}.sets")
    check_limit(
        len(table), limits, "max_sections", what=f"{len(table)} face sets", field=f"{where}.sets"
    )
    checked = []
    for number, entry in enumerate(table):
        if (
            not isinstance(entry, list)
            or len(entry) != 3
            or not isinstance(entry[0], str)
            or not entry[0]
            or not isinstance(entry[1], str)
            or not isinstance(entry[2], int)
            or isinstance(entry[2], bool)
            or not 0 <= entry[2] <= face_count
        ):
            _refuse(
                f"set {number} must be [name, family, count 0..{face_count}], got {entry!r}",
                f"{where}.sets",
            )
        checked.append((entry[0], entry[1], entry[2]))
    return checked


def decode_face_sets(
    payload: bytes | memoryview,
    params: Mapping[str, Any],
    face_count: int,
    limits: Limits,
    where: str,
) -> list[FaceSet]:
    """The face sets of FSET, every number checked to be a face, each set's increasing (R44)."""
    table = _checked_table(params, face_count, limits, where)
    total = sum(count for _, _, count in table)
    check_limit(
        total * streams.MAX_PLANES,
        limits,
        "max_section_bytes",
        what=f"{total} face numbers",
        field=f"{where}.sets",
    )
    planes = streams.checked_planes(params, where)
    stream = streams.unpack_integers(payload, total, planes, where)
    sets, start, following = [], 0, 0
    named: set[tuple[str, str]] = set()
    for name, family, count in table:
        if (family, name) in named:
            _refuse(f"two sets of family {family!r} are named {name!r}", f"{where}.sets")
        named.add((family, name))
        steps = stream[start : start + count]
        start += count
        if count and steps[1:].min(initial=0) < 0:
            _refuse(f"set {name!r}: its face numbers do not increase", where)
        faces = np.cumsum(steps + 1) - 1 + following
        if count and not 0 <= faces[0] <= faces[-1] < face_count:
            _refuse(f"set {name!r} names a face outside 0..{face_count - 1}", where)
        if count:
            following = int(faces[-1]) + 1
        try:
            sets.append(FaceSet(name, faces, family))
        except ValueError as error:  # InputError: a name the model refuses
            _refuse(f"set {name!r}: {error}", where)
    return sets
