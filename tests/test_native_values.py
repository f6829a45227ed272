"""The compiled core's fused decoding of a mesh-predicted qmat section (U1): from the stream's
bytes to the dequantized floats in one pass, on threads, against the pure-Python reference
(``decode_matrix(...).values()``): the same floats to the bit, or the same error."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tests.test_native_prediction import assert_same, both, random_faces
from tuckercodec.format import adaptive, qmat, streams
from tuckercodec.model.topology import MeshPrediction
from tuckercodec.system import native


@pytest.fixture(autouse=True)
def _needs_core() -> None:
    if native.core() is None:
        pytest.skip("the compiled core is not installed (python -m tools.build_native)")


def variants(
    rng: np.random.Generator, params: dict[str, Any], payload: bytes, size: int
) -> list[tuple[dict[str, Any], bytes]]:
    """The section as encoded, with every column on predictor 2, and broken ways."""
    cols = len(params["predict"])
    meaned = dict(params, predict=bytes([qmat.PREDICT_MEAN] * cols))
    wild = dict(meaned)
    stream = rng.integers(-(2**31), 2**31, size=size)
    wild_payload, wild["planes"] = streams.pack_integers(stream, level=1)
    return [
        (params, payload),
        (meaned, payload),  # the residuals of other predictors restored with 2
        (wild, wild_payload),  # values that leave the range of predictor 2
        (meaned, payload[: len(payload) // 2]),  # a cut zstd frame
        (dict(meaned, steps=params["steps"][:-1]), payload),  # steps of the wrong length
    ]


def random_mesh_matrix(rng: np.random.Generator) -> tuple[np.ndarray, qmat.QuantizedMatrix]:
    """A random mesh's faces and a smooth quantized U1 on it, of up to 39 columns (up to five
    blocks of columns, which the core's threads share)."""
    count = int(rng.integers(3, 150))
    faces = random_faces(rng, count, 2 * count)
    cols = int(rng.integers(1, 40))
    values = np.cumsum(rng.integers(-500, 501, size=(count, cols)), axis=0)
    steps = rng.uniform(1e-4, 1.0, size=cols).astype(np.float32)
    return faces, qmat.QuantizedMatrix(values, steps)


def assert_fused_as_reference(decode: Any, reference: Any) -> None:
    """The fused path (``decode``) gives what the pure path and the pure-Python reference give:
    the same values, or the same error."""
    fused, pure = both(decode)
    assert_same(fused, pure)
    with native.pure_python():
        expected = both(reference)[1]
    if isinstance(expected, qmat.QuantizedMatrix):
        expected = expected.values()
    assert_same(fused, expected)


@pytest.mark.parametrize("seed", range(8))
def test_mesh_sections_decode_to_the_same_values(seed: int) -> None:
    rng = np.random.default_rng(300 + seed)
    faces, matrix = random_mesh_matrix(rng)
    count, cols = matrix.q.shape
    params, payload = qmat.encode_matrix(matrix, MeshPrediction(faces, count), level=1)
    for mutated, data in variants(rng, params, payload, count * cols):
        for tools in [True, False]:

            def decode(
                mutated: dict[str, Any] = mutated, data: bytes = data, tools: bool = tools
            ) -> Any:
                mesh = lambda: MeshPrediction(faces, count)  # noqa: E731
                return qmat.decode_values(data, mutated, mesh, "test", coding_tools=tools)

            def reference(
                mutated: dict[str, Any] = mutated, data: bytes = data, tools: bool = tools
            ) -> Any:
                mesh = MeshPrediction(faces, count)
                return qmat.decode_matrix(data, mutated, mesh, "test", coding_tools=tools)

            assert_fused_as_reference(decode, reference)


def adaptive_variants(
    rng: np.random.Generator, params: dict[str, Any], mesh: MeshPrediction, count: int
) -> list[tuple[dict[str, Any], bytes]]:
    """An adaptive section (§6.14) whose every column has predictor 2, and broken ways."""
    cols = len(params["predict"])
    meaned = dict(params, predict=bytes([qmat.PREDICT_MEAN] * cols), coder=1)
    meaned.pop("mean_push", None)
    order = qmat.coding_order(mesh, count)

    def coded(stream: np.ndarray) -> bytes:
        return adaptive.encode_columns(np.ascontiguousarray(stream.reshape(cols, count)), order)

    smooth = np.cumsum(rng.integers(-40, 41, size=(cols, count)), axis=1)
    wild = rng.integers(-(2**31), 2**31, size=(cols, count))
    payload = coded(smooth)
    pushed = dict(meaned, mean_push=bytes(rng.integers(0, 4, size=cols).astype(np.uint8)))
    return [
        (dict(meaned, planes=4), payload),
        (dict(pushed, planes=4), payload),  # pushes other than 2
        (dict(meaned, planes=1), payload),  # integers outside the planes (R46)
        (dict(meaned, planes=4), coded(wild)),  # values that leave the range of predictor 2
        (dict(meaned, planes=1), coded(wild)),  # both: the planes' error comes first
        (dict(meaned, planes=4), payload[: len(payload) // 2]),  # a cut stream
        (dict(meaned, planes=4), payload + b"\0"),  # a byte too many
        (dict(meaned, planes=4, steps=params["steps"][:-1]), payload),  # steps too short
    ]


@pytest.mark.parametrize("seed", range(8))
def test_adaptive_mesh_sections_decode_to_the_same_values(seed: int) -> None:
    rng = np.random.default_rng(700 + seed)
    faces, matrix = random_mesh_matrix(rng)
    count = matrix.q.shape[0]
    mesh = MeshPrediction(faces, count)
    params, _ = qmat.encode_matrix(matrix, mesh, level=1)
    for mutated, data in adaptive_variants(rng, params, mesh, count):

        def decode(mutated: dict[str, Any] = mutated, data: bytes = data) -> Any:
            mesh = lambda: MeshPrediction(faces, count)  # noqa: E731
            return qmat.decode_values(
                data, mutated, mesh, "test", coding_tools=True, adaptive_coding=True
            )

        def reference(mutated: dict[str, Any] = mutated, data: bytes = data) -> Any:
            mesh = MeshPrediction(faces, count)
            return qmat.decode_matrix(
                data, mutated, mesh, "test", coding_tools=True, adaptive_coding=True
            )

        assert_fused_as_reference(decode, reference)
