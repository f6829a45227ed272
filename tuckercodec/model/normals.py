"""Normals of a frame recomputed in the layout of a stored normal attribute, and the angle
between two sets of normals.

A mesh's authored normals are kept as one static attribute (frame 0's values); a writer of an
animated mesh writes each frame's normals recomputed from that frame's positions
(:func:`recomputed_normals`) with the stored attribute's split structure, so that hard edges
stay hard and smooth ones smooth:

* corner domain, indexed (OBJ ``vn``, USD indexed ``faceVarying``): the corners that share a
  normal row are smoothed together; corners of one vertex that use different rows keep a
  crease between them;
* corner domain, not indexed (USD ``faceVarying`` normals without indices): each corner has
  its own row, so the corners of one vertex whose stored normals are equal (bit for bit) are
  smoothed together, and corners whose stored normals differ keep their crease; this is what
  the indexed case does once equal values share a row;
* vertex domain: per vertex (indexed: the vertices that share a row together);
* face domain: the face's own normal (indexed: the faces that share a row together).

Faces weigh by their area (the sum of a polygon's fan triangles' cross products is twice its
area along its normal), the weighting most tools use. A row whose faces add up to nothing
(degenerate faces, or a row no element uses) keeps its stored value.
"""

from __future__ import annotations

import numpy as np

from .attributes import CORNER, FACE, VERTEX, Attribute, corner_faces, corner_vertices


def face_area_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(M, 3) float64: each face's normal scaled by twice its area (padded polygons allowed;
    a polygon is summed as the fan of triangles from its first corner)."""
    points = np.asarray(positions, dtype=np.float64)
    table = np.asarray(faces)
    normals = np.zeros((table.shape[0], 3), dtype=np.float64)
    if table.shape[0] == 0:
        return normals
    first = points[table[:, 0]]
    for corner in range(1, table.shape[1] - 1):
        second, third = table[:, corner], table[:, corner + 1]
        present = third >= 0  # padding (-1) ends a shorter polygon
        cross = np.cross(points[second] - first, points[third] - first)
        normals += np.where(present[:, None], cross, 0.0)
    return normals


def recomputed_normals(
    positions: np.ndarray, faces: np.ndarray, attribute: Attribute
) -> np.ndarray:
    """The normals of ``positions`` (K, 3) on ``faces`` in the layout of ``attribute`` (a
    normal attribute of the same mesh): an array shaped like ``attribute.values``, of its
    dtype when that is a float (float64 for int32 values), each row the normalised,
    area-weighted sum of the normals of the faces around the elements that use it (the module
    says how each domain groups them).

    Raises:
        ValueError: ``attribute`` does not have 3 components or does not fit the mesh.
    """
    table = np.asarray(faces)
    stored = attribute.values
    if stored.shape[1] != 3:
        raise ValueError(f"attribute {attribute.name!r} has {stored.shape[1]} components, not 3")
    dtype = stored.dtype if stored.dtype.kind == "f" else np.dtype(np.float64)
    per_face = face_area_normals(positions, table)
    if attribute.domain == FACE:
        element_normals = per_face
    elif attribute.domain == VERTEX:
        corners = corner_vertices(table)
        element_normals = _summed(per_face[corner_faces(table)], corners, len(positions))
    else:
        element_normals = per_face[corner_faces(table)]
    if attribute.element_count != len(element_normals):
        raise ValueError(
            f"attribute {attribute.name!r} has {attribute.element_count} {attribute.domain} "
            f"values, the mesh has {len(element_normals)}"
        )
    if attribute.indices is not None:
        # every stored row, also those past the largest index (they keep their value)
        rows, count = attribute.indices, len(stored)
    elif attribute.domain == CORNER:
        rows = _smoothing_groups(corner_vertices(table), stored)
        count = int(rows.max(initial=-1)) + 1
    else:
        rows, count = np.arange(len(element_normals)), len(element_normals)
    sums = _summed(element_normals, rows, count)
    if attribute.indices is None and attribute.domain == CORNER:
        sums = sums[rows]  # back from the smoothing groups to one row per corner
    lengths = np.linalg.norm(sums, axis=1)
    usable = lengths > 0
    result = stored.astype(np.float64)
    result[usable] = sums[usable] / lengths[usable, None]
    return result.astype(dtype)


def _summed(values: np.ndarray, rows: np.ndarray, count: int) -> np.ndarray:
    """(count, 3): the sum of the ``values`` of each row number of ``rows``."""
    sums = np.zeros((count, 3), dtype=np.float64)
    for axis in range(3):
        sums[:, axis] = np.bincount(rows, weights=values[:, axis], minlength=count)[:count]
    return sums


def _smoothing_groups(vertices: np.ndarray, stored: np.ndarray) -> np.ndarray:
    """A group number per corner: corners of the same vertex with bit-identical stored
    normals share one."""
    bits = np.ascontiguousarray(stored.astype(np.float64)).view(np.int64)
    keys = np.column_stack([vertices, bits])
    _, groups = np.unique(keys, axis=0, return_inverse=True)
    return groups.reshape(-1).astype(np.int64)


def angle_error_degrees(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The angle in degrees between each row of ``a`` and the same row of ``b`` ((N, 3)
    each), 0 to 180; NaN where either row has zero length (no direction to compare)."""
    first = np.asarray(a, dtype=np.float64)
    second = np.asarray(b, dtype=np.float64)
    if first.shape != second.shape or first.ndim != 2 or first.shape[1] != 3:
        raise ValueError(
            f"two (N, 3) arrays of the same shape needed, got {first.shape}, {second.shape}"
        )
    # atan2 of |a x b| and a . b: accurate for small angles too, where acos is not
    sines = np.linalg.norm(np.cross(first, second), axis=1)
    cosines = np.einsum("ij,ij->i", first, second)
    angles = np.degrees(np.arctan2(sines, cosines))
    degenerate = (np.linalg.norm(first, axis=1) == 0) | (np.linalg.norm(second, axis=1) == 0)
    angles[degenerate] = np.nan
    return angles
