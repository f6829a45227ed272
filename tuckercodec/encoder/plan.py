"""When to segment, and how: the segment boundaries, the blocks read at a time, the sketch's rank,
and the memory each of them takes.

A sequence is encoded whole (one decomposition, format 1.0) unless segments are asked for
(``segment_frames``) or the whole encode would not fit the memory allowed (``max_memory``). The
whole encode holds the float64 tensor and, at its peak, several more arrays of its size: it was
measured at about 7 times the float64 positions (:data:`WHOLE_ENCODE_FACTOR`). A segmented
encode reads the frames in blocks, several times over, and its memory does not grow with F.

The memory allowed is a promise, so the plan counts every term of a segmented encode's peak
(:func:`planned_memory`), each measured (BENCHMARKS.md, "The memory of a segmented encode"):
the process itself (Python, numpy, scipy: :data:`PROCESS_BASELINE`), the mesh's prediction and
the faces' coding beside the first passes, the blocks of frames, the sketch (K x r arrays while
it is summed and orthonormalised), the projections in r dimensions, and at the search's and the
file's peak the shared U1's K x i arrays (quantized, dequantized, predicted, streamed) with
zstd's context. It plans to :data:`MEMORY_MARGIN` below the limit, and refuses a limit below
what even one frame at a time and the smallest sketch need.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, replace

import zstandard

from ..format.streams import DEFAULT_LEVEL
from ..system.memory import human_bytes, memory_allowed

#: Peak memory of a whole (one-segment) encode over the float64 positions, measured on samba
#: (144 MiB for 40 MiB) and on a 100,000-vertex, 1,000-frame cloth (16.6 GB for 2.4 GB).
WHOLE_ENCODE_FACTOR = 7.0
#: The frames of a segment when segments are needed but no length is given: about 10 s of
#: animation at 24 fps, long enough that a segment's core and U2 cost little beside its U3.
DEFAULT_SEGMENT_FRAMES = 250
#: Columns of the randomized range finder beyond the largest rank it must resolve.
OVERSAMPLING = 32
#: The range finder's columns at first: resolves U1 ranks up to about 200. A target the sketch
#: does not resolve makes the encoder sketch again with more (up to what memory allows).
DEFAULT_SKETCH_COLUMNS = 256
#: The fewest columns a sketch has.
MIN_SKETCH_COLUMNS = 8
#: The most frames read at once, whatever the memory: keeps the blocks, and so the sums, the same
#: on machines of different sizes (the output does not depend on the machine).
MAX_BLOCK_FRAMES = 16
#: Of the memory left beside the fixed terms, the share one block of frames may take.
BLOCK_SHARE = 0.2

# The terms of the peak, measured on a 30,000-vertex, 300-frame body (59,980 faces) with
# tracemalloc and the resident memory by phase (BENCHMARKS.md), each with some room:
#: Resident memory of the process before the first frame: Python, numpy, scipy.linalg,
#: zstandard and tuckercodec imported (measured 72 MB), with room for BLAS's per-thread buffers.
PROCESS_BASELINE = 90 * 10**6
#: Per vertex: the mesh's prediction (parents, levels, neighbour means; 525 bytes measured).
VERTEX_BYTES = 700
#: Per face: the faces' coding, which runs beside the first passes (its Python objects: 1,200
#: bytes a face at its peak), and what the allocator keeps of it afterwards (600 measured).
FACE_BYTES, FACE_KEPT_BYTES = 1500, 800
#: Float64 copies of a block of frames held at once: the frames read, centred, and in the
#: measuring pass the reconstruction and its difference (4 measured).
BLOCK_COPIES = 5
#: K x r float64 arrays while the sketch is orthonormalised: the sum and Q.
SKETCH_COPIES = 2
#: K x i arrays of 8 bytes at the search's and the file's peak, beside Q (K x r): the quantized
#: U1, its dequantized values (the measuring pass), and the packing's predicted residuals, the
#: predictor chosen per column, the stream's transpose and its zigzag (6 measured with i = r).
BASIS_COPIES = 7
#: r x 3F float64 arrays of the model: the projections, their concatenation, each segment's
#: rotated tensor and core (4 measured).
MODEL_COPIES = 5
#: Planned peak over the memory allowed: the measured peak varies with the allocator and the
#: machine, so the plan leaves this share free.
MEMORY_MARGIN = 0.1
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
    """The estimated peak memory of encoding the sequence whole: the process itself and
    :data:`WHOLE_ENCODE_FACTOR` times the float64 positions."""
    return PROCESS_BASELINE + int(WHOLE_ENCODE_FACTOR * frames * vertices * 3 * 8)


def zstd_bytes(level: int, source_bytes: int) -> int:
    """zstd's context (bytes) for compressing ``source_bytes`` at ``level`` in one call."""
    parameters = zstandard.ZstdCompressionParameters.from_level(
        level, source_size=max(1, source_bytes)
    )
    return int(parameters.estimated_compression_context_size())


