"""Running one function over many items: in this process, on the cores of this machine, or on a
Dask cluster. The only module that knows about Dask, and longer than most for it: starting and
stopping a LocalCluster cleanly (signals, environment, workers killed or not) is half of it.

:func:`open_executor` picks the executor: with neither ``jobs`` nor ``scheduler`` a plain loop in
this process (Dask is not imported); with ``jobs=N`` a ``dask.distributed`` LocalCluster of N
worker processes on this machine (loopback only, one thread each, and one BLAS thread each, so
that N workers use N cores); with ``scheduler="tcp://host:port"`` the cluster that scheduler
runs. A task computes what it would compute in process; only where it runs changes. The
results are then the same bit for bit, but for what depends on the number of BLAS threads
(sums in another order): the workers have one, a process alone as many as it has cores.

What a function and its arguments must be:

* ``function`` is a module-level function (pickled by name; each worker imports its module);
* each value in ``common`` (a large array the tasks share) is sent to each worker once per
  :meth:`Executor.map` call, not once per item (on a LocalCluster, its large arrays are written
  once to a file in memory, whose pages every task maps);
* an item that is a large array or bytes (1 MiB or more) is sent ahead of its task; any other
  large data belongs in ``common``, or is read by the task itself from a file;
* a task's exception comes back as itself, class and fields intact (the package's errors pickle:
  :mod:`tuckercodec.errors`), with the worker's traceback as a note.

The workers of a remote cluster need tuckercodec installed, the same version as the caller's
(checked on connecting), and read files by the paths the caller gives: a shared file system.

A script that uses ``jobs`` must start from an ``if __name__ == "__main__":`` block, as with any
Dask LocalCluster or multiprocessing pool: each worker process starts a new Python, which imports
the script's main module again.

Ctrl-C stops the caller, which stops the workers at once (they ignore it themselves: see
:func:`_start_cluster`); so do an error and the end of a ``with`` block, the workers being
killed if tasks were left running. A worker that dies fails only the task it was running.
"""

from __future__ import annotations

import abc
import contextlib
import itertools
import logging
import mmap
import multiprocessing
import os
import pickle
import shutil
import signal
import tempfile
import threading
import traceback
import uuid
from collections.abc import Callable, Generator, Iterator, Sequence
from dataclasses import dataclass
from types import TracebackType
from typing import Any, Generic, TypeVar

from .._version import __version__
from ..errors import TuckerCodecError
from .optional import import_optional
from .progress import progress as progress_bar

T = TypeVar("T")

#: What :meth:`Executor.map` reports after each finished item: (items done, items in all).
ProgressCallback = Callable[[int, int], None]
#: Progress: a label (a bar on standard error when it is a terminal, as the readers draw), a
#: callback, or nothing.
Progress = str | ProgressCallback | None

#: The extra that installs Dask and dask.distributed.
EXTRA = "dask"
#: An item at least this large (numpy array or bytes) is sent to the workers before its task:
#: Dask warns about task graphs over 10 MB, and a graph is sent through the scheduler.
LARGE_ITEM_BYTES = 2**20
#: The environment each LocalCluster worker starts with: one BLAS/OpenMP thread, since the
#: cluster has one worker process per core. Set before the process starts (the libraries read
#: it once, when loaded).
WORKER_ENVIRONMENT = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
#: The LocalCluster scheduler's settings: a task whose worker died (out of memory, a crash in
#: a library) fails at once, where distributed would try it on 3 more workers, each of which it
#: would likely kill in the same way. And no active memory manager: its ReduceReplicas policy
#: (every 2 s) drops the copies a broadcast put on each worker, so the next task there fetched
#: the shared values again, a second copy on that worker (seen by test_parallel about once in
#: 25 maps on a busy machine).
SCHEDULER_CONFIG = {
    "distributed.scheduler.allowed-failures": 0,
    "distributed.scheduler.active-memory-manager.start": False,
}
#: How long connecting to a remote scheduler may take.
CONNECT_SECONDS = 10
#: How long a worker process may take to stop once asked, when the work is abandoned (Ctrl-C,
#: an error): then it is killed. A normal close waits for nothing (no task is running).
KILL_SECONDS = 0.5


