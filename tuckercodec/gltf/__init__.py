"""glTF 2.0: mesh sequences and the decomposition as morph animations that viewers play.

Modules, one job each: :mod:`.container` (the .glb/.gltf container and its buffers),
:mod:`.accessors` (typed arrays in and out of buffers), :mod:`.meshopt`
(EXT_meshopt_compression through the ``meshoptimizer`` package), :mod:`.animation` (samplers
and node transforms), :mod:`.reader` (a morph animation sampled into a sequence),
:mod:`.document` (the shared skeleton of written files), :mod:`.sequence_writer` (a sequence
as morph targets), :mod:`.decomposition` (a compressed file's Tucker basis as morph targets,
in three compression variants, with the KG error a viewer shows), :mod:`.quantization` (its
numbers rounded within the error budget) and :mod:`.decomposition_file` (their layout in the
file for each variant).

This package imports nothing of the codec; the decomposition writer takes any object with the
decoder's factor attributes.
"""
