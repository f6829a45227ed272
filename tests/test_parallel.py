"""tuckercodec.system.parallel: one function over many items, in this process and on a real Dask
LocalCluster of 2 worker processes on loopback (one, module-scoped: it takes about a second to
start). Results in item order, shared values sent once per worker, exceptions back with their
class and fields, the workers' environment (one BLAS thread, Ctrl-C ignored), a remote scheduler
whose workers lack this tuckercodec, and Ctrl-C stopping everything."""

from __future__ import annotations

import contextlib
import ctypes
import os
import pickle
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tuckercodec import errors
from tuckercodec.errors import DependencyError, FormatError, InputError, TuckerCodecError
from tuckercodec.system import parallel
from tuckercodec.system.parallel import Executor, InProcessExecutor, open_executor

LINUX = sys.platform.startswith("linux")
#: Shared values a task kept, so that no two copies can share an address (see test below).
_KEPT: list[object] = []
#: What this process had before any cluster started (the nanny writes into os.environ).
_ENVIRONMENT = {
    name: os.environ.get(name) for name in [*parallel.WORKER_ENVIRONMENT, "PYTHONHASHSEED"]
}
_SIGINT = signal.getsignal(signal.SIGINT)


# ------------------------------------------------------------------------------------------
# the tasks (module-level: the workers import this module to run them)


def _after(item: int, folder: str) -> int:
    """Item 0 finishes only once two other items have started (a file every other item leaves
    in ``folder``, polled for at most a minute), whatever the machine's speed; the others at
    once. Two, not one: the first of them has then returned before the second began, so its
    result is reported before item 0's (with one, the item that wrote the file and item 0 could
    finish together, and either be reported first). Any two will do: the scheduler may queue
    item 1 behind item 0 on the same worker, but not all five others."""
    if item == 0:
        deadline = time.monotonic() + 60.0
        while len(list(Path(folder).iterdir())) < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
    else:
        (Path(folder) / str(item)).touch()
    return item * 10


def _where_shared(item: int, shared: np.ndarray) -> tuple[int, int, float]:
    _KEPT.append(shared)  # kept alive: a copy per task could not reuse a freed copy's address
    return os.getpid(), id(shared), float(shared[item])


def _fail_on(item: int, bad: int) -> int:
    if item == bad:
        raise InputError("no vertices", path="frames/f3.obj", line=12, frame=bad)
    return item


def _raise(item: BaseException) -> None:
    raise item


class _Unpicklable(Exception):
    def __init__(self) -> None:
        super().__init__("a library's error")
        self.handle = lambda: None  # what some C libraries' errors carry


def _raise_unpicklable(item: int) -> None:
    raise _Unpicklable()


def _total(item: np.ndarray) -> float:
    return float(item.sum())


