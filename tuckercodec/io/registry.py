"""The registry of sequence file formats, keyed by file-name suffix.

Each format is one module (or package) of :mod:`tuckercodec.io`, and one
:class:`SequenceFormat` entry of the table in :mod:`.builtin`. A format either holds a
whole sequence in one file (``open``/``write``: ``.npz``), or one frame per file (``read_frame``
/``write_frame``: ``.obj``, and the meshes trimesh reads), which a folder, a glob or a list of
files makes into a sequence (:mod:`.frames`). ``open`` is the one loader of a whole-sequence
format: it reads a range of frames at a time (:class:`~tuckercodec.model.sources.FrameSource`), and
``.load()`` reads them all. Modules import their heavy libraries only inside their functions, so
that looking a format up costs nothing.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from .common.budget import Inflation, memory_ceiling


@dataclass(eq=False)
class MeshFrame:
    """One frame as a per-frame reader returns it.

    Attributes:
        vertices: (K, 3) float64 positions in the file's order.
        faces: (M, n) int64, 0-based, rows shorter than n padded with -1; (0, 3) if none.
        face_text: a reader's key for "the same faces as the reference frame" that is cheaper
            to compare than the faces (OBJ: the raw ``f`` lines), or ``None``.
        path: the file it was read from, which errors about a later frame name beside their own.
    """

    vertices: np.ndarray
    faces: np.ndarray
    face_text: bytes | None = None
    path: str | None = None


@dataclass(frozen=True)
class ReadOptions:
    """Choices that some whole-sequence formats need to read a file; ``None`` where not given.

    Attributes:
        prim: USD: the path of the UsdGeomMesh to read, when the stage holds several.
        object_path: Alembic: the full name of the PolyMesh object, when the archive holds
            several.
        faces: PC2, MDD and ``.npy`` (positions only): a mesh file whose faces the points take.
        fps: glTF: sample the animation at this many frames per second instead of at its
            keyframes.
        max_memory: every format: the most bytes a read may decompress and hold at once
            (``--max-memory``; ``None``: half the machine's memory), :mod:`.common.budget`.
    """

    prim: str | None = None
    object_path: str | None = None
    faces: Path | None = None
    fps: float | None = None
    max_memory: int | None = None

    def given(self) -> list[str]:
        """The names of the options that are set which only some formats take (not
        :data:`COMMON_OPTIONS`)."""
        return [
            name
            for name, value in vars(self).items()
            if value is not None and name not in COMMON_OPTIONS
        ]

    def inflation(self) -> Inflation:
        """A new :class:`~.budget.Inflation` of :attr:`max_memory` (or its default)."""
        return Inflation(memory_ceiling(self.max_memory))


#: How each read option that only some formats take is spelled on the command line, for the
#: errors that name one.
OPTION_FLAGS = {"prim": "--prim", "object_path": "--object", "faces": "--faces", "fps": "--fps"}
#: The read options every format takes (never refused as not applying).
COMMON_OPTIONS = frozenset({"max_memory"})


@dataclass(frozen=True)
class WriteOptions:
    """How a sequence is written: ``overwrite`` existing files; ``precision`` significant
    digits for text formats (``None``: exact); ``progress`` bar on a terminal. ``staged``,
    for a frame writer: the file goes into the staging folder of a folder of frames, which is
    made durable as a whole before it is moved in (:func:`tuckercodec.system.atomic.atomic_folder`
    with ``sync``), so it may be written plainly
    (:func:`tuckercodec.system.atomic.write_staged`)."""

    overwrite: bool = False
    precision: int | None = None
    progress: bool = False
    staged: bool = False


#: Reads one frame; the second argument is the sequence's first frame (``None`` for the first
#: itself), which a reader may use to skip work or to name the first difference it finds; the
#: third the read options (only ``max_memory`` applies to a frame's file).
FrameReader = Callable[[Path, MeshFrame | None, ReadOptions], MeshFrame]
FrameWriter = Callable[[Path, np.ndarray, np.ndarray, WriteOptions], None]


@dataclass(frozen=True)
class SequenceFormat:
    """A file format of mesh sequences, and the functions that read and write it."""

    name: str
    suffixes: tuple[str, ...]  # lower case, with the dot
    description: str
    #: a whole sequence: opened to read a range of frames at a time (``.load()``: all of them)
    open: Callable[[Path, ReadOptions], FrameSource] | None = None
    write: Callable[[MeshSequence, Path, WriteOptions], None] | None = None
    read_frame: FrameReader | None = None  # one frame from one file
    write_frame: FrameWriter | None = None  # one frame (vertices, faces) to one file
    #: the :class:`ReadOptions` fields ``open`` uses; giving another one is an error
    read_options: frozenset[str] = frozenset()
    #: the optional extra that installs the library the format needs (``None``: core only)
    extra: str | None = None
    #: what a file keeps of a sequence beyond float32 positions, of: "float64" (positions
    #: exactly), "faces", "polygons" (faces of more than 3 corners, not split into
    #: triangles), "frame_names", "frame_rate", "time_codes", "meters_per_unit", "up_axis"
    carries: frozenset[str] = frozenset()
    #: its "files" are folders (a zarr store), read by this format rather than as a folder
    #: of frames
    folder: bool = False
    #: what a file written from a sequence would not keep of its attributes, face sets and
    #: fields, one line each (empty: all of it); ``None``: the format says nothing
    cannot_keep: Callable[[MeshSequence], list[str]] | None = None


@cache
def formats() -> tuple[SequenceFormat, ...]:
    """Every registered format, in the order the CLI lists them (:data:`.builtin.FORMATS`)."""
    # by name, on first use: the formats import this module for its types (and the point
    # caches the whole package, for --faces), and importing tuckercodec imports none of them
    table: tuple[SequenceFormat, ...] = importlib.import_module(f"{__package__}.builtin").FORMATS
    return table


def format_named(name: str) -> SequenceFormat:
    """The format called ``name`` ("obj", "npz"...); ``ValueError`` naming the others."""
    for candidate in formats():
        if candidate.name == name:
            return candidate
    known = ", ".join(f.name for f in formats())
    raise ValueError(f"unknown sequence format {name!r}: the formats are {known}")


def writable_formats() -> tuple[str, ...]:
    """The names of the formats a sequence can be written in."""
    return tuple(f.name for f in formats() if f.write is not None or f.write_frame is not None)


def format_of(path: str | os.PathLike[str]) -> SequenceFormat | None:
    """The format a file name's suffix names (case-insensitive), or ``None``."""
    suffix = Path(path).suffix.lower()
    for candidate in formats():
        if suffix in candidate.suffixes:
            return candidate
    return None
