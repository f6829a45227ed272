"""Reading and writing meshes and sequences: OBJ, folders, globs, .npz, and the errors on bad input."""

from __future__ import annotations

import random
from pathlib import Path

import numpy as np
import pytest
from conftest import shared_file

from tuckercodec import InputError, MeshSequence
from tuckercodec.io.obj import (
    _parse_careful,
    _parse_fast,
    _read_text,
    read_obj,
    read_obj_frame,
    write_obj,
)
from tuckercodec.io import load_sequence, natural_sort_key, save_sequence

CUBE_VERTICES = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.float64,
)


def write_text(path: Path, text: str | bytes) -> Path:
    """Write a test file verbatim (no newline translation)."""
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


def obj_text(vertices: np.ndarray, faces: list[list[int]]) -> str:
    """A minimal OBJ text: ``v`` lines, then 1-based ``f`` lines."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices).tolist()]
    lines += ["f " + " ".join(str(i) for i in face) for face in faces]
    return "\n".join(lines) + "\n"


def parse_both_ways(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Read with the careful parser, and check the fast one agrees (or declines)."""
    data = _read_text(path)
    careful = _parse_careful(data, path)
    fast = _parse_fast(data, None)
    if fast is not None:
        np.testing.assert_array_equal(fast.vertices, careful.vertices)
        np.testing.assert_array_equal(fast.faces, careful.faces)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, careful.vertices)
    np.testing.assert_array_equal(faces, careful.faces)
    return vertices, faces


# ------------------------------------------------------------------------------------------
# OBJ reading and writing


def test_write_read_round_trip_is_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    vertices = rng.standard_normal((500, 3)) * 10.0 ** rng.integers(-12, 12, (500, 3))
    faces = rng.integers(0, 500, (300, 3))
    path = tmp_path / "mesh.obj"
    write_obj(path, vertices, faces)
    read_vertices, read_faces = parse_both_ways(path)
    assert read_vertices.dtype == np.float64 and read_faces.dtype == np.int64
    np.testing.assert_array_equal(read_vertices, vertices)  # bit-exact, same order
    np.testing.assert_array_equal(read_faces, faces)


def test_write_with_precision(tmp_path: Path) -> None:
    path = tmp_path / "mesh.obj"
    write_obj(path, [[1 / 3, 2 / 3, 1.0]], np.zeros((0, 3), dtype=int), precision=4)
    assert path.read_text().splitlines()[0] == "v 0.3333 0.6667 1"
    with pytest.raises(ValueError, match="precision"):
        write_obj(tmp_path / "other.obj", [[0.0, 0.0, 0.0]], [], precision=0)


def test_texture_and_normal_lines_and_slashed_corners(tmp_path: Path) -> None:
    path = write_text(
        tmp_path / "textured.obj",
        "mtllib cube.mtl\no cube\n"
        + "".join(f"v {x} {y} {z}\nvt 0.5 0.5\nvn 0 0 1\n" for x, y, z in CUBE_VERTICES[:4])
        + "vp 0.1 0.2\ng side\nusemtl red\ns off\n"
        + "f 1/1/1 2/2/2 3/3/3\nf 1//1 3//3 4//4\nf 4/4 3/3 2/2\nl 1 2\n",
    )
    vertices, faces = parse_both_ways(path)
    np.testing.assert_array_equal(vertices, CUBE_VERTICES[:4])
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [3, 2, 1]])


def test_mixed_triangles_and_quads_are_padded(tmp_path: Path) -> None:
    faces = [[1, 2, 3, 4], [5, 6, 7], [1, 2, 6, 5], [8, 7, 3]]
    path = write_text(tmp_path / "mixed.obj", obj_text(CUBE_VERTICES, faces))
    _, read_faces = parse_both_ways(path)
    expected = [[0, 1, 2, 3], [4, 5, 6, -1], [0, 1, 5, 4], [7, 6, 2, -1]]
    np.testing.assert_array_equal(read_faces, expected)

    again = tmp_path / "again.obj"
    write_obj(again, CUBE_VERTICES, read_faces)
    assert "f 5 6 7\n" in again.read_text()  # the padding is not written
    np.testing.assert_array_equal(read_obj(again)[1], expected)


