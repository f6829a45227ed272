"""Writing output files so that nothing is lost: never a half-written file, never an overwrite
that was not asked for.

A file is written to a temporary name in its destination folder and renamed over the target
only once complete (a rename within one file system is atomic), so a failure or an interrupt
leaves either the old file or the new one, and no stray temporary file.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO


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
            raise NotADirectoryError(errno.ENOTDIR, "the output's folder is not a folder", str(folder))
        if not overwrite and Path(path).exists():
            raise FileExistsError(f"{path} already exists (pass --force, or overwrite=True, to replace it)")


@contextmanager
def atomic_output(path: str | Path, *, overwrite: bool = False) -> Iterator[BinaryIO]:
    """Open a temporary file beside ``path`` for binary writing; rename it to ``path`` on success.

    On any exception the temporary file is removed and ``path`` is left as it was.
    """
    target = Path(path)
    refuse_existing([target], overwrite)
    folder = target.parent if str(target.parent) else Path(".")
    # Not a with-block: the file must outlive its handle until the rename below.
    handle = tempfile.NamedTemporaryFile(  # noqa: SIM115
        mode="wb", dir=folder, prefix=f".{target.name}.", suffix=".tmp", delete=False
    )
    try:
        # mkstemp creates the file as 0600; give it the mode a plain open() would have.
        os.chmod(handle.name, 0o666 & ~_current_umask())
        with handle:
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        if not overwrite and target.exists():  # created by someone else while we wrote
            raise FileExistsError(f"{target} already exists (pass --force, or overwrite=True, to replace it)")
        os.replace(handle.name, target)
    except BaseException:
        try:
            os.unlink(handle.name)
        except FileNotFoundError:
            pass
        raise


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_atomic(path: str | Path, data: bytes | Callable[[BinaryIO], None], *, overwrite: bool = False) -> None:
    """Write ``data`` (bytes, or a function that writes to a binary file) to ``path`` atomically."""
    with atomic_output(path, overwrite=overwrite) as handle:
        if callable(data):
            data(handle)
        else:
            handle.write(data)
