"""The ceiling of what one read may decompress: a few hundred bytes of deflate become a
megabyte of zeros, so a small file can declare, consistently, arrays a thousand times its size
(a 467 KB ``.vtp`` of 1.06 GB of points, ``.npz`` members 1,100 times theirs). The bytes a
compressed file declares are not bytes that exist; what a read inflates is bounded by
:attr:`~.registry.ReadOptions.max_memory` (``--max-memory``; by default half the machine's
memory, as for an encode) instead.

A reader takes an :class:`Inflation` for what it holds at once (one ``.vtp`` frame, an
``.npz`` archive's arrays, one XDMF time step, a glTF file's decompressed views) and has each
array's declared size taken from it before the array is inflated: a size beyond what is left is
refused then, before anything is allocated, and each array is inflated no further than its
declared size (zlib's ``max_length``, zipfile's member size), so nothing is ever inflated beyond
the ceiling. Stored (uncompressed) data is not counted: it is bytes the file holds.
"""

from __future__ import annotations

import os

from ...errors import InputError
from ...system.memory import human_bytes, memory_allowed


def memory_ceiling(max_memory: int | None) -> int:
    """The most bytes a read may decompress: ``max_memory``, else half the machine's memory."""
    return memory_allowed(max_memory)


class Inflation:
    """What is left of a read's ceiling (bytes) for the arrays it inflates and holds at once."""

    def __init__(self, ceiling: int):
        self.ceiling = self.left = ceiling

    def take(self, size: int, what: str, path: str | os.PathLike[str] | None = None) -> None:
        """Count ``size`` more bytes inflated for ``what`` (an array, a member: named first in
        the error, with ``path``, the file, if given), or refuse them."""
        if size > self.left:
            held = self.ceiling - self.left
            beside = f" beside the {human_bytes(held)} inflated before it" if held else ""
            raise InputError(
                f"{what}: inflates to {human_bytes(size)}{beside}, beyond the "
                f"{human_bytes(self.ceiling)} a read may decompress (--max-memory, by default "
                "half the machine's memory): refused",
                path=path,
            )
        self.left -= size
