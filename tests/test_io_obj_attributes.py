"""OBJ's texture coordinates, normals, materials and groups (tuckercodec/io/obj_attributes.py,
obj_attributes_fast.py, obj_attribute_writer.py): read into indexed corner attributes and face
sets, the fast path against the careful walk, errors that name the file and line, a later frame
checked against the first, bit-exact round trips, what OBJ cannot keep, trimesh reading what we
write, and the real horse gallop read as before."""

from __future__ import annotations

import random
import shutil
from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import expect_input_error, write_file
from tests.support.sequences import shared_file
from tuckercodec import MeshSequence
from tuckercodec.cli import main
from tuckercodec.io import load_sequence, save_sequence
from tuckercodec.io.obj import read_obj, read_obj_frame_text
from tuckercodec.io.obj_attribute_writer import cannot_keep
from tuckercodec.io.obj_attributes import read_extras_careful
from tuckercodec.io.obj_attributes_fast import read_extras_fast
from tuckercodec.model.attributes import Attribute, FaceSet, Field
from tuckercodec.model.normals import recomputed_normals

SQUARE = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
# vt rows 1-4 (row 4 unused), one vn; materials and groups; a negative vt and vn index
ATTRIBUTED = (
    SQUARE + "vt 0 0\nvt 1 0\nvt 0 1\nvt 9 9\nvn 0 0 1\nusemtl red\ng a b\n"
    "f 1/1/1 2/2/1 3/3/1\ng b\nusemtl\nf 2/-3/-1 4/2/1 3/3/1\nusemtl red\nf 1/1/1 4/2/1 3/3/1\n"
)


def read_one(path: Path) -> MeshSequence:
    return load_sequence(path, progress=False)


def face_sets_by_name(seq: MeshSequence) -> dict[tuple[str, str], np.ndarray]:
    return {(s.family, s.name): s.faces for s in seq.face_sets}


def test_vt_vn_usemtl_and_g_are_read(tmp_path: Path) -> None:
    seq = read_one(write_file(tmp_path / "a.obj", ATTRIBUTED))
    uv, normal = seq.attributes
    assert (uv.name, uv.domain, uv.role, normal.name, normal.role) == (
        "uv",
        "corner",
        "uv",
        "normal",
        "normal",
    )
    np.testing.assert_array_equal(uv.values, [[0, 0], [1, 0], [0, 1], [9, 9]])  # unused row kept
    assert uv.values.dtype == np.float64
    np.testing.assert_array_equal(uv.indices, [0, 1, 2, 1, 1, 2, 0, 1, 2])  # -3 of 4: row 1
    np.testing.assert_array_equal(normal.indices, np.zeros(9))
    sets = face_sets_by_name(seq)
    assert list(sets) == [("materialBind", "red"), ("group", "a"), ("group", "b")]
    np.testing.assert_array_equal(sets["materialBind", "red"], [0, 2])  # face 1: bare usemtl
    np.testing.assert_array_equal(sets["group", "a"], [0])
    np.testing.assert_array_equal(sets["group", "b"], [0, 1, 2])


def test_a_material_name_is_the_rest_of_its_line_and_a_vt_may_have_one_or_three_numbers(
    tmp_path: Path,
) -> None:
    text = SQUARE + "vt 0.5\nvt 1 0.25 7\nusemtl  my   mat # a comment\nf 1/1 2/2 3/1\n"
    seq = read_one(write_file(tmp_path / "a.obj", text))
    np.testing.assert_array_equal(seq.attributes[0].values, [[0.5, 0.0], [1.0, 0.25]])
    assert [s.name for s in seq.face_sets] == ["my mat"]


def test_a_file_without_these_statements_has_no_attributes(tmp_path: Path) -> None:
    seq = read_one(write_file(tmp_path / "a.obj", SQUARE + "vt 0 0\nvn 0 0 1\nf 1 2 3\n"))
    assert seq.attributes == [] and seq.face_sets == []  # vt and vn that no face uses


