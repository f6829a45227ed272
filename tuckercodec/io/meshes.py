"""Single-frame mesh files read through trimesh: PLY, OFF, STL, glTF, 3MF, COLLADA.

One file holds one frame; a folder or a list of them is a sequence (:mod:`.frames`). trimesh
is asked to keep the file's vertex order (``process=False, maintain_order=True``), which a
codec needs: the vertices of every frame must correspond. OBJ is never read this way
(:mod:`.obj` explains why).

What trimesh would decompress is bounded first: an archive (``.zip``, ``.bz2``, ``.tar.gz``,
``.tar.bz2``, which trimesh inflates whole, a bz2 stream without any limit) is refused, and a
``.3mf`` (a zip) is opened only if the sizes its members declare, which zipfile never inflates
beyond, fit ``--max-memory`` together (:mod:`.common.budget`). The files a mesh names (a PLY's
``TextureFile``) trimesh reads only inside the mesh's folder (trimesh 5's resolver; and
materials are not loaded at all).
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from ..errors import InputError
from .registry import MeshFrame, ReadOptions

#: The archives trimesh opens by their suffix and inflates whole before reading a mesh.
ARCHIVES = (".zip", ".bz2", ".tar.gz", ".tar.bz2")


def read_mesh_frame(
    path: Path, reference: MeshFrame | None = None, options: ReadOptions | None = None
) -> MeshFrame:
    """One frame of a mesh file trimesh reads; ``reference`` is unused (checked by the caller);
    what trimesh would decompress is bounded by ``options.max_memory`` (module docstring)."""
    _check_inflation(path, options or ReadOptions())
    return _read_with_trimesh(path)


def _check_inflation(path: Path, options: ReadOptions) -> None:
    """Refuse an archive, and a .3mf whose members declare more than the read may inflate."""
    name = path.name.lower()
    if name.endswith(ARCHIVES):
        raise InputError(
            "is an archive, which trimesh would inflate whole: extract the mesh from it first",
            path=path,
        )
    if not name.endswith(".3mf") or not path.is_file():
        return
    inflation = options.inflation()
    try:
        with zipfile.ZipFile(path) as archive:
            members = archive.infolist()
    except (OSError, zipfile.BadZipFile, ValueError) as error:
        raise InputError(f"cannot read as a 3MF file (a zip archive): {error}", path=path) from None
    for info in members:
        inflation.take(info.file_size, f"member {info.filename!r}", path)


def _read_with_trimesh(path: Path) -> MeshFrame:
    """Vertices and faces of a PLY/OFF/STL/glTF... file, in the file's vertex order."""
    import trimesh  # imported here: it is slow to import and only needed for these formats

    if not path.is_file():
        raise InputError("no such file", path=path)
    try:
        mesh = trimesh.load(
            path, process=False, maintain_order=True, force="mesh", skip_materials=True
        )
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
