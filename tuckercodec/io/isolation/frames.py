"""Frames read range by range by a C++ library in a child process that stays open for the
source's life (USD and Alembic): :class:`IsolatedFrames`.

The child (:func:`.isolation_child.serve_child`) opens the file with the format's in-process
source (``usd.StageFrames``, ``alembic.ArchiveFrames``), sends its description, then serves one
request ``{"read": [start, stop]}`` at a time on its stdin, answering with the frames as raw
float64 on its stdout. It is isolated as a one-shot read is (:mod:`.isolation`): the same
memory cap, signals, death with the caller and its thread (Linux), and a crash, a runaway
allocation or a hang is an :class:`~tuckercodec.errors.InputError` naming the file and the last
frame the reader noted. The time limit applies to each request (the opening, then each read),
not to the child's life: a watchdog kills it when a request takes longer. After a crash the
next read starts a new child; so does the first read after unpickling (workers of a process
pool or Dask each start their own).

Why one child for many reads rather than one per read: starting the interpreter, importing
the library and opening the stage cost about 0.5 s (pxr) and 0.3 s (alembic3d) per child on
this machine, once; a read then costs its frames' sampling and a copy through a pipe (see
BENCHMARKS for the measured figures). Where ``sys.executable`` cannot run Python (a frozen
application), the source reads in process.
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import tempfile
import threading
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import IO, Any, ClassVar

import numpy as np

from ...errors import InputError
from ..registry import ReadOptions
from ..streaming import FrameSource
from . import Ending, can_isolate, child_request, last_words, spawn

#: How long a child may take to leave once told to (its stdin closed), before it is killed.
_GOODBYE_SECONDS = 2.0


class IsolatedFrames(FrameSource):
    """The frames that ``opener(path, options)`` (a module-level FrameSource class of the
    package) reads, read in a child process (see the module docstring).

    Args:
        opener: the in-process source; the child imports it by name.
        library: the library's name for messages ("USD", "Alembic").
        extra: the extra that installs it.
        preload: the modules it imports, looked for here first (a DependencyError without
            starting a process) and imported in the child before its memory is capped.
    """

    _transient: ClassVar[tuple[str, ...]] = ("_child", "_local")
    _child: _Child | None = None
    _local: FrameSource | None = None

    def __init__(
        self,
        opener: Callable[[Path, ReadOptions], FrameSource],
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
        )

    def _start(self) -> FrameSource | _Description:
        """Open the file in a new child (and say what it found), or where no child can
        start, in this process."""
        if not can_isolate(self._preload, self._library, self._extra):
            self._local = self._opener(self._file, self._options)
            return self._local
        request = child_request(self._opener, self._file, self._options, self._preload)
        self._child = _Child(request, self._file, self._library)
        return self._child.description

    def _read(self, start: int, stop: int) -> np.ndarray:
        if self._local is None and (self._child is None or not self._child.alive()):
            if self._child is not None:  # gone while idle (its caller's thread ended)
                self._child.close()
                self._child = None
            opened = self._start()
            if (opened.frame_count, opened.vertex_count) != (self.frame_count, self.vertex_count):
                raise InputError("has changed since it was opened", path=self._file)
        if self._local is not None:
            return self._local.read(start, stop)
        assert self._child is not None
        try:
            return self._child.read(start, stop)
        except InputError:
            if not self._child.alive():  # it crashed: the next read starts afresh
                self._child.close()
                self._child = None
            raise


class _Description:
    """What a child says of the file when it has opened it."""

    def __init__(self, header: dict[str, Any], arrays: dict[str, np.ndarray]):
        self.frame_count = int(header["frame_count"])
        self.vertex_count = int(header["vertex_count"])
        self.frame_names = [str(name) for name in header["frame_names"]]
        self.frame_rate = header["frame_rate"]
        self.faces = arrays["faces"]
        self.time_codes = arrays.get("time_codes")


class _Child:
    """A serving child: its process, the stderr it prints to, and how its requests end."""

    def __init__(self, request: dict[str, Any], path: Path, library: str):
        self.timeout: float | None = request["timeout"]
        self.ending = Ending(path, library, request["memory"], self.timeout, started=False)
        self.stderr = tempfile.TemporaryFile()  # noqa: SIM115  # lives as long as the child
        self.process = spawn("serve_child", request, subprocess.PIPE, subprocess.PIPE, self.stderr)
        self.expired = False
        try:
            header, arrays = self._answer()
            self.description = _Description(header, arrays)
        except BaseException:
            self.close()
            raise

    def alive(self) -> bool:
        return self.process.poll() is None

    def read(self, start: int, stop: int) -> np.ndarray:
        """Frames ``start`` to ``stop`` as the child's source reads them."""
        stdin = self.process.stdin
        assert stdin is not None
        try:
            stdin.write(json.dumps({"read": [start, stop]}).encode() + b"\n")
            stdin.flush()
        except OSError:
            pass  # it died: reading its answer says how
        return self._answer()[1]["vertices"]

    def _answer(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """The next result the child sends, with its arrays, within the time limit; or the
        error it sends, or the one that says how it ended."""
        watchdog = None
        if self.timeout is not None:
            watchdog = threading.Timer(self.timeout, self._expire)
            watchdog.daemon = True
            watchdog.start()
        try:
            header = self._header()
            if header.get("result") in ("description", "frames"):
                arrays = {}
                for name, dtype, shape in header["arrays"]:
                    array = self._array(dtype, shape)
                    if array is None:  # cut short: it died while sending
                        break
                    arrays[name] = array
                else:
                    return header, arrays
                header = {}
        except BaseException:  # interrupted mid-answer: the child is out of step, end it
            self.process.kill()
            raise
        finally:
            if watchdog is not None:
                watchdog.cancel()
        raise self._failure(header)

    def _header(self) -> dict[str, Any]:
        """The next result header (notes before it update where the reader is); ``{}`` if the
        output ends first."""
        stdout = self.process.stdout
        assert stdout is not None
        for line in iter(lambda: stdout.readline(1 << 20), b""):
            try:
                message = json.loads(line)
            except ValueError:  # torn: the child died while writing it
                break
            if "note" in message:
                self.ending.where, self.ending.frame = message["note"], message["frame"]
            self.ending.started = self.ending.started or "started" in message
            if "result" in message:
                return dict(message)
        return {}

    def _array(self, dtype: str, shape: list[int]) -> np.ndarray | None:
        """An array the child sends raw; ``None`` if its output ends first."""
        stdout = self.process.stdout
        assert stdout is not None
        array = np.empty(shape, dtype=np.dtype(dtype))
        view = memoryview(array).cast("B")  # type: ignore[arg-type]  # arrays are buffers
        done = 0
        while done < len(view):
            count = stdout.readinto(view[done:])  # type: ignore[attr-defined]  # a buffered file
            if not count:
                return None
            done += count
        return array

    def _failure(self, header: dict[str, Any]) -> Exception:
        """The error for a result that is not frames: the child's own error (it serves on),
        or how it ended (waited for, unless it was killed at the time limit)."""
        if header.get("result") != "error":
            self.process.wait()  # it exits after a bug or a failed allocation, or it died
            self.ending.returncode = None if self.expired else self.process.returncode
            self.ending.said = last_words(self.stderr)
        return self.ending.error(header)

    def _expire(self) -> None:
        self.expired = True
        self.process.kill()

    def close(self) -> None:
        """Tell the child to leave (its stdin ends), kill it if it does not, release all."""
        streams: list[IO[bytes] | None] = [self.process.stdin, self.process.stdout]
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):  # a broken pipe: it is gone already
                self.process.stdin.close()
        try:
            self.process.wait(_GOODBYE_SECONDS)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        for stream in [*streams, self.stderr]:
            if stream is not None:
                stream.close()
