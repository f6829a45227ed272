"""Which reader or writer a source goes to: a folder, glob or list of one-frame files, or a sequence
file chosen by its suffix from the registry, with the reading options each format accepts."""

from __future__ import annotations

import errno
import os
import re
from collections.abc import Sequence
from pathlib import Path

from ..errors import InputError
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from .frames import FileFrames, folder_files, glob_files, write_frames
from .registry import (
    OPTION_FLAGS,
    ReadOptions,
    SequenceFormat,
    WriteOptions,
    format_named,
    format_of,
    formats,
)

#: What load_sequence accepts: a folder, glob pattern, mesh or sequence file, or a list of files.
Source = str | os.PathLike[str] | Sequence[str | os.PathLike[str]]

_GLOB_CHARACTERS = re.compile(r"[*?[]")
#: Suffixes of files that are not sequence files of their own, which a folder is never named:
#: a series' frames (VTK), XDMF's heavy data, compressed files.
_NOT_A_FOLDER = frozenset({".vtu", ".vtp", ".vtk", ".h5", ".hdf5", ".tkc"})
#: The format of a folder of frames when none is named: OBJ, which every tool reads.
FOLDER_FORMAT = "obj"


def load_sequence(
    source: Source,
    *,
    progress: bool = True,
    prim: str | None = None,
    object_path: str | None = None,
    faces: str | os.PathLike[str] | None = None,
    fps: float | None = None,
    max_memory: int | None = None,
) -> MeshSequence:
    """Load a mesh sequence.

    Args:
        source: one of
            - a folder: every ``*.obj`` file in it (any case), or if it has none, every file
              of a one-frame mesh format (``.ply``, ``.off``, ``.stl``... through trimesh, or
              static ``.glb``); hidden files (names starting with ``.``) are skipped;
            - a glob pattern such as ``"frames/*.obj"``;
            - a list or tuple of files, read in the order given;
            - a file holding a whole sequence, chosen by its suffix (:func:`formats` lists
              them): an ``.npz`` with keys ``V`` (F, K, 3) and optionally ``F`` (faces),
              ``frame_files`` (names), ``frame_rate`` and ``time_codes``; a ``.npy`` array
              (F, K, 3); USD, Alembic, PC2, MDD, glTF, VTK series, XDMF, a zarr store (a
              folder named ``*.zarr``) (some need an extra, named by the error if missing);
            - a single mesh file, giving a one-frame sequence.
            Files of a folder or glob are ordered by :func:`natural_sort_key` of their names.
        progress: draw a progress bar on a terminal while reading many files.
        prim: USD: the mesh prim to read, when the stage holds several.
        object_path: Alembic: the PolyMesh object to read, when the archive holds several.
        faces: PC2, MDD and ``.npy``: a mesh file whose faces the points take (without it,
            points only).
        fps: glTF: sample the animation at this rate rather than at its keyframes.
        max_memory: the most bytes a read may decompress and hold at once (default: half the
            machine's memory): a compressed array that would inflate beyond it (a zlib block
            of a VTK file, a deflated ``.npz`` member, a filtered HDF5 dataset of an XDMF
            series, a glTF's meshopt views) is refused before it is inflated.

    Returns:
        The sequence; faces come from the first frame and ``frame_names`` are the file names.

    Raises:
        InputError: nothing to read, a file that cannot be read, a frame whose vertex count
            or faces differ from the first, or an option the source's format does not take;
            the error names the file, frame and line (or object); data that would
            decompress beyond ``max_memory``.
        DependencyError: the format's library is not installed; names the extra to install.
    """
    opened = open_frames(
        source, prim=prim, object_path=object_path, faces=faces, fps=fps, max_memory=max_memory
    )
    with opened:
        return opened.load(progress)


def open_frames(
    source: Source,
    *,
    prim: str | None = None,
    object_path: str | None = None,
    faces: str | os.PathLike[str] | None = None,
    fps: float | None = None,
    max_memory: int | None = None,
) -> FrameSource:
    """Open a mesh sequence to read a range of frames at a time, without loading it whole.

    Takes the sources and options of :func:`load_sequence`; ``source.read(start, stop)`` gives
    the same numbers as ``load_sequence(source).vertices[start:stop]``. Every built-in format
    streams: a folder or list of files file by file, ``.npy``/PC2/MDD by offset, ``.npz``
    member ``V`` by offset or forward decompression, zarr chunk by chunk, USD and Alembic sample
    by sample (in a child process that stays open), VTK and XDMF step by step, glTF evaluated
    per range (:mod:`tuckercodec.model.sources` says how).

    The description (frame and vertex counts, faces, names, rate, time codes) is read at once;
    each frame is checked when read, so an error in frame 900 is raised by the read of a range
    that holds it. Close the source when done (``with open_frames(...) as source:``). It is
    picklable: a worker process reopens the file on its first read.

    Raises:
        InputError: as :func:`load_sequence`, for what the description needs (the first frame
            of a folder, the header of a file).
        DependencyError: the format's library is not installed.
    """
    options = _read_options(prim, object_path, faces, fps, max_memory)
    resolved = _resolve(source, options)
    if isinstance(resolved, list):
        where = source if isinstance(source, (str, os.PathLike)) else None
        return FileFrames(resolved, where, options)
    found, path = resolved
    assert found.open is not None  # _resolve returns only whole-sequence formats
    return found.open(path, options)


