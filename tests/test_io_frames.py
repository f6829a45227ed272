"""Sequences of one mesh file per frame (tuckercodec/io/frames.py): folders, globs and lists read
in natural order, folders written whole, and frames that disagree with the first one.

A frame with another vertex count or other faces than the first frame, or a bad frame in the
middle of a sequence, is an :class:`InputError` that names the file, its line and the frame
number (and the first frame's file where they are compared).
"""

from __future__ import annotations

import functools
import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given

from tests.support.inputs import (
    CUBE_VERTICES,
    OBJ_TOKENS,
    VALID_OBJ,
    check_sequence,
    expect_input_error,
    obj_text,
    write_cube_frames,
    write_file,
)
from tests.support.properties import PROPERTY, mutations, report_examples, scratch_folder
from tests.support.sequences import shared_file
from tuckercodec import InputError, MeshSequence
from tuckercodec.io import (
    format_named,
    format_of,
    formats,
    load_sequence,
    natural_sort_key,
    save_sequence,
)
from tuckercodec.io.obj import read_obj_frame


def write_square_frames(folder: Path, count: int) -> list[Path]:
    """``count`` frames of a quad and a triangle, the vertices moving along x."""
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for frame in range(count):
        vertices = "".join(f"v {x + frame} {y} 0\n" for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)])
        paths.append(
            write_file(folder / f"f{frame}.obj", vertices + "v 2 2 2\nf 1 2 3 4\nf 2 3 5\n")
        )
    return paths


# ------------------------------------------------------------------------------------------
# reading: folders, globs and lists


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
    write_cube_frames(tmp_path / "seq", 12, name="f{}.obj")
    (tmp_path / "seq" / "notes.txt").write_text("not a frame")
    write_file(tmp_path / "seq" / "._f1.obj", b"\x00\x05\x16\x07 macOS metadata")  # hidden
    seq = load_sequence(tmp_path / "seq", progress=False)
    assert seq.frame_names[:4] == ["f0.obj", "f1.obj", "f2.obj", "f3.obj"]
    assert seq.frame_names[-1] == "f11.obj"
    np.testing.assert_array_equal(seq.vertices[:, 0, 0], np.arange(12))  # f2 before f10
    assert seq.faces.shape == (3, 4) and seq.faces[2, 3] == -1


def test_glob_list_and_upper_case_suffix(tmp_path: Path) -> None:
    paths = write_cube_frames(tmp_path, 3, name="m{}.OBJ")
    by_glob = load_sequence(str(tmp_path / "m*.OBJ"), progress=False)
    by_folder = load_sequence(tmp_path, progress=False)
    by_list = load_sequence([paths[2], paths[0]], progress=False)  # a list keeps its order
    np.testing.assert_array_equal(by_glob.vertices, by_folder.vertices)
    assert by_list.frame_names == ["m2.OBJ", "m0.OBJ"]
    single = load_sequence(paths[1], progress=False)
    assert single.frame_count == 1 and single.frame_names == ["m1.OBJ"]


def test_nothing_to_read(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match=r"no \.obj") as caught:
        load_sequence(tmp_path / "empty")
    assert caught.value.path == str(tmp_path / "empty")
    with pytest.raises(InputError, match="no such file or folder") as caught:
        load_sequence(tmp_path / "missing")
    assert caught.value.path == str(tmp_path / "missing")
    with pytest.raises(InputError, match="matches no files"):
        load_sequence(str(tmp_path / "*.obj"))
    with pytest.raises(InputError, match="empty"):
        load_sequence([])


def test_next_frame_reuses_identical_faces(tmp_path: Path) -> None:
    first, second = write_cube_frames(tmp_path, 2)
    reference = read_obj_frame(first)
    frame = read_obj_frame(second, reference)
    assert frame.faces is reference.faces  # compared as bytes, not parsed again
    relative = write_file(tmp_path / "relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n")
    assert read_obj_frame(relative).face_text is None  # negative indices depend on position


def test_same_faces_written_differently_are_accepted(tmp_path: Path) -> None:
    paths = write_cube_frames(tmp_path, 2)
    text = paths[1].read_text().replace("f 1 2 3 4", "f 1  +2 3 -5")  # -5: vertex 4 of 8
    write_file(paths[1], text)
    seq = load_sequence(tmp_path, progress=False)
    assert seq.frame_count == 2


