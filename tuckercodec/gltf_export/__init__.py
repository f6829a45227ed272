"""A compressed file's decomposition as a glTF morph animation that viewers play unaided.

Frame f of a file is ``c_f + Σ_b U3[f, b] · B_b`` with the basis shapes
``B_b = U1 · B[:, :, b]`` (K x 3, ``B[a, x, b] = Σ_c CORE[a, c, b] · U2[x, c]``, spec §8). The
glTF holds the same sum as a viewer evaluates it:

* the weights are U3's columns rescaled into 0..1, ``w_fb = (U3[f, b] - lo_b) / (hi_b - lo_b)``
  over the frames written, so that tools which store weights as normalized 8- or 16-bit
  integers (gltfpack does) keep them; the offsets go into the mesh,
  ``base = Σ_b lo_b · B_b``, and the ranges into the targets, ``T_b = (hi_b - lo_b) · B_b``;
* the centroids ``c_f`` are the translation track of the root node (in the quantized
  variants plus the rigid shift of the targets' offsets, :mod:`.quantization`), the mesh sits
  on a child node (which holds the dequantization of the quantized variants);
* one keyframe per frame at its time in seconds: the frame's time code (the file's, format 1.4,
  else its number in the file, or in the part written) over the file's frame rate, 24 when the
  file records none.

Variants (``compress``): ``none``, float32 everywhere; ``quantize`` (the default),
KHR_mesh_quantization: mesh and targets as normalized 16-bit integers, dequantized by the
child node's scale and translation, the weights as normalized 8- or 16-bit integers where the
budget allows; ``meshopt``, EXT_meshopt_compression (three.js needs its MeshoptDecoder
registered to load it): the targets as 16-bit integers at the coarsest step the budget allows,
the base, weights and translation float32 with the EXPONENTIAL filter, the triangles in vertex
cache order. The rounding follows from an error budget, not a fixed bit count
(:mod:`.quantization`).

Layout in the file. Nodes: the root ``tuckercodec`` carries the translation track (the
centroids, plus the targets' offsets in the quantized variants), its child ``decomposition``
the mesh and, quantized, the dequantization (translation and uniform scale). One animation,
LINEAR: the mesh's ``weights`` and the root's ``translation``, a keyframe per frame. Per
variant:

* ``none``: float32 everywhere, a buffer view per array.
* ``quantize`` (KHR_mesh_quantization): the base and the targets as normalized SHORT VEC3 (8-byte
  stride), every target in one buffer view (one view instead of k keeps the JSON small); the
  weights as normalized UNSIGNED_BYTE or UNSIGNED_SHORT where the budget allows, else float32.
* ``meshopt`` (EXT_meshopt_compression, vertex codec 0): the targets as above, integers >= 0;
  the base, the weights and the translation float32 with the EXPONENTIAL filter (each a
  multiple of its power-of-two step); the weights' codec stride one keyframe (k weights) where
  it fits the codec's 256 bytes, so it codes differences over time; the triangles reordered
  for the vertex cache (never the vertices) and coded with the index codec.

UVs and normals (:mod:`.surface`), where the sequence has them (``attributes``, by default the
decoder's): the first UV as TEXCOORD_0, per-corner UVs splitting vertices as the sequence writer
does; the normals as a NORMAL and an offset per target fitted to every frame's recomputed
normals (float32; the meshopt variant rounds the offsets to 2^-12 under the EXPONENTIAL
filter). A sequence without normals gets none: viewers compute flat normals, and the file keeps
its size.

It sits beside :mod:`tuckercodec.files` rather than in :mod:`tuckercodec.io`: it takes a
decoder, not a sequence. The glTF container and accessors are :mod:`tuckercodec.io.gltf`'s.
"""

from .export import (
    COMPRESSIONS,
    DEFAULT_COMPRESSION,
    Compression,
    Decomposed,
    GltfReport,
    decomposition_bytes,
    morph_parts,
    write_decomposition_gltf,
)

__all__ = [
    "COMPRESSIONS",
    "DEFAULT_COMPRESSION",
    "Compression",
    "Decomposed",
    "GltfReport",
    "decomposition_bytes",
    "morph_parts",
    "write_decomposition_gltf",
]
