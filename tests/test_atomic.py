"""Nothing is lost (tuckercodec/system/atomic.py, and every writer that uses it): outputs appear
whole or not at all, an interrupted or failed write leaves the previous output as it was, and
nothing is replaced without --force (overwrite=True)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import tuckercodec as tc
from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec.cli import main
from tuckercodec.system import atomic


def _listing(folder: Path) -> list[str]:
    return sorted(os.listdir(folder))


def test_a_failed_write_leaves_the_old_file_and_nothing_else(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")

    def fail_halfway(handle):
        handle.write(b"new, but only half")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError, match="disk full"):
        atomic.write_atomic(target, fail_halfway, overwrite=True)
    assert target.read_bytes() == b"old"
    assert _listing(tmp_path) == ["out.bin"]


def test_nothing_is_replaced_without_overwrite(tmp_path):
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    with pytest.raises(FileExistsError, match="--force"):
        atomic.write_atomic(target, b"new")
    assert target.read_bytes() == b"old"


def test_a_file_that_appears_while_writing_is_not_replaced(tmp_path):
    target = tmp_path / "out.bin"

    def someone_else_writes_meanwhile(handle):
        handle.write(b"ours")
        target.write_bytes(b"theirs")

    with pytest.raises(FileExistsError):
        atomic.write_atomic(target, someone_else_writes_meanwhile)
    assert target.read_bytes() == b"theirs"
    assert _listing(tmp_path) == ["out.bin"]


def test_where_an_unnamed_file_cannot_be_linked_it_is_copied_out(tmp_path, monkeypatch):
    def refuse(*args):
        raise OSError(18, "Invalid cross-device link")

    monkeypatch.setattr(atomic, "_link_descriptor", refuse)
    monkeypatch.setattr(atomic, "_LINKING_WORKS", None)
    atomic.write_atomic(tmp_path / "out.bin", b"payload")
    assert (tmp_path / "out.bin").read_bytes() == b"payload"
    assert _listing(tmp_path) == ["out.bin"]


def test_new_files_get_a_plain_files_permissions(tmp_path):
    atomic.write_atomic(tmp_path / "out.bin", b"data")
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "out.bin").stat().st_mode & 0o777 == 0o666 & ~mask


def test_an_overwrite_replaces_the_file_with_a_plain_files_permissions(tmp_path):
    # (refusing without overwrite, and a failed write keeping the old file: the tests above)
    target = tmp_path / "out.bin"
    target.write_bytes(b"old")
    atomic.write_atomic(target, b"new", overwrite=True)
    assert target.read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bin"]
    # the same permissions as a file written by open(), not mkstemp's private 0600
    plain = tmp_path / "plain.bin"
    plain.write_bytes(b"x")
    assert target.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


def test_a_file_a_library_writes_by_name_appears_only_when_complete(tmp_path):
    target = tmp_path / "out.usda"
    with atomic.atomic_path(target) as temporary:
        # hidden, beside the target, ending in the suffix a library chooses its format by
        assert temporary.parent == tmp_path and temporary.name.startswith(".out.usda.")
        assert temporary.name.endswith(".tmp.usda")
        temporary.write_bytes(b"written by the library")
        assert not target.exists()
    assert target.read_bytes() == b"written by the library"
    assert _listing(tmp_path) == ["out.usda"]
    plain = tmp_path / "plain.bin"
    plain.write_bytes(b"x")
    assert target.stat().st_mode & 0o777 == plain.stat().st_mode & 0o777


def test_a_library_write_that_fails_or_meets_an_existing_file_leaves_it(tmp_path):
    target = tmp_path / "out.abc"
    target.write_bytes(b"old")

    def write(data: bytes, *, overwrite: bool = False, fail: bool = False) -> None:
        with atomic.atomic_path(target, overwrite=overwrite, suffix="") as temporary:
            assert temporary.name.endswith(".tmp")
            temporary.write_bytes(data)
            if fail:
                raise RuntimeError("library failed")
            if data == b"ours":
                target.write_bytes(b"theirs")  # someone else's file, created meanwhile

    with pytest.raises(FileExistsError, match="--force"):  # refused before the library runs
        write(b"new")
    with pytest.raises(RuntimeError, match="library failed"):
        write(b"half", overwrite=True, fail=True)
    assert target.read_bytes() == b"old"
    assert _listing(tmp_path) == ["out.abc"]
    target.unlink()
    with pytest.raises(FileExistsError):
        write(b"ours")
    assert target.read_bytes() == b"theirs"
    assert _listing(tmp_path) == ["out.abc"]
    write(b"new", overwrite=True)
    assert target.read_bytes() == b"new"
    assert _listing(tmp_path) == ["out.abc"]


_SLOW_WRITER = textwrap.dedent(
    """
    import signal, sys, time
    from tuckercodec.system import atomic
    # A shell's background job inherits SIGINT ignored; restore Ctrl-C as a terminal has it.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    folder = sys.argv[1]
    atomic.write_atomic(folder + "/probe.bin", b"x")  # finds out how files are put in place
    print("unnamed" if atomic._LINKING_WORKS else "named", flush=True)

    def slow(handle):
        handle.write(b"n" * (1 << 20))
        handle.flush()
        print("writing", flush=True)
        time.sleep(60)

    atomic.write_atomic(folder + "/out.bin", slow, overwrite=True)
    """
)


@pytest.mark.parametrize("how", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_killing_the_writer_mid_write_keeps_the_old_file(tmp_path, how):
    (tmp_path / "out.bin").write_bytes(b"old")
    with subprocess.Popen(
        [sys.executable, "-c", _SLOW_WRITER, str(tmp_path)], stdout=subprocess.PIPE, text=True
    ) as child:
        assert child.stdout is not None
        try:
            mode = child.stdout.readline().strip()
            assert child.stdout.readline().strip() == "writing"
            child.send_signal(how)
            child.wait(timeout=30)
        finally:
            child.kill()
    assert (tmp_path / "out.bin").read_bytes() == b"old"
    left = set(_listing(tmp_path)) - {"out.bin", "probe.bin"}
    if mode == "unnamed" or how != signal.SIGKILL:
        # an unnamed file dies with the process; an exception removes a named one
        assert left == set()
    else:  # a named temporary file cannot be removed by a process killed with SIGKILL
        assert all(name.startswith(".out.bin.") and name.endswith(".tmp") for name in left)


#: The CLI, run so that it says when its search has begun: SIGTERM is then certain to reach the
#: encode, not the interpreter's start-up (which takes seconds on a slow machine, and there
#: SIGTERM's default action ends the process before the CLI installs its handler).
_ENCODE_SAYING_WHEN = """
import sys
from tuckercodec.cli import main
from tuckercodec.encoder.encoder import Encoder

