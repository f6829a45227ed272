"""§6.5 Section NAME (codec ``msgpack-zstd``): one name per frame, ancillary.

The names are one msgpack array of F strings in one zstd frame; the section's ``size`` parameter
is the array's size in bytes. Files whose frames have the default names ``frame_00000``... leave
the section out.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import msgpack

from ..errors import FormatError
from ..model.sequence import default_frame_names
from . import streams
from .limits import Limits, check_limit


def encode_names(
    names: Sequence[str], level: int = streams.DEFAULT_LEVEL
) -> tuple[dict[str, Any], bytes] | None:
    """``(params, payload)`` of the NAME section, or ``None`` for the default names."""
    if list(names) == default_frame_names(len(names)):
        return None
    raw = msgpack.packb(list(names), use_bin_type=True)
    return {"size": len(raw)}, streams.compress(raw, level)


def decode_names(
    params: Mapping[str, Any],
    payload: Callable[[], memoryview],
    frame_count: int,
    limits: Limits,
    where: str,
) -> list[str]:
    """The frame names of a NAME section (§5 step 17): its ``size`` first, then ``payload()``
    (which checks the CRC), the zstd frame and the content (R35-names)."""
    size = params.get("size")
    if not isinstance(size, int) or isinstance(size, bool) or size < 0:
        raise FormatError(
            f"size must be a non-negative integer, got {size!r}",
            rule="R35-names",
            field=f"{where}.size",
        )
    check_limit(size, limits, "max_section_bytes", what=f"{size} bytes", field=f"{where}.size")
    raw = streams.decompress_exact(payload(), size, where)
    try:
        names = msgpack.unpackb(raw, raw=False, strict_map_key=True)
    except (ValueError, TypeError, msgpack.UnpackException):
        names = None
    if not (
        isinstance(names, list)
        and len(names) == frame_count
        and all(isinstance(n, str) for n in names)
    ):
        raise FormatError(
            f"must be one msgpack array of {frame_count} strings", rule="R35-names", field=where
        )
    return names
