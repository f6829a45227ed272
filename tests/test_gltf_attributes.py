"""What a glTF keeps beside positions: vertex attributes written and read back bit for bit
under their names, per-corner UVs as split vertices whose values are the corners' again,
materials as primitives and back as face sets, per-frame normals in the morph targets, foreign
files' attributes (normalized colours, quantized UVs, materials, a rotated node's normals), what
``cannot_keep`` reports, and tools nobody here wrote on the files: trimesh sees the UVs, the
Khronos glTF-Validator finds no error nor warning."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.js_interop import issues, validate_gltf_files
from tests.support.sequences import shared_sequence
from tuckercodec import Decoder, InputError, MeshSequence, encode, load_sequence, save_sequence
from tuckercodec.gltf_export import morph_parts, write_decomposition_gltf
from tuckercodec.io import format_of
from tuckercodec.io.gltf.accessors import BufferBuilder, read_accessor
from tuckercodec.io.gltf.container import read_document
from tuckercodec.io.gltf.document import add_triangles, file_bytes, new_gltf
from tuckercodec.io.gltf.normals import recomputed_corner_normals
from tuckercodec.io.samples import sample_path
from tuckercodec.model.attributes import (
    CORNER,
    FACE,
    MATERIAL_FAMILY,
    VERTEX,
    Attribute,
    FaceSet,
    Field,
    corner_vertices,
)
from tuckercodec.model.normals import face_area_normals

FACES = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2], [2, 4, 5], [3, 2, 5]])


def _unit(values: np.ndarray) -> np.ndarray:
    return (values / np.linalg.norm(values, axis=1, keepdims=True)).astype(np.float32)


def _vertex_attributes(rng: np.random.Generator, count: int) -> list[Attribute]:
    return [
        Attribute("TEXCOORD_0", VERTEX, rng.random((count, 2)).astype(np.float32), role="uv"),
        Attribute("UVMap", VERTEX, rng.random((count, 2)).astype(np.float32), role="uv"),
        Attribute("NORMAL", VERTEX, _unit(rng.normal(size=(count, 3))), role="normal"),
        Attribute("COLOR_0", VERTEX, rng.random((count, 4)).astype(np.float32), role="color"),
        Attribute("Cd", VERTEX, rng.random((count, 3)).astype(np.float32), role="color"),
        Attribute("_PRESSURE", VERTEX, rng.random((count, 1)).astype(np.float32)),
        Attribute("temperature", VERTEX, rng.random((count, 2)).astype(np.float32)),
        Attribute("id", VERTEX, (np.arange(count) * 1000 - 3000).astype(np.int32)),
        Attribute("label", VERTEX, (np.arange(count) * 100_000).astype(np.int32)),
    ]


def _materials() -> list[FaceSet]:
    return [
        FaceSet("red", np.array([0, 1]), MATERIAL_FAMILY),
        FaceSet("blue", np.array([2, 3]), MATERIAL_FAMILY),
    ]  # face 4 in none


def _sequence(attributes: list[Attribute], frames: int = 3, **kwargs: object) -> MeshSequence:
    vertices = np.random.default_rng(7).normal(size=(frames, 6, 3))
    return MeshSequence(vertices, FACES, attributes=attributes, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_vertex_attributes_and_materials_round_trip_bit_for_bit(
    tmp_path: Path, suffix: str
) -> None:
    attributes = _vertex_attributes(np.random.default_rng(1), 6)
    seq = _sequence(attributes, face_sets=_materials())
    path = tmp_path / f"attributes{suffix}"
    save_sequence(seq, path)
    back = load_sequence(path)
    assert back.vertex_count == seq.vertex_count
    assert np.array_equal(back.faces, seq.faces)
    assert [a.name for a in back.attributes] == [a.name for a in attributes]
    for attribute in attributes:
        assert back.attribute_named(attribute.name).same_as(attribute), attribute.name
    assert len(back.face_sets) == 2
    for written, read in zip(_materials(), back.face_sets, strict=True):
        assert read.same_as(written)
    assert format_of(path).cannot_keep(seq) == []  # type: ignore[union-attr,misc]


def test_the_semantics_written_are_gltf_s_and_the_names_are_recorded(tmp_path: Path) -> None:
    attributes = _vertex_attributes(np.random.default_rng(2), 6)
    save_sequence(_sequence(attributes, face_sets=_materials()), tmp_path / "a.glb")
    doc = read_document(tmp_path / "a.glb")
    mesh = doc.gltf["meshes"][0]
    primitives = mesh["primitives"]
    assert [p.get("material") for p in primitives] == [0, 1, None]
    assert [m["name"] for m in doc.gltf["materials"]] == ["red", "blue"]
    assert sorted(primitives[0]["attributes"]) == sorted(
        [
            "POSITION",
            "TEXCOORD_0",
            "TEXCOORD_1",
            "NORMAL",
            "COLOR_0",
            "COLOR_1",
            "_PRESSURE",
            "_temperature",
            "_id",
            "_label",
        ]
    )
    record = mesh["extras"]["tuckercodec"]["attributes"]
    assert record["TEXCOORD_1"]["name"] == "UVMap" and record["_label"]["type"] == "int32"
    accessors = doc.gltf["accessors"]
    assert accessors[primitives[0]["attributes"]["_id"]]["componentType"] == 5122  # short
    assert all(set(target) == {"POSITION", "NORMAL"} for target in primitives[0]["targets"])


def _seamed_uvs() -> Attribute:
    """Per-corner UVs indexed as OBJ's vt: vertex 2 has a seam (two UVs), the rest one each."""
    corners = corner_vertices(FACES)
    indices = corners.copy()
    indices[[5, 8]] = 6  # face 1's and face 2's corners at vertex 2 take UV 6
    values = np.random.default_rng(3).random((7, 2)).astype(np.float32)
    return Attribute("st", CORNER, values, indices, role="uv")


