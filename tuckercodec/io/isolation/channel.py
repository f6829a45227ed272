"""The caller's side of a reading child (:mod:`tuckercodec.io.isolation`): the limits a read
may take, starting the child, the conversation with it through its pipes (:class:`Child`,
the protocol :mod:`.child` describes), and the error that says how it ended (:class:`Ending`):
its own error, a crash, memory, time.
"""

from __future__ import annotations

import base64
import contextlib
import importlib
import importlib.util
import io
import json
import math
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from ... import errors
from ...errors import InputError
from ...model.attributes import Attribute, FaceSet, Field
from ...system.optional import import_optional
from ..registry import ReadOptions

GIB = 2**30
#: The address space a reading child may add to what its interpreter and libraries take.
MEMORY_BASE = 2 * GIB
#: ... plus this many times the bytes the file occupies on disk (:func:`stored_bytes`)...
MEMORY_PER_BYTE = 16
#: ... and never more than this, whatever the file.
MEMORY_CEILING = 64 * GIB
#: The wall-clock time a read may take: this many seconds...
TIMEOUT_BASE = 60.0
#: ... plus one second per this many bytes the file occupies (a slow network disk)...
TIMEOUT_BYTES_PER_SECOND = 8 * 2**20
#: ... and never more than this (an hour), whatever the file.
TIMEOUT_CEILING = 3600.0
MEMORY_VARIABLE = "TUCKERCODEC_READ_MEMORY_GIB"
TIMEOUT_VARIABLE = "TUCKERCODEC_READ_TIMEOUT"
#: How long a child may take to start (its interpreter and the library's imports, which are
#: not the file's doing) before the read's own time limit begins: a busy machine is slow here.
STARTUP_SECONDS = 60.0
#: Thread pools the child does not need, which would reserve address space per core
#: (glibc's malloc arenas, OpenBLAS's buffers, pxr's workers): one each. The user's own
#: settings win.
CHILD_ENVIRONMENT = {"MALLOC_ARENA_MAX": "2"} | dict.fromkeys(
    ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "PXR_WORK_THREAD_LIMIT"), "1"
)
#: What the child runs: the caller's import path, then :func:`.child.serve`.
_BOOTSTRAP = (
    "import json, sys; sys.path[:] = json.loads(sys.argv[1])['sys_path']; "
    "from tuckercodec.io.isolation.{module} import {function}; {function}(sys.argv[1])"
)
#: How Windows reports a crash: the NTSTATUS exit codes of the usual ones.
_WINDOWS_CRASHES = {0xC0000005: "an access violation", 0xC00000FD: "a stack overflow"}


#: How long a child may take to leave once told to (its stdin closed), before it is killed.
_GOODBYE_SECONDS = 2.0


def child_request(
    function: Callable[..., Any], path: Path, options: ReadOptions, preload: tuple[str, ...]
) -> dict[str, Any]:
    """What a child needs to run ``function(path, options)``, as JSON, with its limits."""
    memory, timeout = _limits(path)
    return {
        "sys_path": [entry for entry in sys.path if isinstance(entry, str)],
        "reader": f"{function.__module__}:{function.__qualname__}",
        "path": os.fspath(path),
        "options": {
            name: None if value is None else (os.fspath(value) if name == "faces" else value)
            for name, value in vars(options).items()
        },
        "preload": preload,
        "memory": memory,
        "timeout": timeout,
        "alarm": None if timeout is None else math.ceil(timeout) + 10,
        "startup": math.ceil(STARTUP_SECONDS),
        "parent": os.getpid(),
    }


def last_words(stderr: IO[bytes]) -> list[str]:
    """The lines of the last 4 KiB a child printed, without pxr's banners of ``#``."""
    stderr.seek(max(0, stderr.seek(0, io.SEEK_END) - 4096))
    said = [line.strip() for line in stderr.read().decode(errors="replace").splitlines()]
    return [line for line in said if line and not line[0] == line[-1] == "#"]


