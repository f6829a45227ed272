"""The decomposition as a glTF morph animation (decode -o OUT.glb): k targets, weights in 0..1,
centroids as the translation track, keyframes at the frames' times; each variant within its
quantization budget; the viewer KG it reports equal to one computed independently here; the
API, decode_file and the CLI taking the same path."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import Decoder, MeshSequence, decode_file, encode, load_sequence
from tuckercodec.cli.main import main
from tuckercodec.gltf_export import COMPRESSIONS, write_decomposition_gltf
from tuckercodec.gltf_export.quantization import BUDGET_SHARE
from tuckercodec.io.samples import sample_path
from tuckercodec.measures.distortion import KG_DEFINITION, kg_error


@pytest.fixture(scope="module")
def cloth() -> MeshSequence:
    return load_sequence(sample_path())


@pytest.fixture(scope="module")
def tkc(cloth: MeshSequence, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("tkc") / "cloth.tkc"
    path.write_bytes(encode(cloth, target_kg=0.1))
    return path


def _json(path: Path) -> dict[str, Any]:
    data = path.read_bytes()
    size = struct.unpack_from("<I", data, 12)[0]
    result: dict[str, Any] = json.loads(data[20 : 20 + size])
    return result


def _floats(path: Path, accessor: int) -> np.ndarray:
    """A float32 accessor of an uncompressed .glb, read here without the package's reader."""
    data = path.read_bytes()
    gltf = _json(path)
    size = struct.unpack_from("<I", data, 12)[0]
    binary = data[20 + size + 8 :]
    entry = gltf["accessors"][accessor]
    view = gltf["bufferViews"][entry["bufferView"]]
    assert entry["componentType"] == 5126
    width = {"SCALAR": 1, "VEC3": 3}[entry["type"]]
    return np.frombuffer(
        binary, dtype="<f4", count=entry["count"] * width, offset=view["byteOffset"]
    ).reshape(entry["count"], width)


def _independent_viewer_positions(path: Path) -> np.ndarray:
    """The morph formula evaluated from the float32 file's arrays, by this test alone:
    translation track + base + weights . targets, at each keyframe."""
    gltf = _json(path)
    primitive = gltf["meshes"][0]["primitives"][0]
    base = _floats(path, primitive["attributes"]["POSITION"])
    targets = np.stack([_floats(path, t["POSITION"]) for t in primitive["targets"]])
    samplers = gltf["animations"][0]["samplers"]
    weights = _floats(path, samplers[0]["output"]).reshape(-1, len(targets))
    moves = _floats(path, samplers[1]["output"])
    local = base + np.einsum("fb,bvx->fvx", weights.astype(np.float64), targets)
    return np.asarray(local + moves[:, None, :])


@pytest.mark.parametrize("compress", COMPRESSIONS)
def test_each_variant_stays_within_its_budget_and_reports_what_a_viewer_shows(
    tkc: Path, cloth: MeshSequence, tmp_path: Path, compress: Any
) -> None:
    decoder = Decoder(str(tkc))
    report = write_decomposition_gltf(
        decoder, tmp_path / "a.glb", compress=compress, reference=cloth
    )
    assert report.size == (tmp_path / "a.glb").stat().st_size
    assert report.targets == decoder.info.ranks[1] and report.frames == 60
    recorded = decoder.info.kg
    assert recorded is not None
    assert report.viewer_kg <= (BUDGET_SHARE * recorded if compress != "none" else 1e-4)
    assert report.viewer_kg_reference is not None and report.viewer_kg_reference <= 0.105
    assert report.tkc_kg_reference == pytest.approx(kg_error(cloth, decoder.positions()))
    assert KG_DEFINITION in report.summary()


def test_the_float32_variant_reports_the_kg_of_the_formula_evaluated_independently(
    tkc: Path, cloth: MeshSequence, tmp_path: Path
) -> None:
    decoder = Decoder(str(tkc))
    report = write_decomposition_gltf(decoder, tmp_path / "a.glb", compress="none")
    shown = _independent_viewer_positions(tmp_path / "a.glb")
    assert report.viewer_kg == pytest.approx(kg_error(decoder.positions(), shown), rel=1e-6)
    assert np.abs(shown - decoder.positions()).max() < 1e-5  # float32 of the decode


def test_weights_lie_in_0_to_1_and_keyframes_at_the_frames_times(tkc: Path, tmp_path: Path) -> None:
    decoder = Decoder(str(tkc))
    write_decomposition_gltf(decoder, tmp_path / "a.glb", compress="none", frames=slice(30, 50))
    samplers = _json(tmp_path / "a.glb")["animations"][0]["samplers"]
    weights = _floats(tmp_path / "a.glb", samplers[0]["output"])
    assert weights.min() == 0.0 and weights.max() == 1.0
    times = _floats(tmp_path / "a.glb", samplers[0]["input"])[:, 0]
    assert np.array_equal(times, (np.arange(30, 50) / 24).astype(np.float32))  # no rate: 24


