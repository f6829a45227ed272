"""The glTF format (.glb, .gltf): sequences written as morph targets and read back within the
float32 rounding of base + target; foreign morph animations read as a viewer shows them
(strips, node transforms, STEP/CUBICSPLINE, normalized weights, sparse accessors, --fps,
--object); and every damaged or hostile file refused with an InputError naming the file and
the part at fault."""

from __future__ import annotations

import base64
import json
import struct
import sys
import tracemalloc
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.sequences import shared_file
from tuckercodec import DependencyError, InputError, MeshSequence, load_sequence, save_sequence
from tuckercodec.io import format_of
from tuckercodec.io.gltf import container
from tuckercodec.io.gltf.container import pack_glb
from tuckercodec.io.samples import sample_path

FLOAT, UBYTE, USHORT = 5126, 5121, 5123


def _within_float32_rounding(back: MeshSequence, seq: MeshSequence) -> None:
    """The bound the sequence writer states: frame 0 is fl32(x0); frame t differs from x_t by
    at most one float32 rounding of its target, |x_t - fl32(x0)| * 2**-24."""
    base = seq.vertices[0].astype(np.float32).astype(np.float64)
    assert np.array_equal(back.vertices[0], base)
    bound = np.abs(seq.vertices[1:] - base) * 2.0**-24
    assert np.all(np.abs(back.vertices[1:] - seq.vertices[1:]) <= bound)


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_the_cloth_sample_round_trips_within_the_float32_rounding_of_base_plus_target(
    tmp_path: Path, suffix: str
) -> None:
    seq = load_sequence(sample_path())
    seq.frame_rate, seq.time_codes = 30.0, np.arange(seq.frame_count) * 2.0 + 5
    path = tmp_path / f"cloth{suffix}"
    save_sequence(seq, path)
    back = load_sequence(path)
    _within_float32_rounding(back, seq)
    assert np.array_equal(back.faces, seq.faces)
    assert back.frame_names == seq.frame_names
    assert back.frame_rate == 30.0
    assert back.time_codes is not None and np.array_equal(back.time_codes, seq.time_codes)


def test_horse_gallop_round_trips_within_the_float32_rounding(tmp_path: Path) -> None:
    seq = load_sequence(shared_file("horse-gallop"), progress=False)
    save_sequence(seq, tmp_path / "horse.glb")
    back = load_sequence(tmp_path / "horse.glb")
    _within_float32_rounding(back, seq)
    assert np.array_equal(back.faces, seq.faces)
    assert back.frame_rate is None and back.time_codes is None


def test_polygons_are_written_as_triangle_fans_and_points_as_points(tmp_path: Path) -> None:
    quads = np.array([[0, 1, 2, 3], [1, 4, 2, -1]])
    vertices = np.random.default_rng(1).normal(size=(3, 5, 3))
    save_sequence(MeshSequence(vertices, quads), tmp_path / "quads.glb")
    # in face order: each polygon's fan, then the next face's
    assert load_sequence(tmp_path / "quads.glb").faces.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]
    save_sequence(MeshSequence(vertices, np.zeros((0, 3))), tmp_path / "points.glb")
    points = load_sequence(tmp_path / "points.glb")
    assert points.faces.shape == (0, 3) and points.frame_count == 3