def test_crlf_cr_comments_and_blank_lines(tmp_path: Path) -> None:
    text = "# a comment\n\nv 0 0 0\nv 1 0 0  # trailing comment\n\n   v 0 1 0\nf 1 2 3\n# end"
    for name, line_end in [("lf", "\n"), ("crlf", "\r\n"), ("cr", "\r")]:
        path = write_text(tmp_path / f"{name}.obj", text.replace("\n", line_end))
        vertices, faces = parse_both_ways(path)
        np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_crlf_tidy_file_is_exact(tmp_path: Path) -> None:
    path = write_text(
        tmp_path / "crlf.obj", obj_text(CUBE_VERTICES, [[1, 2, 3]]).replace("\n", "\r\n")
    )
    assert _parse_fast(_read_text(path), None) is not None
    np.testing.assert_array_equal(read_obj(path)[0], CUBE_VERTICES)


def test_negative_indices_count_back_from_their_line(tmp_path: Path) -> None:
    path = write_text(
        tmp_path / "relative.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf -4/-4 -2 -1\nf 1 -3 4\n",
    )
    _, faces = parse_both_ways(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [0, 1, 3]])


def test_vertex_weight_and_colour_are_ignored(tmp_path: Path) -> None:
    for extra in ["1.0", "0.5 0.25 1", "0.5 0.25 1 1"]:
        path = write_text(
            tmp_path / "extra.obj", f"v 1 2 3 {extra}\nv 4 5 6 {extra}\nv 7 8 9 {extra}\n"
        )
        vertices, _ = parse_both_ways(path)
        np.testing.assert_array_equal(vertices, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


def test_line_continuation(tmp_path: Path) -> None:
    path = write_text(
        tmp_path / "continued.obj", "v 0 0 0\nv 1 0 \\\n 0\nv 0 1 0\nf 1 2 \\\n3\nv 9 9 9\n"
    )
    vertices, faces = parse_both_ways(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [9, 9, 9]])
    np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_utf8_bom_and_tabs(tmp_path: Path) -> None:
    path = write_text(tmp_path / "bom.obj", b"\xef\xbb\xbfv\t0 0 0\nv 1\t0 0\nv 0 1 0\nf 1 2 3\n")
    vertices, _ = parse_both_ways(path)
    assert vertices.shape == (3, 3)


@pytest.mark.parametrize(
    "text",
    [
        "v 0 0 0\nvt 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1/1/1 2//2 3/3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\nf 1 2 3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 1 1 0\nf -1 1 2\n",
        "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n",
        "v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n",
    ],
)
def test_common_variants_take_the_fast_path(tmp_path: Path, text: str) -> None:
    path = write_text(tmp_path / "tidy.obj", text)
    assert _parse_fast(_read_text(path), None) is not None
    parse_both_ways(path)


def random_obj_line(rng: random.Random) -> str:
    """A random, often broken, OBJ line."""
    numbers = ["0", "1", "-1.5", "2e-3", ".5", "5.", "+3", "1E2", "nan", "x", "1e999", "1_0"]
    corners = ["1", "2", "3", "4", "-1", "-4", "0", "6", "+2", "1/1", "2//3", "3/2/1", "/1", "a"]
    kind = rng.random()
    if kind < 0.35:
        return "v " + " ".join(rng.choice(numbers) for _ in range(rng.choice([3, 3, 2, 4, 6, 7])))
    if kind < 0.65:
        return "f " + " ".join(rng.choice(corners) for _ in range(rng.choice([3, 3, 4, 5, 2])))
    others = ["", "# c", "vt 0 0", "o a", "  v 1 2 3", "v\t1 2 3", "v", "f", "v 1 2 \\",
              "f 1 2 3 # x", "f 1/2/#3 2 3", "v 1 2 3 #x", "\\#"]  # fmt: skip
    return rng.choice(others)


