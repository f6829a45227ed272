"""Writing a file with a C++ library in a child process, so that whatever the library does when
the write fails ends as an ``OSError`` naming the output, never as a dead process.

Why: when the disk fills (or any write fails) alembic3d raises the error, then aborts the
process (SIGABRT) when the archive's objects are released: their destructors write what is left
of the archive to a stream that throws, and a C++ exception out of a destructor ends in
``std::terminate``. Nothing in the process that runs the library can catch that, so the write
runs in a child (:func:`write_isolated`) and the caller only hears how it ended.

The conversation, started as the reading child is (:func:`.channel.spawn`, ``python -P -c``),
with the same guards (:func:`.child.guard`: Ctrl-C is the caller's, no core file, death with
the caller): the request (the writer's name, the path, small values) as JSON in the child's
argument; the arrays on its stdin, a JSON line listing their names, dtypes and shapes, then
their bytes, raw; one JSON line back on its stdout, ``{"result": "written"}``, ``"failed"``
(an ``OSError``'s errno and text), ``"error"`` (our own error, pickled) or ``"bug"`` (a
traceback). The child answers once the writer has returned, its objects released (a library
writes its file as they go), and leaves with ``os._exit``, so that after a failure nothing of
the library is released at all. What the library prints goes to a temporary file: its last
line joins the error if the child dies.

No memory or time limit: the data is ours, not a file's. Ctrl-C in the caller kills the child.
Where ``sys.executable`` cannot run Python (a frozen application) the writer runs in process.
"""

from __future__ import annotations

import base64
import errno
import importlib
import json
import os
import pickle
import shutil
import subprocess
import sys
import tempfile
import traceback
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import IO, Any

import numpy as np

from ... import errors
from .channel import can_isolate, how_it_died, last_words, reported_error, spawn
from .child import guard

#: What a writer is: ``writer(path, arrays, values)`` writes ``path``; it raises OSError when the
#: library fails.
Writer = Callable[[Path, dict[str, np.ndarray], dict[str, Any]], None]

#: Free bytes below which a failed write is taken for a full disk (a file system keeps a few
#: blocks that a write of a sample's size cannot use).
_NEARLY_FULL = 1 << 20


def write_isolated(
    writer: Writer,
    path: Path,
    arrays: dict[str, np.ndarray],
    values: dict[str, Any],
    *,
    shown: Path,
    library: str,
    extra: str,
    preload: Iterable[str] = (),
) -> None:
    """``writer(path, arrays, values)`` run in a child process (see the module docstring).

    Args:
        writer: a module-level function of the package (the child imports it by name).
        path: the file it writes (a staging name: the caller removes it on failure).
        arrays: the data, sent to the child raw.
        values: small values (JSON).
        shown: the output the user asked for, which the errors name.
        library: the library's name for messages ("Alembic").
        extra: the extra that installs it.
        preload: the modules the writer imports: a missing one is a DependencyError without
            starting a process.

    Raises:
        OSError: the writer's, or the death of the child; its filename is ``shown``.
        DependencyError: what the writer raised, or a ``preload`` module that is absent.
        RuntimeError: the child could not start, or the writer failed for a reason other
            than the output (a bug): the child's traceback is in the message.
    """
    if not can_isolate(tuple(preload), library, extra, "writing"):
        try:
            writer(path, arrays, values)
        except OSError as error:
            raise _failed(error.errno, error.strerror or str(error), shown) from None
        return
    request = {
        "sys_path": [entry for entry in sys.path if isinstance(entry, str)],
        "writer": f"{writer.__module__}:{writer.__qualname__}",
        "path": os.fspath(path),
        "values": values,
        "parent": os.getpid(),
        "alarm": None,
        "startup": 0,
    }
    with tempfile.TemporaryFile() as stderr:
        process = spawn(request, stderr, "writing:serve_writer")
        answer = None
        try:
            answer = _conversation(process, arrays)
        finally:
            if answer is None:  # interrupted (Ctrl-C): the child must not finish the file
                process.kill()
            process.wait()
            for stream in (process.stdin, process.stdout):
                if stream is not None:
                    stream.close()
        _outcome(answer, process.returncode, last_words(stderr), shown, library)


