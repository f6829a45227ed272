"""§6.10 Section ORDER (codec ``face-order``, format 1.5): the faces' order as given.

faces-traverse (§6.8) returns the faces in the order of its walk. A file whose faces carry data
(UVs per corner, a material per face) keeps the order the faces were given in, so that the
data line up with them and with the original topology: ORDER stores, for the t-th face of the
walk, its number in the given order. The permutation is coded as the differences of consecutive
numbers, less one (the walk mostly moves to the next face of the input), as §6.1's integers.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import FormatError
from . import streams

SECTION_ID = "ORDER"
CODEC = "face-order"


def encode_face_order(order: np.ndarray, level: int) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of ORDER for ``order[t]``, the given number of walked face t."""
    numbers = np.asarray(order, dtype=np.int64)
    steps = np.diff(numbers, prepend=np.int64(-1)) - 1
    payload, planes = streams.pack_integers(steps, level)
    return {"faces": int(numbers.size), "planes": planes}, payload


def decode_face_order(
    payload: bytes | memoryview, params: Mapping[str, Any], face_count: int, where: str
) -> np.ndarray:
    """The given number of each decoded face: a permutation of ``0..face_count-1`` (R42)."""
    faces = params.get("faces")
    if not isinstance(faces, int) or isinstance(faces, bool) or faces != face_count:
        raise FormatError(
            f"faces must be the FACE section's {face_count} faces, got {faces!r}",
            rule="R42-face-order",
            field=f"{where}.faces",
        )
    planes = streams.checked_planes(params, where)
    steps = streams.unpack_integers(payload, face_count, planes, where)
    order = np.cumsum(steps + 1) - 1
    if face_count and (order.min() < 0 or order.max() >= face_count):
        bad = int(np.flatnonzero((order < 0) | (order >= face_count))[0])
        raise FormatError(
            f"face {bad} of the walk has the number {int(order[bad])}, outside 0..{face_count - 1}",
            rule="R42-face-order",
            field=where,
        )
    seen = np.zeros(face_count, dtype=bool)
    seen[order] = True
    if not seen.all():
        missing = int(np.flatnonzero(~seen)[0])
        raise FormatError(
            f"no face has the number {missing}: the numbers are not a permutation",
            rule="R42-face-order",
            field=where,
        )
    return order


def in_given_order(walked: np.ndarray, order: np.ndarray) -> np.ndarray:
    """The faces of the walk (``walked``, as FACE decodes them) put back in the given order."""
    given = np.empty_like(walked)
    given[order] = walked
    return given
