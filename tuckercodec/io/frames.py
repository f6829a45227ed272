"""Sequences stored as one mesh file per frame: a folder, a glob pattern or a list of files.

The files are ordered by natural sort of their names (``frame2`` before ``frame10``), each is
read by its format's frame reader, and every frame must have the vertex count and faces of the
first one. :class:`FileFrames` reads them file by file, a range of frames at a time. Writing
makes a folder of one file per frame, staged and moved in whole.
"""

from __future__ import annotations

import dataclasses
import glob
import os
import re
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from ..system.atomic import atomic_folder
from ..system.progress import progress as progress_bar
from .registry import (
    FrameReader,
    MeshFrame,
    ReadOptions,
    SequenceFormat,
    WriteOptions,
    format_named,
    format_of,
)

_UNSAFE_NAME_CHARACTERS = re.compile(r"[^A-Za-z0-9._-]+")
#: The format that reads a listed file whose suffix no format claims: trimesh reads far more
#: kinds of mesh than the registry lists (.xyz, .drc...), and says so when it cannot.
FALLBACK_FRAME_FORMAT = "mesh"
#: Threads writing the frames of a folder at once. No frame waits for its own fsync (the
#: folder is synced once), so they overlap numpy's GIL-free steps, which are long on a whole
#: frame's values: horse gallop's OBJ folder (8 fresh processes each, load 5, 2 cores) took
#: 0.78-1.01, 0.69-0.91 and 0.63-0.94 s of wall time (min-median) with 1, 2 and 4 threads,
#: 0.71-1.05, 0.90-1.04 and 0.95-1.08 s of CPU.
WRITER_THREADS = 2


def natural_sort_key(name: str) -> tuple[tuple[int | str, ...], str]:
    """A sort key that orders the digit runs of ``name`` by value: ``f2`` before ``f10``.

    Letters compare without regard to case; names that differ only in case or leading zeros
    (``f01`` and ``f1``) are then ordered by their plain text so the order is always the same.
    """
    parts = re.split(r"([0-9]+)", name)
    # re.split with a group alternates text, digits, text...: same kinds meet at each position
    key = tuple(int(part) if i % 2 else part.casefold() for i, part in enumerate(parts))
    return key, name


def folder_files(folder: Path) -> list[Path]:
    """The OBJ files of a folder, else its other one-frame-per-file mesh files, in natural
    order of their names. Hidden files are skipped."""
    # hidden files: editors' backups, macOS "._name.obj" metadata, temporary files
    files = [e for e in folder.iterdir() if e.is_file() and not e.name.startswith(".")]
    objs = [entry for entry in files if entry.suffix.lower() == ".obj"]
    chosen = objs or [entry for entry in files if _frame_format(entry) is not None]
    if not chosen:
        raise InputError("the folder holds no .obj (or other mesh) files", path=folder)
    return sorted(chosen, key=lambda entry: natural_sort_key(entry.name))


def glob_files(pattern: str) -> list[Path]:
    """The files matching a glob pattern, in natural order of their names."""
    matches = glob.glob(os.path.expanduser(pattern))
    files = [Path(name) for name in matches if Path(name).is_file()]
    if not files:
        raise InputError("the pattern matches no files", path=pattern)
    return sorted(files, key=lambda entry: (natural_sort_key(entry.name), str(entry)))


def _frame_format(path: Path) -> SequenceFormat | None:
    """The one-frame-per-file format of ``path``, or ``None``."""
    found = format_of(path)
    return found if found is not None and found.read_frame is not None else None


class FileFrames(FrameSource):
    """One frame per file (a folder, a glob, a list), read file by file: the first file at
    once (for the vertex count and faces), the others when their frames are read, each checked
    against the first. ``where`` is the folder or pattern the files came from, for errors
    that are not one file's; ``options`` are given to each frame's reader (``max_memory``)."""

    def __init__(
        self,
        files: list[Path],
        where: str | os.PathLike[str] | None = None,
        options: ReadOptions | None = None,
    ):
        self._files = list(files)
        self._options = options or ReadOptions()
        self._readers: list[FrameReader] = []
        for index, file in enumerate(self._files):
            found = format_of(file) or format_named(FALLBACK_FRAME_FORMAT)
            if found.read_frame is None:
                raise InputError(
                    f"this {file.suffix} file holds a whole sequence: load it on its own",
                    path=file,
                    frame=index if len(files) > 1 else None,
                )
            self._readers.append(found.read_frame)
        self._reference = self._frame(0, None)
        vertices, faces = self._reference.vertices, self._reference.faces
        names = [file.name for file in self._files]
        self._describe(
            where,
            len(self._files),
            len(vertices),
            faces,
            names,
            attributes=self._reference.attributes,
            face_sets=self._reference.face_sets,
        )

    def _frame(self, index: int, reference: MeshFrame | None) -> MeshFrame:
        """Frame ``index``, checked against ``reference`` (the first frame, if read yet)."""
        file = self._files[index]
        try:
            frame = self._readers[index](file, reference, self._options)
            if reference is not None:
                _check_matches(frame, reference, file)
        except InputError as error:
            if len(self._files) == 1:
                raise
            # add the frame number to the reader's message (file and line are already there)
            raise InputError(error.reason, path=error.path, line=error.line, frame=index) from None
        return frame

    def _read(self, start: int, stop: int, show_progress: bool = False) -> np.ndarray:
        vertices = np.empty((stop - start, self.vertex_count, 3), dtype=np.float64)
        numbered: Iterable[int] = range(start, stop)
        if show_progress:
            suffixes = {file.suffix.lower() for file in self._files}
            label = "reading OBJ" if suffixes == {".obj"} else "reading meshes"
            numbered = progress_bar(numbered, total=stop - start, label=label)
        for index in numbered:
            frame = self._reference if index == 0 else self._frame(index, self._reference)
            vertices[index - start] = frame.vertices
        return vertices

    def load(self, progress: bool = False) -> MeshSequence:
        """The whole sequence, with a progress bar on a terminal if asked."""
        vertices = self._read(0, self.frame_count, progress)
        return MeshSequence(
            vertices,
            self.faces,
            frame_names=self.frame_names,
            attributes=self.attributes,
            face_sets=self.face_sets,
        )