def test_a_static_glb_is_one_frame_and_a_folder_of_them_a_sequence(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    frames = rng.normal(size=(3, 4, 3))
    folder = tmp_path / "frames"
    folder.mkdir()
    for index, frame in enumerate(frames):
        save_sequence(MeshSequence(frame[None], faces), folder / f"f{index}.glb")
    one = load_sequence(folder / "f0.glb")
    assert one.frame_count == 1 and one.frame_rate is None
    seq = load_sequence(folder, progress=False)
    assert np.array_equal(seq.vertices, frames.astype(np.float32))
    assert np.array_equal(seq.faces, faces)
    assert format_of(folder / "a.GLB") is format_of(folder / "a.gltf")


def test_an_animated_glb_in_a_folder_of_frames_is_refused(tmp_path: Path) -> None:
    faces = np.array([[0, 1, 2]])
    save_sequence(MeshSequence(np.zeros((1, 3, 3)), faces), tmp_path / "a.glb")
    save_sequence(MeshSequence(np.ones((2, 3, 3)), faces), tmp_path / "b.glb")
    with pytest.raises(InputError, match="animation of 2 frames") as caught:
        load_sequence(tmp_path, progress=False)
    assert caught.value.frame == 1 and caught.value.path == str(tmp_path / "b.glb")


# ------------------------------------------------------------------------------------------
# foreign files, built by hand


class Builder:
    """A glTF assembled by hand (not by the package's writer), one buffer view per array."""

    def __init__(self) -> None:
        self.binary = bytearray()
        self.gltf: dict[str, Any] = {
            "asset": {"version": "2.0"},
            "bufferViews": [],
            "accessors": [],
        }

    def accessor(self, values: Any, dtype: str, kind: str, **extra: Any) -> int:
        array = np.asarray(values, dtype=dtype)
        self.binary += b"\0" * (-len(self.binary) % 4)
        view = {"buffer": 0, "byteOffset": len(self.binary), "byteLength": array.nbytes}
        self.binary += array.tobytes()
        self.gltf["bufferViews"].append(view)
        codes = {"<f4": FLOAT, "<u1": UBYTE, "<u2": USHORT, "<i2": 5122}
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[kind]
        self.gltf["accessors"].append(
            {
                "bufferView": len(self.gltf["bufferViews"]) - 1,
                "componentType": codes[dtype],
                "count": array.size // width,
                "type": kind,
                **extra,
            }
        )
        return len(self.gltf["accessors"]) - 1

    def write(self, path: Path) -> Path:
        gltf = dict(self.gltf)
        gltf["buffers"] = [{"byteLength": len(self.binary)}]
        path.write_bytes(pack_glb(gltf, bytes(self.binary)))
        return path


BASE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=np.float64)
TARGET = np.array([[0, 0, 1], [0, 0, 2], [0, 0, 3], [0, 0, 4]], dtype=np.float64)


def _animated(tmp_path: Path, *, interpolation: str = "LINEAR") -> Path:
    """A strip of 4 vertices with one morph target, its weights as normalized bytes, under a
    parent scaled by 2 whose child moves by a STEP translation track."""
    b = Builder()
    position = b.accessor(BASE, "<f4", "VEC3", min=[0, 0, 0], max=[1, 1, 0])
    target = b.accessor(TARGET, "<f4", "VEC3", min=[0, 0, 1], max=[0, 0, 4])
    strip = b.accessor([0, 1, 2, 3], "<u2", "SCALAR")
    times = b.accessor([0.0, 1.0, 2.0], "<f4", "SCALAR", min=[0.0], max=[2.0])
    if interpolation == "CUBICSPLINE":  # (in-tangent, value, out-tangent) per key
        weights = b.accessor([0, 0, 0, 0, 255, 0, 0, 51, 0], "<u1", "SCALAR", normalized=True)
    else:
        weights = b.accessor([0, 255, 51], "<u1", "SCALAR", normalized=True)
    moves = b.accessor([[0, 0, 0], [5, 0, 0]], "<f4", "VEC3")
    move_times = b.accessor([0.0, 1.5], "<f4", "SCALAR", min=[0.0], max=[1.5])
    b.gltf.update(
        {
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"scale": [2, 2, 2], "children": [1]}, {"name": "strip", "mesh": 0}],
            "meshes": [
                {
                    "primitives": [
                        {
                            "attributes": {"POSITION": position},
                            "indices": strip,
                            "mode": 5,
                            "targets": [{"POSITION": target}],
                        }
                    ]
                }
            ],
            "animations": [
                {
                    "samplers": [
                        {"input": times, "output": weights, "interpolation": interpolation},
                        {"input": move_times, "output": moves, "interpolation": "STEP"},
                    ],
                    "channels": [
                        {"sampler": 0, "target": {"node": 1, "path": "weights"}},
                        {"sampler": 1, "target": {"node": 1, "path": "translation"}},
                    ],
                }
            ],
        }
    )
    return b.write(tmp_path / "strip.glb")


