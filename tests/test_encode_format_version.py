"""EncodeOptions.format_version (tuckercodec.encoder.versions): a file held to the features of
an older format version, for decoders that read only up to it; what it cannot hold refused."""

from __future__ import annotations

import json
import re
import struct

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import grid_faces, wave_sequence
from tools.generate import vectors as make_vectors
from tuckercodec.cli import main
from tuckercodec.encoder import encode_frames, whole
from tuckercodec.encoder.segmented import shared_basis_of
from tuckercodec.encoder.versions import VERSIONS
from tuckercodec.errors import EXIT_USAGE, FormatVersionError, InternalError
from tuckercodec.format.adaptive import ADAPTIVE
from tuckercodec.format.container import pack_container, parse_container
from tuckercodec.format.residual import ADAPTIVE_CORRECTIONS, CODEBOOKS, CORRECTIONS
from tuckercodec.format.sections import CODING_TOOLS
from tuckercodec.format.segments import SEGMENTED
from tuckercodec.format.traversal import UNIFORM_RANKS
from tuckercodec.io.samples import sheet_triangles, wave_sheet
from tuckercodec.model.attributes import Attribute
from tuckercodec.model.sources import SequenceFrames

TARGET = 0.5


@pytest.fixture(scope="module")
def scrambled() -> tc.MeshSequence:
    """Vertices renumbered and faces shuffled, as an exporter writes them: every tool of the
    newest format pays on it (faces-traverse, the mesh predictors, the adaptive coder)."""
    sheet = tc.MeshSequence(wave_sequence(frames=24, grid=12), grid_faces(12))
    return make_vectors.scrambled(sheet, seed=5)


def _minor(data: bytes) -> int:
    return struct.unpack_from("<H", data, 10)[0]


def _uses_no_feature_above(data: bytes, cap: str) -> None:
    """The file's preamble and sections use nothing newer than format ``cap``."""
    cap_minor = int(cap.split(".")[1])
    container = parse_container(data)
    assert container.minor <= cap_minor
    entries = [section.params for section in container.sections]
    if cap_minor < 9:
        assert not container.flags & UNIFORM_RANKS
        assert not any(
            s.codec == "faces-traverse" and "ranks" in s.params for s in container.sections
        )
    if cap_minor < 8:
        assert not container.flags & CODEBOOKS
        assert not any(
            s.codec == "residual" and "codebooks" in s.params for s in container.sections
        )
    if cap_minor < 7:
        assert not container.flags & ADAPTIVE_CORRECTIONS
        assert not any(s.codec == "residual" and "coder" in s.params for s in container.sections)
    if cap_minor < 6:
        assert not container.flags & ADAPTIVE
        assert not any("coder" in e or "mean_push" in e for e in entries)
    if cap_minor < 3:
        assert not container.flags & CORRECTIONS
    if cap_minor < 2:
        assert not container.flags & CODING_TOOLS
        face = container.section("FACE")
        assert face is not None and face.codec == "faces-delta"
        for section in container.sections:
            assert all(b <= 1 for b in bytes(section.params.get("predict", b"")))
    if cap_minor < 1:
        assert not container.flags & SEGMENTED


# ------------------------------------------------------------------------------------------
# what each version writes


@pytest.mark.parametrize("cap", VERSIONS)
def test_a_whole_file_uses_nothing_newer_than_its_cap_and_meets_the_target(scrambled, cap):
    data = tc.encode(scrambled, target_kg=TARGET, format_version=cap)
    _uses_no_feature_above(data, cap)
    decoder = tc.Decoder(data)
    assert decoder.info.format_version == f"1.{_minor(data)}"
    assert tc.kg_error(scrambled.vertices, decoder.positions()) <= TARGET


def test_the_cap_is_what_holds_the_newer_tools_back(scrambled):
    """Each version's tools are used up to the cap: the file says the newest it uses."""
    written = {
        cap: _minor(tc.encode(scrambled, target_kg=TARGET, format_version=cap)) for cap in VERSIONS
    }
    assert written == {
        "1.0": 0, "1.1": 0, "1.2": 2, "1.3": 2, "1.4": 2, "1.5": 2, "1.6": 6, "1.7": 6,
        "1.8": 6, "1.9": 9
    }  # fmt: skip


def test_the_default_is_the_newest_version_byte_for_byte(scrambled):
    assert tc.EncodeOptions().format_version is None
    assert tc.EncodeOptions().features.version == VERSIONS[-1]
    newest = tc.encode(scrambled, target_kg=TARGET)
    assert tc.encode(scrambled, target_kg=TARGET, format_version=VERSIONS[-1]) == newest