def test_fast_parser_never_disagrees_with_the_careful_one() -> None:
    rng = random.Random(7)
    path = Path("random.obj")
    accepted = 0
    for _ in range(1000):
        lines = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 1 1 1"]
        lines += [random_obj_line(rng) for _ in range(rng.randint(1, 4))]
        data = "\n".join(lines).encode()
        fast = _parse_fast(data, None)
        if fast is None:
            continue
        accepted += 1
        careful = _parse_careful(data, path)  # raises if the fast parser accepted a bad file
        np.testing.assert_array_equal(fast.vertices, careful.vertices)
        np.testing.assert_array_equal(fast.faces, careful.faces)
    assert accepted > 50  # the comparison was made often enough to mean something


def test_next_frame_reuses_identical_faces(tmp_path: Path) -> None:
    first, second = write_frames(tmp_path, 2)
    reference = read_obj_frame(first)
    frame = read_obj_frame(second, reference)
    assert frame.faces is reference.faces  # compared as bytes, not parsed again
    relative = write_text(tmp_path / "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n")
    assert read_obj_frame(relative).face_text is None  # negative indices depend on position


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("v 0 0 0\nv 1 0\nv 0 1 0\n", 2, "x y z"),
        ("v 0 0 0\nv 1 zero 0\n", 2, "not a number"),
        ("v 0 0 0\nv 1_0 0 0\n", 2, "not a number"),
        ("v 0 0 0\nv\n", 2, "x y z"),
        ("v 0 0 0\nv 1 nan 0\n", 2, "non-finite"),
        ("v 0 0 0\nv 1 0 inf\n", 2, "non-finite"),
        ("v 0 0 0\nv 1 0 1e999\n", 2, "non-finite"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "only 3 vertices"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4, "0 is invalid"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n", 5, "at least 3 corners"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", 4, "not a vertex index"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.0\n", 4, "not a vertex index"),
        ("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", 3, "counts back"),
        ("# only a comment\nvt 0 0\n", None, "no vertices"),
        ("", None, "empty"),
        ("  \n\n", None, "empty"),
        (b"v 0 0 0\n\x00\x01\x02binary", 2, "binary"),
        (b"v 0 0 0\nv 1 0 0\n\xff\xfe\x89PNG", 3, "UTF-8"),
    ],
)
def test_bad_obj_names_file_and_line(
    tmp_path: Path, text: str | bytes, line: int | None, message: str
) -> None:
    path = write_text(tmp_path / "bad.obj", text)
    with pytest.raises(InputError, match=message) as caught:
        read_obj(path)
    error = caught.value
    assert error.path == str(path)
    assert error.line == line
    where = f"{path}:{line}" if line is not None else str(path)
    assert str(error).startswith(where + ":")


def test_missing_obj_file_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot read"):
        read_obj(tmp_path / "nothing.obj")


def test_a_single_bad_file_has_no_frame_number(tmp_path: Path) -> None:
    path = write_text(tmp_path / "one.obj", "v 0 0 0\nf 1 2\n")
    with pytest.raises(InputError) as caught:
        load_sequence(path)
    assert caught.value.frame is None and str(caught.value).startswith(f"{path}:2: ")


def test_write_obj_refuses_to_overwrite_and_leaves_no_temporary_files(tmp_path: Path) -> None:
    path = tmp_path / "mesh.obj"
    write_obj(path, CUBE_VERTICES, [[0, 1, 2]])
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match="mesh.obj"):
        write_obj(path, CUBE_VERTICES * 2, [[0, 1, 2]])
    assert path.read_bytes() == before
    with pytest.raises(ValueError, match="finite"):
        write_obj(path, np.full((3, 3), np.nan), [[0, 1, 2]], overwrite=True)
    assert path.read_bytes() == before
    write_obj(path, CUBE_VERTICES * 2, [[0, 1, 2]], overwrite=True)
    np.testing.assert_array_equal(read_obj(path)[0], CUBE_VERTICES * 2)
    assert [p.name for p in tmp_path.iterdir()] == ["mesh.obj"]