def test_a_foreign_morph_animation_reads_as_a_viewer_shows_it(tmp_path: Path) -> None:
    seq = load_sequence(_animated(tmp_path))
    assert seq.faces.tolist() == [[0, 1, 2], [2, 1, 3]]  # a strip's second triangle turns
    # keyframes 0, 1, 1.5 (the translation's), 2 s: weight 0, 1, 0.6, 0.2
    weights = np.array([0.0, 1.0, 0.6, 0.2])
    moves = np.array([[0, 0, 0], [0, 0, 0], [5, 0, 0], [5, 0, 0]])
    expected = 2 * (BASE + weights[:, None, None] * TARGET + moves[:, None, :])
    assert np.allclose(seq.vertices, expected, atol=1e-12)
    assert seq.time_codes is not None
    assert seq.frame_rate == 24.0 and np.allclose(seq.time_codes, [0, 24, 36, 48])


def test_cubicspline_weights_follow_the_spec_hermite_curve(tmp_path: Path) -> None:
    seq = load_sequence(_animated(tmp_path, interpolation="CUBICSPLINE"), fps=4)
    assert seq.frame_count == 9 and seq.frame_rate == 4
    # between keys 0 (value 0, out-tangent 0) and 1 (value 1, in-tangent 0): 3s^2 - 2s^3
    s = 0.25
    weight = 3 * s**2 - 2 * s**3
    assert np.allclose(seq.vertices[1], 2 * (BASE + weight * TARGET), atol=1e-12)


def test_object_picks_one_of_several_meshes_and_an_unknown_name_lists_them(
    tmp_path: Path,
) -> None:
    b = Builder()
    first = b.accessor(BASE[:3], "<f4", "VEC3", min=[0, 0, 0], max=[1, 1, 0])
    second = b.accessor(BASE[1:] + 10, "<f4", "VEC3", min=[10, 10, 10], max=[11, 11, 10])
    b.gltf.update(
        {
            "nodes": [{"name": "a", "mesh": 0}, {"name": "b", "mesh": 1}],
            "meshes": [
                {"primitives": [{"attributes": {"POSITION": first}}]},
                {"name": "mesh-b", "primitives": [{"attributes": {"POSITION": second}}]},
            ],
        }
    )
    path = b.write(tmp_path / "two.glb")
    assert load_sequence(path).vertex_count == 6  # no scene, no --object: both, as shown
    assert np.array_equal(load_sequence(path, object_path="mesh-b").vertices[0], BASE[1:] + 10)
    with pytest.raises(InputError, match=r"no mesh node or mesh named 'c'.*a, b"):
        load_sequence(path, object_path="c")


# ------------------------------------------------------------------------------------------
# hostile files


@pytest.fixture
def good(tmp_path: Path) -> Path:
    seq = MeshSequence(
        np.random.default_rng(3).normal(size=(3, 4, 3)), np.array([[0, 1, 2], [0, 2, 3]])
    )
    save_sequence(seq, tmp_path / "good.glb")
    return tmp_path / "good.glb"


def _edit(path: Path, change: Any) -> Path:
    """The .glb with its JSON changed by ``change(gltf)`` (the BIN chunk kept)."""
    data = path.read_bytes()
    size = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20 : 20 + size])
    change(gltf)
    binary = data[20 + size + 8 :]
    path.write_bytes(pack_glb(gltf, binary))
    return path


def _refused(path: Path, pattern: str) -> InputError:
    with pytest.raises(InputError, match=pattern) as caught:
        load_sequence(path)
    assert caught.value.path == str(path)
    return caught.value


def test_a_truncated_glb_is_refused(good: Path) -> None:
    good.write_bytes(good.read_bytes()[:-100])
    _refused(good, "declares .* bytes but the file has .*truncated")


