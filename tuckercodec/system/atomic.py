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

Every folder output is marked as the tool's: both write, at the folder's root, a small manifest
(:data:`OUTPUT_MARKER`) listing every file and folder they put there. ``overwrite`` (the command
line's ``--force``) replaces an existing folder only if it is empty or one the tool wrote (its
manifest present, and nothing in it beyond what that lists); anything else is refused with
:class:`NotOursError` naming the path and what replacing it would delete, so that ``--force``
never deletes a file a user put in the folder (:func:`refuse_unless_ours`). Without
``overwrite`` an existing folder is never replaced.

A staging folder is named after its writer (host and process), so that one a hard kill left
behind is removed by the next write to the same target once that process is gone
(:func:`clean_stale_staging`).
"""

from __future__ import annotations

import ctypes
import errno
import functools
import hashlib
import json
import os
import re
import shutil
import socket
import tempfile
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import BinaryIO, cast

#: errno values meaning "this file system or kernel has no O_TMPFILE": fall back to a named file.
_NO_TMPFILE = {errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOENT}


def refuse_existing(paths: list[Path], overwrite: bool) -> None:
    """Check, before any work, that every output can be written.

    Raises ``FileExistsError`` naming the first path that exists (unless ``overwrite``;
    with it, :class:`NotOursError` for a folder the tool did not write, see
    :func:`refuse_unless_ours`), and ``FileNotFoundError``/``NotADirectoryError`` naming a path
    whose folder is missing.
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
        if overwrite and Path(path).is_dir() and not Path(path).is_symlink():
            refuse_unless_ours(path)  # a folder is replaced only if the tool wrote it


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


#: The manifest at the root of every folder the tool writes: what it wrote there (see the module
#: docstring). A JSON object: ``format`` (:data:`MARKER_FORMAT`), ``files`` and ``folders``
#: (POSIX paths relative to the folder, sorted).
OUTPUT_MARKER = ".tuckercodec-output.json"
MARKER_FORMAT = "tuckercodec folder output, version 1"
#: How many names a refusal lists before "and N more".
SHOWN_NAMES = 5


class NotOursError(FileExistsError):
    """A folder that ``overwrite`` (``--force``) may not replace: not a folder, or one holding
    something the tool did not write there. The command line exits 1, as for an output that
    exists without ``--force``."""


def _entries(
    folder: Path, descend: Callable[[str], bool] = lambda relative: True
) -> Iterator[tuple[str, os.DirEntry[str]]]:
    """Every entry under ``folder`` with its POSIX path relative to it, links not followed,
    going into a folder only where ``descend(relative)`` says so."""
    pending = [(folder, "")]
    while pending:
        current, prefix = pending.pop()
        with os.scandir(current) as entries:
            for entry in entries:
                relative = prefix + entry.name
                yield relative, entry
                if entry.is_dir(follow_symlinks=False) and descend(relative):
                    pending.append((Path(entry.path), relative + "/"))


def _walk(folder: Path) -> tuple[list[str], list[str]]:
    """The regular files and the folders under ``folder``, as POSIX paths relative to it;
    links are not followed (nor listed: a link is never the tool's)."""
    files: list[str] = []
    folders: list[str] = []
    for relative, entry in _entries(folder):
        if entry.is_dir(follow_symlinks=False):
            folders.append(relative)
        elif entry.is_file(follow_symlinks=False):
            files.append(relative)
    return files, folders


def _manifest(files: Iterable[str], folders: Iterable[str]) -> bytes:
    listed = {"format": MARKER_FORMAT, "files": sorted(files), "folders": sorted(folders)}
    return json.dumps(listed, indent=0).encode()


def mark_output(folder: Path) -> None:
    """Write :data:`OUTPUT_MARKER` into ``folder`` (a staging folder, complete), listing every
    file and folder in it: the folder is then the tool's, which ``overwrite`` may replace."""
    files, folders = _walk(folder)
    write_staged(folder / OUTPUT_MARKER, [_manifest(files, folders)])


def _listed(folder: Path) -> tuple[set[str], set[str]] | None:
    """The files and folders ``folder``'s manifest lists; None without a valid one."""
    marker = folder / OUTPUT_MARKER
    if marker.is_symlink() or not marker.is_file():
        return None
    try:
        listed = json.loads(marker.read_bytes())
    except (OSError, ValueError):
        return None
    if not isinstance(listed, dict) or listed.get("format") != MARKER_FORMAT:
        return None
    files, folders = listed.get("files"), listed.get("folders")
    if not isinstance(files, list) or not isinstance(folders, list):
        return None
    if not all(isinstance(name, str) for name in [*files, *folders]):
        return None
    return set(files), set(folders)


