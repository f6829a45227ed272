"""The node harness the glTF tests trust (tests/js, driven by js_interop): the Khronos
glTF-Validator must pass a good file and catch a broken one, and three.js must play a morph
animation to the positions the glTF spec's formula gives, written by hand here and not by the
project's writer, in plain float32 and in the quantized and meshopt-compressed layouts the writer
produces."""

from __future__ import annotations

import base64
import json
import shutil
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support import js_interop
from tests.support.js_interop import (
    ERROR,
    INFO,
    issues,
    three_evaluate,
    three_positions,
    validate_gltf,
)

FLOAT, SHORT = 5126, 5122
ARRAY_BUFFER = 34962

# a triangle, two morph targets (displacements), a LINEAR weights track and a translation track
BASE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
TARGETS = np.array(
    [
        [[0.0, 0.0, 1.0], [0.0, 0.0, 0.5], [0.25, 0.0, 0.0]],
        [[-0.5, 0.0, 0.0], [0.0, 0.75, 0.0], [0.0, 0.0, -1.0]],
    ]
)
WEIGHT_TIMES = np.array([0.0, 1.0, 2.0])
WEIGHTS = np.array([[0.0, 0.0], [1.0, 0.5], [0.25, 1.0]])
MOVE_TIMES = np.array([0.0, 2.0])
MOVES = np.array([[0.0, 0.0, 0.0], [1.0, -2.0, 0.5]])
# on keyframes, between them, and past the end (where glTF holds the last value)
TIMES = np.array([0.0, 0.5, 1.0, 1.25, 2.0, 3.0])
# the quantized variant's node scale: every base and target coordinate within [-SCALE, SCALE]
SCALE = 1.25


def expected(times: np.ndarray) -> np.ndarray:
    """base + Σ w_i(t)·T_i + translation(t), the glTF spec's formula, in float64."""
    weights = np.stack([np.interp(times, WEIGHT_TIMES, WEIGHTS[:, i]) for i in range(2)], 1)
    moves = np.stack([np.interp(times, MOVE_TIMES, MOVES[:, i]) for i in range(3)], 1)
    return BASE + np.einsum("ti,ikc->tkc", weights, TARGETS) + moves[:, None, :]


