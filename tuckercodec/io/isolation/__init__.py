"""Reading a file with a C++ library in a child process, so that whatever the library does with
a damaged or crafted file ends as an :class:`InputError` naming the file, never as a dead or
stuck process.

Why: alembic3d segfaults on about 2 % of randomly damaged archives, and pxr allocates whatever
a crafted ``.usdc`` declares (8 GiB and 27 s for a 1 KB file declaring 2^31 face indices);
neither can be caught in the process that runs the library. :class:`IsolatedFrames` opens a
format's source (``usd.StageFrames``, ``alembic.ArchiveFrames``) in a fresh Python, which
serves reads of frame ranges, and turns each way a request can end into an outcome in the
caller:

* frames (and first the source's description): sent back raw through a pipe (the protocol is
  :mod:`.child`'s; no pickle) and checked again by :class:`~tuckercodec.model.sources.FrameSource`;
* a :class:`~tuckercodec.errors.TuckerCodecError` (InputError, DependencyError): raised again
  with its class, message, path and frame (unpickled only from :mod:`tuckercodec.errors`);
* a crash (a signal; on Windows an NTSTATUS exit code): ``InputError("object /a/aShape: the
  Alembic library crashed reading it (SIGSEGV): the file is damaged", path=, frame=)``, object
  and frame being the last the reader announced with :func:`note`;
* memory: the child may add :data:`MEMORY_BASE` (2 GiB) plus :data:`MEMORY_PER_BYTE` (16) times
  the bytes the file stores, up to :data:`MEMORY_CEILING` (64 GiB), to its address space
  (``RLIMIT_AS``, set once the libraries are imported; where ``/proc/self/statm`` tells its
  size: Linux). Reading horse gallop adds 0.4 GiB through pxr (its plug-ins), 0.02 GiB through
  Alembic; the base is for files that store a sample once for many frames, as both formats do.
  A MemoryError or ``std::bad_alloc`` becomes ``InputError("declares more data than 2 GiB
  allows")``; pxr turns some failed allocations into a "corrupt asset" error of its own, which
  comes back as such;
* time: :data:`TIMEOUT_BASE` (60 s) plus a second per :data:`TIMEOUT_BYTES_PER_SECOND` (8 MiB)
  the file stores, up to :data:`TIMEOUT_CEILING` (an hour), wall clock, for each request (the
  opening, then each read), not for the child's life; then a watchdog kills the child and the
  error says so. The opening's time begins when the child has started (its interpreter and the
  library imported, which is not the file's doing and slow on a busy machine), which may take
  :data:`~.channel.STARTUP_SECONDS` more;
* the bytes a file stores are its size, but no more than the disk blocks allocated to it
  (:func:`~.channel.stored_bytes`): a 942-byte ``.usdc`` padded with a 1 TiB hole, which costs
  nothing on disk, gets the limits of 942 bytes, not 16,386 GiB and 36 hours (and pxr, which
  maps the whole file, refuses it).

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

Why one child for many reads rather than one per read: starting the interpreter, importing
the library and opening the stage cost about 0.5 s (pxr) and 0.3 s (alembic3d) per child on
this machine, once; a read then costs its frames' sampling and a copy through a pipe (see
BENCHMARKS for the measured figures). After a crash the next read starts a new child; so does
the first read after unpickling (workers of a process pool or Dask each start their own).
:func:`read_isolated` is the same child for a function that reads a whole sequence at once.

Writing a file with Alembic runs in a child too (:func:`write_isolated`, :mod:`.writing`), not
for the data, which is ours, but because alembic3d aborts the process once a write has failed
(a full disk). What runs in a reading child is :mod:`.child`; the caller's side of the
conversation, with the limits, is :mod:`.channel`.
"""

from .channel import (
    MEMORY_BASE,
    MEMORY_CEILING,
    MEMORY_PER_BYTE,
    MEMORY_VARIABLE,
    TIMEOUT_BASE,
    TIMEOUT_BYTES_PER_SECOND,
    TIMEOUT_CEILING,
    TIMEOUT_VARIABLE,
)
from .child import note  # the readers' and hooks' name for it
from .parent import IsolatedFrames, read_isolated
from .writing import write_isolated

__all__ = [
    "MEMORY_BASE",
    "MEMORY_CEILING",
    "MEMORY_PER_BYTE",
    "MEMORY_VARIABLE",
    "TIMEOUT_BASE",
    "TIMEOUT_BYTES_PER_SECOND",
    "TIMEOUT_CEILING",
    "TIMEOUT_VARIABLE",
    "IsolatedFrames",
    "note",
    "read_isolated",
    "write_isolated",
]