# ------------------------------------------------------------------------------------------
# sequences


def write_frames(folder: Path, count: int, name: str = "frame{}.obj") -> list[Path]:
    """``count`` OBJ frames of a moving cube (vertex x shifted by the frame number)."""
    folder.mkdir(parents=True, exist_ok=True)
    faces = [[1, 2, 3, 4], [5, 6, 7, 8], [1, 2, 6]]
    paths = []
    for frame in range(count):
        path = folder / name.format(frame)
        write_text(path, obj_text(CUBE_VERTICES + [frame, 0, 0], faces))
        paths.append(path)
    return paths


def test_natural_sort_key() -> None:
    names = ["f10.obj", "f2.obj", "F1.obj", "f01.obj", "g.obj", "f2b.obj"]
    assert sorted(names, key=natural_sort_key) == [
        "F1.obj",
        "f01.obj",
        "f2.obj",
        "f2b.obj",
        "f10.obj",
        "g.obj",
    ]


def test_folder_is_read_in_natural_order(tmp_path: Path) -> None:
    write_frames(tmp_path / "seq", 12, name="f{}.obj")
    (tmp_path / "seq" / "notes.txt").write_text("not a frame")
    write_text(tmp_path / "seq" / "._f1.obj", b"\x00\x05\x16\x07 macOS metadata")  # hidden
    seq = load_sequence(tmp_path / "seq", progress=False)
    assert seq.frame_names[:4] == ["f0.obj", "f1.obj", "f2.obj", "f3.obj"]
    assert seq.frame_names[-1] == "f11.obj"
    np.testing.assert_array_equal(seq.vertices[:, 0, 0], np.arange(12))  # f2 before f10
    assert seq.faces.shape == (3, 4) and seq.faces[2, 3] == -1


def test_glob_list_and_upper_case_suffix(tmp_path: Path) -> None:
    paths = write_frames(tmp_path, 3, name="m{}.OBJ")
    by_glob = load_sequence(str(tmp_path / "m*.OBJ"), progress=False)
    by_folder = load_sequence(tmp_path, progress=False)
    by_list = load_sequence([paths[2], paths[0]], progress=False)  # a list keeps its order
    np.testing.assert_array_equal(by_glob.vertices, by_folder.vertices)
    assert by_list.frame_names == ["m2.OBJ", "m0.OBJ"]
    single = load_sequence(paths[1], progress=False)
    assert single.frame_count == 1 and single.frame_names == ["m1.OBJ"]


def test_frame_with_different_vertex_count(tmp_path: Path) -> None:
    paths = write_frames(tmp_path, 3)
    write_text(paths[2], obj_text(np.vstack([CUBE_VERTICES, [[5, 5, 5]]]), [[1, 2, 3]]))
    with pytest.raises(InputError, match="has 9 vertices but the first frame has 8") as caught:
        load_sequence(tmp_path, progress=False)
    assert caught.value.path == str(paths[2])
    assert caught.value.frame == 2
    assert caught.value.line == 9  # the first vertex too many
    assert f"{paths[2]}:9, frame 2:" in str(caught.value)


def test_frame_with_different_faces(tmp_path: Path) -> None:
    paths = write_frames(tmp_path, 3)
    text = paths[1].read_text().replace("f 5 6 7 8", "f 5 6 8 7")
    write_text(paths[1], text)
    with pytest.raises(InputError, match="face 2 is f 5 6 8 7") as caught:
        load_sequence(tmp_path, progress=False)
    assert (caught.value.path, caught.value.frame, caught.value.line) == (str(paths[1]), 1, 10)


def test_same_faces_written_differently_are_accepted(tmp_path: Path) -> None:
    paths = write_frames(tmp_path, 2)
    text = paths[1].read_text().replace("f 1 2 3 4", "f 1/1 2/2 3/3 -5/4")
    write_text(paths[1], text)
    seq = load_sequence(tmp_path, progress=False)
    assert seq.frame_count == 2


