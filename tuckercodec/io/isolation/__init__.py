"""Reading a file with a C++ library in a child process, so that whatever the library does with
a damaged or crafted file ends as an :class:`InputError` naming the file, never as a dead or
stuck process.

Why: alembic3d segfaults on about 2 % of randomly damaged archives, and pxr allocates whatever
a crafted ``.usdc`` declares (8 GiB and 27 s for a 1 KB file declaring 2^31 face indices);
neither can be caught in the process that runs the library. :func:`read_isolated` runs a
reader in a fresh Python and turns each way it can end into an outcome in the caller:

* a sequence: sent back through a temporary file (a JSON line, then the arrays in ``.npy``
  format, read without pickle) and checked again by :class:`MeshSequence`;
* a :class:`~tuckercodec.errors.TuckerCodecError` (InputError, DependencyError): raised again
  with its class, message, path and frame (unpickled only from :mod:`tuckercodec.errors`);
* a crash (a signal; on Windows an NTSTATUS exit code): ``InputError("object /a/aShape: the
  Alembic library crashed reading it (SIGSEGV): the file is damaged", path=, frame=)``, object
  and frame being the last the reader announced with :func:`note`;
* memory: the child may add :data:`MEMORY_BASE` (2 GiB) plus :data:`MEMORY_PER_BYTE` (16) times
  the file's size to its address space (``RLIMIT_AS``, set once the libraries are imported;
  where ``/proc/self/statm`` tells its size: Linux). Reading horse gallop adds 0.4 GiB through
  pxr (its plug-ins), 0.02 GiB through Alembic; the base is for files that store a sample once
  for many frames, as both formats do. A MemoryError or ``std::bad_alloc`` becomes
  ``InputError("declares more data than 2 GiB allows")``; pxr turns some failed allocations
  into a "corrupt asset" error of its own, which comes back as such;
* time: :data:`TIMEOUT_BASE` (60 s) plus a second per :data:`TIMEOUT_BYTES_PER_SECOND` (8 MiB)
  of file, wall clock; then the child is killed and the error says so.

``TUCKERCODEC_READ_MEMORY_GIB`` and ``TUCKERCODEC_READ_TIMEOUT`` (seconds) replace those limits
(0: none). The child's stderr and stdout go to a temporary file: the libraries' messages stay
off the terminal, and the last line joins a crash's error. Ctrl-C or SIGTERM in the caller
kills the child; a child whose caller died gets Linux's parent-death signal, or its alarm.

How the child starts, measured reading horse gallop on 2 cores (a first read in a new process,
then later ones; in process 0.14/0.002 s from ``.abc``, 0.27/0.003 s from ``.usdc``): fork
0.17/0.16 s and 0.24/0.23 s, forkserver 0.42/0.16 and 0.52/0.24, spawn 0.47/0.42 and
0.55/0.54, ``subprocess`` 0.40/0.42 and 0.51/0.51. We use ``subprocess`` (``python -P -c``).
Fork copies a process with threads (2 after ``import numpy``, OpenBLAS's; 5 once pxr has run,
as it does here when writing), which POSIX leaves to deadlock in the child, Python 3.12 warns
about, and macOS and Windows do not offer. Forkserver and spawn import the caller's
``__main__`` again in the child (every user script would need an ``if __name__ ==
"__main__"`` guard), and their preloads are global state of multiprocessing. A subprocess gets
the caller's ``sys.path``, its own stderr and exit status, and the same code on every system,
for about 0.3 s more per read than in process, which the 1 s target allows. Where
``sys.executable`` cannot run Python (a frozen application) the read runs in process.

Writing is not isolated: the data is ours, and the library only re-reads what it just wrote.
What runs in the child is :mod:`.isolation_child`; a child that serves many reads of ranges,
for streaming, is :mod:`.isolated_frames`.
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
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from ... import errors
from ...errors import InputError
from ...optional import import_optional
from ...sequence import MeshSequence
from ..registry import ReadOptions
from .child import note as note  # the readers' and hooks' name for it

GIB = 2**30
#: The address space a reading child may add to what its interpreter and libraries take.
MEMORY_BASE = 2 * GIB
#: ... plus this many times the file's size.
MEMORY_PER_BYTE = 16
#: The wall-clock time a read may take: this many seconds...
TIMEOUT_BASE = 60.0
#: ... plus one second per this many bytes of file (a slow network disk).
TIMEOUT_BYTES_PER_SECOND = 8 * 2**20
MEMORY_VARIABLE = "TUCKERCODEC_READ_MEMORY_GIB"
TIMEOUT_VARIABLE = "TUCKERCODEC_READ_TIMEOUT"
#: Thread pools the child does not need, which would reserve address space per core
#: (glibc's malloc arenas, OpenBLAS's buffers, pxr's workers): one each. The user's own
#: settings win.
CHILD_ENVIRONMENT = {"MALLOC_ARENA_MAX": "2"} | dict.fromkeys(
    ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "PXR_WORK_THREAD_LIMIT"), "1"
)
#: What the child runs: the caller's import path, then a function of :mod:`.isolation_child`
#: (:func:`~.isolation_child.read_child`, or ``serve_child`` for :mod:`.isolated_frames`).
_BOOTSTRAP = (
    "import json, sys; sys.path[:] = json.loads(sys.argv[1])['sys_path']; "
    "from tuckercodec.io.isolation.child import {0}; {0}(sys.argv[1])"
)
#: How Windows reports a crash: the NTSTATUS exit codes of the usual ones.
_WINDOWS_CRASHES = {0xC0000005: "an access violation", 0xC00000FD: "a stack overflow"}


def read_isolated(
    reader: Callable[[Path, ReadOptions], MeshSequence],
    path: Path,
    options: ReadOptions,
    library: str,
    extra: str,
    preload: Iterable[str] = (),
) -> MeshSequence:
    """``reader(path, options)`` run in a child process (see the module docstring).

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
    preload = tuple(preload)
    if not can_isolate(preload, library, extra):
        return reader(path, options)  # no interpreter to start: see the module docstring
    request = child_request(reader, path, options, preload)
    memory, timeout = request["memory"], request["timeout"]
    with tempfile.TemporaryFile() as result, tempfile.TemporaryFile() as stderr:
        returncode = _run(request, result, stderr, timeout)
        result.seek(0)
        return _outcome(result, returncode, last_words(stderr), path, library, memory, timeout)


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
        "parent": os.getpid(),
    }


