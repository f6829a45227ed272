"""Reading range by range in a child that serves many reads (tuckercodec/io/isolation/,
for USD and Alembic): the frames come back as the source reads them; the file's own errors
leave the child serving; a crash, a hang or a bug ends in the error a one-shot read gives,
and the next read starts a new child; no child outlives its source; a pickled source starts
its own. The sources are tests/support/streaming_hooks.py."""

from __future__ import annotations

import os
import pickle
import signal
import sys
import time

import numpy as np
import pytest

from tests.support import streaming_hooks as hooks
from tests.support.inputs import expect_input_error
from tests.test_io_isolation import CRASHING, LINUX, children, gone
from tests.test_io_streaming import check_ranges, same_description
from tuckercodec import InputError, load_sequence, save_sequence
from tuckercodec.io import open_frames
from tuckercodec.io.isolation import TIMEOUT_VARIABLE, IsolatedFrames
from tuckercodec.io.registry import ReadOptions


@pytest.fixture
def no_child_left():
    """Fails the test if it leaves a child process behind (Linux only, else not checked)."""
    before = children() if LINUX else set()
    yield
    if LINUX:
        assert children() <= before, "a serving child outlived its source"


@pytest.fixture
def data_file(tmp_path):
    path = tmp_path / "data.bin"
    path.write_bytes(bytes(100))
    return path


def opened(source_class, path) -> IsolatedFrames:
    return IsolatedFrames(source_class, path, ReadOptions(), "Test", "test")


def child_pid(path) -> int:
    return int(hooks.pid_file(path).read_text())


@pytest.mark.usefixtures("no_child_left")
def test_one_child_serves_every_read_and_leaves_when_closed(data_file):
    with opened(hooks.Frames, data_file) as source:
        pid = child_pid(data_file)
        assert pid != os.getpid()
        assert (source.frame_count, source.vertex_count) == (10, 5)
        assert source.faces.tolist() == [[0, 1, 2, 3], [2, 3, 4, -1]]
        assert source.frame_names[3] == "f3" and source.frame_rate == 30.0
        assert source.time_codes is not None
        assert np.array_equal(source.time_codes, np.arange(10) * 2.0 + 1)
        for start, stop in [(0, 10), (3, 4), (2, 9), (0, 1)]:
            assert np.array_equal(source.read(start, stop), hooks.expected(start, stop))
        assert child_pid(data_file) == pid  # opened once
    assert gone(pid)


@pytest.mark.usefixtures("no_child_left")
def test_a_pickled_source_starts_a_child_of_its_own(data_file):
    with opened(hooks.Frames, data_file) as source:
        first = child_pid(data_file)
        copy = pickle.loads(pickle.dumps(source))
        with copy:
            assert np.array_equal(copy.read(5, 10), hooks.expected(5, 10))
            assert child_pid(data_file) not in (first, os.getpid())
        assert np.array_equal(source.read(0, 2), hooks.expected(0, 2))


@pytest.mark.usefixtures("no_child_left")
def test_the_files_own_error_in_a_frame_leaves_the_child_serving(data_file):
    with opened(hooks.RefuseFour, data_file) as source:
        pid = child_pid(data_file)
        error = expect_input_error(lambda: source.read(2, 6), data_file, frame=4, match="broken")
        assert error.reason == "object /hook: frame 4 is broken"
        assert np.array_equal(source.read(5, 10), hooks.expected(5, 10))
        assert child_pid(data_file) == pid and not gone(pid, 0)


@pytest.mark.usefixtures("no_child_left")
def test_a_crash_names_the_frame_and_the_next_read_starts_a_new_child(data_file):
    with opened(hooks.CrashAtSeven, data_file) as source:
        pid = child_pid(data_file)
        assert np.array_equal(source.read(0, 7), hooks.expected(0, 7))
        expect_input_error(
            lambda: source.read(5, 9),
            data_file,
            frame=7,
            match=r"^[^\n]*: object /hook: the Test library crashed reading it \(SIGSEGV\)",
        )
        assert gone(pid)
        assert np.array_equal(source.read(8, 10), hooks.expected(8, 10))
        assert child_pid(data_file) != pid