TIDY_TEXTS = [
    ATTRIBUTED,
    SQUARE + "vt 0 0\nvt 1 0 0\nf 1/1 2/2 3/1 4/2\n",  # vt of 2 and 3 numbers: careful
    SQUARE + "vn 0 0 1\nvn 1 0 0\nf 1//1 2//2 3//-1\nf 2//2 4//1 3//1\n",
    SQUARE + "vt .5 1e-3\nvt +1 -2.5E2\ng x\nf 1/1 2/2 3/1\ng\nf 2/2 4/1 3/2\n",
    SQUARE + "vt 0 0\n  vt 1 1\nf 1/1 2/2 3/1\n",  # indented: the careful way
    SQUARE + "vt 0 0\nf 1/1 2/1 3/1 # comment\n",
    SQUARE + "vt 0 0\nf 1/1 2/1 3/+1\n",
]


@pytest.mark.parametrize("text", TIDY_TEXTS)
def test_the_fast_path_reads_what_the_careful_walk_reads(tmp_path: Path, text: str) -> None:
    path = write_file(tmp_path / "a.obj", text)
    frame, data = read_obj_frame_text(path)
    careful = read_extras_careful(data, path, frame.faces)
    fast = read_extras_fast(data, frame.faces)
    if fast is None:
        return  # declined: the careful walk reads it
    assert fast.face_lines == careful.face_lines
    assert (fast.materials, fast.groups) == (careful.materials, careful.groups)
    for keyword in ("vt", "vn"):
        np.testing.assert_array_equal(fast.tables[keyword], careful.tables[keyword])
        first, second = fast.indices[keyword], careful.indices[keyword]
        assert (first is None) == (second is None)
        if first is not None:
            np.testing.assert_array_equal(first, second)


def test_the_fast_path_agrees_on_random_tidy_files(tmp_path: Path) -> None:
    """Random tables, indices (positive and negative), sets; the fast path must read them
    (nothing untidy in them) and agree."""
    generator = random.Random(5)
    for case in range(30):
        vertices, rows = generator.randint(3, 9), generator.randint(1, 6)
        lines = [f"v {generator.random()} 0 {k}" for k in range(vertices)]
        lines += [f"vt {generator.uniform(-2, 2)!r} {generator.random()!r}" for _ in range(rows)]
        for face in range(generator.randint(1, 8)):
            if generator.random() < 0.3:
                lines.append(generator.choice(["usemtl m1", "usemtl m2", "g a", "g a b", "g"]))
            corners = []
            for _ in range(generator.randint(3, 5)):
                t = generator.randint(1, rows)
                corners.append(f"{generator.randint(1, vertices)}/{-t if face % 2 else t}")
            lines.append("f " + " ".join(corners))
        path = write_file(tmp_path / f"{case}.obj", "\n".join(lines) + "\n")
        frame, data = read_obj_frame_text(path)
        fast = read_extras_fast(data, frame.faces)
        careful = read_extras_careful(data, path, frame.faces)
        assert fast is not None, lines
        np.testing.assert_array_equal(fast.tables["vt"], careful.tables["vt"])
        np.testing.assert_array_equal(fast.indices["vt"], careful.indices["vt"])
        assert (fast.materials, fast.groups) == (careful.materials, careful.groups)


@pytest.mark.parametrize(
    ("text", "line", "match"),
    [
        (SQUARE + "vt 0 0\nf 1/1 2/1 3/7\n", 6, "texture coordinate 7, but the file has only 1"),
        (SQUARE + "vt 0 0\nf 1/1 2/0 3/1\n", 6, "0 is invalid"),
        (SQUARE + "vt 0 0\nf 1/1 2/-2 3/1\n", 6, "counts back past the first texture"),
        (SQUARE + "vn 0 0 1\nf 1//1 2//1 3//4\n", 6, "normal 4, but the file has only 1"),
        (SQUARE + "vt 0 0\nf 1/x 2/1 3/1\n", 6, "no valid texture coordinate index"),
        (SQUARE + "vt 0 0\nf 1/1/1/1 2/1 3/1\n", 6, "more than vertex/texture/normal"),
        (SQUARE + "vt 0 nan\nf 1/1 2/1 3/1\n", 5, "non-finite texture coordinate"),
        (SQUARE + "vt\nf 1/1 2/1 3/1\n", 5, "a 'vt' line needs u"),
        (SQUARE + "vn 0 1\nf 1//1 2//1 3//1\n", 5, "a 'vn' line needs x y z"),
        (SQUARE + "g " + "x" * 300 + "\nf 1 2 3\n", 5, "longer than 255 bytes"),
    ],
)
def test_bad_attribute_statements_name_the_file_and_line(
    tmp_path: Path, text: str, line: int, match: str
) -> None:
    path = write_file(tmp_path / "bad.obj", text)
    expect_input_error(lambda: read_one(path), path, line=line, match=match)


