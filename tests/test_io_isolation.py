"""Reading in a child process (tuckercodec/io/isolation/): a crash, a runaway allocation, a
read that never ends and the libraries' messages stay in the child, and come back as
InputErrors naming the file, the object and the frame; the reader's own errors come back as
they were raised; no child outlives its read, nor its caller."""

from __future__ import annotations

import contextlib
import os
import random
import signal
import struct
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from tests.support import isolation_hooks as hooks
from tests.support.inputs import check_sequence, expect_input_error
from tuckercodec import DependencyError, InputError, MeshSequence
from tuckercodec.cli import main
from tuckercodec.io import isolation, load_sequence
from tuckercodec.io.isolation import MEMORY_VARIABLE, TIMEOUT_VARIABLE, channel, read_isolated
from tuckercodec.io.registry import ReadOptions

TESTS = Path(__file__).resolve().parent
#: A damaged archive on which alembic3d segfaults (tests/data/alembic/README.md).
CRASHING = TESTS / "data" / "alembic" / "polygons-last-sample-cut.abc"
#: Where its one damaged byte is, and what the undamaged archive holds there.
CUT_AT, UNCUT = 1196, 10
LINUX = sys.platform.startswith("linux")


def children() -> set[int]:
    """The processes this one started that still exist (Linux's /proc)."""
    found: set[int] = set()
    for task in Path("/proc/self/task").iterdir():
        with contextlib.suppress(FileNotFoundError, ProcessLookupError):  # a thread that ended
            found |= {int(pid) for pid in (task / "children").read_text().split()}
    return found


def gone(pid: int, seconds: float = 5.0) -> bool:
    """Whether the process ``pid`` has ended (or is a zombie), waiting up to ``seconds``."""
    deadline = time.monotonic() + seconds
    while True:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return True
        if state in ("Z", "X"):
            return True
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)


@pytest.fixture
def no_child_left():
    """Fails the test if it leaves a child process behind (Linux only, else not checked)."""
    before = children() if LINUX else set()
    yield
    if LINUX:
        assert children() <= before, "a reading child outlived its read"


@pytest.fixture
def data_file(tmp_path) -> Path:
    """A file for the hooks to be called on (they do not read it)."""
    path = tmp_path / "data.bin"
    path.write_bytes(bytes(1000))
    return path


def read(hook, path: Path, **options) -> MeshSequence:
    return read_isolated(hook, path, ReadOptions(**options), "Test", "test")


# ------------------------------------------------------------------------------------------
# a real crash of alembic3d


@pytest.mark.usefixtures("no_child_left")
def test_an_archive_that_crashes_alembic3d_is_an_input_error(capfd):
    pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
    expect_input_error(
        lambda: load_sequence(CRASHING),
        CRASHING,
        frame=4,
        match=r"^[^\n]*: object /polygons/polygonsShape: the Alembic library crashed reading it "
        r"\(SIGSEGV\): the file is damaged$",
    )
    assert capfd.readouterr() == ("", "")


def test_the_cli_exits_4_with_one_line_naming_the_crashing_archive(tmp_path, capsys):
    pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
    out = tmp_path / "x.tkc"
    assert main(["encode", str(CRASHING), "-o", str(out), "--kg", "1"]) == 4
    err = capsys.readouterr().err
    assert err == (
        f"tuckercodec: bad input: {CRASHING}, frame 4: object /polygons/polygonsShape: the "
        "Alembic library crashed reading it (SIGSEGV): the file is damaged\n"
    )
    assert not out.exists()


@pytest.mark.usefixtures("no_child_left")
def test_randomly_damaged_archives_end_in_an_input_error_or_a_sequence(tmp_path):
    pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
    good = bytearray(CRASHING.read_bytes())
    good[CUT_AT] = UNCUT
    rng = random.Random(3)
    paths = []
    for index in range(12):  # a bit of 1 to 4 bytes of the Ogawa group tables: crashes there
        data = bytearray(good)
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(1140, 1440)] ^= 1 << rng.randrange(8)
        paths.append(tmp_path / f"m{index}.abc")
        paths[-1].write_bytes(bytes(data))
    (tmp_path / "good.abc").write_bytes(bytes(good))
    paths.append(tmp_path / "good.abc")

    def outcome(path: Path) -> InputError | None:
        try:
            check_sequence(load_sequence(path))
        except InputError as error:
            return error
        return None

    with ThreadPoolExecutor(2) as pool:
        outcomes = list(pool.map(outcome, paths))
    assert outcomes[-1] is None  # the undamaged archive reads
    assert all(
        error is None or error.path == str(path)
        for error, path in zip(outcomes, paths, strict=True)
    )
    crashes = [error for error in outcomes if error and "crashed reading it" in error.reason]
    assert len(crashes) >= 2, outcomes  # there were crashes to survive


