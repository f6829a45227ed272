"""Mesh sequences read a range of frames at a time: :class:`FrameSource`, which
:func:`~tuckercodec.io.open_frames` opens on any source :func:`~tuckercodec.io.load_sequence`
reads, so that a sequence larger than memory can be encoded in passes.

Which formats stream, and how (a format's
:attr:`~tuckercodec.io.registry.SequenceFormat.open`; the readers are in :mod:`tuckercodec.io`):

* ``.npy`` (``io.npz.npy``), PC2 and MDD (``io.pointcache``): by offset in the file
  (:class:`RawFrames`): a range is read with ``readinto`` in pieces of at most
  :data:`PIECE_BYTES`, so that reading costs the range's float64 array and no more. Nothing
  is memory-mapped: the pages of a mapped file count in the process's resident memory.
* ``.npz`` (``io.npz``): key ``V`` by offset when stored, by decompressing forward when
  deflated (the member stays open, so a forward read of ranges never starts again from the
  beginning; a range before the last one does).
* zarr stores (``io.zarr_store``): chunk by chunk, through zarr.
* Folders, globs and lists of one-frame files (``io.frames``): file by file.
* VTK series (``io.vtk``) and XDMF (``io.xdmf``): time step by time step (an XDMF's XML,
  with any inline data, is held; its HDF5 datasets are read per step).
* glTF (``io.gltf``): the file is held and the frames of a range evaluated on demand.
* USD and Alembic (``io.usd``, ``io.alembic``): sample by sample, in a child process that
  stays open for the source's life (``io.isolation``), so that a crash of the library
  is still an :class:`~tuckercodec.errors.InputError`.

Every format streams: ``open`` is the one way a whole-sequence format reads (``load()`` reads
all the frames). :class:`SequenceFrames` is a sequence in memory as a source.

Every source checks what it reads as :class:`~tuckercodec.model.sequence.MeshSequence` does (finite
positions, the first frame's vertex count and faces), when it reads it: an error in frame 900
is raised by the read of a range holding frame 900, naming the file and the frame. A source is
picklable, so that a process or a Dask worker can read its own ranges: it keeps its path and
options, and opens its files (or child process) again on first use after unpickling.
"""

from __future__ import annotations

import abc
import contextlib
import operator
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any, BinaryIO, ClassVar

import numpy as np

from ..errors import InputError
from ..system.reading import open_input
from .attributes import Attribute, FaceSet, Field, check_attached
from .sequence import (
    MeshSequence,
    checked_meters_per_unit,
    checked_time_codes,
    checked_up_axis,
    default_frame_names,
)
from .topology import checked_face_table

#: The most bytes of the file's own type that :class:`RawFrames` reads at a time (a frame more
#: if one frame is larger): what reading costs beyond the float64 array it returns.
PIECE_BYTES = 4 * 2**20


