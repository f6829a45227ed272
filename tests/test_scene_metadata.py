"""Time and scene in the file (spec/FORMAT.md §4, format 1.4): each frame's time code, the
length unit and the up axis, kept from the source through encode and decode, checked on
reading; tuckercodec/format/header.py, the encoders' headers and the readers and writers."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import Parts
from tuckercodec import FormatError, InputError, MeshSequence, decode, encode, info
from tuckercodec.cli import main
from tuckercodec.encoder import EncodeOptions, Encoder
from tuckercodec.io import load_sequence, save_sequence
from tuckercodec.io.samples import sample_path


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    return load_sequence(sample_path(), progress=False)


def _codes(frames: int) -> np.ndarray:
    """A film cache's time codes: from 1001, one sample missing (uneven)."""
    return np.delete(np.arange(1001.0, 1001.0 + frames + 1), 7)


def _film(cloth: MeshSequence, frames: int = 20) -> MeshSequence:
    """A film cache's frames: :func:`_codes`, metres, Z up."""
    codes = _codes(frames)
    return MeshSequence(
        cloth.vertices[:frames],
        cloth.faces,
        frame_rate=24.0,
        time_codes=codes,
        meters_per_unit=1.0,
        up_axis="z",
    )


def test_a_file_keeps_the_time_codes_unit_and_up_axis(cloth):
    film = _film(cloth)
    data = encode(film, target_kg=0.5)
    header = info(data)
    # the keys are 1.4's (§10), adaptive coding 1.6's, the cloth's uniform ranks 1.9's
    assert header.format_version == "1.9"
    assert header.time_codes == tuple(_codes(20).tolist())
    assert (header.meters_per_unit, header.up_axis) == (1.0, "Z")
    assert header.to_dict()["time_codes"][:2] == [1001.0, 1002.0]
    back = decode(data)
    np.testing.assert_array_equal(back.time_codes, film.time_codes)
    assert (back.frame_rate, back.meters_per_unit, back.up_axis) == (24.0, 1.0, "Z")
    part = decode(data, frames=range(5, 9))  # a part keeps its frames' codes
    np.testing.assert_array_equal(part.time_codes, _codes(20)[5:9])
    assert decode(data, frames=[3, 1]).time_codes is None  # out of time order: none


def test_a_sequence_without_them_is_written_as_before(cloth):
    plain = MeshSequence(cloth.vertices[:20], cloth.faces, frame_rate=24.0)
    counted = MeshSequence(  # 0, 1, 2... is what no time codes mean: not written
        cloth.vertices[:20], cloth.faces, frame_rate=24.0, time_codes=np.arange(20.0)
    )
    data = encode(plain, target_kg=0.5)
    assert encode(counted, target_kg=0.5) == data
    assert not {"time_codes", "meters_per_unit", "up_axis"} & set(Parts(data).header)
    assert info(data).format_version != "1.4"
    back = decode(data)
    assert (back.time_codes, back.meters_per_unit, back.up_axis) == (None, None, None)


def test_a_segmented_file_keeps_them_too(cloth):
    film = _film(cloth, frames=30)
    data = Encoder(EncodeOptions(target_kg=0.5, segment_frames=10)).encode(film)
    header = info(data)
    assert len(header.segments) == 3 and header.format_version == "1.9"
    back = decode(data, frames=range(12, 25))
    np.testing.assert_array_equal(back.time_codes, _codes(30)[12:25])
    assert (back.meters_per_unit, back.up_axis) == (1.0, "Z")


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("time_codes", np.arange(19.0).tobytes(), "must be 160 bytes"),
        ("time_codes", [float(n) for n in range(20)], "must be 160 bytes"),
        ("time_codes", np.r_[0.0, np.nan, np.arange(2.0, 20.0)].tobytes(), "finite"),
        ("time_codes", np.r_[0.0, 2.0, 2.0, np.arange(3.0, 20.0)].tobytes(), "increase"),
        ("meters_per_unit", 1, "positive finite float"),  # an int: msgpack floats only (§4)
        ("meters_per_unit", -1.0, "positive finite float"),
        ("up_axis", "X", '"Y" or "Z"'),
    ],
)
def test_bad_values_are_refused_naming_the_key(cloth, key, value, message):
    parts = Parts(encode(MeshSequence(cloth.vertices[:20], cloth.faces), target_kg=0.5))
    parts.header[key] = value
    with pytest.raises(FormatError, match=message) as raised:
        tuckercodec.Decoder(parts.pack())
    assert raised.value.rule == "R20-header-field"
    assert raised.value.field == f"header.{key}"


def test_a_sequence_checks_them():
    vertices = np.zeros((2, 3, 3))
    with pytest.raises(InputError, match="Y or Z"):
        MeshSequence(vertices, np.zeros((0, 3), dtype=np.int64), up_axis="X")
    with pytest.raises(InputError, match="positive"):
        MeshSequence(vertices, np.zeros((0, 3), dtype=np.int64), meters_per_unit=0.0)
    seq = MeshSequence(vertices, np.zeros((0, 3), dtype=np.int64), up_axis="y")
    assert seq.up_axis == "Y"


