"""What PC2 and MDD share: the header read and checked against the file's size, the faces taken from
--faces, and positions made ready for writing."""

from __future__ import annotations

import os
from pathlib import Path
from typing import BinaryIO

import numpy as np

from ...errors import InputError
from ...model.sequence import MeshSequence, float32_vertices
from ...model.sources import RawFrames, as_float64
from ...system.reading import open_input
from ..registry import ReadOptions

#: Bytes of one point: three float32 coordinates.
POINT_BYTES = 12
#: The largest count an int32 header field can hold, and so the largest a cache can declare.
INT32_MAX = 2**31 - 1


class CacheFrames(RawFrames):
    """A point cache's frames, read by offset: what PC2 and MDD share. The file's header is read
    first (:meth:`_open_header`), its counts checked against the file's size, then the place
    and type of the positions and the faces of ``--faces`` set (:meth:`_positions_at`)."""

    def _open_header(self, path: Path, size: int) -> tuple[BinaryIO, bytes, int]:
        """The open file, its first ``size`` bytes (an InputError if it is shorter) and its
        size in bytes."""
        stream, file_size = open_cache(path, self._what)
        try:
            return stream, read_header(stream, size, file_size, self._what, path), file_size
        except BaseException:
            stream.close()
            raise

    def _positions_at(
        self,
        path: Path,
        options: ReadOptions,
        offset: int,
        dtype: str,
        counts: tuple[int, int],
        timing: tuple[float | None, np.ndarray | None] = (None, None),
    ) -> None:
        """The ``counts`` (frames, points) of positions of ``dtype`` start at ``offset``;
        ``timing`` is the frame rate and time codes; the faces are ``options.faces``'s."""
        faces = cache_faces(options, counts[1], path)
        self._file, self._offset, self._dtype = path, offset, np.dtype(dtype)
        self._describe(path, *counts, faces, frame_rate=timing[0], time_codes=timing[1])


def open_cache(path: Path, what: str) -> tuple[BinaryIO, int]:
    """Open a point cache for reading: the stream and the file's size in bytes."""
    stream = open_input(path, what)
    return stream, os.fstat(stream.fileno()).st_size


def read_header(stream: BinaryIO, size: int, file_size: int, what: str, path: Path) -> bytes:
    """The first ``size`` bytes of the file, or an InputError if it is shorter."""
    if file_size < size:
        raise InputError(
            f"is {file_size} bytes, shorter than the {size}-byte header of {what}: it is "
            "truncated or not such a file",
            path=path,
        )
    return stream.read(size)


def check_counts(frames: int, points: int, path: Path) -> None:
    """Refuse a header whose frame or point count is negative or zero."""
    for name, value in (("frame", frames), ("point", points)):
        if value < 0:
            raise InputError(f"declares a negative {name} count ({value})", path=path)
        if value == 0:
            raise InputError(f"declares 0 {name}s: there is nothing to read", path=path)


def check_size(declared: int, actual: int, layout: str, path: Path) -> None:
    """Refuse a file whose size is not the ``declared`` size (computed from its header, with
    Python integers so that no count can overflow); ``layout`` says how it was computed."""
    if actual < declared:
        raise InputError(
            f"is truncated: {layout} make {declared} bytes, but the file has {actual} "
            f"({declared - actual} missing)",
            path=path,
        )
    if actual > declared:
        raise InputError(
            f"has {actual - declared} trailing bytes: {layout} make {declared} bytes, but the "
            f"file has {actual}",
            path=path,
        )


def read_floats(stream: BinaryIO, count: int, dtype: str, path: Path) -> np.ndarray:
    """``count`` float32 values of byte order ``dtype`` ('<f4' or '>f4') from the stream's
    position, as float64; the caller has checked that the file holds them."""
    data = stream.read(count * 4)
    if len(data) != count * 4:  # the file shrank after its size was checked
        raise InputError(f"ended after {len(data)} of the {count * 4} bytes it declares", path=path)
    return as_float64(np.frombuffer(data, dtype=dtype))


def cache_faces(options: ReadOptions, point_count: int, path: Path) -> np.ndarray:
    """The faces the cache's points take: those of the mesh file ``options.faces`` (any file
    :func:`~tuckercodec.io.load_sequence` reads: OBJ, PLY, .npz..., read within the options'
    ``max_memory``), whose vertex count must be the cache's point count; without one, no faces
    (a point sequence)."""
    faces_file = options.faces
    if faces_file is None:
        return np.zeros((0, 3), dtype=np.int64)
    from .. import load_sequence  # here: the package imports the formats' registry

    mesh = load_sequence(faces_file, progress=False, max_memory=options.max_memory)
    if mesh.faces.shape[0] == 0:
        raise InputError(
            f"has no faces to give the points of the cache {path} (--faces names a mesh file)",
            path=faces_file,
        )
    if mesh.vertex_count != point_count:
        raise InputError(
            f"holds {point_count} points but the --faces mesh {faces_file} has "
            f"{mesh.vertex_count} vertices: it must be the mesh the cache was made from",
            path=path,
        )
    return mesh.faces


def float32_positions(seq: MeshSequence, dtype: str, path: Path) -> np.ndarray:
    """The sequence's positions as float32 of byte order ``dtype``, ready to write; a
    position beyond float32's range (which would become infinite) is an InputError."""
    if seq.frame_count > INT32_MAX or seq.vertex_count > INT32_MAX:
        raise InputError(
            f"{seq.frame_count} frames of {seq.vertex_count} points do not fit the 32-bit "
            f"counts of {path.name}"
        )
    return float32_vertices(seq, path, dtype)
