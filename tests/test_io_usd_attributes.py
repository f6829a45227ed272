"""USD's attributes, face sets and fields (tuckercodec/io/usd_primvars.py, usd_authoring.py):
exact round trips through .usda, .usdc and .usd, what pxr itself reads of a written file, what
our reader makes of a stage authored with pxr, recomputed normals, what a file cannot keep,
and primvars that do not fit their mesh, refused naming the file and the primvar."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import expect_input_error
from tuckercodec import Attribute, FaceSet, Field, MeshSequence
from tuckercodec.io import load_sequence, open_frames, save_sequence
from tuckercodec.io.registry import format_named

pxr = pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
from pxr import Sdf, Usd, UsdGeom, Vt  # noqa: E402

from tests.test_io_usd import usdchecker_errors  # noqa: E402
from tuckercodec.io import usd  # noqa: E402

SUFFIXES = [".usda", ".usdc", ".usd"]
#: A quad and a triangle over 5 vertices, then a quad and a triangle again.
FACES = np.array([[0, 1, 2, 3], [1, 4, 2, -1], [4, 5, 6, 2], [6, 3, 2, -1]])
CORNERS = 14


def carrying_sequence(frames: int = 4) -> MeshSequence:
    """A polygon mesh carrying one of each: indexed uv, float64 and int32 attributes, face
    colours, indexed corner normals, face sets of two families, and three fields."""
    rng = np.random.default_rng(7)
    vertices = rng.standard_normal((frames, 7, 3))
    uv_table = rng.random((9, 2)).astype(np.float32)
    normals = rng.standard_normal((10, 3)).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    attributes = [
        Attribute("st", "corner", uv_table, rng.integers(0, 9, CORNERS), "uv"),
        Attribute("normals", "corner", normals, rng.integers(0, 10, CORNERS), "normal"),
        Attribute("displayColor", "face", rng.random((4, 3)).astype(np.float32), role="color"),
        Attribute("weight", "vertex", rng.random(7)),  # float64, 1 component
        Attribute("label", "vertex", rng.integers(-5, 5, (7, 2)).astype(np.int32)),
        Attribute("tint", "corner", rng.random((CORNERS, 4)), role="color"),  # color4d
    ]
    face_sets = [
        FaceSet("skin", np.array([0, 2]), "materialBind"),
        FaceSet("cloth", np.array([1, 3]), "materialBind"),
        FaceSet("left", np.array([0, 1]), "part"),
        FaceSet("loose", np.array([3])),
    ]
    fields = [
        Field(
            "velocities", rng.standard_normal((frames, 7, 3)).astype(np.float32), role="velocity"
        ),
        Field("pressure", rng.standard_normal((frames, 4, 1)), "face"),
        Field("heat", rng.random((frames, 7, 4)).astype(np.float32), role="color"),
    ]
    return MeshSequence(vertices, FACES, attributes=attributes, face_sets=face_sets, fields=fields)


def assert_same_carried(back: MeshSequence, seq: MeshSequence) -> None:
    """The same attributes and face sets (``same_as``: bit for bit) and fields (exact). Face
    sets in order; attributes and fields by name (pxr lists primvars by name)."""
    assert sorted(a.name for a in back.attributes) == sorted(a.name for a in seq.attributes)
    for written in seq.attributes:
        assert back.attribute_named(written.name).same_as(written), written.name
    assert [s.name for s in back.face_sets] == [s.name for s in seq.face_sets]
    for read_set, written_set in zip(back.face_sets, seq.face_sets, strict=True):
        assert read_set.same_as(written_set), read_set.name
    assert sorted(f.name for f in back.fields) == sorted(f.name for f in seq.fields)
    for written_field in seq.fields:
        read_field = back.field_named(written_field.name)
        assert (read_field.domain, read_field.role) == (written_field.domain, written_field.role)
        assert read_field.values.dtype == written_field.values.dtype, read_field.name
        assert read_field.values.tobytes() == written_field.values.tobytes(), read_field.name


def by_name(items, name):
    return next(item for item in items if item.name == name)


def indices_of(attribute: Attribute) -> np.ndarray:
    """An indexed attribute's indices."""
    assert attribute.indices is not None, attribute.name
    return attribute.indices


# ------------------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_attributes_face_sets_and_fields_round_trip_exactly(tmp_path, suffix):
    seq = carrying_sequence()
    path = tmp_path / f"carried{suffix}"
    save_sequence(seq, path)
    back = load_sequence(path)
    assert np.array_equal(back.faces, seq.faces)
    assert_same_carried(back, seq)
    assert usd.cannot_keep(seq) == []


