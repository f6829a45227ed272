"""The compiled core's integer streams (spec/FORMAT.md §6.1) and prediction (§6.2, §6.3) against
the pure-Python reference: the same integers, floats to the bit, bytes, and errors (rule, field
and message), on the conformance vectors, the shared sequences, and random and mutated inputs."""

from __future__ import annotations

import functools
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import shared_case, shared_encoded, shared_sequence
from tuckercodec import Decoder, FormatError
from tuckercodec.format import prediction, qmat, streams
from tuckercodec.model import topology
from tuckercodec.model.topology import MeanSteps, MeshPrediction
from tuckercodec.system import native

ROOT = Path(__file__).resolve().parents[1]
VECTORS = sorted((ROOT / "spec" / "vectors").glob("*.json"))
SHARED = ["samba.npz", "chicken.npz", "cloth-vellum.npz", "horse-gallop"]


@pytest.fixture(autouse=True)
def _needs_core() -> None:
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")


def outcome(run: Callable[[], Any]) -> Any:
    """What ``run`` gives, or the error it raises as (class, rule, field, message)."""
    try:
        return run()
    except (FormatError, ValueError) as error:
        return (
            type(error).__name__,
            getattr(error, "rule", None),
            getattr(error, "field", None),
            str(error),
        )


def both(run: Callable[[], Any]) -> tuple[Any, Any]:
    """``run`` with the core, then in pure Python."""
    with_core = outcome(run)
    with native.pure_python():
        reference = outcome(run)
    return with_core, reference


def assert_same(left: Any, right: Any) -> None:
    """Equal to the bit: arrays by dtype, shape and bytes, containers member by member."""
    if isinstance(left, np.ndarray) or isinstance(right, np.ndarray):
        assert isinstance(left, np.ndarray) and isinstance(right, np.ndarray), (left, right)
        assert left.dtype == right.dtype and left.shape == right.shape
        assert np.ascontiguousarray(left).tobytes() == np.ascontiguousarray(right).tobytes()
    elif isinstance(left, (tuple, list)):
        assert type(left) is type(right) and len(left) == len(right), (left, right)
        for a, b in zip(left, right, strict=True):
            assert_same(a, b)
    elif isinstance(left, qmat.QuantizedMatrix):
        assert isinstance(right, qmat.QuantizedMatrix)
        assert_same(left.q, right.q)
        assert_same(left.steps, right.steps)
        assert_same(left.values(), right.values())
    else:
        assert left == right


def decoded(data: bytes) -> Any:
    """Every frame and every dequantized factor of a file (or its error)."""
    decoder = Decoder(data)
    positions = decoder.positions()
    factors = [decoder.segment_factors(n) for n in range(len(decoder.segments))]
    arrays = [positions] + [array for f in factors for array in (f.u1, f.u3, f.core, f.centroids)]
    return [decoder.frame(0), *arrays]


# -- conformance vectors and shared sequences -------------------------------------------------


@pytest.mark.parametrize("path", VECTORS, ids=lambda p: p.stem)
def test_vectors_decode_the_same(path: Path) -> None:
    expected = json.loads(path.read_text())
    data = (path.parent / expected["file"]).read_bytes()
    assert_same(*both(lambda: decoded(data)))


@pytest.mark.parametrize("name", [shared_case(n) for n in SHARED])
def test_shared_sequences_decode_the_same(name: str) -> None:
    data = shared_encoded(name).data
    assert_same(*both(lambda: decoded(data)))


