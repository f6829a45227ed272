"""The glTF 2.0 sequence format (``.glb``, ``.gltf``): morph targets and a weights animation,
and the glTF library it is written with.

Reading samples the first animation of the file's mesh as a viewer plays it, at the keyframes
or at ``--fps`` (:func:`.reader.read_gltf`); writing puts frame 0 in the mesh and every other
frame in a morph target, one keyframe per frame (:mod:`.writer`), exact to within the float32
rounding of base + target. A static glTF (no animation) is a one-frame sequence, so a folder of
.glb frames still reads one frame per file. :class:`GltfFrames` evaluates the frames a range at
a time.

Modules, one job each: :mod:`.container` (the .glb/.gltf container and its buffers),
:mod:`.accessors` (typed arrays in and out of buffers), :mod:`.meshopt`
(EXT_meshopt_compression through the ``meshoptimizer`` package), :mod:`.animation` (samplers
and node transforms), :mod:`.primitives` (a mesh's primitives merged), :mod:`.reader` (a morph
animation sampled into a sequence), :mod:`.timing` (its frame rate and time codes),
:mod:`.document` (the shared skeleton of written files) and :mod:`.writer` (a sequence as morph
targets). Beside positions: :mod:`.vertex_attributes` (attribute semantics read as values),
:mod:`.scene_attributes` (the meshes' attributes and materials as the sequence's),
:mod:`.attribute_writing` (attributes as semantics, and :func:`cannot_keep`), :mod:`.split`
(per-corner values as split vertices) and :mod:`.normals` (normals recomputed per frame). A
compressed file's decomposition written as glTF is :mod:`tuckercodec.gltf_export`, which uses
this library.
"""

from .attribute_writing import cannot_keep
from .sequence import (
    GltfFrames,
    read_gltf_frame,
    write_gltf,
)

__all__ = [
    "GltfFrames",
    "cannot_keep",
    "read_gltf_frame",
    "write_gltf",
]