def last_words(stderr: IO[bytes]) -> list[str]:
    """The lines of the last 4 KiB a child printed, without pxr's banners of ``#``."""
    stderr.seek(max(0, stderr.seek(0, io.SEEK_END) - 4096))
    said = [line.strip() for line in stderr.read().decode(errors="replace").splitlines()]
    return [line for line in said if line and not line[0] == line[-1] == "#"]


def can_isolate(preload: tuple[str, ...], library: str, extra: str) -> bool:
    """Whether a child can be started (not where ``sys.executable`` cannot run Python: a
    frozen application); first, a DependencyError for a ``preload`` module that is absent."""
    for module in filter(_absent, preload):
        import_optional(module, extra, f"reading {library} files")  # DependencyError
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


def _limits(path: Path) -> tuple[int | None, float | None]:
    """The address space (bytes) and wall-clock time (s) the child may take for this file."""
    try:
        size = os.stat(path).st_size
    except OSError:
        size = 0  # the reader will say why
    gib = _limit(MEMORY_VARIABLE, (MEMORY_BASE + MEMORY_PER_BYTE * size) / GIB)
    timeout = _limit(TIMEOUT_VARIABLE, TIMEOUT_BASE + size / TIMEOUT_BYTES_PER_SECOND)
    return (None if gib is None else int(gib * GIB)), timeout


def _run(
    request: dict[str, Any], result: IO[bytes], stderr: IO[bytes], timeout: float | None
) -> int | None:
    """Run the child to its end; its exit status, or None if it ran out of time."""
    child = spawn("read_child", request, subprocess.DEVNULL, result, stderr)
    try:
        return child.wait(timeout)
    except subprocess.TimeoutExpired:
        return None
    finally:  # out of time, Ctrl-C, SIGTERM raised as an exception: no child left behind
        if child.returncode is None:
            child.kill()
            child.wait()


