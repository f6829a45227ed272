"""Wavefront OBJ, read and written (tuckercodec/io/obj.py): the statements that matter and those
that are read past, exact round trips, the fast parser against the careful one, and broken,
corrupt or crafted files.

A bad file ends in an :class:`InputError` that names the file and the line, quickly and in small
memory; never another exception type, a hang or a huge allocation. The property tests feed
random bytes and random mutations of a small valid file and accept only an InputError or a valid
mesh, the one the careful parser reads.
"""

from __future__ import annotations

import functools
import io
import random
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.support.compressed import deadline
from tests.support.inputs import (
    CUBE_VERTICES,
    OBJ_TOKENS,
    TRIANGLE,
    VALID_OBJ,
    expect_input_error,
    measure,
    obj_text,
    write_file,
)
from tests.support.properties import PROPERTY, mutations, report_examples, scratch_folder
from tuckercodec import InputError, MeshSequence
from tuckercodec.io import load_sequence
from tuckercodec.io import obj as objio
from tuckercodec.io.obj import (
    MAX_LINE_BYTES,
    _parse_careful,
    _parse_fast,
    _read_text,
    read_obj,
    write_obj,
)


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


def check_obj_result(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """What a successful OBJ read must be: finite (K, 3), valid -1-padded faces, and the same
    result as the careful (reference) parser."""
    assert vertices.dtype == np.float64 and vertices.ndim == 2 and vertices.shape[1] == 3
    assert len(vertices) >= 1 and np.isfinite(vertices).all()
    assert faces.dtype == np.int64 and faces.ndim == 2 and faces.shape[1] >= 3
    MeshSequence(vertices[np.newaxis], faces)  # its checks: indices in range, padding at the end
    careful = _parse_careful(_read_text(path), path)
    np.testing.assert_array_equal(vertices, careful.vertices)
    np.testing.assert_array_equal(faces, careful.faces)


# ------------------------------------------------------------------------------------------
# reading and writing


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
    write_obj(path, np.array([[1 / 3, 2 / 3, 1.0]]), np.zeros((0, 3), dtype=int), precision=4)
    assert path.read_text().splitlines()[0] == "v 0.3333 0.6667 1"
    with pytest.raises(ValueError, match="precision"):
        write_obj(tmp_path / "other.obj", np.zeros((1, 3)), np.zeros((0, 3), int), precision=0)


def test_write_obj_refuses_to_overwrite_and_leaves_no_temporary_files(tmp_path: Path) -> None:
    path = tmp_path / "mesh.obj"
    write_obj(path, CUBE_VERTICES, np.array([[0, 1, 2]]))
    before = path.read_bytes()
    with pytest.raises(FileExistsError, match=r"mesh\.obj"):
        write_obj(path, CUBE_VERTICES * 2, np.array([[0, 1, 2]]))
    assert path.read_bytes() == before
    with pytest.raises(ValueError, match="finite"):
        write_obj(path, np.full((3, 3), np.nan), np.array([[0, 1, 2]]), overwrite=True)
    assert path.read_bytes() == before
    write_obj(path, CUBE_VERTICES * 2, np.array([[0, 1, 2]]), overwrite=True)
    np.testing.assert_array_equal(read_obj(path)[0], CUBE_VERTICES * 2)
    assert [p.name for p in tmp_path.iterdir()] == ["mesh.obj"]


def test_texture_and_normal_lines_and_slashed_corners(tmp_path: Path) -> None:
    path = write_file(
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
    path = write_file(tmp_path / "mixed.obj", obj_text(CUBE_VERTICES, faces))
    _, read_faces = parse_both_ways(path)
    expected = [[0, 1, 2, 3], [4, 5, 6, -1], [0, 1, 5, 4], [7, 6, 2, -1]]
    np.testing.assert_array_equal(read_faces, expected)

    again = tmp_path / "again.obj"
    write_obj(again, CUBE_VERTICES, read_faces)
    assert "f 5 6 7\n" in again.read_text()  # the padding is not written
    np.testing.assert_array_equal(read_obj(again)[1], expected)


def test_mixed_polygon_sizes_are_padded(tmp_path: Path) -> None:
    text = TRIANGLE + "v 1 1 0\nv 2 2 0\nf 1 2 3\nf 1 2 3 4 5\nf 1 2 3 4\n"
    path = write_file(tmp_path / "mixed.obj", text)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2, -1, -1], [0, 1, 2, 3, 4], [0, 1, 2, 3, -1]])
    check_obj_result(path, vertices, faces)