def test_a_single_frame_round_trips_its_normals_and_fields(tmp_path):
    seq = carrying_sequence(frames=1)
    path = tmp_path / "one.usdc"
    save_sequence(seq, path)
    assert_same_carried(load_sequence(path), seq)


def test_fields_stream_a_range_at_a_time_through_the_reading_child(tmp_path):
    seq = carrying_sequence(frames=6)
    path = tmp_path / "stream.usdc"
    save_sequence(seq, path)
    with open_frames(path) as source:
        assert sorted(source.field_names) == ["heat", "pressure", "velocities"]
        fields = source.read_fields(2, 5)
    for item in fields:
        assert np.array_equal(item.values, seq.field_named(item.name).values[2:5])


# ------------------------------------------------------------------------------------------
# what pxr reads of a written file


def test_pxr_reads_the_written_primvars_subsets_and_velocities(tmp_path):
    seq = carrying_sequence()
    path = tmp_path / "pxr.usda"
    save_sequence(seq, path)
    stage = Usd.Stage.Open(str(path))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/pxr"))
    primvars = UsdGeom.PrimvarsAPI(mesh)
    st = primvars.GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    assert st.GetTypeName() == Sdf.ValueTypeNames.TexCoord2fArray
    assert np.array_equal(np.asarray(st.Get()), seq.attribute_named("st").values)
    assert np.array_equal(np.asarray(st.GetIndices()), indices_of(seq.attribute_named("st")))
    color = primvars.GetPrimvar("displayColor")
    assert color.GetInterpolation() == UsdGeom.Tokens.uniform
    assert color.GetTypeName() == Sdf.ValueTypeNames.Color3fArray
    assert np.array_equal(np.asarray(color.Get()), seq.attribute_named("displayColor").values)
    tint = primvars.GetPrimvar("tint")
    assert tint.GetTypeName() == Sdf.ValueTypeNames.Color4dArray
    weight = primvars.GetPrimvar("weight")
    assert (weight.GetInterpolation(), weight.GetTypeName()) == ("vertex", "double[]")
    label = primvars.GetPrimvar("label")
    assert label.GetTypeName() == Sdf.ValueTypeNames.Int2Array
    normals = primvars.GetPrimvar("normals")
    assert normals.GetTypeName() == Sdf.ValueTypeNames.Normal3fArray
    assert normals.GetAttr().GetTimeSamples() == [0.0, 1.0, 2.0, 3.0]
    assert np.array_equal(np.asarray(normals.Get(0)), seq.attribute_named("normals").values)
    velocities = mesh.GetVelocitiesAttr()
    for frame in range(seq.frame_count):
        expected = seq.field_named("velocities").values[frame]
        assert np.array_equal(np.asarray(velocities.Get(frame)), expected)
        pressure = np.asarray(primvars.GetPrimvar("pressure").Get(frame))
        assert np.array_equal(pressure, seq.field_named("pressure").values[frame, :, 0])
    assert primvars.GetPrimvar("pressure").GetInterpolation() == UsdGeom.Tokens.uniform
    subsets = {s.GetPrim().GetName(): s for s in UsdGeom.Subset.GetAllGeomSubsets(mesh)}
    assert sorted(subsets) == ["cloth", "left", "loose", "skin"]
    assert list(subsets["skin"].GetIndicesAttr().Get()) == [0, 2]
    assert subsets["skin"].GetFamilyNameAttr().Get() == "materialBind"
    assert subsets["loose"].GetFamilyNameAttr().Get() == ""
    assert UsdGeom.Subset.GetFamilyType(mesh, "materialBind") == UsdGeom.Tokens.partition
    assert UsdGeom.Subset.GetFamilyType(mesh, "part") == UsdGeom.Tokens.nonOverlapping
    valid, reason = UsdGeom.Subset.ValidateFamily(mesh, UsdGeom.Tokens.face, "materialBind")
    assert valid, reason


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_usds_validators_find_nothing_in_a_file_with_attributes(tmp_path, suffix):
    path = tmp_path / f"checked{suffix}"
    save_sequence(carrying_sequence(), path)
    assert usdchecker_errors(path) == []


# ------------------------------------------------------------------------------------------
# a stage authored with pxr


