"""The bytes of the decomposition's glTF (:mod:`.decomposition`), laid out for each variant.

Nodes: the root ``tuckercodec`` carries the translation track (the centroids, plus the
targets' offsets in the quantized variants, :mod:`.quantization`), its child
``decomposition`` the mesh and, quantized, the dequantization (translation and uniform
scale). One animation, LINEAR: the mesh's ``weights`` and the root's ``translation``, a
keyframe per frame.

Layouts:

* ``none``: float32 everywhere, a buffer view per array.
* ``quantize`` (KHR_mesh_quantization): the base and the targets as normalized SHORT VEC3 (8-byte
  stride), every target in one buffer view (one view instead of k keeps the JSON small); the
  weights as normalized UNSIGNED_BYTE or UNSIGNED_SHORT where the budget allows, else float32.
* ``meshopt`` (EXT_meshopt_compression, vertex codec 0): the targets as above, integers >= 0;
  the base, the weights and the translation float32 with the EXPONENTIAL filter (each a
  multiple of its power-of-two step); the weights' codec stride one keyframe (k weights) where
  it fits the codec's 256 bytes, so it codes differences over time; the triangles reordered
  for the vertex cache (never the vertices) and coded with the index codec.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..io.gltf.accessors import ARRAY_BUFFER, BufferBuilder, padded_rows
from ..io.gltf.document import add_triangles, file_bytes, new_gltf
from .quantization import Quantized, weight_values

_MAX_CODEC_STRIDE = 256  # EXT_meshopt_compression's ATTRIBUTES mode


def decomposition_bytes(
    path: Path,
    triangles: np.ndarray,
    times: np.ndarray,
    weights: np.ndarray,
    base: np.ndarray,
    targets: np.ndarray,
    centroids: np.ndarray,
    quantized: Quantized | None,
    compress: str,
) -> bytes:
    """The file: ``weights`` (F, k), ``base`` (K, 3), ``targets`` (k, K, 3) and ``centroids``
    (F, 3) as :func:`~.decomposition.morph_parts` gives them (written as float32 when
    ``quantized`` is None), else the stored numbers of ``quantized``."""
    builder = BufferBuilder()
    extensions = []
    child: dict[str, Any] = {"name": "decomposition", "mesh": 0}
    filtered = compress == "meshopt"
    if quantized is None:
        position = builder.add_accessor(
            base.astype(np.float32), target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
        )
        morphs = [
            builder.add_accessor(
                t.astype(np.float32), target=ARRAY_BUFFER, bounds=True, vertex_attribute=True
            )
            for t in targets
        ]
        stored_weights = weights.astype(np.float32)
        shown_weights = stored_weights
        translation = centroids.astype(np.float32)
        weight_codec = translation_codec = None
    else:
        extensions.append("KHR_mesh_quantization")
        child["translation"] = [float(v) for v in quantized.offset]
        child["scale"] = [float(quantized.scale)] * 3
        base_codec = _exponential(quantized.base_exponents, 12)
        position = builder.add_accessor(
            quantized.base,
            target=ARRAY_BUFFER,
            bounds=True,
            normalized=quantized.base.dtype == np.int16,
            vertex_attribute=True,
            codec=base_codec,
        )
        morphs = _shared_targets(builder, quantized.targets)
        stored_weights = quantized.weights
        shown_weights = weight_values(stored_weights)
        translation = quantized.translation
        weight_codec = _weight_codec(quantized.weight_exponents, len(stored_weights))
        translation_codec = _exponential(quantized.translation_exponents, 12)
    primitive: dict[str, Any] = {"attributes": {"POSITION": position}}
    if filtered and len(triangles):
        from ..io.gltf.meshopt import vertex_cache_order

        triangles = vertex_cache_order(triangles, len(base))
    add_triangles(builder, primitive, triangles, len(base))
    primitive["targets"] = [{"POSITION": m} for m in morphs]
    mesh = {
        "name": "decomposition",
        "primitives": [primitive],
        "weights": [float(w) for w in shown_weights[0].astype(np.float32)],
    }
    key_times = builder.add_accessor(times, bounds=True)
    samplers = [
        {
            "input": key_times,
            "output": builder.add_accessor(
                stored_weights.reshape(-1),
                normalized=stored_weights.dtype != np.float32,
                codec=weight_codec,
            ),
            "interpolation": "LINEAR",
        },
        {
            "input": key_times,
            "output": builder.add_accessor(translation, codec=translation_codec),
            "interpolation": "LINEAR",
        },
    ]
    gltf = new_gltf(extensions)
    gltf.update(
        {
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [
                {
                    "name": "tuckercodec",
                    "children": [1],
                    "translation": [float(v) for v in translation[0]],
                },
                child,
            ],
            "meshes": [mesh],
            "animations": [
                {
                    "name": "decomposition",
                    "samplers": samplers,
                    "channels": [
                        {"sampler": 0, "target": {"node": 1, "path": "weights"}},
                        {"sampler": 1, "target": {"node": 0, "path": "translation"}},
                    ],
                }
            ],
        }
    )
    if filtered:
        return _meshopt_file(gltf, builder, path)
    return file_bytes(gltf, builder, path)


def _shared_targets(builder: BufferBuilder, targets: np.ndarray) -> list[int]:
    """Every target (k, K, 3) int16 in one buffer view of 8-byte rows, an accessor each."""
    count, vertices = targets.shape[:2]
    if count == 0:
        return []
    rows = padded_rows(targets.reshape(-1, 3), 8)
    view = builder.add_view(rows, 6, byteStride=8, target=ARRAY_BUFFER)
    return [
        builder.add_accessor(
            target, view=view, byte_offset=b * vertices * 8, normalized=True, bounds=True
        )
        for b, target in enumerate(targets)
    ]


def _exponential(exponents: np.ndarray | None, stride: int) -> dict[str, Any] | None:
    """The codec of float32 rows of ``stride`` bytes with the EXPONENTIAL filter, if any."""
    if exponents is None:
        return None
    return {"stride": stride, "exponents": exponents}


def _weight_codec(exponents: np.ndarray | None, frames: int) -> dict[str, Any] | None:
    """The weights' codec: a keyframe's k weights per codec row where they fit in 256 bytes
    (differences over time), else one weight per row; each target's exponent."""
    if exponents is None:
        return None
    count = len(exponents)
    if 0 < 4 * count <= _MAX_CODEC_STRIDE:
        return {"stride": 4 * count, "exponents": exponents}
    return {"stride": 4, "exponents": np.tile(exponents, frames)}


def _meshopt_file(gltf: dict[str, Any], builder: BufferBuilder, path: Path) -> bytes:
    from ..io.gltf.container import pack_glb, pack_gltf
    from ..io.gltf.meshopt import EXTENSION, compress_views

    views, binary, fallback = compress_views(
        builder.views, builder.view_data, builder.view_elements, builder.view_codecs
    )
    gltf = dict(gltf)
    gltf["extensionsUsed"] = sorted({*gltf.get("extensionsUsed", []), EXTENSION})
    gltf["extensionsRequired"] = sorted({*gltf.get("extensionsRequired", []), EXTENSION})
    gltf["accessors"] = builder.accessors
    gltf["bufferViews"] = views
    gltf["buffers"] = [
        {"byteLength": len(binary)},
        {"byteLength": fallback, "extensions": {EXTENSION: {"fallback": True}}},
    ]
    if path.suffix.lower() == ".gltf":
        return pack_gltf(gltf, binary)
    return pack_glb(gltf, binary)
