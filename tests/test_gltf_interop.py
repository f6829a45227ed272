"""Every glTF the project writes, judged by tools nobody here wrote (tests/js, js_interop): the
Khronos glTF-Validator finds no error and no warning, and three.js's GLTFLoader plays the
animation to the positions the package's reader evaluates and to the .tkc's decode within the
variant's quantization budget.

The validator does not decode EXT_meshopt_compression (tests/js/README.md), so the meshopt
variant is also validated as its uncompressed twin: the same file with every compressed view
replaced by the bytes the package's reader decodes from it (filters applied), which is what
three.js plays."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.js_interop import HINT, INFO, issues, three_positions, validate_gltf_files
from tuckercodec import Decoder, MeshSequence, encode, load_sequence, save_sequence
from tuckercodec.gltf_export import COMPRESSIONS, write_decomposition_gltf
from tuckercodec.gltf_export.quantization import BUDGET_SHARE
from tuckercodec.io.gltf.accessors import view_bytes
from tuckercodec.io.gltf.container import pack_glb, read_document
from tuckercodec.io.gltf.meshopt import EXTENSION
from tuckercodec.io.gltf.reader import sample_gltf
from tuckercodec.io.samples import sample_path
from tuckercodec.measures.distortion import kg_error

# the validator cannot decode EXT_meshopt_compression: on such a file it says so, as infos
MESHOPT_INFOS = {"UNSUPPORTED_EXTENSION", "UNUSED_OBJECT"}


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The cloth sample as a sequence (.glb, .gltf) and as its decomposition in each variant."""
    folder = tmp_path_factory.mktemp("gltf")
    cloth = load_sequence(sample_path())
    (folder / "cloth.tkc").write_bytes(encode(cloth, target_kg=0.1))
    decoder = Decoder(str(folder / "cloth.tkc"))
    files = {}
    for suffix in (".glb", ".gltf"):
        files[f"sequence{suffix}"] = folder / f"sequence{suffix}"
        save_sequence(cloth, files[f"sequence{suffix}"])
    for compress in COMPRESSIONS:
        files[compress] = folder / f"{compress}.glb"
        write_decomposition_gltf(decoder, files[compress], compress=compress)  # type: ignore[arg-type]
    # a tighter file: the quantize variant's weights no longer fit in 8 bits, so 16
    (folder / "fine.tkc").write_bytes(encode(cloth, ranks=(40, 17)))  # KG 0.036
    files["fine tkc"] = folder / "fine.tkc"
    files["quantize 16"] = folder / "quantize-16.glb"
    report = write_decomposition_gltf(Decoder(str(files["fine tkc"])), files["quantize 16"])
    assert report.weight_bits == 16
    files["meshopt twin"] = folder / "meshopt-twin.glb"
    files["meshopt twin"].write_bytes(_uncompressed(files["meshopt"]))
    files["tkc"] = folder / "cloth.tkc"
    return files


def _uncompressed(path: Path) -> bytes:
    """A .glb using EXT_meshopt_compression with every view decompressed into one buffer."""
    doc = read_document(path)
    gltf: dict[str, Any] = dict(doc.gltf)
    binary = bytearray()
    views = []
    for index, view in enumerate(gltf["bufferViews"]):
        data = bytes(view_bytes(doc, index))
        binary += b"\0" * (-len(binary) % 4)
        plain = {k: v for k, v in view.items() if k not in ("extensions", "buffer", "byteOffset")}
        views.append({**plain, "buffer": 0, "byteOffset": len(binary), "byteLength": len(data)})
        binary += data
    gltf["bufferViews"] = views
    gltf["buffers"] = [{"byteLength": len(binary)}]
    for key in ("extensionsUsed", "extensionsRequired"):
        gltf[key] = [name for name in gltf[key] if name != EXTENSION]
    assert EXTENSION in doc.gltf["extensionsRequired"] and gltf["extensionsRequired"]
    return pack_glb(gltf, bytes(binary))


def test_the_validator_finds_no_error_and_no_warning_in_any_written_file(
    written: dict[str, Path],
) -> None:
    names = [name for name in written if "tkc" not in name]
    reports = validate_gltf_files([written[name] for name in names])
    for name, report in zip(names, reports, strict=True):
        assert report["numErrors"] == report["numWarnings"] == 0, (name, issues(report))
        print(name, "validator infos and hints:", issues(report, HINT) or "none")
        infos = {message["code"] for message in report["messages"]}
        assert infos <= (MESHOPT_INFOS if name == "meshopt" else set()), (name, infos)


@pytest.mark.parametrize("compress", [*COMPRESSIONS, "quantize 16"])
def test_three_js_plays_the_decomposition_as_the_reader_and_the_decode_say(
    written: dict[str, Path], compress: str
) -> None:
    decoder = Decoder(str(written["fine tkc" if compress == "quantize 16" else "tkc"]))
    frames = np.array([0, 31, 45, 59])
    times = (frames / 24).astype(np.float32).astype(np.float64)  # the keyframes, exactly
    shown = three_positions(written[compress], times)
    ours = sample_gltf(written[compress], times).positions
    assert np.abs(shown - ours).max() <= 1e-9 * np.abs(ours).max()
    decoded = decoder.positions(frames)
    recorded = decoder.info.kg
    assert recorded is not None
    budget = BUDGET_SHARE * recorded if compress != "none" else 1e-4
    # the budget holds for the whole animation; over four frames allow twice its share
    assert kg_error(decoded, shown) <= 2 * budget


def test_three_js_plays_a_written_sequence_frame_by_frame(written: dict[str, Path]) -> None:
    cloth = load_sequence(sample_path())
    frames = np.array([0, 1, 40, 59])
    shown = three_positions(written["sequence.glb"], cloth.seconds()[frames].astype(np.float32))
    # three.js sums base + target in float64 from float32 data: within one float32 rounding
    assert np.allclose(shown, cloth.vertices[frames], rtol=0, atol=1e-6)


def test_a_polygon_sequence_and_a_point_sequence_validate(tmp_path: Path) -> None:
    vertices = np.random.default_rng(4).normal(size=(3, 5, 3))
    save_sequence(
        MeshSequence(vertices, np.array([[0, 1, 2, 3], [1, 4, 2, -1]])), tmp_path / "q.glb"
    )
    save_sequence(MeshSequence(vertices, np.zeros((0, 3))), tmp_path / "p.glb")
    for report in validate_gltf_files([tmp_path / "q.glb", tmp_path / "p.glb"]):
        assert not issues(report, INFO), issues(report, INFO)
