"""The codec of animated fields (§6.13) end to end on a table of sections, without a container:
each mode meets its target on what a decoder returns, frames can be decoded alone, and a
damaged parameter is refused with its rule."""

from __future__ import annotations

import copy
import functools
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import load_shared_npz
from tuckercodec.encoder.fields import (
    EncodedField,
    FieldTarget,
    encode_field,
    max_abs,
    relative_rms,
    section_lookup,
)
from tuckercodec.errors import FormatError, LimitError
from tuckercodec.format import fields as fmt
from tuckercodec.format.limits import DEFAULT_LIMITS, Limits
from tuckercodec.model.attributes import Field
from tuckercodec.model.topology import MeshPrediction

FRAME_RATE = 24.0


@functools.cache
def _data(name: str, frames: int) -> tuple[np.ndarray, np.ndarray, MeshPrediction]:
    vertices, faces = load_shared_npz(f"{name}.npz")
    vertices = vertices[:frames]
    velocity = (np.diff(vertices, axis=0, prepend=vertices[:1]) * FRAME_RATE).astype(np.float32)
    faces = faces.astype(np.int64)
    return velocity, faces, MeshPrediction(faces, vertices.shape[1])


def velocity(name: str, frames: int = 30, dtype: Any = np.float32) -> tuple[Field, MeshPrediction]:
    """The finite-difference velocity of a shared sequence's first frames, and its mesh."""
    values, _, mesh = _data(name, frames)
    return Field("velocities", values.astype(dtype), "vertex", "velocity"), mesh


def speed(name: str, frames: int = 30, dtype: Any = np.float64) -> tuple[Field, MeshPrediction]:
    """The per-vertex speed (one component)."""
    values, _, mesh = _data(name, frames)
    return Field("speed", np.linalg.norm(values, axis=2).astype(dtype), "vertex"), mesh


def face_velocity(name: str, frames: int = 30) -> Field:
    """The mean velocity of each face's corners: a field on the faces."""
    values, faces, _ = _data(name, frames)
    return Field("face velocity", values[:, faces].mean(axis=2), "face", "velocity")


def decode(
    encoded: EncodedField | list[tuple[dict[str, Any], bytes]],
    item: Field,
    mesh: MeshPrediction | None,
    *,
    limits: Limits = DEFAULT_LIMITS,
    frames_wanted: np.ndarray | None = None,
    number: int = 3,
) -> Field:
    sections = encoded.sections if isinstance(encoded, EncodedField) else encoded
    section, payload = section_lookup(sections)
    frames, count, _ = item.values.shape
    return fmt.decode_field(
        number, section, payload, count, count, frames, mesh, limits, frames_wanted
    )


# -- targets met --------------------------------------------------------------------------------


@pytest.mark.parametrize("target", [1.0, 0.1])
@pytest.mark.parametrize(
    "make", [lambda: velocity("cloth-vellum", 60), lambda: speed("cloth-vellum", 60)]
)
def test_a_relative_target_is_met_on_the_decoded_field(make: Any, target: float) -> None:
    item, mesh = make()
    encoded = encode_field(item, 3, FieldTarget(relative=target), mesh, 3)
    back = decode(encoded, item, mesh)
    assert encoded.report.mode == fmt.TUCKER
    assert back.values.dtype == item.values.dtype and back.values.shape == item.values.shape
    assert back.name == item.name and back.role == item.role and back.domain == item.domain
    measured = relative_rms(item.values, back.values)
    assert measured <= target
    assert measured == pytest.approx(encoded.report.error)
    assert encoded.sections[0][0]["error"]["definition"] == "relative-rms"
    # a Tucker field is smaller than its raw values
    assert encoded.report.bytes < item.values.nbytes / 2


def test_samba_velocity_and_a_face_field_meet_a_relative_target() -> None:
    item, mesh = velocity("samba", 20)
    encoded = encode_field(item, 0, FieldTarget(relative=1.0), mesh, 3)
    assert relative_rms(item.values, decode(encoded, item, mesh, number=0).values) <= 1.0
    faces = face_velocity("cloth-vellum", 20)
    encoded = encode_field(faces, 3, FieldTarget(relative=0.5), None, 3)
    assert encoded.report.mode == fmt.TUCKER
    assert relative_rms(faces.values, decode(encoded, faces, None).values) <= 0.5


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("name", ["cloth-vellum", "samba"])
def test_a_bound_holds_for_every_value(name: str, dtype: Any) -> None:
    for item, mesh in (velocity(name, 20, dtype), speed(name, 20, dtype)):
        bound = 1e-3 * float(item.values.max() - item.values.min())
        encoded = encode_field(item, 3, FieldTarget(max_error=bound), mesh, 3)
        assert encoded.report.mode == fmt.GRID
        back = decode(encoded, item, mesh).values
        assert back.dtype == item.values.dtype
        assert max_abs(item.values, back) <= bound
        assert encoded.report.error == max_abs(item.values, back)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_lossless_is_bit_for_bit(dtype: Any) -> None:
    for item, mesh in (velocity("cloth-vellum", 20, dtype), speed("samba", 10, dtype)):
        encoded = encode_field(item, 3, FieldTarget(lossless=True), mesh, 3)
        back = decode(encoded, item, mesh).values
        assert back.dtype == item.values.dtype
        assert back.tobytes() == item.values.tobytes()


