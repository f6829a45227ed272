"""The public surface, pinned so that nothing leaves it by accident."""

from __future__ import annotations

import re

import tuckercodec
from tuckercodec import InputError


def test_public_surface():
    assert sorted(tuckercodec.__all__) == sorted(
        [
            "Analysis",
            "ChecksumError",
            "Decoder",
            "DependencyError",
            "EncodeOptions",
            "EncodeReport",
            "EncodeResult",
            "Encoder",
            "FileInfo",
            "FormatError",
            "FrameSource",
            "InputError",
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
    )
    assert re.fullmatch(r"\d+\.\d+\.\d+", tuckercodec.__version__)
    assert all(issubclass(InputError, base) for base in (tuckercodec.TuckerCodecError, ValueError))