@dataclass(frozen=True)
class MemoryUse:
    """A segmented encode's planned peak, term by term (bytes): see :func:`planned_memory`.

    Two phases never overlap: the passes that sketch (``sketch``: the K x r arrays, and
    ``faces``, their coding beside the passes) and the search and packing that follow
    (``basis`` and ``zstd``, with ``faces_kept``); the other terms last the whole encode."""

    baseline: int
    mesh: int
    blocks: int
    model: int
    faces: int
    sketch: int
    faces_kept: int
    basis: int
    zstd: int

    @property
    def peak(self) -> int:
        """The planned peak: the lasting terms and the larger of the two phases."""
        lasting = self.baseline + self.mesh + self.blocks + self.model
        return lasting + max(self.faces + self.sketch, self.faces_kept + self.basis + self.zstd)


def planned_memory(
    vertices: int,
    frames: int,
    faces: int,
    *,
    segments: int,
    own_basis: bool,
    block_frames: int,
    columns: int,
    rank: int,
    level: int,
) -> MemoryUse:
    """The memory of a segmented encode of ``segments`` segments that reads ``block_frames``
    frames at a time, sketches ``columns`` columns and keeps at most ``rank`` of U1's; each
    term measured (the constants above). With a basis per segment, every segment's Q and
    quantized U1 are held at once."""
    column = vertices * 8  # one K-row column of float64 (or int64)
    held_q = segments if own_basis else 1
    return MemoryUse(
        baseline=PROCESS_BASELINE,
        mesh=VERTEX_BYTES * vertices,
        blocks=BLOCK_COPIES * block_frames * vertices * 3 * 8,
        model=MODEL_COPIES * columns * 3 * frames * 8 + 16 * frames * min(frames, 3 * columns),
        faces=FACE_BYTES * faces,
        # pass 1: the running sum and its Q (with a basis per segment, the Qs made so far too)
        sketch=(SKETCH_COPIES + held_q - 1) * columns * column,
        faces_kept=FACE_KEPT_BYTES * faces,
        # the search and the file: Q (or each segment's) and the U1s' arrays
        basis=held_q * columns * column + (BASIS_COPIES + held_q - 1) * rank * column,
        # a U1's stream, its largest: up to 4 bytes a value when its planes are packed
        zstd=zstd_bytes(level, 4 * vertices * rank),
    )


@dataclass(frozen=True)
class SegmentPlan:
    """How a segmented encode cuts and reads the sequence.

    Attributes:
        bounds: (start, stop) of each segment's frames.
        block_frames: frames read and processed at once.
        sketch_columns: r, the columns of the range finder (the largest U1 rank it resolves is
            about r - :data:`OVERSAMPLING`).
        max_rank: the most columns of U1 the search may keep: r, or fewer where the memory
            allowed cannot hold the file's K x i arrays.
        most_columns: the most columns a sketch may have: K, 3F, or what the memory allows. A
            target the sketch does not resolve sketches again with more, up to these.
        memory: the memory allowed (bytes); ``use``: the planned peak, term by term.
    """

    bounds: tuple[tuple[int, int], ...]
    block_frames: int
    sketch_columns: int
    max_rank: int = 0
    most_columns: int = 0
    memory: int = 0
    use: MemoryUse | None = None
    #: what the accounting needs to plan another sketch (:meth:`with_columns`)
    shape: tuple[int, int, int, bool, int] = (0, 0, 0, False, 0)

    def with_columns(self, columns: int) -> SegmentPlan:
        """The same plan with a sketch of ``columns`` columns (at most :attr:`most_columns`),
        and the rank the memory then allows."""
        vertices, frames, faces, own, level = self.shape
        columns = min(columns, self.most_columns)
        rank, use = _largest_rank(
            vertices,
            frames,
            faces,
            len(self.bounds),
            own,
            self.block_frames,
            columns,
            level,
            self.memory,
        )
        return replace(self, sketch_columns=columns, max_rank=rank, use=use)

    @property
    def columns_limited_by(self) -> str:
        """What bounds :attr:`most_columns`: ``"memory"``, or the sequence's own size (``"K"``,
        the vertices, or ``"3F"``, three times the frames)."""
        vertices, frames = self.shape[0], self.shape[1]
        if self.most_columns >= min(vertices, 3 * frames):
            return "K" if vertices <= 3 * frames else "3F"
        return "memory"