def test_a_frame_whose_faces_index_texture_coordinates_the_first_does_not(
    tmp_path: Path,
) -> None:
    """The vertices of the faces are the same, but only the later frame has UVs: the
    sequence's UVs are the first frame's, so the later frame is refused, named."""
    paths = write_cube_frames(tmp_path, 2)
    text = paths[1].read_text()
    faces = [line for line in text.splitlines() if line.startswith("f ")]
    with_uv = ["f " + " ".join(f"{c}/1" for c in line.split()[1:]) for line in faces]
    for old, new in zip(faces, with_uv, strict=True):
        text = text.replace(old + "\n", new + "\n")
    write_file(paths[1], "vt 0 0\n" + text)
    with pytest.raises(InputError, match="this frame has them, the first frame") as caught:
        load_sequence(tmp_path, progress=False)
    assert caught.value.path == str(paths[1]) and caught.value.frame == 1


# ------------------------------------------------------------------------------------------
# frames that disagree name both files and the frame


def test_frame_with_different_vertex_count(tmp_path: Path) -> None:
    paths = write_cube_frames(tmp_path, 3)
    write_file(paths[2], obj_text(np.vstack([CUBE_VERTICES, [[5, 5, 5]]]), [[1, 2, 3]]))
    with pytest.raises(InputError, match="has 9 vertices but the first frame has 8") as caught:
        load_sequence(tmp_path, progress=False)
    assert caught.value.path == str(paths[2])
    assert caught.value.frame == 2
    assert caught.value.line == 9  # the first vertex too many
    assert f"{paths[2]}:9, frame 2:" in str(caught.value)


def test_frame_with_different_faces(tmp_path: Path) -> None:
    paths = write_cube_frames(tmp_path, 3)
    text = paths[1].read_text().replace("f 5 6 7 8", "f 5 6 8 7")
    write_file(paths[1], text)
    with pytest.raises(InputError, match="face 2 is f 5 6 8 7") as caught:
        load_sequence(tmp_path, progress=False)
    assert (caught.value.path, caught.value.frame, caught.value.line) == (str(paths[1]), 1, 10)


def test_a_bad_frame_names_its_frame(tmp_path: Path) -> None:
    paths = write_cube_frames(tmp_path, 4)
    lines = paths[3].read_text().splitlines()
    lines[7] = "v 0 1 nan"
    write_file(paths[3], "\n".join(lines))
    with pytest.raises(InputError, match="non-finite") as caught:
        load_sequence(tmp_path, progress=False)
    assert (caught.value.path, caught.value.frame, caught.value.line) == (str(paths[3]), 3, 8)


def test_frames_with_other_vertex_counts_name_both_files(tmp_path: Path) -> None:
    paths = write_square_frames(tmp_path / "seq", 4)
    write_file(paths[2], paths[2].read_text() + "v 3 3 3\n")
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=8,  # the first vertex too many
        frame=2,
        match="has 6 vertices but the first frame has 5",
    )
    assert str(paths[0]) in str(error)
    # fewer vertices: the line of the last one there is
    write_file(paths[2], "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 2 3 4\n")
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=4,
        frame=2,
        match="has 4 vertices but the first frame has 5",
    )
    assert str(paths[0]) in str(error)


def test_frames_with_other_faces_name_both_files(tmp_path: Path) -> None:
    paths = write_square_frames(tmp_path / "seq", 3)
    write_file(paths[1], paths[1].read_text().replace("f 2 3 5", "f 2 5 3"))
    error = expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[1],
        line=7,
        frame=1,
        match="face 2 is f 2 5 3 but in the first frame it is f 2 3 5",
    )
    assert str(paths[0]) in str(error)


def test_frames_with_other_relative_faces_are_compared_by_meaning(tmp_path: Path) -> None:
    paths = write_square_frames(tmp_path / "seq", 3)
    write_file(paths[1], paths[1].read_text().replace("f 2 3 5", "f -4 -3 -1"))  # the same face
    write_file(paths[2], paths[2].read_text().replace("f 2 3 5", "f -4 -1 -3"))  # another one
    expect_input_error(
        lambda: load_sequence(tmp_path / "seq", progress=False),
        paths[2],
        line=7,
        frame=2,
        match="face 2 is f 2 5 3",
    )


def test_frames_read_by_trimesh_name_both_files_too(tmp_path: Path) -> None:
    folder = tmp_path / "off"
    folder.mkdir()
    square = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
    write_file(folder / "a0.off", square)
    write_file(
        folder / "a1.off", square.replace("4 1 0", "5 1 0").replace("0 1 0\n4", "0 1 0\n2 2 2\n4")
    )
    error = expect_input_error(
        lambda: load_sequence(folder, progress=False),
        folder / "a1.off",
        frame=1,
        match="has 5 vertices but the first frame has 4",
    )
    assert str(folder / "a0.off") in str(error)