def authored_stage(path: Path, *, left_handed: bool = False, edit=None) -> Path:
    """A mesh as a DCC writes one: st indexed faceVarying, displayColor uniform, a constant
    displayOpacity, vertex normals in the ``normals`` attribute, a time-sampled vertex primvar,
    velocities, and two material subsets."""
    stage = Usd.Stage.CreateNew(str(path))
    mesh = UsdGeom.Mesh.Define(stage, "/World/thing")
    mesh.CreateFaceVertexCountsAttr([4, 3])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3, 1, 4, 2])
    if left_handed:
        mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    points, velocities = mesh.CreatePointsAttr(), mesh.CreateVelocitiesAttr()
    temperature = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "temperature", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.vertex
    )
    for time in range(3):
        shape = np.arange(15, dtype=np.float32).reshape(5, 3) + time
        points.Set(Vt.Vec3fArray.FromNumpy(shape), time)
        velocities.Set(Vt.Vec3fArray.FromNumpy(np.full((5, 3), time, np.float32)), time)
        temperature.Set(Vt.FloatArray([time + v for v in range(5)]), time)
    primvars = UsdGeom.PrimvarsAPI(mesh)
    st = primvars.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, "faceVarying")
    st.Set(Vt.Vec2fArray([(0, 0), (1, 0), (1, 1), (0, 1)]))
    st.SetIndices(Vt.IntArray([0, 1, 2, 3, 1, 2, 3]))
    color = primvars.CreatePrimvar("displayColor", Sdf.ValueTypeNames.Color3fArray, "uniform")
    color.Set(Vt.Vec3fArray([(1, 0, 0), (0, 0.5, 0)]))
    opacity = primvars.CreatePrimvar("displayOpacity", Sdf.ValueTypeNames.FloatArray, "constant")
    opacity.Set(Vt.FloatArray([0.5]))
    mesh.CreateNormalsAttr(Vt.Vec3fArray([(0, 0, 1)] * 5))
    mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
    for name, faces in (("wood", [1]), ("metal", [0])):
        UsdGeom.Subset.CreateGeomSubset(
            mesh, name, UsdGeom.Tokens.face, Vt.IntArray(faces), "materialBind"
        )
    if edit is not None:
        edit(mesh)
    stage.Save()
    return path


def test_a_stage_authored_with_pxr_reads_as_its_primvars_say(tmp_path):
    seq = load_sequence(authored_stage(tmp_path / "dcc.usda"))
    assert [a.name for a in seq.attributes] == ["displayColor", "st", "normals"]
    st = seq.attribute_named("st")
    assert (st.domain, st.role, st.values.dtype) == ("corner", "uv", np.dtype(np.float32))
    assert indices_of(st).tolist() == [0, 1, 2, 3, 1, 2, 3]
    assert st.values.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]
    color = seq.attribute_named("displayColor")
    assert (color.domain, color.role) == ("face", "color")
    assert color.values.tolist() == [[1, 0, 0], [0, 0.5, 0]]
    normals = seq.attribute_named("normals")
    assert (normals.domain, normals.role, normals.indices) == ("vertex", "normal", None)
    assert [(s.name, s.family, s.faces.tolist()) for s in seq.face_sets] == [
        ("wood", "materialBind", [1]),
        ("metal", "materialBind", [0]),
    ]
    velocities = seq.field_named("velocities")
    assert (velocities.domain, velocities.role, velocities.values.dtype) == (
        "vertex",
        "velocity",
        np.dtype(np.float32),
    )
    assert velocities.values[:, 0, 0].tolist() == [0, 1, 2]
    temperature = seq.field_named("temperature")
    assert temperature.values[:, :, 0].tolist() == [[t + v for v in range(5)] for t in range(3)]
    assert "displayOpacity" not in [a.name for a in seq.attributes]  # constant: not read


def test_primvars_normals_win_over_the_normals_attribute(tmp_path):
    def indexed_normals(mesh):
        normals = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
            "normals", Sdf.ValueTypeNames.Normal3fArray, UsdGeom.Tokens.faceVarying
        )
        normals.Set(Vt.Vec3fArray([(0, 1, 0), (1, 0, 0)]))
        normals.SetIndices(Vt.IntArray([0, 0, 0, 0, 1, 1, 1]))

    seq = load_sequence(authored_stage(tmp_path / "n.usda", edit=indexed_normals))
    normals = seq.attribute_named("normals")
    assert (normals.domain, normals.role) == ("corner", "normal")
    assert normals.values.tolist() == [[0, 1, 0], [1, 0, 0]]
    assert indices_of(normals).tolist() == [0, 0, 0, 0, 1, 1, 1]


