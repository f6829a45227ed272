"""Format 1.9: faces-traverse's new vertices in a uniform stream (spec §6.8, flag bit 6, R46).

Where the vertex order has nothing to do with the walk (a remeshed simulation's, an exporter's),
each new vertex is its place among the vertices not seen yet, coded in truncated binary: about
log2(K!) bits in all, where the adaptive ranks of 1.6 take about 1.4 bits a vertex more. The
encoder keeps it only where the section is smaller; the faces decoded are the same. The
conformance vectors (``v1.9-*`` and R46's ``-ranks`` vectors) hold the decoders to the layout.
"""

from __future__ import annotations

import math
from contextlib import nullcontext

import msgpack
import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import grid_faces, wave_sequence
from tools.generate import vectors as make_vectors
from tuckercodec.errors import FormatError
from tuckercodec.format import adaptive, faces, traversal, uniform
from tuckercodec.format.container import pack_container, parse_container
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.system import native

RULE = "R46-adaptive-stream"


def _values(total: int, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([rng.integers(total - i) for i in range(count)], dtype=np.int64)


def _scrambled(grid: int = 12, seed: int = 5) -> tc.MeshSequence:
    sheet = tc.MeshSequence(wave_sequence(frames=12, grid=grid), grid_faces(grid))
    return make_vectors.scrambled(sheet, seed=seed)


def _face(data: bytes) -> tuple[dict[str, object], bytes]:
    container = parse_container(data, DEFAULT_LIMITS)
    entry = container.section("FACE")
    assert entry is not None
    return dict(entry.params), bytes(container.payload(data, entry))


# ------------------------------------------------------------------------------------------
# the uniform stream


@pytest.mark.parametrize(("total", "count"), [(1, 1), (2, 2), (3, 3), (5, 2), (8, 8), (1000, 1000)])
def test_values_come_back_and_the_reference_writes_the_cores_bytes(total, count):
    values = _values(total, count, seed=total)
    payload = uniform.encode_uniform(values, total)
    with native.pure_python():
        assert uniform.encode_uniform(values, total) == payload
        assert uniform.decode_uniform(payload, count, total, "here").tolist() == values.tolist()
    assert uniform.decode_uniform(payload, count, total, "here").tolist() == values.tolist()


def test_a_random_order_costs_log2_of_its_choices_and_a_few_hundredths_more():
    total = 5000
    values = _values(total, total, seed=3)
    ideal = sum(math.log2(total - i) for i in range(total)) / 8
    size = len(uniform.encode_uniform(values, total))
    assert ideal <= size <= ideal * 1.01 + 6


@pytest.mark.parametrize("pure", [False, True])
def test_a_value_outside_its_range_is_refused_by_the_encoder(pure):
    with native.pure_python() if pure else nullcontext():
        with pytest.raises(ValueError, match=r"value 1 is 4, outside 0\.\.3"):
            uniform.encode_uniform(np.array([0, 4]), 5)
        with pytest.raises(ValueError, match="3 values over 2 do not make a uniform stream"):
            uniform.encode_uniform(np.array([0, 0, 0]), 2)


@pytest.mark.parametrize("pure", [False, True])
def test_damaged_streams_are_r46_in_both_decoders(pure):
    values = _values(300, 200, seed=9)
    payload = uniform.encode_uniform(values, 300)
    damaged = {
        "short": payload[:-1],
        "long": payload + b"\x00",
        "first byte": b"\x01" + payload[1:],
        "tiny": payload[:4],
    }
    with native.pure_python() if pure else nullcontext():
        for name, data in damaged.items():
            with pytest.raises(FormatError) as caught:
                uniform.decode_uniform(data, 200, 300, "section FACE.streams.vertices")
            assert caught.value.rule == RULE, name
        with pytest.raises(FormatError, match="cannot come from") as caught:
            uniform.decode_uniform(b"\x00" * 5, 5 * adaptive.MAX_EXPANSION + 1, 1 << 31, "here")
        assert caught.value.rule == RULE


# ------------------------------------------------------------------------------------------
# the FACE section


def test_a_scrambled_order_is_coded_uniformly_and_decodes_to_the_same_faces():
    sequence = _scrambled()
    data = tc.encode(sequence, target_kg=0.5)
    container = parse_container(data, DEFAULT_LIMITS)
    params, _ = _face(data)
    assert params["ranks"] == 1 and params["coder"] == 1
    assert container.flags & traversal.UNIFORM_RANKS and container.minor == 9
    decoder = tc.Decoder(data)
    given = {tuple(sorted(row[row >= 0])) for row in sequence.faces}
    assert {tuple(sorted(row[row >= 0])) for row in decoder.faces} == given
    with native.pure_python():
        assert np.array_equal(tc.Decoder(data).faces, decoder.faces)
        assert tc.encode(sequence, target_kg=0.5) == data


def test_the_uniform_stream_is_kept_only_where_it_is_smaller():
    """A vertex order that follows the surface keeps the adaptive ranks; a scrambled one is
    smaller with the uniform stream than without it."""
    ordered = tc.MeshSequence(wave_sequence(frames=12, grid=12), grid_faces(12))
    params, _ = _face(tc.encode(ordered, target_kg=0.5))
    assert "ranks" not in params
    sequence = _scrambled()
    without, chosen = (_section(sequence, uniform_ranks=allowed) for allowed in (False, True))
    assert chosen.params.get("ranks") == 1 and "ranks" not in without.params
    assert _size(chosen) < _size(without)


def _section(sequence: tc.MeshSequence, *, uniform_ranks: bool) -> faces.FaceSection:
    """The FACE section the encoder writes for ``sequence`` in a file of 1.6 (or of 1.9)."""
    return faces.encode_face_sections(
        sequence.faces,
        sequence.vertex_count,
        19,
        keep_order=False,
        adaptive_coding=True,
        uniform_ranks=uniform_ranks,
    )[0]


def _size(section: faces.FaceSection) -> int:
    return len(section.payload) + len(msgpack.packb(section.params))


def test_format_1_8_holds_the_encoder_to_adaptive_ranks():
    data = tc.encode(_scrambled(), target_kg=0.5, format_version="1.8")
    params, _ = _face(data)
    assert "ranks" not in params
    assert not parse_container(data, DEFAULT_LIMITS).flags & traversal.UNIFORM_RANKS


def _walked(sequence: tc.MeshSequence) -> tuple[dict[str, object], bytes, int]:
    section = _section(sequence, uniform_ranks=True)
    assert section.params.get("ranks") == 1
    return dict(section.params), section.payload, sequence.vertex_count


def _decode(params: dict[str, object], payload: bytes, k: int, *, flag: bool = True) -> np.ndarray:
    return traversal.decode_traversal(
        payload, params, k, "section FACE", adaptive_coding=True, uniform_ranks=flag
    )


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"ranks": 2}, "ranks must be 0 or 1"),
        ({"ranks": 1.0}, "ranks must be 0 or 1"),
        ({"ranks": True}, "ranks must be 0 or 1"),
        ({"coder": 0}, "ranks 1 needs coder 1"),
    ],
)
def test_ranks_are_checked_before_the_streams(change, message):
    params, payload, k = _walked(_scrambled())
    with pytest.raises(FormatError, match=message) as caught:
        _decode({**params, **change, "streams": "not read yet"}, payload, k)
    assert caught.value.rule == RULE and caught.value.field == "section FACE.ranks"


