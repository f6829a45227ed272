"""The faces section: codec ``faces-delta`` of ``spec/FORMAT.md`` §6.4.

Faces are stored once for the whole sequence, as the (M, n) index array with 0-based vertex
indices and -1 padding. Each entry plus one (so padding is 0) is taken in row-major order and
replaced by its difference from the entry before it; consecutive indices in a mesh are close,
so the differences are small. On the shared sequences this is 13-45 % smaller than zstd on the
plain int32 triangle list (horse gallop: 0.61 instead of 1.11 bpfv).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import streams
from .errors import FormatError

CODEC = "faces-delta"


def encode_faces(faces: np.ndarray, level: int = streams.DEFAULT_LEVEL) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the FACE section."""
    faces = np.asarray(faces, dtype=np.int64)
    shifted = (faces + 1).reshape(-1)
    deltas = np.diff(shifted, prepend=np.int64(0))
    payload, planes = streams.pack_integers(deltas, level)
    return {"shape": [int(faces.shape[0]), int(faces.shape[1])], "planes": planes}, payload


def decode_faces(payload: bytes | memoryview, params: dict[str, Any], vertex_count: int, where: str) -> np.ndarray:
    """The (M, n) faces of a FACE section, every index checked (§6.4). The caller has checked
    ``shape`` against the limits."""
    count, width = params["shape"]
    planes = params.get("planes")
    if not isinstance(planes, int) or isinstance(planes, bool) or not 1 <= planes <= streams.MAX_PLANES:
        raise FormatError(f"planes must be 1..{streams.MAX_PLANES}, got {planes!r}", field=f"{where}.planes")
    deltas = streams.unpack_integers(payload, count * width, planes, where)
    shifted = np.cumsum(deltas)
    if shifted.size and (shifted.min() < 0 or shifted.max() > vertex_count):
        position = int(np.flatnonzero((shifted < 0) | (shifted > vertex_count))[0])
        raise FormatError(
            f"face {position // width} has a vertex index {int(shifted[position]) - 1} outside "
            f"0..{vertex_count - 1}",
            field=where,
        )
    faces = (shifted - 1).reshape(count, width)
    padded = faces < 0
    if padded.any():
        misplaced = (padded[:, :-1] & ~padded[:, 1:]).any(axis=1) | ((~padded).sum(axis=1) < 3)
        if misplaced.any():
            row = int(np.flatnonzero(misplaced)[0])
            raise FormatError(
                f"face {row} is padded before its end or has fewer than 3 corners: "
                f"{faces[row].tolist()}",
                field=where,
            )
    return faces