def _large_result(item: int) -> dict[str, Any]:
    """A task's value as a segmented encode's first pass returns it: a large Fortran-order
    array beside small ones."""
    large = np.asfortranarray(np.arange(2 * 2**20 // 8, dtype=np.float64).reshape(-1, 8) + item)
    return {"large": large, "small": np.arange(3) + item, "item": item}


def _write_shared(item: int, shared: np.ndarray) -> tuple[float, str]:
    """What a task sees of a large common value: its first number after adding 1 to it (each
    task its own copy of what it writes), and what holds its memory."""
    shared[0] += 1.0
    holder: object = shared
    while isinstance(holder, np.ndarray):
        holder = holder.base
    if isinstance(holder, memoryview):
        holder = holder.obj
    return float(shared[0]) + item, type(holder).__name__


def _environment(item: int) -> dict[str, object]:
    return {
        "pid": os.getpid(),
        "variables": {name: os.environ.get(name) for name in parallel.WORKER_ENVIRONMENT},
        "blas threads": _openblas_threads(),
        "sigint ignored": signal.getsignal(signal.SIGINT) is signal.SIG_IGN,
    }


def _openblas_threads() -> int | None:
    """The thread count of the OpenBLAS that numpy loaded (Linux), or None where unknown."""
    if not LINUX:
        return None
    with open("/proc/self/maps") as maps:
        paths = {line.split()[-1] for line in maps if "openblas" in line.lower()}
    for path in paths:
        library = ctypes.CDLL(path)
        for name in (
            "scipy_openblas_get_num_threads64_",
            "openblas_get_num_threads64_",
            "openblas_get_num_threads",
        ):
            if hasattr(library, name):
                return int(getattr(library, name)())
    return None


# ------------------------------------------------------------------------------------------
# executors


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster of 2 workers (open_executor(2)), for the whole module."""
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    with open_executor(2) as executor:
        yield executor


@pytest.fixture(params=["in process", "LocalCluster"])
def executor(request) -> Executor:
    if request.param == "in process":
        return InProcessExecutor()
    return request.getfixturevalue("cluster")


def test_map_gives_results_in_item_order_whatever_finishes_first(executor, tmp_path):
    # item 0 waits on one worker for another item, which another worker runs: on workers item
    # 0 cannot complete first, however slow the machine (in process the items run in order,
    # so items 1 and 2's files are there from the start)
    folder = tmp_path / "as_completed"
    folder.mkdir()
    if executor.workers == 1:
        (folder / "1").touch()
        (folder / "2").touch()
    order = [done.index for done in executor.as_completed(_after, range(6), str(folder))]
    assert sorted(order) == list(range(6))
    if executor.workers > 1:
        assert order[0] != 0, order
    ready = tmp_path / "map"
    ready.mkdir()
    (ready / "1").touch()  # item 0 need not wait here: map's order is the items'
    (ready / "2").touch()
    assert executor.map(_after, range(6), str(ready)) == [0, 10, 20, 30, 40, 50]
    assert executor.map(_after, [], str(ready)) == []


def test_a_shared_value_reaches_each_worker_once_per_map(executor):
    shared = np.arange(8.0)
    results = executor.map(_where_shared, range(8), shared)
    assert [value for _, _, value in results] == list(shared)
    copies: dict[int, set[int]] = {}
    for pid, address, _ in results:
        copies.setdefault(pid, set()).add(address)
    assert all(len(addresses) == 1 for addresses in copies.values()), copies
    assert len(copies) <= executor.workers


def test_a_task_error_comes_back_as_itself_with_its_fields(executor):
    with pytest.raises(InputError) as caught:
        executor.map(_fail_on, range(4), 2)
    error = caught.value
    assert (error.path, error.line, error.frame) == ("frames/f3.obj", 12, 2)
    assert str(error) == "frames/f3.obj:12, frame 2: no vertices"
    if executor.workers > 1:
        assert "raised on a Dask worker" in error.__notes__[0]
        assert "_fail_on" in error.__notes__[0]  # the worker's traceback
    assert executor.map(_fail_on, range(3), 99) == [0, 1, 2]  # the executor goes on


def test_a_large_result_comes_back_through_a_file_the_caller_removes(cluster):
    # a LocalCluster's workers write a large array to a file of its handoff directory (in
    # memory on Linux) rather than send it through Dask: the same values, in the same order
    directory = cluster._handoff
    assert directory is not None and os.path.isdir(directory)
    if LINUX:
        assert directory.startswith(parallel.SHARED_MEMORY + "/")
    results = cluster.map(_large_result, range(3))
    for item, result in enumerate(results):
        expected = _large_result(item)
        assert result["item"] == item and np.array_equal(result["small"], expected["small"])
        assert np.array_equal(result["large"], expected["large"])
        assert result["large"].flags.f_contiguous and result["large"].flags.writeable
        result["large"] += 1.0  # the caller's own memory (a sketch is summed into in place)
    assert os.listdir(directory) == []  # each file removed once read


def test_a_large_common_value_is_mapped_by_each_task_from_one_file(cluster):
    # written once by the caller rather than copied to every worker; what a task writes is its
    # own (copy on write), and the file is removed when the map ends
    shared = np.zeros(2 * 2**20 // 8)
    results = cluster.map(_write_shared, range(4), shared)
    assert results == [(1.0 + item, "mmap") for item in range(4)]
    assert shared[0] == 0.0 and os.listdir(cluster._handoff) == []


def test_a_handed_off_value_is_read_back_whole(tmp_path):
    ok, value, _ = parallel._call(_large_result, 4, handoff=str(tmp_path))
    assert ok and isinstance(value, parallel._HandedOff)
    assert len(list(tmp_path.iterdir())) == 1 and value.sizes == (2 * 2**20,)
    back = value.unwrap()
    assert np.array_equal(back["large"], _large_result(4)["large"]) and back["item"] == 4
    assert list(tmp_path.iterdir()) == []
    # small values, and a directory that cannot take the file, go through Dask as they are
    assert parallel._call(_fail_on, 1, -1, handoff=str(tmp_path)) == (True, 1, "")
    ok, value, _ = parallel._call(_large_result, 4, handoff=str(tmp_path / "gone"))
    assert ok and isinstance(value, dict) and value["item"] == 4


def test_closing_a_local_cluster_removes_its_handoff_directory():
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    with open_executor(1) as one:
        assert isinstance(one, parallel.DaskExecutor)
        directory = one._handoff
        assert directory is not None
        Path(directory, "left.buffers").write_bytes(b"a task's file never read")
    assert not os.path.exists(directory)


def test_background_gives_the_value_or_raises_the_error():
    assert parallel.Background(sum, [1, 2, 3]).result() == 6
    failing = parallel.Background(_fail_on, 2, 2, name="fails")
    with pytest.raises(InputError, match="no vertices"):
        failing.result()


@pytest.mark.parametrize(
    "error",
    [
        FormatError("bad length", rule="R09-trailing-bytes", field="U1", offset=77, path="a.tkc"),
        errors.ChecksumError("crc", rule="R05-crc", offset=3),
        DependencyError("reading USD files needs pxr: pip install 'tuckercodec[usd]'"),
        ValueError("rank 0 is out of range"),
        KeyError("V"),
    ],
    ids=lambda error: type(error).__name__,
)
def test_every_kind_of_error_crosses_over(executor, error):
    with pytest.raises(type(error)) as caught:
        executor.map(_raise, [error])
    assert type(caught.value) is type(error)
    assert str(caught.value) == str(error)
    assert {k: v for k, v in vars(caught.value).items() if k != "__notes__"} == vars(error)


def test_an_unpicklable_error_comes_back_as_its_text(cluster):
    with pytest.raises(RuntimeError, match="_Unpicklable: a library's error"):
        cluster.map(_raise_unpicklable, [1])


def test_as_completed_gives_every_outcome_without_raising(executor):
    outcomes = sorted(executor.as_completed(_fail_on, range(4), 1), key=lambda done: done.index)
    assert [done.value for done in outcomes] == [0, None, 2, 3]
    assert [type(done.error) for done in outcomes] == [type(None), InputError, *[type(None)] * 2]


def test_progress_is_called_after_each_item():
    calls: list[tuple[int, int]] = []
    with open_executor(progress=lambda done, total: calls.append((done, total))) as executor:
        assert executor.map(_fail_on, range(3), -1) == [0, 1, 2]
    assert calls == [(1, 3), (2, 3), (3, 3)]


def test_a_large_item_is_sent_ahead_not_in_the_task_graph(cluster):
    # Dask warns about a graph over 10 MB, and the test suite turns warnings into errors
    items = [np.ones(11 * 2**20 // 8), np.ones(4)]
    assert cluster.map(_total, items) == [11 * 2**20 // 8, 4.0]


@pytest.mark.parametrize(
    "error",
    [
        InputError("no faces", path="a.obj", line=3, frame=1),
        InputError("plain"),
        FormatError("short", rule="R03-truncated", field="header", offset=9, path="x.tkc"),
        errors.TruncatedFileError("cut", rule="R03-truncated", offset=1),
        errors.ChecksumError("crc", rule="R05-crc"),
        errors.UnsupportedVersionError("v9", rule="R02-version", field="major"),
        errors.LimitError("too big", rule="R10-limits", field="frames"),
        errors.UnreachableTargetError("below the faces"),
        DependencyError("needs h5py"),
        TuckerCodecError("other"),
    ],
    ids=lambda error: type(error).__name__,
)
def test_every_error_class_pickles_with_its_fields(error):
    copy = pickle.loads(pickle.dumps(error))
    assert type(copy) is type(error)
    assert str(copy) == str(error)
    assert vars(copy) == vars(error)
    assert copy.exit_code == error.exit_code


# ------------------------------------------------------------------------------------------
# the LocalCluster's workers, a remote scheduler, the choices open_executor makes


def test_local_workers_use_one_blas_thread_and_ignore_ctrl_c(cluster):
    found = cluster.map(_environment, range(4))
    assert len({worker["pid"] for worker in found}) == 2
    for worker in found:
        assert worker["variables"] == parallel.WORKER_ENVIRONMENT
        assert worker["blas threads"] in (1, None)  # None: not OpenBLAS, or not Linux
        assert worker["sigint ignored"]
    assert cluster.workers == 2
    # the caller's environment and Ctrl-C handler are as they were
    assert {name: os.environ.get(name) for name in _ENVIRONMENT} == _ENVIRONMENT
    assert signal.getsignal(signal.SIGINT) is _SIGINT


def _listening(pids: set[int]) -> list[str]:
    """The addresses (hex host:port, as /proc/net/tcp writes them) on which processes ``pids``
    listen for TCP connections (Linux)."""
    inodes: set[str] = set()
    for pid in pids:
        for fd in Path(f"/proc/{pid}/fd").iterdir():
            with contextlib.suppress(OSError):
                target = os.readlink(fd)
                if target.startswith("socket:["):
                    inodes.add(target[8:-1])
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with contextlib.suppress(OSError), open(table) as lines:
            for line in list(lines)[1:]:
                fields = line.split()
                if fields[3] == "0A" and fields[9] in inodes:  # 0A: LISTEN
                    found.append(fields[1])
    return found


@pytest.mark.skipif(not LINUX, reason="reads the sockets from Linux's /proc")
def test_the_local_cluster_listens_on_loopback_only(cluster):
    workers = {worker["pid"] for worker in cluster.map(_environment, range(4))}
    addresses = _listening({os.getpid(), *workers})
    assert len(addresses) >= 3, addresses  # the scheduler and each worker at least
    loopback = "0100007F:"  # 127.0.0.1, little-endian hex
    assert all(address.startswith(loopback) for address in addresses), addresses


def test_a_remote_scheduler_runs_the_same_tasks(cluster):
    address = cluster.cluster.scheduler_address
    with open_executor(scheduler=address) as remote:
        assert remote.workers == 2
        assert remote.map(_fail_on, range(3), -1) == [0, 1, 2]
        with pytest.raises(InputError, match="no vertices"):
            remote.map(_fail_on, range(3), 1)
    assert cluster.map(_fail_on, range(2), -1) == [0, 1]  # closing it left the cluster running


def test_workers_without_this_tuckercodec_are_refused(cluster, monkeypatch):
    monkeypatch.setattr(parallel, "__version__", "0.0.1")
    with pytest.raises(TuckerCodecError, match=r"2 of the 2 workers .* cannot run .*0\.0\.1"):
        open_executor(scheduler=cluster.cluster.scheduler_address)


def test_an_unreachable_scheduler_is_one_error(monkeypatch):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    monkeypatch.setattr(parallel, "CONNECT_SECONDS", 0.5)
    with pytest.raises(TuckerCodecError, match="cannot reach the Dask scheduler at tcp://127"):
        open_executor(scheduler="tcp://127.0.0.1:9")


def test_open_executor_refuses_what_it_cannot_do(monkeypatch):
    with pytest.raises(ValueError, match="not both"):
        open_executor(2, "tcp://127.0.0.1:8786")
    with pytest.raises(ValueError, match="at least 1"):
        open_executor(0)
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if not installed
    with pytest.raises(DependencyError, match=r"tuckercodec\[dask\]"):
        open_executor(2)
    assert isinstance(open_executor(), InProcessExecutor)  # needs no Dask


def test_in_process_imports_no_dask():
    code = (
        "import sys; from tuckercodec.system.parallel import open_executor\n"
        "with open_executor() as executor: assert executor.map(abs, [-1, -2]) == [1, 2]\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip() == "[]", done.stdout


_INTERRUPTED = textwrap.dedent(
    """
    import signal, sys, time
    from tuckercodec.system.parallel import open_executor
    if __name__ == "__main__":
        # set, not inherited: a background job without job control starts with SIGINT ignored
        signal.signal(signal.SIGINT, signal.default_int_handler)
        try:
            with open_executor(1) as executor:
                print("running", flush=True)
                executor.map(time.sleep, [600])
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(130)
    """
)


@pytest.mark.skipif(not hasattr(os, "killpg"), reason="needs POSIX process groups")
def test_ctrl_c_stops_the_caller_and_its_workers_quietly(tmp_path):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (extra [dask])")
    script = tmp_path / "interrupted.py"
    script.write_text(_INTERRUPTED)
    process = subprocess.Popen(
        [sys.executable, str(script)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own group, as a terminal's foreground job
    )
    try:
        assert process.stdout is not None
        assert process.stdout.readline() == "running\n"
        time.sleep(0.5)  # the task is (most likely) running on the worker
        os.killpg(process.pid, signal.SIGINT)  # what Ctrl-C does: the whole group
        # a hang guard, not a speed test: closing the cluster takes seconds, more on a slow
        # machine (over 60 s once, with the suite pinned to one busy core)
        out, err = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.communicate()  # closes the pipes: no ResourceWarning in a later test
    assert (process.returncode, out, err) == (130, "interrupted\n", "")
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # the workers end with their caller
        try:
            os.killpg(process.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        os.killpg(process.pid, signal.SIGKILL)
        pytest.fail("a worker process outlived its caller")


def _die_on(item: int, bad: int) -> int:
    if item == bad:
        os._exit(3)  # as a crash in a library, or the kernel's out-of-memory killer, would
    return item


def test_a_worker_that_dies_fails_only_its_own_task(cluster):
    # last in the module: the nanny starts a new worker, waited for before the cluster closes
    outcomes = sorted(cluster.as_completed(_die_on, range(5), 1), key=lambda done: done.index)
    assert [done.value for done in outcomes] == [0, None, 2, 3, 4]
    error = outcomes[1].error
    assert type(error) is TuckerCodecError
    assert str(error).startswith("the Dask worker running item 1 died or was lost")
    cluster.client.wait_for_workers(2, timeout=60)
