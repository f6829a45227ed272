"""Normals recomputed in the layout of a stored normal attribute (tuckercodec/model/normals.py):
hard edges stay hard and smooth ones smooth in every domain, the stored dtype is kept, and the
angle between normals is measured accurately."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec.model.attributes import Attribute
from tuckercodec.model.normals import angle_error_degrees, face_area_normals, recomputed_normals

# A unit cube of 6 quads, outward-facing (counter-clockwise seen from outside).
CUBE = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float64,
)
CUBE_FACES = np.array(
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 4, 7, 3]]
)
CUBE_AXES = np.array([[0, 0, -1], [0, 0, 1], [0, -1, 0], [0, 1, 0], [1, 0, 0], [-1, 0, 0]], float)
# An octahedron: every vertex's faces are symmetric about its direction from the centre.
OCTAHEDRON = np.array(
    [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
)
OCTAHEDRON_FACES = np.array(
    [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
)


def rotation(angle: float) -> np.ndarray:
    """A rotation about the axis (1, 1, 1)."""
    axis = np.ones(3) / np.sqrt(3)
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def test_face_area_normals_are_twice_the_area_along_the_normal() -> None:
    normals = face_area_normals(CUBE * 2, CUBE_FACES)  # faces of area 4
    np.testing.assert_allclose(normals, CUBE_AXES * 8)
    padded = np.array([[0, 1, 2, -1], [0, 3, 2, 1]])
    np.testing.assert_allclose(face_area_normals(CUBE, padded)[0], [0, 0, 1])  # area 1/2


def test_hard_edges_of_an_indexed_corner_attribute_stay_hard() -> None:
    """OBJ's cube: one vn per face, its 4 corners use it; rotated, each row turns with its face
    and the corners of one vertex keep three different normals."""
    indices = np.repeat(np.arange(6), 4)
    stored = Attribute("normal", "corner", CUBE_AXES, indices, "normal")
    turn = rotation(0.7)
    result = recomputed_normals(CUBE @ turn.T, CUBE_FACES, stored)
    np.testing.assert_allclose(result, CUBE_AXES @ turn.T, atol=1e-12)
    assert result.dtype == np.float64


def test_shared_rows_are_smoothed_together() -> None:
    """The same cube with one normal per vertex shared by its three corners: smooth."""
    indices = CUBE_FACES.reshape(-1)
    stored = Attribute("normal", "corner", np.zeros((8, 3)), indices, "normal")
    result = recomputed_normals(CUBE, CUBE_FACES, stored)
    np.testing.assert_allclose(result, (CUBE - 0.5) / np.linalg.norm(CUBE - 0.5, axis=1)[:, None])


def test_vertex_normals_point_away_from_a_symmetric_solid() -> None:
    stored = Attribute("normals", "vertex", np.zeros((6, 3), np.float32), role="normal")
    turn = rotation(1.3)
    result = recomputed_normals(OCTAHEDRON @ turn.T, OCTAHEDRON_FACES, stored)
    assert result.dtype == np.float32  # the stored attribute's own
    np.testing.assert_allclose(result, OCTAHEDRON @ turn.T, atol=1e-6)


def test_unindexed_corners_are_smoothed_where_their_stored_normals_are_equal() -> None:
    """USD-style faceVarying normals without indices: two triangles folded along an edge.
    Stored equal at the shared vertices: smoothed there; stored different: each face flat."""
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]], dtype=np.float64)
    faces = np.array([[0, 1, 2], [1, 3, 2]])
    weighted = face_area_normals(points, faces)
    flat = weighted / np.linalg.norm(weighted, axis=1)[:, None]
    same = np.tile([0.0, 0.0, 1.0], (6, 1))
    smooth = recomputed_normals(points, faces, Attribute("n", "corner", same, role="normal"))
    shared = weighted[0] + weighted[1]  # weighted by area
    np.testing.assert_allclose(smooth[1], shared / np.linalg.norm(shared))  # vertex 1, face 0
    np.testing.assert_allclose(smooth[3], smooth[1])  # vertex 1, face 1
    np.testing.assert_allclose(smooth[0], flat[0])  # vertex 0 has one face
    split = same.copy()
    split[3:] = [0.0, 1.0, 0.0]  # the second face's corners differ: a crease
    creased = recomputed_normals(points, faces, Attribute("n", "corner", split, role="normal"))
    np.testing.assert_allclose(creased, np.repeat(flat, 3, axis=0))


def test_face_domain_and_degenerate_faces() -> None:
    """Face normals per face; a face of no area keeps its stored value."""
    points = np.vstack([CUBE, [[5, 5, 5]]])
    faces = np.array([[0, 3, 2, 1], [8, 8, 8, -1]])
    stored = np.array([[0.0, 0.0, 1.0], [0.6, 0.8, 0.0]])
    result = recomputed_normals(points, faces, Attribute("n", "face", stored, role="normal"))
    np.testing.assert_allclose(result, np.array([[0, 0, -1], [0.6, 0.8, 0.0]]))


CUBE_COUNTS = {"vertex": 8, "corner": 24, "face": 6}


@pytest.mark.parametrize("domain", ["vertex", "corner", "face"])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_every_domain_gives_unit_rows_in_the_stored_layout(domain: str, dtype: type) -> None:
    """Not indexed: one row per element, of the stored dtype, unit length; a corner normal
    stored equal at all corners of a vertex comes back equal at them (smooth)."""
    count = CUBE_COUNTS[domain]
    stored = Attribute(
        "n", domain, np.tile(np.array([[0, 0, 1]], dtype), (count, 1)), None, "normal"
    )
    result = recomputed_normals(CUBE @ rotation(0.4).T, CUBE_FACES, stored)
    assert result.shape == (count, 3) and result.dtype == dtype
    np.testing.assert_allclose(np.linalg.norm(result, axis=1), 1, rtol=1e-6)
    if domain == "corner":
        vertex_of = CUBE_FACES.reshape(-1)
        for vertex in range(8):
            assert np.ptp(result[vertex_of == vertex], axis=0).max() == 0


@pytest.mark.parametrize("domain", ["vertex", "corner", "face"])
def test_indexed_rows_no_element_uses_keep_their_value(domain: str) -> None:
    """Indices that leave out the last rows (an OBJ vn table or a USD indexed primvar may
    hold more values than are used): all rows come back, the unused ones as stored."""
    count = CUBE_COUNTS[domain]
    stored = np.tile(np.array([[0.6, 0.8, 0.0]]), (count + 2, 1))
    indexed = Attribute("n", domain, stored, np.arange(count), "normal")
    result = recomputed_normals(CUBE, CUBE_FACES, indexed)
    assert result.shape == stored.shape
    np.testing.assert_array_equal(result[count:], stored[count:])
    exact = Attribute("n", domain, stored[:count], np.arange(count), "normal")
    np.testing.assert_array_equal(result[:count], recomputed_normals(CUBE, CUBE_FACES, exact))


def test_a_normal_attribute_of_the_wrong_size_is_refused() -> None:
    stored = Attribute("n", "vertex", np.zeros((3, 3)), role="normal")
    with pytest.raises(ValueError, match="3 vertex values, the mesh has 8"):
        recomputed_normals(CUBE, CUBE_FACES, stored)


def test_angle_error_degrees() -> None:
    a = np.array([[1.0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 0, 2], [0, 0, 0]])
    b = np.array([[2.0, 0, 0], [0, 3, 0], [-1, 0, 0], [0, np.sin(1e-9), np.cos(1e-9)], [1, 0, 0]])
    angles = angle_error_degrees(a, b)
    np.testing.assert_allclose(angles[:4], [0, 90, 180, np.degrees(1e-9)], rtol=1e-6)
    assert np.isnan(angles[4])  # no direction to compare
    with pytest.raises(ValueError, match="two"):
        angle_error_degrees(a, b[:2])
