"""tuckercodec: compression of animated meshes by truncated higher-order SVD (Tucker).

The public API::

    seq = load_sequence("frames/")        # folder of OBJ files, glob, list of paths, or .npz
    result = analyze(seq)                  # exact rate-distortion table of every (i, 3, k)
    result.cheapest(0.1)                   # the smallest truncation meeting a KG error of 0.1 %
    save_sequence(seq, "out/")             # OBJ frames with their faces, or an .npz

Errors are KG errors (Karni-Gotsman, per-frame centroid) unless a name says otherwise.
"""

from ._version import __version__
from .analysis import Analysis, RankChoice, analyze
from .errors import InputError, TuckerCodecError
from .metrics import bpfv, kg_error, max_vertex_displacement, relative_error
from .seqio import load_sequence, save_sequence
from .sequence import MeshSequence

__all__ = [
    "Analysis",
    "InputError",
    "MeshSequence",
    "RankChoice",
    "TuckerCodecError",
    "__version__",
    "analyze",
    "bpfv",
    "kg_error",
    "load_sequence",
    "max_vertex_displacement",
    "relative_error",
    "save_sequence",
]
