"""The parent's side of a read in a child process: :class:`IsolatedFrames` starts the child, asks it
for ranges of frames and turns whatever ends it into an InputError naming the file."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import ClassVar, TypeVar

import numpy as np

from ...errors import InputError
from ...model.attributes import Field
from ...model.sequence import MeshSequence
from ...model.sources import FrameSource, SequenceFrames
from ..registry import ReadOptions
from .channel import (
    Child,
    Description,
    can_isolate,
    child_request,
)

T = TypeVar("T")


class IsolatedFrames(FrameSource):
    """The frames that ``opener(path, options)`` reads, read in a child process (see the
    module docstring).

    Args:
        opener: the in-process source (a module-level FrameSource class), or a module-level
            function that reads a whole sequence; the child imports it by name.
        library: the library's name for messages ("USD", "Alembic").
        extra: the extra that installs it.
        preload: the modules it imports, looked for here first (a DependencyError without
            starting a process) and imported in the child before its memory is capped.
    """

    _transient: ClassVar[tuple[str, ...]] = ("_child", "_local")
    _child: Child | None = None
    _local: FrameSource | None = None

    def __init__(
        self,
        opener: Callable[[Path, ReadOptions], FrameSource | MeshSequence],
        path: Path,
        options: ReadOptions,
        library: str,
        extra: str,
        preload: Iterable[str] = (),
    ):
        self._opener, self._file, self._options = opener, path, options
        self._library, self._extra, self._preload = library, extra, tuple(preload)
        opened = self._start()
        self._describe(
            path,
            opened.frame_count,
            opened.vertex_count,
            opened.faces,
            opened.frame_names,
            opened.frame_rate,
            opened.time_codes,
            opened.meters_per_unit,
            opened.up_axis,
            opened.attributes,
            opened.face_sets,
            opened.field_names,
        )

    def _start(self) -> FrameSource | Description:
        """Open the file in a new child (and say what it found), or where no child can
        start, in this process."""
        if not can_isolate(self._preload, self._library, self._extra):
            opened = self._opener(self._file, self._options)
            if isinstance(opened, MeshSequence):
                opened = SequenceFrames(opened, self._file)
            self._local = opened
            return opened
        request = child_request(self._opener, self._file, self._options, self._preload)
        self._child = Child(request, self._file, self._library)
        return self._child.description

    def _read(self, start: int, stop: int) -> np.ndarray:
        self._ready()
        if self._local is not None:
            return self._local.read(start, stop)
        return self._asked(lambda child: child.read(start, stop))

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        self._ready()
        if self._local is not None:
            return self._local.read_fields(start, stop)
        return self._asked(lambda child: child.read_fields(start, stop))

    def _ready(self) -> None:
        """A child to ask (a new one if the last is gone), unless the source reads here."""
        if self._local is None and (self._child is None or not self._child.alive()):
            if self._child is not None:  # gone while idle (its caller's thread ended)
                self._child.close()
                self._child = None
            opened = self._start()
            if (opened.frame_count, opened.vertex_count) != (self.frame_count, self.vertex_count):
                raise InputError("has changed since it was opened", path=self._file)

    def _asked(self, request: Callable[[Child], T]) -> T:
        """What the child answers to ``request``; after a crash the next read starts afresh."""
        assert self._child is not None
        try:
            return request(self._child)
        except InputError:
            if not self._child.alive():
                self._child.close()
                self._child = None
            raise


def read_isolated(
    reader: Callable[[Path, ReadOptions], MeshSequence],
    path: Path,
    options: ReadOptions,
    library: str,
    extra: str,
    preload: Iterable[str] = (),
) -> MeshSequence:
    """``reader(path, options)``, a function that reads a whole sequence, run in a child
    process (see the module docstring): the child serves the sequence it read as frames,
    all read at once.

    Args:
        reader: a module-level function of the package (the child imports it by name).
        library: the library's name for messages: "Alembic" gives "the Alembic library
            crashed reading it", and "reading Alembic files needs..." when it is missing.
        extra: the extra that installs it.
        preload: the modules the reader imports, imported in the child before its memory is
            capped, and looked for here first: a missing one is a DependencyError without
            starting a process.

    Raises:
        InputError: what the reader raised, or the crash, memory or time that stopped it.
        DependencyError: what the reader raised, or a ``preload`` module that is absent.
        RuntimeError: the child could not start, or the reader failed for a reason other
            than the file (a bug): the child's traceback is in the message.
    """
    with IsolatedFrames(reader, path, options, library, extra, preload) as source:
        return source.load()