class Gltf:
    """A glTF document and its binary buffer, built one accessor at a time."""

    def __init__(self) -> None:
        self.json: dict[str, Any] = {
            "asset": {"version": "2.0", "generator": "tuckercodec tests (by hand)"},
            "buffers": [{"byteLength": 0}],
            "bufferViews": [],
            "accessors": [],
        }
        self.bin = bytearray()

    def view(self, data: bytes, *, stride: int | None = None, target: int | None = None) -> int:
        """A bufferView on ``data``, 4-byte aligned; its index."""
        self.bin += b"\0" * (-len(self.bin) % 4)
        view: dict[str, Any] = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride is not None:
            view["byteStride"] = stride
        if target is not None:
            view["target"] = target
        self.bin += data
        self.json["bufferViews"].append(view)
        return len(self.json["bufferViews"]) - 1

    def accessor(self, view: int, values: np.ndarray, kind: str, **extra: Any) -> int:
        """An accessor of ``values`` (rows of float32 or int16) in bufferView ``view``; its
        index. min and max are the stored values, as glTF defines them."""
        rows = values.reshape(len(values), -1)
        accessor = {
            "bufferView": view,
            "componentType": FLOAT if values.dtype == np.float32 else SHORT,
            "count": len(rows),
            "type": kind,
            "min": [v.item() for v in rows.min(0)],
            "max": [v.item() for v in rows.max(0)],
            **extra,
        }
        self.json["accessors"].append(accessor)
        return len(self.json["accessors"]) - 1

    def meshopt_view(self, data: np.ndarray) -> int:
        """An EXT_meshopt_compression bufferView of vertex rows ``data``: the encoded bytes in
        the BIN chunk, the view itself in a fallback buffer that holds no data; its index."""
        meshoptimizer = pytest.importorskip(
            "meshoptimizer", reason="the meshopt variant needs the meshoptimizer package"
        )
        meshoptimizer.encode_vertex_version(0)  # the version EXT_meshopt_compression defines
        stride = data.nbytes // len(data)
        encoded = meshoptimizer.encode_vertex_buffer(data, len(data), stride)
        self.bin += b"\0" * (-len(self.bin) % 4)
        offset = len(self.bin)
        self.bin += encoded
        buffers = self.json["buffers"]
        if len(buffers) == 1:
            fallback = {"EXT_meshopt_compression": {"fallback": True}}
            buffers.append({"byteLength": 0, "extensions": fallback})
        view = {
            "buffer": 1,
            "byteOffset": buffers[1]["byteLength"],
            "byteLength": data.nbytes,
            "byteStride": stride,
            "target": ARRAY_BUFFER,
            "extensions": {
                "EXT_meshopt_compression": {
                    "buffer": 0,
                    "byteOffset": offset,
                    "byteLength": len(encoded),
                    "byteStride": stride,
                    "count": len(data),
                    "mode": "ATTRIBUTES",
                }
            },
        }
        buffers[1]["byteLength"] += data.nbytes
        self.json["bufferViews"].append(view)
        return len(self.json["bufferViews"]) - 1

    def floats(self, values: np.ndarray, kind: str, target: int | None = None) -> int:
        """An accessor of float32 values in a bufferView of its own."""
        data = np.ascontiguousarray(values, dtype="<f4")
        return self.accessor(self.view(data.tobytes(), target=target), data, kind)

    def glb(self) -> bytes:
        """The GLB file: header, JSON chunk, BIN chunk."""
        self.bin += b"\0" * (-len(self.bin) % 4)
        self.json["buffers"][0]["byteLength"] = len(self.bin)
        text = json.dumps(self.json, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<I4s", len(text), b"JSON") + text
        chunks += struct.pack("<I4s", len(self.bin), b"BIN\0") + bytes(self.bin)
        return struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks


def animate(doc: Gltf, weights_node: int, move_node: int) -> None:
    """The weights and translation tracks, LINEAR."""
    accessors = [
        doc.floats(WEIGHT_TIMES, "SCALAR"),
        doc.floats(WEIGHTS.ravel(), "SCALAR"),
        doc.floats(MOVE_TIMES, "SCALAR"),
        doc.floats(MOVES, "VEC3"),
    ]
    doc.json["animations"] = [
        {
            "name": "morph",
            "samplers": [
                {"input": accessors[0], "output": accessors[1], "interpolation": "LINEAR"},
                {"input": accessors[2], "output": accessors[3], "interpolation": "LINEAR"},
            ],
            "channels": [
                {"sampler": 0, "target": {"node": weights_node, "path": "weights"}},
                {"sampler": 1, "target": {"node": move_node, "path": "translation"}},
            ],
        }
    ]


def mesh(doc: Gltf, position: int, targets: list[int]) -> None:
    doc.json["meshes"] = [
        {
            "name": "triangle",
            "primitives": [
                {
                    "attributes": {"POSITION": position},
                    "targets": [{"POSITION": t} for t in targets],
                }
            ],
        }
    ]


def plain_glb() -> bytes:
    """float32 base and targets, both tracks on the mesh's node."""
    doc = Gltf()
    mesh(
        doc,
        doc.floats(BASE, "VEC3", ARRAY_BUFFER),
        [doc.floats(t, "VEC3", ARRAY_BUFFER) for t in TARGETS],
    )
    doc.json["nodes"] = [{"name": "triangle", "mesh": 0}]
    doc.json["scenes"] = [{"nodes": [0]}]
    doc.json["scene"] = 0
    animate(doc, 0, 0)
    return doc.glb()


def quantized_glb(compress: bool = False) -> bytes:
    """KHR_mesh_quantization: normalized SHORT base and targets (xyz padded to 8 bytes a
    vertex: vertex attributes are 4-byte aligned) under a node scaled by SCALE, whose parent
    carries the translation track; with ``compress``, their bufferViews EXT_meshopt_compression'd
    as gltfpack does."""
    doc = Gltf()
    accessors = []
    for values in (BASE, *TARGETS):
        data = np.zeros((len(values), 4), dtype="<i2")
        data[:, :3] = np.round(values / SCALE * 32767)
        view = (
            doc.meshopt_view(data)
            if compress
            else doc.view(data.tobytes(), stride=8, target=ARRAY_BUFFER)
        )
        accessors.append(doc.accessor(view, data[:, :3], "VEC3", normalized=True))
    mesh(doc, accessors[0], accessors[1:])
    doc.json["nodes"] = [
        {"name": "mover", "children": [1]},
        {"name": "triangle", "mesh": 0, "scale": [SCALE] * 3},
    ]
    doc.json["scenes"] = [{"nodes": [0]}]
    doc.json["scene"] = 0
    animate(doc, 1, 0)
    used = ["KHR_mesh_quantization"] + (["EXT_meshopt_compression"] if compress else [])
    doc.json["extensionsUsed"] = used
    doc.json["extensionsRequired"] = used
    return doc.glb()


def write(folder: Path, name: str, data: bytes) -> Path:
    path = folder / name
    path.write_bytes(data)
    return path


def as_gltf(glb: bytes, folder: Path, bin_name: str | None = "triangle.bin") -> Path:
    """The same document as a .gltf whose buffer is an external .bin beside it (or, with
    ``bin_name=None``, a base64 data: URI)."""
    (length,) = struct.unpack_from("<I", glb, 12)
    document = json.loads(glb[20 : 20 + length])
    data = glb[20 + length + 8 :]
    if bin_name is None:
        uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    else:
        uri = bin_name
        (folder / bin_name).write_bytes(data)
    document["buffers"][0]["uri"] = uri
    path = folder / "triangle.gltf"
    path.write_text(json.dumps(document))
    return path


def test_the_validator_passes_a_clean_file_in_each_layout(tmp_path: Path) -> None:
    plain = write(tmp_path, "plain.glb", plain_glb())
    for path in (plain, as_gltf(plain.read_bytes(), tmp_path)):
        report = validate_gltf(path)
        assert issues(report, INFO) == [], path
        assert report["info"]["animationCount"] == 1 and report["info"]["totalVertexCount"] == 3
    report = validate_gltf(write(tmp_path, "quantized.glb", quantized_glb()))
    assert issues(report, INFO) == []


def test_the_validator_reports_a_broken_file(tmp_path: Path) -> None:
    # the POSITION accessor reaching past its bufferView (the same length of JSON text)
    good = plain_glb()
    broken = good.replace(b'"count":3,"type":"VEC3"', b'"count":9,"type":"VEC3"', 1)
    assert broken != good
    report = validate_gltf(write(tmp_path, "broken.glb", broken))
    codes = {m["code"] for m in report["messages"] if m["severity"] == ERROR}
    assert report["numErrors"] >= 1 and "ACCESSOR_TOO_LONG" in codes, issues(report)


def test_the_validator_reads_a_gltf_external_buffer(tmp_path: Path) -> None:
    path = as_gltf(plain_glb(), tmp_path, "missing.bin")
    (tmp_path / "missing.bin").unlink()
    report = validate_gltf(path)
    assert report["numErrors"] >= 1, "the external .bin was not looked for"


def test_three_plays_the_morph_formula(tmp_path: Path) -> None:
    plain = write(tmp_path, "plain.glb", plain_glb())
    positions = three_positions(plain, TIMES)
    assert positions.shape == (len(TIMES), 3, 3)
    np.testing.assert_allclose(positions, expected(TIMES), rtol=0, atol=1e-6)
    # a time between keyframes really moves the vertices (the formula is not trivially met)
    assert np.abs(positions[1] - positions[0]).max() > 0.1
    for bin_name in ("triangle.bin", None):  # an external .bin, a data: URI
        gltf = as_gltf(plain.read_bytes(), tmp_path, bin_name)
        np.testing.assert_array_equal(three_positions(gltf, TIMES), positions)


def test_three_plays_the_quantized_and_meshopt_layouts(tmp_path: Path) -> None:
    quantized = three_positions(write(tmp_path, "q.glb", quantized_glb()), TIMES)
    # half a step of 16-bit rounding in the base and in each target, times its weight
    bound = 0.5 * SCALE / 32767 * (1 + np.abs(WEIGHTS).sum(1).max()) + 1e-6
    error = np.abs(quantized - expected(TIMES)).max()
    assert 0 < error <= bound, (error, bound)
    meshopt = write(tmp_path, "meshopt.glb", quantized_glb(compress=True))
    # meshopt's vertex codec is lossless: the very same numbers
    np.testing.assert_array_equal(three_positions(meshopt, TIMES), quantized)
    # the validator cannot look into the compressed views: it says so, and only that
    report = validate_gltf(meshopt)
    assert [(m["code"], m["severity"]) for m in report["messages"]] == [
        ("UNSUPPORTED_EXTENSION", INFO)
    ]


def test_the_evaluation_names_what_it_played(tmp_path: Path) -> None:
    summary = three_evaluate(write(tmp_path, "q.glb", quantized_glb()), [0.0, 1.0])
    (only,) = summary["meshes"]
    assert (only["node"], only["mesh"], only["primitive"]) == (1, 0, 0)
    assert only["vertexCount"] == 3 and only["morphTargets"] == 2
    assert summary["clip"] == {"index": 0, "name": "morph", "duration": 2.0}
    assert summary["times"] == [0.0, 1.0]


def test_what_three_warns_about_fails_the_evaluation(tmp_path: Path) -> None:
    glb = plain_glb()
    (length,) = struct.unpack_from("<I", glb, 12)
    document = json.loads(glb[20 : 20 + length])
    document["extensionsUsed"] = document["extensionsRequired"] = ["EXT_nobody_knows"]
    path = as_gltf(glb, tmp_path)
    path.write_text(json.dumps({**document, "buffers": json.loads(path.read_text())["buffers"]}))
    with pytest.raises(AssertionError, match="EXT_nobody_knows"):
        three_positions(path, TIMES)


def test_a_machine_without_node_skips_naming_what_is_missing(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert js_interop._setup.__wrapped__() == (None, "node and npm not found on PATH")
