"""Quantized matrices, codec ``qmat`` (spec/FORMAT.md §6.3): quantization, prediction per
column, and the checks of ``steps`` and ``predict``; tuckercodec/format/qmat.py."""

from __future__ import annotations

import numpy as np
import pytest

from tuckercodec import FormatError
from tuckercodec.format.qmat import decode_matrix, encode_matrix, quantize


def test_quantized_matrix_round_trip_with_prediction():
    rng = np.random.default_rng(0)
    smooth = np.cumsum(rng.standard_normal((200, 3)), axis=0)
    noisy = rng.standard_normal((200, 2))
    values = np.hstack([smooth, noisy])
    matrix = quantize(values, np.array([0.01, 0.02, 0.05, 0.1, 0.1]))
    params, payload = encode_matrix(matrix, None)
    assert np.frombuffer(params["predict"], np.uint8).tolist() == [1, 1, 1, 0, 0]
    decoded = decode_matrix(payload, params, None, "test")
    np.testing.assert_array_equal(decoded.q, matrix.q)
    assert np.abs(decoded.values() - values).max() <= 0.05 + 1e-12
    with pytest.raises(FormatError, match="predictor must be 0") as raised:
        decode_matrix(payload, params, None, "test", allow_predict=False)
    assert raised.value.rule == "R32-predictor"
    with pytest.raises(FormatError, match="steps must be") as raised:
        decode_matrix(payload, {**params, "steps": params["steps"][:-4]}, None, "test")
    assert raised.value.rule == "R31-steps"


def test_quantization_refuses_steps_too_small_for_the_integers():
    with pytest.raises(ValueError, match="integer range"):
        quantize(np.array([[1.0]]), np.array([1e-20]))
    # within float64's exact integers, but not the 32-bit stream: refused when packed
    with pytest.raises(ValueError, match="32-bit"):
        encode_matrix(quantize(np.array([[1.0], [1.0]]), np.array([1e-12])), None)
