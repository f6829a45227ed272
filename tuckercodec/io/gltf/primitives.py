"""A glTF mesh's primitives merged into one: positions, morph target deltas, triangles, the
other vertex attributes and each triangle's material.

Primitives that share their vertex attributes (the same accessor for every semantic, and the
same morph targets) share their vertices; others follow one another (two primitives that share
POSITION but not NORMAL give two copies of the positions, as glTF's vertices are the tuples of
all their attributes). Triangles are in the primitives' order, then in their index order.
TRIANGLES give triangles, TRIANGLE_STRIP and TRIANGLE_FAN are converted to triangles (a strip's
degenerate joining triangles dropped), POINTS add vertices without faces; line modes are
refused. Every primitive must have as many morph targets as the first. The attributes beside
POSITION are read as :mod:`.vertex_attributes` says, and combined over the vertex blocks by
:func:`.vertex_attributes.combined`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .accessors import read_accessor
from .animation import numbers
from .container import Document
from .vertex_attributes import VertexValues, combined, read_vertex_attribute

_TRIANGLES, _STRIP, _FAN, _POINTS = 4, 5, 6, 0
#: The most numbers one mesh's morph targets may hold (2 GiB of float64), checked first.
MAX_NUMBERS = 1 << 28


@dataclass
class Mesh:
    """The merged primitives of one mesh: base positions (K, 3), targets (J, K, 3), faces, the
    default weights (J,); the other vertex attributes by semantic, each face's material (an
    index of ``materials``, -1 for none), and where each vertex block's morph targets are (for
    their NORMAL deltas, read only when asked: :meth:`normal_delta`)."""

    base: np.ndarray
    targets: np.ndarray
    faces: np.ndarray
    weights: np.ndarray
    attributes: dict[str, VertexValues] = field(default_factory=dict)
    materials: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    #: each vertex block's first vertex, vertex count, morph targets (JSON) and primitive
    morph_blocks: list[tuple[int, int, list[Any], str]] = field(default_factory=list)

    def normal_delta(self, doc: Document, target: int) -> np.ndarray:
        """Morph target ``target``'s NORMAL deltas (K, 3), zero where a block has none."""
        deltas = np.zeros_like(self.base)
        for offset, count, morphs, where in self.morph_blocks:
            morph = morphs[target]
            if isinstance(morph, dict) and "NORMAL" in morph:
                label = f"{where}.targets[{target}] NORMAL"
                delta = read_accessor(doc, morph["NORMAL"], label, width=3)
                if len(delta) != count:
                    raise doc.fail(f"{label}: {len(delta)} values for {count} vertices")
                deltas[offset : offset + count] = delta
        return deltas


def read_mesh(doc: Document, index: int) -> Mesh:
    """Mesh ``index``'s primitives merged: positions, morph target deltas, faces, weights."""
    key = ("mesh", index)
    if key not in doc.cache:
        doc.cache[key] = _merge_primitives(doc, index)
    mesh: Mesh = doc.cache[key]
    return mesh


def _merge_primitives(doc: Document, index: int) -> Mesh:
    mesh = doc.item("meshes", index, "a node")
    primitives = mesh.get("primitives")
    if not isinstance(primitives, list) or not primitives:
        raise doc.fail(f"meshes[{index}] has no primitives")
    bases: list[np.ndarray] = []
    targets: list[np.ndarray] = []
    morph_blocks: list[tuple[int, int, list[Any], str]] = []
    attributes: list[dict[str, VertexValues]] = []
    faces: list[np.ndarray] = []
    materials: list[np.ndarray] = []
    blocks: dict[str, tuple[int, int]] = {}  # vertex attributes and targets -> (offset, count)
    target_count: int | None = None
    for number, primitive in enumerate(primitives):
        where = f"meshes[{index}].primitives[{number}]"
        if not isinstance(primitive, dict) or not isinstance(primitive.get("attributes"), dict):
            raise doc.fail(f"{where} lacks attributes")
        accessor = primitive["attributes"].get("POSITION")
        if accessor is None:
            raise doc.fail(f"{where} has no POSITION")
        morphs = primitive.get("targets", [])
        if not isinstance(morphs, list):
            raise doc.fail(f"{where}.targets must be a list")
        if target_count is None:
            target_count = len(morphs)
        elif len(morphs) != target_count:
            raise doc.fail(
                f"{where} has {len(morphs)} morph targets, the first primitive {target_count}"
            )
        if not isinstance(accessor, int) or isinstance(accessor, bool):
            raise doc.fail(f"{where}: POSITION must be an accessor index")
        key = json.dumps([primitive["attributes"], morphs], sort_keys=True)
        if key not in blocks:
            base = read_accessor(doc, accessor, f"{where} POSITION", width=3)
            blocks[key] = (sum(len(b) for b in bases), len(base))
            bases.append(base)
            targets.append(_deltas(doc, morphs, len(base), where))
            morph_blocks.append((blocks[key][0], len(base), morphs, where))
            attributes.append(_attributes(doc, primitive["attributes"], len(base), where))
        offset, count = blocks[key]
        triangles = _faces(doc, primitive, count, where) + offset
        faces.append(triangles)
        materials.append(np.full(len(triangles), _material(doc, primitive, where)))
    weights = np.zeros(target_count or 0)
    if "weights" in mesh:
        weights = numbers(doc, mesh["weights"], target_count or 0, f"meshes[{index}].weights")
    # float64 whatever the accessors' type: integer positions (KHR_mesh_quantization without
    # normalization) gave an int64 base, to which the morph targets' float deltas could not be
    # added in place (found by fuzzing the glTF reader, tools.fuzz)
    base = np.concatenate(bases).astype(np.float64)
    counts = [len(b) for b in bases]
    return Mesh(
        base,
        np.concatenate(targets, axis=1),
        np.concatenate(faces),
        weights,
        combined(attributes, counts),
        np.concatenate(materials).astype(np.int64),
        morph_blocks,
    )