def test_time_sampled_normals_are_frame_zeros(tmp_path):
    def sampled(mesh):
        normals = mesh.GetNormalsAttr()
        normals.Clear()
        for time in range(3):
            normals.Set(Vt.Vec3fArray([(0, 0, time + 1)] * 5), time)

    seq = load_sequence(authored_stage(tmp_path / "t.usda", edit=sampled))
    assert seq.attribute_named("normals").values[:, 2].tolist() == [1] * 5
    assert "normals" not in [f.name for f in seq.fields]


def test_a_left_handed_meshs_corner_attributes_follow_its_reversed_faces(tmp_path):
    right = load_sequence(authored_stage(tmp_path / "r.usda"))
    left = load_sequence(authored_stage(tmp_path / "l.usda", left_handed=True))
    assert left.faces.tolist() == [[3, 2, 1, 0], [2, 4, 1, -1]]
    # each corner keeps its uv: the same (vertex, uv) pairs, corner for corner
    for seq, expected in ((right, [0, 1, 2, 3, 1, 2, 3]), (left, [3, 2, 1, 0, 3, 2, 1])):
        assert indices_of(seq.attribute_named("st")).tolist() == expected
    # corner for corner, each face's (vertex, uv) pairs reversed: every corner keeps its uv
    for face in range(2):
        pairs = {}
        for seq in (right, left):
            corners = slice(4 * face, 4 * face + 4 - face)  # a quad, then a triangle
            vertices = seq.faces[face][seq.faces[face] >= 0].tolist()
            uvs = indices_of(seq.attribute_named("st"))[corners].tolist()
            pairs[seq is left] = list(zip(vertices, uvs, strict=True))
        assert pairs[True] == pairs[False][::-1]


def _typed_primvars(mesh):
    primvars = UsdGeom.PrimvarsAPI(mesh)
    primvars.RemovePrimvar("st")  # and its indices
    names = Sdf.ValueTypeNames
    for name, type_name, interpolation, values in (
        ("st", names.Float2Array, "varying", Vt.Vec2fArray([(0, 0)] * 5)),  # untyped: a uv
        ("N", names.Vector3fArray, "vertex", Vt.Vec3fArray([(0, 0, 1)] * 5)),  # a vector
        ("uvw", names.TexCoord3fArray, "vertex", Vt.Vec3fArray([(0, 0, 1)] * 5)),
        ("ids", names.IntArray, "uniform", Vt.IntArray([4, 5])),
        ("half", names.HalfArray, "vertex", Vt.HalfArray([1] * 5)),  # not read
        ("text", names.StringArray, "uniform", Vt.StringArray(["a", "b"])),  # not read
    ):
        primvars.CreatePrimvar(name, type_name, interpolation).Set(values)
    pair = primvars.CreatePrimvar("pair", names.FloatArray, "vertex", elementSize=2)
    pair.Set(Vt.FloatArray([0] * 10))  # elementSize 2: not read


def test_roles_and_types_come_from_the_value_type_then_the_name(tmp_path):
    seq = load_sequence(authored_stage(tmp_path / "typed.usda", edit=_typed_primvars))
    found = {a.name: (a.domain, a.role, a.values.dtype.str, a.components) for a in seq.attributes}
    assert found["st"] == ("vertex", "uv", "<f4", 2)
    assert found["N"] == ("vertex", "generic", "<f4", 3)
    assert found["uvw"] == ("vertex", "generic", "<f4", 3)
    assert found["ids"] == ("face", "generic", "<i4", 1)
    assert not {"half", "text", "pair"} & set(found)


# ------------------------------------------------------------------------------------------
# primvars that do not fit the mesh


def _with_primvar(values, interpolation, indices=None):
    def edit(mesh):
        primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
            "bad", Sdf.ValueTypeNames.FloatArray, interpolation
        )
        primvar.Set(Vt.FloatArray(values))
        if indices is not None:
            primvar.SetIndices(Vt.IntArray(indices))

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_with_primvar([1, 2, 3], "vertex"), r"primvar 'bad' \(vertex\) has 3 values.* 5 vertices"),
        (_with_primvar([1, 2, 3], "uniform"), r"primvar 'bad' \(uniform\) has 3 values.* 2 faces"),
        (
            _with_primvar([1, 2], "faceVarying", [0, 1, 1]),
            r"primvar 'bad' \(faceVarying\) has 3 indices.* 7 corners",
        ),
        (_with_primvar([1, 2], "faceVarying", [0, 1, 1, 1, 1, 9, 0]), "primvar 'bad'.*index 9"),
    ],
)
def test_a_primvar_that_does_not_fit_its_interpolation_is_refused(tmp_path, edit, message):
    path = authored_stage(tmp_path / "bad.usda", edit=edit)
    error = expect_input_error(lambda: load_sequence(path), path, match=message)
    assert "prim /World/thing" in str(error)


