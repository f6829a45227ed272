"""Single-frame mesh files read through trimesh: PLY, OFF, STL, glTF, 3MF, COLLADA.

One file holds one frame; a folder or a list of them is a sequence (:mod:`.frames`). trimesh
is asked to keep the file's vertex order (``process=False, maintain_order=True``), which a
codec needs: the vertices of every frame must correspond. OBJ is never read this way
(:mod:`.obj` explains why).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import InputError
from .registry import MeshFrame


def read_mesh_frame(path: Path, reference: MeshFrame | None = None) -> MeshFrame:
    """One frame of a mesh file trimesh reads; ``reference`` is unused (checked by the caller)."""
    return _read_with_trimesh(path)


def _read_with_trimesh(path: Path) -> MeshFrame:
    """Vertices and faces of a PLY/OFF/STL/glTF... file, in the file's vertex order."""
    import trimesh  # imported here: it is slow to import and only needed for these formats

    if not path.is_file():
        raise InputError("no such file", path=path)
    try:
        mesh = trimesh.load(path, process=False, maintain_order=True, force="mesh")
    except Exception as error:
        raise InputError(
            f"trimesh cannot read it as a mesh: {type(error).__name__}: {error}", path=path
        ) from None
    if not isinstance(mesh, trimesh.Trimesh):
        raise InputError(f"trimesh reads it as a {type(mesh).__name__}, not a mesh", path=path)
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) == 0:
        raise InputError("no vertices found", path=path)
    if faces.size == 0:
        faces = np.zeros((0, 3), dtype=np.int64)
    if not np.isfinite(vertices).all():
        row = int(np.argwhere(~np.isfinite(vertices))[0, 0])
        raise InputError(f"vertex {row} has a non-finite coordinate", path=path)
    return MeshFrame(vertices, faces, path=str(path))