def can_isolate(
    preload: tuple[str, ...], library: str, extra: str, purpose: str = "reading"
) -> bool:
    """Whether a child can be started (not where ``sys.executable`` cannot run Python: a
    frozen application); first, a DependencyError for a ``preload`` module that is absent
    (``purpose``: "reading" or "writing" in its message)."""
    for module in filter(_absent, preload):
        import_optional(module, extra, f"{purpose} {library} files")  # DependencyError
    return bool(sys.executable) and not getattr(sys, "frozen", False)


def _absent(module: str) -> bool:
    """Whether ``module`` cannot be imported, found without importing it where possible."""
    if module in sys.modules:
        return sys.modules[module] is None
    try:
        return importlib.util.find_spec(module.partition(".")[0]) is None
    except (ImportError, ValueError):
        return True


def _limit(variable: str, default: float) -> float | None:
    """The limit an environment variable sets (0: none), else ``default``."""
    text = os.environ.get(variable, "").strip()
    if not text:
        return default
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{variable} must be a number >= 0 (0: no limit), got {text!r}")
    return value or None


def stored_bytes(path: Path) -> int:
    """The bytes of data ``path`` really holds: its size, but no more than the disk blocks
    allocated to it (``st_blocks``, where the system counts them), so that a sparse file, whose
    size a hole of zeros inflates for free (``truncate -s 1T``), counts what it stores. 0 for
    a file that cannot be looked at (the reader will say why)."""
    try:
        found = os.stat(path)
    except OSError:
        return 0
    blocks = getattr(found, "st_blocks", None)  # not on Windows: the size it is
    return found.st_size if blocks is None else min(found.st_size, blocks * 512)


def _limits(path: Path) -> tuple[int | None, float | None]:
    """The address space (bytes) and wall-clock time (s) the child may take for this file: a
    base, plus a share of the bytes it stores (:func:`stored_bytes`), up to fixed ceilings;
    the environment's limits replace them."""
    size = stored_bytes(path)
    memory = min(MEMORY_BASE + MEMORY_PER_BYTE * size, MEMORY_CEILING)
    gib = _limit(MEMORY_VARIABLE, memory / GIB)
    timeout = _limit(
        TIMEOUT_VARIABLE, min(TIMEOUT_BASE + size / TIMEOUT_BYTES_PER_SECOND, TIMEOUT_CEILING)
    )
    return (None if gib is None else int(gib * GIB)), timeout


def spawn(
    request: dict[str, Any], stderr: IO[bytes], entry: str = "child:serve"
) -> subprocess.Popen[bytes]:
    """Start ``python -P -c`` running ``entry`` (a function of this package, by default
    :func:`.child.serve`; :func:`.writing.serve_writer` for a writing child) on the request,
    with the caller's import path and :data:`CHILD_ENVIRONMENT`, talking through pipes,
    printing to ``stderr``."""
    environment = {**CHILD_ENVIRONMENT, **os.environ}
    environment.pop("PYTHONINSPECT", None)  # would wait at a prompt once the child is done
    module, _, function = entry.partition(":")
    bootstrap = _BOOTSTRAP.format(module=module, function=function)
    command = [sys.executable, "-P", "-c", bootstrap, json.dumps(request)]
    pipe = subprocess.PIPE
    return subprocess.Popen(command, stdin=pipe, stdout=pipe, stderr=stderr, env=environment)


