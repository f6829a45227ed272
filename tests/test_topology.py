"""The face table and what follows from it (tuckercodec/model/topology.py): the edges of polygons,
and the mesh parents of spec/FORMAT.md §6.2, compared with the spec's queue walk written out
literally, on random faces and on faces hypothesis makes (repeated, degenerate, padded)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.compressed import spec_walk
from tests.support.properties import HYPOTHESIS_SETTINGS
from tuckercodec.model import topology
from tuckercodec.model.topology import face_edges, mesh_parents


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


@pytest.mark.parametrize(
    "fallback", ["levels", "rounds"], ids=["deeper-than-the-level-walk", "hooking-unfinished"]
)
def test_both_walks_of_the_forest_give_the_spec_walk(monkeypatch, fallback):
    """The forest is walked a level at a time in numpy, or by scipy's compiled search for a
    forest deeper than LEVEL_WALK_LIMIT (or components the hooking has not found in
    COMPONENT_ROUNDS rounds): the same walk order and parents, the spec's (§6.2), on random
    faces of several components, a strip and a grid."""
    rng = np.random.default_rng(19)
    strip = np.arange(60)
    tables = [
        (rng.integers(0, count, size=(int(rng.integers(1, 50)), 3)), count)
        for count in rng.integers(2, 80, size=60).tolist()
    ]
    tables.append((np.stack([strip, strip + 1, strip + 2], 1), 62))
    tables.append(
        (rng.permutation(100)[np.stack([strip[:50], strip[:50] + 1, strip[:50] + 10], 1)], 100)
    )
    for faces, count in tables:
        numpy_forest = topology._mesh_forest(faces, count)
        with monkeypatch.context() as patch:
            if fallback == "levels":
                patch.setattr(topology, "LEVEL_WALK_LIMIT", 0)
            else:
                patch.setattr(topology, "COMPONENT_ROUNDS", 0)
            scipy_forest = topology._mesh_forest(faces, count)
        np.testing.assert_array_equal(numpy_forest.walk, scipy_forest.walk)
        np.testing.assert_array_equal(numpy_forest.found, scipy_forest.found)
        spec = spec_walk(faces, count)
        used = numpy_forest.used
        reached = [v for v in spec.reached_order if spec.neighbours[v]]
        by_depth = sorted(reached, key=lambda v: spec.depth[v])  # stable: the forest's order
        assert used[numpy_forest.walk].tolist() == by_depth
        assert numpy_forest.parents(count).tolist() == spec.parent
