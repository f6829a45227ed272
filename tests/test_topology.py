"""The face table and what follows from it (tuckercodec/topology.py): the edges of polygons, and
the mesh parents of spec/FORMAT.md §6.2, compared with the spec's queue walk written out
literally, on random faces and on faces hypothesis makes (repeated, degenerate, padded)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.compressed import spec_walk
from tests.support.properties import HYPOTHESIS_SETTINGS
from tuckercodec.topology import face_edges, mesh_parents


def _spec_walk(faces: np.ndarray, count: int) -> list[int]:
    """The pseudocode of spec/FORMAT.md §6.2, literally: the parents."""
    return spec_walk(faces, count).parent


def test_polygon_edges_close_at_the_last_real_corner():
    a, b = face_edges(np.array([[0, 1, 2, -1], [3, 4, 5, 6]]))
    edges = set(zip(a.tolist(), b.tolist(), strict=True))
    assert edges == {(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 6), (6, 3)}


def test_mesh_parents_follow_the_queue_walk_of_the_spec():
    rng = np.random.default_rng(7)
    for _ in range(300):
        count = int(rng.integers(1, 60))
        width = int(rng.integers(3, 6))
        faces = rng.integers(0, count, size=(int(rng.integers(0, 40)), width))
        if width > 3 and len(faces):
            faces[rng.random(len(faces)) < 0.4, -1] = -1  # padded polygons
        np.testing.assert_array_equal(mesh_parents(faces, count), _spec_walk(faces, count))


@settings(max_examples=100, **HYPOTHESIS_SETTINGS)
@given(
    count=st.integers(1, 40),
    faces=st.lists(st.lists(st.integers(-1, 39), min_size=3, max_size=5), max_size=30),
    repeat=st.integers(1, 300),
)
def test_mesh_parents_match_the_walk_of_the_spec(count, faces, repeat):
    """The compiled breadth-first search gives the parents of §6.2's queue walk, whatever the
    faces: repeated (even 300 times), degenerate, padded, or leaving vertices alone."""
    width = max((len(f) for f in faces), default=3)
    array = np.full((len(faces), width), -1, dtype=np.int64)
    for row, face in enumerate(faces):
        real = [v % count for v in face if v >= 0][:width]
        real += [real[0] if real else 0] * (3 - len(real))  # at least 3 real corners
        array[row, : len(real)] = real
    if len(array):
        array = np.concatenate([array, np.repeat(array[:1], repeat, axis=0)])
    assert mesh_parents(array, count).tolist() == _spec_walk(array, count)
