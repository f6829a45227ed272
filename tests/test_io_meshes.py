"""Single-frame mesh files read through trimesh (tuckercodec/io/meshes.py): the vertex order is
kept, and a file trimesh cannot read is an InputError naming it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import CUBE_VERTICES, write_file
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
