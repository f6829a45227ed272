"""What a viewer shades beside the positions of an exported morph animation: the UVs and the
normals of the sequence, where it has them.

* UVs: the first attribute of role ``uv`` is written as TEXCOORD_0 (float32). Per-corner UVs
  (seams) split vertices as the sequence writer does (:mod:`tuckercodec.io.gltf.split`): one
  glTF vertex per vertex and UV, each with its vertex's base and targets (the file then has K'
  >= K vertices).
* Normals, only where the sequence has a ``normal`` attribute (without one a viewer computes
  flat normals, correct at every frame, and the file keeps its size): the normals of every
  exported frame are recomputed from its decoded positions with the split structure of that
  attribute (:mod:`tuckercodec.io.gltf.normals`), and fitted in the least-squares sense by
  what a viewer evaluates, ``NORMAL + Σ_b w_fb · D_b`` with the frame's morph weights: NORMAL
  is the unit intercept of the fit, each target's NORMAL offset D_b the best fit given it. A
  viewer normalizes the sum, so the normals follow the animation as far as a linear blend of k
  offsets can (exactly when the normals are linear in the weights, closely for the smooth
  motions the decomposition keeps). Cost: float32, 12 bytes per vertex for NORMAL and 12 more
  per vertex per target, about 1.5 times what the quantized targets' positions take (8 bytes);
  the meshopt variant rounds the offsets to 2^-12 for its codec. Measured on the cloth sample
  (3101 vertices, 14 targets, KG 0.1): quantize 414 KB, 439 KB with UVs, 999 KB with UVs and
  normals; meshopt 140, 163 and 433 KB. Normals are worth it where lighting matters; static
  normals would cost only the 12 bytes per vertex but light every frame as the first.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..io.gltf.normals import recomputed_corner_normals
from ..io.gltf.split import SplitLayout, split_vertices
from ..model.attributes import NORMAL, UV, VERTEX, Attribute


@dataclass
class Surface:
    """The written vertices (``layout``), a written vertex of each vertex (``representative``,
    (K,)), the base vertex attributes by semantic ((K', c) float32) and each target's NORMAL
    offsets ((k, K', 3) float32, or None)."""

    layout: SplitLayout
    representative: np.ndarray
    attributes: dict[str, np.ndarray]
    normal_offsets: np.ndarray | None


def surface_of(
    faces: np.ndarray,
    attributes: Sequence[Attribute],
    decoded: np.ndarray,
    weights: np.ndarray,
) -> Surface | None:
    """The surface of the frames ``decoded`` (F, K, 3) drawn with morph ``weights`` (F, k), or
    None where ``attributes`` hold neither a UV nor a normal."""
    uv = next((a for a in attributes if a.role == UV), None)
    normal = next((a for a in attributes if a.role == NORMAL), None)
    if uv is None and normal is None:
        return None
    vertex_count = decoded.shape[1]
    layout = split_vertices(faces, vertex_count, [a for a in (uv, normal) if a is not None])
    representative = np.empty(vertex_count, dtype=np.int64)
    representative[layout.vertex_of[::-1]] = np.arange(layout.count)[::-1]
    written: dict[str, np.ndarray] = {}
    offsets = None
    if uv is not None:
        with np.errstate(over="ignore"):
            written["TEXCOORD_0"] = layout.expanded(uv, faces).astype(np.float32)
    if normal is not None:
        written["NORMAL"], offsets = _fitted_normals(faces, normal, layout, decoded, weights)
    return Surface(layout, representative, written, offsets)


def _fitted_normals(
    faces: np.ndarray,
    normal: Attribute,
    layout: SplitLayout,
    decoded: np.ndarray,
    weights: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """NORMAL (K', 3) and the targets' offsets (k, K', 3) fitted to every frame's normals
    (module docstring), float32, from the normal equations summed a frame at a time."""
    count = weights.shape[1]
    design = np.column_stack([np.ones(len(weights)), weights])  # (F, k + 1)
    if normal.domain == VERTEX:
        fallback = normal.element_values().astype(np.float64)
    else:
        fallback = np.zeros((decoded.shape[1], 3))
    moments = np.zeros((count + 1, layout.count * 3))  # design^T · normals
    for frame, positions in enumerate(decoded):
        per_corner = recomputed_corner_normals(positions, faces, normal)
        normals = layout.corner_expanded(per_corner, fallback).reshape(-1)
        moments += design[frame][:, None] * normals[None]
    gram = design.T @ design
    intercept = (np.linalg.pinv(gram) @ moments)[0].reshape(-1, 3)
    length = np.linalg.norm(intercept, axis=1, keepdims=True)
    safe = np.where(length > 0, length, 1.0)
    base = np.where(length > 0, intercept / safe, np.array([0.0, 0.0, 1.0]))
    # the offsets given that unit base: weights^T weights D = weights^T (normals - base)
    sums = weights.sum(axis=0)
    right = moments[1:] - sums[:, None] * base.reshape(-1)[None]
    offsets = (np.linalg.pinv(gram[1:, 1:]) @ right).reshape(count, -1, 3)
    return base.astype(np.float32), offsets.astype(np.float32)