def _attributes(
    doc: Document, semantics: dict[str, Any], vertices: int, where: str
) -> dict[str, VertexValues]:
    """A primitive's vertex attributes other than POSITION, by semantic."""
    found: dict[str, VertexValues] = {}
    for semantic, accessor in semantics.items():
        if semantic == "POSITION":
            continue
        values = read_vertex_attribute(doc, accessor, str(semantic), vertices, where)
        if values is not None:
            found[str(semantic)] = values
    return found


def _material(doc: Document, primitive: dict[str, Any], where: str) -> int:
    """The primitive's material index, checked, or -1 for none."""
    if "material" not in primitive:
        return -1
    doc.item("materials", primitive["material"], f"{where}.material")
    return int(primitive["material"])


def _deltas(doc: Document, morphs: list[Any], vertices: int, where: str) -> np.ndarray:
    """The morph targets' POSITION deltas, (J, K, 3); a target without POSITION moves nothing."""
    if len(morphs) * vertices * 3 > MAX_NUMBERS:
        raise doc.fail(f"{where}: {len(morphs)} morph targets of {vertices} vertices are too many")
    deltas = np.zeros((len(morphs), vertices, 3))
    for j, morph in enumerate(morphs):
        if not isinstance(morph, dict):
            raise doc.fail(f"{where}.targets[{j}] must be an object")
        if "POSITION" in morph:
            delta = read_accessor(doc, morph["POSITION"], f"{where}.targets[{j}] POSITION", width=3)
            if len(delta) != vertices:
                raise doc.fail(
                    f"{where}.targets[{j}] has {len(delta)} positions for {vertices} vertices"
                )
            deltas[j] = delta
    return deltas


def _faces(doc: Document, primitive: dict[str, Any], vertices: int, where: str) -> np.ndarray:
    """A primitive's triangles (T, 3), 0-based within its vertices; (0, 3) for points."""
    mode = primitive.get("mode", _TRIANGLES)
    if mode == _POINTS:
        return np.zeros((0, 3), dtype=np.int64)
    if mode not in (_TRIANGLES, _STRIP, _FAN):
        raise doc.fail(f"{where}: mode {mode!r} (lines?) is not a surface nor points; not read")
    if "indices" in primitive:
        accessor = primitive["indices"]
        indices = read_accessor(doc, accessor, f"{where} indices", width=1)[:, 0]
        if doc.item("accessors", accessor, where).get("componentType") not in (5121, 5123, 5125):
            raise doc.fail(f"{where}: indices must be unsigned integers")
        if indices.size and int(indices.max()) >= vertices:
            raise doc.fail(f"{where}: index {int(indices.max())} is beyond its {vertices} vertices")
    else:
        indices = np.arange(vertices, dtype=np.int64)
    if mode == _TRIANGLES:
        if len(indices) % 3:
            raise doc.fail(f"{where}: {len(indices)} indices are not whole triangles")
        return indices.reshape(-1, 3)
    if len(indices) < 3:
        return np.zeros((0, 3), dtype=np.int64)
    n = np.arange(len(indices) - 2)
    if mode == _FAN:
        triangles = np.stack([np.full_like(n, indices[0]), indices[n + 1], indices[n + 2]], 1)
    else:  # a strip: every other triangle is wound the other way
        odd = n % 2 == 1
        first = np.where(odd, indices[n + 1], indices[n])
        second = np.where(odd, indices[n], indices[n + 1])
        triangles = np.stack([first, second, indices[n + 2]], 1)
        degenerate = (
            (triangles[:, 0] == triangles[:, 1])
            | (triangles[:, 1] == triangles[:, 2])
            | (triangles[:, 0] == triangles[:, 2])
        )
        triangles = triangles[~degenerate]  # the joins between strips
    return triangles.astype(np.int64)