@pytest.mark.parametrize(
    "text",
    [
        SQUARE + "vt 0 0\nf 1/1 2/1 3/1\nf 4 2 3\n",
        SQUARE + "vt 0 0\nf 1/1 2 3/1\n",
        SQUARE + "vn 0 0 1\nf 1 2 3\nf 4//1 2//1 3//1\n",
    ],
)
def test_a_table_only_some_corners_index_is_left_out_and_the_mesh_read(
    tmp_path: Path, text: str
) -> None:
    """Objects with and without UVs in one file (as exporters write them): the positions and
    faces are read as before; the table cannot be a value per corner, so it is not read."""
    path = write_file(tmp_path / "mixed.obj", text)
    sequence = read_one(path)
    assert sequence.attributes == []
    assert sequence.vertex_count == 4
    assert len(sequence.faces) == text.count("\nf ")


def write_frames(folder: Path, texts: list[str]) -> list[Path]:
    folder.mkdir()
    return [write_file(folder / f"f{n}.obj", text) for n, text in enumerate(texts)]


def test_a_later_frame_that_indexes_its_vt_otherwise_is_named(tmp_path: Path) -> None:
    second = ATTRIBUTED.replace("f 1/1/1 4/2/1 3/3/1", "f 1/1/1 4/3/1 3/3/1")
    paths = write_frames(tmp_path / "seq", [ATTRIBUTED, ATTRIBUTED, second])
    error = expect_input_error(
        lambda: read_one(tmp_path / "seq"), paths[2], line=17, frame=2, match="uses texture"
    )
    assert "corner 8 (of face 3)" in error.reason and str(paths[0]) in error.reason


def test_later_frames_written_otherwise_with_the_same_indices_are_read(tmp_path: Path) -> None:
    """Negative indices in a later frame (its text differs, its indices do not); its own vn
    values differ: the sequence's normals are the first frame's."""
    second = ATTRIBUTED.replace("f 1/1/1 2/2/1 3/3/1", "f -4/-4/-1  2/2/1 3/3/1").replace(
        "vn 0 0 1", "vn 0 1 0"
    )
    write_frames(tmp_path / "seq", [ATTRIBUTED, second])
    seq = read_one(tmp_path / "seq")
    first = read_one(tmp_path / "seq" / "f0.obj")
    assert seq.frame_count == 2
    assert all(a.same_as(b) for a, b in zip(seq.attributes, first.attributes, strict=True))


def attributed_sequence(frames: int = 3, uv_dtype: type = np.float64) -> MeshSequence:
    """A cube of quads and triangles (polygons padded) whose corners carry an indexed UV
    table with an unused row, hard-edged normals (one row per face), two materials with
    a run in none between them, and overlapping groups."""
    generator = np.random.default_rng(3)
    cube = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        dtype=np.float64,
    )
    faces = np.array(
        [[3, 2, 1, 0], [4, 5, 6, 7], [1, 5, 4, -1], [1, 4, 0, -1], [2, 3, 7, 6], [2, 6, 5, 1]]
    )  # corner rotations as given (face 0 starts at vertex 3)
    vertices = np.stack(
        [cube * (1 + 0.1 * f) + generator.normal(0, 0.01, cube.shape) for f in range(frames)]
    )
    corners = int((faces >= 0).sum())
    uv_values: np.ndarray = np.vstack([generator.random((corners, 2)), [[np.pi, -1e-300]]]).astype(
        uv_dtype
    )
    uv_indices = generator.permutation(corners)
    normal_rows = np.repeat(np.arange(6), (faces >= 0).sum(axis=1))
    normals = recomputed_normals(
        cube, faces, Attribute("n", "corner", np.zeros((6, 3)), normal_rows, "normal")
    )
    return MeshSequence(
        vertices,
        faces,
        attributes=[
            Attribute("uv", "corner", uv_values, uv_indices, "uv"),
            Attribute("normal", "corner", normals, normal_rows, "normal"),
        ],
        face_sets=[
            FaceSet("steel", np.array([0, 1]), "materialBind"),
            FaceSet("rubber paint", np.array([4, 5]), "materialBind"),
            FaceSet("top", np.array([1, 2, 3]), "group"),
            FaceSet("sides", np.array([3, 4]), "group"),
        ],
    )


