"""Single-frame mesh files read through trimesh (tuckercodec/io/meshes.py): the vertex order is
kept, and a file trimesh cannot read is an InputError naming it."""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import CUBE_VERTICES, expect_input_error, write_file
from tuckercodec import InputError
from tuckercodec.io import load_sequence


def test_other_mesh_formats_via_trimesh(tmp_path: Path) -> None:
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    text = "OFF\n4 2 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in CUBE_VERTICES[:4].tolist())
    text += "".join("3 " + " ".join(map(str, face)) + "\n" for face in faces.tolist())
    path = write_file(tmp_path / "quad.off", text)
    seq = load_sequence(path, progress=False)
    np.testing.assert_array_equal(seq.vertices[0], CUBE_VERTICES[:4])
    np.testing.assert_array_equal(seq.faces, faces)
    broken = write_file(tmp_path / "broken.ply", b"ply\nformat nonsense\n")
    with pytest.raises(InputError) as caught:
        load_sequence(broken)
    assert caught.value.path == str(broken)


OFF_QUAD = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"


@pytest.mark.parametrize("suffix", [".zip", ".bz2", ".tar.gz", ".tar.bz2", ".ZIP"])
def test_archives_trimesh_would_inflate_whole_are_refused(tmp_path: Path, suffix: str) -> None:
    """A decompression bomb: trimesh inflates an archive whole before it reads a mesh (a bz2
    stream without any limit), so a small archive could fill the memory."""
    path = tmp_path / f"mesh{suffix}"
    with zipfile.ZipFile(path, "w") as archive:  # whatever the kind: refused by its name
        archive.writestr("quad.off", OFF_QUAD)
    expect_input_error(lambda: load_sequence(path), path, match="is an archive")


def test_a_3mf_whose_members_declare_more_than_max_memory_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "bomb.3mf"
    with (
        zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive,
        archive.open("3D/3dmodel.model", "w") as member,
    ):
        for _ in range(16):  # 16 MiB of zeros in 16 KB
            member.write(bytes(2**20))
    expect_input_error(
        lambda: load_sequence(path, max_memory=2**20),
        path,
        match=r"member '3D/3dmodel.model': inflates to 16.8 MB, beyond the 1.05 MB",
    )
    with pytest.raises(InputError) as caught:  # within the ceiling: trimesh's turn (and error)
        load_sequence(path, max_memory=2**30)
    assert "inflates" not in str(caught.value)


def test_a_ply_texture_is_never_read(tmp_path: Path) -> None:
    """A PLY may name a TextureFile; materials are not loaded, so no file it names is read."""
    fifo = tmp_path / "texture.png"
    os.mkfifo(fifo)  # reading it would wait for a writer for ever
    path = write_file(
        tmp_path / "tex.ply",
        "ply\nformat ascii 1.0\ncomment TextureFile texture.png\nelement vertex 3\n"
        "property float x\nproperty float y\nproperty float z\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    assert load_sequence(path).vertex_count == 3
