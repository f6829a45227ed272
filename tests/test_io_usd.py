"""The USD format (tuckercodec/io/usd.py): exact round trips through .usda, .usdc and .usd,
the checks of usd-core's own usdchecker, choosing a mesh with --prim, and broken or odd stages,
each refused with an InputError that names the file, the prim and the frame."""

from __future__ import annotations

import os
import re
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import expect_input_error
from tests.support.sequences import shared_file
from tuckercodec import DependencyError, InputError, MeshSequence
from tuckercodec.cli import main
from tuckercodec.io import load_sequence, save_sequence
from tuckercodec.io.common.polygons import (
    faces_from_polygons,
    polygons_from_faces,
    reverse_winding,
)

pxr = pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
from pxr import Usd, UsdGeom, UsdValidation, Vt  # noqa: E402

SUFFIXES = [".usda", ".usdc", ".usd"]


@pytest.fixture(scope="module")
def horse() -> MeshSequence:
    return load_sequence(shared_file("horse-gallop"), progress=False)


def exact(back: MeshSequence, seq: MeshSequence) -> bool:
    """The same float32 positions bit for bit, the same faces."""
    return np.array_equal(back.vertices, seq.vertices.astype(np.float32)) and np.array_equal(
        back.faces, seq.faces
    )


def polygon_sequence() -> MeshSequence:
    """Quads and triangles (rows padded with -1) at uneven times and 30 frames per second."""
    rng = np.random.default_rng(1)
    faces = np.array([[0, 1, 2, 3], [1, 4, 2, -1], [4, 5, 6, 2], [6, 3, 2, -1]])
    return MeshSequence(
        rng.standard_normal((5, 7, 3)),
        faces,
        frame_rate=30.0,
        time_codes=np.array([-2.0, 0.5, 1.0, 7.25, 100.0]),
    )


# ------------------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_the_cloth_round_trips_exactly(cloth, tmp_path, suffix):
    path = tmp_path / f"cloth{suffix}"
    save_sequence(cloth, path)
    back = load_sequence(path)
    assert exact(back, cloth)
    assert back.frame_rate == 24.0  # the sequence has none: USD's default, written and read
    assert back.time_codes is not None
    assert np.array_equal(back.time_codes, cloth.codes())
    expected = b"#usda 1.0" if suffix == ".usda" else b"PXR-USDC"
    assert path.read_bytes().startswith(expected)


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_polygons_rates_and_uneven_time_codes_round_trip_exactly(tmp_path, suffix):
    seq = polygon_sequence()
    path = tmp_path / f"poly{suffix}"
    save_sequence(seq, path)
    back = load_sequence(path)
    assert exact(back, seq)
    assert back.time_codes is not None and seq.time_codes is not None
    assert back.frame_rate == 30.0 and np.array_equal(back.time_codes, seq.time_codes)


@pytest.mark.parametrize("suffix", [".usda", ".usdc"])
def test_horse_gallop_round_trips_exactly(horse, tmp_path, suffix):
    """(Its reading speed is measured by tools.bench read --formats, not asserted here.)"""
    path = tmp_path / f"horse{suffix}"
    save_sequence(horse, path)
    assert exact(load_sequence(path), horse)


def test_the_written_stage_is_what_the_docstring_says(tmp_path):
    path = tmp_path / "my-cloth 2.usda"
    save_sequence(polygon_sequence(), path)
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == "Y"
    assert stage.GetDefaultPrim().GetPath() == "/Root"
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (-2.0, 100.0)
    assert stage.GetTimeCodesPerSecond() == stage.GetFramesPerSecond() == 30.0
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Root/my_cloth_2"))
    assert mesh.GetSubdivisionSchemeAttr().Get() == "none"
    assert list(mesh.GetFaceVertexCountsAttr().Get()) == [4, 3, 4, 3]
    points = mesh.GetPointsAttr()
    assert points.GetTypeName() == "point3f[]" and points.GetTimeSamples() == [
        -2.0,
        0.5,
        1.0,
        7.25,
        100.0,
    ]
    extent = np.asarray(mesh.GetExtentAttr().Get(7.25))
    frame = np.asarray(points.Get(7.25))
    assert np.array_equal(extent, [frame.min(axis=0), frame.max(axis=0)])


