"""The ``.npz`` sequence format: one NumPy archive holding the whole sequence.

Keys: ``V`` positions (frames, vertices, 3), optionally ``F`` faces (0-based, -1 padding),
``frame_files`` (one name per frame), ``frame_rate`` and ``time_codes``. It is read with
:mod:`zipfile` and ``numpy.lib.format``, never with pickle, and every declared size is checked
against the file before anything is allocated (:mod:`.npz_archive`). :mod:`.npz_frames` reads
key ``V`` a range of frames at a time.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ...atomic import atomic_output
from ...errors import InputError
from ...sequence import MeshSequence
from ..registry import ReadOptions, SequenceFormat, WriteOptions
from ..streaming import FrameSource, SequenceFrames
from .archive import NpzArchive
from .frames import NpzFrames, Scattered


def read_npz(path: Path, options: ReadOptions | None = None) -> MeshSequence:
    """A sequence from an .npz archive (keys V, optional F, frame_files, frame_rate,
    time_codes); the archive format takes no read options.

    The archive is read with :mod:`zipfile` and each array with ``numpy.lib.format``, never
    with pickle. A member must be a ``.npy`` array, stored or deflated (what ``np.savez`` and
    ``np.savez_compressed`` write), not encrypted, and present once. Before an array is
    allocated, the shape and dtype in its header must account for exactly the bytes of its
    member, and the member's sizes must be possible for the file: a header that claims a
    billion vertices in a small file is refused without allocating anything, and reading
    every byte of the member makes zipfile check its CRC.
    """
    with NpzArchive(path) as archive:
        vertices = _npz_vertices(archive.array("V"), path)
        faces, names, rate, codes = archive.metadata(*vertices.shape[:2])
    try:
        return MeshSequence(vertices, faces, frame_names=names, frame_rate=rate, time_codes=codes)
    except InputError as error:
        raise InputError(error.reason, path=path, frame=error.frame) from None


def _npz_vertices(values: np.ndarray, path: Path) -> np.ndarray:
    """Key V as float64 (F, K, 3); a (K, 3) array is one frame."""
    if values.dtype.kind not in "fiu":
        raise InputError(f"key 'V' must hold real numbers, got dtype {values.dtype}", path=path)
    if values.ndim == 2:
        values = values[np.newaxis]
    if values.ndim != 3 or values.shape[2] != 3 or values.shape[0] < 1 or values.shape[1] < 1:
        raise InputError(
            f"key 'V' must have shape (frames, vertices, 3), got {values.shape}", path=path
        )
    with np.errstate(over="ignore"):  # a long double beyond float64 becomes inf, named below
        values = values.astype(np.float64)
    bad = ~np.isfinite(values)
    if bad.any():
        frame, vertex, _ = (int(i) for i in np.argwhere(bad)[0])
        raise InputError(
            f"key 'V': vertex {vertex} has a non-finite coordinate", path=path, frame=frame
        )
    return values


def write_npz(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as an .npz archive, atomically."""
    arrays: dict[str, Any] = {
        "V": np.asarray(seq.vertices, dtype=np.float64),
        "F": np.asarray(seq.faces, dtype=np.int64),
        "frame_files": np.array(seq.frame_names, dtype=str),
    }
    if seq.frame_rate is not None:
        arrays["frame_rate"] = np.float64(seq.frame_rate)
    if seq.time_codes is not None:
        arrays["time_codes"] = np.asarray(seq.time_codes, dtype=np.float64)
    # np.savez adds ".npz" to a file *name* without it, so it gets an open file instead
    with atomic_output(path, overwrite=options.overwrite) as stream:
        np.savez(stream, **arrays)


def open_npz(path: Path, options: ReadOptions) -> FrameSource:
    """The frames of an .npz archive, a range at a time (:mod:`.npz_frames`); a ``V`` in
    Fortran order, whose frames are scattered over its member, is read whole."""
    try:
        return NpzFrames(path)
    except Scattered:
        return SequenceFrames(read_npz(path, options), path)


FORMAT = SequenceFormat(
    name="npz",
    suffixes=(".npz",),
    description=(
        "NumPy archive: V (frames, vertices, 3), F faces, frame_files, frame_rate, time_codes"
    ),
    read=read_npz,
    write=write_npz,
    open=open_npz,
    carries=frozenset({"float64", "faces", "polygons", "frame_names", "frame_rate", "time_codes"}),
)