def test_the_files_frame_rate_sets_the_keyframe_times(cloth: MeshSequence, tmp_path: Path) -> None:
    seq = MeshSequence(cloth.vertices[:6], cloth.faces, frame_rate=30.0)
    (tmp_path / "a.tkc").write_bytes(encode(seq, ranks=(6, 3)))
    report = write_decomposition_gltf(Decoder(str(tmp_path / "a.tkc")), tmp_path / "a.glb")
    samplers = _json(tmp_path / "a.glb")["animations"][0]["samplers"]
    assert report.frame_rate == 30.0
    assert samplers[0]["input"] == samplers[1]["input"]
    back = load_sequence(tmp_path / "a.glb")
    assert back.frame_rate == 30.0 and back.time_codes is None


def test_an_existing_file_and_an_unknown_variant_are_refused_before_any_work(
    tkc: Path, tmp_path: Path
) -> None:
    (tmp_path / "a.glb").write_bytes(b"keep")
    with pytest.raises(FileExistsError):
        write_decomposition_gltf(Decoder(str(tkc)), tmp_path / "a.glb")
    assert (tmp_path / "a.glb").read_bytes() == b"keep"
    with pytest.raises(ValueError, match="compress must be one of none, quantize, meshopt"):
        write_decomposition_gltf(Decoder(str(tkc)), tmp_path / "b.glb", compress="zip")  # type: ignore[arg-type]


def test_decode_file_writes_the_decomposition_not_one_target_per_frame(
    tkc: Path, tmp_path: Path
) -> None:
    decoded = decode_file(tkc, tmp_path / "out", output_format="gltf", glb_compress="none")
    gltf = _json(tmp_path / "out.glb")
    assert len(gltf["meshes"][0]["primitives"][0]["targets"]) == Decoder(str(tkc)).info.ranks[1]
    assert decoded.frame_count == 60
    with pytest.raises(ValueError, match="glb_compress applies only"):
        decode_file(tkc, tmp_path / "frames", glb_compress="meshopt")