@pytest.mark.parametrize(("cap", "minor"), [("1.1", 1), ("1.2", 2), ("1.6", 6)])
def test_segments_follow_the_cap(scrambled, cap, minor):
    result = tc.encode_with_report(
        scrambled, target_kg=TARGET, segment_frames=8, format_version=cap
    )
    _uses_no_feature_above(result.data, cap)
    assert _minor(result.data) == minor and parse_container(result.data).segmented
    assert tc.kg_error(scrambled.vertices, tc.Decoder(result.data).positions()) <= TARGET


@pytest.mark.parametrize("cap", ["1.6", "1.7"])
def test_lossless_corrections_are_adaptive_only_from_1_7(cap):
    # float32 values: their corrections gain more than 3 % from the adaptive coder
    sheet = tc.MeshSequence(
        wave_sheet(20, 8).astype(np.float32).astype(np.float64), sheet_triangles(8)
    )
    data = tc.encode(sheet, lossless=True, format_version=cap)
    _uses_no_feature_above(data, cap)
    assert _minor(data) == int(cap.split(".")[1])
    assert np.array_equal(tc.Decoder(data).positions(), sheet.vertices)


@pytest.mark.parametrize("cap", ["1.7", "1.8"])
def test_lossless_codebooks_only_from_1_8(cap):
    # positions on a coarse grid take few distinct values: codebooks pay from 1.8
    sheet = tc.MeshSequence(np.round(wave_sheet(20, 8) * 64) / 64, sheet_triangles(8))
    data = tc.encode(sheet, lossless=True, format_version=cap)
    _uses_no_feature_above(data, cap)
    assert _minor(data) == int(cap.split(".")[1])
    assert np.array_equal(tc.Decoder(data).positions(), sheet.vertices)


def test_lossless_at_1_3_is_bit_for_bit_without_adaptive_coding(scrambled):
    data = tc.encode(scrambled, lossless=True, format_version="1.3")
    _uses_no_feature_above(data, "1.3")
    assert _minor(data) == 3
    assert np.array_equal(tc.Decoder(data).positions(), scrambled.vertices)


def test_faces_kept_in_their_order_below_1_5_need_no_order_section(scrambled):
    data = tc.encode(scrambled, target_kg=TARGET, face_order="given", format_version="1.4")
    container = parse_container(data)
    assert container.section("ORDER") is None and _minor(data) <= 4
    assert np.array_equal(tc.decode(data).faces, scrambled.faces)


# ------------------------------------------------------------------------------------------
# what a version cannot hold is refused, naming it


@pytest.mark.parametrize(
    ("fields", "feature", "needs"),
    [
        ({"lossless": True, "format_version": "1.2"}, "lossless", "1.3"),
        ({"max_error": "0.1%", "format_version": "1.2"}, "max_error", "1.3"),
        ({"segment_frames": 8, "format_version": "1.0"}, "segment_frames", "1.1"),
    ],
)
def test_an_option_newer_than_the_cap_is_refused_naming_both(fields, feature, needs):
    with pytest.raises(FormatVersionError) as raised:
        tc.EncodeOptions(**fields)
    error = raised.value
    assert (error.feature, error.needs, error.format_version) == (
        feature,
        needs,
        fields["format_version"],
    )
    assert f"{feature} needs format {needs}" in str(error)
    assert isinstance(error, ValueError) and error.exit_code == EXIT_USAGE


def test_time_codes_need_1_4(scrambled):
    film = tc.MeshSequence(
        scrambled.vertices, scrambled.faces, time_codes=np.arange(1001.0, 1025.0)
    )
    with pytest.raises(
        FormatVersionError, match=re.escape("time_codes needs format 1.4")
    ) as raised:
        tc.encode(film, target_kg=TARGET, format_version="1.3")
    assert raised.value.needs == "1.4"
    assert _minor(tc.encode(film, target_kg=TARGET, format_version="1.4")) == 4


def test_attributes_need_1_5_unless_left_out(scrambled):
    rest = Attribute("rest", "vertex", scrambled.vertices[0].copy())
    textured = tc.MeshSequence(scrambled.vertices, scrambled.faces, attributes=[rest])
    with pytest.raises(
        FormatVersionError, match=r"attributes needs format 1\.5.*attachments=False"
    ):
        tc.encode(textured, target_kg=TARGET, format_version="1.4")
    alone = tc.encode(textured, target_kg=TARGET, format_version="1.4", attachments=False)
    assert _minor(alone) <= 4 and not tc.Decoder(alone).attributes
    assert _minor(tc.encode(textured, target_kg=TARGET, format_version="1.5")) == 5