@pytest.mark.parametrize(
    "face", ["f 1/2/3 2/3/1 3/1/2", "f 1//3 2//1 3//2", "f 1/2 2/3 3/1", "f 1/ 2/ 3/"]
)
def test_slashed_corner_forms(tmp_path: Path, face: str) -> None:
    path = write_file(tmp_path / "slashed.obj", TRIANGLE + "vt 0 0\nvt 1 0\nvt 0 1\n" + face + "\n")
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2]])
    check_obj_result(path, vertices, faces)


def test_negative_indices_count_back_from_their_line(tmp_path: Path) -> None:
    path = write_file(
        tmp_path / "relative.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf -4/-4 -2 -1\nf 1 -3 4\n",
    )
    _, faces = parse_both_ways(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [0, 1, 3]])


def test_negative_relative_indices_are_resolved_from_their_line(tmp_path: Path) -> None:
    text = (
        "v 0 0 0\nv 1 0 0\nv 1 1 0\n"
        "f -3 -2 -1\n"  # the three vertices so far: 1 2 3
        "v 0 1 0\nv 2 2 2\n"
        "f -1 -2 -5\n"  # now -1 is vertex 5: 5 4 1
        "f 1/1/1 -3/2/2 -1//3\n"  # slashed relative corners: 1 3 5
        "f -5 -4 -3 -2 -1\n"  # a pentagon of every vertex
    )
    path = write_file(tmp_path / "relative.obj", text)
    vertices, faces = read_obj(path)
    expected = [[0, 1, 2, -1, -1], [4, 3, 0, -1, -1], [0, 2, 4, -1, -1], [0, 1, 2, 3, 4]]
    np.testing.assert_array_equal(faces, expected)
    check_obj_result(path, vertices, faces)


def test_a_face_may_name_a_vertex_defined_further_down(tmp_path: Path) -> None:
    # documented in objio: positive indices are checked against the whole file's vertices
    path = write_file(tmp_path / "forward.obj", "f 1 2 3\n" + TRIANGLE)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, [[0, 1, 2]])
    check_obj_result(path, vertices, faces)


