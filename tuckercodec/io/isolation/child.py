"""The child of :mod:`tuckercodec.io.isolation`: what runs in the child process, started with
``python -P -c`` and given its request (opener, file, options, limits) as JSON.

One protocol, over the child's stdin and stdout. The child writes to its stdout, unbuffered so
that nothing is lost in a crash, one JSON line at a time: ``{"started": true}`` once its
libraries are imported and its memory capped, the reader's notes (:func:`note`: where it
reads, for the error should it crash there), then a result header: the description of the
opened source (``"description"``) or frames (``"frames"``), each followed by its arrays as raw
bytes (the header lists their names, dtypes and shapes), or an error (our own errors pickled; a
failed allocation; a bug's traceback). The description carries the source's attributes and face
sets (names, domains, roles and families in the header, values as arrays) and its field names.
It reads one request a line on its stdin, ``{"read": [start, stop]}`` for frames or ``{"fields":
[start, stop]}`` for the animated fields of a range (result ``"fields"``: each field's name,
domain and role, its values an array), and leaves when its stdin ends. What the libraries print
goes to stderr.
"""

from __future__ import annotations

import base64
import contextlib
import importlib
import json
import os
import pickle
import signal
import sys
import traceback
from pathlib import Path
from typing import IO, Any

import numpy as np

from ... import errors
from ...model.attributes import Field
from ...model.sequence import MeshSequence
from ...model.sources import FrameSource, SequenceFrames
from ..registry import ReadOptions

#: In the child: where :func:`note` writes (its stdout); None in any other process.
_notes: IO[bytes] | None = None


def note(where: str, frame: int | None = None) -> None:
    """Tell the caller what the reader reads now (``"object /a/aShape"``, and the frame), for
    the error should the library crash there. Does nothing outside a reading child."""
    if _notes is not None:
        send({"note": where, "frame": frame})


def start_child(request: dict[str, Any]) -> Any:
    """Make this process a reading child (notes and results on stdout, the libraries' prints
    to stderr, signals, limits), and return the function the request names."""
    global _notes
    _notes = os.fdopen(os.dup(1), "wb", buffering=0)  # unbuffered: notes survive a crash
    os.dup2(2, 1)  # what the libraries print to stdout goes with their stderr
    guard(request)
    module, _, name = request["reader"].partition(":")
    reader = getattr(importlib.import_module(module), name)
    for library in request["preload"]:  # their own mappings are not the file's doing
        with contextlib.suppress(ImportError):  # the reader raises DependencyError
            importlib.import_module(library)
    _cap_memory(request["memory"])
    if request["alarm"] is not None and hasattr(signal, "alarm"):
        signal.alarm(request["alarm"])  # the read's own time begins, as the caller's does
    send({"started": True})
    return reader


def child_options(request: dict[str, Any]) -> ReadOptions:
    """The request's read options."""
    options = dict(request["options"])
    if options["faces"] is not None:
        options["faces"] = Path(options["faces"])
    return ReadOptions(**options)


def send_failure(error: BaseException) -> None:
    """Send what stopped the reader: our error (pickled), a failed allocation, or a bug."""
    if isinstance(error, errors.TuckerCodecError):
        pickled = base64.b64encode(pickle.dumps(error)).decode()
        send(_memory(error) or {"result": "error", "pickle": pickled})
    else:
        send(_memory(error) or {"result": "bug", "traceback": traceback.format_exc()})


def send(message: dict[str, Any]) -> None:
    """One line of the child's output: a note, or the result's header."""
    assert _notes is not None
    _notes.write(json.dumps(message).encode() + b"\n")