@dataclass
class Ending:
    """How a reading child ended (or a request to it did), for :meth:`error`: the file, the
    library and the limits; the exit status (``None``: killed at the time limit), its last
    words on stderr, the last place it noted, and whether it started at all."""

    path: Path
    library: str
    memory: int | None
    timeout: float | None
    returncode: int | None = None
    said: list[str] = field(default_factory=list)
    where: str | None = None
    frame: int | None = None
    started: bool = True

    def error(self, header: dict[str, Any]) -> Exception:
        """What to raise: what the child's result ``header`` says (its error, a bug, memory),
        or what its exit status says (a crash, the time limit)."""
        path, said, returncode, memory = self.path, self.said, self.returncode, self.memory
        raised = reported_error(header, path, "reading")
        if raised is not None:
            return raised
        kind = header.get("result")
        last = f" (it printed: {said[-1][:200]})" if said else ""
        if returncode is not None and not self.started:
            return RuntimeError(
                f"{path}: could not start a process to read it with {sys.executable} "
                f"(exit status {returncode}){last}"
            )
        if kind == "memory" or any("bad_alloc" in line for line in said):
            limit = "there is memory for"  # no cap: none asked for, or not Linux (_cap_memory)
            if memory is not None and os.path.exists("/proc/self/statm"):
                limit = (
                    f"{memory / GIB:.3g} GiB allows (the memory limit of a read: {MEMORY_VARIABLE})"
                )
            reason = f"declares more data than {limit}"
        elif returncode is None and not self.started:
            reason = (
                f"the process to read it with the {self.library} library did not start within "
                f"{self.timeout or 0:g} + {STARTUP_SECONDS:g} s (the time limit of a read: "
                f"{TIMEOUT_VARIABLE}, after the start)"
            )
        elif returncode is None:
            reason = (
                f"the {self.library} library did not finish reading it in {self.timeout:g} s: the "
                f"file is damaged or far larger than it looks (the time limit of a read: "
                f"{TIMEOUT_VARIABLE})"
            )
        else:
            given = os.environ.get(MEMORY_VARIABLE, "").strip()  # a low cap can crash pxr too
            given = f", or {MEMORY_VARIABLE}={given} is too little" if given and memory else ""
            how = how_it_died(returncode)
            reason = f"the {self.library} library crashed reading it ({how}): the file is damaged"
            reason += given + last
        where = self.where
        return InputError(f"{where}: {reason}" if where else reason, path=path, frame=self.frame)


def how_it_died(returncode: int) -> str:
    """A crashed child's exit status in words: the signal's name, or Windows's crash code."""
    if returncode < 0:
        with contextlib.suppress(ValueError):
            return signal.Signals(-returncode).name
    return _WINDOWS_CRASHES.get(returncode, f"exit status {returncode}")


class ErrorUnpickler(pickle.Unpickler):
    """Unpickles tuckercodec's errors and nothing else: no other class or function runs."""

    def find_class(self, module: str, name: str) -> Any:
        found = getattr(errors, name, None) if module == errors.__name__ else None
        if found is errors._rebuild or (
            isinstance(found, type) and issubclass(found, errors.TuckerCodecError)
        ):
            return found
        raise pickle.UnpicklingError(f"{module}.{name} is not an error of tuckercodec")


class Description:
    """What a child says of the file when it has opened it (:func:`.child.described`).

    Raises:
        InputError: an attribute or face set that the model refuses (the child built them,
            so only a child that is not ours sends one); names the file.
    """

    def __init__(self, header: dict[str, Any], arrays: dict[str, np.ndarray], path: Path):
        self.frame_count = int(header["frame_count"])
        self.vertex_count = int(header["vertex_count"])
        self.frame_names = [str(name) for name in header["frame_names"]]
        self.frame_rate = header["frame_rate"]
        self.faces = arrays["faces"]
        self.time_codes = arrays.get("time_codes")
        # checked by FrameSource._describe, as every value a child sends
        self.meters_per_unit = header.get("meters_per_unit")
        self.up_axis = header.get("up_axis")
        self.field_names = [str(name) for name in header.get("field_names", [])]
        try:
            self.attributes = [
                Attribute(
                    name,
                    domain,
                    arrays[f"attribute.{number}.values"],
                    arrays.get(f"attribute.{number}.indices"),
                    role,
                )
                for number, (name, domain, role) in enumerate(header.get("attributes", []))
            ]
            self.face_sets = [
                FaceSet(name, arrays[f"face_set.{number}"], family)
                for number, (name, family) in enumerate(header.get("face_sets", []))
            ]
        except InputError as error:
            raise InputError(error.reason, path=path) from None