def _conversation(
    process: subprocess.Popen[bytes], arrays: dict[str, np.ndarray]
) -> dict[str, Any]:
    """Send the arrays, return the child's answer (``{}`` if it died without one)."""
    stdin, stdout = process.stdin, process.stdout
    assert stdin is not None and stdout is not None
    contiguous = {name: np.ascontiguousarray(array) for name, array in arrays.items()}
    listed = [[name, a.dtype.str, list(a.shape)] for name, a in contiguous.items()]
    try:
        stdin.write(json.dumps({"arrays": listed}).encode() + b"\n")
        for array in contiguous.values():
            # flat: a memoryview of a shape with a 0 in it (no faces: (0, 3)) cannot be cast
            stdin.write(memoryview(array.reshape(-1)).cast("B"))  # type: ignore[arg-type]
        stdin.close()
    except OSError:
        pass  # it died: its answer, or its exit status, says how
    line = stdout.readline(1 << 20)
    try:
        return dict(json.loads(line)) if line else {}
    except ValueError:  # torn: it died while answering
        return {}


def _outcome(
    answer: dict[str, Any], returncode: int, said: list[str], shown: Path, library: str
) -> None:
    """Return if the child wrote the file, else raise what its answer or its end says."""
    kind = answer.get("result")
    if kind == "written":
        return
    if kind == "failed":
        raise _failed(answer["errno"], answer["message"], shown)
    raised = reported_error(answer, shown, "writing")
    if raised is not None:
        raise raised
    last = f" (it printed: {said[-1][:200]})" if said else ""
    raise _failed(
        None, f"the {library} library died writing it ({how_it_died(returncode)}){last}", shown
    )


def _failed(number: int | None, message: str, shown: Path) -> OSError:
    """The OSError for a failed write of ``shown``: ``number``, or ENOSPC where its disk is
    (nearly) full (said so, as the library's own words rarely do), else EIO."""
    try:
        free = shutil.disk_usage(shown.parent).free
    except OSError:
        free = None
    if number in (None, errno.EIO) and free is not None and free < _NEARLY_FULL:
        number = errno.ENOSPC
        message = f"no space left on device ({free} bytes free); {message}"
    return OSError(number or errno.EIO, message, os.fspath(shown))


# ------------------------------------------------------------------------------------------
# the child


def serve_writer(argument: str) -> None:
    """The writing child's whole life: read the arrays from stdin, run the writer, answer one
    line, exit (never returns)."""
    request = json.loads(argument)
    answer = os.fdopen(os.dup(1), "wb", buffering=0)
    os.dup2(2, 1)  # what the library prints to stdout goes with its stderr
    try:
        guard(request)
        module, _, name = request["writer"].partition(":")
        writer = getattr(importlib.import_module(module), name)
        arrays = _receive(sys.stdin.buffer)
        writer(Path(request["path"]), arrays, request["values"])
    except BaseException as error:
        # answered and gone while the error lives: releasing it would release the library's
        # objects, whose destructors abort after a failed write
        answer.write(json.dumps(_result(error)).encode() + b"\n")
        os._exit(0)
    answer.write(json.dumps({"result": "written"}).encode() + b"\n")
    os._exit(0)


def _result(error: BaseException) -> dict[str, Any]:
    """The answer for what stopped the writer: the output's fault (an OSError), ours, a bug."""
    if isinstance(error, OSError):
        return {"result": "failed", "errno": error.errno, "message": error.strerror or str(error)}
    if isinstance(error, MemoryError):
        return {"result": "failed", "errno": errno.ENOMEM, "message": "out of memory"}
    if isinstance(error, errors.TuckerCodecError):
        return {"result": "error", "pickle": base64.b64encode(pickle.dumps(error)).decode()}
    return {"result": "bug", "traceback": traceback.format_exc()}


def _receive(stdin: IO[bytes]) -> dict[str, np.ndarray]:
    """The arrays the caller sends: their list on a line, then their bytes."""
    header = json.loads(stdin.readline())
    arrays = {}
    for name, dtype, shape in header["arrays"]:
        array = np.empty(shape, dtype=np.dtype(dtype))
        view = memoryview(array.reshape(-1)).cast("B")  # type: ignore[arg-type]
        done = 0
        while done < len(view):
            count = stdin.readinto(view[done:])  # type: ignore[attr-defined]  # buffered
            if not count:
                raise EOFError("the caller's data ended early")
            done += count
        arrays[name] = array
    return arrays
