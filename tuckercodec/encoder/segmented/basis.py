"""A shared U1 given rather than found: read from a segmented file, or fitted so that every
segment of a sequence meets a target with it alone (the zarr codec's fitted chunks)."""

from __future__ import annotations

import math

import numpy as np

from ...format import qmat, streams
from ...format.container import parse_container
from ...format.segments import BASIS_SHARED
from ...model.sources import FrameSource
from ...system.memory import memory_allowed
from ...system.parallel import InProcessExecutor
from ..plan import plan_segments
from ..whole import column_steps
from .workspace import SegmentedWorkspace, SharedBasis


def shared_basis_of(data: bytes | memoryview) -> SharedBasis:
    """The shared U1 of a segmented file (its U1 section, as stored), to encode other frames
    with (:func:`tuckercodec.encoder.encode_frames`, ``shared_basis=...``). ``ValueError``
    for a file without one."""
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
    memory = memory_allowed(max_memory)
    plan = plan_segments(
        source.frame_count,
        source.vertex_count,
        segment_frames=segment_frames,
        max_memory=memory,
        faces=len(source.faces),
        level=level,
    )
    work = SegmentedWorkspace(source, plan, BASIS_SHARED, InProcessExecutor(), level, None)
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
    params, payload = qmat.encode_matrix(matrix, work.mesh, level=level, adaptive_coding=True)
    return SharedBasis(params, payload)


__all__ = ["SharedBasis", "fit_basis", "shared_basis_of"]