def received_fields(
    header: dict[str, Any], arrays: dict[str, np.ndarray], path: Path, start: int
) -> list[Field]:
    """The fields of a ``"fields"`` result (:func:`.child.fields_sent`) of frames from
    ``start``; an InputError (from a child that is not ours) names the file and frame."""
    try:
        return [
            Field(name, arrays[f"field.{number}"], domain, role)
            for number, (name, domain, role) in enumerate(header["fields"])
        ]
    except InputError as error:
        frame = None if error.frame is None else start + error.frame
        raise InputError(error.reason, path=path, frame=frame) from None


class Child:
    """A serving child: its process, the stderr it prints to, and how its requests end."""

    def __init__(self, request: dict[str, Any], path: Path, library: str):
        self.timeout: float | None = request["timeout"]
        self.ending = Ending(path, library, request["memory"], self.timeout, started=False)
        self.stderr = tempfile.TemporaryFile()  # noqa: SIM115  # lives as long as the child
        self.process = spawn(request, self.stderr)
        self.expired = False
        self.watchdog: threading.Timer | None = None
        try:
            header, arrays = self._answer()
            self.description = Description(header, arrays, path)
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

    def read_fields(self, start: int, stop: int) -> list[Field]:
        """The fields of frames ``start`` to ``stop`` as the child's source reads them."""
        stdin = self.process.stdin
        assert stdin is not None
        try:
            stdin.write(json.dumps({"fields": [start, stop]}).encode() + b"\n")
            stdin.flush()
        except OSError:
            pass  # it died: reading its answer says how
        header, arrays = self._answer()
        return received_fields(header, arrays, self.ending.path, start)

    def _answer(self) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """The next result the child sends, with its arrays, within the time limit; or the
        error it sends, or the one that says how it ended."""
        if self.timeout is not None:  # from when the child has started, not from its spawn
            self._watch(self.timeout if self.ending.started else self.timeout + STARTUP_SECONDS)
        try:
            header = self._header()
            if header.get("result") in ("description", "frames", "fields"):
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
            self._watch(None)
        raise self._failure(header)

    def _watch(self, seconds: float | None) -> None:
        """Kill the child in ``seconds`` (the watchdog before replaced), or never (None)."""
        if self.watchdog is not None:
            self.watchdog.cancel()
        self.watchdog = None
        if seconds is not None:
            self.watchdog = threading.Timer(seconds, self._expire)
            self.watchdog.daemon = True
            self.watchdog.start()

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
            if "started" in message and not self.ending.started:
                self.ending.started = True
                if self.timeout is not None:  # the read's own limit begins now
                    self._watch(self.timeout)
            if "result" in message:
                return dict(message)
        return {}

    def _array(self, dtype: str, shape: list[int]) -> np.ndarray | None:
        """An array the child sends raw; ``None`` if its output ends first."""
        stdout = self.process.stdout
        assert stdout is not None
        array = np.empty(shape, dtype=np.dtype(dtype))
        # flat: a memoryview of a shape with a 0 in it (no faces: (0, 3)) cannot be cast
        view = memoryview(array.reshape(-1)).cast("B")  # type: ignore[arg-type]
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


def reported_error(header: dict[str, Any], path: object, doing: str) -> Exception | None:
    """The error a child's result ``header`` reports, if it reports one: our own error as it
    was raised there, or any other (a bug) as a RuntimeError with the child's traceback, saying
    what it was ``doing`` with ``path``. None for a result that is not an error."""
    kind = header.get("result")
    if kind == "error":
        raised = ErrorUnpickler(io.BytesIO(base64.b64decode(header["pickle"]))).load()
        if isinstance(raised, errors.TuckerCodecError):
            return raised
    if kind in ("bug", "error"):
        detail = header.get("traceback", "an error that is not tuckercodec's")
        return RuntimeError(f"{path}: {doing} it failed in a child process:\n{detail}")
    return None