def test_bad_json_is_refused(good: Path) -> None:
    data = bytearray(good.read_bytes())
    data[20:22] = b"[}"
    good.write_bytes(bytes(data))
    _refused(good, "JSON cannot be parsed")


def test_an_accessor_beyond_its_buffer_view_is_refused_before_allocating(good: Path) -> None:
    def grow(gltf: dict[str, Any]) -> None:
        gltf["accessors"][0]["count"] = 10**12

    _refused(_edit(good, grow), r"accessors\[0\] \(meshes\[0\].primitives\[0\] POSITION\).*need")


def test_a_buffer_view_beyond_its_buffer_is_refused(good: Path) -> None:
    def shift(gltf: dict[str, Any]) -> None:
        gltf["bufferViews"][1]["byteOffset"] = 10**9

    _refused(_edit(good, shift), r"bufferViews\[1\]: bytes .* run past")


def test_non_finite_positions_are_refused_naming_the_accessor(good: Path) -> None:
    data = bytearray(good.read_bytes())
    size = struct.unpack_from("<I", data, 12)[0]
    struct.pack_into("<f", data, 20 + size + 8 + 4, float("nan"))  # vertex 0, y
    good.write_bytes(bytes(data))
    _refused(good, r"accessors\[0\].*element 0 is not finite")