@pytest.mark.parametrize("suffix", [".usda", ".usdc"])
def test_a_point_sequence_round_trips(tmp_path, suffix):
    seq = MeshSequence(np.random.default_rng(3).standard_normal((3, 5, 3)), np.zeros((0, 3)))
    save_sequence(seq, tmp_path / f"p{suffix}")
    back = load_sequence(tmp_path / f"p{suffix}")
    assert exact(back, seq) and back.faces.shape == (0, 3)
    assert usdchecker_errors(tmp_path / f"p{suffix}") == []


def test_nothing_is_replaced_without_overwrite(cloth, tmp_path):
    path = tmp_path / "out.usdc"
    path.write_bytes(b"old")
    with pytest.raises(FileExistsError, match="--force"):
        save_sequence(cloth, path)
    assert path.read_bytes() == b"old"
    save_sequence(cloth, path, overwrite=True)
    assert exact(load_sequence(path), cloth)
    assert [p.name for p in tmp_path.iterdir()] == ["out.usdc"]


# ------------------------------------------------------------------------------------------
# usdchecker


def usdchecker_errors(path: Path) -> list[str]:
    """What ``usdchecker --useNewValidationFramework`` reports for the file, errors and
    warnings: the usd-core wheel ships no usdchecker command (nor, since 25.x, the Python
    ComplianceChecker), so this is that command's code path run directly: every registered
    validator of usd-core's UsdValidation framework, less the usdz ones (kept only with
    --arkit) and RootPackageValidator (kept only with --rootPackageOnly)."""
    registry = UsdValidation.ValidationRegistry()
    names = [
        meta.name
        for meta in registry.GetAllValidatorMetadata()
        if "UsdzValidators" not in meta.GetKeywords()
        and meta.name != "usdUtilsValidators:RootPackageValidator"
    ]
    assert len(names) > 10, "too few validators: the check would prove little"
    context = UsdValidation.ValidationContext(registry.GetOrLoadValidatorsByName(names))
    return [error.GetErrorAsString() for error in context.Validate(Usd.Stage.Open(str(path)))]


@pytest.mark.parametrize("suffix", SUFFIXES)
def test_usdchecker_finds_no_error_or_warning_in_written_files(tmp_path, suffix):
    path = tmp_path / f"poly{suffix}"
    save_sequence(polygon_sequence(), path)
    assert usdchecker_errors(path) == []


def test_usdchecker_does_find_errors_in_a_stage_that_lacks_them(tmp_path):
    # the same check on a bare mesh: no upAxis, metersPerUnit, defaultPrim
    path = tmp_path / "bare.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Mesh.Define(stage, "/m")
    stage.Save()
    found = " ".join(usdchecker_errors(path))
    for rule in ("MissingUpAxisMetadata", "MissingMetersPerUnitMetadata", "MissingDefaultPrim"):
        assert rule in found


# ------------------------------------------------------------------------------------------
# choosing a mesh


def make_stage(path: Path, meshes: dict[str, int], **extra: object) -> Path:
    """A stage with one triangle-fan Mesh per entry (its path: its number of time samples, 0
    for a default value only), plus an Xform /World."""
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.Xform.Define(stage, "/World")
    for prim_path, samples in meshes.items():
        mesh = UsdGeom.Mesh.Define(stage, prim_path)
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3, 3]))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([0, 1, 2, 0, 2, 3]))
        points = mesh.CreatePointsAttr()
        base = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)
        if samples == 0:
            points.Set(Vt.Vec3fArray.FromNumpy(base))
        for frame in range(samples):
            points.Set(Vt.Vec3fArray.FromNumpy(base + frame), 10.0 + frame)
        for name, value in extra.items():
            mesh.GetPrim().GetAttribute(name).Set(value)
    stage.Save()
    return path


