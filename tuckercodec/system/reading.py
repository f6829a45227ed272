"""Opening files to read them: only regular files, never anything that could block or never end.

Every reader of the package (mesh sequences, compressed files) opens its input here, so that a
folder, a named pipe or a device given by mistake gets a clear :class:`InputError` instead of a
hang (opening a named pipe waits for a writer for ever) or an endless read (``/dev/zero``).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import BinaryIO

from ..errors import InputError


def open_regular_file(path: str | os.PathLike[str], what: str) -> BinaryIO:
    """Open ``path`` for reading in binary; a folder, named pipe or device is an InputError.

    ``what`` names what the file should have been ("an OBJ file"). Raises OSError when the file
    cannot be opened at all.
    """
    # O_NONBLOCK: opening a named pipe would otherwise wait for a writer, for ever. It changes
    # nothing for a regular file.
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    descriptor = os.open(path, flags)
    try:
        mode = os.fstat(descriptor).st_mode
        if stat.S_ISDIR(mode):
            raise InputError(f"is a folder, not {what}", path=path)
        if not stat.S_ISREG(mode):
            raise InputError(
                f"is not a regular file (a pipe or a device?), so not {what}", path=path
            )
        return os.fdopen(descriptor, "rb")
    except BaseException:
        os.close(descriptor)
        raise


def open_input(path: str | os.PathLike[str], what: str) -> BinaryIO:
    """:func:`open_regular_file` for a reader of input files: a file that cannot be opened at
    all (missing, unreadable) is an InputError naming it too, not an OSError."""
    try:
        return open_regular_file(path, what)
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror or error}", path=path) from None


def inside_folder(folder: Path, name: str) -> Path:
    """The resolved path of ``name``, a file that another file lists (a .pvd's frames, an
    .xdmf's HDF5 files), which must lie inside ``folder``, the lister's own: an absolute path, or
    one that leads out through ``..`` or a symbolic link, or one with a NUL character, is an
    :class:`InputError` without a path (the caller names the file that lists it), as glTF
    keeps its buffers beside it. A service that converts uploads must not hand out its own
    files."""
    text = name.replace("\\", "/")
    if "\0" in text:  # no file system has such a name; os refuses it with a bare ValueError
        raise InputError(f"names {name!r}, with a NUL character, which no file name holds")
    if "://" in text or text.startswith("/") or Path(text).is_absolute() or text[1:2] == ":":
        raise InputError(f"names {name!r}, an absolute path: only files inside its folder are read")
    base = folder.resolve()
    target = (base / text).resolve()
    if not target.is_relative_to(base):
        raise InputError(f"names {name!r}, which leads out of its folder ({base}): refused")
    return target