def test_a_bad_frame_names_its_frame(tmp_path: Path) -> None:
    paths = write_frames(tmp_path, 4)
    lines = paths[3].read_text().splitlines()
    lines[7] = "v 0 1 nan"
    write_text(paths[3], "\n".join(lines))
    with pytest.raises(InputError, match="non-finite") as caught:
        load_sequence(tmp_path, progress=False)
    assert (caught.value.path, caught.value.frame, caught.value.line) == (str(paths[3]), 3, 8)


def test_nothing_to_read(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no .obj") as caught:
        load_sequence(tmp_path / "empty")
    assert caught.value.path == str(tmp_path / "empty")
    with pytest.raises(InputError, match="no such file or folder") as caught:
        load_sequence(tmp_path / "missing")
    assert caught.value.path == str(tmp_path / "missing")
    with pytest.raises(InputError, match="matches no files"):
        load_sequence(str(tmp_path / "*.obj"))
    with pytest.raises(InputError, match="empty"):
        load_sequence([])


def test_other_mesh_formats_via_trimesh(tmp_path: Path) -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    text = "OFF\n4 2 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in CUBE_VERTICES[:4].tolist())
    text += "".join("3 " + " ".join(map(str, face)) + "\n" for face in faces.tolist())
    path = write_text(tmp_path / "quad.off", text)
    seq = load_sequence(path, progress=False)
    np.testing.assert_array_equal(seq.vertices[0], CUBE_VERTICES[:4])
    np.testing.assert_array_equal(seq.faces, faces)
    broken = write_text(tmp_path / "broken.ply", b"ply\nformat nonsense\n")
    with pytest.raises(InputError) as caught:
        load_sequence(broken)
    assert caught.value.path == str(broken)


# ------------------------------------------------------------------------------------------
# .npz


def test_npz_round_trip(tmp_path: Path) -> None:
    seq = MeshSequence(
        np.random.default_rng(0).standard_normal((4, 8, 3)),
        np.array([[0, 1, 2, 3], [4, 5, 6, -1]]),
        frame_names=["a", "b", "c", "d"],
        frame_rate=25.0,
    )
    path = tmp_path / "seq.npz"
    save_sequence(seq, path)
    again = load_sequence(path)
    np.testing.assert_array_equal(again.vertices, seq.vertices)
    np.testing.assert_array_equal(again.faces, seq.faces)
    assert again.frame_names == seq.frame_names and again.frame_rate == 25.0
    with pytest.raises(FileExistsError, match="seq.npz"):
        save_sequence(seq, path)
    save_sequence(seq, path, overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["seq.npz"]


def test_npz_single_frame_and_no_faces(tmp_path: Path) -> None:
    path = tmp_path / "one.npz"
    np.savez(path, V=CUBE_VERTICES.astype(np.float32))
    seq = load_sequence(path)
    assert (seq.frame_count, seq.vertex_count, seq.faces.shape) == (1, 8, (0, 3))


@pytest.mark.parametrize(
    ("arrays", "key", "message"),
    [
        ({"X": np.zeros((2, 3, 3))}, "'V'", "missing key"),
        ({"V": np.array([["a", "b", "c"]])}, "'V'", "real numbers"),
        ({"V": np.array([[[0, 0, 0]]], dtype=object)}, "'V'", "Python objects"),
        ({"V": np.zeros((2, 3, 2))}, "'V'", "shape"),
        ({"V": np.full((2, 3, 3), np.nan)}, "'V'", "non-finite"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([[0.0, 1.0, 2.0]])}, "'F'", "integer"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([0, 1, 2])}, "'F'", "shape"),
        ({"V": np.zeros((2, 3, 3)), "F": np.array([[1, 2, 3]])}, "'F'", "1-based"),
        ({"V": np.zeros((2, 3, 3)), "frame_files": np.array(["a"])}, "'frame_files'", "2 strings"),
        ({"V": np.zeros((2, 3, 3)), "frame_rate": np.array(-1.0)}, "'frame_rate'", "positive"),
    ],
)
def test_bad_npz_names_file_and_key(tmp_path: Path, arrays: dict, key: str, message: str) -> None:
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(InputError, match=message) as caught:
        load_sequence(path)
    assert caught.value.path == str(path)
    assert key in str(caught.value)


