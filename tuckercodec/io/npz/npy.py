"""The ``.npy`` sequence format: one NumPy array of positions, (frames, vertices, 3).

The array holds float32 or float64 numbers of either byte order, in C order (a (vertices, 3) array
is one frame); that is all a ``.npy`` holds, so faces come from ``--faces MESH``
(:attr:`ReadOptions.faces`, as for the point caches:
:func:`~tuckercodec.io.pointcache.cache_faces`), and without it the sequence is a point sequence.
The header is read and checked as in an ``.npz`` (:func:`.archive.npy_header`: never pickle), and
the file's size must be exactly what it declares, before anything is allocated.

It streams (:class:`NpyFrames`): a range of frames is read by offset with ``readinto``, a few MiB at
a time (:class:`~tuckercodec.model.sources.RawFrames`), so that reading a range costs its float64
array and nothing in proportion to the file. The file is not memory-mapped: mapped pages count in
the process's resident memory.

Writing: float32 where that is exact, else float64 (:meth:`MeshSequence.compact_vertices`);
faces, frame names, rate and time codes are not kept.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...errors import InputError
from ...model.sequence import MeshSequence
from ...model.sources import RawFrames
from ...system.atomic import atomic_output
from ...system.reading import open_input
from ..common.attached_keys import everything_attached
from ..pointcache import cache_faces, check_size
from ..registry import ReadOptions, WriteOptions
from .archive import npy_header

#: The numbers a .npy of positions may hold (either byte order).
_KINDS = ("f4", "f8")


class NpyFrames(RawFrames):
    """The frames of a ``.npy`` file, read by offset (see the module docstring)."""

    _what = "a .npy array"

    def __init__(self, path: Path, options: ReadOptions | None = None):
        options = options or ReadOptions()
        stream = open_input(path, self._what)
        try:
            if stream.read(len(np.lib.format.MAGIC_PREFIX)) != np.lib.format.MAGIC_PREFIX:
                raise InputError(
                    "is not a .npy array: it does not start with NumPy's signature", path=path
                )
            stream.seek(0)
            header = npy_header(stream, "its array", path)
            dtype, shape = header.dtype, header.positions()
            if dtype.kind != "f" or f"{dtype.kind}{dtype.itemsize}" not in _KINDS:
                raise InputError(
                    f"holds {dtype} numbers; a .npy of positions holds float32 or float64",
                    path=path,
                )
            if shape is None:
                raise InputError(
                    f"holds an array of shape {header.shape}, not (frames, vertices, 3)",
                    path=path,
                )
            if header.fortran_order and shape[0] > 1:
                raise InputError(
                    "holds its array in Fortran order, where a frame's numbers are scattered "
                    "over the file; save it in C order (numpy.save(path, "
                    "numpy.ascontiguousarray(array)))",
                    path=path,
                )
            check_size(
                header.size + header.data_bytes(),
                os.fstat(stream.fileno()).st_size,
                f"a {header.size}-byte header and {shape[0]} frames of {shape[1]} vertices "
                f"of {dtype}",
                path,
            )
        except BaseException:
            stream.close()
            raise
        self._stream = stream
        self._file, self._offset, self._dtype = path, header.size, dtype
        self._describe(path, shape[0], shape[1], cache_faces(options, shape[1], path))


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What a ``.npy`` cannot keep of ``seq``: every attribute, face set and field (it holds
    positions only)."""
    return everything_attached(seq)


def write_npy(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the positions as a ``.npy`` array, float32 where exact, else float64, atomically;
    faces, names, rate and time codes are not kept."""
    with atomic_output(path, overwrite=options.overwrite) as stream:
        np.save(stream, seq.compact_vertices(), allow_pickle=False)
