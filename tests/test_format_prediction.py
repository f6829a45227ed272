"""Prediction (spec/FORMAT.md §6.2): residuals along a forest of parents and their sums back,
on any forest and on a mesh whose breadth-first walk is 2**18 levels deep; predictor 2 (the
mean of the decoded neighbours, format 1.2) against its spec text written out in Python
integers; tuckercodec/format/prediction.py. (The parents of a mesh are tests/test_topology.py's.)"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.compressed import IDENTITY_U2, deadline, spec_walk
from tests.support.work import lines_run
from tuckercodec import Decoder
from tuckercodec.format import prediction
from tuckercodec.format.container import pack_container
from tuckercodec.format.faces import encode_faces
from tuckercodec.format.prediction import (
    MEAN_LIMIT,
    accumulate,
    mean_accumulate,
    mean_predictions,
    mean_residuals,
    residuals,
)
from tuckercodec.format.streams import compress, pack_integers
from tuckercodec.model import topology
from tuckercodec.model.topology import MAX_MEAN_LEVELS, mesh_parents, mesh_prediction


def test_accumulate_inverts_residuals_on_any_forest():
    rng = np.random.default_rng(3)
    for count in (1, 2, 17, 500):
        # a random forest: parents anywhere (earlier or later), never a cycle
        order = rng.permutation(count)
        parents = np.full(count, -1)
        for position in range(1, count):
            if rng.random() < 0.9:
                parents[order[position]] = order[rng.integers(0, position)]
        values = rng.integers(-1000, 1000, size=(count, 4))
        np.testing.assert_array_equal(accumulate(residuals(values, parents), parents), values)
        np.testing.assert_array_equal(accumulate(residuals(values, None), None), values)
        # in place: the same sums, in the array given
        stored = residuals(values, parents)
        assert accumulate(stored, parents, in_place=True) is stored
        np.testing.assert_array_equal(stored, values)
    # a chain 100 000 deep takes about 17 passes, not 100 000 (pointer jumping: too many levels
    # for a loop over them); a chain 4000 deep is restored level by level
    for depth in (100_000, 4_000):
        chain = np.arange(-1, depth - 1)
        values = rng.integers(-5, 5, size=(depth, 2))
        np.testing.assert_array_equal(accumulate(residuals(values, chain), chain), values)
        stored = residuals(values, chain)
        accumulate(stored, chain, in_place=True)
        np.testing.assert_array_equal(stored, values)


def _strip_file(count: int) -> bytes:
    """A valid file whose ``count`` vertices form one strip of triangles, U1 1 at vertex 0 and
    0 elsewhere: §6.2's breadth-first walk is count/2 levels deep."""
    row = np.arange(count - 2)
    faces = np.stack([row, row + 1, row + 2], 1)
    face_params, face_payload = encode_faces(faces)
    q = np.zeros((count, 1), np.int64)
    q[0] = 1
    payload, planes = pack_integers(
        np.ascontiguousarray(residuals(q, mesh_parents(faces, count)).T)
    )
    one = np.ones(1, "<f4").tobytes()
    sections = [
        ({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload),
        (
            {
                "id": "U1",
                "critical": True,
                "codec": "qmat",
                "shape": [count, 1],
                "planes": planes,
                "steps": one,
                "predict": b"\x01",
            },
            payload,
        ),
        (
            {
                "id": "U3",
                "critical": True,
                "codec": "qmat",
                "shape": [1, 1],
                "planes": 1,
                "steps": one,
                "predict": b"\x00",
            },
            compress(b"\x02"),
        ),
        (
            {
                "id": "CORE",
                "critical": True,
                "codec": "qmat",
                "shape": [3, 1],
                "planes": 1,
                "steps": one,
                "predict": b"\x00",
            },
            compress(b"\x02\x00\x00"),
        ),
        (
            {
                "id": "CENT",
                "critical": True,
                "codec": "qmat",
                "shape": [1, 3],
                "planes": 1,
                "steps": np.ones(3, "<f4").tobytes(),
                "predict": b"\x00\x00\x00",
            },
            compress(b"\x00\x00\x00"),
        ),
    ]
    return pack_container(
        {"vertices": count, "frames": 1, "ranks": [1, 1], "u2": IDENTITY_U2}, sections
    )


def test_a_deep_strip_of_faces_decodes_quickly():
    """A valid 866-byte file whose 2**19 vertices form one strip: the breadth-first walk of
    §6.2 is 2**18 levels deep (one Python pass per level took 5 s; minutes at 2**26). The
    cost is counted in lines of the walk's modules, not seconds: pointer jumping runs a few
    hundred (a pass per level would run at least 2**18), on any machine. The forest's level
    walk gives up after topology.LEVEL_WALK_LIMIT levels (about 20 lines each) for scipy's
    compiled search: a bound that does not grow with the depth."""
    count = 2**19
    data = _strip_file(count)
    decoded: list[Decoder] = []
    budget = 10_000 + 20 * topology.LEVEL_WALK_LIMIT
    with deadline(120.0):  # a hang guard only: the bound is the count of lines
        lines = lines_run(
            lambda: decoded.append(Decoder(data)),
            [prediction.__file__, topology.__file__],
            budget=budget,
        )
    assert lines <= budget
    decoder = decoded[0]
    expected = np.zeros((count, 1))
    expected[0] = 1
    np.testing.assert_array_equal(decoder.u1, expected)  # every residual summed along the strip
    assert decoder.frame(0)[0].tolist() == [1.0, 0.0, 0.0]


# -- predictor 2: the mean of the decoded neighbours (format 1.2) ------------------------------


def _spec_mean_restore(
    residual: np.ndarray, faces: np.ndarray, count: int, push: list[int] | None = None
) -> np.ndarray:
    """Predictor 2's restoration as §6.2 words it, vertex by vertex in Python integers (no
    overflow, no float); ``push``: each column's push (format 1.6), 2 by default."""
    pushes = push or [2] * residual.shape[1]
    walk = spec_walk(faces, count)
    neighbours, parent, depth, reached_order = (
        walk.neighbours,
        walk.parent,
        walk.depth,
        walk.reached_order,
    )
    rank, seen = [0] * count, [0] * (count + 1)
    for v in reached_order:
        rank[v], seen[depth[v]] = seen[depth[v]], seen[depth[v]] + 1
    phase = [r % 8 for r in rank]
    q = [[int(x) for x in row] for row in residual]
    order = sorted(
        (v for v in range(count) if depth[v] >= 1),
        key=lambda v: (depth[v], phase[v], reached_order.index(v)),
    )
    for v in order:
        sources = [
            w
            for w in neighbours[v]
            if depth[w] == depth[v] - 1 or (depth[w] == depth[v] and phase[w] < phase[v])
        ]
        c = len(sources)
        for col in range(residual.shape[1]):
            a, total = pushes[col], 0
            for w in sources:
                anchor = parent[w] if depth[w] == depth[v] - 1 and parent[w] >= 0 else w
                total += (6 + a) * q[w][col] - a * q[anchor][col]
            q[v][col] += (2 * total + 6 * c) // (12 * c)
    return np.array(q, dtype=np.int64).reshape(residual.shape)


def _random_mesh(rng: np.random.Generator, count: int) -> np.ndarray:
    """Triangles, quads padded to 4 corners, degenerate faces and some vertices on no face,
    in several components."""
    faces = []
    for _ in range(rng.integers(1, 2 * count)):
        corners = int(rng.choice([3, 4]))
        row = rng.integers(0, count - count // 5, size=4)  # the last fifth on no face
        if rng.random() < 0.1:
            row[1] = row[0]  # degenerate
        if corners == 3:
            row[3] = -1
        faces.append(row)
    return np.array(faces, dtype=np.int64)


def test_predictor_2_follows_the_spec_text_exactly():
    rng = np.random.default_rng(13)
    for count in (5, 12, 40, 90):
        for _ in range(6):
            faces = _random_mesh(rng, count)
            steps = mesh_prediction(faces, count).mean_steps
            # values anywhere within the limit, and small ones (ties of the rounding are common)
            for values in (
                rng.integers(-MEAN_LIMIT, MEAN_LIMIT, size=(count, 3), endpoint=True),
                rng.integers(-3, 4, size=(count, 3)),
            ):
                residual = mean_residuals(values, steps)
                if residual is None:  # a prediction left the limit with these values
                    continue
                np.testing.assert_array_equal(_spec_mean_restore(residual, faces, count), values)
                np.testing.assert_array_equal(mean_accumulate(residual, steps), values)


@pytest.mark.parametrize("crafted", [False, True], ids=["float", "int64"])
def test_predictor_2_with_pushes_follows_the_spec_text_exactly(monkeypatch, crafted):
    """Format 1.6's push per column (§6.2): residuals and restoration as the spec words them,
    every push 0..9 in one matrix, in the float path and the int64 one; push 2 is 1.2's."""
    if crafted:
        monkeypatch.setattr(prediction, "_FLOAT_SOURCES", 1)
        monkeypatch.setattr(prediction, "_PUSHED_FLOAT_SOURCES", 1)
    rng = np.random.default_rng(23)
    push = np.arange(10, dtype=np.uint8)
    for count in (12, 40, 90):
        faces = _random_mesh(rng, count)
        steps = mesh_prediction(faces, count).mean_steps
        for values in (
            rng.integers(-(2**30), 2**30, size=(count, 10)),
            rng.integers(-3, 4, size=(count, 10)),
        ):
            residual = mean_residuals(values, steps, push)
            assert residual is not None
            spec = _spec_mean_restore(residual, faces, count, push.tolist())
            np.testing.assert_array_equal(spec, values)
            np.testing.assert_array_equal(mean_accumulate(residual, steps, push), values)
            columns = np.ascontiguousarray(residual.T)
            prediction.mean_accumulate_columns(columns, steps, push)
            np.testing.assert_array_equal(columns.T, values)
            plain = mean_residuals(values[:, 2:3], steps)
            np.testing.assert_array_equal(plain, residual[:, 2:3])  # push 2: format 1.2's


@pytest.mark.parametrize("block_values", [1 << 22, 7, 1])
@pytest.mark.parametrize("crafted", [False, True], ids=["float", "int64"])
def test_predictor_2_restored_in_blocks_of_columns_is_the_same(monkeypatch, block_values, crafted):
    """The decoder restores a U1 of predictor 2 in place, a block of columns at a time
    (mean_accumulate_columns): the same integers as mean_accumulate, whole or one column at a
    time, and the same refusal of a value beyond the range."""
    monkeypatch.setattr(prediction, "MEAN_RESTORE_VALUES", block_values)
    if crafted:
        monkeypatch.setattr(prediction, "_FLOAT_SOURCES", 1)
    rng = np.random.default_rng(17)
    for count in (12, 90):
        faces = _random_mesh(rng, count)
        steps = mesh_prediction(faces, count).mean_steps
        values = rng.integers(-MEAN_LIMIT, MEAN_LIMIT, size=(count, 5), endpoint=True)
        residual = mean_residuals(values, steps)
        assert residual is not None
        columns = np.ascontiguousarray(residual.T)
        prediction.mean_accumulate_columns(columns, steps)
        np.testing.assert_array_equal(columns.T, mean_accumulate(residual, steps))
        np.testing.assert_array_equal(columns.T, values)
        if steps.rows.size:
            with pytest.raises(ValueError, match="range of predictor 2"):
                prediction.mean_accumulate_columns(np.ascontiguousarray(residual.T) * 2**20, steps)


def test_predictor_2_rounds_half_up():
    # one edge: vertex 1's only source is root 0, its own anchor: U = 3 q[0], U / 3c = q[0]
    # a triangle: vertex 2 (depth 1, phase 1) has sources 0 (up) and 1 (same depth, phase 0)
    faces = np.array([[0, 1, 2]])
    steps = mesh_prediction(faces, 3).mean_steps
    assert steps.rows.tolist() == [1, 2]
    assert steps.sources.tolist() == [0, 0, 1] and steps.anchors.tolist() == [0, 0, 1]
    # U = 3 q0 + 3 q1 over 3c = 6: the mean of q0 and q1, ties up (also below zero)
    q = np.array([[0, 0, -1], [1, 2, 0], [0, 0, 0]])
    assert mean_predictions(q, steps).tolist() == [[0, 0, -1], [1, 1, 0]]  # -0.5 -> 0
    q = np.array([[0], [-3], [0]])
    assert mean_predictions(q, steps)[1].tolist() == [-1]  # -1.5 rounds up to -1


def test_predictor_2_int64_path_for_a_vertex_with_many_sources(monkeypatch):
    """A vertex with 2**18 sources sums in int64 rather than float64: both give the spec's
    integers (the int64 path is forced here on a small mesh)."""
    rng = np.random.default_rng(5)
    faces = _random_mesh(rng, 60)
    steps = mesh_prediction(faces, 60).mean_steps
    values = rng.integers(-MEAN_LIMIT, MEAN_LIMIT, size=(60, 2), endpoint=True)
    residual = mean_residuals(values, steps)
    assert residual is not None
    monkeypatch.setattr(prediction, "_FLOAT_SOURCES", 1)
    again = mean_residuals(values, steps)
    assert again is not None and again.tolist() == residual.tolist()
    np.testing.assert_array_equal(mean_accumulate(residual, steps), values)
    with pytest.raises(ValueError, match="range of predictor 2"):
        mean_accumulate(residual * 2**20, steps)


def test_predictor_2_refuses_values_beyond_its_range():
    faces = np.array([[0, 1, 2], [1, 2, 3]])
    steps = mesh_prediction(faces, 4).mean_steps
    assert mean_residuals(np.full((4, 1), MEAN_LIMIT + 1), steps) is None
    residual = np.full((4, 1), 2**31 - 1)  # each level adds 2**31 - 1 to its sources' mean
    with pytest.raises(ValueError, match="range of predictor 2"):
        mean_accumulate(residual * 3, steps)


def test_minus_two_to_the_63_is_beyond_every_predictor_range():
    """Its abs() is itself (int64 wraps), so a check by abs() let it through; found by the
    compiled core's fuzzer (predictor 2's residuals of such a column did not restore)."""
    faces = np.array([[0, 1, 2], [1, 2, 3]])
    steps = mesh_prediction(faces, 4).mean_steps
    column = np.zeros((4, 1), dtype=np.int64)
    column[0] = np.iinfo(np.int64).min
    assert mean_residuals(column, steps) is None
    # the running sums wrap back to -2**63 and 0
    wraps = np.array([[np.iinfo(np.int64).min], [0]], dtype=np.int64)
    with pytest.raises(ValueError, match="difference restored with predictor 3"):
        prediction.linear_accumulate(wraps)


def test_mesh_prediction_steps_on_a_strip_and_without_edges():
    assert mesh_prediction(np.zeros((0, 3), np.int64), 4).mean_steps.rows.size == 0
    count = 2 * MAX_MEAN_LEVELS + 10  # one strip: about count / 2 levels
    row = np.arange(count - 2)
    mesh = mesh_prediction(np.stack([row, row + 1, row + 2], 1), count)
    assert mesh.levels == MAX_MEAN_LEVELS + 1  # counted no further than "too deep"
    assert mesh.mean_steps.levels > MAX_MEAN_LEVELS + 1


def test_the_public_sparse_product_gives_what_scipys_private_one_gives():
    """The mean predictor's restore uses scipy's private csr_matvecs; its fallback, through the
    public API, must give the same sums."""
    from tuckercodec.format.prediction import _csr_matvecs, _public_csr_matvecs

    rng = np.random.default_rng(3)
    ptr = np.array([0, 2, 2, 5], dtype=np.int64)
    idx = np.array([0, 3, 1, 2, 3], dtype=np.int64)
    weights = rng.integers(-4, 5, size=5).astype(np.float64)  # integers, as the restore's are
    x = rng.integers(-1000, 1000, size=(4, 6)).astype(np.float64)
    expected, got = np.ones((3, 6)), np.ones((3, 6))
    _csr_matvecs()(3, 4, 6, ptr, idx, weights, x.reshape(-1), expected.reshape(-1))
    _public_csr_matvecs(3, 4, 6, ptr, idx, weights, x.reshape(-1), got.reshape(-1))
    np.testing.assert_array_equal(got, expected)