@pytest.mark.parametrize(
    ("damage", "line", "message"),
    [
        (lambda text: text.replace("v 2 2 2", "v 2 2"), 5, "got 2 value"),
        (lambda text: text.replace("v 2 2 2", "v 2 2 nan"), 5, "non-finite"),
        (lambda text: "", None, "empty"),
        (lambda text: text + "\x00", 8, "NUL"),
    ],
)
def test_a_bad_middle_frame_is_named(
    tmp_path: Path, damage: Callable[[str], str], line: int | None, message: str
) -> None:
    paths = write_square_frames(tmp_path / "seq", 4)
    write_file(paths[2], damage(paths[2].read_text()))
    for source in (tmp_path / "seq", str(tmp_path / "seq" / "*.obj"), paths):
        expect_input_error(
            functools.partial(load_sequence, source, progress=False),
            paths[2],
            line=line,
            frame=2,
            match=message,
        )


@PROPERTY
@given(data=mutations(VALID_OBJ, OBJ_TOKENS))
def test_mutated_second_frame(data: bytes) -> None:
    """A sequence whose second frame is mutated: a valid sequence, or an error naming frame 1."""
    EXAMPLES_RUN["mutated frame of a sequence"] = (
        EXAMPLES_RUN.get("mutated frame of a sequence", 0) + 1
    )
    folder = SCRATCH / "seq"
    folder.mkdir(exist_ok=True)
    write_file(folder / "a0.obj", VALID_OBJ)
    second = write_file(folder / "a1.obj", data)
    try:
        seq = load_sequence(folder, progress=False)
    except InputError as error:
        refused = error
    else:
        check_sequence(seq)
        assert seq.frame_count == 2
        return
    assert (refused.path, refused.frame) == (str(second), 1), str(refused)


# ------------------------------------------------------------------------------------------
# writing folders of OBJ files


def test_save_folder_round_trip_refuses_overwrite(tmp_path: Path) -> None:
    write_cube_frames(tmp_path / "in", 3, name="f{}.obj")
    seq = load_sequence(tmp_path / "in", progress=False)
    out = tmp_path / "out"
    save_sequence(seq, out)
    again = load_sequence(out, progress=False)
    np.testing.assert_array_equal(again.vertices, seq.vertices)
    np.testing.assert_array_equal(again.faces, seq.faces)
    assert again.frame_names == seq.frame_names

    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "f1.obj").unlink()  # one missing target: still nothing may be written
    with pytest.raises(FileExistsError, match=r"f0\.obj"):
        save_sequence(seq, out)
    assert sorted(p.name for p in out.glob("*.obj")) == ["f0.obj", "f2.obj"]
    save_sequence(seq, out, overwrite=True)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # and no temporary files


def test_saved_names_are_safe_unique_and_keep_the_order(tmp_path: Path) -> None:
    seq = MeshSequence(
        np.zeros((4, 3, 3)) + np.arange(4)[:, None, None],
        np.array([[0, 1, 2]]),
        frame_names=["z/walk.ply", "walk.obj", "a b", ""],
    )
    save_sequence(seq, tmp_path / "out", precision=6)
    names = sorted((p.name for p in (tmp_path / "out").glob("*.obj")), key=natural_sort_key)
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


EXAMPLES_RUN: dict[str, int] = {}  # examples run by each property test, printed at the end
SCRATCH = scratch_folder()


def teardown_module() -> None:
    """Remove the scratch folder; report how many examples each property test ran (``-s``)."""
    shutil.rmtree(SCRATCH, ignore_errors=True)
    report_examples(EXAMPLES_RUN)


def test_formats_are_chosen_by_suffix_from_one_registry(tmp_path: Path) -> None:
    suffixes = [suffix for found in formats() for suffix in found.suffixes]
    assert len(suffixes) == len(set(suffixes))  # each suffix names one format
    assert format_of(tmp_path / "a.OBJ") is format_named("obj")
    whole, framed = format_of(tmp_path / "a.npz"), format_of(tmp_path / "a.ply")
    assert whole is not None and whole.open is not None  # a whole sequence in one file
    assert framed is not None and framed.read_frame is not None  # one frame per file
    assert format_of(tmp_path / "a.txt") is None
    with pytest.raises(
        ValueError, match=r"unknown sequence format 'abc': the formats are obj, npz,"
    ):
        format_named("abc")  # a suffix is not a name: Alembic's format is "alembic"


def test_a_list_of_frames_refuses_what_is_not_one_frame_per_file(tmp_path: Path) -> None:
    cube = write_cube_frames(tmp_path, 1)[0]
    archive = tmp_path / "whole.npz"
    np.savez(archive, V=np.zeros((2, 8, 3)))
    notes = write_file(tmp_path / "notes.txt", b"v 0 0 0\n")
    with pytest.raises(InputError, match=r"whole\.npz, frame 1: this \.npz file holds a whole"):
        load_sequence([cube, archive], progress=False)
    # a suffix no format claims goes to trimesh, which reads far more than the registry lists
    with pytest.raises(InputError, match=r"notes\.txt, frame 1: trimesh cannot read it"):
        load_sequence([cube, notes], progress=False)