def test_vertex_weight_and_colour_are_ignored(tmp_path: Path) -> None:
    for extra in ["1.0", "0.5 0.25 1", "0.5 0.25 1 1"]:
        path = write_file(
            tmp_path / "extra.obj", f"v 1 2 3 {extra}\nv 4 5 6 {extra}\nv 7 8 9 {extra}\n"
        )
        vertices, _ = parse_both_ways(path)
        np.testing.assert_array_equal(vertices, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


@pytest.mark.parametrize(
    ("extra", "why"),
    [("1.0", "weight w"), ("0.5 0.25 1", "RGB colour"), ("0.5 0.25 1 1", "RGBA colour")],
)
def test_weight_and_colours_are_read_past(tmp_path: Path, extra: str, why: str) -> None:
    # Documented in objio: x y z are kept, a weight (4 numbers) or colour (6 or 7) is ignored.
    path = write_file(
        tmp_path / "extra.obj", f"v 1 2 3 {extra}\nv 4 5 6 {extra}\nv 7 8 9\nf 1 2 3\n"
    )
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    check_obj_result(path, vertices, faces)


def test_a_non_finite_weight_or_colour_is_ignored_like_any_other(tmp_path: Path) -> None:
    # ignored values are not used, so they need not be finite (but they must be numbers)
    path = write_file(tmp_path / "w.obj", "v 1 2 3 nan\nv 4 5 6 inf 0 0\nv 7 8 9\n")
    np.testing.assert_array_equal(read_obj(path)[0], [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


def test_crlf_cr_comments_and_blank_lines(tmp_path: Path) -> None:
    text = "# a comment\n\nv 0 0 0\nv 1 0 0  # trailing comment\n\n   v 0 1 0\nf 1 2 3\n# end"
    for name, line_end in [("lf", "\n"), ("crlf", "\r\n"), ("cr", "\r")]:
        path = write_file(tmp_path / f"{name}.obj", text.replace("\n", line_end))
        vertices, faces = parse_both_ways(path)
        np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_crlf_tidy_file_is_exact(tmp_path: Path) -> None:
    path = write_file(
        tmp_path / "crlf.obj", obj_text(CUBE_VERTICES, [[1, 2, 3]]).replace("\n", "\r\n")
    )
    assert _parse_fast(_read_text(path), None) is not None
    np.testing.assert_array_equal(read_obj(path)[0], CUBE_VERTICES)


@pytest.mark.parametrize("ending", ["\n", "\r\n", "\r", "mixed"])
def test_line_endings_and_error_lines(tmp_path: Path, ending: str) -> None:
    lines = ["# head", "v 0 0 0", "v 1 0 0", "", "v 0 1 0", "f 1 2 3"]
    if ending == "mixed":  # each kind once, and "\n\r" which is two line ends
        text = "# head\r\nv 0 0 0\rv 1 0 0\n\r\nv 0 1 0\nf 1 2 3\r"
    else:
        text = ending.join(lines) + ending
    path = write_file(tmp_path / "ends.obj", text)
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    check_obj_result(path, vertices, faces)
    # and the line number of an error counts every kind of line end the same way
    broken = write_file(tmp_path / "broken.obj", text.replace("f 1 2 3", "f 1 2 9"))
    expect_input_error(lambda: read_obj(broken), broken, line=6, match="vertex 9")


def test_line_continuation(tmp_path: Path) -> None:
    path = write_file(
        tmp_path / "continued.obj", "v 0 0 0\nv 1 0 \\\n 0\nv 0 1 0\nf 1 2 \\\n3\nv 9 9 9\n"
    )
    vertices, faces = parse_both_ways(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [9, 9, 9]])
    np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_line_continuation_is_supported(tmp_path: Path) -> None:
    path = write_file(tmp_path / "cont.obj", "v 0 0 \\\n0\nv 1 \\\r\n0 0\nv 0 1 0\nf 1 \\\n2 3\n")
    vertices, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(faces, [[0, 1, 2]])


def test_utf8_bom_and_tabs(tmp_path: Path) -> None:
    path = write_file(tmp_path / "bom.obj", b"\xef\xbb\xbfv\t0 0 0\nv 1\t0 0\nv 0 1 0\nf 1 2 3\n")
    vertices, _ = parse_both_ways(path)
    assert vertices.shape == (3, 3)


def test_non_ascii_utf8_in_comments_and_names_is_fine(tmp_path: Path) -> None:
    path = write_file(tmp_path / "utf8.obj", "# café ☕\no Über\n" + TRIANGLE + "g 頂点\nf 1 2 3\n")
    assert read_obj(path)[0].shape == (3, 3)


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
    path = write_file(tmp_path / "tidy.obj", text)
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


# ------------------------------------------------------------------------------------------
# bad files: one bad thing at a time, each with its file, line and message


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
    path = write_file(tmp_path / "bad.obj", text)
    with pytest.raises(InputError, match=message) as caught:
        read_obj(path)
    error = caught.value
    assert error.path == str(path)
    assert error.line == line
    where = f"{path}:{line}" if line is not None else str(path)
    assert str(error).startswith(where + ":")


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        # coordinates: too few, a count that is neither xyz, xyzw nor xyz+rgb(a), none at all
        ("v 0 0 0\nv 1 2\n", 2, r"needs x y z .* got 2 value"),
        ("v 0 0 0\nv 1 2 3 4 5\n", 2, "got 5 value"),
        ("v 1 2 3 4 5 6 7 8\n", 1, "got 8 value"),
        ("v\n", 1, "got 0 value"),
        # not numbers
        ("v 1 two 3\n", 1, "not a number: 'two'"),
        ("v 1 0x10 3\n", 1, "not a number: '0x10'"),
        ("v 1 +-inf 3\n", 1, r"not a number: '\+-inf'"),  # float() takes one sign
        ("v 1,5 2 3\n", 1, "not a number: '1,5'"),
        ("v 1 2 3,\n", 1, "not a number: '3,'"),
        ("v 1_0 2 3\n", 1, "not a number: '1_0'"),
        ("v 1 2 3abc\n", 1, "not a number"),
        ("v 1 2 3 x\n", 1, "not a number: 'x'"),  # a weight must be a number too
        ("v 1 2 3 0.5 0.5 y\n", 1, "not a number: 'y'"),  # and a colour
        # NaN and infinity, spelled every way float() accepts, and overflow to infinity
        ("v nan 0 0\n", 1, "non-finite"),
        ("v 0 NaN 0\n", 1, "non-finite"),
        ("v 0 0 inf\n", 1, "non-finite"),
        ("v 0 0 -Infinity\n", 1, "non-finite"),
        ("v 1e999 0 0\n", 1, "non-finite"),
        ("v 0 -1e309 0\n", 1, "non-finite"),
        # faces: out of range, zero, relative past the first vertex, not integers, too short
        (TRIANGLE + "f 1 2 4\n", 4, "vertex 4, but the file has only 3"),
        (TRIANGLE + "f 0 1 2\n", 4, "0 is invalid"),
        (TRIANGLE + "f -4 -1 -2\n", 4, "counts back past the first vertex"),
        ("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n", 2, "counts back"),  # relative to its line
        (TRIANGLE + "f 1 2 x\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 3.0\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 +-3\n", 4, "not a vertex index"),
        (TRIANGLE + "f 1 2 /3\n", 4, "not a vertex index"),  # a corner without its vertex
        (TRIANGLE + "f 1 2\n", 4, "at least 3 corners"),
        (TRIANGLE + "f\n", 4, "at least 3 corners"),
        (TRIANGLE + "f 1 2 99999999999999999999999\n", 4, "vertex"),
        (TRIANGLE + "f 1 2 -99999999999999999999999\n", 4, "vertex"),
        (TRIANGLE + "f 1 2 " + "7" * 5000 + "\n", 4, "vertex"),  # beyond int()'s digit limit
        (TRIANGLE + "f 1 2 -" + "7" * 5000 + "\n", 4, "vertex"),
        # empty, or nothing that makes a mesh
        ("", None, "empty"),
        (" \n\t\r\n\n", None, "empty"),
        ("# only a comment\nvt 0 0\nvn 0 0 1\n", None, "no vertices"),
        ("f 1 2 3\n", None, "no vertices"),
        ("\ufeff", None, "empty"),  # a UTF-8 byte-order mark and nothing else
        # binary data
        (b"v 0 0 0\n\x00\x01\x02binary", 2, "NUL"),
        (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", 3, "NUL"),
        (b"PK\x03\x04\x14\x00\x00\x00\x08\x00", 1, "NUL"),
        (b"v 0 0 0\nv 1 0 0\n\xff\xfe\x89PNG", 3, "UTF-8"),
        (b"v 0 0 0\r\nv 1 0 0\r\n\xc0\xaf\r\n", 3, "UTF-8"),  # an overlong encoding of '/'
        (b"v 0 0 0\rv 1 0 0\r\xed\xa0\x80\r", 3, "UTF-8"),  # a surrogate; old-Mac line ends
        (b"v 0 0 0\n# caf\xc3", 2, "UTF-8"),  # the file ends inside a character
        # a line continued into the end of the file (the continuation keeps its first line)
        ("v 0 0 0\nv 1 2 \\", 2, "got 2 value"),
        ("v 0 0 0\nv 1 \\\n2 3\nf 1 2 x\n", 4, "not a vertex index"),
        ("v 0 0 0\nv 1 \\\n2 \\\n\n", 2, "got 2 value"),
    ],
)
def test_bad_obj_is_refused_with_file_and_line(
    tmp_path: Path, text: str | bytes, line: int | None, message: str
) -> None:
    path = write_file(tmp_path / "bad.obj", text)
    expect_input_error(lambda: read_obj(path), path, line=line, match=message)
    # the same through a sequence: a single file has no frame number
    expect_input_error(lambda: load_sequence(path, progress=False), path, line=line, match=message)


def test_missing_obj_file_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot read"):
        read_obj(tmp_path / "nothing.obj")


def test_a_single_bad_file_has_no_frame_number(tmp_path: Path) -> None:
    path = write_file(tmp_path / "one.obj", "v 0 0 0\nf 1 2\n")
    with pytest.raises(InputError) as caught:
        load_sequence(path)
    assert caught.value.frame is None and str(caught.value).startswith(f"{path}:2: ")


def test_messages_quote_a_long_token_only_in_part(tmp_path: Path) -> None:
    path = write_file(tmp_path / "long.obj", "v 0 0 " + "1" * 100_000 + "x\n")
    error = expect_input_error(lambda: read_obj(path), path, line=1, match="not a number")
    assert "..." in str(error)


def test_a_long_broken_number_is_refused_quickly(tmp_path: Path) -> None:
    # A regex that backtracks quadratically took 8 s on 20 000 digits; a line may hold millions.
    path = write_file(tmp_path / "digits.obj", "v 0 0 " + "1" * (MAX_LINE_BYTES - 10) + "x\n")
    with deadline():  # quadratic, it would take hours at this length: a hang guard suffices
        expect_input_error(lambda: read_obj(path), path, line=1, match="not a number")


def test_one_huge_polygon_among_many_faces(tmp_path: Path) -> None:
    # Padding 1001 faces to 20 000 corners would be 20 M entries from a 110 kB file (a 0.7 MB
    # file asked for 45 GiB before the limit); refused at the widest face's line.
    corners = " ".join(str(1 + i % 3) for i in range(20_000))
    path = write_file(tmp_path / "wide.obj", TRIANGLE + "f 1 2 3\n" * 1000 + f"f {corners}\n")
    raised, _, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError), raised
    assert (raised.line, raised.path) == (1004, str(path)) and "20000 corners" in str(raised)
    assert peak < 64 * 2**20
    # a 500-gon cap among 2000 triangles is an ordinary mesh
    corners = " ".join(str(1 + i % 3) for i in range(500))
    path = write_file(tmp_path / "cap.obj", TRIANGLE + "f 1 2 3\n" * 2000 + f"f {corners}\n")
    vertices, faces = read_obj(path)
    assert faces.shape == (2001, 500)
    check_obj_result(path, vertices, faces)