def test_per_corner_uvs_read_back_at_the_corners_of_the_split_vertices(tmp_path: Path) -> None:
    uvs = _seamed_uvs()
    shading = Attribute("shade", FACE, np.arange(5, dtype=np.float32) / 4)
    seq = _sequence([uvs, shading])
    assert any("split vertices" in line for line in format_of("a.glb").cannot_keep(seq))  # type: ignore[union-attr,misc]
    save_sequence(seq, tmp_path / "split.glb")
    back = load_sequence(tmp_path / "split.glb")
    # vertex 2 is in 4 faces with 4 different shades, one of which has the other UV: 4 copies;
    # vertices 0 and 4 in two faces each, 1, 3 and 5 in several: one per distinct face
    assert back.vertex_count > seq.vertex_count
    assert back.faces.shape == seq.faces.shape
    written = uvs.element_values()
    read = back.attribute_named("st")
    assert read.domain == VERTEX and read.role == "uv"
    assert np.array_equal(read.values[corner_vertices(back.faces)], written)
    shade = back.attribute_named("shade").values[back.faces][:, :, 0]
    assert np.array_equal(shade, np.repeat(shading.values, 3, axis=1))
    # each written vertex carries its vertex's positions in every frame (float32 rounding)
    single = seq.vertices.astype(np.float32).astype(np.float64)
    assert np.array_equal(back.vertices[0][back.faces], single[0][seq.faces])
    assert np.allclose(back.vertices[:, back.faces], seq.vertices[:, seq.faces], atol=1e-6)