def spawn(
    entry: str, request: dict[str, Any], stdin: Any, stdout: Any, stderr: Any
) -> subprocess.Popen[bytes]:
    """Start ``python -P -c`` running :mod:`.isolation_child`'s function ``entry`` on the
    request, with the caller's import path and :data:`CHILD_ENVIRONMENT`."""
    environment = {**CHILD_ENVIRONMENT, **os.environ}
    environment.pop("PYTHONINSPECT", None)  # would wait at a prompt once the child is done
    command = [sys.executable, "-P", "-c", _BOOTSTRAP.format(entry), json.dumps(request)]
    return subprocess.Popen(command, stdin=stdin, stdout=stdout, stderr=stderr, env=environment)


def _outcome(
    result: IO[bytes],
    returncode: int | None,
    said: list[str],
    path: Path,
    library: str,
    memory: int | None,
    timeout: float | None,
) -> MeshSequence:
    """The sequence the child sent, or the exception that says how it ended."""
    where, frame, started = None, None, False
    header: dict[str, Any] = {}
    for line in iter(lambda: result.readline(1 << 20), b""):
        try:
            message = json.loads(line)
        except ValueError:  # torn: the child died while writing it
            break
        if "note" in message:
            where, frame = message["note"], message["frame"]
        started = started or "started" in message
        if "result" in message:
            header = message if returncode == 0 else {}  # believe only a clean exit
            break
    if header.get("result") == "sequence":
        try:
            return _sequence(result, header, path)
        except (ValueError, OSError, EOFError) as error:  # cut short: the child's disk full?
            raise RuntimeError(f"{path}: the reading process sent half a result: {error}") from None
    ending = Ending(path, library, memory, timeout, returncode, said, where, frame, started)
    raise ending.error(header)


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
        kind = header.get("result")
        if kind == "error":
            raised = _ErrorUnpickler(io.BytesIO(base64.b64decode(header["pickle"]))).load()
            if isinstance(raised, errors.TuckerCodecError):
                return raised
        if kind in ("bug", "error"):
            detail = header.get("traceback", "an error that is not tuckercodec's")
            return RuntimeError(f"{path}: reading it failed in a child process:\n{detail}")
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
        elif returncode is None:
            reason = (
                f"the {self.library} library did not finish reading it in {self.timeout:g} s: the "
                f"file is damaged or far larger than it looks (the time limit of a read: "
                f"{TIMEOUT_VARIABLE})"
            )
        else:
            given = os.environ.get(MEMORY_VARIABLE, "").strip()  # a low cap can crash pxr too
            given = f", or {MEMORY_VARIABLE}={given} is too little" if given and memory else ""
            how = _how(returncode)
            reason = f"the {self.library} library crashed reading it ({how}): the file is damaged"
            reason += given + last
        where = self.where
        return InputError(f"{where}: {reason}" if where else reason, path=path, frame=self.frame)


def _how(returncode: int) -> str:
    """A crashed child's exit status in words: the signal's name, or Windows's crash code."""
    if returncode < 0:
        with contextlib.suppress(ValueError):
            return signal.Signals(-returncode).name
    return _WINDOWS_CRASHES.get(returncode, f"exit status {returncode}")


def _sequence(result: IO[bytes], header: dict[str, Any], path: Path) -> MeshSequence:
    """The sequence whose arrays follow the header in the result file."""
    arrays = [np.lib.format.read_array(result, allow_pickle=False) for _ in header["arrays"]]
    named = dict(zip(header["arrays"], arrays, strict=True))
    try:
        return MeshSequence(
            named["vertices"],
            named["faces"],
            frame_names=header["frame_names"],
            frame_rate=header["frame_rate"],
            time_codes=named.get("time_codes"),
        )
    except InputError as error:
        raise InputError(error.reason, path=path, frame=error.frame) from None


class _ErrorUnpickler(pickle.Unpickler):
    """Unpickles tuckercodec's errors and nothing else: no other class or function runs."""

    def find_class(self, module: str, name: str) -> Any:
        found = getattr(errors, name, None) if module == errors.__name__ else None
        if found is errors._rebuild or (
            isinstance(found, type) and issubclass(found, errors.TuckerCodecError)
        ):
            return found
        raise pickle.UnpicklingError(f"{module}.{name} is not an error of tuckercodec")
