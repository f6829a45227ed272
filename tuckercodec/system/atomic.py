"""Writing output files so that nothing is lost: never a half-written file, never an overwrite
that was not asked for, never a stray temporary file.

A file is written first where no one can see it, and put in place only once complete:

* On Linux it is an *unnamed* file in the destination folder (``O_TMPFILE``): if the process is
  killed while writing, even by SIGKILL, the kernel frees it and nothing is left behind. Once
  complete it is linked in under its name. Without ``overwrite`` the link itself refuses an
  existing file, so there is no window between a check and the write in which another program's
  file could be replaced.
* Elsewhere (or on a file system without ``O_TMPFILE``) it is a hidden temporary file beside the
  target, renamed over it when complete and removed on any error. Only a hard kill in the middle
  of writing can leave that temporary file (named ``.<target>.<random>.tmp``).

Either way a rename within one folder is atomic, so readers see the old file or the new one.
A folder of files (decoded OBJ frames) is written as a whole with :func:`atomic_folder`, and
a folder that a library writes (a zarr store) with :func:`atomic_store`. The files of an
:func:`atomic_folder` may be written plainly into its staging folder (:func:`write_staged`),
since no one sees them there: ``sync=True`` makes them durable, all at once, before they are
moved in.
"""

from __future__ import annotations

import ctypes
import errno
import functools
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO, cast

#: errno values meaning "this file system or kernel has no O_TMPFILE": fall back to a named file.
_NO_TMPFILE = {errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOENT}


def refuse_existing(paths: list[Path], overwrite: bool) -> None:
    """Check, before any work, that every output can be written.

    Raises ``FileExistsError`` naming the first path that exists (unless ``overwrite``), and
    ``FileNotFoundError``/``NotADirectoryError`` naming a path whose folder is missing.
    """
    for path in paths:
        folder = Path(path).parent
        if not folder.exists():
            raise FileNotFoundError(errno.ENOENT, "the output folder does not exist", str(folder))
        if not folder.is_dir():
            raise NotADirectoryError(
                errno.ENOTDIR, "the output's folder is not a folder", str(folder)
            )
        if not overwrite and Path(path).exists():
            raise _exists(path)


def _exists(path: str | Path) -> FileExistsError:
    return FileExistsError(
        f"{path} already exists (pass --force, or overwrite=True, to replace it)"
    )


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _file_mode() -> int:
    """The permissions a plain ``open()`` would give a new file (0666 less the umask)."""
    return 0o666 & ~_umask()


def _open_unnamed(folder: Path) -> int | None:
    """A descriptor of a new unnamed file in ``folder``, or None where that is not supported."""
    flag = getattr(os, "O_TMPFILE", None)
    if flag is None or not Path("/proc/self/fd").is_dir():  # linking it in needs /proc
        return None
    try:
        # read-write: the fallback in atomic_output copies it back out if linking fails
        return os.open(folder, flag | os.O_RDWR, _file_mode())
    except OSError as error:
        if error.errno in _NO_TMPFILE:
            return None
        raise


#: Whether linking an unnamed file into place has worked here (None: not tried yet). Some
#: kernels and sandboxes refuse both ways of doing it; then named temporary files are used.
_LINKING_WORKS: bool | None = None
_AT_FDCWD, _AT_EMPTY_PATH = -100, 0x1000


@functools.lru_cache(maxsize=1)
def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _link_descriptor(descriptor: int, name: Path) -> None:
    """Give the unnamed file ``descriptor`` the name ``name`` (FileExistsError if taken)."""
    libc = _libc()
    # linkat(fd, "", AT_FDCWD, name, AT_EMPTY_PATH): the direct way where it is allowed.
    if libc.linkat(descriptor, b"", _AT_FDCWD, os.fsencode(name), _AT_EMPTY_PATH) == 0:
        return
    code = ctypes.get_errno()
    if code == errno.EEXIST:
        raise FileExistsError(code, os.strerror(code), str(name))
    # The unprivileged way: follow the descriptor's link in /proc.
    os.link(f"/proc/self/fd/{descriptor}", name, follow_symlinks=True)