def test_an_animated_mesh_s_targets_hold_each_frame_s_recomputed_normals(tmp_path: Path) -> None:
    # a cube turning about z: its hard-edged per-corner normals turn with it
    cube = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])
    quads = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    )
    angles = np.array([0.0, 0.3, 1.1])
    turns = np.array(
        [[[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]] for a in angles]
    )
    vertices = np.einsum("fij,kj->fki", turns, cube)
    area = face_area_normals(cube, quads)
    authored = _unit(np.repeat(area, 4, axis=0))  # one normal per corner: the face's
    normal = Attribute("N", CORNER, authored, role="normal")
    seq = MeshSequence(vertices, quads, attributes=[normal])
    save_sequence(seq, tmp_path / "cube.glb")
    doc = read_document(tmp_path / "cube.glb")
    primitive = doc.gltf["meshes"][0]["primitives"][0]
    base = read_accessor(doc, primitive["attributes"]["NORMAL"], "test")
    assert len(base) == 24  # every corner of the cube its own vertex: 3 normals per corner
    positions = read_accessor(doc, primitive["attributes"]["POSITION"], "test")
    for frame in (1, 2):
        delta = read_accessor(doc, primitive["targets"][frame - 1]["NORMAL"], "test")
        assert np.allclose(base + delta, base @ turns[frame].T, atol=1e-6)
    back = load_sequence(tmp_path / "cube.glb")
    assert back.vertex_count == len(positions) == 24
    read = back.attribute_named("N")
    assert read.values.tobytes() == base.astype(np.float32).tobytes()
    # the triangles are the quads' fans, corners 0, 1, 2 then 0, 2, 3 of each
    fans = (np.arange(6)[:, None] * 4 + np.array([0, 1, 2, 0, 2, 3])[None]).reshape(-1)
    assert np.array_equal(read.values[corner_vertices(back.faces)], authored[fans])


def test_recomputed_corner_normals_follow_each_vertex_s_own_faces() -> None:
    """A sheet authored flat with one normal row for all its corners (an exporter that merges
    equal normals), folded: each corner gets the normal of its own vertex's faces, not one
    average of the sheet (glTF writes a normal per corner, it need not keep the shared rows);
    a face normal indexed the same way gives each face its own."""
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 1], [2, 1, 1]], float)
    faces = np.array([[0, 1, 2, 3], [1, 4, 5, 2]])  # folded along the edge 1-2
    up = np.array([[0, 0, 1]], np.float32)
    one_row = Attribute("N", CORNER, up, np.zeros(8, dtype=np.int64), role="normal")
    weighted = face_area_normals(points, faces)
    flat = weighted / np.linalg.norm(weighted, axis=1, keepdims=True)
    fold = (weighted[0] + weighted[1]) / np.linalg.norm(weighted[0] + weighted[1])
    by_vertex = np.array([flat[0], fold, fold, flat[0], flat[1], flat[1]])
    result = recomputed_corner_normals(points, faces, one_row)
    np.testing.assert_allclose(result, by_vertex[corner_vertices(faces)], atol=1e-12)
    per_face = Attribute("N", FACE, up, np.zeros(2, dtype=np.int64), role="normal")
    result = recomputed_corner_normals(points, faces, per_face)
    np.testing.assert_allclose(result, np.repeat(flat, 4, axis=0), atol=1e-12)


def test_what_gltf_cannot_keep_is_reported() -> None:
    seq = _sequence(
        [
            _seamed_uvs(),
            Attribute("weight", VERTEX, np.linspace(0, 1, 6)),
            Attribute("tag", VERTEX, np.array([0, 1, 2, 3, 4, 2**30], dtype=np.int32)),
        ],
        face_sets=[FaceSet("left", np.array([0, 1]), "group"), *_materials()],
        fields=[Field("speed", np.zeros((3, 6, 1)))],
    )
    said = " | ".join(format_of("a.gltf").cannot_keep(seq))  # type: ignore[union-attr,misc]
    for expected in (
        "corner-domain attributes become split vertices",
        "st",
        "float64 attributes are written as float32: weight",
        "int32 values beyond ±2^24 are rounded to float32: tag",
        "face sets other than materials are not written: group/left",
        "fields (animated values) are not written",
        "speed",
        "indexed attributes",
    ):
        assert expected in said