@dataclass(frozen=True)
class Completed:
    """One finished item: its position in ``items``, and the function's value or the exception
    it raised (one of the two is None, unless the function returned None)."""

    index: int
    value: Any
    error: BaseException | None


class Executor(abc.ABC):
    """Runs a function over items, here or on workers. Use it as a context manager, or call
    :meth:`close` when done."""

    #: How many tasks run at once: 1 in process, else the workers' threads in all.
    workers: int

    def __init__(self, progress: Progress = None) -> None:
        self.progress = progress

    def map(self, function: Callable[..., T], items: Sequence[Any], *common: Any) -> list[T]:
        """``[function(item, *common) for item in items]``, run by the workers.

        The results come in the order of ``items``, whatever order the tasks finish in. The
        first task to fail (in the order they finish) cancels the rest, and its exception is
        raised here, with its class and fields.
        """
        results: list[Any] = [None] * len(items)
        finished = self.as_completed(function, items, *common)
        try:
            for done, completed in enumerate(self._with_progress(finished, len(items)), 1):
                if completed.error is not None:
                    raise completed.error
                results[completed.index] = completed.value
                if callable(self.progress):
                    self.progress(done, len(items))
        finally:
            finished.close()  # cancels what is still queued or running
        return results

    def _with_progress(self, finished: Iterator[Completed], total: int) -> Iterator[Completed]:
        if isinstance(self.progress, str):
            return progress_bar(finished, total, self.progress)
        return finished

    @abc.abstractmethod
    def as_completed(
        self, function: Callable[..., Any], items: Sequence[Any], *common: Any
    ) -> Generator[Completed, None, None]:
        """Run ``function(item, *common)`` for every item and yield each one as it finishes,
        successful or not: a task's exception is given, not raised. Closing the iterator early
        cancels the tasks that have not finished."""

    @abc.abstractmethod
    def close(self) -> None:
        """Stop the workers, or disconnect from them."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        self.close()


class InProcessExecutor(Executor):
    """A plain loop in this process, one item after the other."""

    workers = 1

    def as_completed(
        self, function: Callable[..., Any], items: Sequence[Any], *common: Any
    ) -> Generator[Completed, None, None]:
        for index, item in enumerate(items):
            try:
                value = function(item, *common)
            except Exception as error:  # given to the caller, as a worker's would be
                yield Completed(index, None, error)
            else:
                yield Completed(index, value, None)

    def close(self) -> None:
        """Nothing to stop."""


class DaskExecutor(Executor):
    """Tasks on a dask.distributed cluster: a LocalCluster it started (``cluster``), or a remote
    one it only connected to (``cluster`` None). Built by :func:`open_executor`."""

    def __init__(self, client: Any, cluster: Any | None, progress: Progress = None) -> None:
        super().__init__(progress)
        self.client = client
        self.cluster = cluster
        # a remote cluster may have no worker yet (one that grows on demand): count 1
        self.workers = max(1, sum(client.nthreads().values()))
        self._abandoned = False  # tasks were left running: stop the workers without waiting
        # On a LocalCluster, one task per worker at a time (distributed would send each two):
        # a worker that dies (out of memory, a crash in a library) then takes down only the
        # task it was running. A remote cluster gets them all, to queue and scale as it does.
        self._in_flight = self.workers if cluster is not None else 0
        self._submitted: set[Any] = set()  # the futures of the maps under way
        # On a LocalCluster, the workers hand large results back through files in memory
        # (:class:`_HandedOff`): removed, with whatever a task left there, on closing
        self._handoff = _handoff_directory() if cluster is not None else None

    def as_completed(
        self, function: Callable[..., Any], items: Sequence[Any], *common: Any
    ) -> Generator[Completed, None, None]:
        distributed = import_optional("distributed", EXTRA, "running on Dask workers")
        client = self.client
        sent: list[Any] = []  # every future made here, released at the end
        handed: list[_HandedOff] = []  # the common values' files, removed at the end
        try:
            values = list(common)
            if self._handoff is not None:  # large ones written once, mapped by every task
                values = [_HandedOff.wrap(value, self._handoff) for value in values]
                handed += [value for value in values if isinstance(value, _HandedOff)]
            # a list, so that scatter sends each value whole (it splits lists and dicts)
            shared = client.scatter(values, broadcast=True, hash=False) if values else []
            sent += shared
            large = [i for i, item in enumerate(items) if _nbytes(item) >= LARGE_ITEM_BYTES]
            arguments = list(items)
            if large:
                scattered = client.scatter([items[i] for i in large], hash=False)
                sent += scattered
                for i, future in zip(large, scattered, strict=True):
                    arguments[i] = future
            name = getattr(function, "__name__", "task")
            batch = uuid.uuid4().hex[:12]
            position: dict[Any, int] = {}
            finished = distributed.as_completed([], loop=client.loop)
            waiting = iter(enumerate(arguments))

            def submit_next() -> None:
                for i, argument in itertools.islice(waiting, 1):
                    future = client.submit(
                        _call,
                        function,
                        argument,
                        *shared,
                        handoff=self._handoff,
                        key=f"{name}-{batch}-{i}",
                        pure=False,
                    )
                    sent.append(future)
                    self._submitted.add(future)
                    position[future.key] = i
                    finished.add(future)

            for _ in range(self._in_flight or len(arguments)):
                submit_next()
            for future in finished:
                submit_next()  # before the caller handles this one: no worker waits for it
                yield _completed(position[future.key], future)
        except BaseException:
            # stopped early (an error, Ctrl-C): cancelling does not stop a running task
            self._abandoned = self._abandoned or self._busy()
            raise
        finally:
            self._submitted.difference_update(sent)
            if sent:
                with contextlib.suppress(Exception):  # the cluster may be gone already
                    client.cancel(sent)
            for value in handed:  # a task still running keeps its mapping of the file
                with contextlib.suppress(OSError):
                    os.unlink(value.path)

    def _busy(self) -> bool:
        """Whether a task submitted here may still be queued or running."""
        return any(not future.done() for future in self._submitted)

    def close(self) -> None:
        """Disconnect; stop the LocalCluster, at once if tasks were left running (Ctrl-C, an
        error) rather than waiting for them."""
        hurry = self._abandoned or self._busy()
        try:
            with contextlib.suppress(Exception):
                self.client.close()
            if self.cluster is not None:
                if hurry:
                    _kill_workers(self.cluster)
                self.cluster.close()
        finally:
            self.cluster = None
            self._submitted.clear()
            if self._handoff is not None:
                shutil.rmtree(self._handoff, ignore_errors=True)
                self._handoff = None


class Background(Generic[T]):
    """``function(*args)`` run in a daemon thread of this process, beside the caller's own
    work: for what only this process can do while the workers (or BLAS, which releases the
    GIL) keep the cores busy. :meth:`result` waits for it, and gives its value or raises its
    exception. A daemon thread, so that Ctrl-C or an error in the caller never waits for work
    it no longer wants (a thread cannot be stopped; it dies with the process)."""

    def __init__(self, function: Callable[..., T], *args: Any, name: str = "background") -> None:
        self._outcome: list[Any] = []  # [value, None] or [None, exception], once done
        self._thread = threading.Thread(
            target=self._run, args=(function, args), name=f"tuckercodec: {name}", daemon=True
        )
        self._thread.start()

    def _run(self, function: Callable[..., Any], args: tuple[Any, ...]) -> None:
        try:
            self._outcome[:] = [function(*args), None]
        except BaseException as error:  # handed to the caller of result()
            self._outcome[:] = [None, error]

    def result(self) -> T:
        """The function's value, once it has returned; its exception, raised here, if it
        raised one."""
        self._thread.join()
        value, error = self._outcome
        if error is not None:
            raise error
        result: T = value
        return result


def open_executor(
    jobs: int | None = None, scheduler: str | None = None, *, progress: Progress = None
) -> Executor:
    """The executor for ``jobs`` worker processes on this machine, or a Dask cluster.

    Args:
        jobs: None: run in this process (no Dask). N >= 1: start a LocalCluster of N worker
            processes, one thread each, listening on 127.0.0.1 only.
        scheduler: the address of a running Dask scheduler (``tcp://host:port``); its workers
            need tuckercodec installed (the same version) and the input files at the same paths.
            Give ``jobs`` or ``scheduler``, not both.
        progress: a label to draw a progress bar of each :meth:`Executor.map` (on standard
            error, when it is a terminal), or a callable ``progress(done, total)`` called after
            each item.

    Raises:
        ValueError: ``jobs`` below 1, or both ``jobs`` and ``scheduler``.
        DependencyError: dask.distributed is not installed (the extra ``[dask]``).
        TuckerCodecError: the scheduler cannot be reached, or its workers lack tuckercodec or
            have another version.
    """
    if jobs is not None and scheduler is not None:
        raise ValueError(
            "give jobs (a cluster on this machine) or a scheduler (a running cluster, whose "
            "workers are its own), not both"
        )
    if jobs is not None and jobs < 1:
        raise ValueError(f"jobs must be at least 1, got {jobs}")
    if jobs is None and scheduler is None:
        return InProcessExecutor(progress)
    purpose = "running on several cores (--jobs) or on a Dask cluster (--scheduler)"
    distributed = import_optional("distributed", EXTRA, purpose)
    if scheduler is not None:
        return DaskExecutor(_connect(distributed, scheduler), None, progress)
    assert jobs is not None
    return _start_local(distributed, jobs, progress)


def _start_local(distributed: Any, jobs: int, progress: Progress) -> DaskExecutor:
    """A LocalCluster of ``jobs`` single-threaded worker processes on loopback, and a client."""
    cluster = _start_cluster(distributed, jobs)
    try:
        client = distributed.Client(cluster, set_as_default=False)
    except BaseException:
        cluster.close()
        raise
    return DaskExecutor(client, cluster, progress)


def _start_cluster(distributed: Any, jobs: int) -> Any:
    """The LocalCluster, its worker processes started ignoring SIGINT.

    The terminal's Ctrl-C reaches every process of the foreground group: a worker would print
    a traceback, or die half started and make the cluster fail. Ignoring SIGINT is inherited
    through fork and exec (a signal mask would not do: the child's is reset), so each worker
    process is started while this process ignores it, and Ctrl-C then stops only this process,
    which stops the workers. The cluster starts in a thread meanwhile; once the processes exist
    (a few milliseconds), a Ctrl-C is held rather than lost, as a SIGTERM is from the start,
    until the cluster is up (interrupted half way, it could not be closed); then it is delivered
    to the handler that was there, and the cluster closed if that raises. A second signal gives
    up waiting for a start that hangs. Only from the main thread (the only one that can set
    signal handlers); elsewhere the cluster just starts.
    """
    previous = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM)}
    if (
        threading.current_thread() is not threading.main_thread()
        or None in previous.values()  # a handler set outside Python, which cannot be put back
    ):
        return _new_cluster(distributed, jobs)
    held: list[int] = []

    def hold(number: int, frame: object) -> None:
        held.append(number)

    outcome: list[Any] = []  # the cluster, or None and the exception

    def start() -> None:
        try:
            outcome.append(_new_cluster(distributed, jobs))
        except BaseException as error:
            outcome.extend([None, error])

    before = set(multiprocessing.active_children())
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if previous[signal.SIGTERM] is not signal.SIG_IGN:
        signal.signal(signal.SIGTERM, hold)
    try:
        thread = threading.Thread(target=start, name="tuckercodec: LocalCluster", daemon=True)
        thread.start()
        spawned = False
        while thread.is_alive():
            thread.join(0.01)
            if not spawned and len(set(multiprocessing.active_children()) - before) >= jobs:
                spawned = True  # every worker has been started (exec included)
                signal.signal(signal.SIGINT, hold)
            if len(held) > 1:  # asked twice: give up a start that does not end
                break
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
    if not outcome:  # still starting, in a thread that ends with this process
        signal.raise_signal(held[0])
        raise KeyboardInterrupt  # the handler let it go on: there is no cluster to go on with
    cluster = outcome[0]
    if cluster is None:
        raise outcome[1]
    if held:
        try:
            signal.raise_signal(held[0])
        except BaseException:
            cluster.close()
            raise
    return cluster


def _new_cluster(distributed: Any, jobs: int) -> Any:
    """A LocalCluster of ``jobs`` single-threaded worker processes, on loopback, quiet."""
    # The nanny gives these to each worker before it starts (distributed's default too, made
    # sure of here whatever a dask config or the shell says: N workers on N cores) and writes
    # them into this process's environment, which is put back as it was.
    saved = {name: os.environ.get(name) for name in [*WORKER_ENVIRONMENT, "PYTHONHASHSEED"]}
    os.environ.update(WORKER_ENVIRONMENT)
    dask_config = import_optional("dask.config", EXTRA, "running on several cores")
    try:
        with dask_config.set(SCHEDULER_CONFIG):
            return distributed.LocalCluster(
                n_workers=jobs,
                threads_per_worker=1,
                processes=True,
                host="127.0.0.1",
                dashboard_address=None,
                # no dashboard, and its HTTP server (health checks) on a free port, not 8787:
                # that one may be taken, and distributed then warns
                scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                # a failure is reported by the caller, as the task's error; not logged as well
                silence_logs=logging.CRITICAL,
            )
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


def _connect(distributed: Any, address: str) -> Any:
    """A client of the scheduler at ``address``, whose workers run this tuckercodec."""
    try:
        client = distributed.Client(address, timeout=CONNECT_SECONDS, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as error:
        raise TuckerCodecError(f"cannot reach the Dask scheduler at {address}: {error}") from None
    try:
        versions = client.get_versions(packages=["tuckercodec"])
        wrong = {
            worker: found["packages"].get("tuckercodec")
            for worker, found in versions["workers"].items()
            if found["packages"].get("tuckercodec") != __version__
        }
        if wrong:
            worker, version = next(iter(sorted(wrong.items())))
            has = "no tuckercodec" if version is None else f"tuckercodec {version}"
            raise TuckerCodecError(
                f"{len(wrong)} of the {len(versions['workers'])} workers of {address} cannot run "
                f"this tuckercodec ({__version__}): {worker} has {has}; install "
                f"tuckercodec=={__version__} where the workers run"
            )
    except BaseException:
        client.close()
        raise
    return client


def _kill_workers(cluster: Any) -> None:
    """Stop a LocalCluster's worker processes without waiting for their running tasks (the
    nanny otherwise gives a worker 4 s to finish before it kills it)."""
    import asyncio  # here: only a cluster needs it, and it costs every command's start-up

    async def kill() -> None:
        nannies = list(cluster.workers.values())
        await asyncio.gather(*(nanny.close(timeout=KILL_SECONDS) for nanny in nannies))

    with contextlib.suppress(Exception):  # a worker already gone, another distributed version
        cluster.sync(kill)


#: Where a LocalCluster's workers hand large results back: memory, where there is such a file
#: system (Linux), else the temporary directory (a file read back at once, mostly from cache).
SHARED_MEMORY = "/dev/shm"


def _handoff_directory() -> str:
    """A new private directory for the workers' result files (:class:`_HandedOff`)."""
    where = SHARED_MEMORY if os.access(SHARED_MEMORY, os.W_OK | os.X_OK) else None
    return tempfile.mkdtemp(prefix="tuckercodec-results-", dir=where)


def _nbytes(item: object) -> int:
    """The size of an array or bytes item, else 0 (small by assumption)."""
    if isinstance(item, bytes | bytearray | memoryview):
        return len(item)
    size = getattr(item, "nbytes", 0)
    return size if isinstance(size, int) else 0


def _call(
    function: Callable[..., Any], item: Any, *common: Any, handoff: str | None = None
) -> tuple[bool, Any, str]:
    """Run a task on a worker: ``(True, value, "")``, or ``(False, exception, traceback)``.

    The exception is returned, not raised, so that it reaches the caller as itself (Dask would
    also log it on the worker's standard error) with the traceback as text (tracebacks do not
    pickle). With ``handoff`` (a LocalCluster's directory), the value's large arrays come back
    through a file there, as the large ``common`` values came (:class:`_HandedOff`).
    """
    try:
        common = tuple(c.mapped() if isinstance(c, _HandedOff) else c for c in common)
        value = function(item, *common)
        return True, value if handoff is None else _HandedOff.wrap(value, handoff), ""
    except Exception as error:
        trace = "".join(traceback.format_exception(error))
        try:
            pickle.dumps(error)
        except Exception:  # an exception a library made unpicklable: its text still comes back
            error = RuntimeError(f"{type(error).__name__}: {error}")
        return False, error, trace


def _completed(index: int, future: Any) -> Completed:
    """What a finished Dask future says: a value, the task's exception, or a failure of the
    cluster (a worker that died running it, a lost connection)."""
    try:
        ok, value, trace = future.result()
    except Exception as error:  # not the task's own exception: _call returns those
        failure = TuckerCodecError(
            f"the Dask worker running item {index} died or was lost (out of memory? a crash "
            f"in a library?): {type(error).__name__}: {error}"
        )
        failure.__cause__ = error
        return Completed(index, None, failure)
    if ok:
        if isinstance(value, _HandedOff):
            value = value.unwrap()
        return Completed(index, value, None)
    value.add_note(f"raised on a Dask worker:\n{trace.rstrip()}")
    return Completed(index, None, value)


@dataclass(frozen=True)
class _HandedOff:
    """A value whose large buffers (arrays of :data:`LARGE_ITEM_BYTES` or more) wait in a file
    of the LocalCluster's handoff directory, on this machine, rather than travel through Dask's
    connection: the rest is ``pickled`` here (pickle protocol 5, the buffers out of band).

    A task's result: a segmented encode's first pass returns one K x r sketch per segment (410
    MB at 200,000 x 256); received through Dask, each cost the caller seconds of copying, which
    a file in memory (``/dev/shm``) written by the worker and mapped by the caller does not. A
    map's common value: the second pass's K x r basis, which Dask copied to every worker before
    the pass could start, is written once and mapped by each task."""

    path: str
    pickled: bytes
    sizes: tuple[int, ...]

    @staticmethod
    def wrap(value: Any, directory: str) -> Any:
        """``value`` itself if it holds no large buffer (or the file cannot be written, the
        directory full or gone), else its :class:`_HandedOff`."""
        large: list[pickle.PickleBuffer] = []

        def keep_small(buffer: pickle.PickleBuffer) -> bool:
            try:
                size = buffer.raw().nbytes
            except BufferError:  # not contiguous: in band, as pickle would
                return True
            if size < LARGE_ITEM_BYTES:
                return True  # in band: in the pickle itself
            large.append(buffer)
            return False

        pickled = pickle.dumps(value, protocol=5, buffer_callback=keep_small)
        if not large:
            return value
        path = None
        try:
            descriptor, path = tempfile.mkstemp(dir=directory, suffix=".buffers")
            with os.fdopen(descriptor, "wb") as file:
                for buffer in large:
                    file.write(buffer.raw())
        except OSError:  # no room, or the directory is gone: the value goes through Dask
            if path is not None:
                with contextlib.suppress(OSError):
                    os.unlink(path)
            return value
        return _HandedOff(path, pickled, tuple(buffer.raw().nbytes for buffer in large))

    def unwrap(self) -> Any:
        """The value, its buffers mapped from the file (no copy: a page is copied only when
        written, as a sketch summed into is), and the file removed (its pages stay until the
        value is freed)."""
        try:
            return self.mapped()
        finally:
            with contextlib.suppress(OSError):
                os.unlink(self.path)

    def mapped(self) -> Any:
        """The value, its buffers mapped from the file rather than read (written, a page
        becomes this process's own copy), the file kept: for a common value, which every task
        of a map maps, sharing its pages, until the caller removes it when the map ends."""
        with open(self.path, "rb") as file:
            if os.fstat(file.fileno()).st_size != sum(self.sizes):
                raise TuckerCodecError(f"the worker's file {self.path} is not the size it wrote")
            pages = mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_COPY)
        whole = memoryview(pages)
        ends = list(itertools.accumulate(self.sizes))
        buffers = [whole[end - size : end] for end, size in zip(ends, self.sizes, strict=True)]
        return pickle.loads(self.pickled, buffers=buffers)