@pytest.mark.parametrize(
    "data",
    [
        pytest.param(np.random.default_rng(5).bytes(4096), id="random"),
        pytest.param(b"\x89PNG\r\n\x1a\n" + np.random.default_rng(6).bytes(300), id="png"),
        pytest.param(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n1 0 obj", id="pdf"),
        pytest.param(b"\x7fELF\x02\x01\x01", id="elf-ascii-start"),
    ],
)
def test_binary_garbage(tmp_path: Path, data: bytes) -> None:
    path = write_file(tmp_path / "garbage.obj", data)
    with pytest.raises(InputError) as caught:
        read_obj(path)
    assert caught.value.path == str(path)


def test_a_zip_named_obj(tmp_path: Path) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, V=np.zeros((1, 3, 3)))
    path = write_file(tmp_path / "archive.obj", buffer.getvalue())
    expect_input_error(lambda: read_obj(path), path, line=1, match="NUL")


def test_a_folder_and_a_missing_file(tmp_path: Path) -> None:
    (tmp_path / "dir.obj").mkdir()
    expect_input_error(lambda: read_obj(tmp_path / "dir.obj"), tmp_path / "dir.obj", match="folder")
    missing = tmp_path / "missing.obj"
    expect_input_error(lambda: read_obj(missing), missing, match="cannot read")