def _foreign(tmp_path: Path) -> Path:
    """A glTF as another tool writes it: two primitives of one vertex buffer with two materials
    (one unnamed), colours as normalized unsigned bytes, UVs as normalized unsigned shorts, an
    integer _CUSTOM attribute, a third primitive of its own vertices without a colour, and the
    node turned a quarter about y."""
    builder = BufferBuilder()
    rng = np.random.default_rng(5)
    positions = rng.normal(size=(6, 3)).astype(np.float32)
    colors = rng.integers(0, 256, size=(6, 3)).astype(np.uint8)
    uvs = rng.integers(0, 65536, size=(6, 2)).astype(np.uint16)
    custom = rng.integers(-500, 500, size=(6, 1)).astype(np.int16)
    normals = _unit(rng.normal(size=(6, 3)))
    shared = {
        "POSITION": builder.add_accessor(positions, bounds=True, vertex_attribute=True),
        "COLOR_0": builder.add_accessor(colors, normalized=True, vertex_attribute=True),
        "TEXCOORD_0": builder.add_accessor(uvs, normalized=True, vertex_attribute=True),
        "NORMAL": builder.add_accessor(normals, vertex_attribute=True),
        "_CUSTOM": builder.add_accessor(custom, vertex_attribute=True),
    }
    first: dict[str, object] = {"attributes": shared, "material": 1}
    add_triangles(builder, first, FACES[:2], 6)
    second: dict[str, object] = {"attributes": shared, "material": 0}
    add_triangles(builder, second, FACES[2:], 6)
    own = {
        "POSITION": builder.add_accessor(positions[:3] + 5, bounds=True, vertex_attribute=True),
        "TEXCOORD_0": builder.add_accessor(uvs[:3], normalized=True, vertex_attribute=True),
        "NORMAL": builder.add_accessor(normals[:3], vertex_attribute=True),
        "_CUSTOM": builder.add_accessor(custom[:3], vertex_attribute=True),
    }
    third: dict[str, object] = {"attributes": own, "material": 1}
    add_triangles(builder, third, np.array([[0, 1, 2]]), 3)
    gltf = new_gltf()
    quarter = [0.0, float(np.sin(np.pi / 4)), 0.0, float(np.cos(np.pi / 4))]
    gltf.update(
        {
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "rotation": quarter}],
            "meshes": [{"primitives": [first, second, third]}],
            "materials": [{"name": "skin"}, {}],
        }
    )
    path = tmp_path / "foreign.glb"
    path.write_bytes(file_bytes(gltf, builder, path))
    np.savez(tmp_path / "foreign.npz", colors=colors, uvs=uvs, custom=custom, normals=normals)
    return path


def test_a_foreign_file_s_attributes_materials_and_turned_normals(tmp_path: Path) -> None:
    path = _foreign(tmp_path)
    source = np.load(tmp_path / "foreign.npz")
    seq = load_sequence(path)
    assert seq.vertex_count == 9  # the shared buffer's 6, then the third primitive's own 3
    assert seq.faces.tolist() == [*FACES.tolist(), [6, 7, 8]]  # primitive order, index order
    color = seq.attribute_named("COLOR_0")
    assert color.role == "color" and color.values.dtype == np.float32
    expected = (source["colors"] / 255).astype(np.float32)
    assert np.array_equal(color.values[:6], expected)
    assert np.array_equal(color.values[6:], np.zeros((3, 3)))  # no colour there: zeros
    uv = seq.attribute_named("TEXCOORD_0")
    assert uv.role == "uv" and uv.values.dtype == np.float32
    assert np.array_equal(uv.values[:6], (source["uvs"] / 65535).astype(np.float32))
    custom = seq.attribute_named("_CUSTOM")
    assert custom.role == "generic" and custom.values.dtype == np.int32
    assert np.array_equal(custom.values[:6], source["custom"])
    # the node turns a quarter about y: the normals turn with the positions
    turn = np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]])
    normals = seq.attribute_named("NORMAL").values
    assert np.allclose(normals[:6], source["normals"] @ turn.T, atol=1e-6)
    unnamed, skin = seq.face_sets  # in the order of their first faces
    assert (unnamed.name, unnamed.faces.tolist()) == ("material_1", [0, 1, 5])
    assert (skin.name, skin.faces.tolist()) == ("skin", [2, 3, 4])
    assert {skin.family, unnamed.family} == {MATERIAL_FAMILY}


