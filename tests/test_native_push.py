"""The compiled core's predictor 2 with a push per column (``mean_push``, spec/FORMAT.md §6.2,
*Push*): its residuals, its restored columns and its dequantized values against a plain integer
reference written here from the spec's formula, for every push 0..9 on random meshes."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from tuckercodec.format import streams
from tuckercodec.format.prediction import mean_residual_columns
from tuckercodec.model.topology import MeanSteps, mesh_prediction
from tuckercodec.system import native


@pytest.fixture(autouse=True)
def _needs_core() -> None:
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")


def reference_prediction(q: list[int], steps: MeanSteps, j: int, push: int) -> int:
    """Row j's prediction from one column ``q`` of Python ints, straight from the spec:
    ``V = sum of (6 + a) q[w] - a q[anchor(w)]``, ``floor((2 V + 6 c) / 12 c)``."""
    first, last = int(steps.source_ends[j]), int(steps.source_ends[j + 1])
    total = sum(
        (6 + push) * q[int(w)] - push * q[int(anchor)]
        for w, anchor in zip(steps.sources[first:last], steps.anchors[first:last], strict=True)
    )
    count = last - first
    return (2 * total + 6 * count) // (12 * count)


def reference_residuals(values: np.ndarray, steps: MeanSteps, push: list[int]) -> np.ndarray:
    """Each predicted row of a (K, cols) matrix minus its prediction from the values."""
    out = values.copy()
    for c, a in enumerate(push):
        column = [int(v) for v in values[:, c]]
        for j, row in enumerate(steps.rows):
            out[int(row), c] -= reference_prediction(column, steps, j, a)
    return out


def reference_restore(residual: np.ndarray, steps: MeanSteps, push: list[int]) -> np.ndarray:
    """The spec's restoring order: depth 0 as it is, then a step (depth and phase) at a time,
    each row from values restored before it."""
    out = residual.copy()
    for c, a in enumerate(push):
        q = [int(v) for v in residual[:, c]]
        for s in range(steps.step_ends.size - 1):
            for j in range(int(steps.step_ends[s]), int(steps.step_ends[s + 1])):
                row = int(steps.rows[j])
                q[row] = int(residual[row, c]) + reference_prediction(q, steps, j, a)
        out[:, c] = q
    return out


def random_mesh(rng: np.random.Generator, count: int, faces: int) -> np.ndarray:
    """Random triangles and quads (padded with -1) over ``count`` vertices, some on none."""
    table = rng.integers(0, count, size=(faces, 4), dtype=np.int64)
    table[rng.random(faces) < 0.5, 3] = -1
    return table


def grid(side: int) -> np.ndarray:
    """A side x side grid of quads: a mesh many levels deep."""
    corner = (np.arange(side - 1)[:, None] * side + np.arange(side - 1)[None, :]).reshape(-1)
    return np.stack([corner, corner + 1, corner + side + 1, corner + side], axis=1)


MESHES = [
    pytest.param(lambda rng: (grid(8), 64), id="grid"),
    pytest.param(lambda rng: (random_mesh(rng, 50, 80), 50), id="sparse"),
    pytest.param(lambda rng: (random_mesh(rng, 30, 150), 30), id="dense"),
]


@pytest.mark.parametrize("make", MESHES)
@pytest.mark.parametrize("seed", [1, 2])
def test_pushes_match_the_reference(
    make: Callable[[np.random.Generator], tuple[np.ndarray, int]], seed: int
) -> None:
    rng = np.random.default_rng(seed)
    faces, count = make(rng)
    steps = mesh_prediction(faces, count).mean_steps
    plan = steps.native_plan()
    # every push, mixed within blocks (16 columns for residuals, 8 for values), a block of 2s
    push = [int(a) for a in rng.integers(0, 10, size=19)] + list(range(10)) + [2] * 8
    width = len(push)
    values = rng.integers(-(2**20), 2**20 + 1, size=(count, width), dtype=np.int64)
    expected = reference_residuals(values, steps, push)
    push_bytes = bytes(push)
    push_array = np.array(push, dtype=np.uint8)

    for given in (push_bytes, push_array):
        residual = plan.residuals(values, given)
        assert residual is not None
        np.testing.assert_array_equal(residual, expected)
        columns = plan.residuals(values, given, columns=True)  # as a section streams them
        assert columns.flags.c_contiguous
        np.testing.assert_array_equal(columns, expected.T)
    np.testing.assert_array_equal(mean_residual_columns(values, steps, push_array), expected.T)
    with native.pure_python():
        reference = mean_residual_columns(values, steps, push_array)
    assert reference is not None and reference.flags.c_contiguous
    np.testing.assert_array_equal(reference, expected.T)

    np.testing.assert_array_equal(reference_restore(expected, steps, push), values)
    columns = np.ascontiguousarray(expected.T)
    plan.restore_columns(columns, push_array)
    np.testing.assert_array_equal(columns.T, values)

    scales = (rng.random(width) * 0.01 + 1e-4).astype(np.float32)
    unsigned = streams.zigzag(np.ascontiguousarray(expected.T).reshape(-1))
    planes = streams.planes_needed(unsigned)
    raw = streams.to_planes(unsigned, planes)
    product = np.multiply(values, scales.astype(np.float64))
    for threads in (1, 2, 0):
        restored = plan.restore_values(raw, planes, count, scales, threads, push_bytes)
        assert restored.tobytes() == product.tobytes()


def test_no_push_is_push_two() -> None:
    rng = np.random.default_rng(7)
    faces, count = random_mesh(rng, 40, 70), 40
    steps = mesh_prediction(faces, count).mean_steps
    plan = steps.native_plan()
    values = rng.integers(-(2**31), 2**31, size=(count, 5), dtype=np.int64)
    plain = plan.residuals(values)
    np.testing.assert_array_equal(plain, plan.residuals(values, bytes([2] * 5)))
    np.testing.assert_array_equal(plain, reference_residuals(values, steps, [2] * 5))
    columns = np.ascontiguousarray(plain.T)
    plan.restore_columns(columns)
    np.testing.assert_array_equal(columns.T, values)


@pytest.mark.parametrize(
    "push", [b"\x02", b"\x02\x02\x02", b"\x02\x0a", np.array([2, 255], np.uint8)]
)
def test_bad_pushes_are_value_errors(push: bytes | np.ndarray) -> None:
    steps = mesh_prediction(grid(4), 16).mean_steps
    plan = steps.native_plan()
    values = np.zeros((16, 2), dtype=np.int64)
    with pytest.raises(ValueError, match="push"):
        plan.residuals(values, push)
    with pytest.raises(ValueError, match="push"):
        plan.restore_columns(np.ascontiguousarray(values.T), push)
    raw = bytes(16 * 2)
    with pytest.raises(ValueError, match="push"):
        plan.restore_values(raw, 1, 16, np.ones(2, dtype=np.float32), 1, push)
    with pytest.raises(ValueError, match="push"):
        plan.residuals(values, [2, 2])  # neither bytes nor a uint8 array