# ------------------------------------------------------------------------------------------
# a 2 GB line: refused after MAX_LINE_BYTES, without reading the file, in small memory


def sparse_file(path: Path, head: bytes, size: int = 2**31) -> Path:
    """A file of ``size`` bytes that starts with ``head`` and costs no disk beyond it (the rest
    is a hole, which reads as NUL bytes)."""
    with path.open("wb") as stream:
        stream.write(head)
        stream.truncate(size)
    return path


@pytest.mark.skipif(sys.platform == "win32", reason="no sparse files by default")
def test_a_2gb_line_of_nul_bytes(tmp_path: Path) -> None:
    path = sparse_file(tmp_path / "hole.obj", b"v 0 0 0\nv 1 ")
    with deadline():
        raised, elapsed, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError) and raised.line == 2, raised
    print(f"\n2 GB sparse line (NUL): {elapsed * 1000:.1f} ms, peak {peak / 2**20:.2f} MiB")
    assert peak < 8 * 2**20


@pytest.mark.skipif(sys.platform == "win32", reason="no sparse files by default")
def test_a_2gb_line_of_digits(tmp_path: Path) -> None:
    # Real digits for more than the limit, then a hole: it is the line limit that stops it.
    head = b"v 0 0 0\nv 1 " + b"1" * (MAX_LINE_BYTES + 2**20)
    path = sparse_file(tmp_path / "long.obj", head)
    with deadline():
        raised, elapsed, peak = measure(lambda: read_obj(path))
    assert isinstance(raised, InputError), raised
    assert raised.line == 2 and "longer than" in str(raised), raised
    print(f"\n2 GB line (digits then hole): {elapsed * 1000:.1f} ms, peak {peak / 2**20:.2f} MiB")
    assert peak < MAX_LINE_BYTES + 4 * 2**20


