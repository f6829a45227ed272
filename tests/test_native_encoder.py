"""The compiled core's encoder loops against the pure-Python reference: rate-distortion rounding
(tuckercodec.encoder.rdo), the integers of a trial's entropy (tuckercodec.encoder.estimate) and
the analysis's max-abs checks give the same integers, floats and errors both ways, and a whole
encode the same bytes."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import grid_faces, shared_sequence, wave_sequence
from tuckercodec import encode
from tuckercodec.decomposition import analysis
from tuckercodec.decomposition.hosvd import centre_frames
from tuckercodec.encoder import estimate, rdo
from tuckercodec.errors import InputError
from tuckercodec.format import adaptive, qmat
from tuckercodec.model.sequence import MeshSequence
from tuckercodec.model.topology import MeshPrediction, mesh_parents
from tuckercodec.system import native


@pytest.fixture(scope="module")
def core():
    module = native.core()
    if module is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")
    return module


def _both(function, *args):
    """``function(*args)`` with the core, then in pure Python."""
    fast = function(*args)
    with native.pure_python():
        reference = function(*args)
    return fast, reference


def _smooth(rows: int, cols: int, seed: int, scale: float = 1.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    walk = np.cumsum(rng.standard_normal((rows, cols)), axis=0)
    return scale * walk * np.geomspace(1, 0.01, cols)


def _random_tree(rows: int, seed: int) -> np.ndarray:
    """Parents earlier in the order, a few roots, as a mesh's breadth-first forest has."""
    rng = np.random.default_rng(seed)
    parents = np.array([rng.integers(0, r) if r else -1 for r in range(rows)], dtype=np.int64)
    parents[rng.random(rows) < 0.02] = -1
    return parents


LEVELS = {
    "chain": lambda rows, seed: rdo.Levels.chain(rows),
    "flat": lambda rows, seed: rdo.Levels.flat(rows),
    "tree": lambda rows, seed: rdo.Levels(_random_tree(rows, seed)),
    "mesh": lambda rows, seed: rdo.Levels(mesh_parents(grid_faces(int(rows**0.5)), rows)),
}


# the last two scale the values so that residuals pass the bit table (escapes)
SHAPES = [
    (1, 0.05, 1, 1.0),
    (2, 0.05, 1, 1.0),
    (7, 0.05, 2, 1.0),
    (5, 0.0, 1, 1.0),
    (6, 1.5, 1, 1.0),
    (4, 0.05, 1, 4000.0),
    (3, 0.3, 2, 1e6),
]


@pytest.mark.parametrize("levels", sorted(LEVELS))
@pytest.mark.parametrize(("cols", "lam", "passes", "scale"), SHAPES)
def test_rdo_quantize_is_the_same(core, levels, cols, lam, passes, scale):
    rows = 144  # a square grid for the mesh
    for seed in range(3):
        values = _smooth(rows, cols, seed, scale)
        steps = np.geomspace(0.05, 0.2, cols)
        settings = rdo.Settings(lam=lam, passes=passes)
        fast, reference = _both(rdo.quantize, values, steps, LEVELS[levels](rows, seed), settings)
        np.testing.assert_array_equal(fast.q, reference.q)
        np.testing.assert_array_equal(fast.steps, reference.steps)


def test_rdo_blocks_of_columns_are_the_same(core, monkeypatch):
    # a narrow block width: several blocks, the last one a single column (decided in Python)
    monkeypatch.setattr(rdo, "BLOCK_VALUES", 64)
    values = _smooth(16, 2 * rdo.COLUMN_BLOCK + 1, seed=4)
    steps = np.full(values.shape[1], 0.1)
    fast, reference = _both(rdo.quantize, values, steps, rdo.Levels(_random_tree(16, 2)))
    np.testing.assert_array_equal(fast.q, reference.q)


def test_rdo_strided_values_are_the_same(core):
    values = _smooth(50, 12, seed=5)[:, ::2]  # not contiguous
    steps = np.full(values.shape[1], 0.07)
    fast, reference = _both(rdo.quantize, values, steps, rdo.Levels.chain(50))
    np.testing.assert_array_equal(fast.q, reference.q)