def test_trimesh_sees_the_uvs_and_the_validator_finds_no_issue(tmp_path: Path) -> None:
    trimesh = pytest.importorskip("trimesh", reason="trimesh (a core dependency) is missing")
    uvs = _seamed_uvs()
    vertex_attributes = _vertex_attributes(np.random.default_rng(4), 6)
    one_material = [FaceSet("cloth", np.arange(5), MATERIAL_FAMILY)]
    files = {
        "corner": _sequence([uvs], face_sets=one_material),
        "vertex": _sequence(vertex_attributes, face_sets=_materials()),
        "still": _sequence(vertex_attributes, frames=1),
    }
    paths = []
    for name, seq in files.items():
        for suffix in (".glb", ".gltf"):
            paths.append(tmp_path / f"{name}{suffix}")
            save_sequence(seq, paths[-1])
    loaded = trimesh.load(tmp_path / "corner.glb", force="mesh", process=False)
    back = load_sequence(tmp_path / "corner.glb")
    expected = back.attribute_named("st").values.astype(np.float64)
    expected[:, 1] = 1 - expected[:, 1]  # trimesh turns glTF's top-left origin to bottom-left
    assert np.allclose(loaded.visual.uv, expected)
    assert np.array_equal(loaded.faces, back.faces)
    for report in validate_gltf_files(paths):
        assert report["numErrors"] == 0 and report["numWarnings"] == 0, issues(report)


def test_samba_with_a_synthetic_uv_map_round_trips(tmp_path: Path) -> None:
    seq = shared_sequence("samba.npz")
    frames = MeshSequence(seq.vertices[:4], seq.faces)
    rest = frames.vertices[0]
    planar = (rest[:, [0, 1]] - rest[:, [0, 1]].min(0)) / np.ptp(rest[:, [0, 1]], 0)
    uv = Attribute("UVMap", VERTEX, planar.astype(np.float32), role="uv")
    # a seam down the middle: the corners of faces right of the median x take their UV shifted
    corners = corner_vertices(frames.faces)
    middle = np.median(rest[:, 0])
    right = np.repeat(rest[frames.faces].mean(axis=1)[:, 0] > middle, 3)
    shifted = planar[corners].astype(np.float32)
    shifted[right, 0] += 1
    seam = Attribute("seam", CORNER, shifted, role="uv")
    attributed = MeshSequence(frames.vertices, frames.faces, attributes=[uv, seam])
    save_sequence(attributed, tmp_path / "samba.glb")
    back = load_sequence(tmp_path / "samba.glb")
    assert np.array_equal(back.attribute_named("UVMap").values[back.faces], uv.values[frames.faces])
    assert np.array_equal(back.attribute_named("seam").values[corner_vertices(back.faces)], shifted)
    # one written vertex per vertex and side of the seam (and the vertices no face uses)
    sides = np.unique(np.column_stack([corners, right]), axis=0).shape[0]
    unused = frames.vertex_count - np.unique(corners).size
    assert back.vertex_count == sides + unused > frames.vertex_count
    single = frames.vertices.astype(np.float32).astype(np.float64)
    assert np.array_equal(back.vertices[0][back.faces], single[0][frames.faces])


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    """The cloth sample's decomposition exported in each variant with a seamed UV map and
    smooth per-vertex normals, and once without them."""
    folder = tmp_path_factory.mktemp("export")
    cloth = load_sequence(sample_path())
    (folder / "cloth.tkc").write_bytes(encode(cloth, target_kg=0.1))
    decoder = Decoder(str(folder / "cloth.tkc"))
    # per-corner values follow the faces in the decoder's order (this one's are reordered)
    faces = decoder.faces
    rest = cloth.vertices[0]
    corners = corner_vertices(faces)
    right = np.repeat(rest[faces].mean(axis=1)[:, 0] > np.median(rest[:, 0]), 3)
    uv = rest[corners][:, [0, 2]].astype(np.float32)
    uv[right, 0] += 1  # a seam: the faces right of the middle take other UVs
    uvs = Attribute("UVMap", CORNER, uv, role="uv")
    smooth = Attribute("N", VERTEX, np.zeros((cloth.vertex_count, 3), np.float32), role="normal")
    normals = np.zeros((cloth.vertex_count, 3))
    normals[corners] = recomputed_corner_normals(rest, faces, smooth)
    normal = Attribute("N", VERTEX, normals.astype(np.float32), role="normal")
    written: dict[str, object] = {"decoder": decoder, "uv": uv, "faces": faces}
    for compress in ("none", "quantize", "meshopt"):
        path = folder / f"{compress}.glb"
        written[compress] = write_decomposition_gltf(
            decoder,
            path,
            compress=compress,
            attributes=[uvs, normal],
        )
        written[f"plain {compress}"] = write_decomposition_gltf(
            decoder,
            folder / f"plain-{compress}.glb",
            compress=compress,
        )
    return written