def test_the_cli_prints_the_viewer_kg_beside_the_files(
    tkc: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "a.glb"
    code = main(["decode", str(tkc), "-o", str(out), "--reference", "sample"])
    printed = capsys.readouterr().out
    assert code == 0 and out.exists()
    assert "quantize" in printed and "glTF viewer KG vs the .tkc decode: " in printed
    assert "vs the original: " in printed and KG_DEFINITION in printed
    assert main(["decode", str(tkc), "-o", str(tmp_path / "f"), "--glb-compress", "none"]) == 2


def test_the_quantize_variant_stores_weights_in_the_narrowest_type_within_the_budget(
    tkc: Path, cloth: MeshSequence, tmp_path: Path
) -> None:
    (tmp_path / "fine.tkc").write_bytes(encode(cloth, ranks=(40, 17)))  # KG 0.036
    for source, bits, code in ((tkc, 8, 5121), (tmp_path / "fine.tkc", 16, 5123)):
        decoder = Decoder(str(source))
        out = tmp_path / f"{bits}.glb"
        report = write_decomposition_gltf(decoder, out, compress="quantize")
        gltf = _json(out)
        output = gltf["accessors"][gltf["animations"][0]["samplers"][0]["output"]]
        assert report.weight_bits == bits
        assert (output["componentType"], output.get("normalized")) == (code, True)
        assert report.viewer_kg <= BUDGET_SHARE * decoder.info.kg  # type: ignore[operator]


def test_the_meshopt_variant_spends_the_budget_with_filtered_floats_and_positive_integers(
    tkc: Path, tmp_path: Path
) -> None:
    pytest.importorskip("meshoptimizer", reason="the meshopt variant needs meshoptimizer")
    decoder = Decoder(str(tkc))
    report = write_decomposition_gltf(decoder, tmp_path / "m.glb", compress="meshopt")
    budget = BUDGET_SHARE * decoder.info.kg  # type: ignore[operator]
    assert 0.8 * budget <= report.viewer_kg <= budget  # the coarsest step that fits
    gltf = _json(tmp_path / "m.glb")
    primitive = gltf["meshes"][0]["primitives"][0]
    samplers = gltf["animations"][0]["samplers"]

    def codec(accessor: int) -> dict[str, Any]:
        view = gltf["bufferViews"][gltf["accessors"][accessor]["bufferView"]]
        result: dict[str, Any] = view["extensions"]["EXT_meshopt_compression"]
        return result

    for accessor in (primitive["attributes"]["POSITION"], samplers[0]["output"]):
        assert codec(accessor)["filter"] == "EXPONENTIAL"
    assert codec(samplers[1]["output"])["filter"] == "EXPONENTIAL"
    # the weights' codec rows are keyframes: k float32 weights
    assert codec(samplers[0]["output"])["byteStride"] == 4 * report.targets
    assert codec(primitive["indices"])["mode"] == "TRIANGLES"
    for target in primitive["targets"]:
        accessor = gltf["accessors"][target["POSITION"]]
        assert accessor["componentType"] == 5122 and min(accessor["min"]) >= 0


def test_the_meshopt_variant_reorders_triangles_never_vertices(tkc: Path, tmp_path: Path) -> None:
    pytest.importorskip("meshoptimizer", reason="the meshopt variant needs meshoptimizer")
    decoder = Decoder(str(tkc))
    write_decomposition_gltf(decoder, tmp_path / "m.glb", compress="meshopt")
    back = load_sequence(tmp_path / "m.glb")

    def canonical(triangles: np.ndarray) -> np.ndarray:
        """Each triangle rotated to start at its smallest index (winding kept), sorted."""
        turn = np.argmin(triangles, axis=1)
        rows = np.arange(len(triangles))[:, None]
        rotated = triangles[rows, (turn[:, None] + np.arange(3)) % 3]
        return rotated[np.lexsort(rotated.T[::-1])]

    assert not np.array_equal(back.faces, decoder.faces)  # the order changed...
    assert np.array_equal(canonical(back.faces), canonical(np.asarray(decoder.faces)))
    # ...and each vertex is still the decode's vertex
    assert np.abs(back.vertices - decoder.positions()).max() < 0.05 * np.ptp(back.vertices)


def test_exponential_words_decode_to_the_values_and_refuse_what_is_not_a_multiple() -> None:
    meshopt = pytest.importorskip("meshoptimizer", reason="the EXPONENTIAL filter's decoder")
    from tuckercodec.io.gltf.meshopt import exponential_words

    values = np.array([[0.75, -3.0, 1e-3 * 2**-10], [0.0, 5.0, -(2**-20)]])
    exponents = np.array([-2, 0, -40])
    values[:, 2] = np.round(values[:, 2] / 2.0**-40) * 2.0**-40
    words = exponential_words(values.astype(np.float32).tobytes(), exponents)
    decoded = np.asarray(meshopt.decode_filter_exp(np.frombuffer(words, np.uint8), 2, 12))
    assert np.array_equal(decoded.view(np.float32).reshape(2, 3), values.astype(np.float32))
    with pytest.raises(ValueError, match="not 24-bit multiples"):
        exponential_words(np.array([0.3, 0, 0], np.float32).tobytes(), exponents)


@pytest.mark.parametrize("compress", ["quantize", "meshopt"])
def test_the_quantized_targets_share_one_buffer_view_of_8_byte_rows(
    tkc: Path, tmp_path: Path, compress: Any
) -> None:
    write_decomposition_gltf(Decoder(str(tkc)), tmp_path / "a.glb", compress=compress)
    gltf = _json(tmp_path / "a.glb")
    targets = gltf["meshes"][0]["primitives"][0]["targets"]
    accessors = [gltf["accessors"][t["POSITION"]] for t in targets]
    assert len({a["bufferView"] for a in accessors}) == 1
    assert gltf["bufferViews"][accessors[0]["bufferView"]]["byteStride"] == 8
    count = accessors[0]["count"]
    assert [a.get("byteOffset", 0) for a in accessors] == [
        8 * count * b for b in range(len(targets))
    ]


def test_a_frame_rate_whose_times_float32_cannot_hold_is_a_clean_refusal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A valid frame rate of 5e-324 puts frame 1 at 2e323 s, beyond float32: the export once
    failed in its JSON with exit 2 (the usage code); it is now exit 4 naming the output and
    the frame, with nothing written."""
    seq = MeshSequence(wave_sequence(4, 4), grid_faces(4), frame_rate=5e-324)
    packed = tmp_path / "tiny_rate.tkc"
    packed.write_bytes(encode(seq, ranks=(2, 2)))
    out = tmp_path / "tiny_rate.glb"
    assert main(["decode", str(packed), "-o", str(out)]) == 4
    err = capsys.readouterr().err.strip()
    assert err == (
        f"tuckercodec: bad input: {out}, frame 1: its time is beyond the range of float32, in "
        "which the file stores times"
    )
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["tiny_rate.tkc"]