def test_a_missing_external_buffer_and_uris_out_of_the_folder_are_refused(tmp_path: Path) -> None:
    gltf: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": "frames.bin", "byteLength": 48}],
        "bufferViews": [{"buffer": 0, "byteLength": 48}],
        "accessors": [{"bufferView": 0, "componentType": FLOAT, "count": 4, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
        "nodes": [{"mesh": 0}],
    }
    path = tmp_path / "a.gltf"
    path.write_text(json.dumps(gltf))
    _refused(path, r"buffers\[0\]: its file 'frames.bin' is missing")
    (tmp_path / "frames.bin").write_bytes(np.arange(12, dtype="<f4").tobytes())
    assert np.array_equal(load_sequence(path).vertices[0].ravel(), np.arange(12))
    (tmp_path / "link.bin").symlink_to(tmp_path.parent / "elsewhere.bin")
    outside = [
        "../frames.bin",
        "%2E%2E/frames.bin",
        "..\\frames.bin",
        "/etc/passwd",
        "%2Fetc%2Fpasswd",
        "C:/Windows/win.ini",
        "https://example.com/a.bin",
        "link.bin",
    ]
    for uri in outside:  # refused by the check every reader shares (reading.inside_folder)
        gltf["buffers"][0]["uri"] = uri
        path.write_text(json.dumps(gltf))
        _refused(path, r"buffers\[0\]: its uri names .*(leads out of its folder|absolute path)")
    for uri in ("frames%00.bin", "frames.bin\u0000"):  # a bare ValueError once, with no file named
        gltf["buffers"][0]["uri"] = uri
        path.write_text(json.dumps(gltf))
        _refused(path, r"buffers\[0\]: its uri names .* with a NUL character")


def test_an_accessor_without_a_buffer_view_is_bounded_by_the_bytes_the_file_holds(
    tmp_path: Path,
) -> None:
    """A crafted file: a .gltf of a few hundred bytes whose buffer declares 3 GB and is
    never loaded (no uri) asked for 3 GB of zeros; it is refused at once, naming the accessor.
    Zeros within the file's real data still read."""
    import tracemalloc

    count = 250_000_000  # 3 GB of float VEC3
    gltf: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": count * 12}],
        "accessors": [{"componentType": FLOAT, "count": count, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
        "nodes": [{"mesh": 0}],
    }
    path = tmp_path / "a.gltf"
    path.write_text(json.dumps(gltf))
    assert path.stat().st_size < 400
    for buffer in ({"byteLength": count * 12}, {"uri": "absent.bin", "byteLength": count * 12}):
        gltf["buffers"] = [buffer]
        path.write_text(json.dumps(gltf))
        pattern = r"accessors\[0\] \(.*POSITION\): 250000000 elements without"
        _refused(path, pattern)  # once first: the reader's imports are not the file's doing
        tracemalloc.start()
        try:
            error = _refused(path, pattern)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        # under a MiB now; 3.4 GB (and 12 s) before: memory holds on any machine, seconds not
        assert peak < 1 << 20, (peak, error)
        assert "more than the 0 bytes of data the file holds" in str(error)
    data = base64.b64encode(bytes(48)).decode()
    gltf["buffers"] = [{"uri": f"data:application/octet-stream;base64,{data}", "byteLength": 48}]
    gltf["accessors"][0]["count"] = 4  # 48 bytes of zeros: as much as the file holds
    path.write_text(json.dumps(gltf))
    assert np.array_equal(load_sequence(path).vertices, np.zeros((1, 4, 3)))
    gltf["accessors"][0]["count"] = 5
    path.write_text(json.dumps(gltf))
    _refused(path, "5 elements without a buffer view, more than the 48 bytes")


def test_buffers_of_one_file_read_it_once_and_count_its_bytes_once(tmp_path: Path) -> None:
    """A crafted file: a thousand buffers naming one file read it a thousand times, and
    counted it a thousand times as the data that bounds an accessor without a buffer view."""
    (tmp_path / "data.bin").write_bytes(bytes(48))
    gltf: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": "data.bin", "byteLength": 48}] * 1000,
        "accessors": [{"componentType": FLOAT, "count": 5, "type": "VEC3"}],  # 60 bytes
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
        "nodes": [{"mesh": 0}],
    }
    path = tmp_path / "a.gltf"
    path.write_text(json.dumps(gltf))
    doc = container.read_document(path)
    assert doc.buffer(0, "test").obj is doc.buffer(999, "test").obj
    _refused(path, "5 elements without a buffer view, more than the 48 bytes")


def _chain(path: Path, count: int, meshes: bool) -> Path:
    """A .gltf of ``count`` nodes, each the child of the next, each moved by x + 1; a point
    mesh at the bottom node, or at every node."""
    data = base64.b64encode(bytes(12)).decode()
    nodes: list[dict[str, Any]] = [
        {"translation": [1, 0, 0], **({"children": [index - 1]} if index else {})}
        for index in range(count)
    ]
    for index in range(count) if meshes else [0]:
        nodes[index]["mesh"] = 0
    gltf = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": f"data:application/octet-stream;base64,{data}", "byteLength": 12}],
        "bufferViews": [{"buffer": 0, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": FLOAT, "count": 1, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
        "nodes": nodes,
        "scenes": [{"nodes": [count - 1]}],
    }
    path.write_text(json.dumps(gltf, separators=(",", ":")))
    return path


def test_a_deep_hierarchy_costs_work_in_proportion_to_its_nodes(tmp_path: Path) -> None:
    """Quadratic work: the check for cycles walked from every node to its root, the scene's order
    was a list searched for every node, and each mesh node multiplied its whole chain of
    transforms: a chain of 30,000 nodes (1 MB of JSON) took 450 million steps to check, and
    30,000 mesh nodes nested each in the one before 450 million matrix products a frame.
    Each node is walked once now, and nesting beyond 64 levels per node of the file, in all,
    is refused before any frame is evaluated."""
    count = 10_000
    seq = load_sequence(_chain(tmp_path / "deep.gltf", count, meshes=False))
    assert seq.vertices.tolist() == [[[count, 0, 0]]]  # every level's translation applied
    path = _chain(tmp_path / "nested.gltf", count, meshes=True)
    _refused(path, r"its 10000 mesh nodes lie more than 640064 levels deep in all")


def test_the_weights_of_many_targets_are_evaluated_a_few_frames_at_a_time(
    tmp_path: Path,
) -> None:
    """A crafted file: the weights of every frame of a read were one (frames x targets)
    array, which 400 KB of JSON and keyframes made 800 MB: 5,000 targets that name one
    accessor, and 20,000 keyframes of a translation. They are evaluated a few frames at a
    time now, and the frames come out the same."""
    targets, frames = 5_000, 20_000
    b = Builder()
    position = b.accessor([[0, 0, 0]], "<f4", "VEC3", min=[0, 0, 0], max=[0, 0, 0])
    key = b.accessor([0.0], "<f4", "SCALAR", min=[0.0], max=[0.0])
    weights = b.accessor(np.zeros(targets), "<f4", "SCALAR")
    times = np.arange(frames, dtype=np.float32)
    move_times = b.accessor(times, "<f4", "SCALAR", min=[0.0], max=[float(frames - 1)])
    moves = b.accessor(np.stack([times, 0 * times, 0 * times], 1), "<f4", "VEC3")
    b.gltf.update(
        {
            "nodes": [{"mesh": 0}],
            "meshes": [
                {
                    "primitives": [
                        {
                            "attributes": {"POSITION": position},
                            "mode": 0,
                            "targets": [{"POSITION": position}] * targets,
                        }
                    ]
                }
            ],
            "animations": [
                {
                    "samplers": [
                        {"input": key, "output": weights},
                        {"input": move_times, "output": moves},
                    ],
                    "channels": [
                        {"sampler": 0, "target": {"node": 0, "path": "weights"}},
                        {"sampler": 1, "target": {"node": 0, "path": "translation"}},
                    ],
                }
            ],
        }
    )
    path = b.write(tmp_path / "many.glb")
    tracemalloc.start()
    try:
        seq = load_sequence(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert seq.vertices[:, 0, 0].tolist() == times.tolist()
    assert peak < 100 * 2**20, peak  # 800 MB of weights at once before


def test_a_data_uri_beyond_the_limit_is_refused(tmp_path: Path, monkeypatch: Any) -> None:
    save_sequence(MeshSequence(np.ones((2, 3, 3)), np.array([[0, 1, 2]])), tmp_path / "a.gltf")
    monkeypatch.setattr(container, "MAX_DATA_URI", 100)
    _refused(tmp_path / "a.gltf", "data: URI of .* characters")


def test_unsupported_required_extensions_skins_and_glTF_1_are_refused(good: Path) -> None:
    _refused(
        _edit(good, lambda g: g.update(extensionsRequired=["KHR_draco_mesh_compression"])),
        "requires KHR_draco_mesh_compression",
    )
    _edit(good, lambda g: g.pop("extensionsRequired"))
    _refused(_edit(good, lambda g: g["nodes"][0].update(skin=0)), r"nodes\[0\].*skinned")
    _refused(_edit(good, lambda g: g["asset"].update(version="1.0")), "not glTF 2.0")


def test_a_meshopt_file_without_meshoptimizer_names_the_extra(
    tmp_path: Path, monkeypatch: Any
) -> None:
    from tuckercodec import Decoder, encode
    from tuckercodec.gltf_export import write_decomposition_gltf

    seq = load_sequence(sample_path())
    data = encode(MeshSequence(seq.vertices[:8], seq.faces), ranks=(4, 3))
    (tmp_path / "a.tkc").write_bytes(data)
    decoder = Decoder(str(tmp_path / "a.tkc"))
    write_decomposition_gltf(decoder, tmp_path / "a.glb", compress="meshopt")
    monkeypatch.setitem(sys.modules, "meshoptimizer", None)  # import fails
    with pytest.raises(DependencyError, match=r"tuckercodec\[gltf\]"):
        load_sequence(tmp_path / "a.glb")
    with pytest.raises(DependencyError, match=r"tuckercodec\[gltf\]"):
        write_decomposition_gltf(decoder, tmp_path / "b.glb", compress="meshopt")
    assert not (tmp_path / "b.glb").exists()


def test_a_meshopt_view_claiming_more_than_its_codec_can_expand_is_refused(
    tmp_path: Path,
) -> None:
    from tuckercodec import Decoder, encode
    from tuckercodec.gltf_export import write_decomposition_gltf

    seq = load_sequence(sample_path())
    (tmp_path / "a.tkc").write_bytes(
        encode(MeshSequence(seq.vertices[:8], seq.faces), ranks=(4, 3))
    )
    path = tmp_path / "a.glb"
    write_decomposition_gltf(Decoder(str(tmp_path / "a.tkc")), path, compress="meshopt")
    assert load_sequence(path).frame_count == 8

    def inflate(gltf: dict[str, Any]) -> None:
        view = gltf["bufferViews"][0]
        view["extensions"]["EXT_meshopt_compression"]["count"] = 10**9
        view["byteLength"] = 10**9 * view["extensions"]["EXT_meshopt_compression"]["byteStride"]

    _refused(_edit(path, inflate), r"bufferViews\[0\].*impossible")


def test_meshopt_views_decode_within_max_memory_together(tmp_path: Path) -> None:
    """A decompression bomb: the attribute codec turns 16 bytes of zeros into 2 bits, so a
    meshopt view may honestly declare 64 times its bytes; the views a file decodes (and keeps)
    are bounded by --max-memory together, before each is decoded."""
    pytest.importorskip("meshoptimizer", reason="meshoptimizer (the 'gltf' extra) is missing")
    from tuckercodec.io.gltf.meshopt import EXTENSION, encode_attributes

    count = 2**20  # 12 MiB of float VEC3 zeros
    payload = encode_attributes(bytes(count * 12), count, 12)
    extension = {"buffer": 0, "byteLength": len(payload), "byteStride": 12, "count": count}
    view = {"buffer": 0, "byteLength": count * 12, "byteStride": 12}
    gltf: dict[str, Any] = {
        "asset": {"version": "2.0"},
        "extensionsUsed": [EXTENSION],
        "extensionsRequired": [EXTENSION],
        "buffers": [{"byteLength": len(payload)}],
        "bufferViews": [{**view, "extensions": {EXTENSION: {**extension, "mode": "ATTRIBUTES"}}}],
        "accessors": [{"bufferView": 0, "componentType": FLOAT, "count": count, "type": "VEC3"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
        "nodes": [{"mesh": 0}],
    }
    path = tmp_path / "zeros.glb"
    path.write_bytes(pack_glb(gltf, payload))
    assert load_sequence(path, max_memory=count * 12 * 2).vertex_count == count
    tracemalloc.start()
    try:
        beyond = r"inflates to 12\.6 MB, beyond the 4\.19 MB"
        with pytest.raises(InputError, match=beyond) as caught:
            load_sequence(path, max_memory=4 * 2**20)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert caught.value.path == str(path)
    assert str(caught.value).startswith(f"{path}: bufferViews[0].extensions.{EXTENSION}: ")
    assert peak < 4 * len(path.read_bytes()), peak  # not decoded
    folder = tmp_path / "frames"  # a static .glb is one frame of a folder: the same ceiling
    folder.mkdir()
    path.rename(folder / "0.glb")
    with pytest.raises(InputError, match=beyond):
        load_sequence(folder, max_memory=4 * 2**20)


def _beyond_float32() -> MeshSequence:
    """A finite float64 sequence one of whose coordinates float32 cannot hold (1e39)."""
    vertices = np.zeros((2, 4, 3))
    vertices[:, 1, 0] = vertices[:, 2, 1] = vertices[:, 3, 2] = 1.0
    vertices[1, 3, 2] = 1e39
    return MeshSequence(vertices, np.array([[0, 1, 2], [0, 2, 3]]))


def test_a_position_beyond_float32_is_refused_naming_the_frame(tmp_path: Path) -> None:
    # float32 turned it into inf, which json refused with a bare ValueError after a warning
    with pytest.raises(InputError, match="beyond the range of float32") as caught:
        save_sequence(_beyond_float32(), tmp_path / "big.glb")
    assert caught.value.frame == 1
    assert not (tmp_path / "big.glb").exists()