def _publish_unnamed(descriptor: int, target: Path, overwrite: bool) -> None:
    """Give the unnamed file ``descriptor`` the name ``target``."""
    if not overwrite:
        try:
            _link_descriptor(descriptor, target)  # fails if target exists: no race
        except FileExistsError:
            raise _exists(target) from None
        return
    # To replace a file, link under a temporary name and rename that over the target: the
    # temporary name exists only between these two calls.
    temporary = target.parent / f".{target.name}.{os.getpid()}.{descriptor}.tmp"
    _link_descriptor(descriptor, temporary)
    try:
        os.replace(temporary, target)
    except BaseException:
        _remove(temporary)
        raise


def _copy_to_named(descriptor: int, target: Path, overwrite: bool) -> None:
    """Publish an unnamed file whose linking failed: copy it to a named temporary file."""
    with _named_output(target, overwrite) as handle:
        os.lseek(descriptor, 0, os.SEEK_SET)
        with os.fdopen(os.dup(descriptor), "rb") as source:
            shutil.copyfileobj(source, handle, 1 << 20)


def _remove(path: str | Path) -> None:
    with suppress(FileNotFoundError):
        os.unlink(path)


@contextmanager
def atomic_output(path: str | os.PathLike[str], *, overwrite: bool = False) -> Iterator[BinaryIO]:
    """Open a hidden file in ``path``'s folder for binary writing; it becomes ``path`` when the
    block ends without an exception, and vanishes otherwise (see the module docstring).

    Raises ``FileExistsError`` if ``path`` exists and ``overwrite`` is False (checked before the
    block runs and again, atomically where possible, when the file is put in place).
    """
    global _LINKING_WORKS
    target = Path(path)
    refuse_existing([target], overwrite)
    descriptor = None if _LINKING_WORKS is False else _open_unnamed(target.parent)
    if descriptor is None:
        with _named_output(target, overwrite) as handle:
            yield handle
        return
    with os.fdopen(descriptor, "w+b") as handle:
        yield handle
        handle.flush()
        os.fsync(handle.fileno())
        try:
            _publish_unnamed(handle.fileno(), target, overwrite)
            _LINKING_WORKS = True
        except FileExistsError:
            raise
        except OSError:
            if _LINKING_WORKS:  # it worked before: this failure is real
                raise
            _LINKING_WORKS = False
            _copy_to_named(handle.fileno(), target, overwrite)


@contextmanager
def _named_output(target: Path, overwrite: bool) -> Iterator[BinaryIO]:
    """The fallback: a hidden named temporary file beside ``target``, renamed over it."""
    # Not a with-block: the file must outlive its handle until the rename below.
    handle = tempfile.NamedTemporaryFile(  # noqa: SIM115
        mode="wb", dir=target.parent, prefix=f".{target.name}.", suffix=".tmp", delete=False
    )
    try:
        os.chmod(handle.name, _file_mode())  # mkstemp makes 0600; match a plain open()
        with handle:
            yield cast(BinaryIO, handle)  # the wrapper delegates every file method
            handle.flush()
            os.fsync(handle.fileno())
        if not overwrite and target.exists():  # created by someone else while we wrote
            raise _exists(target)
        os.replace(handle.name, target)
    except BaseException:
        _remove(handle.name)
        raise


def write_atomic(
    path: str | os.PathLike[str],
    data: bytes | Callable[[BinaryIO], None],
    *,
    overwrite: bool = False,
) -> None:
    """Write ``data`` (bytes, or a function that writes to a binary file) to ``path`` atomically."""
    with atomic_output(path, overwrite=overwrite) as handle:
        if callable(data):
            data(handle)
        else:
            handle.write(data)