def test_more_vertices_than_32_bits_take_is_r46():
    params, payload, _ = _walked(_scrambled())
    with pytest.raises(FormatError, match="at most 2147483648 vertices") as caught:
        _decode(params, payload, (1 << 31) + 1)
    assert caught.value.rule == RULE


def test_without_flag_bit_6_ranks_is_an_unknown_parameter():
    params, payload, k = _walked(_scrambled())
    without = {key: value for key, value in params.items() if key != "ranks"}

    # the same streams read as adaptive ranks: whatever they say, the parameter changes nothing
    def outcome(given: dict[str, object]) -> str:
        try:
            return _decode(given, payload, k, flag=False).tobytes().hex()
        except FormatError as error:
            return str(error.rule)

    assert outcome({**params, "ranks": 7}) == outcome(without)


def test_a_file_with_ranks_says_flag_bit_6_and_minor_9():
    """pack_container sets the flag and the minor for a faces-traverse FACE with ``ranks``,
    whatever flags it is given, so that a 1.8 decoder refuses the file cleanly (R06)."""
    data = tc.encode(_scrambled(), target_kg=0.5)
    container = parse_container(data, DEFAULT_LIMITS)
    sections = [
        (
            {**section.params, "id": section.id, "critical": section.critical,
             "codec": section.codec},
            bytes(container.payload(data, section)),
        )
        for section in container.sections
    ]  # fmt: skip
    header = {key: value for key, value in container.header.items() if key != "sections"}
    repacked = parse_container(pack_container(header, sections), DEFAULT_LIMITS)
    assert repacked.flags & traversal.UNIFORM_RANKS and repacked.minor == 9