@pytest.mark.parametrize("compress", ["none", "quantize", "meshopt"])
def test_the_export_carries_the_uvs_at_the_corners_and_shows_the_same_frames(
    exported: dict[str, Any], compress: str
) -> None:
    if compress == "meshopt":
        pytest.importorskip("meshoptimizer", reason="meshoptimizer (extra gltf) is missing")
    report, plain = exported[compress], exported[f"plain {compress}"]
    back = load_sequence(report.path)
    assert back.vertex_count > exported["decoder"].u1.shape[0]  # the seam split vertices
    uv = back.attribute_named("TEXCOORD_0")
    assert uv.role == "uv" and uv.values.dtype == np.float32
    assert _triangle_uvs(uv.values[back.faces]) == _triangle_uvs(exported["uv"].reshape(-1, 3, 2))
    # splitting copies vertices, it moves none: the viewer shows the same frames
    assert report.viewer_kg == plain.viewer_kg
    assert report.size > plain.size


def _triangle_uvs(per_triangle: np.ndarray) -> list[bytes]:
    """Each triangle's three UVs (T, 3, 2) as bytes, sorted: the same whatever the order of
    the triangles and of their corners (the meshopt variant orders them for the vertex cache)."""
    rows = np.ascontiguousarray(per_triangle, dtype=np.float32)
    return sorted(b"".join(sorted(uv.tobytes() for uv in row)) for row in rows)