def test_not_an_npz(tmp_path: Path) -> None:
    path = write_text(tmp_path / "fake.npz", b"this is not a zip archive")
    with pytest.raises(InputError, match="npz") as caught:
        load_sequence(path)
    assert caught.value.path == str(path)


# ------------------------------------------------------------------------------------------
# saving folders of OBJ files


def test_save_folder_round_trip_refuses_overwrite(tmp_path: Path) -> None:
    write_frames(tmp_path / "in", 3, name="f{}.obj")
    seq = load_sequence(tmp_path / "in", progress=False)
    out = tmp_path / "out"
    save_sequence(seq, out)
    again = load_sequence(out, progress=False)
    np.testing.assert_array_equal(again.vertices, seq.vertices)
    np.testing.assert_array_equal(again.faces, seq.faces)
    assert again.frame_names == seq.frame_names

    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "f1.obj").unlink()  # one missing target: still nothing may be written
    with pytest.raises(FileExistsError, match="f0.obj"):
        save_sequence(seq, out)
    assert sorted(p.name for p in out.iterdir()) == ["f0.obj", "f2.obj"]
    save_sequence(seq, out, overwrite=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # and no temporary files


def test_saved_names_are_safe_unique_and_keep_the_order(tmp_path: Path) -> None:
    seq = MeshSequence(
        np.zeros((4, 3, 3)) + np.arange(4)[:, None, None],
        np.array([[0, 1, 2]]),
        frame_names=["z/walk.ply", "walk.obj", "a b", ""],
    )
    save_sequence(seq, tmp_path / "out", precision=6)
    names = sorted((p.name for p in (tmp_path / "out").iterdir()), key=natural_sort_key)
    assert names == ["00000_walk.obj", "00001_walk_2.obj", "00002_a_b.obj", "00003_frame_00003.obj"]
    again = load_sequence(tmp_path / "out", progress=False)
    np.testing.assert_array_equal(again.vertices, seq.vertices)


# ------------------------------------------------------------------------------------------
# the real sequences of ../shared/data


def reference_vertices(path: Path) -> np.ndarray:
    """The ``v`` lines of an OBJ file, parsed the plain Python way."""
    rows = []
    with path.open() as stream:
        for line in stream:
            parts = line.split()
            if parts and parts[0] == "v":
                rows.append([float(value) for value in parts[1:4]])
    return np.array(rows)


@pytest.mark.slow
def test_horse_gallop_folder() -> None:
    folder = shared_file("horse-gallop")
    seq = load_sequence(folder, progress=False)
    assert (seq.frame_count, seq.vertex_count, len(seq.faces)) == (48, 8431, 16843)
    assert seq.frame_names[0] == "horse-gallop-01.obj"
    assert seq.frame_names[-1] == "horse-gallop-48.obj"
    np.testing.assert_array_equal(seq.vertices[6], reference_vertices(folder / seq.frame_names[6]))


@pytest.mark.parametrize(
    ("name", "shape"),
    [
        ("cloth-vellum.npz", (60, 3101, 5912)),
        ("samba.npz", (175, 9971, 19938)),
        ("chicken.npz", (400, 3030, 5664)),
    ],
)
def test_shared_npz_sequences(name: str, shape: tuple[int, int, int]) -> None:
    path = shared_file(name)
    seq = load_sequence(path)
    assert (seq.frame_count, seq.vertex_count, len(seq.faces)) == shape
    with np.load(path, allow_pickle=False) as data:
        np.testing.assert_array_equal(seq.vertices, data["V"])