search = Encoder._search

def announced(self, work):
    print("searching", flush=True)
    return search(self, work)

Encoder._search = announced
sys.exit(main(sys.argv[1:]))
"""


def test_sigterm_during_an_encode_exits_cleanly_and_keeps_the_old_file(tmp_path):
    source = tmp_path / "big.npz"
    frames, side = 200, 60
    np.savez(source, V=wave_sequence(frames, side), F=grid_faces(side))
    out = tmp_path / "out.tkc"
    out.write_bytes(b"old")
    arguments = ["encode", str(source), "-o", str(out), "--kg", "0.0001", "--force"]
    with subprocess.Popen(
        [sys.executable, "-c", _ENCODE_SAYING_WHEN, *arguments],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as child:
        try:
            assert child.stdout is not None
            assert child.stdout.readline() == "searching\n"  # the search takes seconds
            child.send_signal(signal.SIGTERM)
            _, err = child.communicate(timeout=300)  # a hang guard: it takes milliseconds
        finally:
            child.kill()
    assert child.returncode == 128 + signal.SIGTERM, err
    assert err.strip() == "tuckercodec: interrupted"
    assert out.read_bytes() == b"old"
    assert _listing(tmp_path) == ["big.npz", "out.tkc"]


def test_an_unwritable_folder_gives_one_line_and_leaves_nothing(tmp_path, monkeypatch, capsys):
    # Simulated, because a read-only folder does not stop root (see the next test).
    source = tmp_path / "in.npz"
    np.savez(source, V=wave_sequence(6, 4), F=grid_faces(4))
    out_folder = tmp_path / "out"
    out_folder.mkdir()

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied", str(out_folder / "x.tkc"))

    monkeypatch.setattr(atomic, "_open_unnamed", refuse)
    assert main(["encode", str(source), "-o", str(out_folder / "x.tkc")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Permission denied" in err
    assert _listing(out_folder) == []


@pytest.mark.skipif(
    os.name != "posix" or os.geteuid() == 0,
    reason="a read-only folder does not stop root, which CI may be",
)
def test_a_read_only_folder_gives_one_line_and_leaves_nothing(tmp_path, capsys):
    source = tmp_path / "in.npz"
    np.savez(source, V=wave_sequence(6, 4), F=grid_faces(4))
    out_folder = tmp_path / "out"
    out_folder.mkdir()
    out_folder.chmod(0o555)
    try:
        assert main(["encode", str(source), "-o", str(out_folder / "x.tkc")]) == 1
        assert "Permission denied" in capsys.readouterr().err
        assert _listing(out_folder) == []
    finally:
        out_folder.chmod(0o755)


def test_encode_file_never_replaces_without_overwrite(tmp_path):
    sequence = tc.MeshSequence(wave_sequence(6, 4), grid_faces(4))
    source = tmp_path / "in.npz"
    tc.save_sequence(sequence, source)
    out = tmp_path / "out.tkc"
    out.write_bytes(b"old")
    with pytest.raises(FileExistsError):
        tc.encode_file(source, out)
    assert out.read_bytes() == b"old"
    tc.encode_file(source, out, overwrite=True)
    assert tc.info(out).vertices == 16


def _failing_after(count: int, real):
    calls = {"n": 0}

    def write(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] > count:
            raise OSError(28, "No space left on device")
        return real(*args, **kwargs)

    return write


def test_a_decode_into_a_new_folder_that_fails_leaves_no_folder(tmp_path, monkeypatch):
    from tuckercodec.io import obj as obj_io

    sequence = tc.MeshSequence(wave_sequence(6, 4), grid_faces(4))
    monkeypatch.setattr(obj_io, "write_obj", _failing_after(3, obj_io.write_obj))
    with pytest.raises(OSError, match="No space"):
        tc.save_sequence(sequence, tmp_path / "frames", progress=False)
    assert _listing(tmp_path) == []  # neither the folder nor its staging folder


def test_a_failed_decode_over_an_existing_folder_keeps_every_old_frame(tmp_path, monkeypatch):
    from tuckercodec.io import obj as obj_io

    old = tc.MeshSequence(wave_sequence(6, 4), grid_faces(4))
    tc.save_sequence(old, tmp_path / "frames", progress=False)
    before = {p.name: p.read_bytes() for p in (tmp_path / "frames").iterdir()}
    assert atomic.OUTPUT_MARKER in before  # the folder is marked as the tool's
    new = tc.MeshSequence(wave_sequence(6, 4, seed=1), grid_faces(4))
    with pytest.raises(FileExistsError):
        tc.save_sequence(new, tmp_path / "frames", progress=False)  # no overwrite: refused first
    monkeypatch.setattr(obj_io, "write_obj", _failing_after(3, obj_io.write_obj))
    with pytest.raises(OSError, match="No space"):
        tc.save_sequence(new, tmp_path / "frames", overwrite=True, progress=False)
    assert {p.name: p.read_bytes() for p in (tmp_path / "frames").iterdir()} == before
    assert _listing(tmp_path) == ["frames"]
    monkeypatch.undo()
    tc.save_sequence(new, tmp_path / "frames", overwrite=True, progress=False)
    np.testing.assert_array_equal(
        tc.load_sequence(tmp_path / "frames", progress=False).vertices, new.vertices
    )
    assert _listing(tmp_path) == ["frames"]


def _user_files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_force_keeps_a_folder_of_frames_holding_a_users_file(tmp_path):
    """--force once replaced whatever the folder held; now only a folder the tool wrote."""
    old = tc.MeshSequence(wave_sequence(6, 4), grid_faces(4))
    new = tc.MeshSequence(wave_sequence(6, 4, seed=1), grid_faces(4))
    frames = tmp_path / "frames"
    tc.save_sequence(old, frames, progress=False)
    (frames / "notes.txt").write_text("not ours")
    before = _user_files(frames)
    with pytest.raises(atomic.NotOursError, match=r"frames holds files .* \(notes.txt\)"):
        tc.save_sequence(new, frames, overwrite=True, progress=False)
    assert _user_files(frames) == before and _listing(tmp_path) == ["frames"]
    # a folder of frames the tool did not write (no manifest) is refused the same way
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "frame_00000.obj").write_text("v 0 0 0\n")
    with pytest.raises(atomic.NotOursError, match="was not written by tuckercodec"):
        tc.save_sequence(new, foreign, overwrite=True, progress=False)
    assert (foreign / "frame_00000.obj").read_text() == "v 0 0 0\n"


def test_force_replaces_a_folder_of_frames_it_wrote_whole(tmp_path):
    """No frame of a longer earlier output lingers: the folder is replaced, not merged."""
    frames = tmp_path / "frames"
    tc.save_sequence(tc.MeshSequence(wave_sequence(9, 4), grid_faces(4)), frames, progress=False)
    new = tc.MeshSequence(wave_sequence(4, 4, seed=1), grid_faces(4))
    tc.save_sequence(new, frames, overwrite=True, progress=False)
    back = tc.load_sequence(frames, progress=False)
    np.testing.assert_array_equal(back.vertices, new.vertices)
    assert len(list(frames.glob("*.obj"))) == 4 and _listing(tmp_path) == ["frames"]


def test_frames_merged_into_an_empty_or_foreign_folder(tmp_path):
    """Without --force an existing folder gets the new files beside its own, untouched; an
    empty folder (even with --force) becomes the tool's, a folder of other files does not."""
    sequence = tc.MeshSequence(wave_sequence(3, 4), grid_faces(4))
    empty = tmp_path / "empty"
    empty.mkdir()
    tc.save_sequence(sequence, empty, overwrite=True, progress=False)
    atomic.refuse_unless_ours(empty)  # the tool's now: --force may replace it
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    (mixed / "mine.txt").write_text("mine")
    tc.save_sequence(sequence, mixed, progress=False)
    assert (mixed / "mine.txt").read_text() == "mine"
    assert not (mixed / atomic.OUTPUT_MARKER).exists()
    with pytest.raises(atomic.NotOursError, match=r"mine\.txt"):
        atomic.refuse_unless_ours(mixed)