def test_the_export_s_normals_follow_the_animation(exported: dict[str, Any]) -> None:
    report = exported["none"]
    decoder = exported["decoder"]
    doc = read_document(report.path)
    primitive = doc.gltf["meshes"][0]["primitives"][0]
    base = read_accessor(doc, primitive["attributes"]["NORMAL"], "test")
    assert np.allclose(np.linalg.norm(base, axis=1), 1, atol=1e-6)
    offsets = np.stack([read_accessor(doc, t["NORMAL"], "test") for t in primitive["targets"]])
    weights, _, _ = morph_parts(decoder, np.arange(decoder.u3.shape[0]))
    decoded = decoder.positions()
    faces = exported["faces"]
    smooth = Attribute("N", VERTEX, np.zeros((decoded.shape[1], 3), np.float32), role="normal")
    shown = load_sequence(report.path)
    first = np.zeros(shown.vertex_count, dtype=np.int64)
    first[corner_vertices(shown.faces)] = corner_vertices(faces)  # each written vertex's own
    fitted, still = [], []
    for frame in range(0, len(weights), 7):
        normals = base + np.einsum("b,bvx->vx", weights[frame], offsets)
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        true = np.zeros((decoded.shape[1], 3))
        true[corner_vertices(faces)] = recomputed_corner_normals(decoded[frame], faces, smooth)
        fitted.append(_angles(normals, true[first]))
        still.append(_angles(base, true[first]))
    # a linear blend of the targets' offsets: close, not exact (the cloth folds), and far
    # closer than one set of normals for every frame
    assert np.median(fitted) < 1 and np.max(fitted) < 15
    assert np.median(still) > 5 * np.median(fitted)


def _angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The angles in degrees between unit vectors, row by row."""
    return np.degrees(np.arccos(np.clip((a * b).sum(axis=1), -1, 1)))


def test_the_exports_with_uvs_and_normals_pass_the_validator(exported: dict[str, Any]) -> None:
    paths = [exported[c].path for c in ("none", "quantize")]
    for report in validate_gltf_files(paths):
        assert report["numErrors"] == 0 and report["numWarnings"] == 0, issues(report)


def _morphed_normals(tmp_path: Path, change: dict[str, object] | None = None) -> Path:
    """A still mesh shown at its default weight 0.5 of a target that moves its normals."""
    builder = BufferBuilder()
    positions = np.random.default_rng(8).normal(size=(6, 3)).astype(np.float32)
    normals = np.tile(np.array([[0, 0, 1]], np.float32), (6, 1))
    delta = np.tile(np.array([[2, 0, -1]], np.float32), (6, 1))
    primitive: dict[str, object] = {
        "attributes": {
            "POSITION": builder.add_accessor(positions, bounds=True, vertex_attribute=True),
            "NORMAL": builder.add_accessor(normals, vertex_attribute=True),
            "TEXCOORD_0": builder.add_accessor(positions[:, :2], vertex_attribute=True),
        },
        "targets": [
            {
                "POSITION": builder.add_accessor(0 * positions, bounds=True, vertex_attribute=True),
                "NORMAL": builder.add_accessor(delta, vertex_attribute=True),
            }
        ],
        "material": 0,
    }
    add_triangles(builder, primitive, FACES, 6)
    primitive.update(change or {})
    gltf = new_gltf()
    gltf.update(
        {
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [primitive], "weights": [0.5]}],
            "materials": [{"name": "bad\nname"}],
        }
    )
    path = tmp_path / "morphed.gltf"
    path.write_bytes(file_bytes(gltf, builder, path))
    return path


def test_frame_0_s_normals_add_the_weighted_normal_offsets(tmp_path: Path) -> None:
    seq = load_sequence(_morphed_normals(tmp_path))
    normals = seq.attribute_named("NORMAL").values
    assert normals.dtype == np.float32
    assert np.allclose(normals, np.array([1, 0, 0.5]) / np.sqrt(1.25), atol=1e-7)
    # a material name that is not a valid name (a control character) falls back to its number
    assert [s.name for s in seq.face_sets] == ["material_0"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"material": 3}, r"primitives\[0\]\.material refers to materials\[3\]"),
        ({"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}, r"TEXCOORD_0 needs 2 components"),
        ({"attributes": {"POSITION": 0, "_CUSTOM": 5}}, r"15 values for the 6 vertices"),
    ],
)
def test_bad_attributes_and_materials_are_refused_naming_them(
    tmp_path: Path, change: dict[str, object], message: str
) -> None:
    path = _morphed_normals(tmp_path, change)
    with pytest.raises(InputError, match=message) as caught:
        load_sequence(path)
    assert caught.value.path == str(path) or str(path) in str(caught.value)