# ------------------------------------------------------------------------------------------
# memory and time


def _small_stage(path: Path) -> Path:
    """A crate file of 10 quads over 7 points in 2 frames (about a KB)."""
    from pxr import Usd, UsdGeom, Vt

    stage = Usd.Stage.CreateInMemory()
    mesh = UsdGeom.Mesh.Define(stage, "/m")
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4] * 10))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([i % 7 for i in range(40)]))  # compressed
    points = mesh.CreatePointsAttr()
    for time_code in range(2):
        points.Set(Vt.Vec3fArray.FromNumpy(np.ones((7, 3), np.float32) * time_code), time_code)
    stage.GetRootLayer().Export(str(path))
    return path


def _crafted_stage(path: Path, indices: int) -> Path:
    """A crate file whose compressed faceVertexIndices declare ``indices`` values."""
    data = bytearray(_small_stage(path).read_bytes())
    [at] = [i for i in range(len(data) - 8) if struct.unpack_from("<Q", data, i)[0] == 40]
    struct.pack_into("<Q", data, at, indices)
    path.write_bytes(bytes(data))
    return path


@pytest.mark.usefixtures("no_child_left")
def test_a_crafted_usdc_declaring_2_31_face_indices_is_refused_quickly_and_quietly(tmp_path, capfd):
    pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
    # in process, pxr allocates the 8 GiB and fills them (27 s), printing to fd 2
    path = _crafted_stage(tmp_path / "crafted.usdc", 2**31)
    start = time.perf_counter()
    expect_input_error(lambda: load_sequence(path), path, match="prim /m: cannot read")
    # the child's start-up (importing pxr) is counted too: a margin for a much slower machine,
    # still short of the 27 s the allocation took
    assert time.perf_counter() - start < 20.0
    assert capfd.readouterr() == ("", "")


@pytest.mark.skipif(not LINUX, reason="the address-space cap needs Linux's /proc/self/statm")
@pytest.mark.parametrize("hook", [hooks.allocate, hooks.allocate_and_wrap])
def test_an_allocation_beyond_the_cap_names_the_limit(data_file, monkeypatch, hook):
    monkeypatch.setenv(MEMORY_VARIABLE, "0.5")
    expect_input_error(
        lambda: read(hook, data_file),
        data_file,
        frame=1,
        match=rf"prim /World/big: declares more data than 0\.5 GiB allows \(the memory limit of a "
        rf"read: {MEMORY_VARIABLE}\)$",
    )


def test_the_default_limits_grow_with_the_file(tmp_path, monkeypatch):
    monkeypatch.delenv(MEMORY_VARIABLE, raising=False)
    monkeypatch.delenv(TIMEOUT_VARIABLE, raising=False)
    path = tmp_path / "f"
    path.write_bytes(os.urandom(2**20))  # not zeros: a compressing file system stores them all
    assert channel._limits(path) == (2 * 2**30 + 16 * 2**20, 60.0 + 1 / 8)
    monkeypatch.setenv(MEMORY_VARIABLE, "0")
    monkeypatch.setenv(TIMEOUT_VARIABLE, "2.5")
    assert channel._limits(path) == (None, 2.5)
    monkeypatch.setenv(TIMEOUT_VARIABLE, "soon")
    with pytest.raises(ValueError, match=f"{TIMEOUT_VARIABLE} must be a number >= 0"):
        channel._limits(path)


def _sparse(path: Path, size: int = 2**40) -> Path:
    """``path`` grown to ``size`` bytes by a hole, which stores nothing; skips the test where
    the file system cannot make one."""
    try:
        os.truncate(path, size)
    except OSError as error:  # a file system whose files cannot be that large
        pytest.skip(f"cannot make a sparse file of {size} bytes here: {error}")
    found = path.stat()
    if not hasattr(found, "st_blocks") or found.st_blocks * 512 >= found.st_size:
        pytest.skip("this file system does not make sparse files")
    return path


