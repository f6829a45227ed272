"""The memory a piece of work may use: what it is told, else half the machine's.

An encode (whether to segment, how large a block or sketch may be) and a read (how much a
compressed file may inflate) both take a ``max_memory`` that defaults to half the machine's
memory, so that a large cache does not push the machine into swap. That default is decided here
only, by :func:`memory_allowed`; everything that takes a ``max_memory`` asks it.
"""

from __future__ import annotations

import os

#: What :func:`default_max_memory` allows where the machine's memory is unknown (bytes).
UNKNOWN_MACHINE_MEMORY = 4 * 10**9


def physical_memory() -> int | None:
    """The machine's physical memory in bytes, where the system says (Linux, macOS)."""
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def default_max_memory() -> int:
    """Half the machine's memory (:data:`UNKNOWN_MACHINE_MEMORY` where it is unknown): what a
    piece of work may use unless told otherwise."""
    total = physical_memory()
    return total // 2 if total else UNKNOWN_MACHINE_MEMORY


def memory_allowed(max_memory: int | None) -> int:
    """The bytes a piece of work may use: ``max_memory`` if given, else
    :func:`default_max_memory`."""
    return default_max_memory() if max_memory is None else max_memory


def human_bytes(count: float) -> str:
    """``1.5 GB``: a size for messages."""
    for unit in ("B", "kB", "MB", "GB"):
        if count < 1000 or unit == "GB":
            return f"{count:.3g} {unit}" if unit != "B" else f"{int(count)} B"
        count /= 1000
    return f"{count:.3g} TB"  # pragma: no cover