def test_without_prim_the_only_animated_mesh_is_read(tmp_path):
    path = make_stage(tmp_path / "s.usda", {"/World/ground": 0, "/World/cloth": 3})
    seq = load_sequence(path)
    assert seq.time_codes is not None
    assert seq.frame_count == 3 and np.array_equal(seq.time_codes, [10.0, 11.0, 12.0])
    assert seq.vertices[2, 0, 0] == 2.0


def test_a_single_static_mesh_is_one_frame(tmp_path):
    seq = load_sequence(make_stage(tmp_path / "s.usda", {"/World/ground": 0}))
    assert seq.frame_count == 1 and seq.time_codes is None
    assert np.array_equal(seq.faces, [[0, 1, 2], [0, 2, 3]])


def test_several_animated_meshes_need_prim_and_prim_chooses(tmp_path):
    meshes = {"/World/a": 2, "/World/b": 4, "/World/ground": 0}
    path = make_stage(tmp_path / "s.usdc", meshes)
    error = expect_input_error(lambda: load_sequence(path), path, match="--prim")
    assert "/World/a" in str(error) and "/World/b" in str(error)
    assert "/World/ground" not in str(error)  # not a candidate: its points are not animated
    assert load_sequence(path, prim="/World/b").frame_count == 4
    assert load_sequence(path, prim="/World/ground").frame_count == 1


@pytest.mark.parametrize(
    ("prim", "message"),
    [
        ("/World/missing", "there is no prim /World/missing"),
        ("/World", "prim /World is a Xform prim, not a Mesh"),
        ("World/a", "is not the absolute path of a prim"),
        ("not a path", "is not the absolute path of a prim"),
        ("/World/a.points", "is not the absolute path of a prim"),
    ],
)
def test_a_prim_that_is_not_a_mesh_is_named_with_the_meshes(tmp_path, prim, message, capfd):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 2, "/World/b": 2})
    error = expect_input_error(lambda: load_sequence(path, prim=prim), path, match=message)
    assert "the meshes are: /World/a, /World/b" in str(error)
    assert capfd.readouterr().err == ""  # pxr's warning about an ill-formed path is kept


def test_a_stage_without_meshes_says_so(tmp_path):
    path = make_stage(tmp_path / "s.usda", {})
    expect_input_error(lambda: load_sequence(path), path, match="holds no Mesh prim")


def test_prim_does_not_apply_to_other_formats(cloth, tmp_path):
    path = tmp_path / "c.npz"
    save_sequence(cloth, path)
    with pytest.raises(InputError, match=r"--prim \(prim\) does not apply.*usd"):
        load_sequence(path, prim="/Root/c")


# ------------------------------------------------------------------------------------------
# odd and broken stages


def test_a_left_handed_mesh_has_its_faces_reversed(tmp_path):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 2}, orientation="leftHanded")
    assert np.array_equal(load_sequence(path).faces, [[2, 1, 0], [3, 2, 0]])


def _edit_mesh(path: Path, prim: str, edit) -> Path:
    stage = Usd.Stage.Open(str(path))
    edit(UsdGeom.Mesh(stage.GetPrimAtPath(prim)))
    stage.Save()
    return path


@pytest.mark.parametrize("attribute", ["faceVertexIndices", "faceVertexCounts"])
def test_faces_that_change_over_time_are_refused_naming_the_frame(tmp_path, attribute):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 4})

    def change(mesh):
        attr = mesh.GetPrim().GetAttribute(attribute)
        first = attr.Get()
        attr.Set(first, 10.0)
        attr.Set(first, 11.0)  # the same: not a change
        other = [0, 1, 3, 1, 2, 3] if attribute == "faceVertexIndices" else [4, 2]
        attr.Set(Vt.IntArray(other), 11.5)  # held from 11.5 on: frame 2 (time 12) differs

    _edit_mesh(path, "/World/a", change)
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=2,
        match=r"prim /World/a: the faces change at time code 12\.0",
    )


