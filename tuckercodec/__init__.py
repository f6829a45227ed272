"""tuckercodec: compression of animated meshes by truncated higher-order SVD (Tucker).

The public API::

    seq = load_sequence("frames/")        # folder of OBJ files, glob, list of paths, or .npz
    result = analyze(seq)                  # exact rate-distortion table of every (i, 3, k)
    result.cheapest(target_kg=0.1)         # the smallest truncation meeting a KG error
    save_sequence(seq, "out/")             # OBJ frames with their faces, or an .npz
"""

from ._version import __version__
from .errors import InputError, TuckerCodecError
from .sequence import MeshSequence

__all__ = [
    "InputError",
    "MeshSequence",
    "TuckerCodecError",
    "__version__",
]