def test_the_manifest_is_checked_at_every_depth(tmp_path):
    """A file put inside a folder the tool wrote (its data/, say) makes it not the tool's."""
    target = tmp_path / "store"
    with atomic.atomic_store(target) as staging:
        (staging / "data").mkdir()
        (staging / "data" / "x.bin").write_bytes(b"x")
    atomic.refuse_unless_ours(target)
    (target / "data" / "mine.txt").write_text("mine")
    (target / "data" / "sub").mkdir()
    with pytest.raises(atomic.NotOursError) as refused:
        atomic.refuse_unless_ours(target)
    assert "2 entries (data/mine.txt, data/sub/)" in str(refused.value)
    (target / "data" / "mine.txt").unlink()
    (target / "data" / "sub").rmdir()
    (target / "data" / "x.bin").unlink()
    (target / "data" / "x.bin").symlink_to(tmp_path)  # a link where a file was: not ours
    with pytest.raises(atomic.NotOursError, match=r"data/x\.bin"):
        atomic.refuse_unless_ours(target)
    (target / "data" / "x.bin").unlink()
    (target / atomic.OUTPUT_MARKER).write_text("{not json")
    with pytest.raises(atomic.NotOursError, match="was not written by tuckercodec"):
        atomic.refuse_unless_ours(target)