def test_a_point_count_that_changes_is_refused_naming_the_frame(tmp_path):
    path = make_stage(tmp_path / "s.usdc", {"/World/a": 3})
    _edit_mesh(
        path, "/World/a", lambda m: m.GetPointsAttr().Set(Vt.Vec3fArray([(0, 0, 0)] * 5), 11.0)
    )
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=1,
        match="prim /World/a: 5 points at time code 11.0, where frame 0 has 4",
    )


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_non_finite_point_names_the_frame_and_vertex(tmp_path, value):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 3})
    bad = np.zeros((4, 3), dtype=np.float32)
    bad[3, 1] = value
    _edit_mesh(path, "/World/a", lambda m: m.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(bad), 12))
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=2,
        match="prim /World/a: vertex 3 has a non-finite coordinate at time code 12.0",
    )


def test_a_blocked_points_sample_is_refused(tmp_path):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 3})
    _edit_mesh(path, "/World/a", lambda m: m.GetPointsAttr().Set(pxr.Sdf.ValueBlock(), 11))
    expect_input_error(lambda: load_sequence(path), path, frame=1, match="no points at")


@pytest.mark.parametrize(
    ("counts", "indices", "message"),
    [
        ([3, 2], [0, 1, 2, 0, 2], "face 1 has 2 corners"),
        ([3, 3], [0, 1, 2, 0, 2, 4], "face 1 has a vertex index 4 outside 0..3"),
        ([3, 3], [0, 1, 2, 0, 2], "the face counts add up to 6 corners but there are 5"),
        ([3, 3], [0, 1, 2, 0, -1, 3], "face 1 has a vertex index -1"),
    ],
)
def test_broken_faces_are_refused_naming_the_face(tmp_path, counts, indices, message):
    path = make_stage(tmp_path / "s.usda", {"/World/a": 2})

    def edit(mesh):
        mesh.GetFaceVertexCountsAttr().Set(Vt.IntArray(counts))
        mesh.GetFaceVertexIndicesAttr().Set(Vt.IntArray(indices))

    _edit_mesh(path, "/World/a", edit)
    expect_input_error(lambda: load_sequence(path), path, match=f"prim /World/a: {message}")


def _valid_crate(tmp_path: Path) -> bytes:
    path = tmp_path / "valid.usdc"
    save_sequence(polygon_sequence(), path)
    return path.read_bytes()


