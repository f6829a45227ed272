"""The public surface, pinned so that nothing leaves it by accident; the sequence type's checks;
atomic output."""

from __future__ import annotations

import re

import numpy as np
import pytest

import tuckercodec
from tuckercodec import InputError, MeshSequence
from tuckercodec.atomic import write_atomic


def test_public_surface():
    assert sorted(tuckercodec.__all__) == sorted(
        [
            "Analysis",
            "ChecksumError",
            "Decoder",
            "DependencyError",
            "EncodeReport",
            "EncodeResult",
            "FileInfo",
            "FormatError",
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
            "info",
            "kg_error",
            "load_sequence",
            "max_vertex_displacement",
            "read_compressed",
            "relative_error",
            "save_sequence",
            "sted",
        ]
    )
    assert re.fullmatch(r"\d+\.\d+\.\d+", tuckercodec.__version__)
    assert issubclass(InputError, tuckercodec.TuckerCodecError) and issubclass(InputError, ValueError)


def test_sequence_checks_its_arrays():
    vertices = np.zeros((2, 4, 3))
    quads = np.array([[0, 1, 2, 3], [0, 1, 2, -1]])
    seq = MeshSequence(vertices, quads)
    assert seq.frame_names == ["frame_00000", "frame_00001"]
    assert seq.triangles().tolist() == [[0, 1, 2], [0, 1, 2], [0, 2, 3]]
    with pytest.raises(InputError, match="outside 0..3"):
        MeshSequence(vertices, np.array([[0, 1, 4]]))
    with pytest.raises(InputError, match="padded before its end"):
        MeshSequence(vertices, np.array([[0, -1, 1, 2]]))
    bad = vertices.copy()
    bad[1, 2, 0] = np.inf
    with pytest.raises(InputError, match="frame 1: vertex 2 has a non-finite"):
        MeshSequence(bad, quads)
    with pytest.raises(InputError, match="shape"):
        MeshSequence(np.zeros((4, 3)), quads)
    with pytest.raises(InputError, match="frame names"):
        MeshSequence(vertices, quads, frame_names=["a"])


def test_atomic_write_never_leaves_half_a_file(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")

    def fail_halfway(handle):
        handle.write(b"new, partial")
        raise RuntimeError("disk full")

    with pytest.raises(FileExistsError):
        write_atomic(target, b"new")
    with pytest.raises(RuntimeError, match="disk full"):
        write_atomic(target, fail_halfway, overwrite=True)
    assert target.read_bytes() == b"old"
    write_atomic(target, b"new", overwrite=True)
    assert target.read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]
    # the same permissions as a file written by open(), not mkstemp's private 0600
    plain = tmp_path / "plain.bin"
    plain.write_bytes(b"x")
    assert target.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


def test_builtin_sample_is_the_shared_cloth_unchanged():
    from conftest import load_shared_npz

    from tuckercodec.samples import sample_path

    shipped = tuckercodec.load_sequence(sample_path(), progress=False)
    vertices, faces = load_shared_npz("cloth-vellum.npz")
    np.testing.assert_array_equal(shipped.vertices, vertices.astype(np.float64))
    np.testing.assert_array_equal(shipped.faces, faces)
    assert (sample_path().parent / "cloth-vellum.LICENSE.txt").read_text().count("MIT License") == 1