def test_atomic_store_checks_the_folder_again_as_it_replaces_it(tmp_path):
    """A file put into the folder while the new one was built is seen when the old folder is
    moved aside: the replacement is refused and the folder put back as it was."""
    target = tmp_path / "store"
    with atomic.atomic_store(target) as staging:
        (staging / "old.txt").write_text("old")

    def replace_while_a_user_adds_a_file() -> None:
        with atomic.atomic_store(target, overwrite=True) as staging:
            (staging / "new.txt").write_text("new")
            (target / "mine.txt").write_text("mine")  # meanwhile, by someone else

    with pytest.raises(atomic.NotOursError, match=r"mine\.txt"):
        replace_while_a_user_adds_a_file()
    assert sorted(p.name for p in target.iterdir()) == [
        atomic.OUTPUT_MARKER,
        "mine.txt",
        "old.txt",
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["store"]
    (target / "mine.txt").unlink()
    with atomic.atomic_store(target, overwrite=True) as staging:
        (staging / "new.txt").write_text("new")
    assert sorted(p.name for p in target.iterdir()) == [atomic.OUTPUT_MARKER, "new.txt"]


def test_a_stale_staging_folder_of_a_dead_writer_is_removed_by_the_next_write(tmp_path):
    """SIGKILL while a store is written leaves its staging folder; the next write to the same
    target removes it, and only it: a live writer's, or a look-alike of another host or with
    no such name, is left."""
    target = tmp_path / "out.zarr"
    script = (
        "import sys, time\n"
        "from tuckercodec.system.atomic import atomic_store\n"
        "with atomic_store(sys.argv[1]) as staging:\n"
        "    (staging / 'part').write_bytes(b'x')\n"
        "    print(staging, flush=True)\n"
        "    time.sleep(120)\n"
    )
    child = subprocess.Popen(
        [sys.executable, "-c", script, str(target)], stdout=subprocess.PIPE, text=True
    )
    assert child.stdout is not None
    staged = Path(child.stdout.readline().strip())
    os.kill(child.pid, signal.SIGKILL)
    child.wait(timeout=60)
    child.stdout.close()
    assert staged.is_dir()
    alive = atomic._make_staging(target)  # this process's: running
    other_host = tmp_path / f".out.zarr.tkc-00000000-{child.pid}-abc.tmp"
    other_host.mkdir()
    plain = tmp_path / ".out.zarr.mine.tmp"
    plain.mkdir()
    with atomic.atomic_store(target) as staging:
        (staging / "part").write_bytes(b"y")
    assert not staged.exists()
    assert alive.is_dir() and other_host.is_dir() and plain.is_dir()


def test_frames_written_plainly_are_synced_before_their_folder_appears(tmp_path, monkeypatch):
    """A folder of OBJ frames is written without an fsync per file: every file, and the
    staging folder, is synced before the folder is moved in (an fsync that fails leaves
    nothing), so a crash cannot leave a visible folder of incomplete frames."""
    sequence = tc.MeshSequence(wave_sequence(5, 4), grid_faces(4))
    target = tmp_path / "frames"
    synced: set[int] = set()  # inodes: the files and the folder keep theirs when moved in
    real_fsync = os.fsync

    def fsync(descriptor: int) -> None:
        assert not target.exists()  # nothing is visible before the syncs
        synced.add(os.fstat(descriptor).st_ino)
        real_fsync(descriptor)

    monkeypatch.setattr(os, "fsync", fsync)
    tc.save_sequence(sequence, target, progress=False)
    files = list(target.iterdir())
    assert len(files) == 6  # five frames and the manifest, all synced
    assert synced >= {path.stat().st_ino for path in files}
    assert target.stat().st_ino in synced or os.name != "posix"  # a folder is synced on POSIX

    def failing(descriptor: int) -> None:
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(os, "fsync", failing)
    with pytest.raises(OSError, match="Input/output"):
        tc.save_sequence(sequence, tmp_path / "other", progress=False)
    assert _listing(tmp_path) == ["frames"]


def test_write_staged_writes_new_files_only(tmp_path):
    atomic.write_staged(tmp_path / "a", [b"one ", b"", b"two"])
    assert (tmp_path / "a").read_bytes() == b"one two"
    with pytest.raises(FileExistsError):
        atomic.write_staged(tmp_path / "a", [b"three"])
    assert (tmp_path / "a").read_bytes() == b"one two"
