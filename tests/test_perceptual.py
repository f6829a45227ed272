"""STED, the spatio-temporal edge difference of Vasa and Skala 2011
(tuckercodec/measures/perceptual.py): its edge neighbourhoods, and its value on cases known by hand
(rigid motions, uniform scaling, one moved vertex), on a real sequence, and on bad arguments."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tests.support.sequences import grid_faces, load_shared_npz, wave_sequence
from tuckercodec import InputError, MeshSequence
from tuckercodec.measures.perceptual import STED_DEFINITION, Sted, neighbourhood_edges, sted
from tuckercodec.model.topology import mesh_edges

# A 2 x 1 rectangle in the plane z = 0, two triangles: its bounding-box diagonal is sqrt(5).
RECTANGLE = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0]], dtype=float)


RECTANGLE_FACES = np.array([[0, 1, 2], [0, 2, 3]])


TETRAHEDRON_FACES = np.array([[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]])


def strip_faces(quads: int) -> np.ndarray:
    """A strip of quads split into triangles: vertices 2j (bottom) and 2j+1 (top)."""
    faces = []
    for j in range(quads):
        a, b, c, d = 2 * j, 2 * j + 2, 2 * j + 3, 2 * j + 1
        faces += [[a, b, c], [a, c, d]]
    return np.array(faces)


def rotation(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def test_edges_of_polygons_and_the_neighbourhood_of_width_1():
    # a quad has its 4 sides and no diagonal; a padded triangle closes at its last real corner
    faces = np.array([[0, 1, 2, 3], [2, 3, 4, -1]])
    assert mesh_edges(faces, 5).tolist() == [[0, 1], [0, 3], [1, 2], [2, 3], [2, 4], [3, 4]]
    # a hexagonal fan: centre 0, rim 1..6
    fan = np.array([[0, j, j % 6 + 1] for j in range(1, 7)])
    edges = mesh_edges(fan, 7)
    members = neighbourhood_edges(edges, 7, 1).toarray()
    assert members.shape == (7, 12)
    assert members[0].sum() == 12  # the 6 spokes and the 6 rim edges
    ring = {tuple(e) for e in edges[members[1] > 0].tolist()}
    assert ring == {(0, 1), (0, 2), (0, 6), (1, 2), (1, 6)}  # 1's spokes and its rim, not 2-6
    assert (neighbourhood_edges(edges, 7, 2).toarray() == 1).all()


def test_sted_of_a_rigid_motion_is_zero():
    original = wave_sequence(12, 5)
    moved = original @ rotation([1, 2, 3], 0.7).T + [3.0, -1.0, 2.0]  # the same for all frames
    result = sted(original, moved, grid_faces(5))
    assert result.spatial == pytest.approx(0.0, abs=1e-12)
    assert result.temporal == pytest.approx(0.0, abs=1e-12)
    assert result.value == pytest.approx(0.0, abs=1e-12)
    assert sted(original, original, grid_faces(5)).value == 0.0


def test_sted_of_a_uniform_scaling_is_known():
    # The rectangle moves by d each frame; the approximation is the original scaled by a, so
    # every edge changes by the same factor (STED_s = 0) and every temporal edge of the
    # approximation is sqrt(a^2 |d|^2 s^2 + dt^2) against sqrt(|d|^2 s^2 + dt^2).
    a, d, dt, c = 1.1, np.array([0.01, 0.02, 0.0]), 0.0003, 9.144e-05
    original = RECTANGLE + np.arange(12)[:, None, None] * d
    s = 1 / np.sqrt(2**2 + 1**2)  # the first frame's bounding box is 2 x 1 x 0
    moved = np.sqrt(d @ d) * s
    expected = abs(np.hypot(a * moved, dt) - np.hypot(moved, dt)) / np.hypot(moved, dt)
    result = sted(original, a * original, RECTANGLE_FACES)
    assert result.scale == pytest.approx(s)
    assert result.spatial == pytest.approx(0.0, abs=1e-14)
    assert result.temporal == pytest.approx(expected, rel=1e-12)
    assert result.value == pytest.approx(c * expected, rel=1e-12)
    assert (result.width, result.window, result.dt, result.c) == (1, 5, dt, c)
    # a scale given explicitly is used instead of the bounding box
    assert sted(original, a * original, RECTANGLE_FACES, scale=1.0).scale == 1.0


def test_sted_of_one_triangle_with_a_vertex_moved():
    triangle = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    moved = triangle.copy()
    moved[0, 2] = [0, 2, 0]
    # edges 0-1, 1-2, 2-0: lengths 1, sqrt(2), 1 before; 1, sqrt(5), 2 after
    lengths = np.array([1.0, np.sqrt(2), 1.0])
    changes = (np.array([1.0, np.sqrt(5), 2.0]) - lengths) / lengths
    mean = np.sum(lengths * changes) / lengths.sum()
    deviation = np.sqrt(np.sum(lengths * (changes - mean) ** 2) / lengths.sum())
    # every vertex's 1-ring holds the three edges, so every vertex has this deviation
    result = sted(triangle, moved, np.array([[0, 1, 2]]))
    assert result.spatial == pytest.approx(deviation, rel=1e-12)
    assert result.temporal == 0.0  # a single frame
    assert result.value == pytest.approx(deviation, rel=1e-12)


def test_sted_width_2_covers_more_edges_only_where_there_are_more():
    rng = np.random.default_rng(3)
    tetrahedron = rng.standard_normal((6, 4, 3))
    noisy = tetrahedron + 0.05 * rng.standard_normal(tetrahedron.shape)
    # every vertex of a tetrahedron is adjacent to all others: width 1 already sees every edge
    one = sted(tetrahedron, noisy, TETRAHEDRON_FACES, width=1)
    two = sted(tetrahedron, noisy, TETRAHEDRON_FACES, width=2)
    assert two.spatial == one.spatial and two.width == 2

    strip = np.stack([np.arange(16) // 2, np.arange(16) % 2, np.zeros(16)], axis=1).astype(float)
    original = strip + 0.01 * rng.standard_normal((5, 16, 3))
    noisy = original + 0.05 * rng.standard_normal(original.shape)
    one = sted(original, noisy, strip_faces(7), width=1)
    two = sted(original, noisy, strip_faces(7), width=2)
    assert two.spatial != pytest.approx(one.spatial, rel=1e-3)
    assert two.temporal == one.temporal  # the temporal part does not depend on the width


def test_sted_is_not_symmetric_and_uses_the_sequences_faces():
    original = MeshSequence(wave_sequence(10, 5), grid_faces(5))
    noisy = original.vertices * (
        1 + 0.05 * np.random.default_rng(2).standard_normal(original.vertices.shape)
    )
    forward = sted(original, noisy)  # the faces of the original sequence
    assert isinstance(forward, Sted) and forward.value > 0
    assert forward == sted(original.vertices, noisy, grid_faces(5))
    assert sted(noisy, original.vertices, grid_faces(5)).value != pytest.approx(forward.value)
    assert "Vasa-Skala 2011" in STED_DEFINITION
    assert forward.to_dict()["definition"] == STED_DEFINITION


def test_sted_skips_edges_of_zero_length_and_isolated_vertices():
    triangle = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]]])  # vertex 3 on no face
    moved = triangle.copy()
    moved[0, 2] = [0, 2, 0]
    alone = sted(triangle[:, :3], moved[:, :3], np.array([[0, 1, 2]]))
    with_isolated = sted(triangle, moved, np.array([[0, 1, 2]]), scale=alone.scale)
    assert with_isolated.spatial == pytest.approx(alone.spatial, rel=1e-12)
    # two corners at the same place: the zero-length edge has weight 0, nothing is NaN
    pinched = np.array([[[0.0, 0, 0], [0, 0, 0], [0, 1, 0]]])
    result = sted(
        pinched, pinched + np.array([[[0, 0, 0], [0.1, 0, 0], [0, 0, 0]]]), np.array([[0, 1, 2]])
    )
    # left: 1-2 (length 1, now sqrt(1.01)) and 0-2 (unchanged), equal weights: dev = half the change
    assert result.spatial == pytest.approx((np.sqrt(1.01) - 1) / 2, rel=1e-12)


def test_sted_refuses_bad_arguments():
    original = wave_sequence(4, 3)
    faces = grid_faces(3)
    with pytest.raises(ValueError, match="faces are required"):
        sted(original, original)
    with pytest.raises(InputError, match="differ in shape"):
        sted(original, original[:3], faces)
    bad = original.copy()
    bad[2, 1, 0] = np.nan
    with pytest.raises(InputError, match="approx: vertex 1 has a non-finite"):
        sted(original, bad, faces)
    with pytest.raises(InputError, match="shape"):
        sted(original[0], original[0], faces)
    with pytest.raises(InputError, match=r"outside 0\.\.8"):
        sted(original, original, faces + 100)
    with pytest.raises(InputError, match="padded before its end"):
        sted(original, original, np.array([[0, -1, 1, 2]]))
    with pytest.raises(InputError, match="no edges"):
        sted(original, original, np.zeros((0, 3), dtype=np.int64))
    with pytest.raises(InputError, match="single point"):
        sted(np.zeros((2, 3, 3)), np.zeros((2, 3, 3)), np.array([[0, 1, 2]]))
    for keyword, value, error in (
        ("width", 0, ValueError),
        ("width", 1.5, TypeError),
        ("width", True, TypeError),
        ("window", -1, ValueError),
        ("dt", 0.0, ValueError),
        ("dt", float("nan"), ValueError),
        ("c", -1.0, ValueError),
        ("scale", 0.0, ValueError),
        ("scale", "big", TypeError),
    ):
        options: dict[str, Any] = {keyword: value}
        with pytest.raises(error, match=keyword):
            sted(original, original, faces, **options)


def test_sted_on_samba_against_a_noisy_copy():
    vertices, faces = load_shared_npz("samba.npz")
    original = vertices.astype(np.float64)
    noisy = original + 1e-3 * np.random.default_rng(0).standard_normal(original.shape)
    result = sted(original, noisy, faces)
    assert np.isfinite(result.value) and result.value > 0
    assert result.spatial > 0 and result.temporal > 0
    assert result.value == pytest.approx(np.hypot(result.spatial, result.c * result.temporal))
