"""Corner and face values on a format without them: glTF's vertices are the tuples of all their
attributes, so a vertex whose corners hold different UVs (a seam) or whose faces hold different
values becomes one written vertex per distinct combination, each with the vertex's positions.

:func:`split_vertices` finds the written vertices; :class:`SplitLayout` maps any attribute onto
them and gives the faces in their numbers. Written vertices keep the order of the vertices they
copy (a vertex's copies side by side), so a mesh without corner or face values is unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ...model.attributes import CORNER, FACE, VERTEX, Attribute, corner_faces, corner_vertices


@dataclass
class SplitLayout:
    """The written vertices of a mesh.

    Attributes:
        vertex_of: (K',) the vertex each written vertex copies.
        first_corner: (K',) one corner of each written vertex (corner order), -1 for a vertex
            no face uses.
        faces: the face table (M, n) in written vertex numbers (padding kept).
    """

    vertex_of: np.ndarray
    first_corner: np.ndarray
    faces: np.ndarray

    @property
    def count(self) -> int:
        """K', the number of written vertices."""
        return int(self.vertex_of.size)

    def expanded(self, attribute: Attribute, source_faces: np.ndarray) -> np.ndarray:
        """``attribute``'s value at each written vertex, (K', c): its vertex's, or its corners'
        (which are all the same, that is why they were split); zeros on a vertex no face uses
        where the attribute is per corner or per face."""
        values = attribute.element_values()
        if attribute.domain == VERTEX:
            return values[self.vertex_of]
        used = self.first_corner >= 0
        corners = self.first_corner[used]
        if attribute.domain == FACE:
            corners = corner_faces(source_faces)[corners]
        result = np.zeros((self.count, values.shape[1]), dtype=values.dtype)
        result[used] = values[corners]
        return result

    def corner_expanded(self, per_corner: np.ndarray, per_vertex: np.ndarray) -> np.ndarray:
        """Values given per corner (C, c) at each written vertex, ``per_vertex`` (K, c)'s value
        of its vertex where no face uses it."""
        used = self.first_corner >= 0
        result = np.asarray(per_vertex)[self.vertex_of].astype(per_corner.dtype)
        result[used] = per_corner[self.first_corner[used]]
        return result


def split_vertices(
    faces: np.ndarray, vertex_count: int, attributes: Sequence[Attribute]
) -> SplitLayout:
    """The written vertices of a mesh of ``vertex_count`` vertices and ``faces`` whose corner
    and face ``attributes`` must each have one value per written vertex."""
    faces = np.asarray(faces)
    splitting = [a for a in attributes if a.domain in (CORNER, FACE)]
    corners = corner_vertices(faces)
    if not splitting:
        first = np.full(vertex_count, -1, dtype=np.int64)
        first[corners[::-1]] = np.arange(corners.size, dtype=np.int64)[::-1]
        return SplitLayout(np.arange(vertex_count, dtype=np.int64), first, faces.copy())
    face_of = corner_faces(faces)
    columns = [corners]
    for attribute in splitting:
        ids = _value_ids(attribute)
        columns.append(ids if attribute.domain == CORNER else ids[face_of])
    unused = np.setdiff1d(np.arange(vertex_count), corners)
    keys = np.concatenate(
        [
            np.stack(columns, axis=1),
            np.column_stack([unused, np.full((unused.size, len(splitting)), -1)]),
        ]
    ).astype(np.int64)
    unique, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    first = np.where(first < corners.size, first, -1)
    written = faces.copy()
    written[written >= 0] = inverse.reshape(-1)[: corners.size]
    return SplitLayout(np.ascontiguousarray(unique[:, 0]), first.astype(np.int64), written)


def _value_ids(attribute: Attribute) -> np.ndarray:
    """One id per element, equal where the values are (bit for bit; an indexed attribute's
    elements by their index)."""
    if attribute.indices is not None:
        return attribute.indices
    values = np.ascontiguousarray(attribute.values)
    rows = values.view(np.dtype((np.void, values.dtype.itemsize * values.shape[1]))).reshape(-1)
    return np.unique(rows, return_inverse=True)[1].reshape(-1).astype(np.int64)