def test_a_sequence_round_trips_bit_for_bit(tmp_path: Path) -> None:
    seq = attributed_sequence()
    save_sequence(seq, tmp_path / "out", progress=False)
    back = read_one(tmp_path / "out")
    np.testing.assert_array_equal(back.faces, seq.faces)  # order and corner rotation kept
    np.testing.assert_array_equal(back.vertices, seq.vertices)
    assert len(back.attributes) == 2
    assert all(a.same_as(b) for a, b in zip(back.attributes, seq.attributes, strict=True))
    ours = face_sets_by_name(seq)
    theirs = face_sets_by_name(back)
    assert ours.keys() == theirs.keys()
    assert all(np.array_equal(ours[key], theirs[key]) for key in ours)
    assert cannot_keep(seq) == []
    frame_zero = (tmp_path / "out" / "frame_00000.obj").read_text()
    assert "\nusemtl\n" in frame_zero  # faces 2 and 3 have no material


def test_later_frames_get_normals_recomputed_from_their_positions(tmp_path: Path) -> None:
    seq = attributed_sequence()
    save_sequence(seq, tmp_path / "out", progress=False)
    normal = seq.attributes[1]
    for frame in (1, 2):
        read = read_one(tmp_path / "out" / f"frame_{frame:05d}.obj").attributes[1]
        expected = recomputed_normals(seq.vertices[frame], seq.faces, normal)
        np.testing.assert_array_equal(read.values, expected)
        np.testing.assert_array_equal(read.indices, normal.indices)
        assert not np.array_equal(read.values, normal.values)  # the frames moved apart


def test_float32_uvs_read_back_as_the_same_numbers(tmp_path: Path) -> None:
    seq = attributed_sequence(frames=1, uv_dtype=np.float32)
    save_sequence(seq, tmp_path / "out", progress=False)
    uv = read_one(tmp_path / "out").attributes[0]
    assert uv.values.dtype == np.float64
    np.testing.assert_array_equal(uv.values, seq.attributes[0].values.astype(np.float64))
    np.testing.assert_array_equal(uv.values.astype(np.float32), seq.attributes[0].values)


def test_a_vertex_uv_reads_back_as_corners_with_the_same_values(tmp_path: Path) -> None:
    base = attributed_sequence(frames=1)
    uv = Attribute("st", "vertex", np.arange(16, dtype=np.float64).reshape(8, 2) / 7, role="uv")
    seq = MeshSequence(base.vertices, base.faces, attributes=[uv])
    save_sequence(seq, tmp_path / "out", progress=False)
    back = read_one(tmp_path / "out").attributes[0]
    assert back.domain == "corner"
    np.testing.assert_array_equal(back.element_values(), uv.values[base.faces[base.faces >= 0]])


def test_what_obj_cannot_keep_is_listed_and_left_out(tmp_path: Path) -> None:
    base = attributed_sequence(frames=2)
    colour = Attribute("Cd", "vertex", np.zeros((8, 3), np.float32), role="color")
    second_uv = Attribute(
        "uv2", "corner", base.attributes[0].values, base.attributes[0].indices, "uv"
    )
    seq = MeshSequence(
        base.vertices,
        base.faces,
        attributes=[*base.attributes, colour, second_uv],
        face_sets=[
            *base.face_sets,
            FaceSet("tagged", np.array([0]), "subsets"),
            FaceSet("two words", np.array([0]), "group"),
            FaceSet("steel again", np.array([1, 2]), "materialBind"),
        ],
        fields=[Field("velocity", np.zeros((2, 8, 3)), role="velocity")],
    )
    assert cannot_keep(seq) == [
        "field 'velocity'",
        "color attribute 'Cd'",
        "a second uv attribute, 'uv2'",
        "face set 'tagged' of family 'subsets'",
        "face set 'two words' of family 'group' (a name OBJ cannot write)",
        "material 'steel again' on faces also in an earlier material (they keep that one)",
    ]
    save_sequence(seq, tmp_path / "out", progress=False)
    back = read_one(tmp_path / "out")
    assert [a.name for a in back.attributes] == ["uv", "normal"]
    assert {(s.family, s.name) for s in back.face_sets} == {
        ("materialBind", "steel"),
        ("materialBind", "rubber paint"),
        ("materialBind", "steel again"),  # face 2, in no earlier material
        ("group", "top"),
        ("group", "sides"),
    }


