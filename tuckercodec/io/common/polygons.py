"""Faces stored flat, as USD, Alembic and VTK store them (a count of corners per face and one
list of every face's corners), to and from the padded face table of
:class:`~tuckercodec.MeshSequence`, and the reversal of their winding.

The face table pads every face with -1 to the widest one, so one huge polygon among many
triangles would make it far larger than the file: it may hold at most :data:`PADDED_PER_CORNER`
entries per corner of the file, or :data:`PADDED_AT_LEAST` entries, whichever is more (the
OBJ reader's rule).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...errors import InputError

#: The face table may hold this many entries per corner of the file...
PADDED_PER_CORNER = 16
#: ...or this many (128 MiB of int64), whichever is more.
PADDED_AT_LEAST = 2**24


def faces_from_polygons(counts: object, indices: object, vertex_count: int) -> np.ndarray:
    """The (M, n) int64 face table, -1 padded, of faces given as corner ``counts`` and the
    flat list of their vertex ``indices``, in the file's order; (0, 3) when there are none.

    Raises :class:`InputError` (without a path: the caller adds it, and the object) for counts
    or indices that are not integers, a face of fewer than 3 corners, counts that do not add up
    to the number of indices, an index outside 0..K-1, or a table too large for the corners.
    """
    sizes, flat = np.asarray(counts), np.asarray(indices)
    for name, values in (("face counts", sizes), ("face indices", flat)):
        if values.ndim != 1 or (values.size and not np.issubdtype(values.dtype, np.integer)):
            raise InputError(
                f"{name} must be a list of integers, got dtype {values.dtype} shape {values.shape}"
            )
    if sizes.size == 0:
        if flat.size:
            raise InputError(f"there are {flat.size} face indices but no face counts")
        return np.zeros((0, 3), dtype=np.int64)
    small = np.flatnonzero(sizes < 3)
    if small.size:
        face = int(small[0])
        raise InputError(f"face {face} has {int(sizes[face])} corners; a face needs at least 3")
    widest = int(np.argmax(sizes))
    if sizes[widest] > flat.size:  # checked before the cast and the sum: neither can overflow
        raise InputError(
            f"face {widest} has {int(sizes[widest])} corners but there are only {flat.size} "
            "face indices"
        )
    sizes = sizes.astype(np.int64)
    total = int(sizes.sum())
    if total != flat.size:
        raise InputError(
            f"the face counts add up to {total} corners but there are {flat.size} face indices"
        )
    outside = np.flatnonzero((flat < 0) | (flat >= vertex_count))
    if outside.size:
        corner = int(outside[0])
        face = int(np.searchsorted(np.cumsum(sizes), corner, side="right"))
        raise InputError(
            f"face {face} has a vertex index {int(flat[corner])} outside 0..{vertex_count - 1}"
        )
    width = int(sizes[widest])
    if sizes.size * width > max(PADDED_AT_LEAST, PADDED_PER_CORNER * total):
        raise InputError(
            f"face {widest} has {width} corners: padding all {sizes.size} faces to its width "
            f"would take {sizes.size * width * 8 / 2**30:.1f} GiB; split the polygon"
        )
    flat = flat.astype(np.int64)
    if (sizes == width).all():
        return flat.reshape(sizes.size, width)
    table = np.full((sizes.size, width), -1, dtype=np.int64)
    table[np.arange(width) < sizes[:, np.newaxis]] = flat  # row by row: the file's order
    return table


def first_change(
    topology: Callable[[int], tuple[np.ndarray, np.ndarray]], frames: int, varying: bool
) -> tuple[tuple[np.ndarray, np.ndarray], int | None]:
    """Frame 0's corner counts and vertex indices (``topology(frame)`` reads a frame's), and
    the first frame whose differ from them, or ``None``: a sequence keeps one set of faces.
    Only frame 0 is read unless the file says they may be ``varying`` (USD and Alembic do)."""
    first = topology(0)
    for frame in range(1, frames if varying else 1):
        now = topology(frame)
        if not (np.array_equal(now[0], first[0]) and np.array_equal(now[1], first[1])):
            return first, frame
    return first, None


def polygons_from_faces(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The corner counts and flat vertex indices (both int32, as USD and Alembic store them)
    of a face table that follows the rule of :mod:`tuckercodec.model.topology`."""
    real = np.asarray(faces) >= 0
    counts = real.sum(axis=1).astype(np.int32)
    return counts, np.asarray(faces)[real].astype(np.int32)


def reverse_winding(faces: np.ndarray) -> np.ndarray:
    """Each face's corners in reverse order ([a, b, c, d] becomes [d, c, b, a]), padding kept
    at the end: what USD's Alembic plugin and Blender's Alembic importer do to turn a
    clockwise face counter-clockwise (and back: the reversal is its own inverse)."""
    table = np.asarray(faces)
    if table.size == 0:
        return table.copy()
    sizes = (table >= 0).sum(axis=1)
    source = sizes[:, np.newaxis] - 1 - np.arange(table.shape[1])
    real = source >= 0
    out = np.full_like(table, -1)
    rows = np.broadcast_to(np.arange(table.shape[0])[:, np.newaxis], table.shape)
    out[real] = table[rows[real], source[real]]
    return out


def reversed_corners(faces: np.ndarray) -> np.ndarray:
    """For each corner of ``faces`` (in corner order: the real entries in C order), the number
    of the same corner in ``reverse_winding(faces)``: face f's corner j of n is corner n-1-j of
    the reversed face. Per-corner values follow the faces with it (``values[order]``,
    ``indices[order]``); it is its own inverse, as the reversal is."""
    table = np.asarray(faces)
    degrees = (table >= 0).sum(axis=1).astype(np.int64)
    starts = np.zeros(degrees.size + 1, dtype=np.int64)
    np.cumsum(degrees, out=starts[1:])
    face_of = np.repeat(np.arange(degrees.size), degrees)
    local = np.arange(starts[-1], dtype=np.int64) - starts[face_of]
    return starts[face_of] + degrees[face_of] - 1 - local
