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
from tuckercodec.format.prediction import mean_residuals
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


def _polygons(rng: np.random.Generator, count: int, faces: int) -> np.ndarray:
    """Random triangles, quads and pentagons (padded with -1) over ``count`` vertices."""
    table = rng.integers(0, count, size=(faces, 5), dtype=np.int64)
    corners = rng.integers(3, 6, size=faces)
    table[np.arange(5)[None, :] >= corners[:, None]] = -1
    return table


MEAN_MESHES = {
    "grid": lambda rng: (grid_faces(13), 169),
    "polygons": lambda rng: (_polygons(rng, 90, 160), 90),
    "dense polygons": lambda rng: (_polygons(rng, 25, 120), 25),
    "two pieces and loose vertices": lambda rng: (
        np.concatenate([grid_faces(6), grid_faces(4) + 36]),
        60,
    ),
    "no faces": lambda rng: (np.zeros((0, 3), dtype=np.int64), 7),
}


def _same_mean_choice(core, values, steps, mean, push, residual, lam) -> np.ndarray:
    """rdo._mean_choice in the core and in numpy, its bits from the counts of ``residual``: the
    same integers (returned)."""
    counts = rdo._residual_counts(residual)
    reference = rdo._mean_choice(values, steps, mean, push, counts, lam)
    fast = rdo._native_mean_choice(core, values, steps, mean, push, counts, lam)
    assert fast.dtype == np.int64
    np.testing.assert_array_equal(fast, reference)
    return reference


def _random_value_table(table: np.ndarray) -> np.ndarray:
    """A value table of random bits, the same for the same number of columns: every entry
    differs from its neighbours, so that an index one off changes choices."""
    rng = np.random.default_rng(table.shape[0])
    return rng.random((table.shape[0], 2 * rdo.VALUE_TABLE_HALF + 1)) * 8.0


@pytest.mark.parametrize("mesh", sorted(MEAN_MESHES))
@pytest.mark.parametrize("seed", range(3))
def test_rdo_mean_choice_is_the_same(core, monkeypatch, mesh, seed):
    if seed == 2:  # bits that no histogram makes: an index one off changes choices
        monkeypatch.setattr(rdo, "_value_table", _random_value_table)
    rng = np.random.default_rng(seed)
    faces, count = MEAN_MESHES[mesh](rng)
    mean = MeshPrediction(faces, count).mean_steps
    cols = 10
    push = np.arange(cols, dtype=np.uint8)  # every push 0..9
    steps = np.geomspace(0.01, 0.05, cols)
    smooth = _smooth(count, cols, seed, scale=0.3)
    half_steps = np.rint(smooth / steps * 2.0) * 0.5 * steps  # floors and ceilings tie
    # large: residuals through the bit table's escapes and past the value table's edges
    large = smooth * 1e3 + rng.choice([-1.0, 1.0], cols) * rdo.VALUE_TABLE_HALF * steps
    for values in (smooth, half_steps, large, -large):
        nearest = qmat.quantize(values, steps)
        residual = mean_residuals(nearest.q, mean, push)
        assert residual is not None
        noise = rng.integers(-3, 4, residual.shape)  # a table that does not fit the values
        steps64 = nearest.steps.astype(np.float64)
        for lam in (0.0, 0.05, 0.4, 30.0):
            for table_of in (residual, noise):
                q = _same_mean_choice(core, values, steps64, mean, push, table_of, lam)
                assert np.isin(q - np.floor(values / steps64), (0, 1)).all()


@pytest.mark.parametrize("random_bits", [False, True])
def test_rdo_mean_choice_at_the_value_table_edges(core, monkeypatch, random_bits):
    # roots (predicted by 0) whose floor lies at and around the table's edges, -half and half - 1,
    # where the reference clips the index, and far beyond them
    if random_bits:
        monkeypatch.setattr(rdo, "_value_table", _random_value_table)
    half = rdo.VALUE_TABLE_HALF
    mean = MeshPrediction(np.zeros((0, 3), dtype=np.int64), 12).mean_steps
    floors = np.array([-half - 2, -half - 1, -half, -half + 1, half - 2, half - 1, half, half + 1])
    floors = np.concatenate([floors, [-(1 << 30), 1 << 30, 0, -1]])
    rng = np.random.default_rng(5)
    cols = 16
    values = floors[:, None] + rng.random((12, cols))
    values[:, 3] = floors + 0.5  # ties
    steps = np.ones(cols)
    residual = rng.integers(-half - 100, half + 100, (50, cols))
    for lam in (0.0, 0.05, 3.0):
        _same_mean_choice(core, values, steps, mean, np.full(cols, 2), residual, lam)


def test_rdo_mean_choice_blocks_of_columns_are_the_same(core, monkeypatch):
    # a block per column, and a few columns per block: the same integers as one block
    grid = 16
    rng = np.random.default_rng(9)
    values = np.cumsum(np.cumsum(rng.standard_normal((grid, grid, 40)), axis=0), axis=1)
    values = values.reshape(grid * grid, 40) * 1e-2
    steps = np.geomspace(0.005, 0.05, 40)
    mesh = MeshPrediction(grid_faces(grid), grid * grid)
    chosen = qmat.predicted_stream(qmat.quantize(values, steps).q, mesh, True, pushes=True)
    assert (chosen.predict == qmat.PREDICT_MEAN).sum() > 20  # what this test is about
    levels = rdo.Levels(mesh.parents)

    def rounded() -> np.ndarray:
        return rdo.quantize_mesh(values, steps, levels, mesh, chosen.predict, chosen.push).q

    whole = rounded()
    for block in (1, 3 * grid * grid):
        monkeypatch.setattr(rdo, "MEAN_BLOCK_VALUES", block)
        fast, reference = _both(rounded)
        np.testing.assert_array_equal(fast, reference)
        np.testing.assert_array_equal(fast, whole)