def _fits(memory: int, use: MemoryUse) -> bool:
    return use.peak <= memory * (1.0 - MEMORY_MARGIN)


def _largest(low: int, high: int, fits: Callable[[int], bool]) -> int:
    """The largest n in low..high with ``fits(n)`` (monotone: true up to some n), or low - 1."""
    if high < low or not fits(low):
        return low - 1
    while low < high:
        middle = (low + high + 1) // 2
        if fits(middle):
            low = middle
        else:
            high = middle - 1
    return low


def _largest_rank(
    vertices: int,
    frames: int,
    faces: int,
    segments: int,
    own: bool,
    block: int,
    columns: int,
    level: int,
    memory: int,
) -> tuple[int, MemoryUse]:
    """The most columns of U1 (at most ``columns``) that fit ``memory``, and the use then
    (0 if not even one fits)."""

    def use(rank: int) -> MemoryUse:
        return planned_memory(
            vertices,
            frames,
            faces,
            segments=segments,
            own_basis=own,
            block_frames=block,
            columns=columns,
            rank=rank,
            level=level,
        )

    rank = _largest(1, columns, lambda n: _fits(memory, use(n)))
    return rank, use(max(rank, 1))


def plan_segments(
    frames: int,
    vertices: int,
    *,
    segment_frames: int | None,
    max_memory: int,
    faces: int = 0,
    basis_own: bool = False,
    level: int = DEFAULT_LEVEL,
    sketch_columns: int = DEFAULT_SKETCH_COLUMNS,
) -> SegmentPlan:
    """Segments of ``segment_frames`` frames (the last one holds the rest; one shorter than half
    a segment joins the one before), blocks and sketch sized to ``max_memory`` (the planned peak
    of :func:`planned_memory` at most 1 - :data:`MEMORY_MARGIN` of it): the block first takes
    up to :data:`BLOCK_SHARE` of what the lasting terms leave, then the sketch its
    ``sketch_columns`` or as many as fit. ``ValueError`` if not even one frame at a time and
    :data:`MIN_SKETCH_COLUMNS` columns fit."""
    length = DEFAULT_SEGMENT_FRAMES if segment_frames is None else segment_frames
    if length < 1:
        raise ValueError(f"segment_frames must be at least 1, got {length}")
    starts = list(range(0, frames, length))
    if len(starts) > 1 and frames - starts[-1] < max(1, length // 2):
        starts.pop()  # a short tail joins the segment before
    bounds = tuple(zip(starts, [*starts[1:], frames], strict=True))
    shape = (vertices, frames, faces, basis_own, level)

    def use(block: int, columns: int, rank: int) -> MemoryUse:
        return planned_memory(
            vertices,
            frames,
            faces,
            segments=len(bounds),
            own_basis=basis_own,
            block_frames=block,
            columns=columns,
            rank=rank,
            level=level,
        )

    least = use(1, MIN_SKETCH_COLUMNS, 1)
    if not _fits(max_memory, least):
        raise ValueError(
            f"a memory limit of {human_bytes(max_memory)} is too small for a segmented encode "
            f"of {vertices} vertices: it needs at least "
            f"{human_bytes(least.peak / (1.0 - MEMORY_MARGIN))} (the process itself takes about "
            f"{human_bytes(PROCESS_BASELINE)}, the faces' coding {human_bytes(least.faces)}); "
            "allow more memory (max_memory, --max-memory)"
        )
    spare = max_memory * (1.0 - MEMORY_MARGIN) - least.peak + least.blocks
    frame_bytes = BLOCK_COPIES * vertices * 3 * 8
    block = max(1, min(MAX_BLOCK_FRAMES, int(BLOCK_SHARE * spare) // frame_bytes))
    wanted = max(MIN_SKETCH_COLUMNS, min(sketch_columns, vertices, 3 * frames))
    ceiling = max(MIN_SKETCH_COLUMNS, min(vertices, 3 * frames), wanted)
    most = _largest(MIN_SKETCH_COLUMNS, ceiling, lambda r: _fits(max_memory, use(block, r, 1)))
    columns = min(wanted, most)
    plan = SegmentPlan(bounds, block, columns, 0, most, max_memory, None, shape)
    return plan.with_columns(columns)


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
