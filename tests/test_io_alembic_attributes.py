"""The Alembic format's attributes, face sets and fields (tuckercodec/io/alembic_attached.py,
alembic_plan.py, alembic_writing.py): exact round trips; what we write, read with alembic3d
itself (each corner's UV in Alembic's clockwise winding); an archive authored with alembic3d
read through our reader (each corner keeps its value through the reversed winding); and
params that do not fit the mesh, refused naming the file and the param."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tuckercodec import Attribute, FaceSet, Field, InputError, MeshSequence
from tuckercodec.io import load_sequence, open_frames, save_sequence
from tuckercodec.io.alembic_plan import cannot_keep, per_frame_normals
from tuckercodec.io.registry import format_named
from tuckercodec.model.attributes import corner_faces, corner_vertices
from tuckercodec.model.normals import recomputed_normals

pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
import imath
from alembic3d import Abc, AbcCoreAbstract, AbcGeom

WRAP = Abc.WrapExistingFlag.kWrapExisting
#: Quads and triangles, counter-clockwise (ours); 14 corners.
FACES = np.array([[0, 1, 2, 3], [1, 4, 2, -1], [4, 5, 6, 2], [6, 3, 2, -1]])
#: The same faces as Alembic stores them, clockwise: counts and flat indices.
FILE_COUNTS = [4, 3, 4, 3]
FILE_INDICES = [3, 2, 1, 0, 2, 4, 1, 2, 6, 5, 4, 2, 3, 6]


def rich_sequence(frames: int = 3) -> MeshSequence:
    """A sequence with every kind of attribute, face set and field the writer keeps, and two
    it cannot (a float64 of 4 components, a second face set of the same name)."""
    rng = np.random.default_rng(7)
    corners = 14
    vertices = rng.standard_normal((frames, 7, 3)).astype(np.float32).astype(np.float64)
    attributes = [
        Attribute(
            "st", "corner", rng.random((5, 2), dtype=np.float32), rng.integers(0, 5, 14), "uv"
        ),
        Attribute("normals", "corner", rng.random((corners, 3), dtype=np.float32), None, "normal"),
        Attribute("uv2", "vertex", rng.random((7, 2)), None, "uv"),
        Attribute("Cd", "face", rng.random((4, 3), dtype=np.float32), None, "color"),
        Attribute(
            "rgba", "corner", rng.random((3, 4), dtype=np.float32), rng.integers(0, 3, 14), "color"
        ),
        Attribute("id", "face", np.arange(4, dtype=np.int32)),
        Attribute("weights", "vertex", rng.random((7, 3)), None),
        Attribute("four", "vertex", rng.random((7, 4))),  # float64 of 4: not kept
    ]
    face_sets = [
        FaceSet("red", np.array([0, 2]), "materialBind"),
        FaceSet("legs", np.array([1]), "group"),
        FaceSet("free", np.array([3]), ""),
        FaceSet("red", np.array([3]), "group"),  # a second "red": not kept
    ]
    fields = [
        Field("v", rng.random((frames, 7, 3), dtype=np.float32), "vertex", "velocity"),
        Field("pressure", rng.random((frames, 4)), "face", "generic"),
        Field("heat", rng.random((frames, 7, 1), dtype=np.float32), "vertex", "color"),
    ]
    return MeshSequence(vertices, FACES, attributes=attributes, face_sets=face_sets, fields=fields)


def mesh_schema(path: Path, name: str) -> tuple[Any, Any]:
    """The object and PolyMesh schema of ``name`` in ``path``, read with alembic3d."""
    item = Abc.IArchive(str(path)).getTop()
    for part in name.strip("/").split("/"):
        item = item.getChild(part)
    return item, AbcGeom.IPolyMesh(item, WRAP).getSchema()


# ------------------------------------------------------------------------------------------
# round trips


def test_attributes_face_sets_and_fields_round_trip_exactly(tmp_path):
    seq = rich_sequence()
    path = tmp_path / "rich.abc"
    save_sequence(seq, path)
    back = load_sequence(path)
    assert np.array_equal(back.faces, seq.faces)
    kept = [a for a in seq.attributes if a.name != "four"]
    assert sorted(a.name for a in back.attributes) == sorted(a.name for a in kept)
    for attribute in kept:
        assert back.attribute_named(attribute.name).same_as(attribute), attribute.name
    assert len(back.face_sets) == 3
    for face_set, read_set in zip(seq.face_sets[:3], back.face_sets, strict=True):
        assert read_set.same_as(face_set), face_set.name
    assert [f.name for f in back.fields] == ["v", "pressure", "heat"]
    for item in seq.fields:
        read = back.field_named(item.name)
        assert (read.domain, read.role) == (item.domain, item.role)
        assert read.values.dtype == item.values.dtype
        assert np.array_equal(read.values, item.values), item.name


def test_cannot_keep_says_what_an_archive_leaves_out():
    dropped = cannot_keep(rich_sequence())
    assert len(dropped) == 2
    assert "'four'" in dropped[0] and "float64 of 4" in dropped[0]
    assert "'red'" in dropped[1] and "group" in dropped[1]
    assert format_named("alembic").cannot_keep is cannot_keep
    assert cannot_keep(MeshSequence(np.zeros((2, 3, 3)), np.array([[0, 1, 2]]))) == []


def test_a_single_frame_keeps_its_normals_and_an_unindexed_uv(tmp_path):
    rng = np.random.default_rng(3)
    uv = Attribute("uv", "corner", rng.random((14, 2), dtype=np.float32), None, "uv")
    normal = Attribute("N", "vertex", rng.random((7, 3), dtype=np.float32), None, "normal")
    seq = MeshSequence(rng.standard_normal((1, 7, 3)), FACES, attributes=[uv, normal])
    save_sequence(seq, tmp_path / "one.abc")
    back = load_sequence(tmp_path / "one.abc")
    assert back.attribute_named("uv").same_as(uv)
    assert back.attribute_named("N").same_as(normal)


def test_fields_are_served_a_range_at_a_time_from_the_reading_child(tmp_path):
    seq = rich_sequence(frames=5)
    save_sequence(seq, tmp_path / "rich.abc")
    with open_frames(tmp_path / "rich.abc") as source:
        assert source.field_names == ["v", "pressure", "heat"]
        assert [s.name for s in source.face_sets] == ["red", "legs", "free"]
        fields = source.read_fields(2, 4)
        assert np.array_equal(source.read(2, 4), seq.vertices[2:4])
    for item, read in zip(seq.fields, fields, strict=True):
        assert np.array_equal(read.values, item.values[2:4])


# ------------------------------------------------------------------------------------------
# what we write, read by alembic3d itself


def test_alembic_reads_each_corners_uv_in_its_own_winding(tmp_path):
    seq = rich_sequence()
    path = tmp_path / "rich.abc"
    save_sequence(seq, path)
    _, schema = mesh_schema(path, "/rich/richShape")
    sample = schema.getValue(Abc.ISampleSelector(schema.getTimeSampling().getSampleTime(0)))
    assert np.asarray(sample.getFaceIndices()).tolist() == FILE_INDICES
    uvs = schema.getUVsParam()
    assert uvs.isIndexed() and uvs.getScope() == AbcGeom.GeometryScope.kFacevaryingScope
    assert uvs.getMetaData().get("sourceName") == "st"
    expanded = np.asarray(uvs.getExpandedValue().getVals())
    # Alembic's corner k of face f, at vertex v, holds the UV our corner of (f, v) holds
    ours = {
        (int(f), int(v)): row
        for f, v, row in zip(
            corner_faces(FACES),
            corner_vertices(FACES),
            seq.attribute_named("st").element_values(),
            strict=True,
        )
    }
    file_faces = np.repeat(np.arange(4), FILE_COUNTS)
    assert len(expanded) == 14
    for corner, (face, vertex) in enumerate(zip(file_faces, FILE_INDICES, strict=True)):
        assert np.array_equal(expanded[corner], ours[(int(face), vertex)])
    assert expanded.tolist() != seq.attribute_named("st").element_values().tolist()


def test_alembic_reads_normals_velocities_params_and_face_sets(tmp_path):
    seq = rich_sequence()
    path = tmp_path / "rich.abc"
    save_sequence(seq, path)
    item, schema = mesh_schema(path, "/rich/richShape")
    times = schema.getTimeSampling()
    normals = schema.getNormalsParam()
    assert normals.getScope() == AbcGeom.GeometryScope.kFacevaryingScope
    assert normals.getNumSamples() == 3 and not normals.isConstant()
    first = np.asarray(
        normals.getExpandedValue(Abc.ISampleSelector(times.getSampleTime(0))).getVals()
    )
    assert sorted(map(tuple, first.tolist())) == sorted(
        map(tuple, seq.attribute_named("normals").values.tolist())
    )
    later = np.asarray(
        normals.getExpandedValue(Abc.ISampleSelector(times.getSampleTime(2))).getVals()
    )
    assert np.allclose(np.linalg.norm(later, axis=1), 1, atol=1e-6)  # recomputed: unit length
    velocities = schema.getVelocitiesProperty()
    assert np.array_equal(
        np.asarray(velocities.getValue(Abc.ISampleSelector(times.getSampleTime(1)))),
        seq.field_named("v").values[1],
    )
    arb = schema.getArbGeomParams()
    assert AbcGeom.IC3fGeomParam.matches(arb.getPropertyHeader("Cd"))  # strict: rgb
    pressure = AbcGeom.IDoubleGeomParam(arb, "pressure")
    assert pressure.getScope() == AbcGeom.GeometryScope.kUniformScope
    assert pressure.getNumSamples() == 3
    assert sorted(schema.getFaceSetNames()) == ["free", "legs", "red"]
    red = AbcGeom.IFaceSet(item.getChild("red"), WRAP).getSchema()
    assert np.asarray(red.getValue().getFaces()).tolist() == [0, 2]


# ------------------------------------------------------------------------------------------
# an archive authored with alembic3d, read through our reader


def author(path: Path, *, uv_indices=None, temp_counts=(7, 7, 7), set_faces=(1, 3)) -> None:
    """A clockwise quad-and-triangle mesh of 3 samples with UVs indexed per corner (each
    corner's UV is (its vertex, its face), through a shuffled table), normals per corner
    (vertex, face, 9), face set "skin", an animated per-vertex float ``temp``."""
    file_faces = np.repeat(np.arange(4), FILE_COUNTS)
    pairs = np.column_stack([FILE_INDICES, file_faces]).astype(np.float32)
    shuffle = np.random.default_rng(5).permutation(14)
    table = np.zeros((14, 2), dtype=np.float32)
    table[shuffle] = pairs  # corner c's UV is table[shuffle[c]]
    indices = shuffle if uv_indices is None else np.asarray(uv_indices)
    archive = Abc.OArchive(str(path))
    sampling = archive.addTimeSampling(AbcCoreAbstract.TimeSampling(1 / 24, 0))
    mesh = AbcGeom.OPolyMesh(archive.getTop(), "shape", sampling)
    schema = mesh.getSchema()
    scope = AbcGeom.GeometryScope
    wide = imath.DoubleArrayFromBuffer(indices.astype(np.float64))
    uvs = AbcGeom.OV2fGeomParamSample(
        imath.V2fArrayFromBuffer(table), imath.UnsignedIntArray(wide), scope.kFacevaryingScope
    )
    normal_values = np.column_stack([pairs, np.full(14, 9, np.float32)])
    normals = AbcGeom.ON3fGeomParamSample(
        imath.V3fArrayFromBuffer(normal_values), scope.kFacevaryingScope
    )
    positions = np.random.default_rng(6).standard_normal((3, 7, 3)).astype(np.float32)
    for frame in range(3):
        points = imath.V3fArrayFromBuffer(positions[frame])
        if frame == 0:
            topology = [
                imath.IntArrayFromBuffer(np.array(a, np.int32)) for a in (FILE_INDICES, FILE_COUNTS)
            ]
            schema.set(AbcGeom.OPolyMeshSchemaSample(points, *topology, uvs, normals))
        else:
            schema.set(AbcGeom.OPolyMeshSchemaSample(points))
    temp = AbcGeom.OFloatGeomParam(
        schema.getArbGeomParams(), "temp", False, scope.kVertexScope, 1, sampling
    )
    for frame, count in enumerate(temp_counts):
        values = np.arange(count, dtype=np.float32) * 10 + frame
        temp.set(
            AbcGeom.OFloatGeomParamSample(imath.FloatArrayFromBuffer(values), scope.kVertexScope)
        )
    skin = schema.createFaceSet("skin").getSchema()
    skin.set(AbcGeom.OFaceSetSchemaSample(imath.IntArrayFromBuffer(np.array(set_faces, np.int32))))


def test_an_archive_authored_with_alembic_reads_with_every_corner_keeping_its_value(tmp_path):
    path = tmp_path / "authored.abc"
    author(path)
    seq = load_sequence(path)
    assert np.array_equal(seq.faces, FACES)  # counter-clockwise
    ours = np.column_stack([corner_vertices(FACES), corner_faces(FACES)]).astype(np.float32)
    uv = seq.attribute_named("uv")
    assert (uv.domain, uv.role, uv.values.dtype.name) == ("corner", "uv", "float32")
    assert uv.indices is not None and len(uv.values) == 14
    assert np.array_equal(uv.element_values(), ours)
    normal = seq.attribute_named("N")
    assert (normal.domain, normal.role, normal.indices) == ("corner", "normal", None)
    assert np.array_equal(normal.values, np.column_stack([ours, np.full(14, 9, np.float32)]))
    assert [s.name for s in seq.face_sets] == ["skin"]
    assert seq.face_sets[0].family == "materialBind"
    assert seq.face_sets[0].faces.tolist() == [1, 3]
    temp = seq.field_named("temp")
    assert (temp.domain, temp.role, temp.values.dtype.name) == ("vertex", "generic", "float32")
    expected = np.arange(7, dtype=np.float32)[None, :] * 10 + np.arange(3)[:, None]
    assert np.array_equal(temp.values[:, :, 0], expected)


@pytest.mark.parametrize(
    ("options", "words", "frame"),
    [
        ({"uv_indices": np.arange(14) + 1}, ["param uv", "index 14 of element 13"], 0),
        (
            {"temp_counts": (7, 7, 6)},
            ["param temp", "has 6 values for the mesh's 7 vertex elements"],
            2,
        ),
        ({"set_faces": (1, 4)}, ["face set skin", "face 4"], None),
    ],
)
def test_params_that_do_not_fit_the_mesh_are_refused_naming_file_and_param(
    tmp_path, options, words, frame
):
    path = tmp_path / "bad.abc"
    author(path, **options)
    with pytest.raises(InputError) as caught:
        load_sequence(path)
    message = str(caught.value)
    assert str(path) in message and "object /shape" in message
    for word in words:
        assert word in message
    assert caught.value.frame == frame


# ------------------------------------------------------------------------------------------
# normals per frame


def test_per_frame_normals_keep_frame_0_s_bits_and_recompute_the_others():
    seq = rich_sequence()
    normal = seq.attribute_named("normals")
    frames = per_frame_normals(seq, normal)
    assert frames.shape == (3, *normal.values.shape) and frames.dtype == np.float32
    assert frames[0].tobytes() == normal.values.tobytes()
    for frame in (1, 2):
        expected = recomputed_normals(seq.vertices[frame], seq.faces, normal)
        assert np.array_equal(frames[frame], expected)