def test_an_npz_keeps_them(cloth, tmp_path):
    film = _film(cloth)
    save_sequence(film, tmp_path / "film.npz", progress=False)
    back = load_sequence(tmp_path / "film.npz", progress=False)
    np.testing.assert_array_equal(back.time_codes, film.time_codes)
    assert (back.meters_per_unit, back.up_axis) == (1.0, "Z")


def test_the_cli_prints_them_and_convert_names_what_a_format_drops(cloth, tmp_path, capsys):
    save_sequence(_film(cloth), tmp_path / "film.npz", progress=False)
    assert main(["encode", str(tmp_path / "film.npz"), "-o", str(tmp_path / "f.tkc")]) == 0
    assert "not kept" not in capsys.readouterr().out
    assert main(["info", str(tmp_path / "f.tkc")]) == 0
    out = capsys.readouterr().out
    assert "time codes 1001 to 1021" in out and "1 metres per unit" in out and "Z up" in out
    assert main(["convert", str(tmp_path / "film.npz"), str(tmp_path / "film.mdd")]) == 0
    assert "unit (metres per unit), up axis" in capsys.readouterr().out


_USD = importlib.util.find_spec("pxr") is not None
_ALEMBIC = importlib.util.find_spec("alembic3d") is not None


@pytest.mark.skipif(not _USD, reason="usd-core (the 'usd' extra) is not installed")
def test_a_metre_scale_z_up_usd_stage_goes_through_encode_and_decode(cloth, tmp_path):
    # the stage is authored with pxr itself, as a DCC would, not by our writer
    from pxr import Usd, UsdGeom, Vt

    stage = Usd.Stage.CreateNew(str(tmp_path / "stage.usda"))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, UsdGeom.LinearUnits.meters)
    stage.SetTimeCodesPerSecond(24.0)
    mesh = UsdGeom.Mesh.Define(stage, "/World/cloth")
    faces = cloth.faces
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(faces), 3, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(faces.reshape(-1).astype(np.int32)))
    points = mesh.CreatePointsAttr()
    codes = [1001.0, 1002.0, 1003.0, 1005.0, 1006.0, 1009.0, 1010.0, 1011.0]
    for frame, code in enumerate(codes):
        positions = cloth.vertices[frame].astype(np.float32)
        points.Set(Vt.Vec3fArray.FromNumpy(positions), Usd.TimeCode(code))
    stage.GetRootLayer().Save()

    tkc, out = tmp_path / "stage.tkc", tmp_path / "back.usda"
    assert main(["encode", str(tmp_path / "stage.usda"), "-o", str(tkc), "--kg", "0.5"]) == 0
    assert main(["decode", str(tkc), "-o", str(out)]) == 0
    back = Usd.Stage.Open(str(out))
    assert UsdGeom.GetStageUpAxis(back) == UsdGeom.Tokens.z
    assert UsdGeom.GetStageMetersPerUnit(back) == 1.0
    back_mesh = UsdGeom.Mesh(back.GetPrimAtPath(f"/Root/{out.stem}"))
    assert back_mesh.GetPointsAttr().GetTimeSamples() == codes
    assert back.GetTimeCodesPerSecond() == 24.0


@pytest.mark.skipif(not _ALEMBIC, reason="alembic3d (the 'alembic' extra) is not installed")
def test_an_unevenly_sampled_alembic_cache_keeps_its_times(cloth, tmp_path):
    seconds = np.array([0.0, 0.04, 0.1, 0.13, 0.2, 0.21, 0.3, 0.5])  # acyclic sampling
    uneven = MeshSequence(
        cloth.vertices[:8], cloth.faces, frame_rate=25.0, time_codes=seconds * 25.0
    )
    save_sequence(uneven, tmp_path / "cache.abc", progress=False)
    source = load_sequence(tmp_path / "cache.abc", progress=False)
    tkc, out = tmp_path / "cache.tkc", tmp_path / "back.abc"
    assert main(["encode", str(tmp_path / "cache.abc"), "-o", str(tkc), "--kg", "0.5"]) == 0
    assert main(["decode", str(tkc), "-o", str(out)]) == 0
    back = load_sequence(out, progress=False)
    np.testing.assert_array_equal(back.time_codes, source.time_codes)
    np.testing.assert_allclose(back.seconds(), seconds, rtol=0, atol=1e-12)
    assert back.frame_rate == 25.0


def test_old_files_decode_with_no_scene(tmp_path):
    # a committed vector of 1.2 (written before 1.4) decodes as before: no codes, unit, axis
    vector = Path(__file__).parent.parent / "spec" / "vectors" / "v1.2-traverse-triangles.tkc"
    back = decode(vector.read_bytes())
    assert (back.time_codes, back.meters_per_unit, back.up_axis) == (None, None, None)


def test_the_decomposition_as_gltf_keys_frames_at_the_files_times(cloth, tmp_path):
    pytest.importorskip("meshoptimizer", reason="meshoptimizer (the 'gltf' extra) is not installed")
    (tmp_path / "film.tkc").write_bytes(encode(_film(cloth), target_kg=0.5))
    assert main(["decode", str(tmp_path / "film.tkc"), "-o", str(tmp_path / "film.glb")]) == 0
    back = load_sequence(tmp_path / "film.glb", progress=False)
    np.testing.assert_allclose(back.seconds(), _codes(20) / 24.0, rtol=1e-6)
