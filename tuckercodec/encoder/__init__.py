"""The encoder: a mesh sequence to a compressed file that meets the error asked for.

Three modes, one at a time: a target KG error (the default, 0.1), fixed ranks (i, k), or a target
size in bpfv (the smallest error that fits).

How a target KG error is met (errors are squared norms; E is the KG denominator's square):

1. The exact table (:mod:`tuckercodec.analysis`) gives the truncation error of every (i, k).
2. Quantization adds error. An error e in column a of U1 reaches the tensor multiplied by the
   norm of core slice a, so column a gets the step sqrt(D) / ||CORE[a, :, :]||; likewise U3's
   column b with ||CORE[:, :, b]||, the core gets sqrt(D), the centroids sqrt(D / K) (an error
   there moves all K vertices). Every stored number then adds about D/12 to the squared error,
   which is also the split that minimises the bits for a given error (reverse water-filling),
   so one number D sets the whole quantizer.
3. For a few splits of the error budget between truncation and quantization, the encoder picks
   the cheapest ranks whose truncation error fits the truncation share (by the exact table, or by
   the paper's bound with ``select="bound"``), sets D from the remaining share, and packs the
   result to count its real bytes. The smallest wins.
4. It then reconstructs exactly what the decoder will return, measures the KG error, and
   tightens D (or loosens it once, if there is room) until the decoded error is at most the
   target. The decoded error is never above the target.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from ..analysis import Analysis, Selection, analyze
from ..format import streams
from ..format.segments import BASIS_SHARED
from ..io.streaming import FrameSource, SequenceFrames
from ..parallel import Executor
from ..sequence import MeshSequence
from .plan import needs_segments
from .results import EncodeReport, EncodeResult, Mode, check_modes
from .search import TRUNCATION_SHARES, initial_step, meet, search_bpfv, search_kg
from .segmented import encode_frames
from .workspace import Workspace

DEFAULT_TARGET_KG = 0.1
#: With fixed ranks, quantization may add this much to the truncation's squared error (KG +5 %).
RANKS_QUANTIZATION_SHARE = 1.05**2 - 1
#: With fixed ranks that lose nothing, the quantization error aimed for, in KG percent.
RANKS_FLOOR_KG = 1e-4


def encode_with_report(
    sequence: MeshSequence,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    select: Selection = "exact",
    level: int = streams.DEFAULT_LEVEL,
    analysis: Analysis | None = None,
    segment_frames: int | None = None,
    max_memory: int | None = None,
    basis: str = BASIS_SHARED,
    executor: Executor | None = None,
) -> EncodeResult:
    """Encode a sequence; the file's bytes and a report of ranks, errors and sizes.

    Args:
        sequence: the mesh sequence (any number of frames; not every frame a single point).
        target_kg: the largest KG error allowed for the decoded sequence, in percent (default
            0.1 when no mode is given).
        ranks: fixed ranks (i, k); quantization then adds at most about 5 % to the KG error of
            the truncation.
        target_bpfv: the largest whole-file size in bits per frame per vertex; the smallest KG
            error that fits is chosen, down to a KG error of 1e-4 (a larger budget is not filled).
        select: ``"exact"`` chooses ranks by the exact error table, ``"bound"`` by the seed
            paper's bound alone.
        level: zstd level of the sections (1-22).
        analysis: the sequence's :func:`~tuckercodec.analyze` result, if already computed.
        segment_frames: cut the frames into segments of this many, each its own decomposition
            (format 1.1; :func:`tuckercodec.encoder.segmented.encode_frames`). Without it,
            segments are made only when encoding the sequence whole would take more than
            ``max_memory`` bytes (default: half the machine's memory).
        max_memory: the memory the encode may use, in bytes.
        basis: with segments, ``"shared"`` (one U1 for all, the default) or ``"own"``.
        executor: with segments, where the passes' tasks run (:mod:`tuckercodec.parallel`);
            the bytes written do not depend on it.

    Raises:
        InputError: the sequence cannot be encoded (every frame a single point, or coordinates
            float64 cannot square).
        UnreachableTargetError: no file of the format meets the target: a ``target_bpfv``
            below the coarsest file's size, or an error target too small for the format's
            32-bit integers (centroids far from the origin, or a target within rounding of 0).
        ValueError: a mode argument that is out of range (ranks, a non-positive target).
    """
    start = time.perf_counter()
    mode = check_modes(target_kg, ranks, target_bpfv)
    if select not in ("exact", "bound"):
        raise ValueError(f"select must be 'exact' or 'bound', got {select!r}")
    if not isinstance(sequence, MeshSequence):
        raise TypeError(f"expected a MeshSequence, got {type(sequence).__name__}")
    if needs_segments(
        sequence.frame_count,
        sequence.vertex_count,
        segment_frames=segment_frames,
        max_memory=max_memory,
    ):
        return encode_source(
            SequenceFrames(sequence),
            target_kg=target_kg,
            ranks=ranks,
            target_bpfv=target_bpfv,
            select=select,
            segment_frames=segment_frames,
            max_memory=max_memory,
            basis=basis,
            executor=executor,
            level=level,
        )
    analysis = analyze(sequence) if analysis is None else analysis
    work = Workspace(sequence, analysis, level)
    exact_ranks = bound_ranks = None
    target: float | None = None

    if mode == "ranks":
        i, k = _checked_ranks(ranks, analysis)
        truncation2 = work.truncation_error2(i, k)
        floor2 = (RANKS_FLOOR_KG / 100.0) ** 2 * work.denominator2
        budget2 = max(
            RANKS_QUANTIZATION_SHARE * truncation2, floor2, 1.01 * work.centroid_floor_error2
        )
        quantized, error2, trials = meet(
            work, i, k, initial_step(work, i, k, budget2), truncation2 + budget2
        )
        target_for_header = None
    elif mode == "kg":
        target = DEFAULT_TARGET_KG if target_kg is None else float(target_kg)
        exact, bound = analysis.cheapest(target), analysis.cheapest(target, select="bound")
        exact_ranks, bound_ranks = (exact.i, exact.k), (bound.i, bound.k)
        quantized, error2, trials = search_kg(work, target, select, TRUNCATION_SHARES)
        target_for_header = target
    else:
        assert target_bpfv is not None  # the mode says so
        target = float(target_bpfv)
        quantized, error2, trials = search_bpfv(work, target, select)
        target_for_header = None

    data, sizes = work.pack(quantized, error2, target_for_header)
    report = EncodeReport(
        mode=mode,
        target=target,
        select=select,
        ranks=(quantized.i, quantized.k),
        kg=work.kg(error2),
        truncation_kg=work.kg(work.truncation_error2(quantized.i, quantized.k)),
        exact_ranks=exact_ranks,
        bound_ranks=bound_ranks,
        total_bytes=len(data),
        section_bytes=sizes,
        vertices=work.vertex_count,
        frames=work.frame_count,
        seconds=time.perf_counter() - start,
        trials=trials,
    )
    return EncodeResult(data, report)


def encode_source(
    frames: FrameSource,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    select: Selection = "exact",
    segment_frames: int | None = None,
    max_memory: int | None = None,
    basis: str = BASIS_SHARED,
    executor: Executor | None = None,
    level: int = streams.DEFAULT_LEVEL,
    progress: Callable[[str], None] | None = None,
) -> EncodeResult:
    """Encode an opened sequence (:func:`tuckercodec.io.open_frames`): whole (loaded, format
    1.0) when that fits ``max_memory`` (default half the machine's memory) and no
    ``segment_frames`` is given, else in segments read a range at a time (format 1.1,
    :func:`tuckercodec.encoder.segmented.encode_frames`). Arguments as for
    :func:`encode_with_report`; ``progress`` is called with a line as each pass starts."""
    if not needs_segments(
        frames.frame_count,
        frames.vertex_count,
        segment_frames=segment_frames,
        max_memory=max_memory,
    ):
        return encode_with_report(
            frames.load(),
            target_kg=target_kg,
            ranks=ranks,
            target_bpfv=target_bpfv,
            select=select,
            level=level,
        )
    if select != "exact":
        raise ValueError("a segmented encode chooses its ranks by the exact error (select)")
    return encode_frames(
        frames,
        target_kg=target_kg,
        ranks=ranks,
        target_bpfv=target_bpfv,
        segment_frames=segment_frames,
        max_memory=max_memory,
        basis=basis,
        executor=executor,
        level=level,
        progress=progress,
    )


def _checked_ranks(ranks: Any, analysis: Analysis) -> tuple[int, int]:
    r1, r3 = analysis.max_ranks
    try:
        i, k = (int(r) for r in ranks)
        valid = all(float(a) == b for a, b in zip(ranks, (i, k), strict=True))
    except (TypeError, ValueError):
        valid = False
    if not valid or not (1 <= i <= r1 and 1 <= k <= r3):
        raise ValueError(
            f"ranks must be two integers with 1 <= i <= {r1} and 1 <= k <= {r3}, got {ranks!r}"
        )
    return i, k


def encode(
    sequence: MeshSequence,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    select: Selection = "exact",
) -> bytes:
    """Encode a sequence into the bytes of a file (``spec/FORMAT.md``).

    One mode at a time: ``target_kg`` (default 0.1, a KG error in percent that the decoded
    sequence never exceeds), ``ranks`` (i, k), or ``target_bpfv`` (the smallest error that fits).
    :func:`encode_with_report` also says what was chosen and measured.
    """
    return encode_with_report(
        sequence, target_kg=target_kg, ranks=ranks, target_bpfv=target_bpfv, select=select
    ).data


__all__ = [
    "EncodeReport",
    "EncodeResult",
    "Mode",
    "encode",
    "encode_frames",
    "encode_source",
    "encode_with_report",
]
