"""The decoder's limits (spec/FORMAT.md §7): headers and sections that claim far more than the
file holds are refused before anything is allocated for them.

Each file is at most a few KB and lies about its sizes (a billion vertices, frames or ranks, 4
GiB of faces or names behind a bare zstd header, a 16 MiB header); decoding it fails with the
right error class, at once, and with a traced peak of a few MiB at most.
"""

from __future__ import annotations

import struct
import tracemalloc
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import IDENTITY_U2, Parts, deadline, vector, with_preamble
from tuckercodec import FormatError, LimitError, TruncatedFileError
from tuckercodec.format.container import pack_container
from tuckercodec.format.faces import encode_faces
from tuckercodec.format.streams import compress

#: Peak traced memory a file that lies about its sizes may cost.
CLAIM_PEAK_BYTES = 4 << 20


def traced_peak(action: Callable[[], object]) -> int:
    """Peak bytes traced by tracemalloc while ``action`` runs (numpy reports its buffers to
    tracemalloc, and zstandard's output is a Python bytes object, so both are counted)."""
    tracemalloc.start()
    try:
        action()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


def zstd_header_only(size: int) -> bytes:
    """A 16-byte 'frame': magic, a header declaring ``size`` bytes, one empty last raw block."""
    return b"\x28\xb5\x2f\xfd" + bytes([0b11100000]) + struct.pack("<Q", size) + b"\x01\x00\x00"


def _tiny(
    header: dict[str, Any], sections: list[tuple[dict[str, Any], bytes]] | None = None
) -> bytes:
    return pack_container({"u2": IDENTITY_U2, **header}, sections or [])


def _claiming(
    vertices: int,
    frames: int,
    i: int,
    k: int,
    *,
    faces: np.ndarray | None = None,
    lie_in: tuple[str, ...] = ("FACE", "U1", "U3", "CORE", "CENT"),
) -> bytes:
    """A small file whose sections have the shapes a header of these sizes implies, every
    payload in ``lie_in`` a 16-byte zstd header that claims the whole size; others real."""
    faces = np.zeros((0, 3), np.int64) if faces is None else faces
    face_params, face_payload = encode_faces(faces)
    sections = [
        ({"id": "FACE", "critical": True, "codec": "faces-delta", **face_params}, face_payload)
    ]
    for section_id, rows, cols in [
        ("U1", vertices, i),
        ("U3", frames, k),
        ("CORE", i * 3 * k, 1),
        ("CENT", frames, 3),
    ]:
        payload = (
            zstd_header_only(rows * cols) if section_id in lie_in else compress(bytes(rows * cols))
        )
        sections.append(
            (
                {
                    "id": section_id,
                    "critical": True,
                    "codec": "qmat",
                    "shape": [rows, cols],
                    "planes": 1,
                    "steps": np.ones(cols, "<f4").tobytes(),
                    "predict": bytes(cols),
                },
                payload,
            )
        )
    return pack_container(
        {"vertices": vertices, "frames": frames, "ranks": [i, k], "u2": IDENTITY_U2}, sections
    )


BILLION = 10**9


CLAIMS: dict[str, tuple[Callable[[], bytes], type[FormatError]]] = {
    "a billion vertices": (
        lambda: _tiny({"vertices": BILLION, "frames": 10, "ranks": [5, 5]}),
        LimitError,
    ),
    "a billion frames": (
        lambda: _tiny({"vertices": 10, "frames": BILLION, "ranks": [5, 5]}),
        LimitError,
    ),
    "a billion of both": (
        lambda: _tiny({"vertices": BILLION, "frames": BILLION, "ranks": [BILLION, BILLION]}),
        LimitError,
    ),
    "a billion ranks": (
        lambda: _tiny({"vertices": 2**20, "frames": 2**8, "ranks": [BILLION, BILLION]}),
        FormatError,
    ),
    "2**64-1 vertices": (
        lambda: _tiny({"vertices": 2**64 - 1, "frames": 1, "ranks": [1, 1]}),
        LimitError,
    ),
    "K*F beyond max_positions": (
        lambda: _tiny({"vertices": 2**26, "frames": 2**24, "ranks": [1, 1]}),
        LimitError,
    ),
    "ranks beyond max_factor_values": (
        lambda: _tiny({"vertices": 2**20, "frames": 2**8, "ranks": [768, 256]}),
        LimitError,
    ),
    "max_vertices, payloads that cannot hold them": (
        lambda: _claiming(2**26, 1, 1, 1),
        FormatError,
    ),
    "max_frames, payloads that cannot hold them": (
        lambda: _claiming(1, 2**24, 1, 3, lie_in=("U3", "CENT")),
        FormatError,
    ),
    "max_vertices, only U1 lies": (lambda: _claiming(2**26, 1, 1, 1, lie_in=("U1",)), FormatError),
    "max_vertices, a face, U1 lies": (
        lambda: _claiming(2**26, 1, 1, 1, faces=np.array([[0, 1, 2**26 - 1]]), lie_in=("U1",)),
        FormatError,
    ),
    "max_factor_values in U1 and CORE": (lambda: _claiming(2**24, 8, 7, 8), FormatError),
}