@contextmanager
def atomic_path(
    path: str | os.PathLike[str], *, overwrite: bool = False, suffix: str | None = None
) -> Iterator[Path]:
    """For a library that writes a file itself, by name (USD, Alembic): yield a hidden
    temporary path beside ``path`` (``.<name>.<random>.tmp<suffix>``) to write to; when the
    block ends without an exception, that file becomes ``path``, and on any exception it is
    removed.

    ``suffix`` ends the temporary name (default: ``path``'s own suffix), since some libraries
    choose the file format by it. Raises ``FileExistsError`` if ``path`` exists and
    ``overwrite`` is False, checked before the block runs and again, atomically where the file
    system has hard links, when the file is put in place. Unlike :func:`atomic_output`, a hard
    kill while the library writes leaves the temporary file: it has a name from the start.
    """
    target = Path(path)
    refuse_existing([target], overwrite)
    descriptor, name = tempfile.mkstemp(
        dir=target.parent,
        prefix=f".{target.name}.",
        suffix=".tmp" + (target.suffix if suffix is None else suffix),
    )
    os.close(descriptor)  # the library opens it again by name
    temporary = Path(name)
    try:
        yield temporary
        os.chmod(temporary, _file_mode())  # mkstemp makes 0600; match a plain open()
        _move_in(temporary, target, overwrite)
    finally:
        _remove(temporary)  # gone already after a successful move


def _move_in(source: Path, target: Path, overwrite: bool) -> None:
    """Rename ``source`` to ``target``; without ``overwrite``, never replace an existing file."""
    if overwrite:
        os.replace(source, target)
        return
    try:
        os.link(source, target)  # refuses an existing file, with no window for a race
    except FileExistsError:
        raise _exists(target) from None
    except OSError:  # a file system without hard links: check, then rename
        if target.exists():
            raise _exists(target) from None
        os.replace(source, target)
        return
    os.unlink(source)


#: sync_file_range's flag that starts the writeback of a range without waiting for it.
_SYNC_FILE_RANGE_WRITE = 2
#: Windows opens files as text unless told otherwise; elsewhere there is no such flag.
_O_BINARY = getattr(os, "O_BINARY", 0)


def _start_writeback(descriptor: int) -> None:
    """Ask the kernel to start writing a file's data to disk now, without waiting (Linux's
    ``sync_file_range``; elsewhere nothing): the fsync that makes it durable later then finds
    it written, or being written, while the caller did other work meanwhile."""
    if not hasattr(os, "O_TMPFILE"):  # not Linux: the later fsync does all the work
        return
    try:
        function = _libc().sync_file_range
    except (AttributeError, OSError):
        return
    function.argtypes = [ctypes.c_int, ctypes.c_int64, ctypes.c_int64, ctypes.c_uint]
    function(descriptor, 0, 0, _SYNC_FILE_RANGE_WRITE)  # a failure only loses the head start


def write_staged(path: str | os.PathLike[str], chunks: list[bytes]) -> None:
    """Write a new file of ``chunks`` plainly, for a staging folder of :func:`atomic_folder`
    whose ``sync=True`` makes it durable before it is moved in (no one else sees it meanwhile,
    and the folder is removed on any error). Its writeback is started at once.
    ``FileExistsError`` if ``path`` exists."""
    descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_BINARY, 0o666)
    with os.fdopen(descriptor, "wb", buffering=0) as handle:
        for chunk in chunks:
            view = memoryview(chunk)
            while view:  # a raw write may write less than asked
                view = view[handle.write(view) or 0 :]
        _start_writeback(descriptor)


#: Files synced at once by :func:`sync_files`: the file system commits the waits of
#: concurrent fsyncs together (on ext4 one journal commit serves them all), where one fsync
#: after another waits for a commit and a disk cache flush each.
SYNC_THREADS = 8


