"""Putting a glTF together: the JSON skeleton every file this package writes shares, and the
bytes of a ``.glb`` or a self-contained ``.gltf`` chosen by the file name."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..._version import __version__
from .accessors import ELEMENT_ARRAY_BUFFER, BufferBuilder
from .container import pack_glb, pack_gltf


def new_gltf(extensions: list[str] | None = None) -> dict[str, Any]:
    """The asset record (and the extensions used and required, if any)."""
    gltf: dict[str, Any] = {"asset": {"version": "2.0", "generator": f"tuckercodec {__version__}"}}
    if extensions:
        gltf["extensionsUsed"] = sorted(extensions)
        gltf["extensionsRequired"] = sorted(extensions)
    return gltf


def file_bytes(gltf: dict[str, Any], builder: BufferBuilder, path: Path) -> bytes:
    """The finished file: the builder's views, accessors and buffer added to ``gltf``; a .glb
    unless ``path`` ends in .gltf (then one JSON file, its buffer in a data: URI)."""
    binary = builder.binary()
    gltf = dict(gltf)
    gltf["accessors"] = builder.accessors
    gltf["bufferViews"] = builder.views
    buffers = gltf.get("buffers", [])
    gltf["buffers"] = [{"byteLength": len(binary)}, *buffers[1:]]
    if path.suffix.lower() == ".gltf":
        return pack_gltf(gltf, binary)
    return pack_glb(gltf, binary)


def add_triangles(
    builder: BufferBuilder, primitive: dict[str, Any], triangles: np.ndarray, vertices: int
) -> None:
    """Give ``primitive`` the triangles (T, 3) as indices (16-bit where the vertices allow), or
    make it POINTS when there are none."""
    if len(triangles) == 0:
        primitive["mode"] = 0
        return
    index_type = np.uint16 if vertices <= 0xFFFF else np.uint32
    primitive["indices"] = builder.add_accessor(
        np.asarray(triangles).reshape(-1).astype(index_type), target=ELEMENT_ARRAY_BUFFER
    )
    primitive["mode"] = 4