def test_a_field_constant_over_its_elements_is_stored_exact() -> None:
    values = np.repeat(np.linspace(0, 1, 12)[:, None, None], 50, axis=1) * np.ones(3)
    item = Field("wind", values, "face")
    encoded = encode_field(item, 3, FieldTarget(relative=0.1), None, 3)
    assert encoded.report.mode == fmt.EXACT
    assert decode(encoded, item, None).values.tobytes() == item.values.tobytes()


def test_a_bound_too_fine_for_the_values_falls_back_to_exact() -> None:
    item = Field("big", np.full((4, 10, 1), 1e6) + np.arange(10)[None, :, None], "face")
    encoded = encode_field(item, 3, FieldTarget(max_error=1e-12), None, 3)
    assert encoded.report.mode == fmt.EXACT
    assert decode(encoded, item, None).values.tobytes() == item.values.tobytes()


# -- frames alone -------------------------------------------------------------------------------


@pytest.mark.parametrize("target", ["rel:0.5", "max:0.01", "lossless"])
def test_frames_wanted_give_the_rows_of_a_full_decode(target: str) -> None:
    item, mesh = velocity("cloth-vellum", 40)
    encoded = encode_field(item, 3, FieldTarget.parse(target), mesh, 3)
    full = decode(encoded, item, mesh).values
    wanted = np.array([39, 0, 17, 17, 5])
    part = decode(encoded, item, mesh, frames_wanted=wanted).values
    assert part.tobytes() == full[wanted].tobytes()


def test_a_decoder_reads_only_the_chunks_of_the_frames_asked_for() -> None:
    item, mesh = speed("cloth-vellum", 40)
    encoded = encode_field(item, 3, FieldTarget(lossless=True), mesh, 3)
    entry = encoded.sections[0][0]
    chunk_frames = 8
    chunks, body = fmt.pack_chunks(
        fmt.exact_integers(item.values), entry["predict"], chunk_frames, 3
    )
    entry = {**entry, "chunk_frames": chunk_frames, "chunks": chunks}
    damaged = bytearray(body)
    damaged[chunks[0][1] + 5] ^= 0xFF  # break chunk 1 only
    sections = [(entry, bytes(damaged))]
    wanted = np.array([0, 7, 16, 39])  # chunks 0, 2 and 4
    part = decode(sections, item, mesh, frames_wanted=wanted).values
    assert part.tobytes() == item.values[wanted].tobytes()
    with pytest.raises(FormatError):
        decode(sections, item, mesh, frames_wanted=np.array([8]))


# -- damaged files ------------------------------------------------------------------------------


@functools.cache
def _encoded(mode: str) -> tuple[EncodedField, Field, MeshPrediction]:
    item, mesh = velocity("cloth-vellum", 12)
    target = {"tucker": "rel:1", "grid": "max:0.01", "exact": "lossless"}[mode]
    encoded = encode_field(item, 3, FieldTarget.parse(target), mesh, 3)
    assert encoded.report.mode == mode
    return encoded, item, mesh


COMMON_DAMAGE = [
    ("name", ""),
    ("name", "x" * 256),
    ("name", "bad\nname"),
    ("name", 7),
    ("role", 3),
    ("domain", "corner"),
    ("components", 0),
    ("components", 5),
    ("components", True),
    ("components", 2),  # not the components the sections hold: their shapes disagree
    ("type", "f16"),
    ("mode", "wavelet"),
]
MODE_DAMAGE = {
    "tucker": [
        ("ranks", [0, 1]),
        ("ranks", [1]),
        ("ranks", [10**9, 1]),
        ("ranks", [1, 13]),
        ("u2", [1.0] * 8),
        ("u2", [float("nan")] * 9),
        ("u2", [1] * 9),
    ],
    "grid": [
        ("step", 0.0),
        ("step", float("inf")),
        ("step", 1),
        ("predict", 3),
        ("chunk_frames", 0),
        ("chunks", []),
        ("chunks", [[9, 0]]),
    ],
    "exact": [("predict", -1), ("chunk_frames", "8"), ("chunks", [[1, -1]]), ("chunks", [[1, 0]])],
}