@pytest.mark.parametrize("ending", [b"\n", b"\r\n", b"\r"])
def test_line_length_limit_is_exact_across_chunks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ending: bytes
) -> None:
    # A small limit makes the chunks small too, so lines cross chunk boundaries everywhere.
    monkeypatch.setattr(objio, "MAX_LINE_BYTES", 16)
    longest = b"# " + b"c" * 14  # exactly 16 bytes
    lines = [b"v 0 0 0", longest, b"v 1 0 0", b"v 0 1 0", longest, b"f 1 2 3"]
    path = write_file(tmp_path / "fits.obj", ending.join(lines) + ending)
    assert read_obj(path)[0].shape == (3, 3)
    for number in range(len(lines)):
        too_long = list(lines)
        too_long[number] += b" " * (17 - len(too_long[number]))  # 17 bytes: one too many
        path = write_file(tmp_path / f"long{number}.obj", ending.join(too_long) + ending)
        expect_input_error(
            functools.partial(read_obj, path), path, line=number + 1, match="longer than 16"
        )
    # the last line, without a line end
    path = write_file(tmp_path / "last.obj", ending.join(lines) + ending + b"#" * 17)
    expect_input_error(lambda: read_obj(path), path, line=len(lines) + 1, match="longer than 16")


# ------------------------------------------------------------------------------------------
# property tests: random bytes and random mutations


def _obj_outcome(path: Path) -> None:
    """Read ``path`` as OBJ: it must succeed with a valid mesh or raise an InputError naming it."""
    try:
        vertices, faces = read_obj(path)
    except InputError as error:
        refused = error
    else:
        check_obj_result(path, vertices, faces)
        return
    assert refused.path == str(path) and str(refused).startswith(str(path))


@PROPERTY
@given(data=st.binary(max_size=2048))
def test_random_bytes_as_obj(data: bytes) -> None:
    EXAMPLES_RUN["random bytes as OBJ"] = EXAMPLES_RUN.get("random bytes as OBJ", 0) + 1
    path = write_file(SCRATCH / "random.obj", data)
    _obj_outcome(path)


@PROPERTY
@given(data=mutations(VALID_OBJ, OBJ_TOKENS))
def test_mutated_obj(data: bytes) -> None:
    EXAMPLES_RUN["mutated OBJ"] = EXAMPLES_RUN.get("mutated OBJ", 0) + 1
    path = write_file(SCRATCH / "mutated.obj", data)
    _obj_outcome(path)


EXAMPLES_RUN: dict[str, int] = {}  # examples run by each property test, printed at the end
SCRATCH = scratch_folder()


def teardown_module() -> None:
    """Remove the scratch folder; report how many examples each property test ran (``-s``)."""
    shutil.rmtree(SCRATCH, ignore_errors=True)
    report_examples(EXAMPLES_RUN)


def test_a_folder_of_frames_gets_each_frames_own_faces(tmp_path):
    """The faces' text is kept from one frame to the next (a folder writes the same faces in
    each): a frame with other faces must still get its own, and the text of every frame is
    what formatting it alone gives (repr of each float, 1-based corners)."""
    vertices = np.random.default_rng(4).standard_normal((5, 3))
    first = np.array([[0, 1, 2], [2, 3, 4]])
    second = np.array([[0, 1, 2, 3], [1, 2, 4, -1]])
    changed = first.copy()  # the same table changed in place: its new faces, not the kept text
    tables = (first, second, first, first.astype(np.int32), changed, changed)
    for number, faces in enumerate(tables):
        if number == len(tables) - 1:
            changed[1] = [4, 3, 2]
        path = tmp_path / f"frame{number}.obj"
        write_obj(path, vertices, faces)
        expected = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
        expected += ["f " + " ".join(str(i + 1) for i in row if i >= 0) for row in faces.tolist()]
        assert path.read_text() == "\n".join(expected) + "\n"