def _check_matches(frame: MeshFrame, reference: MeshFrame, path: Path) -> None:
    """A frame must have the first frame's vertex count and faces (a reader such as OBJ's
    checks this itself, naming the line; this catches every other reader)."""
    first = f" ({reference.path})" if reference.path else ""  # the other file to look at
    if len(frame.vertices) != len(reference.vertices):
        raise InputError(
            f"has {len(frame.vertices)} vertices but the first frame has "
            f"{len(reference.vertices)}{first}: every frame must have the same vertices",
            path=path,
        )
    if frame.faces is not reference.faces and not np.array_equal(frame.faces, reference.faces):
        raise InputError(
            f"its faces differ from the first frame's{first}: every frame must have the same faces",
            path=path,
        )


def write_frames(
    seq: MeshSequence, destination: Path, frame_format: SequenceFormat, options: WriteOptions
) -> None:
    """Write one file per frame into the folder ``destination`` (created if needed), named
    after the frame names (:func:`frame_file_names`). All frames are written to a staging
    folder first (existing targets refused before any work), so a failure or an interrupt
    leaves the destination as it was."""
    write_frame = frame_format.write_frame
    if write_frame is None:
        raise ValueError(f"the {frame_format.name} format cannot write frames")
    names = frame_file_names(seq.frame_names, frame_format.suffixes[0])
    destination.parent.mkdir(parents=True, exist_ok=True)

    frame_writer = write_frame(seq, dataclasses.replace(options, staged=True))

    def write(index: int) -> None:
        frame_writer(staging / names[index], index)

    # The frames are written plainly into the staging folder, their writeback started at
    # once, and made durable all together (sync) before anything is moved in: the same
    # guarantee as an fsync per file before its link, without a wait on the disk per frame.
    # WRITER_THREADS write them (numpy, which makes an OBJ frame's text, frees the GIL).
    # The pool ends (its frames written or cancelled) before the folder is synced and moved
    # in, or removed.
    with (
        atomic_folder(destination, names, overwrite=options.overwrite, sync=True) as staging,
        ThreadPoolExecutor(max_workers=WRITER_THREADS) as pool,
    ):
        written: Iterable[None] = pool.map(write, range(seq.frame_count))
        if options.progress:
            written = progress_bar(
                written, total=seq.frame_count, label=f"writing {frame_format.name.upper()}"
            )
        try:
            for _ in written:
                pass
        except BaseException:
            pool.shutdown(cancel_futures=True)  # and wait for the frames being written
            raise


def frame_file_names(frame_names: Sequence[str], suffix: str) -> list[str]:
    """Safe, unique file names for the frames, which natural-sort into frame order."""
    names: list[str] = []
    taken: set[str] = set()
    for index, frame_name in enumerate(frame_names):
        stem = _safe_stem(frame_name) or f"frame_{index:05d}"
        name = f"{stem}{suffix}"
        copy = 1
        while name.casefold() in taken:  # case-insensitive file systems would merge them
            copy += 1
            name = f"{stem}_{copy}{suffix}"
        taken.add(name.casefold())
        names.append(name)
    if sorted(names, key=natural_sort_key) != names:
        # reading the folder back must give the frames in this order
        width = max(5, len(str(len(names) - 1)))
        names = [f"{index:0{width}d}_{name}" for index, name in enumerate(names)]
    return names


def _safe_stem(frame_name: str) -> str:
    """The frame name without folders, mesh suffix or characters unsafe in file names."""
    name = Path(str(frame_name).replace("\\", "/")).name
    if format_of(name) is not None:
        name = Path(name).stem
    return _UNSAFE_NAME_CHARACTERS.sub("_", name).lstrip(".")