def test_rdo_under_predictor_2_is_the_same(core):
    # U1's rounding against predictor 2: its predictors and residuals come from the core or
    # from numpy, and must give the same integers
    grid = 20
    rng = np.random.default_rng(8)
    values = np.cumsum(np.cumsum(rng.standard_normal((grid, grid, 6)), axis=0), axis=1)
    values = values.reshape(grid * grid, 6) * 1e-2
    steps = np.geomspace(0.01, 0.05, 6)

    def rounded() -> np.ndarray:
        mesh = MeshPrediction(grid_faces(grid), grid * grid)
        chosen = qmat.predicted_stream(qmat.quantize(values, steps).q, mesh, True, pushes=True)
        levels = rdo.Levels(mesh.parents)
        return rdo.quantize_mesh(values, steps, levels, mesh, chosen.predict, chosen.push).q

    fast, reference = _both(rounded)
    np.testing.assert_array_equal(fast, reference)


def test_rdo_refusals_are_the_same(core):
    values = _smooth(10, 3, seed=6)
    for steps in (np.array([0.1, 0.0, 0.1]), np.array([0.1, np.nan, 0.1])):
        with pytest.raises(ValueError, match="positive finite") as fast:
            rdo.quantize(values, steps, rdo.Levels.chain(10))
        with native.pure_python(), pytest.raises(ValueError, match="positive finite") as reference:
            rdo.quantize(values, steps, rdo.Levels.chain(10))
        assert str(fast.value) == str(reference.value)


def test_core_refuses_inconsistent_arguments(core):
    q = np.zeros((3, 2), dtype=np.int64)
    with pytest.raises(ValueError, match="parent 7"):
        core.rdo_residual_counts(q, np.array([-1, 0, 7]), np.ones(2, dtype=bool), 8)
    with pytest.raises(ValueError, match="before its parent"):
        core.rdo_choose(
            np.zeros((3, 2)),
            np.ones(2),
            np.array([-1, 0, 1]),
            np.array([0, 2, 1]),
            np.ones(2, dtype=bool),
            np.zeros((2, 9)),
            0.1,
        )


@pytest.mark.parametrize("seed", range(4))
def test_coded_bits_are_the_same(core, seed):
    rng = np.random.default_rng(seed)
    rows, cols = int(rng.integers(1, 120)), int(rng.integers(1, 12))
    stream = np.rint(rng.laplace(0, 10.0 ** rng.uniform(0, 4), (rows, cols))).astype(np.int64)
    order = adaptive.sequence_order(rows)
    fast, reference = _both(estimate.coded_bits, stream, order)
    assert fast == reference  # bit for bit: it ranks the trials


def test_max_abs_checks_are_the_same(core):
    vertices = wave_sequence(frames=5)
    tensor, _ = centre_frames(vertices)
    for array in (vertices, tensor, -vertices):
        fast, reference = _both(analysis._max_abs, array)
        assert fast == reference


def _refusal(vertices: np.ndarray) -> str:
    with pytest.raises(InputError) as caught:
        analysis.analyze(vertices)
    return str(caught.value)


@pytest.mark.parametrize(
    "case", ["nan", "inf", "huge", "overflowing squares", "tiny", "one point", "strided nan"]
)
def test_analysis_refusals_are_the_same(core, case):
    vertices = wave_sequence(frames=4)
    if case == "nan":
        vertices[2, 5, 1] = np.nan
    elif case == "inf":
        vertices[0, 0, 0] = -np.inf
    elif case == "huge":
        vertices = vertices * 1e300
    elif case == "overflowing squares":
        vertices = vertices * 1e154
    elif case == "tiny":
        vertices = vertices * 1e-150
    elif case == "one point":  # every frame one point, to float64's precision
        vertices = np.full((3, 4, 3), 1e6) + 1e-7 * np.arange(12.0).reshape(1, 4, 3)
    else:
        vertices = np.repeat(vertices, 2, axis=2)[:, :, ::2].copy()[:, ::-1]
        vertices[1, 1, 1] = np.nan
    fast, reference = _both(_refusal, vertices)
    assert fast == reference


@pytest.mark.parametrize("target", [0.1, 0.02])
def test_whole_encode_is_byte_identical(core, target):
    sequence = MeshSequence(wave_sequence(frames=30, grid=12), grid_faces(12))
    fast, reference = _both(lambda: encode(sequence, target_kg=target))
    assert fast == reference


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cloth-vellum.npz"])
def test_real_encode_is_byte_identical(core, name):
    sequence = shared_sequence(name)
    fast, reference = _both(lambda: encode(sequence, target_kg=0.1))
    assert fast == reference