def test_convert_notes_what_the_output_cannot_keep(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    base = attributed_sequence(frames=2)
    seq = MeshSequence(
        base.vertices,
        base.faces,
        attributes=base.attributes,
        fields=[Field("velocity", np.zeros((2, 8, 3)), role="velocity")],
    )
    monkeypatch.setattr("tuckercodec.cli.convert.load_input", lambda source, args: seq)
    assert main(["convert", str(tmp_path / "in.npz"), str(tmp_path / "out")]) == 0
    assert "note: OBJ cannot keep field 'velocity'; dropped\n" in capsys.readouterr().err


def test_trimesh_reads_the_same_uv_at_every_corner(tmp_path: Path) -> None:
    """trimesh parses vt and the f lines itself and splits vertices where a vertex's corners
    have different UVs: at every corner of every triangle, its vertex and UV must be ours."""
    trimesh = pytest.importorskip("trimesh", reason="trimesh is needed to read the OBJ back")
    base = attributed_sequence(frames=1)
    uv = Attribute("uv", "vertex", np.random.default_rng(0).random((8, 2)), role="uv")
    seq = MeshSequence(base.vertices, base.triangles(), attributes=[uv])
    save_sequence(seq, tmp_path / "out", progress=False)
    mesh = trimesh.load(tmp_path / "out" / "frame_00000.obj", process=False, force="mesh")
    assert mesh.faces.shape == seq.faces.shape
    np.testing.assert_allclose(mesh.vertices[mesh.faces], seq.vertices[0][seq.faces])
    np.testing.assert_allclose(mesh.visual.uv[mesh.faces], uv.values[seq.faces])


def test_horse_gallop_reads_as_before_and_round_trips_with_a_uv_table(tmp_path: Path) -> None:
    folder = shared_file("horse-gallop")
    files = sorted(folder.glob("*.obj"))[:3]
    seq = load_sequence(files, progress=False)
    assert seq.attributes == [] and seq.face_sets == []
    for index, path in enumerate(files):
        vertices, faces = read_obj(path)
        np.testing.assert_array_equal(seq.vertices[index], vertices)
        np.testing.assert_array_equal(seq.faces, faces)
    corners = int((seq.faces >= 0).sum())
    uv = Attribute("uv", "corner", seq.vertices[0][:, :2].copy(), seq.faces[seq.faces >= 0], "uv")
    assert uv.element_count == corners
    with_uv = MeshSequence(
        seq.vertices,
        seq.faces,
        attributes=[uv],
        face_sets=[FaceSet("horse", np.arange(seq.faces.shape[0]), "materialBind")],
    )
    save_sequence(with_uv, tmp_path / "out", progress=False)
    back = load_sequence(tmp_path / "out", progress=False)
    np.testing.assert_array_equal(back.vertices, seq.vertices)
    np.testing.assert_array_equal(back.faces, seq.faces)
    assert back.attributes[0].same_as(uv) and back.face_sets[0].same_as(with_uv.face_sets[0])
    shutil.rmtree(tmp_path / "out")


def test_a_later_frame_s_own_vt_values_are_not_read(tmp_path: Path) -> None:
    """The sequence's UVs are the first frame's: a later frame whose f lines are the first's
    is not read for its vt (a bad row there goes unseen); read alone, it is refused."""
    good = ATTRIBUTED.replace("2/-3/-1", "2/2/1")  # no relative index: the same f text
    paths = write_frames(tmp_path / "seq", [good, good.replace("vt 9 9", "vt 9 x")])
    assert read_one(tmp_path / "seq").frame_count == 2
    expect_input_error(lambda: read_one(paths[1]), paths[1], line=8, match="not a number")
