"""The frames of an ``.npz`` archive read a range at a time (:class:`NpzFrames`).

Key ``V`` is read in place: a stored member (``np.savez``) by offset in the file, as a ``.npy``
is (:class:`.streaming.RawFrames`); a deflated one (``np.savez_compressed``) by decompressing
forward from where the last read stopped, the member staying open between reads, so that
reading the ranges in order decompresses the member once (a range before the last one starts
again from the member's beginning). The other keys (faces, names, rate, time codes) are read
whole when the archive is opened, with the checks of :func:`.npz.read_npz`. A stored member's
CRC is not checked by a range read (only reading every byte could check it; ``load_sequence``
does); a deflated one's is, when a read reaches its end. A ``V`` in Fortran order, whose frames
are scattered over the member, is read whole.
"""

from __future__ import annotations

import struct
import zipfile
from pathlib import Path
from typing import IO, ClassVar

from ...errors import InputError
from ...reading import open_input
from ..streaming import RawFrames, read_into
from .archive import ZIP_ERRORS, NpzArchive, member_header

#: A zip local file header: signature, 22 bytes, then the lengths of the name and extra field.
_LOCAL_HEADER = struct.Struct("<4s22xHH")
_LOCAL_SIGNATURE = b"PK\x03\x04"


class Scattered(Exception):
    """Key V is in Fortran order, its frames scattered over the member: read it whole."""


class NpzFrames(RawFrames):
    """Key V of an .npz archive read in place (see the module docstring)."""

    _transient: ClassVar[tuple[str, ...]] = ("_member", "_archive", "_stream")
    _what = "an .npz archive"
    _member: IO[bytes] | None = None
    _archive: zipfile.ZipFile | None = None

    def __init__(self, path: Path):
        with NpzArchive(path) as archive:
            info = archive.info("V")
            header = member_header(archive.zip, info, "V", archive.size, path)
            shape, dtype = header.shape, header.dtype
            if dtype.kind not in "fiu":
                raise InputError(f"key 'V' must hold real numbers, got dtype {dtype}", path=path)
            if len(shape) == 2:  # one frame
                shape = (1, *shape)
            if len(shape) != 3 or shape[2] != 3 or shape[0] < 1 or shape[1] < 1:
                raise InputError(
                    f"key 'V' must have shape (frames, vertices, 3), got {header.shape}",
                    path=path,
                )
            if header.fortran_order and shape[0] > 1:
                raise Scattered
            faces, names, rate, codes = archive.metadata(shape[0], shape[1])
            self._name = info.filename
            self._deflated = info.compress_type == zipfile.ZIP_DEFLATED
            self._offset = header.size  # in the member
            if not self._deflated:  # in the file: after the member's local header
                self._offset += _data_start(archive.stream, info, archive.size, path)
        self._file, self._dtype = path, dtype
        self._describe(path, shape[0], shape[1], faces, names, rate, codes)

    def _read_at(self, offset: int, into: memoryview) -> None:
        if not self._deflated:
            super()._read_at(offset, into)
            return
        try:
            if self._member is None:
                self._stream = open_input(self._file, self._what)
                self._archive = zipfile.ZipFile(self._stream)
                self._member = self._archive.open(self._name)
            # forward: decompresses from where the last read stopped; backward: from the start
            self._member.seek(offset)
            read_into(self._member, into, self._file)
        except InputError:
            raise
        except ZIP_ERRORS as error:
            raise InputError(f"key 'V' cannot be read: {error}", path=self._file) from None


def _data_start(stream: IO[bytes], info: zipfile.ZipInfo, size: int, path: Path) -> int:
    """Where a stored member's bytes start in the file: after its local header."""
    stream.seek(info.header_offset)
    raw = stream.read(_LOCAL_HEADER.size)
    if len(raw) != _LOCAL_HEADER.size or raw[:4] != _LOCAL_SIGNATURE:
        raise InputError("key 'V' has no local header where the archive says", path=path)
    _, name_length, extra_length = _LOCAL_HEADER.unpack(raw)
    start = info.header_offset + _LOCAL_HEADER.size + name_length + extra_length
    if start + info.compress_size > size:
        raise InputError(
            f"key 'V' ends beyond the end of the file ({size} bytes): the file is truncated",
            path=path,
        )
    return start