@pytest.mark.usefixtures("no_child_left")
def test_a_read_that_never_ends_is_killed_at_the_limit_but_waiting_is_not_limited(
    data_file, monkeypatch
):
    monkeypatch.setenv(TIMEOUT_VARIABLE, "1")
    with opened(hooks.HangAtEight, data_file) as source:
        pid = child_pid(data_file)
        time.sleep(1.5)  # the caller computing between two reads: longer than a read may take
        assert np.array_equal(source.read(0, 8), hooks.expected(0, 8))
        expect_input_error(
            lambda: source.read(7, 10),
            data_file,
            frame=8,
            match=r"object /hook: the Test library did not finish reading it in 1 s",
        )
        assert gone(pid)


@pytest.mark.usefixtures("no_child_left")
def test_a_bug_is_a_runtime_error_with_the_childs_traceback(data_file):
    with opened(hooks.BugAtTwo, data_file) as source:
        with pytest.raises(RuntimeError, match="ZeroDivisionError: a mistake in the reader"):
            source.read(0, 5)
        assert np.array_equal(source.read(3, 5), hooks.expected(3, 5))  # a new child


@pytest.mark.usefixtures("no_child_left")
def test_an_error_opening_the_file_is_raised_and_no_child_is_left(data_file):
    expect_input_error(lambda: opened(hooks.RefuseToOpen, data_file), data_file, match="not a mesh")
    assert gone(child_pid(data_file))


@pytest.mark.usefixtures("no_child_left")
@pytest.mark.skipif(not LINUX, reason="kills the child by its id, found through /proc")
def test_a_child_gone_while_idle_is_replaced_without_an_error(data_file):
    with opened(hooks.Frames, data_file) as source:
        pid = child_pid(data_file)
        os.kill(pid, signal.SIGKILL)
        assert gone(pid)
        assert np.array_equal(source.read(1, 3), hooks.expected(1, 3))
        assert child_pid(data_file) != pid


def test_a_frozen_application_reads_in_process(data_file, monkeypatch):
    monkeypatch.setattr(sys, "frozen", True, raising=False)
    with opened(hooks.Frames, data_file) as source:
        assert child_pid(data_file) == os.getpid()
        assert np.array_equal(source.read(2, 4), hooks.expected(2, 4))
        copy = pickle.loads(pickle.dumps(source))
        with copy:
            assert np.array_equal(copy.read(0, 10), hooks.expected(0, 10))


# ------------------------------------------------------------------------------------------
# the real libraries


@pytest.mark.usefixtures("no_child_left")
def test_an_archive_that_crashes_alembic3d_reading_a_sample_is_an_input_error():
    pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
    with open_frames(CRASHING) as source:
        assert source.frame_count == 5
        source.read(0, 4)
        expect_input_error(
            lambda: source.read(2, 5),
            CRASHING,
            frame=4,
            match=r"object /polygons/polygonsShape: the Alembic library crashed reading it "
            r"\(SIGSEGV\): the file is damaged$",
        )


@pytest.mark.usefixtures("no_child_left")
@pytest.mark.parametrize("suffix", [".usdc", ".usda", ".abc"])
def test_usd_and_alembic_stream_as_they_load(cloth, tmp_path, suffix):
    module = "pxr" if suffix.startswith(".usd") else "alembic3d"
    pytest.importorskip(module, reason=f"{module} (its extra) is not installed")
    target = tmp_path / f"cloth{suffix}"
    save_sequence(cloth, target)
    expected = load_sequence(target)
    with open_frames(target) as source:
        assert isinstance(source, IsolatedFrames)
        same_description(source, expected)
        check_ranges(source, expected.vertices)
        copy = pickle.loads(pickle.dumps(source))
        with copy:
            check_ranges(copy, expected.vertices)


@pytest.mark.usefixtures("no_child_left")
def test_the_options_reach_the_child(cloth, tmp_path):
    pytest.importorskip("pxr", reason="pxr (the 'usd' extra) is not installed")
    target = tmp_path / "cloth.usdc"
    save_sequence(cloth, target)
    with open_frames(target, prim="/Root/cloth") as source:
        assert source.frame_count == 60
    with pytest.raises(InputError, match="there is no prim /Root/other"):
        open_frames(target, prim="/Root/other")
