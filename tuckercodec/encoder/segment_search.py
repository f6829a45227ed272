"""Meeting a target with segments: the ranks and the quantization parameter D (the segmented
counterpart of :mod:`.search`).

:func:`search_kg` tries a few shares of the error budget for truncation, each with the cheapest
ranks that fit it (:func:`.segment_model.cheapest_ranks`), and keeps the smallest file;
:func:`meet` finds D on the model of the decoded error, then measures the error on the input
(a pass) and tightens D until the measured error meets the target. :func:`search_bpfv` fills
a size budget as the unsegmented search does: candidates on the model, D on the real file.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from ..errors import UnreachableTargetError
from ..format import streams
from ..format.segments import BASIS_SHARED
from .search import (
    FILL_LEAST,
    FINAL_FILLS,
    HIGHEST_KG,
    KG_SLOPE_PER_VALUE,
    LOWEST_KG,
    SAFETY,
    SIZE_SHARES,
    SLOPE_PER_VALUE,
    TRIAL_FILLS,
    TRIAL_RATIO,
    TRIAL_WINDOW,
    Filled,
    fill,
    fill_erratic,
)
from .segment_file import pack_segmented, segment_sections
from .segment_model import RankChoice, cheapest_ranks, fixed_ranks
from .segment_work import Quantized, SegmentedEncode

#: Truncation shares tried when none of the usual ones fits: a basis that leaves little room
#: (a given one, or a small sketch) spends most of the budget on truncation.
LATE_SHARES = (0.8, 0.9, 0.95, 0.98)
#: Measuring passes before giving up on the target (each one tightens D to what it measured).
MAX_MEASURING_PASSES = 6
#: Quantization may add this much to a fixed-ranks truncation's squared error (as unsegmented).
RANKS_QUANTIZATION_SHARE = 1.05**2 - 1


def trial_bytes(work: SegmentedEncode, quantized: Quantized) -> int:
    """The payload bytes at the fast zstd level: to compare trials, not the final size."""
    return sum(len(p) for _, p in segment_sections(work, quantized, streams.SEARCH_LEVEL))


def meet_in_model(
    work: SegmentedEncode, choice: RankChoice, step: float, limit2: float
) -> tuple[Quantized, float]:
    """D as loose as the model allows with the decoded error within ``limit2`` (the same
    steps as the unsegmented :func:`.search.meet`, on the model's error)."""
    fixed2 = choice.truncation2 + work.floor_error2
    best: tuple[Quantized, float] | None = None
    loosened = False
    for _ in range(40):
        quantized = work.quantize(choice, step)
        error2 = work.model_error2(quantized)
        added, room = max(error2 - fixed2, 1e-300), limit2 - fixed2
        if error2 <= limit2:
            best = (quantized, error2)
            if loosened or added >= 0.97 * room:
                return best
            loosened = True
            step *= min(1.5, 0.99 * room / added)
        elif best is not None:
            return best
        else:
            step *= min(0.95, max(0.25, 0.97 * room / added))
    raise UnreachableTargetError(  # pragma: no cover
        "could not meet the error target with the segments' ranks"
    )


def meet(
    work: SegmentedEncode, choice: RankChoice, step: float, limit2: float
) -> tuple[Quantized, float]:
    """The model's D, then passes over the input until the measured error is within
    ``limit2``: each pass that finds it above tightens the model's limit by the excess."""
    model_limit2 = limit2
    for _ in range(MAX_MEASURING_PASSES):
        quantized, modelled2 = meet_in_model(work, choice, step, model_limit2)
        measured2 = work.measured_error2(quantized)
        if measured2 <= limit2:
            return quantized, measured2
        work.say(
            f"measured KG {work.kg(measured2):.6g} above the target: finer steps, and another pass"
        )
        model_limit2 -= 1.01 * (measured2 - modelled2) + 1e-12 * limit2
        step = quantized.step * 0.9
        if model_limit2 <= choice.truncation2 + work.floor_error2:
            break
    raise UnreachableTargetError(
        "the segmented encoder could not meet the error target: the sketch misses too much "
        "of the sequence (ask for a larger error, or longer segments)"
    )


def search_kg(
    work: SegmentedEncode, target_kg: float, shares: tuple[float, ...]
) -> tuple[Quantized, float, int]:
    limit2 = (target_kg * (1.0 - SAFETY) / 100.0) ** 2 * work.denominator2
    if work.floor_error2 >= limit2:
        raise UnreachableTargetError(
            "the sequence lies too far from the origin for this error target: its centroids "
            "are stored as 32-bit multiples of a step, and the finest step that fits already "
            f"costs a KG error of {work.kg(work.floor_error2):.3g}"
        )
    trials: list[tuple[int, RankChoice, float]] = []
    seen: set[tuple[int, tuple[tuple[int, int], ...]]] = set()
    shared = work.basis == BASIS_SHARED
    for share in shares:
        choice = cheapest_ranks(work.models, work.basis_vertices, shared, share * limit2)
        if choice is None or (choice.shared, choice.ranks) in seen:
            continue
        seen.add((choice.shared, choice.ranks))
        room = limit2 - choice.truncation2 - work.floor_error2
        if room <= 0:
            continue
        step = work.initial_step(choice, room)
        trials.append((trial_bytes(work, work.quantize(choice, step)), choice, step))
    if not trials and shares != LATE_SHARES:  # most of the budget goes to the truncation
        return search_kg(work, target_kg, LATE_SHARES)
    if not trials:
        largest = fixed_ranks(work.models, shared, work.vertex_count, work.frame_count)
        if largest.truncation2 + work.floor_error2 >= limit2:
            resolved = (
                "the given basis"
                if work.fixed_basis is not None
                else f"the sketch of {work.plan.sketch_columns} columns (what the memory "
                f"allowed for {work.vertex_count} vertices)"
            )
            raise UnreachableTargetError(
                f"a KG error of {target_kg:g} is below what {resolved} resolves: KG "
                f"{work.kg(largest.truncation2):.3g} at its largest ranks. Allow more memory "
                "(max_memory, --max-memory) or ask for a larger error"
            )
        room = limit2 - largest.truncation2 - work.floor_error2
        trials.append((0, largest, work.initial_step(largest, room)))
    _, choice, step = min(trials, key=lambda trial: trial[0])
    quantized, error2 = meet(work, choice, step, limit2)
    return quantized, error2, len(trials)


def encode_ranks(work: SegmentedEncode, i: int, k: int) -> tuple[Quantized, float]:
    choice = fixed_ranks(work.models, work.basis == BASIS_SHARED, i, k)
    floor2 = (1e-4 / 100.0) ** 2 * work.denominator2
    budget2 = max(RANKS_QUANTIZATION_SHARE * choice.truncation2, floor2, 1.01 * work.floor_error2)
    limit2 = choice.truncation2 + budget2
    return meet(work, choice, work.initial_step(choice, budget2), limit2)


def search_bpfv(work: SegmentedEncode, target_bpfv: float) -> tuple[Quantized, float]:
    """The smallest error found whose whole file fits ``target_bpfv`` (as the unsegmented
    :func:`.search.search_bpfv`): a first KG error whose trial file fills the budget, then the
    ranks for shares of it (:data:`.search.SIZE_SHARES`), each with the D whose trial file
    fills it and ranked by the model's error there, then the winner's D filled on the real
    file (the final level, every section and the header), and one pass to measure the error
    the header states."""
    pixels = work.frame_count * work.vertex_count
    budget = target_bpfv * pixels / 8.0
    aim = 0.5 * (FILL_LEAST + 1.0) * budget
    shared = work.basis == BASIS_SHARED
    fixed = len(work.face_section[1]) + (
        0 if work.name_section is None else len(work.name_section[1])
    )
    if work.fixed_basis is not None:
        fixed += len(work.fixed_basis.payload)
    # the header beside the payloads: the section table and the segment index
    overhead = 400 + 300 * len(work.ranges)
    lowest2 = (LOWEST_KG / 100.0) ** 2 * work.denominator2

    def trial_sizes(choice: RankChoice) -> Callable[[float], tuple[float, Quantized | None]]:
        def size_of(step: float) -> tuple[float, Quantized | None]:
            try:
                quantized = work.quantize(choice, step)
                variable = trial_bytes(work, quantized) - fixed
            except (UnreachableTargetError, ValueError):  # D too small for the format
                return math.inf, None
            return overhead + fixed + TRIAL_RATIO * variable, quantized

        return size_of

    def limits(choice: RankChoice) -> tuple[float, float]:
        top2 = (HIGHEST_KG / 10.0) ** 2 * work.denominator2
        return work.initial_step(choice, 0.01 * lowest2), work.initial_step(choice, top2)

    def ranks_for(kg: float, share: float) -> RankChoice | None:
        limit2 = (kg / 100.0) ** 2 * work.denominator2
        return cheapest_ranks(work.models, work.basis_vertices, shared, share * limit2)

    def kg_size(kg: float) -> tuple[float, float]:
        choice = ranks_for(kg, 0.3)
        if choice is None:
            return math.inf, kg
        room = max((kg / 100.0) ** 2 * work.denominator2 * 0.7 - work.floor_error2, lowest2)
        return trial_sizes(choice)(work.initial_step(choice, room))[0], kg

    first, _ = fill(
        kg_size,
        1.0,
        KG_SLOPE_PER_VALUE * work.vertex_count * work.frame_count,
        (0.8 * aim, aim),
        (LOWEST_KG, HIGHEST_KG),
        8,
    )
    if first is None:
        coarsest = kg_size(HIGHEST_KG)[0]
        needs = (
            "" if not math.isfinite(coarsest) else f" needs about {coarsest * 8 / pixels:.3f} bpfv"
        )
        raise UnreachableTargetError(
            f"no file fits {target_bpfv} bpfv: even the coarsest one{needs} (the faces "
            f"alone take {len(work.face_section[1]) * 8 / pixels:.3f})"
        )
    kg = first.item
    best: tuple[float, RankChoice, Filled[Quantized | None]] | None = None
    seen: set[tuple[int, tuple[tuple[int, int], ...]]] = set()
    for share in SIZE_SHARES:
        choice = ranks_for(kg, share)
        if choice is None or (choice.shared, choice.ranks) in seen:
            continue
        seen.add((choice.shared, choice.ranks))
        fixed2 = choice.truncation2 + work.floor_error2
        if best is not None and fixed2 >= best[0]:
            continue  # its truncation alone loses
        room = max((kg / 100.0) ** 2 * work.denominator2 - fixed2, 0.1 * fixed2, lowest2)
        filled, _ = fill(
            trial_sizes(choice),
            work.initial_step(choice, room),
            SLOPE_PER_VALUE * work.stored_values(choice),
            (aim * (1.0 - TRIAL_WINDOW), aim),
            limits(choice),
            TRIAL_FILLS,
        )
        if filled is None or filled.item is None:
            continue
        quantization2 = work.model_error2(filled.item) - fixed2
        quantization2 *= math.exp((aim - filled.size) / filled.slope)  # at the aim
        error2 = fixed2 + max(quantization2, 0.0)
        if best is None or error2 < best[0]:
            best = (error2, choice, filled)
    if best is None:
        raise UnreachableTargetError(f"no file fits {target_bpfv} bpfv")
    estimate2, choice, trial = best

    def real_size(step: float) -> tuple[float, Quantized | None]:
        try:
            quantized = work.quantize(choice, step)
        except (UnreachableTargetError, ValueError):
            return math.inf, None
        return len(pack_segmented(work, quantized, estimate2, None)[0]), quantized

    filled, _ = fill_erratic(
        real_size,
        (trial.step, aim, trial.slope),
        (FILL_LEAST * budget, budget),
        limits(choice),
        FINAL_FILLS,
    )
    if filled is None or filled.item is None:
        raise UnreachableTargetError(f"no file fits {target_bpfv} bpfv")
    # the header holds the measured error, a float: the file keeps its size
    return filled.item, work.measured_error2(filled.item)
