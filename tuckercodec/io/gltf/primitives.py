"""A glTF mesh's primitives merged into one: positions, morph target deltas, triangles.

Primitives that share a POSITION accessor share its vertices; others follow one another.
TRIANGLES give triangles, TRIANGLE_STRIP and TRIANGLE_FAN are converted to triangles (a strip's
degenerate joining triangles dropped), POINTS add vertices without faces; line modes are
refused. Every primitive must have as many morph targets as the first.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .accessors import read_accessor
from .animation import numbers
from .container import Document

_TRIANGLES, _STRIP, _FAN, _POINTS = 4, 5, 6, 0
#: The most numbers one mesh's morph targets may hold (2 GiB of float64), checked first.
MAX_NUMBERS = 1 << 28


@dataclass
class Mesh:
    """The merged primitives of one mesh: base positions (K, 3), targets (J, K, 3), faces."""

    base: np.ndarray
    targets: np.ndarray
    faces: np.ndarray
    weights: np.ndarray  # the default weights (J,)


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
    faces: list[np.ndarray] = []
    blocks: dict[Any, tuple[int, int]] = {}  # POSITION accessor -> (offset, vertex count)
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
        if accessor not in blocks:
            base = read_accessor(doc, accessor, f"{where} POSITION", width=3)
            blocks[accessor] = (sum(len(b) for b in bases), len(base))
            bases.append(base)
            targets.append(_deltas(doc, morphs, len(base), where))
        offset, count = blocks[accessor]
        faces.append(_faces(doc, primitive, count, where) + offset)
    weights = np.zeros(target_count or 0)
    if "weights" in mesh:
        weights = numbers(doc, mesh["weights"], target_count or 0, f"meshes[{index}].weights")
    # float64 whatever the accessors' type: integer positions (KHR_mesh_quantization without
    # normalization) gave an int64 base, to which the morph targets' float deltas could not be
    # added in place (found by fuzzing the glTF reader, tools.fuzz)
    base = np.concatenate(bases).astype(np.float64)
    return Mesh(base, np.concatenate(targets, axis=1), np.concatenate(faces), weights)


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
