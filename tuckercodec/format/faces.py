"""§6.4 Codec ``faces-delta``: the connectivity, stored once for the whole sequence; and the
choice between it and §6.8's ``faces-traverse`` (:mod:`.traversal`).

The faces are the (M, n) index array with 0-based vertex indices and -1 padding. Each entry plus
one (so padding is 0) is taken in row-major order and replaced by its difference from the entry
before it; consecutive indices in a mesh are close, so the differences are small. On the shared
sequences this is 13-45 % smaller than zstd on the plain int32 triangle list (horse gallop: 0.61
instead of 1.11 bpfv).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np

from ..errors import FormatError
from ..model.topology import face_table_problem
from . import streams
from .face_order import encode_face_order
from .limits import DEFAULT_LIMITS, Limits
from .sections import FACES_DELTA, FACES_TRAVERSE, section_shape
from .traversal import decode_traversal, encode_traversal_ordered


class FaceSection(NamedTuple):
    """A coded FACE section, and the faces a decoder gives back from it."""

    codec: str
    params: dict[str, Any]
    payload: bytes
    faces: np.ndarray


def encode_face_section(
    faces: np.ndarray,
    vertex_count: int,
    level: int = streams.DEFAULT_LEVEL,
    *,
    adaptive_coding: bool = False,
) -> FaceSection:
    """The smaller of faces-traverse (format 1.2, the face order becomes the walk's; with
    ``adaptive_coding``, its streams may use the adaptive coder of format 1.6) and faces-delta
    (format 1.0, faces as given). Either way every face keeps its corners, their order and its
    orientation."""
    section, _, _ = encode_face_sections(
        faces, vertex_count, level, keep_order=False, adaptive_coding=adaptive_coding
    )
    return section


def encode_face_sections(
    faces: np.ndarray,
    vertex_count: int,
    level: int,
    *,
    keep_order: bool,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
    traverse: bool = True,
) -> tuple[FaceSection, tuple[dict[str, Any], bytes] | None, np.ndarray | None]:
    """The FACE section; when ``keep_order`` asks for the faces as given and the walk is
    chosen, the ORDER section that restores their order (format 1.5, §6.10): the smaller
    of faces-delta alone and faces-traverse with ORDER; and when the walk is chosen, its
    order (the given number of each walked face). ``adaptive_coding``: the file may be of
    format 1.6 (flag bit 3), so that the walk's streams may use the adaptive coder;
    ``uniform_ranks``: of format 1.9 (flag bit 6), so that its new vertices may be a uniform
    stream. ``traverse``: the file may be of format 1.2, so that the walk may be chosen at all
    (otherwise faces-delta, the faces as given)."""
    table = np.asarray(faces, dtype=np.int64)
    delta_params, delta_payload = encode_faces(table, level)
    if not traverse:
        return FaceSection(FACES_DELTA, delta_params, delta_payload, table), None, None
    walk_params, walk_payload, walked, order = encode_traversal_ordered(
        table,
        vertex_count,
        level,
        adaptive_coding=adaptive_coding,
        uniform_ranks=uniform_ranks,
    )
    order_section = encode_face_order(order, level) if keep_order else None
    walk_size = len(walk_payload) + (0 if order_section is None else len(order_section[1]))
    if walk_size < len(delta_payload) and _walk_holds(
        walk_params, walk_payload, walked, table, vertex_count
    ):
        walk = FaceSection(FACES_TRAVERSE, walk_params, walk_payload, walked)
        return walk, order_section, order
    return FaceSection(FACES_DELTA, delta_params, delta_payload, table), None, None


def _walk_holds(
    params: dict[str, Any],
    payload: bytes,
    walked: np.ndarray,
    table: np.ndarray,
    vertex_count: int,
) -> bool:
    """Whether the walk decodes to the faces given (in its order), as §6.8 promises: checked
    once per encode, so that a walk the encoder got wrong costs size (faces-delta), never faces."""
    # the encoder writes coder 1 only where it may (a file of format 1.6), ranks 1 in 1.9
    decoded = decode_traversal(
        payload,
        params,
        vertex_count,
        "section FACE",
        adaptive_coding="coder" in params,
        uniform_ranks="ranks" in params,
    )
    same_rows = np.lexsort(decoded.T[::-1]), np.lexsort(table.T[::-1])
    return np.array_equal(decoded, walked) and np.array_equal(
        decoded[same_rows[0]], table[same_rows[1]]
    )


def decode_face_section(
    codec: str,
    payload: bytes | memoryview,
    params: Mapping[str, Any],
    vertex_count: int,
    where: str,
    limits: Limits = DEFAULT_LIMITS,
    *,
    adaptive_coding: bool = False,
    uniform_ranks: bool = False,
) -> np.ndarray:
    """The faces of a FACE section of either codec (the caller has checked that the codec is
    allowed in this file, and the shape against ``limits``). ``adaptive_coding``: the file sets
    flag bit 3, so that faces-traverse's ``coder`` may be 1 (§6.8); ``uniform_ranks``: flag bit
    6, so that its ``ranks`` may be 1."""
    if codec == FACES_TRAVERSE:
        return decode_traversal(
            payload,
            params,
            vertex_count,
            where,
            limits,
            adaptive_coding=adaptive_coding,
            uniform_ranks=uniform_ranks,
        )
    return decode_faces(payload, params, vertex_count, where)


def encode_faces(
    faces: np.ndarray, level: int = streams.DEFAULT_LEVEL
) -> tuple[dict[str, Any], bytes]:
    """``(params, payload)`` of the FACE section."""
    faces = np.asarray(faces, dtype=np.int64)
    shifted = (faces + 1).reshape(-1)
    deltas = np.diff(shifted, prepend=np.int64(0))
    payload, planes = streams.pack_integers(deltas, level)
    return {"shape": [int(faces.shape[0]), int(faces.shape[1])], "planes": planes}, payload


def decode_faces(
    payload: bytes | memoryview, params: Mapping[str, Any], vertex_count: int, where: str
) -> np.ndarray:
    """The (M, n) faces of a FACE section, every index checked (R33-face-index,
    R34-face-padding). The caller has checked ``shape`` against the limits."""
    count, width = section_shape(params, where, min_cols=3)
    planes = streams.checked_planes(params, where)
    deltas = streams.unpack_integers(payload, count * width, planes, where)
    faces = np.cumsum(deltas).reshape(count, width)
    faces -= 1
    problem = face_table_problem(faces, vertex_count)
    if problem is not None and problem.kind == "index":
        raise FormatError(problem.message, rule="R33-face-index", field=where)
    if problem is not None:
        raise FormatError(problem.message, rule="R34-face-padding", field=where)
    return faces
