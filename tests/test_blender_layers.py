"""The add-on's UV maps, colours, attributes, normals, materials and fields: the array work
(tuckercodec.blender.layers) anywhere, and in headless Blender (the ``bpy`` module, in a
process of its own: tests/support/blender_layers_session.py) a mesh of every kind of layer
exported and imported back, and the cloth-vellum sequence with a UV map imported and exported
again, each compared bit for bit."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest

import tuckercodec
from tests.support.sequences import SHARED_DATA, shared_file
from tuckercodec import Attribute, Decoder, FaceSet, MeshSequence
from tuckercodec.blender.layers import (
    blender_type,
    loop_values,
    material_face_sets,
    material_slots,
    maybe_indexed,
    rgba,
    split_animated,
)
from tuckercodec.blender.meshes import ExportFrames
from tuckercodec.model.attributes import corner_vertices

ROOT = Path(__file__).resolve().parents[1]
SESSION = Path(__file__).parent / "support" / "blender_layers_session.py"
NO_BPY = "needs Blender's bpy module (pip install 'bpy<5', Python 3.11): run with its Python"

# ------------------------------------------------------------------------------------------
# the array work, without Blender

FACES = np.array([[0, 1, 2, -1], [2, 1, 3, 4], [4, 3, 5, -1]])


def test_vertex_and_face_values_are_repeated_on_their_loops():
    per_vertex = Attribute("v", "vertex", np.arange(6, dtype=np.float32) * 10)
    per_face = Attribute("f", "face", np.array([7, 8, 9], dtype=np.int32))
    assert loop_values(per_vertex, FACES).ravel().tolist() == [
        0, 10, 20, 20, 10, 30, 40, 40, 30, 50,
    ]  # fmt: skip
    assert loop_values(per_face, FACES).ravel().tolist() == [7, 7, 7, 8, 8, 8, 8, 9, 9, 9]
    table = np.array([[0.5, 0.25], [1.0, 0.0]], dtype=np.float32)
    indexed = Attribute("uv", "corner", table, np.array([1, 0] * 5), "uv")
    np.testing.assert_array_equal(loop_values(indexed, FACES), table[[1, 0] * 5])


def test_shared_values_are_indexed_bit_for_bit_in_order_of_first_use():
    values = np.array([[0.5, 1.0], [0.0, 0.0], [0.5, 1.0], [-0.0, 0.0], [0.0, 0.0]], np.float32)
    attribute = maybe_indexed("uv", "corner", np.tile(values, (2, 1)), "uv")
    assert attribute.indices is not None
    assert attribute.indices.tolist() == [0, 1, 0, 2, 1] * 2  # -0.0 is a value of its own
    assert attribute.element_values().tobytes() == np.tile(values, (2, 1)).tobytes()
    distinct = np.arange(8, dtype=np.float32).reshape(4, 2)
    assert maybe_indexed("uv", "corner", distinct, "uv").indices is None


def test_material_sets_become_slots_and_come_back():
    sets = [
        FaceSet("red", np.array([0, 2]), "materialBind"),
        FaceSet("group", np.array([1]), "group"),
    ]
    names, slots = material_slots(sets, 4)
    assert names == [None, "red"]  # faces in no material: an empty slot first
    assert slots.tolist() == [1, 0, 1, 0]
    again = material_face_sets(names, slots)
    assert len(again) == 1 and again[0].same_as(sets[0])
    both = [
        FaceSet("a", np.array([1, 2]), "materialBind"),
        FaceSet("b", np.array([0]), "materialBind"),
    ]
    names, slots = material_slots(both, 3)
    assert names == ["a", "b"] and slots.tolist() == [1, 0, 0]
    assert all(x.same_as(y) for x, y in zip(material_face_sets(names, slots), both, strict=True))


def test_a_material_in_two_slots_or_on_no_face_makes_one_set_each():
    sets = material_face_sets(["a", "b", "a", "unused"], np.array([0, 1, 2, 7]))
    assert [(s.name, s.faces.tolist()) for s in sets] == [
        ("a", [0, 2]),
        ("b", [1]),
        ("unused", [3]),  # a slot beyond the last is the last, as Blender renders it
    ]
    assert material_face_sets([], np.zeros(3, dtype=np.int32)) == []


def test_blender_types_of_a_files_attributes():
    assert blender_type("w", np.zeros((2, 1), np.float64)) == "FLOAT"
    assert blender_type("uv", np.zeros((2, 2), np.float32)) == "FLOAT2"
    assert blender_type("v", np.zeros((2, 3), np.float32)) == "FLOAT_VECTOR"
    assert blender_type("c", np.zeros((2, 4), np.float32)) == "FLOAT_COLOR"
    assert blender_type("id", np.zeros((2, 1), np.int32)) == "INT"
    assert blender_type("sharp_face", np.zeros((2, 1), np.int32)) == "BOOLEAN"
    assert blender_type("pair", np.zeros((2, 2), np.int32)) == "INT32_2D"
    assert rgba(np.ones((2, 3))).tolist() == [[1.0] * 4] * 2


def test_attributes_that_change_over_the_frames_become_fields():
    static = Attribute("rest", "vertex", np.ones((3, 1), np.float32))
    moving = Attribute("velocity", "vertex", np.zeros((3, 3), np.float32))
    frames = {
        "rest": [static.values.copy(), static.values.copy()],
        "velocity": [moving.values, moving.values + 1.0],
    }
    kept, fields = split_animated([static, moving], frames)
    assert [a.name for a in kept] == ["rest"]
    assert [(f.name, f.role, f.values.shape) for f in fields] == [
        ("velocity", "velocity", (2, 3, 3))
    ]
    gathered = ExportFrames("obj")
    for number in (1, 2):
        gathered.add(number, np.zeros((3, 3)), np.array([[0, 1, 2]]))
    gathered.attributes, gathered.animated = [static, moving], frames
    sequence = gathered.sequence(24.0)
    assert [a.name for a in sequence.attributes] == ["rest"]
    assert [f.name for f in sequence.fields] == ["velocity"]


# ------------------------------------------------------------------------------------------
# in headless Blender

needs_bpy = pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason=NO_BPY)


class Session(NamedTuple):
    """What the Blender session did (tests/support/blender_layers_session.py)."""

    work: Path
    report: dict[str, Any]
    arrays: dict[str, np.ndarray]
    vellum: MeshSequence | None  # what WORKDIR/vellum.tkc was encoded from (None: no data)

    def vellums(self) -> MeshSequence:
        """The cloth-vellum sequence the session imported (or skip: ../shared/data absent)."""
        if self.vellum is None:
            shared_file("cloth-vellum.npz")  # skips, naming the missing file
        assert self.vellum is not None
        return self.vellum


def vellum_with_layers() -> MeshSequence:
    """12 frames of cloth-vellum (MIT, ../shared/data) with a UV map (frame 0 projected on
    its two widest axes, one UV per vertex: indexed by the corners' vertices) and two
    material sets (alternate faces)."""
    with np.load(shared_file("cloth-vellum.npz")) as data:
        positions, faces = data["V"][:12], data["F"].astype(np.int64)
    first = positions[0].astype(np.float64)
    low, high = first.min(axis=0), first.max(axis=0)
    axes = np.argsort(high - low)[1:]
    uv = ((first[:, axes] - low[axes]) / (high[axes] - low[axes])).astype(np.float32)
    numbers = np.arange(len(faces))
    return MeshSequence(
        positions,
        faces,
        frame_rate=24.0,
        attributes=[Attribute("UVMap", "corner", uv, corner_vertices(faces), "uv")],
        face_sets=[
            FaceSet("front", numbers[numbers % 2 == 0], "materialBind"),
            FaceSet("back", numbers[numbers % 2 == 1], "materialBind"),
        ],
    )


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> Session:
    if importlib.util.find_spec("bpy") is None:
        pytest.skip(NO_BPY)
    work = tmp_path_factory.mktemp("blender_layers")
    vellum = None
    if (SHARED_DATA / "cloth-vellum.npz").exists():  # else the session skips that part
        vellum = vellum_with_layers()
        (work / "vellum.tkc").write_bytes(tuckercodec.encode(vellum, target_kg=0.5))
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    environment["BLENDER_USER_RESOURCES"] = str(work / "user")  # not the user's own Blender
    done = subprocess.run(
        [sys.executable, str(SESSION), str(work)],
        capture_output=True,
        text=True,
        env=environment,
        cwd=work,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, f"the Blender session failed:\n{done.stdout}\n{done.stderr}"
    report = json.loads((work / "layers.json").read_text())
    with np.load(work / "layers.npz") as arrays:
        return Session(work, report, dict(arrays), vellum)


def _same_bits(first: np.ndarray, second: np.ndarray, what: str) -> None:
    assert first.dtype == second.dtype and first.shape == second.shape, what
    assert first.tobytes() == second.tobytes(), what


@needs_bpy
def test_a_meshs_uvs_colours_attributes_and_materials_come_back_bit_for_bit(session):
    report, arrays = session.report, session.arrays
    assert report["made_export"] == ["FINISHED"]
    made, again = report["made"], report["made_again"]
    assert made["uv_maps"] == again["uv_maps"] == ["UVMap", "detail"]
    assert made["materials"] == again["materials"] == ["cloth_red", "cloth_blue"]
    assert again["custom_normals"]
    # a byte colour comes back as the float colour Blender rendered it with
    assert again["colours"] == {
        "paint": ["FLOAT_COLOR", "POINT"],
        "tint": ["FLOAT_COLOR", "CORNER"],
    }
    compared = [key for key in arrays if key.startswith("made_") and "again" not in key]
    assert len(compared) == 11  # with the faces' sizes and the edges
    for key in compared:
        if key != "made_normals":
            _same_bits(arrays[key], arrays[key.replace("made_", "made_again_", 1)], key)
    assert len(np.unique(arrays["made_material_index"])) == 2


@needs_bpy
def test_custom_normals_come_back_within_blenders_own_rounding(session):
    """Blender keeps a custom normal as two 16-bit numbers in its corner's normal space, so a
    normal set again is rounded again: the same within 1e-4, not bit for bit."""
    made, again = session.arrays["made_normals"], session.arrays["made_again_normals"]
    assert np.abs(made - again).max() < 1e-4
    assert np.abs(made - [0.0, 0.0, 1.0]).max() > 0.05  # not Blender's own flat normals


@needs_bpy
def test_the_file_holds_what_blender_held(session):
    decoder = Decoder(session.work / "made.tkc")
    held = {a.name: a for a in decoder.attributes}
    expected = {"UVMap", "detail", "tint", "paint", "weight", "label", "normals", "sharp_face"}
    assert set(held) == expected
    # the grid's flat faces: Blender's boolean as 0 and 1
    assert held["sharp_face"].values.dtype == np.int32 and held["sharp_face"].values.all()
    uv = held["UVMap"]
    assert (uv.role, uv.domain, uv.values.dtype) == ("uv", "corner", np.dtype(np.float32))
    assert uv.indices is not None  # the grid's corners share their vertex's UV
    assert (held["weight"].domain, held["label"].values.dtype) == ("face", np.dtype(np.int32))
    assert held["normals"].role == "normal"
    np.testing.assert_array_equal(
        decoder.faces[decoder.faces >= 0], session.arrays["made_corners"]
    )  # the polygons and loops in Blender's order
    assert [(s.name, s.family) for s in decoder.face_sets] == [
        ("cloth_red", "materialBind"),
        ("cloth_blue", "materialBind"),
    ]


@needs_bpy
def test_cloth_vellums_uv_map_and_materials_are_imported_as_the_file_holds_them(session):
    session.vellums()
    file = Decoder(session.work / "vellum.tkc")
    arrays, report = session.arrays, session.report["vellum"]
    assert report["uv_maps"] == ["UVMap"] and report["materials"] == ["front", "back"]
    _same_bits(arrays["vellum_uv_UVMap"], file.attributes[0].element_values(), "UVMap")
    np.testing.assert_array_equal(arrays["vellum_corners"], corner_vertices(file.faces))
    expected = np.zeros(len(file.faces), dtype=np.int32)
    expected[file.face_sets[1].faces] = 1
    np.testing.assert_array_equal(arrays["vellum_material_index"], expected)


@needs_bpy
def test_cloth_vellum_exported_again_keeps_its_uv_map_and_materials(session):
    assert session.report["vellum_export"] == ["FINISHED"]
    original, again = session.vellums(), Decoder(session.work / "vellum_again.tkc")
    np.testing.assert_array_equal(again.faces, original.faces)
    assert [a.name for a in again.attributes] == ["UVMap"]  # smooth faces: no sharp_face
    uv = again.attributes[0]
    _same_bits(uv.element_values(), original.attributes[0].element_values(), "UVMap")
    assert uv.indices is not None and len(uv.values) == original.vertex_count
    assert len(again.face_sets) == 2
    assert all(x.same_as(y) for x, y in zip(again.face_sets, original.face_sets, strict=True))


RENDER_SESSION = Path(__file__).parent / "support" / "blender_render_session.py"


@pytest.fixture(scope="module")
def renders(tmp_path_factory) -> dict[str, np.ndarray]:
    """Headless Blender's images of cloth-vellum's frame 0 with a checker on its UV map: as it
    was, as the add-on imports it from a lossless and a KG 0.5 file, and with its UVs mirrored
    (tests/support/blender_render_session.py), by ``ENGINE_NAME``."""
    if importlib.util.find_spec("bpy") is None:
        pytest.skip(NO_BPY)
    work = tmp_path_factory.mktemp("blender_render")
    vellum = vellum_with_layers()
    np.savez(
        work / "original.npz",
        positions=vellum.vertices[0].astype(np.float32),
        faces=vellum.faces,
        uv=vellum.attributes[0].element_values(),
    )
    (work / "lossless.tkc").write_bytes(tuckercodec.encode(vellum, lossless=True))
    (work / "lossy.tkc").write_bytes(tuckercodec.encode(vellum, target_kg=0.5))
    done = subprocess.run(
        [sys.executable, str(RENDER_SESSION), str(work)],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT), "BLENDER_USER_RESOURCES": str(work / "u")},
        cwd=work,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, f"the Blender session failed:\n{done.stdout}\n{done.stderr}"
    with np.load(work / "renders.npz") as images:
        return dict(images)


@needs_bpy
@pytest.mark.parametrize("engine", ["BLENDER_WORKBENCH", "CYCLES"])
def test_headless_blender_renders_the_same_texture_before_and_after(renders, engine):
    """A lossless file renders the same pixels as the mesh it was made from; a KG 0.5 file
    differs only where its positions moved a little (a mean absolute difference under 0.01 of
    full scale, where mirrored UVs differ by over 0.1)."""
    original = renders[f"{engine}_original"][..., :3]
    assert original.std() > 0.1  # the checker is seen

    def difference(name: str) -> float:
        return float(np.abs(renders[f"{engine}_{name}"][..., :3] - original).mean())

    assert difference("lossless") == 0.0
    assert difference("lossy") < 0.01
    assert difference("mirrored") > 0.1
