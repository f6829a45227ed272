"""When to segment, and how: the segment boundaries, the blocks read at a time, the sketch's rank.

A sequence is encoded whole (one decomposition, format 1.0) unless segments are asked for
(``segment_frames``) or the whole encode would not fit the memory allowed (``max_memory``). The
whole encode holds the float64 tensor and, at its peak, several more arrays of its size: it was
measured at about 7 times the float64 positions (:data:`WHOLE_ENCODE_FACTOR`). A segmented
encode reads the frames in blocks, several times over, and holds only a block, the sketch (K x r)
and the small projected tensor (r x 3 x F), so its memory does not grow with F.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..system.memory import memory_allowed

#: Peak memory of a whole (one-segment) encode over the float64 positions, measured on samba
#: (144 MiB for 40 MiB) and on a 100,000-vertex, 1,000-frame cloth (16.6 GB for 2.4 GB).
WHOLE_ENCODE_FACTOR = 7.0
#: The frames of a segment when segments are needed but no length is given: about 10 s of
#: animation at 24 fps, long enough that a segment's core and U2 cost little beside its U3.
DEFAULT_SEGMENT_FRAMES = 250
#: Columns of the randomized range finder beyond the largest rank it must resolve.
OVERSAMPLING = 32
#: The range finder's columns when nothing bounds them lower: resolves U1 ranks up to about 200.
DEFAULT_SKETCH_COLUMNS = 256
#: Of the memory allowed, the share the sketch (K x r, held up to three times while it is
#: orthonormalised) may take, and the share one block of frames (float64, a few copies) may.
SKETCH_SHARE, BLOCK_SHARE = 0.5, 0.2
#: Bytes of one block's float64 positions and the copies made while centring and projecting.
BLOCK_COPIES = 4
#: The most frames read at once, whatever the memory: keeps the blocks, and so the sums, the same
#: on machines of different sizes (the output does not depend on the machine).
MAX_BLOCK_FRAMES = 16

_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*([kmgt]?i?b?)?\s*$", re.IGNORECASE)
_UNITS = {"": 1, "b": 1, "k": 10**3, "m": 10**6, "g": 10**9, "t": 10**12}


def parse_size(text: str) -> int:
    """Bytes from a size such as ``2GB``, ``1.5G``, ``512MiB`` or ``1000000`` (SI units; ``i``
    means powers of 1024). ``ValueError`` for anything else."""
    match = _SIZE.match(text)
    if match is None:
        raise ValueError(f"not a size: {text!r} (write e.g. 2GB, 1.5G or 512MiB)")
    number, unit = float(match.group(1)), (match.group(2) or "").lower()
    binary = "i" in unit
    unit = unit.replace("i", "").replace("b", "")
    scale = 1024 ** "kmgt".index(unit) * 1024 if binary and unit else _UNITS[unit]
    value = int(number * scale)
    if value <= 0:
        raise ValueError(f"a size must be positive: {text!r}")
    return value


def whole_encode_bytes(frames: int, vertices: int) -> int:
    """The estimated peak memory of encoding the sequence whole."""
    return int(WHOLE_ENCODE_FACTOR * frames * vertices * 3 * 8)


@dataclass(frozen=True)
class SegmentPlan:
    """How a segmented encode cuts and reads the sequence.

    Attributes:
        bounds: (start, stop) of each segment's frames.
        block_frames: frames read and processed at once.
        sketch_columns: r, the columns of the range finder (the largest U1 rank it resolves is
            about r - :data:`OVERSAMPLING`).
    """

    bounds: tuple[tuple[int, int], ...]
    block_frames: int
    sketch_columns: int


def plan_segments(
    frames: int, vertices: int, *, segment_frames: int | None, max_memory: int
) -> SegmentPlan:
    """Segments of ``segment_frames`` frames (the last one holds the rest; one shorter than half
    a segment joins the one before), blocks and sketch sized to ``max_memory``."""
    length = DEFAULT_SEGMENT_FRAMES if segment_frames is None else segment_frames
    if length < 1:
        raise ValueError(f"segment_frames must be at least 1, got {length}")
    starts = list(range(0, frames, length))
    if len(starts) > 1 and frames - starts[-1] < max(1, length // 2):
        starts.pop()  # a short tail joins the segment before
    bounds = tuple(zip(starts, [*starts[1:], frames], strict=True))
    frame_bytes = vertices * 3 * 8 * BLOCK_COPIES
    block = max(1, min(MAX_BLOCK_FRAMES, int(BLOCK_SHARE * max_memory) // frame_bytes))
    affordable = int(SKETCH_SHARE * max_memory) // (3 * vertices * 8)
    columns = max(8, min(DEFAULT_SKETCH_COLUMNS, affordable, vertices, 3 * frames))
    return SegmentPlan(bounds, block, columns)


def needs_segments(
    frames: int, vertices: int, *, segment_frames: int | None, max_memory: int | None
) -> bool:
    """Whether to segment: when asked, or when the whole encode would not fit ``max_memory``."""
    if segment_frames is not None:
        return True
    return whole_encode_bytes(frames, vertices) > memory_allowed(max_memory)


def blocks(start: int, stop: int, block_frames: int) -> list[tuple[int, int]]:
    """The blocks of frames ``start .. stop - 1`` read at once."""
    return [(a, min(a + block_frames, stop)) for a in range(start, stop, block_frames)]