def _face_claim(rows: int, cols: int, planes: int = 4) -> bytes:
    parts = Parts(vector("v1-wave-triangles"))
    index = parts.index("FACE")
    entry, _ = parts.sections[index]
    parts.sections[index] = (
        {**entry, "shape": [rows, cols], "planes": planes},
        zstd_header_only(rows * cols * planes),
    )
    return parts.pack()


def _name_claim(size: int) -> bytes:
    parts = Parts(vector("v1-polygons-names"))
    index = parts.index("NAME")
    entry, _ = parts.sections[index]
    parts.sections[index] = ({**entry, "size": size}, zstd_header_only(size))
    return parts.pack()


CLAIMS.update(
    {
        "2**28 faces of 4 corners in 16 bytes": (lambda: _face_claim(2**28, 4), FormatError),
        "faces beyond max_section_bytes": (lambda: _face_claim(2**28, 5), LimitError),
        "faces beyond max_faces": (lambda: _face_claim(2**28 + 1, 3), LimitError),
        "faces of 65 corners": (lambda: _face_claim(10, 65), LimitError),
        "4 GiB of names in 16 bytes": (lambda: _name_claim(2**32), FormatError),
        "names beyond max_section_bytes": (lambda: _name_claim(2**32 + 1), LimitError),
        "a 16 MiB header in a small file": (
            lambda: with_preamble(
                vector("v1-wave-triangles"), header_length=16 << 20, total=(16 << 20) + 36
            ),
            TruncatedFileError,
        ),
        "2**64-1 total bytes": (
            lambda: with_preamble(vector("v1-wave-triangles"), total=2**64 - 1),
            TruncatedFileError,
        ),
    }
)


@pytest.fixture(scope="module")
def decoder_imports() -> None:
    """The modules the decoder imports on first use (the mesh prediction's graph search):
    imported before a case is timed, as importing them is not the file's cost and took more
    than the case's 2 s under tracemalloc on a busy core."""
    import scipy.sparse.csgraph  # noqa: F401


@pytest.mark.usefixtures("decoder_imports")
@pytest.mark.parametrize("case", list(CLAIMS))
def test_claims_beyond_the_file_cost_no_memory(case):
    """Each file is at most a few KB and lies about its sizes; decoding it must fail with the
    right error, at once, with a traced peak under CLAIM_PEAK_BYTES (the file included)."""
    build, kind = CLAIMS[case]
    data = build()
    assert len(data) < 4096, len(data)
    errors: list[FormatError] = []

    def attempt() -> None:
        for read in (tuckercodec.decode, tuckercodec.info):
            try:
                read(data)
            except FormatError as error:
                errors.append(error)

    with deadline():  # a hang guard: the bound is the traced peak, the same on any machine
        peak = traced_peak(attempt)
    assert errors and isinstance(errors[0], kind), f"{case}: {errors!r}"
    assert type(errors[0]) is kind, f"{case}: {errors[0]!r}"
    assert peak < CLAIM_PEAK_BYTES, f"{case}: {peak / 2**20:.1f} MiB traced"


def test_a_billion_vertex_header_in_200_bytes():
    data = _tiny({"vertices": BILLION, "frames": BILLION, "ranks": [BILLION, BILLION]})
    assert len(data) <= 200

    def attempt() -> None:
        with pytest.raises(LimitError):
            tuckercodec.decode(data)

    assert traced_peak(attempt) < 1 << 20
