"""A compressed file on disk: read whole, its head alone, or a section's byte range at a time.

:func:`read_file` and :func:`open_file_container` are the only ways a file is read from a path:
only a regular file (a folder or a named pipe is an :class:`~tuckercodec.errors.InputError`), and
no more than its preamble declares, so that a huge file that is not ours is refused after its
first 32 bytes and trailing bytes are counted from the file's size, not read (§5 step 5).
"""

from __future__ import annotations

import os

from ..system.reading import open_regular_file
from .container import (
    HEAD_SIZE,
    Container,
    check_not_longer,
    check_reaches,
    parse_container,
    read_preamble,
)
from .limits import DEFAULT_LIMITS, Limits


def read_file(
    path: str | os.PathLike[str], limits: Limits = DEFAULT_LIMITS, *, header_only: bool = False
) -> bytes:
    """The bytes of a compressed file on disk, or with ``header_only`` just its preamble and
    header (for :func:`tuckercodec.info`).

    Only a regular file is opened (a folder or a named pipe is an :class:`InputError`), and no
    more is read than the preamble declares: a huge file that is not ours is refused after its
    first 32 bytes, and trailing bytes are counted from the file's size, not read (§5 step 5).
    A header-only read also refuses a file shorter than ``total_length`` from its size, before
    the header's CRC (§5's note on header-only readers); a whole read leaves that to
    :func:`parse_container`, in §5's order. The caller names ``path`` in the errors.
    """
    with open_regular_file(path, "a tuckercodec file") as handle:
        head = handle.read(HEAD_SIZE)
        preamble = read_preamble(head, limits)
        size = os.fstat(handle.fileno()).st_size
        check_not_longer(size, preamble.total_length)
        if header_only:
            check_reaches(size, preamble.total_length, "the data area", "preamble.total_length")
            return head + handle.read(preamble.data_start - len(head))
        return head + handle.read(preamble.total_length - len(head))


class FileRanges:
    """A compressed file on disk read a range at a time: a decoder that needs one segment
    reads that segment's sections, never the whole file (§8, random access).

    Each read opens the file, reads its range and closes it again, so that an opened decoder
    holds no file handle; a range the file no longer holds (it shrank since it was opened) is
    a :class:`TruncatedFileError`.
    """

    def __init__(self, path: str | os.PathLike[str], size: int) -> None:
        self.path = os.fspath(path)
        self.size = size
        self.bytes_read = 0  # for tests and benchmarks: what decoding really read

    def read(self, offset: int, length: int) -> bytes:
        """``length`` bytes from ``offset``."""
        with open_regular_file(self.path, "a tuckercodec file") as handle:
            data: bytes = os.pread(handle.fileno(), length, offset) if length else b""
        self.bytes_read += len(data)
        check_reaches(
            offset + len(data), offset + length, "a section (since it was opened)", "section"
        )
        return data


def open_file_container(
    path: str | os.PathLike[str], limits: Limits = DEFAULT_LIMITS
) -> tuple[Container, FileRanges]:
    """Parse a file on disk from its preamble and header alone (§5 steps 1-8, the whole-file
    checks made from its size), and a reader of its sections' ranges."""
    with open_regular_file(path, "a tuckercodec file") as handle:
        head = handle.read(HEAD_SIZE)
        preamble = read_preamble(head, limits)
        size = os.fstat(handle.fileno()).st_size
        check_not_longer(size, preamble.total_length)
        head += handle.read(preamble.data_start - len(head))
    container = parse_container(head, limits, whole=False, size=size)
    ranges = FileRanges(path, size)
    ranges.bytes_read = len(head)
    return container, ranges
