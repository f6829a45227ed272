"""The segmented encoder's memory plan and its sketch: every term of the peak counted within
``max_memory``, and a sketch that grows until it resolves a target the whole encoder meets.

The plan's arithmetic is tested, not a process's resident memory (which depends on the machine
and on what else runs): BENCHMARKS.md gives the peaks measured against it."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from tuckercodec import Decoder, MeshSequence, UnreachableTargetError, encode_with_report
from tuckercodec.encoder import search
from tuckercodec.encoder.plan import (
    BLOCK_COPIES,
    DEFAULT_SKETCH_COLUMNS,
    MAX_BLOCK_FRAMES,
    MEMORY_MARGIN,
    PROCESS_BASELINE,
    parse_size,
    plan_segments,
    planned_memory,
    zstd_bytes,
)
from tuckercodec.encoder.segmented import SegmentedWorkspace
from tuckercodec.format.streams import DEFAULT_LEVEL
from tuckercodec.measures.distortion import kg_error
from tuckercodec.model.sources import SequenceFrames
from tuckercodec.system.parallel import InProcessExecutor

#: (frames, vertices, faces, segment frames, basis own): a mid-size body, a large cloth, and a
#: basis per segment (every segment's Q held at once).
SHAPES = [
    (300, 30_000, 59_980, None, False),
    (1_000, 100_000, 199_960, 250, False),
    (400, 20_000, 40_000, 100, True),
]
LIMITS = ["20GB", "4GB", "1GB", "500MB", "300MB"]


@pytest.mark.parametrize(("frames", "vertices", "faces", "length", "own"), SHAPES)
def test_every_term_of_the_planned_peak_is_within_the_limit(frames, vertices, faces, length, own):
    previous = None
    segments = max(1, frames // (length or 250))
    least = planned_memory(
        vertices, frames, faces, segments=segments, own_basis=own, block_frames=1,
        columns=8, rank=1, level=DEFAULT_LEVEL,
    ).peak / (1 - MEMORY_MARGIN)  # fmt: skip
    for limit in map(parse_size, LIMITS):
        if limit < least:  # below what one frame and the least sketch need: refused
            with pytest.raises(ValueError, match="too small for a segmented encode"):
                plan_segments(frames, vertices, segment_frames=length, max_memory=limit,
                              faces=faces, basis_own=own)  # fmt: skip
            continue
        plan = plan_segments(
            frames, vertices, segment_frames=length, max_memory=limit, faces=faces, basis_own=own
        )
        use = plan.use
        assert use is not None

        # the plan's use is the accounting of its own choices, each term counted
        planned = functools.partial(
            planned_memory,
            vertices,
            frames,
            faces,
            segments=len(plan.bounds),
            own_basis=own,
            block_frames=plan.block_frames,
            columns=plan.sketch_columns,
            level=DEFAULT_LEVEL,
        )
        assert use == planned(rank=plan.max_rank)
        assert use.baseline == PROCESS_BASELINE  # the process itself: numpy, scipy, ...
        assert use.blocks == BLOCK_COPIES * plan.block_frames * vertices * 24
        assert use.sketch >= 2 * plan.sketch_columns * vertices * 8  # the sum and its Q
        assert use.basis >= (plan.sketch_columns + plan.max_rank) * vertices * 8
        assert use.zstd == zstd_bytes(DEFAULT_LEVEL, 4 * vertices * plan.max_rank) > 0
        assert use.faces > use.faces_kept > 0 and use.mesh > 0 and use.model > 0
        for term in vars(use).values():
            assert 0 <= term <= limit
        assert use.peak <= (1 - MEMORY_MARGIN) * limit  # with the margin
        # a wider sketch, a longer block or one more column of U1 would not fit
        if plan.max_rank < plan.sketch_columns:
            assert plan.with_columns(plan.sketch_columns).max_rank == plan.max_rank
            assert planned(rank=plan.max_rank + 1).peak > (1 - MEMORY_MARGIN) * limit
        if previous is not None:  # the limit shrank: nothing grows
            assert plan.block_frames <= previous.block_frames
            assert plan.sketch_columns <= previous.sketch_columns
            assert plan.max_rank <= previous.max_rank
            assert plan.most_columns <= previous.most_columns
        previous = plan
    assert previous is not None and previous.block_frames < MAX_BLOCK_FRAMES


def test_ample_memory_plans_as_before():
    """Where memory does not bind, the plan is the one files were made with: 16-frame blocks,
    a 256-column sketch, every one of its columns allowed (the same bytes)."""
    plan = plan_segments(400, 3030, segment_frames=100, max_memory=parse_size("12GB"), faces=5664)
    assert plan.block_frames == MAX_BLOCK_FRAMES
    assert plan.sketch_columns == plan.max_rank == DEFAULT_SKETCH_COLUMNS
    assert plan.most_columns == 1200 and plan.columns_limited_by == "3F"
    short = plan_segments(60, 3101, segment_frames=16, max_memory=parse_size("12GB"))
    assert short.sketch_columns == short.most_columns == 180  # all of 3F at once
    few = plan_segments(400, 200, segment_frames=100, max_memory=parse_size("12GB"))
    assert few.sketch_columns == few.most_columns == 200 and few.columns_limited_by == "K"


def test_a_limit_below_the_least_is_refused_with_what_is_needed():
    with pytest.raises(ValueError, match=r"too small .* needs at least .* process itself"):
        plan_segments(300, 30_000, segment_frames=None, max_memory=parse_size("100MB"))


@pytest.fixture(scope="module")
def spread() -> MeshSequence:
    """600 vertices whose mode-1 spectrum decays slowly (0.88 per rank): KG 2 needs a U1 of
    about 18 columns, more than a 16-column sketch resolves."""
    rng = np.random.default_rng(7)
    vertices, frames, components = 600, 60, 60
    basis = np.linalg.qr(rng.standard_normal((vertices, components)))[0]
    weights = rng.standard_normal((components, 3, frames))
    spectrum = 0.88 ** np.arange(components)
    positions = np.einsum("kj,j,jxt->tkx", basis, spectrum, weights)
    positions += rng.standard_normal((1, vertices, 3))
    faces = np.array([(i, i + 1, i + 2) for i in range(vertices - 2)])
    return MeshSequence(positions, faces)


def workspace(sequence: MeshSequence, max_memory: int, lines: list[str]) -> SegmentedWorkspace:
    plan = plan_segments(
        sequence.frame_count,
        sequence.vertex_count,
        segment_frames=20,
        max_memory=max_memory,
        faces=len(sequence.faces),
        sketch_columns=16,  # a small first sketch, as 256 columns are for a large sequence
    )
    return SegmentedWorkspace(
        SequenceFrames(sequence), plan, "shared", InProcessExecutor(), DEFAULT_LEVEL, lines.append
    )


def test_the_sketch_grows_until_it_meets_what_the_whole_encoder_meets(spread):
    target = 2.0
    whole = encode_with_report(spread, target_kg=target).report
    assert whole.kg <= target and whole.ranks[0] > 16  # the whole encoder meets it
    lines: list[str] = []
    work = workspace(spread, parse_size("1GB"), lines)
    assert work.plan.sketch_columns == 16 and work.plan.most_columns == 180  # 3F
    quantized, error2, _ = search.search_kg(work, target)
    assert work.plan.sketch_columns > 16
    assert any("sketching again with 32" in line for line in lines)
    data, _ = work.pack(quantized, error2, target)
    assert kg_error(spread.vertices, Decoder(data).positions()) <= target


def test_a_refusal_names_the_memory_when_the_memory_binds(spread):
    vertices, frames, faces = spread.vertex_count, spread.frame_count, len(spread.faces)
    least = planned_memory(
        vertices, frames, faces, segments=3, own_basis=False, block_frames=1, columns=16,
        rank=16, level=DEFAULT_LEVEL,
    )  # fmt: skip
    lines: list[str] = []
    work = workspace(spread, int(least.peak / (1 - MEMORY_MARGIN)), lines)
    assert work.plan.max_rank < 16  # the file's K x i arrays bind before the sketch
    with pytest.raises(UnreachableTargetError, match=r"memory allowed.*Allow more memory"):
        search.search_kg(work, 2.0)
    assert not any("sketching again" in line for line in lines)  # no pass that cannot help
