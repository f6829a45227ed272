"""What the two point-cache formats share (:mod:`.pc2`, :mod:`.mdd`): reading a fixed-size
header and checking the file's size against what it declares (positions are then read by offset:
:class:`~tuckercodec.model.sources.RawFrames`), the faces the points take from ``--faces MESH`` (as
``.npy`` files do too), and positions made ready for writing.

A point cache holds positions only: F frames of K points, each a float32 x, y, z. The header
declares F and K, so the file's size is known before anything is read: a file that is shorter
(truncated) or longer (trailing bytes) than declared is refused with both sizes, before any
array is allocated.
"""

from .cache import (
    INT32_MAX,
    POINT_BYTES,
    CacheFrames,
    cache_faces,
    check_counts,
    check_size,
    float32_positions,
    open_cache,
    read_floats,
    read_header,
)

__all__ = [
    "INT32_MAX",
    "POINT_BYTES",
    "CacheFrames",
    "cache_faces",
    "check_counts",
    "check_size",
    "float32_positions",
    "open_cache",
    "read_floats",
    "read_header",
]