def test_a_time_sampled_primvar_whose_count_changes_names_the_frame(tmp_path):
    def shrinking(mesh):
        primvar = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("temperature")
        primvar.Set(Vt.FloatArray([1, 2]), 2)

    path = authored_stage(tmp_path / "shrink.usda", edit=shrinking)
    with open_frames(path) as source:
        assert source.read_fields(0, 2)  # frames 0 and 1 are fine
        expect_input_error(
            lambda: source.read_fields(1, 3), path, frame=2, match="primvar 'temperature'"
        )


def test_a_subset_naming_a_face_the_mesh_lacks_is_refused(tmp_path):
    def outside(mesh):
        UsdGeom.Subset.CreateGeomSubset(mesh, "far", UsdGeom.Tokens.face, Vt.IntArray([7]))

    path = authored_stage(tmp_path / "subset.usda", edit=outside)
    expect_input_error(lambda: load_sequence(path), path, match="GeomSubset 'far' names face 7")


# ------------------------------------------------------------------------------------------
# what a file cannot keep


def test_cannot_keep_is_the_formats_hook():
    assert format_named("usd").cannot_keep is usd.cannot_keep


def test_cannot_keep_names_renamed_names_and_lost_roles(tmp_path):
    base = carrying_sequence(frames=2)
    seq = MeshSequence(
        base.vertices,
        base.faces,
        attributes=[
            Attribute("UV Map.001", "corner", np.zeros((CORNERS, 2), np.float32), role="uv"),
            Attribute("st", "vertex", np.zeros((7, 2), np.float32)),  # generic: reads as a uv
            Attribute("ids", "face", np.zeros((4, 3), np.int32), role="color"),
        ],
        face_sets=[
            FaceSet("a b", np.array([0]), "materialBind"),
            FaceSet("a_b", np.array([1]), "materialBind"),
        ],
        fields=[Field("speed", np.zeros((2, 7, 3)), role="velocity")],
    )
    lost = usd.cannot_keep(seq)
    assert len(lost) == 6, lost
    text = "\n".join(lost)
    assert "'UV Map.001' is written as primvars:UV_Map_001" in text
    assert "attribute 'st' (generic, float32) reads back as a uv" in text
    assert "attribute 'ids' (color, int32) reads back as a generic" in text
    assert "face set 'a b' is written as GeomSubset a_b" in text
    assert "face set 'a_b' is written as GeomSubset a_b_2" in text
    assert "field 'speed' (velocity, 3 components) reads back as a generic field" in text
    path = tmp_path / "lossy.usda"
    save_sequence(seq, path)  # written all the same, under the names listed
    back = load_sequence(path)
    assert sorted(a.name for a in back.attributes) == ["UV_Map_001", "ids", "st"]
    assert [s.name for s in back.face_sets] == ["a_b", "a_b_2"]
    assert by_name(back.fields, "speed").role == "generic"


# ------------------------------------------------------------------------------------------
# normals of an animated mesh


def _rotation(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_written_normals_turn_with_the_surface_and_keep_their_hard_edges(tmp_path):
    # a unit cube's 6 quads, one normal per face shared by its 4 corners (hard edges)
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=np.float64)
    quads = np.array(
        [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    )
    flat = np.array(
        [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]], np.float32
    )
    normals = Attribute("normals", "corner", flat, np.repeat(np.arange(6), 4), "normal")
    turn = _rotation(np.pi / 2)
    seq = MeshSequence(np.stack([cube, cube @ turn.T]), quads, attributes=[normals])
    path = tmp_path / "cube.usda"
    save_sequence(seq, path)
    stage = Usd.Stage.Open(str(path))  # held: a prim does not keep its stage alive
    primvar = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/Root/cube")).GetPrimvar("normals")
    assert np.array_equal(np.asarray(primvar.Get(0)), flat)  # frame 0: stored, bit for bit
    turned = np.asarray(primvar.Get(1))
    assert np.allclose(turned, flat @ turn.T.astype(np.float32), atol=1e-6)
    assert np.array_equal(np.asarray(primvar.GetIndices()), indices_of(normals))
    assert load_sequence(path).attribute_named("normals").same_as(normals)
