"""Each corner's normal recomputed from a frame's positions, for the frames of an animated mesh
after the first (the first keeps its authored normals): the shared
:func:`~tuckercodec.model.normals.recomputed_normals` expanded to one row per corner, the
layout the glTF writers need (a written vertex is a corner's).

glTF writes a normal per written vertex, so it is not held to the authored rows: the attribute
is given one row per element first (its indices resolved). A vertex's normal is then smoothed
over its own faces, a face's is its own, and a corner's over the corners of its vertex with the
same authored value (the hard edges), rather than over every element that happened to share a
row of equal values.
"""

from __future__ import annotations

import numpy as np

from ...model.attributes import FACE, VERTEX, Attribute, corner_faces, corner_vertices
from ...model.normals import recomputed_normals


def recomputed_corner_normals(
    positions: np.ndarray, faces: np.ndarray, attribute: Attribute
) -> np.ndarray:
    """The normals of ``positions`` (K, 3) at every corner (C, 3), float64, smoothed as the
    module docstring says; a corner whose faces have no area keeps its authored normal."""
    # float64 rows: the result keeps that precision; equal float32 values stay equal
    own_rows = Attribute(
        attribute.name,
        attribute.domain,
        attribute.element_values().astype(np.float64),
        role=attribute.role,
    )
    values = recomputed_normals(positions, faces, own_rows)
    if attribute.domain == VERTEX:
        return values[corner_vertices(faces)]
    if attribute.domain == FACE:
        return values[corner_faces(faces)]
    return values