def test_segments_below_1_1_are_refused_however_they_are_asked_for(scrambled):
    with pytest.raises(
        FormatVersionError, match=re.escape("larger than max_memory needs format 1.1")
    ):
        tc.encode(scrambled, target_kg=TARGET, max_memory=1000, format_version="1.0")
    with pytest.raises(FormatVersionError, match=re.escape("encode_segments needs format 1.1")):
        encode_frames(SequenceFrames(scrambled), target_kg=TARGET, format_version="1.0")


def test_a_shared_basis_newer_than_the_cap_is_refused(scrambled):
    newest = tc.encode_with_report(scrambled, target_kg=TARGET, segment_frames=8).data
    basis = shared_basis_of(newest)
    part = SequenceFrames(tc.MeshSequence(scrambled.vertices[:8], scrambled.faces))
    with pytest.raises(FormatVersionError, match=re.escape("the shared basis needs format 1.6")):
        encode_frames(part, target_kg=TARGET, format_version="1.5", shared_basis=basis)
    predicted = shared_basis_of(
        tc.encode_with_report(
            scrambled, target_kg=TARGET, segment_frames=8, format_version="1.2"
        ).data
    )
    assert 2 in predicted.params["predict"]  # U1's mean predictor, a tool of 1.2
    with pytest.raises(FormatVersionError, match=re.escape("the shared basis needs format 1.2")):
        encode_frames(part, target_kg=TARGET, format_version="1.1", shared_basis=predicted)
    older = tc.encode_with_report(
        scrambled, target_kg=TARGET, segment_frames=8, format_version="1.1"
    ).data
    held = encode_frames(
        part, target_kg=TARGET, format_version="1.1", shared_basis=shared_basis_of(older)
    ).data
    assert _minor(held) == 1


def test_a_file_above_the_cap_is_a_bug_never_returned(scrambled, monkeypatch):
    """Should a feature escape the cap, the encoder's last check stops the file."""

    def with_adaptive_flag(*args, **kwargs):
        return pack_container(*args, **kwargs, adaptive=True)

    monkeypatch.setattr(whole, "pack_container", with_adaptive_flag)
    with pytest.raises(InternalError, match=re.escape("format 1.6, newer than format_version 1.2")):
        tc.encode(scrambled, target_kg=TARGET, format_version="1.2")


@pytest.mark.parametrize("value", ["1.10", "2.0", "one", "", 1.2, 2, (1, 2)])
def test_a_version_the_encoder_does_not_write_is_refused(value):
    with pytest.raises(ValueError, match=re.escape("format_version must be one of 1.0, 1.1")):
        tc.EncodeOptions(format_version=value)


def test_the_version_is_normalised_and_travels_as_json():
    options = tc.EncodeOptions(format_version=" 1 ")
    assert options.format_version == "1.0"
    config = json.loads(json.dumps(options.to_config()))
    assert tc.EncodeOptions.from_config(config) == options


# ------------------------------------------------------------------------------------------
# the command line


@pytest.fixture
def scrambled_npz(scrambled, tmp_path):
    path = tmp_path / "scrambled.npz"
    np.savez(path, V=scrambled.vertices, F=scrambled.faces)
    return path


def test_encode_writes_the_version_asked_for(scrambled_npz, tmp_path, capsys):
    packed = tmp_path / "old.tkc"
    command = ["encode", str(scrambled_npz), "-o", str(packed), "--kg", "0.5"]
    assert main([*command, "--format-version", "1.2"]) == 0
    assert "format 1.2;" in capsys.readouterr().out
    assert tc.info(packed).format_version == "1.2"


def test_encode_refuses_what_the_version_cannot_hold_with_exit_2(scrambled_npz, tmp_path, capsys):
    packed = tmp_path / "old.tkc"
    command = ["encode", str(scrambled_npz), "-o", str(packed), "--format-version", "1.2"]
    assert main([*command, "--lossless"]) == 2
    err = capsys.readouterr().err
    assert "lossless needs format 1.3" in err and len(err.splitlines()) == 1
    assert not packed.exists()
    with pytest.raises(SystemExit) as exit_info:
        main(["encode", str(scrambled_npz), "-o", str(packed), "--format-version", "1.10"])
    assert exit_info.value.code == 2
    assert "expected one of 1.0, 1.1" in capsys.readouterr().err
