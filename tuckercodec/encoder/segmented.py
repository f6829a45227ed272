"""The segmented encoder: a sequence larger than memory, read in passes, to a file of format 1.1.

The frames are cut into segments (:mod:`.plan`), each its own decomposition with its own U3,
core, centroids and U2, and one U1 shared by all of them (``basis="shared"``, the default) or
one per segment (``basis="own"``). Three passes read the input, a segment per task, on any
executor (:mod:`tuckercodec.parallel`; :mod:`.passes`):

1. the centroids, the energies and a randomized range finder's sketch of the mode-1 space;
2. the projection of every frame on the sketch's orthonormal basis Q, which leaves the whole
   sequence in r dimensions (:mod:`.segment_model`): the ranks, the steps and even the decoded
   error are then found in memory;
3. the decoded error measured on the input with the decoder's own reconstruction, which the
   file must meet (a fourth pass, with finer steps, in the rare case that it does not).

The KG guarantee holds for the whole sequence: the squared errors of the segments add, and so do
their KG denominators, since each frame's centroid is its own. One quantization parameter D
serves every segment (equal slopes, the split of a total error that costs the fewest bits), and
the ranks are the cheapest whose truncation errors add up to the truncation's share of the budget.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import numpy as np

from ..format import qmat, streams
from ..format.container import parse_container
from ..format.segments import BASIS_SHARED
from ..io.streaming import FrameSource
from ..parallel import Executor, InProcessExecutor
from .plan import default_max_memory, plan_segments
from .results import EncodeReport, EncodeResult, check_modes
from .search import TRUNCATION_SHARES
from .segment_file import pack_segmented
from .segment_search import encode_ranks, search_bpfv, search_kg
from .segment_work import BASES, SegmentedEncode, SharedBasis
from .workspace import column_steps


def encode_frames(
    source: FrameSource,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    segment_frames: int | None = None,
    max_memory: int | None = None,
    basis: str = BASIS_SHARED,
    executor: Executor | None = None,
    level: int = streams.DEFAULT_LEVEL,
    progress: Callable[[str], None] | None = None,
    shared_basis: SharedBasis | None = None,
) -> EncodeResult:
    """Encode a sequence read a range of frames at a time into a segmented file (format 1.1).

    Args:
        source: the frames (:func:`tuckercodec.io.open_frames`, or a
            :class:`~tuckercodec.io.streaming.SequenceFrames` around a sequence in memory).
        target_kg, ranks, target_bpfv: the mode, as for :func:`tuckercodec.encode_with_report`;
            the KG error is of the whole sequence.
        segment_frames: frames per segment (default 250; a short last segment joins the one
            before).
        max_memory: bytes the encode may use (default: half the machine's memory); it sizes
            the blocks read at once and the sketch.
        basis: ``"shared"`` (one U1 for every segment) or ``"own"`` (one per segment).
        executor: runs the passes' tasks (default: in this process); the bytes written do not
            depend on it.
        level: zstd level of the sections.
        progress: called with a line of text as each pass starts.
        shared_basis: a shared U1 to use as it is (the U1 section of another segmented file,
            :func:`shared_basis_of`), instead of one found from these frames; every segment
            then uses its leading columns, and the file holds the section byte for byte.
    """
    start = time.perf_counter()
    mode = check_modes(target_kg, ranks, target_bpfv)
    if basis not in BASES:
        raise ValueError(f"basis must be one of {', '.join(BASES)}, got {basis!r}")
    memory = default_max_memory() if max_memory is None else max_memory
    plan = plan_segments(
        source.frame_count, source.vertex_count, segment_frames=segment_frames, max_memory=memory
    )
    work = SegmentedEncode(
        source, plan, basis, executor or InProcessExecutor(), level, progress, shared_basis
    )
    target: float | None = None
    trials = 0
    if mode == "ranks":
        assert ranks is not None
        quantized, error2 = encode_ranks(work, int(ranks[0]), int(ranks[1]))
        header_target = None
    elif mode == "kg":
        target = 0.1 if target_kg is None else float(target_kg)
        quantized, error2, trials = search_kg(work, target, TRUNCATION_SHARES)
        header_target = target
    else:
        assert target_bpfv is not None
        target = float(target_bpfv)
        quantized, error2 = search_bpfv(work, target)
        header_target = None
    data, sizes = pack_segmented(work, quantized, error2, header_target)
    choice = quantized.choice
    largest_i = choice.shared or max(i for i, _ in choice.ranks)
    report = EncodeReport(
        mode=mode,
        target=target,
        select="exact",
        ranks=(largest_i, max(k for _, k in choice.ranks)),
        kg=work.kg(error2),
        truncation_kg=work.kg(choice.truncation2),
        exact_ranks=None,
        bound_ranks=None,
        total_bytes=len(data),
        section_bytes=sizes,
        vertices=work.vertex_count,
        frames=work.frame_count,
        seconds=time.perf_counter() - start,
        trials=trials + work.passes,
        segments=len(work.models),
        basis=basis,
    )
    return EncodeResult(data, report)


def shared_basis_of(data: bytes | memoryview) -> SharedBasis:
    """The shared U1 of a segmented file (its U1 section, as stored), to encode other frames
    with (``encode_frames(..., shared_basis=...)``). ``ValueError`` for a file without one."""
    container = parse_container(data)
    section = container.section("U1")
    if not container.segmented or section is None:
        raise ValueError("the file has no shared basis: it is not a segmented file of shared U1")
    return SharedBasis(dict(section.params), bytes(container.payload(data, section)))


#: Of each segment's budget, the share a fitted basis may leave as truncation error, and the
#: share its own quantization may add (the rest is the segment's own U3, core and centroids).
FIT_TRUNCATION_SHARE, FIT_BASIS_NOISE_SHARE = 0.6, 0.15


def fit_basis(
    source: FrameSource,
    *,
    target_kg: float,
    segment_frames: int,
    max_memory: int | None = None,
    level: int = streams.DEFAULT_LEVEL,
) -> SharedBasis:
    """A shared U1 with which every segment of ``segment_frames`` frames of ``source`` can meet
    ``target_kg`` on its own (a zarr chunk each, say), so that each can be encoded alone with
    ``encode_frames(..., shared_basis=...)`` and still share the basis's bytes.

    Its columns are the fewest that leave every segment's truncation within
    :data:`FIT_TRUNCATION_SHARE` of its own squared budget (t/100)^2 ||X_s - E(X_s)||^2, and
    its steps make its quantization add at most :data:`FIT_BASIS_NOISE_SHARE` of it (about D/12
    per value, reaching segment s in proportion to its share of each column's core energy).
    """
    memory = default_max_memory() if max_memory is None else max_memory
    plan = plan_segments(
        source.frame_count, source.vertex_count, segment_frames=segment_frames, max_memory=memory
    )
    work = SegmentedEncode(source, plan, BASIS_SHARED, InProcessExecutor(), level, None)
    budgets = [(target_kg / 100.0) ** 2 * model.energy for model in work.models]
    largest = min(model.error_table.shape[0] for model in work.models) - 1
    columns = next(
        (
            i
            for i in range(1, largest + 1)
            if all(
                model.error_table[i, -1] <= FIT_TRUNCATION_SHARE * budget
                for model, budget in zip(work.models, budgets, strict=True)
            )
        ),
        largest,
    )
    energy = [np.square(m.core[:columns]).sum(axis=(1, 2)) for m in work.models]
    column_energy = np.maximum(sum(energy), 1e-300)
    # segment s's squared error from the basis's noise is about (D/12) K sum_a (its share of
    # column a's energy): D is the largest that keeps every segment within its share
    step = min(
        FIT_BASIS_NOISE_SHARE
        * budget
        * 12.0
        / (work.vertex_count * float((e / column_energy).sum()))
        for e, budget in zip(energy, budgets, strict=True)
    )
    matrix = qmat.quantize(
        work.shared_q @ work.models[0].rotation[:, :columns],
        column_steps(math.sqrt(step), np.sqrt(column_energy)),
    )
    params, payload = qmat.encode_matrix(matrix, work.mesh, level=level)
    return SharedBasis(params, payload)


__all__ = ["SharedBasis", "encode_frames", "fit_basis", "shared_basis_of"]
