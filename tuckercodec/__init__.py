"""tuckercodec: compression of animated meshes by truncated higher-order SVD (Tucker).

The public API::

    seq = load_sequence("frames/")        # folder of OBJ files, glob, list of paths, or .npz
    result = analyze(seq)                  # exact rate-distortion table of every (i, 3, k)
    result.cheapest(0.1)                   # the smallest truncation meeting a KG error of 0.1 %
    save_sequence(seq, "out/")             # OBJ frames with their faces, or an .npz
    save_sequence(seq, "out.usdc")         # or any format of formats(): USD, Alembic, glTF...
    with open_frames("big.npy") as src:    # any of them, a range of frames at a time
        block = src.read(0, 64)            # (64, K, 3) float64, without loading the rest

    data = encode(seq, target_kg=0.1)      # a compressed file (spec/FORMAT.md) as bytes
    encoder = Encoder(EncodeOptions(target_bpfv=2.0, level=19))  # every option in one object
    data = encoder.encode(seq)             # ... for as many sequences as you like
    decode(data, frames=range(10, 20))     # any frames back, as a MeshSequence (or pass a path)
    info(data)                             # the header, without decoding anything

The package follows the pipeline: :mod:`~tuckercodec.io` reads and writes sequences,
:mod:`~tuckercodec.decomposition.hosvd` and :mod:`~tuckercodec.decomposition.analysis` decompose and
tabulate, :mod:`~tuckercodec.encoder` meets the target over :mod:`~tuckercodec.format` (the spec's
parts), and :mod:`~tuckercodec.decoder` rebuilds frames from it.

Errors are KG errors (Karni-Gotsman, per-frame centroid) unless a name says otherwise;
``sted(original, approx)`` is the perception-correlated STED of Váša and Skala (2011).
"""

from __future__ import annotations

import importlib
import importlib.util
from typing import TYPE_CHECKING, Any

from ._version import __version__

# Each public name and the module that defines it. They are imported when first used (PEP 562),
# so that a process that only decodes never imports the encoder, scipy.linalg or the format
# libraries: ``import tuckercodec`` took 0.6-1.3 s and 61 MB where numpy alone takes 0.15 s.
_PUBLIC = {
    "Analysis": "decomposition.analysis",
    "RankChoice": "decomposition.analysis",
    "analyze": "decomposition.analysis",
    "Decoder": "decoder",
    "FileInfo": "decoder",
    "decode": "decoder",
    "info": "decoder",
    "EncodeOptions": "encoder",
    "Encoder": "encoder",
    "EncodeReport": "encoder",
    "EncodeResult": "encoder",
    "encode": "encoder",
    "encode_with_report": "encoder",
    "ChecksumError": "errors",
    "DependencyError": "errors",
    "FormatError": "errors",
    "FormatVersionError": "errors",
    "InputError": "errors",
    "InternalError": "errors",
    "LimitError": "errors",
    "TruncatedFileError": "errors",
    "TuckerCodecError": "errors",
    "UnreachableTargetError": "errors",
    "UnsupportedVersionError": "errors",
    "decode_file": "files",
    "encode_file": "files",
    "read_compressed": "files",
    "Limits": "format.limits",
    "FrameSource": "io",
    "formats": "io",
    "load_sequence": "io",
    "open_frames": "io",
    "save_sequence": "io",
    "kg_error": "measures.distortion",
    "max_vertex_displacement": "measures.distortion",
    "relative_error": "measures.distortion",
    "sted": "measures.perceptual",
    "bpfv": "measures.rate",
    "MeshSequence": "model.sequence",
    "Attribute": "model.attributes",
    "FaceSet": "model.attributes",
    "Field": "model.attributes",
}

if TYPE_CHECKING:
    from .decoder import Decoder, FileInfo, decode, info
    from .decomposition.analysis import Analysis, RankChoice, analyze
    from .encoder import (
        EncodeOptions,
        Encoder,
        EncodeReport,
        EncodeResult,
        encode,
        encode_with_report,
    )
    from .errors import (
        ChecksumError,
        DependencyError,
        FormatError,
        FormatVersionError,
        InputError,
        InternalError,
        LimitError,
        TruncatedFileError,
        TuckerCodecError,
        UnreachableTargetError,
        UnsupportedVersionError,
    )
    from .files import decode_file, encode_file, read_compressed
    from .format.limits import Limits
    from .io import FrameSource, formats, load_sequence, open_frames, save_sequence
    from .measures.distortion import kg_error, max_vertex_displacement, relative_error
    from .measures.perceptual import sted
    from .measures.rate import bpfv
    from .model.attributes import Attribute, FaceSet, Field
    from .model.sequence import MeshSequence


def __getattr__(name: str) -> Any:
    """A public name, imported from its module on first use (then kept in this module), or a
    submodule (``tuckercodec.io`` works after a bare ``import tuckercodec``, as it used to)."""
    module = _PUBLIC.get(name)
    if module is None:
        if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}"):
            return importlib.import_module(f".{name}", __name__)  # the import binds it here
        raise AttributeError(f"module 'tuckercodec' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_PUBLIC})


__all__ = [
    "Analysis",
    "Attribute",
    "ChecksumError",
    "Decoder",
    "DependencyError",
    "EncodeOptions",
    "EncodeReport",
    "EncodeResult",
    "Encoder",
    "FaceSet",
    "Field",
    "FileInfo",
    "FormatError",
    "FormatVersionError",
    "FrameSource",
    "InputError",
    "InternalError",
    "LimitError",
    "Limits",
    "MeshSequence",
    "RankChoice",
    "TruncatedFileError",
    "TuckerCodecError",
    "UnreachableTargetError",
    "UnsupportedVersionError",
    "__version__",
    "analyze",
    "bpfv",
    "decode",
    "decode_file",
    "encode",
    "encode_file",
    "encode_with_report",
    "formats",
    "info",
    "kg_error",
    "load_sequence",
    "max_vertex_displacement",
    "open_frames",
    "read_compressed",
    "relative_error",
    "save_sequence",
    "sted",
]