class FrameSource(abc.ABC):
    """A mesh sequence read a range of frames at a time.

    Attributes:
        path: the file or folder read, named in errors (``None`` if there is none).
        frame_count: F, the number of frames.
        vertex_count: K, the number of vertices of every frame.
        faces: (M, n) int64 as :class:`~tuckercodec.model.sequence.MeshSequence` holds them ((0, 3)
            for a point sequence).
        frame_names: F names (``frame_00000``... where the source has none).
        frame_rate: frames per second, if known.
        time_codes: each frame's time in frames, or ``None`` (0, 1, 2...).
        meters_per_unit: the length of a unit of the positions in metres, if known.
        up_axis: ``"Y"`` or ``"Z"``, if known.

    A source may hold open files or a child process: close it (or use ``with``) when done.
    It reads for one caller at a time; several threads need one source each.
    """

    path: str | None
    frame_count: int
    vertex_count: int
    faces: np.ndarray
    frame_names: list[str]
    frame_rate: float | None
    time_codes: np.ndarray | None
    meters_per_unit: float | None = None
    up_axis: str | None = None
    #: static attributes and face sets, read when the source is opened (empty by default)
    attributes: list[Attribute]
    face_sets: list[FaceSet]
    #: the names of the source's animated fields; :meth:`read_fields` reads them
    field_names: list[str]

    #: The attributes that hold open files or processes: ``None`` when closed or unpickled,
    #: opened again on first use (each needs a class-level default of ``None``).
    _transient: ClassVar[tuple[str, ...]] = ()
    #: How errors name the positions, before "vertex 5 has...": "key 'V': " in an .npz.
    _vertex_label: ClassVar[str] = ""

    def _describe(
        self,
        path: str | os.PathLike[str] | None,
        frame_count: int,
        vertex_count: int,
        faces: object,
        frame_names: list[str] | None = None,
        frame_rate: float | None = None,
        time_codes: object = None,
        meters_per_unit: object = None,
        up_axis: object = None,
        attributes: list[Attribute] | None = None,
        face_sets: list[FaceSet] | None = None,
        field_names: list[str] | None = None,
    ) -> None:
        """Set the description, checked as MeshSequence checks it; errors name ``path``.
        ``field_names``: the fields :meth:`_read_fields` reads (a source with fields
        overrides it)."""
        self.path = None if path is None else os.fspath(path)
        try:
            if frame_count < 1 or vertex_count < 1:
                raise InputError(
                    f"a sequence needs at least one frame and one vertex, got {frame_count} "
                    f"frames of {vertex_count} vertices"
                )
            self.frame_count, self.vertex_count = int(frame_count), int(vertex_count)
            self.faces = checked_face_table(faces, self.vertex_count)
            names = [str(name) for name in frame_names or default_frame_names(frame_count)]
            if len(names) != frame_count:
                raise InputError(f"{len(names)} frame names given for {frame_count} frames")
            self.frame_names = names
            if frame_rate is not None and not (np.isfinite(frame_rate) and frame_rate > 0):
                raise InputError(f"frame rate must be a positive number, got {frame_rate}")
            self.frame_rate = None if frame_rate is None else float(frame_rate)
            self.time_codes = None
            if time_codes is not None:
                self.time_codes = checked_time_codes(np.asarray(time_codes), frame_count)
            self.meters_per_unit = checked_meters_per_unit(meters_per_unit)
            self.up_axis = checked_up_axis(up_axis)
            self.attributes = list(attributes or [])
            self.face_sets = list(face_sets or [])
            self.field_names = list(field_names or [])
            check_attached(
                self.attributes, self.face_sets, [], frame_count, self.vertex_count, self.faces
            )
        except InputError as error:
            raise InputError(error.reason, path=error.path or path, frame=error.frame) from None

    def read(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop`` (excluded): a C-contiguous (stop - start, K, 3) float64
        array, the same numbers :func:`~tuckercodec.io.load_sequence` gives for them.

        Raises:
            ValueError: not a range of the frames (0 <= start <= stop <= frame_count).
            InputError: a frame of the range cannot be read, or has non-finite positions,
                another vertex count or other faces; names the file and the frame.
        """
        start, stop = operator.index(start), operator.index(stop)
        if not 0 <= start <= stop <= self.frame_count:
            raise ValueError(
                f"frames {start}:{stop} are not a range of the {self.frame_count} frames"
            )
        if start == stop:
            return np.empty((0, self.vertex_count, 3), dtype=np.float64)
        values = self._read(start, stop)
        values = np.ascontiguousarray(as_float64(values))  # non-finite: named below
        if values.shape != (stop - start, self.vertex_count, 3):  # a reader's bug, not the file's
            raise RuntimeError(f"{type(self).__name__} read {values.shape} for {start}:{stop}")
        with np.errstate(over="ignore", invalid="ignore"):
            total = values.sum()  # not finite if a coordinate is not (or, rarely, on overflow)
        if not np.isfinite(total):  # then look, with an array of the range's size
            bad = ~np.isfinite(values)
            if bad.any():
                frame, vertex, _ = (int(i) for i in np.argwhere(bad)[0])
                raise InputError(
                    f"{self._vertex_label}vertex {vertex} has a non-finite coordinate",
                    path=self.path,
                    frame=start + frame,
                )
        return values

    @abc.abstractmethod
    def _read(self, start: int, stop: int) -> np.ndarray:
        """The frames of a valid, non-empty range as an (n, K, 3) array of real numbers;
        :meth:`read` converts and checks them."""

    def read_fields(self, start: int, stop: int) -> list[Field]:
        """The animated fields (:attr:`field_names`) of frames ``start`` to ``stop``
        (excluded), each with ``stop - start`` rows; an InputError names the file and frame."""
        start, stop = operator.index(start), operator.index(stop)
        if not 0 <= start <= stop <= self.frame_count:
            raise ValueError(
                f"frames {start}:{stop} are not a range of the {self.frame_count} frames"
            )
        if not self.field_names:
            return []
        fields = self._read_fields(start, stop)
        if [item.name for item in fields] != self.field_names:  # a reader's bug
            raise RuntimeError(f"{type(self).__name__} read fields {[f.name for f in fields]}")
        return fields

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        """The fields of a valid range; a source with :attr:`field_names` overrides it."""
        raise NotImplementedError(f"{type(self).__name__} reads no fields")

    def blocks(self, size: int) -> Iterator[tuple[int, np.ndarray]]:
        """Every frame in order, ``size`` at a time: ``(start, read(start, start + size))``."""
        if size < 1:
            raise ValueError(f"a block holds at least one frame, not {size}")
        for start in range(0, self.frame_count, size):
            yield start, self.read(start, min(start + size, self.frame_count))

    def load(self, progress: bool = False) -> MeshSequence:
        """The whole sequence in memory; ``progress`` draws a progress bar on a terminal where
        the source reads many files (:class:`~.frames.FileFrames`), others read too fast to
        need one."""
        try:
            return MeshSequence(
                self.read(0, self.frame_count),
                self.faces,
                frame_names=self.frame_names,
                frame_rate=self.frame_rate,
                time_codes=self.time_codes,
                meters_per_unit=self.meters_per_unit,
                up_axis=self.up_axis,
                attributes=self.attributes,
                face_sets=self.face_sets,
                fields=self.read_fields(0, self.frame_count),
            )
        except InputError as error:
            raise InputError(
                error.reason, path=error.path or self.path, frame=error.frame
            ) from None

    @property
    def input_bytes(self) -> int:
        """F x K x 3 x 4: the size of the positions as float32, for throughput figures."""
        return self.frame_count * self.vertex_count * 12

    def close(self) -> None:
        """Close what the source holds open (it opens it again if read once more)."""
        for name in self._transient:
            handle = self.__dict__.get(name)
            setattr(self, name, None)
            if handle is not None and hasattr(handle, "close"):
                handle.close()

    def __enter__(self) -> FrameSource:
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()

    def __del__(self) -> None:
        with contextlib.suppress(Exception):  # at interpreter exit, or half-built
            self.close()

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        for name in self._transient:
            state[name] = None
        return state

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}({self.path!r}, frames={self.frame_count}, "
            f"vertices={self.vertex_count}, faces={self.faces.shape[0]})"
        )


class SequenceFrames(FrameSource):
    """A sequence in memory as a :class:`FrameSource` (for a format that cannot stream, or a
    sequence made by the program). ``read`` returns copies."""

    def __init__(self, sequence: MeshSequence, path: str | os.PathLike[str] | None = None):
        self.sequence = sequence
        self._describe(
            path,
            sequence.frame_count,
            sequence.vertex_count,
            sequence.faces,
            sequence.frame_names,
            sequence.frame_rate,
            sequence.time_codes,
            sequence.meters_per_unit,
            sequence.up_axis,
            sequence.attributes,
            sequence.face_sets,
            [item.name for item in sequence.fields],
        )

    def _read(self, start: int, stop: int) -> np.ndarray:
        return self.sequence.vertices[start:stop].copy()

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        return [
            Field(item.name, item.values[start:stop], item.domain, item.role)
            for item in self.sequence.fields
        ]

    def load(self, progress: bool = False) -> MeshSequence:
        return self.sequence


class FrameByFrame(FrameSource):
    """A source whose library reads one frame at a time (:meth:`_frame`: USD, Alembic); frame 0
    is read when the file is opened (for the vertex count) and kept in :attr:`_first`."""

    _first: np.ndarray

    def _read(self, start: int, stop: int) -> np.ndarray:
        vertices = np.empty((stop - start, self.vertex_count, 3), dtype=np.float64)
        for frame in range(start, stop):
            vertices[frame - start] = self._first if frame == 0 else self._frame(frame)
        return vertices

    @abc.abstractmethod
    def _frame(self, frame: int) -> np.ndarray:
        """Frame ``frame``'s positions, (K, 3), checked."""


class RawFrames(FrameSource):
    """Frames stored one after the other as a C-ordered array of numbers at an offset of a file
    (``.npy``, PC2, MDD, a stored ``.npz`` member), read by offset.

    Subclasses describe the file (:meth:`_describe`) and set :attr:`_file` (the file),
    :attr:`_offset` (where frame 0 starts) and :attr:`_dtype` (the numbers as stored, any byte
    order); :meth:`_read_at` may be replaced to read from something else than the file itself.
    """

    _transient: ClassVar[tuple[str, ...]] = ("_stream",)
    _file: Path
    _offset: int
    _dtype: np.dtype
    _stream: BinaryIO | None = None
    #: What the file is, for the error when it cannot be opened again ("a PC2 point cache").
    _what: str = "a file"

    def _read(self, start: int, stop: int) -> np.ndarray:
        out = np.empty((stop - start, self.vertex_count, 3), dtype=np.float64)
        frame_bytes = self.vertex_count * 3 * self._dtype.itemsize
        step = max(1, PIECE_BYTES // frame_bytes)
        same = self._dtype == out.dtype  # the file's own numbers: straight into the result
        piece = None if same else np.empty((min(step, len(out)), *out.shape[1:]), self._dtype)
        for first in range(0, len(out), step):
            count = min(step, len(out) - first)
            part = out[first : first + count] if piece is None else piece[:count]
            into = memoryview(part).cast("B")  # type: ignore[arg-type]  # arrays are buffers
            self._read_at(self._offset + (start + first) * frame_bytes, into)
            if piece is not None:  # cast into its place: no float64 copy of the piece
                with np.errstate(over="ignore", invalid="ignore"):  # as as_float64 says
                    out[first : first + count] = part  # non-finite: named later
        return out

    def _read_at(self, offset: int, into: memoryview) -> None:
        """Fill ``into`` with the file's bytes from ``offset``."""
        if self._stream is None:
            self._stream = open_input(self._file, self._what)
        self._stream.seek(offset)
        read_into(self._stream, into, self._file)


def as_float64(values: np.ndarray) -> np.ndarray:
    """``values`` (a file's numbers) as float64, without a warning: a float32 signalling NaN
    (exponent all ones, quiet bit clear) raises numpy's "invalid value encountered in cast", a
    long double beyond float64 its "overflow"; both become NaN or infinity, which the reader's
    finiteness check names (:meth:`FrameSource.read`)."""
    with np.errstate(over="ignore", invalid="ignore"):
        return np.asarray(values).astype(np.float64, copy=False)  # float64 already: itself


def read_into(stream: IO[bytes], into: memoryview, path: str | os.PathLike[str]) -> None:
    """Fill ``into`` from the stream's position; a stream that ends first (a file that shrank
    since its size was checked) is an InputError."""
    done = 0
    while done < len(into):
        count = stream.readinto(into[done:])  # type: ignore[attr-defined]  # files have it
        if not count:
            raise InputError(
                f"ended {len(into) - done} bytes short of the data it declares (did it shrink "
                "while being read?)",
                path=path,
            )
        done += count
