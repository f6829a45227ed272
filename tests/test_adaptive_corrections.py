"""Format 1.7: corrections stored as adaptive streams (spec §6.9 ``coder`` 1, flag bit 4).

The encoder codes a RESD section's chunks both ways and keeps the adaptive streams only where
they are smaller by more than ``ADAPTIVE_GAIN``; the stream holds the same integers, so the
decoded bits are the same. The conformance vectors (``v1.7-*``, ``R46-adaptive-stream-resd*``,
``R29-zstd-content-size-resd-coder``) hold the decoders to the layout and the rules."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest

import tuckercodec as tc
from tuckercodec import Decoder, MeshSequence
from tuckercodec.format import adaptive, residual
from tuckercodec.format.container import parse_container
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.io.samples import sheet_triangles, wave_sheet
from tuckercodec.system import native

FLOAT32 = residual.Domain(residual.FLOAT32)


def _float32_sheet() -> MeshSequence:
    """A sheet of float32 values: its lossless corrections are binary32 steps, many of them."""
    return MeshSequence(wave_sheet(20, 8).astype(np.float32).astype(np.float64), sheet_triangles(8))


def _resd(data: bytes) -> dict[str, object]:
    entry = parse_container(data, DEFAULT_LIMITS).section("RESD")
    assert entry is not None
    return dict(entry.params)


def test_a_lossless_file_keeps_adaptive_chunks_where_smaller_and_is_bit_exact():
    sequence = _float32_sheet()
    data = tc.encode(sequence, lossless=True)
    assert _resd(data).get("coder") == adaptive.CODER_ADAPTIVE
    assert tc.info(data).format_version == "1.7"
    container = parse_container(data, DEFAULT_LIMITS)
    assert container.adaptive_corrections and container.corrections
    decoded = Decoder(data).positions()
    assert np.array_equal(decoded.view(np.int64), sequence.vertices.view(np.int64))


def _integers(seed: int, frames: int = 6, vertices: int = 40) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.laplace(scale=300.0, size=(frames, vertices, 3)).astype(np.int64)


@pytest.mark.parametrize("predict", [0, 1])
def test_adaptive_chunks_read_back_and_the_reference_writes_the_same_bytes(predict):
    integers = _integers(1)
    integers[2, 5, 1] = 2**62  # past 32 bits: more than 4 planes
    params, payload = residual.encode_section(
        integers, FLOAT32, 3, predict=predict, chunk_frames=4, adaptive_coding=True,
        adaptive_gain=-1.0,
    )  # fmt: skip
    assert params["coder"] == adaptive.CODER_ADAPTIVE and params["predict"] == predict
    with native.pure_python():
        assert residual.encode_section(
            integers, FLOAT32, 3, predict=predict, chunk_frames=4, adaptive_coding=True,
            adaptive_gain=-1.0,
        ) == (params, payload)  # fmt: skip
    frames, vertices, _ = integers.shape
    layout = residual.read_layout(
        params, len(payload), frames, vertices, DEFAULT_LIMITS, "RESD", adaptive_corrections=True
    )
    assert layout.coder == adaptive.CODER_ADAPTIVE and layout.planes[0] == 8
    chunks = [
        residual.decode_chunk(payload, layout, n, vertices, "RESD")
        for n in range(len(layout.planes))
    ]
    assert np.array_equal(np.concatenate(chunks), integers)


def test_coder_is_an_unknown_parameter_without_flag_bit_4():
    integers = _integers(2)
    params, payload = residual.encode_section(integers, FLOAT32, 3, predict=0)
    frames, vertices, _ = integers.shape
    for coder in (1, 2, "adaptive"):
        layout = residual.read_layout(
            {**params, "coder": coder}, len(payload), frames, vertices, DEFAULT_LIMITS, "RESD"
        )
        assert layout.coder == adaptive.CODER_ZSTD


@pytest.mark.parametrize("coder", [2, -1, True, "1", 1.0])
def test_a_coder_other_than_0_or_1_is_refused_with_flag_bit_4(coder):
    integers = _integers(3)
    params, payload = residual.encode_section(integers, FLOAT32, 3, predict=0)
    frames, vertices, _ = integers.shape
    with pytest.raises(tc.FormatError) as caught:
        residual.read_layout(
            {**params, "coder": coder},
            len(payload),
            frames,
            vertices,
            DEFAULT_LIMITS,
            "RESD",
            adaptive_corrections=True,
        )
    assert caught.value.rule == "R46-adaptive-stream"


def test_zstd_is_kept_unless_the_adaptive_chunks_gain_enough():
    integers = _integers(4)
    zstd_only = residual.encode_section(integers, FLOAT32, 3, predict=0)
    # no gain is enough: the section is the zstd one, byte for byte
    never = residual.encode_section(
        integers, FLOAT32, 3, predict=0, adaptive_coding=True, adaptive_gain=1.0
    )
    assert never == zstd_only and "coder" not in never[0]


def test_minus_2_to_the_63_stays_in_zstd_planes():
    """§6.14 codes bit lengths up to 63: the one int64 it cannot hold keeps the zstd chunks."""
    integers = _integers(5)
    integers[0, 0, 0] = np.iinfo(np.int64).min
    params, _ = residual.encode_section(
        integers, FLOAT32, 3, predict=0, adaptive_coding=True, adaptive_gain=-1.0
    )
    assert "coder" not in params


# seeds whose adaptive payload is a few bytes smaller than zstd's, but not by its key's bytes
@pytest.mark.parametrize("seed", [0, 4, 23, 27])
def test_the_adaptive_twin_never_makes_a_small_section_larger(seed):
    """The choice weighs the payload and the parameters together (``coder`` is a key more), so
    that no file grows for it, however small its corrections."""
    rng = np.random.default_rng(seed)
    vertices, scale = int(rng.integers(1, 40)), float(rng.choice([0.3, 1, 3, 30, 1000]))
    shape = (int(rng.integers(1, 3)), vertices, 3)
    integers = np.round(rng.laplace(scale=scale, size=shape)).astype(np.int64)
    zstd_only = residual.encode_section(integers, FLOAT32, 3, predict=0)
    chosen = residual.with_adaptive_chunks(zstd_only, integers, FLOAT32, adaptive_gain=0.0)

    def size(section: tuple[dict[str, object], bytes]) -> int:
        return len(section[1]) + len(msgpack.packb(section[0]))

    assert size(chosen) <= size(zstd_only)