def _strays(folder: Path, listed: tuple[set[str], set[str]] | None) -> list[str]:
    """What in ``folder`` its manifest ``listed`` does not list (everything without one): the
    topmost such entries, a folder ending with ``/``, sorted."""
    if listed is None:
        return sorted(
            e.name + ("/" if e.is_dir(follow_symlinks=False) else "") for e in os.scandir(folder)
        )
    files, folders = listed
    strays: list[str] = []
    for relative, entry in _entries(folder, descend=lambda relative: relative in folders):
        if relative == OUTPUT_MARKER:
            continue
        if entry.is_dir(follow_symlinks=False):
            if relative not in folders:
                strays.append(relative + "/")
        elif not (entry.is_file(follow_symlinks=False) and relative in files):
            strays.append(relative)
    return sorted(strays)


def refuse_unless_ours(folder: str | Path, *, shown: str | Path | None = None) -> None:
    """Check that ``folder``, a folder output's destination, may be replaced in whole: missing,
    empty, or a folder the tool wrote (its :data:`OUTPUT_MARKER`, and nothing in it, at any
    depth, that the marker does not list). ``shown`` names it in the message (default
    ``folder``: a folder moved aside is checked under its own name).

    Raises:
        NotOursError: ``folder`` is a file or a link, or holds what the tool did not write,
            which the message names.
    """
    path = Path(folder)
    name = path if shown is None else shown
    if not os.path.lexists(path):
        return
    if path.is_symlink() or not path.is_dir():
        raise NotOursError(
            f"{name} is not a folder: --force replaces only a folder tuckercodec wrote or an "
            "empty folder"
        )
    listed = _listed(path)
    strays = _strays(path, listed)
    if not strays:
        return
    shown_names = ", ".join(strays[:SHOWN_NAMES])
    more = f" and {len(strays) - SHOWN_NAMES} more" if len(strays) > SHOWN_NAMES else ""
    what = (
        f"was not written by tuckercodec (no {OUTPUT_MARKER})"
        if listed is None
        else "holds files tuckercodec did not write"
    )
    count = f"{len(strays)} entr{'y' if len(strays) == 1 else 'ies'}"
    raise NotOursError(
        f"{name} {what}: --force would delete {count} ({shown_names}{more}), so it is refused; "
        "--force replaces only a folder tuckercodec wrote or an empty folder (move or delete "
        "it yourself)"
    )


#: A staging folder's name: ``.<target>.tkc-<host>-<pid>-<random>.tmp`` (``.old`` for a
#: replaced folder on its way out), ``<host>`` a digest of the host's name.
_STAGING = re.compile(r"\.tkc-([0-9a-f]{8})-([0-9]+)-[^.]+\.tmp")


@functools.lru_cache(maxsize=1)
def _host() -> str:
    return hashlib.sha256(socket.gethostname().encode()).hexdigest()[:8]


def _make_staging(target: Path) -> Path:
    """A new, empty, private staging folder beside ``target``, named after this process."""
    prefix = f".{target.name}.tkc-{_host()}-{os.getpid()}-"
    return Path(tempfile.mkdtemp(dir=target.parent, prefix=prefix, suffix=".tmp"))


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it exists
        return True
    return True


def clean_stale_staging(target: str | Path) -> list[Path]:
    """Remove the staging folders of writes to ``target`` that a hard kill (SIGKILL, a power
    cut) left behind, where that is safe: named as this module names them, on this host, owned
    by this user, and their process no longer running. Returns what was removed. A folder
    whose process still runs (or whose number a new process took) is left."""
    path = Path(target)
    prefix = f".{path.name}"
    removed: list[Path] = []
    try:
        entries = list(os.scandir(path.parent))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(prefix):
            continue
        found = _STAGING.fullmatch(entry.name[len(prefix) :])
        if found is None or found.group(1) != _host() or not entry.is_dir(follow_symlinks=False):
            continue
        pid = int(found.group(2))
        if pid == os.getpid() or _running(pid):
            continue
        with suppress(OSError):
            if entry.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            shutil.rmtree(entry.path)
            removed.append(Path(entry.path))
    return removed


