"""Normals recomputed from a frame's positions with the split structure of the authored ones, for
the frames of an animated mesh after the first (the first keeps its authored normals).

Each face's normal is its area vector (Newell's formula, which polygons share with triangles);
the corners that share a normal in the authored attribute (the same vertex for a per-vertex
normal, the same index for an indexed one, the same vertex and value for a per-corner one, the
same face for a per-face one) get the unit sum of their faces' area vectors, so hard edges stay
hard. Where that sum is zero (degenerate faces) the authored normal is kept.

This is the writer's own until the shared ``tuckercodec.model.normals.recomputed_normals``
exists; it answers per corner, the layout the glTF writer needs.
"""

from __future__ import annotations

import numpy as np

from ...model.attributes import CORNER, FACE, VERTEX, Attribute, corner_faces, corner_vertices


def face_area_vectors(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each face's area vector (M, 3): its normal times its area (Newell)."""
    faces = np.asarray(faces)
    total = np.zeros((faces.shape[0], 3))
    first = faces[:, 0]
    for column in range(faces.shape[1]):
        here = faces[:, column]
        following = faces[:, column + 1] if column + 1 < faces.shape[1] else first
        following = np.where(following >= 0, following, first)  # the row's end wraps to 0
        real = here >= 0
        total[real] += np.cross(positions[here[real]], positions[following[real]])
    return total / 2


def recomputed_corner_normals(
    positions: np.ndarray, faces: np.ndarray, attribute: Attribute
) -> np.ndarray:
    """The normals of ``positions`` (K, 3) at every corner (C, 3), float64, smoothed over the
    corners that share a normal in ``attribute`` (module docstring)."""
    corners = corner_vertices(faces)
    face_of = corner_faces(faces)
    authored = attribute.element_values().astype(np.float64)
    if attribute.domain == VERTEX:
        groups = corners
        fallback = authored[corners]
    elif attribute.domain == FACE:
        groups = face_of
        fallback = authored[face_of]
    else:
        assert attribute.domain == CORNER
        fallback = authored
        if attribute.indices is not None:
            groups = attribute.indices
        else:
            keyed = np.column_stack([corners, _row_ids(attribute.values)])
            groups = np.unique(keyed, axis=0, return_inverse=True)[1].reshape(-1)
    area = face_area_vectors(positions, faces)
    sums = np.zeros((int(groups.max(initial=-1)) + 1, 3))
    np.add.at(sums, groups, area[face_of])
    per_corner = sums[groups]
    length = np.linalg.norm(per_corner, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = per_corner / length
    return np.where(length > 0, unit, fallback)


def _row_ids(values: np.ndarray) -> np.ndarray:
    values = np.ascontiguousarray(values)
    rows = values.view(np.dtype((np.void, values.dtype.itemsize * values.shape[1]))).reshape(-1)
    return np.unique(rows, return_inverse=True)[1].reshape(-1)