@pytest.mark.parametrize("mesh", sorted(MEAN_MESHES))
@pytest.mark.parametrize("cols", [1, 2, 16, 17, 33])
def test_push_choice_is_the_same(core, mesh, cols):
    # qmat._pushed_mean: the core prices every push of every column at once (numpy's log2 of
    # each residual from a table, summed in numpy's order: pairwise for a column alone in its
    # block of 16, as the 17th and the 33rd are), the reference forms each push's residuals
    rng = np.random.default_rng(cols)
    faces, count = MEAN_MESHES[mesh](rng)
    steps = MeshPrediction(faces, count).mean_steps
    smooth = np.rint(_smooth(count, cols, cols, scale=40.0)).astype(np.int64)
    mixed = smooth.copy()
    mixed[:, ::3] *= 10**4  # residuals beyond the core's table: those blocks priced by numpy
    constant = np.full((count, cols), 7, dtype=np.int64)  # every push ties: PUSH is kept
    beyond = smooth.copy()
    beyond[0, -1] = 2**33  # out of predictor 2's range: no residuals, every push PUSH
    # the prices themselves, to the bit
    costs = steps.native_plan().push_costs(smooth, qmat._log2_table(), 16)
    for a in range(10):
        residual = mean_residuals(smooth, steps, np.full(cols, a, dtype=np.uint8))
        assert residual is not None
        assert costs[:, a].tobytes() == qmat._cost(residual).tobytes()
    pushes = []
    for q in (smooth, mixed, -mixed, constant, beyond):
        (fast, fast_push), (reference, push) = _both(qmat._pushed_mean, q, steps, True)
        np.testing.assert_array_equal(fast_push, push)
        if reference is None:
            assert fast is None
        else:
            np.testing.assert_array_equal(fast, reference)
        pushes.append(push)
    assert (pushes[3] == 2).all() and (pushes[4] == 2).all()


@pytest.mark.parametrize("mesh", sorted(MEAN_MESHES))
def test_mean_residual_counts_are_the_same(core, mesh):
    # quantize_mesh's histograms: counted by the core without the residuals, or from numpy's
    rng = np.random.default_rng(3)
    faces, count = MEAN_MESHES[mesh](rng)
    steps = MeshPrediction(faces, count).mean_steps
    smooth = np.rint(_smooth(count, 12, 4, scale=300.0)).astype(np.int64)
    push = np.arange(12, dtype=np.uint8) % 10
    for q, meaned in (
        (smooth, np.arange(12)),  # every column
        (smooth, np.array([1, 4, 5, 11])),  # some
        (smooth * 10**6, np.arange(0, 12, 2)),  # residuals past the table, clipped
        (smooth + 2**32, np.arange(12)),  # out of predictor 2's range
    ):
        fast, reference = _both(rdo._mean_residual_counts, q, meaned, steps, push[meaned])
        if reference is None:
            assert fast is None
        else:
            assert fast.dtype == reference.dtype and fast.shape == (meaned.size, rdo.TABLE_SIZE + 1)
            np.testing.assert_array_equal(fast, reference)


def test_core_refuses_inconsistent_mean_steps(core):
    mean = MeshPrediction(grid_faces(4), 16).mean_steps
    arrays = [mean.rows, mean.step_ends, mean.sources, mean.anchors, mean.source_ends]
    table = np.zeros((2, 2 * 8 + 1))
    args = (np.zeros((16, 2)), np.ones(2), *arrays, np.full(2, 2), table)
    assert core.rdo_mean_choice(*args, 8, 0.1).shape == (16, 2)
    with pytest.raises(ValueError, match="value table"):
        core.rdo_mean_choice(*args, 7, 0.1)
    # every row in one step: rows read rows of their own step
    whole = np.array([0, mean.rows.size])
    with pytest.raises(ValueError, match="not chosen before its step"):
        core.rdo_mean_choice(args[0], args[1], arrays[0], whole, *arrays[2:], *args[7:], 8, 0.1)


@pytest.mark.slow
def test_rdo_mean_choice_on_a_real_encode(core, monkeypatch):
    # every call the encoder makes on a real mesh, checked against the reference as it runs
    calls = []
    native_choice = rdo._native_mean_choice

    def checked(core, values, steps, mean, push, counts, lam):
        calls.append(values.shape)
        fast = native_choice(core, values, steps, mean, push, counts, lam)
        reference = rdo._mean_choice(values, steps, mean, push, counts, lam)
        np.testing.assert_array_equal(fast, reference)
        return fast

    monkeypatch.setattr(rdo, "_native_mean_choice", checked)
    plain = encode(shared_sequence("cloth-vellum.npz"), target_kg=0.1)
    assert calls
    monkeypatch.setattr(rdo, "_native_mean_choice", native_choice)
    assert encode(shared_sequence("cloth-vellum.npz"), target_kg=0.1) == plain


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