def _replace_folder(staging: Path, target: Path) -> None:
    """Put the complete folder ``staging`` in place of ``target`` (replacing one that
    :func:`refuse_unless_ours` allows): the old folder is renamed aside, checked again there
    (what it holds now is what would be deleted; refused, it is put back), the new one renamed
    in, and the old one removed."""
    aside: Path | None = None
    try:
        if os.path.lexists(target):
            aside = staging.with_suffix(".old")  # the staging folder's random name: free
            os.rename(target, aside)
            try:
                refuse_unless_ours(aside, shown=target)
            except BaseException:
                os.rename(aside, target)
                aside = None
                raise
        try:
            os.rename(staging, target)
        except OSError:
            if aside is not None:
                os.rename(aside, target)  # put the old one back
                aside = None
            raise
    finally:
        if aside is not None:
            shutil.rmtree(aside, ignore_errors=True)


@contextmanager
def atomic_folder(
    destination: str | Path, names: list[str], *, overwrite: bool = False, sync: bool = False
) -> Iterator[Path]:
    """Write the files ``names`` of a folder as a whole: yield a hidden staging folder beside
    ``destination``; when the block ends without an exception, its files are put in place, and
    on any exception the staging folder is removed, leaving ``destination`` as it was.

    A new ``destination`` appears at once, complete, with its manifest (one rename). With
    ``overwrite`` an existing folder must be one the tool wrote, or empty
    (:func:`refuse_unless_ours`, checked before the block runs and again when it is
    replaced); it is then replaced in whole, so no frame of an earlier, longer output lingers.
    Without it, existing files among ``names`` are refused before the block runs and the files
    are moved into the existing folder one rename each, after all of them have been written;
    other files there are never touched (a folder that was the tool's, or empty, keeps a
    manifest listing them all). A hard kill while the files are written can leave the staging
    folder, which the next write to ``destination`` removes (:func:`clean_stale_staging`).

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
        if overwrite:
            refuse_unless_ours(target)
        else:
            refuse_existing([target / name for name in names], overwrite)
    clean_stale_staging(target)
    staging = _make_staging(target)
    try:
        yield staging
        mark_output(staging)
        if sync:
            sync_files(staging, [*names, OUTPUT_MARKER])
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700; match a plain mkdir
        if not os.path.lexists(target) or (overwrite and _holds_anything(target)):
            try:
                _replace_folder(staging, target)
                return
            except OSError:
                if overwrite or not target.is_dir():  # someone made it meanwhile: merge
                    raise
        _merge(staging, target, names)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _holds_anything(folder: Path) -> bool:
    with os.scandir(folder) as entries:
        return next(entries, None) is not None


def _merge(staging: Path, target: Path, names: list[str]) -> None:
    """Move the files ``names`` into the existing folder ``target`` (none replaced); if it was
    the tool's or empty, its manifest lists them too, written before they appear."""
    listed = _listed(target)
    if not _strays(target, listed):
        files, folders = listed or (set(), set())
        write_atomic(target / OUTPUT_MARKER, _manifest(files | set(names), folders), overwrite=True)
    for name in names:
        _move_in(staging / name, target / name, False)


@contextmanager
def atomic_store(destination: str | Path, *, overwrite: bool = False) -> Iterator[Path]:
    """A folder that a library writes as a whole (a zarr store, the viewer's export): yield a
    hidden, empty staging folder beside ``destination``; when the block ends without an
    exception it gets its manifest and becomes ``destination`` in one rename, and on any
    exception it is removed.

    An existing ``destination`` is refused before the block runs (``FileExistsError``) unless
    ``overwrite``, and then unless it is empty or a folder the tool wrote
    (:func:`refuse_unless_ours`: :class:`NotOursError`, checked before the block runs and again
    as it is replaced); it is replaced in whole (renamed aside, the new folder renamed in, the
    old one removed), never merged with the new files, which would mix two stores.
    """
    target = Path(destination)
    refuse_existing([target], overwrite)
    if overwrite:
        refuse_unless_ours(target)
    clean_stale_staging(target)
    staging = _make_staging(target)
    try:
        yield staging
        mark_output(staging)
        os.chmod(staging, 0o777 & ~_umask())  # mkdtemp makes 0700; match a plain mkdir
        if not overwrite and os.path.lexists(target):
            raise _exists(target)
        _replace_folder(staging, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