def sync_files(folder: Path, names: list[str]) -> None:
    """Make the files ``names`` of ``folder``, and the folder's entries, durable: an fsync of
    each file (a few at once), then of the folder itself (where a folder can be opened: not
    on Windows). The first error is raised once every fsync has ended."""

    def sync(name: str) -> None:
        descriptor = os.open(folder / name, os.O_RDWR | _O_BINARY)  # Windows syncs writable ones
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)

    with ThreadPoolExecutor(max_workers=max(1, min(SYNC_THREADS, len(names)))) as pool:
        for _ in pool.map(sync, names):
            pass
    if os.name == "posix":
        descriptor = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)


@contextmanager
def atomic_folder(
    destination: str | Path, names: list[str], *, overwrite: bool = False, sync: bool = False
) -> Iterator[Path]:
    """Write the files ``names`` of a folder as a whole: yield a hidden staging folder beside
    ``destination``; when the block ends without an exception, its files are moved into
    ``destination`` (created if missing), and on any exception the staging folder is removed,
    leaving ``destination`` as it was.

    A new ``destination`` appears at once, complete (one rename). Into an existing folder the
    files are moved one rename each, after all of them have been written, so an interruption
    can only fall in that short last step. Existing files among ``names`` are refused unless
    ``overwrite``; other files in ``destination`` are never touched. Only a hard kill while the
    files are being written can leave the staging folder (``.<destination>.<random>.tmp``).

    With ``sync``, the files and the staging folder are made durable (:func:`sync_files`)
    before anything is moved in, so files written plainly into it (:func:`write_staged`) are
    complete on disk before they can be seen under ``destination``, as those of
    :func:`write_atomic` are.
    """
    target = Path(destination)
    if target.exists() and not target.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "not a folder", str(target))
    parent = target.parent
    if not parent.is_dir():
        raise FileNotFoundError(
            errno.ENOENT, "the output folder's parent does not exist", str(parent)
        )
    if target.is_dir():
        refuse_existing([target / name for name in names], overwrite)
    staging = Path(tempfile.mkdtemp(dir=parent, prefix=f".{target.name}.", suffix=".tmp"))
    try:
        yield staging
        if sync:
            sync_files(staging, names)
        if not target.exists():
            os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700; match a plain mkdir
            try:
                os.rename(staging, target)  # fails if someone made target meanwhile
                return
            except OSError:
                if not target.is_dir():
                    raise
        for name in names:
            _move_in(staging / name, target / name, overwrite)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


@contextmanager
def atomic_store(
    destination: str | Path,
    *,
    overwrite: bool = False,
    replaceable: Callable[[Path], None] | None = None,
) -> Iterator[Path]:
    """A folder that a library writes as a whole (a zarr store): yield a hidden, empty staging
    folder beside ``destination``; when the block ends without an exception it becomes
    ``destination`` in one rename, and on any exception it is removed.

    An existing ``destination`` is refused before the block runs (``FileExistsError``) unless
    ``overwrite``; then it is replaced in whole (renamed aside, the new folder renamed in, the
    old one removed), never merged with the new files, which would mix two stores.
    ``replaceable``, if given, is called with an existing ``destination`` just before it is
    renamed aside, and may refuse it by raising (the staging folder is then removed).
    """
    target = Path(destination)
    refuse_existing([target], overwrite)
    staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp"))
    aside: Path | None = None
    try:
        yield staging
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700; match a plain mkdir
        if os.path.lexists(target):
            if not overwrite:
                raise _exists(target)
            if replaceable is not None:
                replaceable(target)
            aside = staging.with_suffix(".old")  # the staging folder's random name: free
            os.rename(target, aside)
        try:
            os.rename(staging, target)
        except OSError:
            if aside is not None:
                os.rename(aside, target)  # put the old one back
                aside = None
            raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        if aside is not None:
            if aside.is_dir() and not aside.is_symlink():
                shutil.rmtree(aside, ignore_errors=True)
            else:
                aside.unlink(missing_ok=True)