@pytest.mark.parametrize("name", [shared_case(n) for n in SHARED])
def test_shared_meshes_predict_the_same(name: str) -> None:
    sequence = shared_sequence(name)
    faces, count = sequence.faces, sequence.vertex_count
    frames = sequence.vertices[:: max(1, sequence.vertices.shape[0] // 8)]
    # U1-like columns: the coordinates of a few frames, quantized as smooth integers
    values = np.rint(frames.transpose(1, 0, 2).reshape(count, -1) / 1e-4).astype(np.int64)
    compare_mesh(faces, count, values)


def compare_mesh(faces: np.ndarray, count: int, values: np.ndarray) -> None:
    """The forest, predictor 2's steps and matrix, and every predictor both ways on ``values``
    (count, columns)."""

    def relations() -> Any:
        mesh = MeshPrediction(faces, count)
        levels = mesh.levels
        steps = mesh.mean_steps
        arrays = [steps.rows, steps.step_ends, steps.sources, steps.anchors, steps.source_ends]
        return [mesh.parents, topology.mesh_parents(faces, count), levels, steps.levels, *arrays]

    assert_same(*both(relations))
    with native.pure_python():
        mesh = MeshPrediction(faces, count)
        steps = mesh.mean_steps
        matrix = steps.matrix
    native_steps = MeshPrediction(faces, count).mean_steps
    assert_same(list(native_steps.native_plan().matrix()), list(matrix))
    compare_predictors(values, mesh.parents, steps)


def compare_predictors(values: np.ndarray, parents: np.ndarray, steps: MeanSteps) -> None:
    """Residuals and their restoring, with each predictor, both ways, on ``values``."""
    mean = both(lambda: prediction.mean_residuals(values, steps))
    assert_same(*mean)
    tree = prediction.residuals(values, parents)
    assert_same(*both(lambda: prediction.accumulate(tree, parents)))
    assert_same(*both(lambda: prediction.accumulate(tree.copy(), parents, in_place=True)))
    assert_same(*both(lambda: prediction.accumulate(tree, None)))
    assert_same(*both(lambda: prediction.linear_accumulate(tree)))
    if mean[0] is None or isinstance(mean[0], tuple):
        return
    residual = mean[0]
    assert_same(*both(lambda: prediction.mean_accumulate(residual, steps)))

    def columns() -> np.ndarray:
        restored = np.ascontiguousarray(residual.T)
        prediction.mean_accumulate_columns(restored, steps)
        return restored

    restored = both(columns)
    assert_same(*restored)
    if not isinstance(restored[0], tuple):
        assert_same(restored[0].T, values)


# -- random and mutated inputs -----------------------------------------------------------------


def random_faces(rng: np.random.Generator, count: int, rows: int) -> np.ndarray:
    """A face table with triangles, quads padded to triangles, repeats and lone vertices."""
    faces = rng.integers(0, max(count - 2, 1), size=(rows, 4))
    faces[rng.random(rows) < 0.4, 3] = -1  # triangles beside quads
    strip = np.arange(count - 3)[:, None] + np.arange(3)  # a long strip: a deep forest
    strip = np.hstack([strip, np.full((strip.shape[0], 1), -1)])
    return np.vstack([faces, strip[: rows // 2]]) if rng.random() < 0.5 else faces


@pytest.mark.parametrize("seed", range(12))
def test_random_meshes_predict_the_same(seed: int) -> None:
    rng = np.random.default_rng(seed)
    count = int(rng.integers(4, 300))
    faces = random_faces(rng, count, int(rng.integers(1, 3 * count)))
    span = [2**8, 2**20, 2**31, 2**33][seed % 4]  # the last leaves predictor 2's range
    smooth = np.cumsum(rng.integers(-span, span + 1, size=(count, 5)), axis=0) // count
    values = np.hstack([smooth, rng.integers(-span, span + 1, size=(count, 2))])
    compare_mesh(faces, count, values)
    # residuals that restore out of range, and values at the limits
    wild = rng.integers(-(2**31), 2**31, size=(count, 3))
    compare_predictors(
        wild, MeshPrediction(faces, count).parents, MeshPrediction(faces, count).mean_steps
    )
    edge = np.full((count, 2), prediction.MEAN_LIMIT)
    edge[::2, 1] = -prediction.MEAN_LIMIT - seed % 2
    compare_predictors(
        edge, MeshPrediction(faces, count).parents, MeshPrediction(faces, count).mean_steps
    )


def test_meshes_without_edges_and_empty() -> None:
    for faces, count in [
        (np.zeros((0, 3), dtype=np.int64), 5),
        (np.array([[1, 1, 1]]), 3),
        (np.array([[0, 1, 2, -1], [2, 3, 4, 5]]), 9),
    ]:
        compare_mesh(faces, count, np.arange(count * 2, dtype=np.int64).reshape(count, 2))


def test_crafted_mesh_restores_in_int64_the_same() -> None:
    """A row of 2**17 sources (only a crafted mesh has one): the int64 path, not the floats."""
    sources = np.zeros(2**17, dtype=np.int64)
    sources[1::2] = 2
    steps = MeanSteps(
        rows=np.array([1, 3]),
        step_ends=np.array([0, 1, 2]),
        sources=np.concatenate([sources, [1]]),
        anchors=np.concatenate([np.zeros(2**17, dtype=np.int64), [1]]),
        source_ends=np.array([0, 2**17, 2**17 + 1]),
        levels=2,
    )
    rng = np.random.default_rng(5)
    for span in [2**10, 2**31]:
        values = rng.integers(-span, span, size=(4, 3))
        compare_predictors(values, np.array([-1, 0, -1, 1]), steps)


@pytest.mark.parametrize("seed", range(8))
def test_streams_pack_and_unpack_the_same(seed: int) -> None:
    rng = np.random.default_rng(seed)
    bits = [4, 9, 17, 31, 40, 63][seed % 6]
    values = rng.integers(-(2**bits), 2**bits, size=int(rng.integers(0, 5000)))
    if seed == 7:
        values = np.array([np.iinfo(np.int64).min, np.iinfo(np.int64).max, 0, -1])
    packed = both(lambda: streams.pack_integers(values, level=1))
    assert_same(*packed)
    if isinstance(packed[0], tuple) and isinstance(packed[0][0], bytes):
        payload, planes = packed[0]
        assert_same(*both(lambda: streams.unpack_integers(payload, values.size, planes, "s")))
        # wrong counts, wrong planes, mutated and cut payloads: the same values or error
        for count, wanted in [(values.size + 1, planes), (values.size, planes + 1)]:
            assert_same(
                *both(functools.partial(streams.unpack_integers, payload, count, wanted, "s"))
            )
        for _ in range(10):
            broken = bytearray(payload)
            if broken and rng.random() < 0.7:
                broken[int(rng.integers(len(broken)))] ^= 1 << int(rng.integers(8))
            else:
                broken = broken[: int(rng.integers(len(broken) + 1))]
            raw = bytes(broken)
            unpack = functools.partial(streams.unpack_integers, raw, values.size, planes, "s")
            assert_same(*both(unpack))


@pytest.mark.parametrize("seed", range(10))
def test_qmat_sections_decode_the_same(seed: int) -> None:
    """Random and mutated sections: predictors 0-3, a mesh or the previous row, with and without
    the coding tools; the same matrix or the same error."""
    rng = np.random.default_rng(100 + seed)
    count = int(rng.integers(3, 120))
    faces = random_faces(rng, count, 2 * count)
    cols = int(rng.integers(1, 6))
    values = np.cumsum(rng.integers(-50, 51, size=(count, cols)), axis=0)
    matrix = qmat.QuantizedMatrix(values, np.full(cols, 0.5, dtype=np.float32))
    for relation in ["mesh", "rows"]:
        parents = MeshPrediction(faces, count) if relation == "mesh" else None
        params, payload = qmat.encode_matrix(matrix, parents, level=1)
        for _ in range(6):
            mutated = dict(params)
            predict = np.frombuffer(params["predict"], np.uint8).copy()
            choice = rng.random()
            if choice < 0.5:  # another predictor for the same residuals
                predict[int(rng.integers(cols))] = rng.integers(0, 4)
            elif choice < 0.7:
                stream = rng.integers(-(2**31), 2**31, size=count * cols)
                payload, mutated["planes"] = streams.pack_integers(stream, level=1)
            mutated["predict"] = predict.tobytes()
            tools = bool(rng.random() < 0.8)

            def decode(
                mutated: dict[str, Any] = mutated,
                tools: bool = tools,
                payload: bytes = payload,
                on_mesh: bool = relation == "mesh",
            ) -> Any:
                mesh = MeshPrediction(faces, count) if on_mesh else None
                return qmat.decode_matrix(payload, mutated, mesh, "test", coding_tools=tools)

            assert_same(*both(decode))


def test_decoding_imports_no_scipy() -> None:
    """A process that only decodes a file with predictor 2 (format 1.2) never imports scipy."""
    vector = ROOT / "spec" / "vectors" / "v1.2-traverse-triangles.tkc"
    code = (
        "import sys; from tuckercodec import Decoder; "
        f"Decoder(open({str(vector)!r}, 'rb').read()).frame(0); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT), "TUCKERCODEC_NATIVE": "1"}
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"