def _damage_cases() -> list[tuple[str, str, Any]]:
    return [
        (mode, key, value)
        for mode in ("tucker", "grid", "exact")
        for key, value in COMMON_DAMAGE + MODE_DAMAGE[mode]
    ]


@pytest.mark.parametrize(("mode", "key", "value"), _damage_cases())
def test_a_damaged_parameter_is_refused(mode: str, key: str, value: Any) -> None:
    encoded, item, mesh = _encoded(mode)
    sections = copy.deepcopy(encoded.sections)
    sections[0][0][key] = value
    with pytest.raises(FormatError) as raised:
        decode(sections, item, mesh)
    expected = {"R45-field"}
    if key == "components" and value == 2:
        # tucker: u2 has c * c entries; chunked: the zstd frames hold other sizes
        expected = {"R45-field"} if mode == "tucker" else {"R29-zstd-content-size"}
    assert raised.value.rule in expected, raised.value


def test_an_unknown_role_is_generic_and_the_error_map_is_not_checked() -> None:
    encoded, item, mesh = _encoded("grid")
    sections = copy.deepcopy(encoded.sections)
    sections[0][0]["role"] = "temperature"
    sections[0][0]["error"] = "anything"
    assert decode(sections, item, mesh).role == "generic"


@pytest.mark.parametrize(
    ("change", "rule"),
    [
        (lambda s: s.pop(1), "R45-field"),  # U1 missing
        (lambda s: s[2][0].update(critical=True), "R45-field"),
        (lambda s: s[3][0].update(codec="faces-delta"), "R45-field"),
        (lambda s: s[4][0].update(shape=[12, 4]), "R28-shape"),
        (lambda s: s[2][0].update(planes=9), "R30-planes"),
        (lambda s: s.__setitem__(0, (s[0][0], b"x")), "R45-field"),  # a payload in tucker
        (lambda s: s[0][0].update(codec="qmat"), "R45-field"),
        (lambda s: s.__setitem__(2, (s[2][0], s[2][1][:-3])), "R29-zstd-content-size"),
    ],
)
def test_damaged_tucker_sections_are_refused(change: Any, rule: str) -> None:
    encoded, item, mesh = _encoded("tucker")
    sections = copy.deepcopy(encoded.sections)
    change(sections)
    with pytest.raises(FormatError) as raised:
        decode(sections, item, mesh)
    assert raised.value.rule == rule, raised.value


def test_damaged_integers_are_refused() -> None:
    encoded, item, mesh = _encoded("exact")
    entry, _ = encoded.sections[0]
    # integers beyond the finite float32 values
    huge = np.full(item.values.shape, 2**40, dtype=np.int64)
    chunks, payload = fmt.pack_chunks(huge, 0, entry["chunk_frames"], 3)
    with pytest.raises(FormatError, match="ordered integer") as raised:
        decode([({**entry, "chunks": chunks}, payload)], item, mesh)
    assert raised.value.rule == "R45-field"


@pytest.mark.parametrize("limit", ["max_positions", "max_chunk_values", "max_factor_values"])
def test_sizes_beyond_the_limits_are_refused_before_decoding(limit: str) -> None:
    mode = "tucker" if limit == "max_factor_values" else "exact"
    encoded, item, mesh = _encoded(mode)
    with pytest.raises(LimitError) as raised:
        decode(encoded, item, mesh, limits=Limits(**{limit: 10}))
    assert raised.value.rule == "R21-header-limit"


def test_field_ids_name_the_sub_sections() -> None:
    encoded, _, _ = _encoded("tucker")
    ids = fmt.field_ids(encoded.sections[0][0], 3)
    assert ids == [entry["id"] for entry, _ in encoded.sections[1:]]
    assert ids == ["FLD.3.U1", "FLD.3.U3", "FLD.3.CORE", "FLD.3.MEAN"]
    assert fmt.field_ids({"mode": "grid"}, 3) == []
    assert all(fmt.is_field_section(i) for i in ["FLD.3", *ids])
    assert not fmt.is_field_section("FLD.x") and not fmt.is_field_section("FLD.3.RESD")


# -- targets ------------------------------------------------------------------------------------


def test_targets_parse_and_refuse_with_clear_words() -> None:
    assert FieldTarget.parse("rel:0.1") == FieldTarget(relative=0.1)
    assert FieldTarget.parse("max:0.001") == FieldTarget(max_error=0.001)
    assert FieldTarget.parse("lossless") == FieldTarget(lossless=True)
    for text in ("rel:", "rel:-1", "max:nan", "lossy", "lossless:1", "max:1e999"):
        with pytest.raises(ValueError, match="rel:PERCENT"):
            FieldTarget.parse(text)
    with pytest.raises(ValueError, match="one of"):
        FieldTarget(relative=1.0, lossless=True)