def test_a_sparse_file_gets_the_limits_of_the_bytes_it_stores(tmp_path, monkeypatch):
    # the limits grew with st_size, which a hole inflates for free: 943 bytes and a 1 TiB hole
    # got 16,386 GiB and 36 hours
    monkeypatch.delenv(MEMORY_VARIABLE, raising=False)
    monkeypatch.delenv(TIMEOUT_VARIABLE, raising=False)
    path = tmp_path / "padded.usdc"
    path.write_bytes(os.urandom(943))
    _sparse(path)
    stored = channel.stored_bytes(path)
    assert stored <= 2**20  # a block or a few, whatever the file system's block size
    assert channel._limits(path) == (2 * 2**30 + 16 * stored, 60.0 + stored / 2**23)
    monkeypatch.setenv(MEMORY_VARIABLE, "100")  # the environment still wins
    monkeypatch.setenv(TIMEOUT_VARIABLE, "7200")
    assert channel._limits(path) == (100 * 2**30, 7200.0)


def test_the_limits_have_fixed_ceilings_however_much_a_file_stores(tmp_path, monkeypatch):
    monkeypatch.delenv(MEMORY_VARIABLE, raising=False)
    monkeypatch.delenv(TIMEOUT_VARIABLE, raising=False)
    monkeypatch.setattr(channel, "stored_bytes", lambda path: 2**40)  # a real 1 TiB
    assert channel._limits(tmp_path) == (channel.MEMORY_CEILING, channel.TIMEOUT_CEILING)
    assert (channel.MEMORY_CEILING, channel.TIMEOUT_CEILING) == (64 * 2**30, 3600.0)


def test_without_block_counts_a_file_stores_its_size(tmp_path, monkeypatch):
    path = tmp_path / "f"
    path.write_bytes(bytes(1000))
    real_stat = os.stat

    def stat(name, *args, **kwargs):  # as on Windows: no st_blocks
        found = real_stat(name, *args, **kwargs)
        return SimpleNamespace(st_size=found.st_size) if Path(name) == path else found

    monkeypatch.setattr(os, "stat", stat)  # the module channel uses
    assert channel.stored_bytes(path) == 1000
    assert channel.stored_bytes(tmp_path / "missing") == 0


@pytest.mark.skipif(not LINUX, reason="the address-space cap needs Linux's /proc/self/statm")
@pytest.mark.usefixtures("no_child_left")
def test_a_usdc_padded_with_a_hole_is_read_within_the_limits_of_its_bytes(tmp_path, monkeypatch):
    pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
    monkeypatch.delenv(MEMORY_VARIABLE, raising=False)
    monkeypatch.delenv(TIMEOUT_VARIABLE, raising=False)
    path = _sparse(_small_stage(tmp_path / "padded.usdc"))
    # pxr maps the whole file: 1 TiB of address space, which the limits of its size allowed
    # (the read took 16,386 GiB and 36 hours to stop); those of its bytes do not
    expect_input_error(
        lambda: load_sequence(path), path, match="cannot read as a USD file: Couldn't map asset"
    )
    assert load_sequence(_small_stage(tmp_path / "whole.usdc")).frame_count == 2


@pytest.mark.usefixtures("no_child_left")
def test_a_read_that_never_ends_is_killed_at_the_time_limit(data_file, monkeypatch):
    monkeypatch.setenv(TIMEOUT_VARIABLE, "0.5")
    start = time.perf_counter()
    expect_input_error(
        lambda: read(hooks.hang, data_file),
        data_file,
        frame=2,
        match=r"object /slow: the Test library did not finish reading it in 0\.5 s",
    )
    # the child's start-up is counted here too (0.6 s on a busy 2-core machine): a wide margin
    assert time.perf_counter() - start < 20.0
    assert gone(int(hooks.pid_file(data_file).read_text()), 0)


@pytest.mark.usefixtures("no_child_left")
def test_the_time_limit_begins_when_the_child_has_started(data_file, tmp_path, monkeypatch):
    """A library whose import takes longer than the limit (a busy machine) is not the file's
    doing: the read is not killed, and a read that never ends still is, at its limit."""
    # the import takes three times the limit; the limit leaves a read that takes milliseconds
    # room on a machine many times slower than this one
    (tmp_path / "slow_library.py").write_text("import time\ntime.sleep(3.0)\n")
    monkeypatch.syspath_prepend(os.fspath(tmp_path))
    monkeypatch.setenv(TIMEOUT_VARIABLE, "1")
    slow = ("slow_library",)
    seq = read_isolated(hooks.chatty, data_file, ReadOptions(), "Test", "test", slow)
    assert np.array_equal(seq.vertices, hooks.chatty(data_file, ReadOptions()).vertices)
    expect_input_error(
        lambda: read_isolated(hooks.hang, data_file, ReadOptions(), "Test", "test", slow),
        data_file,
        frame=2,
        match=r"object /slow: the Test library did not finish reading it in 1 s",
    )


