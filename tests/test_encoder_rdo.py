"""Rate-distortion optimized quantization (tuckercodec.encoder.rdo): every integer is one of the
two either side of x / step, the choice is deterministic and follows the prediction the file
uses, and an encode with it still meets its KG target with the decoder's own reconstruction."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest

from tests.support.sequences import grid_faces
from tuckercodec import decode, encode_with_report, kg_error
from tuckercodec.encoder import rdo
from tuckercodec.format import qmat
from tuckercodec.format.prediction import mean_residuals, residuals
from tuckercodec.model.topology import MeshPrediction


def _matrix(rows: int = 400, cols: int = 6, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.standard_normal((rows, cols)), axis=0) * np.geomspace(1, 0.01, cols)


def test_every_integer_is_the_floor_or_the_ceiling():
    values = _matrix()
    steps = np.full(values.shape[1], 0.05)
    q = rdo.quantize(values, steps, rdo.Levels.chain(values.shape[0])).q
    scaled = values / np.float32(0.05).astype(np.float64)
    assert ((q == np.floor(scaled)) | (q == np.floor(scaled) + 1)).all()


def test_no_rate_weight_is_nearest_rounding():
    values = _matrix()
    steps = np.full(values.shape[1], 0.05)
    plain = qmat.quantize(values, steps)
    for settings in (rdo.NEAREST, rdo.Settings(lam=0.0)):
        chosen = rdo.quantize(values, steps, rdo.Levels.chain(values.shape[0]), settings)
        np.testing.assert_array_equal(chosen.q, plain.q)
        np.testing.assert_array_equal(chosen.steps, plain.steps)


def test_deterministic_and_cheaper_residuals():
    values = _matrix()
    steps = np.full(values.shape[1], 0.05)
    levels = rdo.Levels.chain(values.shape[0])
    first = rdo.quantize(values, steps, levels, rdo.Settings(lam=0.2)).q
    again = rdo.quantize(values.copy(), steps, levels, rdo.Settings(lam=0.2)).q
    np.testing.assert_array_equal(first, again)
    plain = qmat.quantize(values, steps).q
    assert (first != plain).any()
    # what it trades error for: smaller residuals after previous-row prediction
    assert np.abs(residuals(first, None)).sum() < np.abs(residuals(plain, None)).sum()


def test_dead_zone_is_exact():
    # no prediction: |x / step| below the zone goes to 0, above it the magnitude is
    # floor(|x / step| + 1 - zone)
    scaled = np.array([[0.0], [0.55], [-0.55], [0.65], [-0.65], [1.55], [1.75], [-2.7]])
    q = rdo.quantize(scaled, np.ones(1), rdo.Levels.flat(8), rdo.Settings(dead_zone=0.6)).q
    np.testing.assert_array_equal(q[:, 0], [0, 0, 0, 1, -1, 1, 2, -3])


def test_levels_put_parents_first():
    parents = np.array([-1, 0, 0, 1, -1, 4, 3])
    levels = rdo.Levels(parents)
    seen: set[int] = set()
    for group in levels.groups:
        assert all(parents[r] < 0 or parents[r] in seen for r in group)
        seen.update(group.tolist())
    assert seen == set(range(7))


@pytest.mark.parametrize("target", [1.0, 0.1])
def test_encode_with_rdo_meets_the_target(cloth, target):
    with mock.patch.object(rdo, "DEFAULT", rdo.Settings(lam=rdo.DEFAULT_LAMBDA)):
        result = encode_with_report(cloth, target_kg=target)
    assert kg_error(cloth.vertices, decode(result.data).vertices) <= target
    assert result.report.kg <= target


def _mesh_columns(grid: int = 24, cols: int = 5) -> tuple[np.ndarray, MeshPrediction]:
    """Columns smooth over a grid sheet (as U1's are over a mesh), and the sheet's predictors."""
    y, x = np.mgrid[0:grid, 0:grid] / grid
    rng = np.random.default_rng(3)
    columns = [np.sin((c + 1) * 2.0 * x + c) * np.cos((c + 2) * y) for c in range(cols)]
    values = np.stack(columns, axis=-1).reshape(grid * grid, cols)
    values += 1e-3 * rng.standard_normal(values.shape)
    return values, MeshPrediction(grid_faces(grid), grid * grid)


def _mesh_quantized(values, mesh, steps, settings=rdo.DEFAULT):
    nearest = qmat.quantize(values, steps)
    chosen = qmat.predicted_stream(nearest.q, mesh, True, pushes=True)
    levels = rdo.Levels(mesh.parents)
    return rdo.quantize_mesh(values, steps, levels, mesh, chosen.predict, chosen.push, settings)


def test_mesh_rounding_follows_predictor_2():
    values, mesh = _mesh_columns()
    steps = np.full(values.shape[1], 0.02)
    nearest = qmat.quantize(values, steps)
    chosen = qmat.predicted_stream(nearest.q, mesh, True, pushes=True)
    assert (chosen.predict == qmat.PREDICT_MEAN).all()  # what this test is about
    q = _mesh_quantized(values, mesh, steps).q
    scaled = values / nearest.steps.astype(np.float64)
    assert ((q == np.floor(scaled)) | (q == np.floor(scaled) + 1)).all()
    assert (q != nearest.q).any()
    np.testing.assert_array_equal(q, _mesh_quantized(values.copy(), mesh, steps).q)
    # what it trades error for: smaller residuals under the file's own predictor, with its
    # push, than the rounding that models the mesh parent's prediction leaves
    parent_rounded = _mesh_quantized(values, mesh, steps, rdo.Settings(mean=False)).q

    def cost(q: np.ndarray) -> float:
        residual = mean_residuals(q, mesh.mean_steps, chosen.push)
        assert residual is not None
        return float(np.log2(1.0 + 2.0 * np.abs(residual)).sum())

    assert cost(q) < cost(parent_rounded) < cost(nearest.q)


def test_mesh_rounding_without_rate_weight_is_nearest():
    values, mesh = _mesh_columns()
    steps = np.full(values.shape[1], 0.02)
    plain = qmat.quantize(values, steps)
    for settings in (rdo.NEAREST, rdo.Settings(lam=0.0)):
        chosen = _mesh_quantized(values, mesh, steps, settings)
        np.testing.assert_array_equal(chosen.q, plain.q)
        np.testing.assert_array_equal(chosen.steps, plain.steps)


def test_mesh_rounding_keeps_other_columns_as_before():
    # columns the file does not predict with predictor 2 are rounded as quantize() rounds them
    values, mesh = _mesh_columns()
    steps = np.full(values.shape[1], 0.02)
    predict = np.array([qmat.PREDICT_MEAN, 1, qmat.PREDICT_MEAN, 0, 1], dtype=np.uint8)
    push = np.full(values.shape[1], 2, dtype=np.uint8)
    levels = rdo.Levels(mesh.parents)
    q = rdo.quantize_mesh(values, steps, levels, mesh, predict, push).q
    others = np.flatnonzero(predict != qmat.PREDICT_MEAN)
    alone = rdo.quantize(values[:, others], steps[others], levels).q
    np.testing.assert_array_equal(q[:, others], alone)
    with mock.patch.object(rdo, "MEAN_BLOCK_VALUES", 1):  # a block per column: the same
        np.testing.assert_array_equal(
            rdo.quantize_mesh(values, steps, levels, mesh, predict, push).q, q
        )