def guard(request: dict[str, Any]) -> None:
    """Signals and limits of a child, reading or writing: Ctrl-C is the caller's to handle (it
    kills us), no core dump of a crash, death with the caller (Linux) or after the time
    allowed."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
    except (ImportError, ValueError, OSError):
        pass  # Windows: no core files to keep from the disk
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG: die with the caller
        if os.getppid() != request["parent"]:  # the caller died before prctl
            os._exit(1)
    if request["alarm"] is not None and hasattr(signal, "alarm"):
        # SIGALRM's default ends the process, even mid-library; the start has time of its own
        signal.alarm(request["alarm"] + request["startup"])


def _cap_memory(memory: int | None) -> None:
    """Let the child's address space grow by ``memory`` bytes from here, where the system
    says how large it is (Linux)."""
    if memory is None:
        return
    try:
        import resource

        with open("/proc/self/statm", "rb") as statm:
            now = int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        _, hard = resource.getrlimit(resource.RLIMIT_AS)
        cap = now + memory if hard == resource.RLIM_INFINITY else min(hard, now + memory)
        resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    except (ImportError, OSError, ValueError, IndexError):
        pass  # not Linux: isolated, without a cap


def _memory(error: BaseException) -> dict[str, Any] | None:
    """The "memory" outcome if the error, or one it was raised from, is a failed allocation."""
    seen: BaseException | None = error
    for _ in range(8):
        if seen is None:
            return None
        try:
            text = str(seen)
        except Exception:
            text = ""
        if isinstance(seen, MemoryError) or "bad_alloc" in text:
            return {"result": "memory"}
        seen = seen.__cause__ or seen.__context__
    return None


def serve(argument: str) -> None:
    """The child's whole life: open the request's source (a
    :class:`~tuckercodec.model.sources.FrameSource` class, or a function that reads a whole
    sequence, served from memory), send its description, then for each line ``{"read": [start,
    stop]}`` on stdin send the frames (for ``{"fields": [start, stop]}`` the fields), until stdin
    ends; then exit (never returns). Our own errors are sent and the child serves on; anything
    else ends it. The time limit (``alarm``) runs while
    the child opens the file or reads, not while it waits."""
    request = json.loads(argument)
    try:
        opener = start_child(request)
        path = Path(request["path"])
        source = opener(path, child_options(request))
        if isinstance(source, MeshSequence):  # read whole: served from memory
            source = SequenceFrames(source, path)
        send_arrays(*described(source))
    except BaseException as error:
        send_failure(error)
        os._exit(0)
    alarm = request["alarm"] if hasattr(signal, "alarm") else None
    if alarm is not None:
        signal.alarm(0)  # waiting for the caller is not reading
    for line in sys.stdin.buffer:
        request = json.loads(line)
        start, stop = request["read"] if "read" in request else request["fields"]
        if alarm is not None:
            signal.alarm(alarm)
        try:
            if "read" in request:
                send_arrays({"result": "frames"}, {"vertices": source.read(start, stop)})
            else:
                send_arrays(*fields_sent(source.read_fields(start, stop)))
        except errors.TuckerCodecError as error:
            send_failure(error)  # the file's fault in these frames: others may still be read
        except BaseException as error:
            send_failure(error)
            os._exit(0)
        if alarm is not None:
            signal.alarm(0)
    os._exit(0)


def described(source: FrameSource) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """The description of an opened source as a result header and its arrays: the faces and
    time codes, each attribute's values (and indices) and each face set's faces as arrays
    ``attribute.N.values``, ``attribute.N.indices``, ``face_set.N``, listed in the header."""
    arrays = {"faces": source.faces}
    if source.time_codes is not None:
        arrays["time_codes"] = source.time_codes
    attributes = []
    for number, attribute in enumerate(source.attributes):
        attributes.append([attribute.name, attribute.domain, attribute.role])
        arrays[f"attribute.{number}.values"] = attribute.values
        if attribute.indices is not None:
            arrays[f"attribute.{number}.indices"] = attribute.indices
    for number, face_set in enumerate(source.face_sets):
        arrays[f"face_set.{number}"] = face_set.faces
    description = {
        "frame_count": source.frame_count,
        "vertex_count": source.vertex_count,
        "frame_names": source.frame_names,
        "frame_rate": source.frame_rate,
        "meters_per_unit": source.meters_per_unit,
        "up_axis": source.up_axis,
        "attributes": attributes,
        "face_sets": [[face_set.name, face_set.family] for face_set in source.face_sets],
        "field_names": source.field_names,
    }
    return {"result": "description", **description}, arrays


def fields_sent(fields: list[Field]) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """Fields read for a range as a result header (each field's name, domain and role) and
    their values as arrays ``field.N``."""
    listed = [[item.name, item.domain, item.role] for item in fields]
    arrays = {f"field.{number}": item.values for number, item in enumerate(fields)}
    return {"result": "fields", "fields": listed}, arrays


def send_arrays(header: dict[str, Any], arrays: dict[str, np.ndarray]) -> None:
    """A result header listing the arrays (name, dtype, shape), then their bytes, raw: the
    caller reads them into arrays it allocates, from a pipe that cannot seek."""
    contiguous = {name: np.ascontiguousarray(array) for name, array in arrays.items()}
    listed = [[name, a.dtype.str, list(a.shape)] for name, a in contiguous.items()]
    send({**header, "arrays": listed})
    assert _notes is not None
    for array in contiguous.values():
        # flat: a memoryview of a shape with a 0 in it (no faces: (0, 3)) cannot be cast
        data = memoryview(array.reshape(-1)).cast("B")  # type: ignore[arg-type]
        while data:
            written = _notes.write(data) or 0
            data = data[written:]