# ------------------------------------------------------------------------------------------
# what the reader raises or returns


@pytest.mark.usefixtures("no_child_left")
def test_the_readers_errors_keep_their_class_message_and_place(data_file):
    error = expect_input_error(
        lambda: read(hooks.fail, data_file, object_path="/x"),
        data_file,
        line=3,
        frame=7,
        match="object /x: broken$",
    )
    assert type(error) is InputError and error.reason == "object /x: broken"
    with pytest.raises(DependencyError, match=r"^reading Nothing files needs 'nothing'"):
        read(hooks.missing, data_file)
    with pytest.raises(RuntimeError, match=r"(?s)failed in a child process.*ZeroDivisionError"):
        read(hooks.bug, data_file)


@pytest.mark.usefixtures("no_child_left")
def test_a_segfault_names_the_signal_and_where_it_happened(data_file):
    expect_input_error(
        lambda: read(hooks.crash, data_file),
        data_file,
        frame=3,
        match=r"object /a/aShape: the Test library crashed reading it \(SIGSEGV\)",
    )


def test_a_sequence_comes_back_whole_and_the_libraries_messages_stay_in_the_child(data_file, capfd):
    seq = read(hooks.chatty, data_file)
    assert int(seq.frame_names[2]) != os.getpid()  # read in another process
    expected = hooks.chatty(data_file, ReadOptions())
    capfd.readouterr()  # what the hook printed here, in this process
    assert np.array_equal(seq.vertices, expected.vertices)
    assert np.array_equal(seq.faces, expected.faces) and seq.faces.dtype == np.int64
    assert seq.time_codes is not None and expected.time_codes is not None
    assert np.array_equal(seq.time_codes, expected.time_codes)
    assert seq.frame_rate == 30000 / 1001 and seq.frame_names[:2] == ["a", "b"]
    read(hooks.chatty, data_file)
    assert capfd.readouterr() == ("", "")


def test_a_missing_library_is_named_before_any_process_starts(data_file, monkeypatch):
    monkeypatch.setitem(sys.modules, "nothing.here", None)
    monkeypatch.setattr(isolation.parent, "Child", None)  # starting a child would fail
    with pytest.raises(DependencyError, match=r"^reading Test files needs .*'nothing'.*\[test\]"):
        read_isolated(hooks.chatty, data_file, ReadOptions(), "Test", "test", ["nothing.here"])


def test_a_frozen_application_reads_in_process(data_file, monkeypatch):
    monkeypatch.setattr(sys, "frozen", True, raising=False)
    assert read(hooks.chatty, data_file).frame_names[2] == str(os.getpid())


# ------------------------------------------------------------------------------------------
# the caller interrupted or killed

# SIGINT's handler is set, not inherited: a shell that starts a job in the background without
# job control (a CI script's `cmd &`) passes SIGINT on as ignored, and Python then keeps it so
CALLER = """
import signal, sys
from pathlib import Path
signal.signal(signal.SIGINT, signal.default_int_handler)
from tests.support import isolation_hooks
from tuckercodec.io.isolation import read_isolated
from tuckercodec.io.registry import ReadOptions
try:
    read_isolated(isolation_hooks.hang, Path(sys.argv[1]), ReadOptions(), "Test", "test")
except KeyboardInterrupt:
    sys.exit(130)
"""


@pytest.mark.skipif(not LINUX, reason="checks processes through Linux's /proc")
@pytest.mark.parametrize(("how", "status"), [(signal.SIGINT, 130), (signal.SIGKILL, -9)])
def test_the_child_dies_with_its_interrupted_or_killed_caller(data_file, how, status):
    search = [str(TESTS.parent), *filter(None, [os.environ.get("PYTHONPATH")])]  # for tests.support
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(search)}
    pid_file = hooks.pid_file(data_file)
    with subprocess.Popen(
        [sys.executable, "-c", CALLER, str(data_file)], env=environment, stderr=subprocess.PIPE
    ) as caller:
        assert caller.stderr is not None
        deadline = time.monotonic() + 30
        while not pid_file.exists() or not pid_file.read_text():
            assert caller.poll() is None and time.monotonic() < deadline, caller.stderr.read()
            time.sleep(0.02)
        child = int(pid_file.read_text())
        caller.send_signal(how)
        try:  # a hang guard, not a speed test: it took 10 s once on one busy core
            code = caller.wait(120)
        finally:
            caller.kill()
        assert code == status, caller.stderr.read()
    assert gone(child), "the reading child outlived its caller"