@pytest.mark.parametrize(
    ("suffix", "make"),
    [
        (".usdc", lambda good: good[: len(good) // 2]),  # truncated
        (".usdc", lambda good: b"PXR-USDC" + bytes(range(256)) * 4),  # garbage after the magic
        (".usdc", lambda good: b""),
        (".usda", lambda good: b'#usda 1.0\ndef Mesh "m" {\n point3f[] points = [(0, 0'),
        (".usda", lambda good: b'#usda 1.0\ndef Mesh "m\xf2x" {\n}\n'),  # pxr quotes non-UTF-8
        (".usd", lambda good: b"\x00\xff" * 100),
    ],
)
def test_a_truncated_or_garbage_file_is_refused_quietly(tmp_path, suffix, make, capfd):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(make(_valid_crate(tmp_path)))
    expect_input_error(lambda: load_sequence(path), path, match="cannot read as a USD file")
    assert capfd.readouterr().err == ""


def test_points_declared_far_beyond_the_file_are_refused(tmp_path):
    # pxr 26 checks an uncompressed array's byte range against the file before reading it;
    # the count sits just before the 7 points of frame 0 in the crate
    seq = polygon_sequence()
    path = tmp_path / "huge.usdc"
    save_sequence(seq, path)
    data = bytearray(path.read_bytes())
    at = bytes(data).find(seq.vertices[0].astype(np.float32).tobytes())
    assert at > 8 and struct.unpack_from("<Q", data, at - 8)[0] == 7
    struct.pack_into("<Q", data, at - 8, 10**11)
    path.write_bytes(bytes(data))
    expect_input_error(
        lambda: load_sequence(path), path, frame=0, match="out-of-bounds|cannot read the points"
    )


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes on this system")
def test_a_pipe_named_like_a_stage_is_refused_without_hanging(tmp_path):
    pipe = tmp_path / "pipe.usda"
    os.mkfifo(pipe)
    expect_input_error(lambda: load_sequence(pipe), pipe, match="not a regular file")


# ------------------------------------------------------------------------------------------
# confinement: a stage reads only files inside its own folder, so a crafted one cannot read
# another file of the machine


def _arc(kind: str, asset: str):
    """An edit of a stage that makes it name ``asset`` by one kind of arc or clip."""

    def edit(stage) -> None:
        prim = stage.DefinePrim("/Other")
        if kind == "sublayer":
            stage.GetRootLayer().subLayerPaths.append(asset)
        elif kind == "reference":
            prim.GetReferences().AddReference(asset, "/World/cloth")
        elif kind == "payload":
            prim.GetPayloads().AddPayload(asset, "/World/cloth")
        elif kind == "variant":
            variants = prim.GetVariantSets().AddVariantSet("look")
            variants.AddVariant("outside")
            variants.SetVariantSelection("outside")
            with variants.GetVariantEditContext():
                prim.GetReferences().AddReference(asset, "/World/cloth")
        elif kind == "clip":
            clips = Usd.ClipsAPI(prim)
            clips.SetClipAssetPaths(pxr.Sdf.AssetPathArray([asset]))
            clips.SetClipPrimPath("/World/cloth")
        elif kind == "manifest":
            Usd.ClipsAPI(prim).SetClipManifestAssetPath(pxr.Sdf.AssetPath(asset))
        else:  # a clip template: a pattern of files
            Usd.ClipsAPI(prim).SetClipTemplateAssetPath(asset.replace(".usda", ".#.usda"))

    return edit


def _confined(tmp_path: Path, edit) -> Path:
    """In folder stage/: s.usda (an animated mesh) edited by ``edit``; outside it, beside the
    folder, secret.usda (another mesh, its data not the stage's to give)."""
    make_stage(tmp_path / "secret.usda", {"/World/cloth": 2})
    (tmp_path / "stage").mkdir(exist_ok=True)
    path = make_stage(tmp_path / "stage" / "s.usda", {"/World/cloth": 3})
    stage = Usd.Stage.Open(str(path))
    edit(stage)
    stage.Save()
    return path


@pytest.mark.parametrize(
    "kind", ["sublayer", "reference", "payload", "variant", "clip", "manifest", "template"]
)
@pytest.mark.parametrize("outside", ["../secret.usda", "{tmp}/secret.usda"])
def test_a_stage_naming_a_file_outside_its_folder_is_refused(tmp_path, kind, outside):
    asset = outside.format(tmp=tmp_path)
    path = _confined(tmp_path, _arc(kind, asset))
    named = asset.replace(".usda", ".#.usda") if kind == "template" else asset
    expect_input_error(
        lambda: load_sequence(path, prim="/World/cloth"),
        path,
        # the message names at most the asset's first 80 characters (a long {tmp}, as under
        # pytest-xdist's popen-gwN/ folders, is cut there)
        match=rf"it names the asset '{re.escape(named[:80])}', which leads out of the stage's",
    )


def test_a_layer_inside_that_names_one_outside_is_refused_naming_both(tmp_path, capsys):
    inner = _confined(tmp_path, lambda stage: None).parent / "inner.usda"
    layer = pxr.Sdf.Layer.CreateNew(str(inner))
    layer.subLayerPaths.append("/etc/passwd")  # found by the resolver: it exists
    layer.Save()
    path = _confined(tmp_path, _arc("sublayer", "./inner.usda"))
    expect_input_error(
        lambda: load_sequence(path),
        path,
        match=f"its layer {re.escape(str(inner))} names the asset '/etc/passwd', which leads out",
    )
    assert main(["convert", str(path), str(tmp_path / "out.npz")]) == 4
    said = capsys.readouterr().err
    assert said.count("\n") == 1 and "'/etc/passwd', which leads out" in said, said


def test_files_inside_the_folder_and_missing_ones_are_read_as_usd_reads_them(tmp_path):
    (tmp_path / "stage" / "parts").mkdir(parents=True)
    make_stage(tmp_path / "stage" / "parts" / "more.usda", {"/World/cloth": 2})
    for kind in ("sublayer", "reference", "payload"):
        path = _confined(tmp_path, _arc(kind, "./parts/more.usda"))
        assert load_sequence(path, prim="/World/cloth").frame_count == 3
    # a file that is not there is not read by pxr either: its warning, not our refusal
    path = _confined(tmp_path, _arc("reference", str(tmp_path / "absent.usda")))
    assert load_sequence(path, prim="/World/cloth").frame_count == 3
    expression = _arc("reference", '`"${WHERE}/secret.usda"`')
    path = _confined(tmp_path, expression)
    expect_input_error(lambda: load_sequence(path), path, match="a variable expression")


def test_a_missing_usd_core_names_the_extra(cloth, tmp_path, monkeypatch):
    path = tmp_path / "c.usda"
    save_sequence(cloth, path)
    monkeypatch.setitem(sys.modules, "pxr.Usd", None)  # import pxr.Usd now fails
    with pytest.raises(DependencyError, match=r"pip install 'tuckercodec\[usd\]'"):
        load_sequence(path)
    with pytest.raises(DependencyError, match=r"tuckercodec\[usd\]"):
        save_sequence(cloth, tmp_path / "d.usdc")
    assert not (tmp_path / "d.usdc").exists()


# ------------------------------------------------------------------------------------------
# the face lists of tuckercodec/io/common/polygons.py


def test_polygon_lists_and_the_face_table_convert_both_ways():
    faces = np.array([[0, 1, 2, 3, 4], [4, 3, 2, -1, -1], [5, 6, 7, 8, -1]])
    counts, indices = polygons_from_faces(faces)
    assert counts.tolist() == [5, 3, 4] and indices.dtype == np.int32
    assert indices.tolist() == [0, 1, 2, 3, 4, 4, 3, 2, 5, 6, 7, 8]
    assert np.array_equal(faces_from_polygons(counts, indices, 9), faces)
    reversed_faces = reverse_winding(faces)
    assert reversed_faces.tolist() == [[4, 3, 2, 1, 0], [2, 3, 4, -1, -1], [8, 7, 6, 5, -1]]
    assert np.array_equal(reverse_winding(reversed_faces), faces)
    assert faces_from_polygons([], [], 3).shape == (0, 3)


def test_a_huge_polygon_among_triangles_is_refused_before_padding():
    counts = np.array([3] * 2_000_000 + [100_000])
    indices = np.zeros(int(counts.sum()), dtype=np.int32)
    with pytest.raises(InputError, match="face 2000000 has 100000 corners: padding"):
        faces_from_polygons(counts, indices, 3)
    with pytest.raises(InputError, match="face 0 has 99 corners but there are only 3"):
        faces_from_polygons(np.array([99], dtype=np.uint64), [0, 1, 2], 3)


# ------------------------------------------------------------------------------------------
# the command line


def test_the_cli_converts_to_usd_and_decodes_to_usd(tmp_path, capsys):
    usda, packed, usdc = tmp_path / "out.usda", tmp_path / "x.tkc", tmp_path / "y.usdc"
    assert main(["convert", "sample", str(usda)]) == 0
    # the sample's frame names are all USD loses
    assert "not carried by the output's format: frame names\n" in capsys.readouterr().out
    assert main(["encode", str(usda), "-o", str(packed), "--kg", "0.5"]) == 0
    assert main(["decode", str(packed), "-o", str(usdc)]) == 0
    assert load_sequence(usdc).frame_count == load_sequence(usda).frame_count == 60
    path = make_stage(tmp_path / "two.usda", {"/World/a": 2, "/World/b": 3})
    assert main(["convert", str(path), str(tmp_path / "b.npz"), "--prim", "/World/b"]) == 0
    assert load_sequence(tmp_path / "b.npz").frame_count == 3
    assert main(["convert", str(path), str(tmp_path / "c.npz")]) == 4
    assert "--prim" in capsys.readouterr().err
