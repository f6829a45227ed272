"""Meeting a target with segments: the ranks and the quantization parameter D (the segmented
counterpart of :mod:`.search`).

:func:`search_kg` tries a few shares of the error budget for truncation, each with the cheapest
ranks that fit it (:func:`.segment_model.cheapest_ranks`), and keeps the smallest file;
:func:`meet` finds D on the model of the decoded error, then measures the error on the input
(a pass) and tightens D until the measured error meets the target. :func:`search_bpfv` bisects
the error for a size, on the model.
"""

from __future__ import annotations

import math

from ..errors import UnreachableTargetError
from ..format import streams
from ..format.segments import BASIS_SHARED
from .search import QUICK_SHARES, SAFETY
from .segment_file import segment_sections
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
    """The smallest KG error whose file fits: bisection on log KG over the model (sizes at
    the fast level), then the measuring pass, which only makes the file smaller."""
    budget = target_bpfv * work.frame_count * work.vertex_count / 8.0
    # the header beside the payloads: the section table and the segment index
    overhead = 400 + 300 * len(work.ranges)

    def size(kg: float) -> tuple[int, RankChoice, float] | None:
        limit2 = (kg / 100.0) ** 2 * work.denominator2
        best = None
        for share in QUICK_SHARES:
            choice = cheapest_ranks(
                work.models, work.basis_vertices, work.basis == BASIS_SHARED, share * limit2
            )
            room = 0.0 if choice is None else limit2 - choice.truncation2 - work.floor_error2
            if choice is None or room <= 0:
                continue
            quantized, _ = meet_in_model(work, choice, work.initial_step(choice, room), limit2)
            bytes_ = trial_bytes(work, quantized) + overhead
            if best is None or bytes_ < best[0]:
                best = (bytes_, choice, quantized.step)
        return best

    low, high = math.log(1e-4), math.log(100.0)
    coarsest = size(100.0)
    if coarsest is None or coarsest[0] > budget:
        pixels = work.frame_count * work.vertex_count
        needs = "" if coarsest is None else f" needs {coarsest[0] * 8 / pixels:.3f} bpfv"
        raise UnreachableTargetError(
            f"no file fits {target_bpfv} bpfv: even the coarsest one{needs} (the faces "
            f"alone take {len(work.face_section[1]) * 8 / pixels:.3f})"
        )
    for _ in range(14):
        middle = 0.5 * (low + high)
        found = size(math.exp(middle))
        if found is not None and found[0] <= budget:
            high = middle
        else:
            low = middle
    kg = math.exp(high)
    limit2 = (kg * (1.0 - SAFETY) / 100.0) ** 2 * work.denominator2
    found = size(kg)
    assert found is not None
    return meet(work, found[1], found[2], limit2)
