"""Quantized matrices, codec ``qmat`` (spec/FORMAT.md §6.3): quantization, prediction per
column (predictor 2, the mean of the decoded neighbours, only with format 1.2's coding tools
flag), and the checks of ``steps`` and ``predict``; tuckercodec/format/qmat.py."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.compressed import IDENTITY_U2
from tuckercodec import Decoder, FormatError, encode, load_sequence
from tuckercodec.format.container import pack_container, parse_container
from tuckercodec.format.faces import encode_faces
from tuckercodec.format.qmat import (
    PREDICT_LINEAR,
    PREDICT_MEAN,
    PREDICT_PARENT,
    QuantizedMatrix,
    decode_matrix,
    encode_matrix,
    quantize,
)
from tuckercodec.format.sections import uses_coding_tools
from tuckercodec.format.streams import compress, pack_integers
from tuckercodec.io.samples import sample_path
from tuckercodec.model.topology import MAX_MEAN_LEVELS, mesh_prediction


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


def _smooth_mesh(rng: np.random.Generator, side: int) -> tuple[np.ndarray, np.ndarray, int]:
    """A grid of quads (two with padding to 4 corners, as triangles) with smooth columns over
    it, plus two vertices on no face."""
    count = side * side + 2
    grid = np.arange(side * side).reshape(side, side)
    quads = np.stack([grid[:-1, :-1], grid[:-1, 1:], grid[1:, 1:], grid[1:, :-1]], axis=-1).reshape(
        -1, 4
    )
    faces = np.vstack([quads, [[0, 1, side, -1]]])
    y, x = np.divmod(np.arange(count), side)
    values = np.stack(
        [np.sin(x / 3.0) * np.cos(y / 4.0), x * y / 50.0, rng.standard_normal(count)], 1
    )
    return faces, values, count


def test_predictor_2_round_trip_needs_the_coding_tools_flag():
    rng = np.random.default_rng(2)
    faces, values, count = _smooth_mesh(rng, 24)
    mesh = mesh_prediction(faces, count)
    matrix = quantize(values, np.array([1e-3, 1e-3, 0.5]))
    params, payload = encode_matrix(matrix, mesh)
    predict = np.frombuffer(params["predict"], np.uint8).tolist()
    assert predict[:2] == [PREDICT_MEAN, PREDICT_MEAN] and predict[2] != PREDICT_MEAN
    assert uses_coding_tools([{"id": "U1", "codec": "qmat", **params}])
    for given in (mesh, lambda: mesh):
        decoded = decode_matrix(payload, params, given, "test", coding_tools=True)
        np.testing.assert_array_equal(decoded.q, matrix.q)
    with pytest.raises(FormatError, match="coding tools flag") as raised:
        decode_matrix(payload, params, mesh, "test")  # a file of format 1.0 or 1.1
    assert raised.value.rule == "R32-predictor"
    with pytest.raises(FormatError, match=r"in \[0, 1, 3\]") as raised:  # U3: no mesh
        decode_matrix(payload, params, None, "test", coding_tools=True)
    assert raised.value.rule == "R32-predictor"
    # without the coding tools, the encoder keeps to predictors 0 and 1 (format 1.0 and 1.1)
    plain_params, plain_payload = encode_matrix(matrix, mesh, coding_tools=False)
    assert not uses_coding_tools([{"id": "U1", "codec": "qmat", **plain_params}])
    assert set(np.frombuffer(plain_params["predict"], np.uint8).tolist()) <= {0, 1}
    plain = decode_matrix(plain_payload, plain_params, mesh.parents, "test")
    np.testing.assert_array_equal(plain.q, matrix.q)


def test_predictor_2_is_refused_on_a_mesh_too_deep_or_out_of_range():
    count = 2 * MAX_MEAN_LEVELS + 10
    row = np.arange(count - 2)
    strip = mesh_prediction(np.stack([row, row + 1, row + 2], 1), count)
    matrix = quantize(np.linspace(0.0, 1.0, count)[:, None], np.array([1e-3]))
    params, _ = encode_matrix(matrix, strip)
    assert params["predict"] == bytes([PREDICT_PARENT])  # too deep: the encoder keeps to 1
    # a section that says 2 anyway
    payload, planes = pack_integers(np.zeros((1, count), np.int64))
    forced = {**params, "predict": bytes([PREDICT_MEAN]), "planes": planes}
    with pytest.raises(FormatError, match=f"{MAX_MEAN_LEVELS} levels") as raised:
        decode_matrix(payload, forced, strip, "test", coding_tools=True)
    assert raised.value.rule == "R32-predictor"
    # residuals that carry a value beyond +-2**32 (each one adds 2**31 - 1 to its sources)
    faces = np.array([[0, 1, 2], [1, 2, 3], [2, 3, 4]])
    payload, planes = pack_integers(np.full((1, 5), 2**31 - 1, np.int64))
    params = {"shape": [5, 1], "planes": planes, "steps": b"\0\0\x80\x3f", "predict": b"\x02"}
    with pytest.raises(FormatError, match="outside") as raised:
        decode_matrix(payload, params, mesh_prediction(faces, 5), "test", coding_tools=True)
    assert raised.value.rule == "R32-predictor"


def test_the_sample_u1_packs_smaller_with_predictor_2():
    sequence = load_sequence(sample_path())
    data = encode(sequence, target_kg=1.0)
    container = parse_container(data)
    section = container.section("U1")
    assert section is not None
    mesh = mesh_prediction(np.asarray(sequence.faces), sequence.vertex_count)
    q = decode_matrix(
        container.payload(data, section),
        section.params,
        mesh,
        "U1",
        coding_tools=True,
        adaptive_coding=container.adaptive,
    )
    assert PREDICT_MEAN in section.params["predict"]
    assert container.coding_tools
    _, plain = encode_matrix(q, mesh, coding_tools=False)
    _, better = encode_matrix(q, mesh)
    assert len(encode_matrix(q, mesh, adaptive_coding=True)[1]) == section.length
    assert len(better) < 0.95 * len(plain)  # 5427 against 6385 bytes when written


def test_a_file_with_predictor_2_and_no_coding_tools_flag_is_refused():
    rng = np.random.default_rng(4)
    faces, values, count = _smooth_mesh(rng, 12)
    params, payload = encode_matrix(
        quantize(values, np.full(3, 1e-3)), mesh_prediction(faces, count)
    )
    assert uses_coding_tools([{"id": "U1", "codec": "qmat", **params}])
    face_params, face_payload = encode_faces(faces)
    one = np.ones(1, "<f4").tobytes()
    sections = [
        ({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload),
        ({"id": "U1", "critical": True, "codec": "qmat", **params}, payload),
        (
            {"id": "U3", "critical": True, "codec": "qmat", "shape": [1, 1], "planes": 1}
            | {"steps": one, "predict": b"\x00"},
            compress(b"\x02"),
        ),
        (
            {"id": "CORE", "critical": True, "codec": "qmat", "shape": [9, 1], "planes": 1}
            | {"steps": one, "predict": b"\x00"},
            compress(bytes(9)),
        ),
        (
            {"id": "CENT", "critical": True, "codec": "qmat", "shape": [1, 3], "planes": 1}
            | {"steps": np.ones(3, "<f4").tobytes(), "predict": b"\x00\x00\x00"},
            compress(bytes(3)),
        ),
    ]
    header = {"vertices": count, "frames": 1, "ranks": [3, 1], "u2": IDENTITY_U2}
    decoded = Decoder(pack_container(header, sections)).u1  # the flag set: decodes
    np.testing.assert_allclose(decoded, values, atol=1e-3)
    with pytest.raises(FormatError, match="coding tools flag") as raised:
        Decoder(pack_container(header, sections, coding_tools=False))
    assert raised.value.rule == "R32-predictor"


def test_predictor_3_extrapolates_along_time_and_needs_the_flag():
    """U3 and CENT (previous-row sections) may store second differences (format 1.2): a smooth
    column is then nearly all zeros."""
    t = np.arange(50, dtype=np.float64)
    values = np.stack([3.0 * t + 7.0, np.sin(t / 5.0), np.zeros(50)], axis=1)
    matrix = quantize(values, np.array([0.5, 1e-3, 1.0]))
    params, payload = encode_matrix(matrix, None)
    predict = np.frombuffer(params["predict"], np.uint8).tolist()
    assert predict[0] == PREDICT_LINEAR  # a straight line: second differences all 0
    assert uses_coding_tools([{"id": "U3", "codec": "qmat", **params}])
    decoded = decode_matrix(payload, params, None, "test", coding_tools=True)
    np.testing.assert_array_equal(decoded.q, matrix.q)
    with pytest.raises(FormatError, match="3 needs the coding tools flag") as raised:
        decode_matrix(payload, params, None, "test")
    assert raised.value.rule == "R32-predictor"
    plain, _ = encode_matrix(matrix, None, coding_tools=False)
    assert PREDICT_LINEAR not in np.frombuffer(plain["predict"], np.uint8)


def test_predictor_3_refuses_values_out_of_range():
    residual = np.zeros((4, 1), np.int64)
    residual[0, 0] = 2**31 - 1  # then 2**31 - 1 more each row: 3 * (2**31 - 1) > 2**32
    residual[1, 0] = 2**31 - 1
    payload, planes = pack_integers(np.ascontiguousarray(residual.T))
    params = {
        "shape": [4, 1],
        "planes": planes,
        "steps": np.array([1.0], "<f4").tobytes(),
        "predict": bytes([PREDICT_LINEAR]),
    }
    with pytest.raises(FormatError, match="leaves the range") as raised:
        decode_matrix(payload, params, None, "test", coding_tools=True)
    assert raised.value.rule == "R32-predictor"


def test_the_encoder_uses_predictor_3_only_where_a_decoder_accepts_it():
    """A column that grows past 2**32 in small steps (a fast-moving centroid at a tight target)
    fits predictor 1 but not 3's range (R32): the encoder must not choose 3 for it."""
    t = np.arange(40, dtype=np.int64)
    q = np.stack([t * 2**30, t * 3], axis=1)
    matrix = QuantizedMatrix(q, np.array([1.0, 1.0], np.float32))
    params, payload = encode_matrix(matrix, None)
    assert np.frombuffer(params["predict"], np.uint8)[0] != PREDICT_LINEAR
    decoded = decode_matrix(payload, params, None, "test", coding_tools=True)
    np.testing.assert_array_equal(decoded.q, q)