def _read_options(
    prim: str | None,
    object_path: str | None,
    faces: str | os.PathLike[str] | None,
    fps: float | None,
    max_memory: int | None,
) -> ReadOptions:
    if max_memory is not None and max_memory <= 0:
        raise ValueError(f"max_memory must be a positive number of bytes, got {max_memory}")
    return ReadOptions(
        prim=prim,
        object_path=object_path,
        faces=None if faces is None else Path(faces),
        fps=fps,
        max_memory=max_memory,
    )


def _resolve(source: Source, options: ReadOptions) -> list[Path] | tuple[SequenceFormat, Path]:
    """What a source is: one-frame files to read in this order, or a file (or a folder, for a
    format of folders) of a whole-sequence format; options the source does not take are
    refused."""
    if not isinstance(source, (str, os.PathLike)):  # a list, tuple or other sequence of files
        files = [Path(item) for item in source]
        if not files:
            raise InputError("the list of frame files is empty")
        _refuse_options(options, frozenset(), "a list of frame files")
        return files

    path = Path(source)
    if not path.exists() and _GLOB_CHARACTERS.search(str(source)):
        _refuse_options(options, frozenset(), "frame files", path)
        return glob_files(str(source))
    found = format_of(path)
    if path.is_dir() and not (found is not None and found.folder):
        _refuse_options(options, frozenset(), "a folder of frames", path)
        return folder_files(path)
    if not path.exists():
        raise InputError("no such file or folder", path=path)
    if found is not None and found.open is not None:
        _refuse_options(options, found.read_options, f"{found.name} files", path)
        return found, path
    _refuse_options(options, frozenset(), "a one-frame mesh file", path)
    return [path]


def _refuse_options(
    options: ReadOptions, accepted: frozenset[str], what: str, path: Path | None = None
) -> None:
    """An InputError for a read option the source's format does not use, naming which do."""
    for name in options.given():
        if name not in accepted:
            users = [f.name for f in formats() if name in f.read_options]
            raise InputError(
                f"{OPTION_FLAGS[name]} ({name}) does not apply to {what}; it applies to "
                f"{', '.join(users) or 'no format'} files",
                path=path,
            )


def save_sequence(
    seq: MeshSequence,
    destination: str | os.PathLike[str],
    *,
    overwrite: bool = False,
    precision: int | None = None,
    progress: bool = True,
) -> None:
    """Save a sequence: a file whose suffix names a sequence format (``.npz``, ``.usd``,
    ``.abc``, ``.pc2``, ``.mdd``, ``.glb``...), or a folder of OBJ files.

    Args:
        seq: the sequence.
        destination: a path whose suffix names a whole-sequence format writes one file (or,
            for a VTK series, an index file beside a folder of frames); an ``.npz`` holds V
            float64, F int64, frame_files, and frame_rate and time_codes if set. Anything
            else is a folder (created if needed)
            that receives one OBJ file per frame, named after ``seq.frame_names`` (made safe
            for file names, with an ``.obj`` suffix, unique). If those names would not sort
            back into frame order, they are prefixed with the frame number.
        overwrite: replace existing files; otherwise an existing target file is an error,
            raised before anything is written.
        precision: significant digits of OBJ coordinates; ``None`` writes exact round-trip
            text. Ignored by binary formats.
        progress: draw a progress bar on a terminal while writing many files.

    Raises:
        FileExistsError: a target file exists and ``overwrite`` is False.
        ValueError: ``destination`` names a file of a format that cannot hold a sequence
            (``.obj``, ``.ply``, ``.vtu``...), where a folder of OBJ frames would surprise.
    """
    destination = Path(destination)
    options = WriteOptions(overwrite=overwrite, precision=precision, progress=progress)
    found = format_of(destination)
    if found is not None and found.write is not None:
        destination.parent.mkdir(parents=True, exist_ok=True)  # as for a folder of frames
        found.write(seq, destination, options)
        return
    if destination.exists() and not destination.is_dir():
        raise NotADirectoryError(
            errno.ENOTDIR,
            "not a folder: name a sequence file (.npz, .usd, .glb...) or a folder for OBJ frames",
            str(destination),
        )
    suffix = destination.suffix.lower()
    if not destination.is_dir() and (found is not None or suffix in _NOT_A_FOLDER):
        # a file's name, not a folder's: a folder of OBJ frames called "out.ply" is a mistake
        raise ValueError(
            f"{destination}: no format writes a sequence as one {suffix} file; name a sequence "
            "file (.npz, .usdc, .abc, .glb, .pvd...: 'tuckercodec formats' lists them) or a "
            "folder for OBJ frames"
        )
    write_frames(seq, destination, format_named(FOLDER_FORMAT), options)
