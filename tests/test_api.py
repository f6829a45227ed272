"""The public surface, pinned so that nothing leaves it by accident."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

import tuckercodec
from tuckercodec import InputError
from tuckercodec.io.samples import sample_path


def test_public_surface():
    assert sorted(tuckercodec.__all__) == sorted(
        [
            "Analysis",
            "Attribute",
            "FaceSet",
            "Field",
            "ChecksumError",
            "Decoder",
            "DependencyError",
            "EncodeOptions",
            "EncodeReport",
            "EncodeResult",
            "Encoder",
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
    )
    assert re.fullmatch(r"\d+\.\d+\.\d+", tuckercodec.__version__)
    assert all(issubclass(InputError, base) for base in (tuckercodec.TuckerCodecError, ValueError))


def test_every_public_name_is_found_where_the_package_says():
    # the names are imported on first use (PEP 562): each must come from its module, and the
    # lazy table must name exactly the public surface
    for name in tuckercodec.__all__:
        value = getattr(tuckercodec, name)
        if name != "__version__":
            assert value.__name__ == name, name
            assert value.__module__.startswith("tuckercodec."), name
    assert set(tuckercodec._PUBLIC) | {"__version__"} == set(tuckercodec.__all__)
    assert set(tuckercodec.__all__) <= set(dir(tuckercodec))
    assert tuckercodec.io.registry.__name__ == "tuckercodec.io.registry"  # submodules still work
    with pytest.raises(AttributeError, match="no_such_name"):
        tuckercodec.no_such_name  # noqa: B018


def test_decoding_imports_neither_the_encoder_nor_scipy_linalg(tmp_path):
    # a process that only decodes starts faster and smaller: the encoder (and scipy.linalg
    # under it), the format libraries and the cluster code stay unimported
    path = tmp_path / "sample.tkc"
    path.write_bytes(tuckercodec.encode(tuckercodec.load_sequence(sample_path()), target_kg=1.0))
    script = (
        "import sys, numpy, tuckercodec\n"
        "decoder = tuckercodec.Decoder(sys.argv[1])\n"
        "assert numpy.isfinite(decoder.frame(0)).all()\n"
        "assert numpy.isfinite(decoder.positions()).all()\n"
        "bad = ('tuckercodec.encoder', 'tuckercodec.decomposition.analysis', 'tuckercodec.io',"
        " 'scipy.linalg', 'trimesh', 'tuckercodec.system.parallel', 'asyncio')\n"
        "print(sorted(name for name in bad if name in sys.modules))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script, str(path)], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
