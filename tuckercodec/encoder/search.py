"""Meeting a target: the ranks and the quantization parameter D for an error or a size.

:func:`search_kg` tries a few splits of the error budget between truncation and quantization
and keeps the smallest packed file; :func:`meet` then adjusts D until the decoded error is at
most the target; :func:`search_bpfv` bisects the error for the smallest one whose file fits a
size. The package docstring (:mod:`tuckercodec.encoder`) gives the method.
"""

from __future__ import annotations

import math

from ..analysis import Selection
from ..errors import UnreachableTargetError
from ..format import streams
from ..format.reconstruction import factor_value_count
from ..rate import bpfv as bits_per_frame_vertex
from .workspace import Quantized, Workspace

#: Shares of the squared error budget given to truncation in the search (the rest is quantization).
TRUNCATION_SHARES = (0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
#: Fewer shares while searching for a size target, where each trial is a whole encode.
QUICK_SHARES = (0.1, 0.3, 0.5)
#: The decoded error must stay this far (relative) below the target, so that a decoder whose
#: BLAS rounds differently (about 1e-15 relative) still meets it.
SAFETY = 1e-9


def initial_step(work: Workspace, i: int, k: int, budget2: float) -> float:
    """D such that the quantization noise, about D/12 per stored number, fills ``budget2``."""
    return 12.0 * budget2 / factor_value_count(work.vertex_count, work.frame_count, i, k)


def meet(
    work: Workspace, i: int, k: int, step: float, limit2: float
) -> tuple[Quantized, float, int]:
    """Adjust D so that the decoded squared error is at most ``limit2``, as loose as it can be.

    Returns the quantization, its decoded squared error and the number of measurements.
    """
    # The error no choice of D removes: the truncation's, and the centroids' at their coarsest
    # usable step (zero unless the sequence lies far from the origin).
    truncation2 = work.truncation_error2(i, k) + work.centroid_floor_error2
    best: tuple[Quantized, float] | None = None
    loosened = False
    for attempt in range(1, 40):
        quantized = work.quantize(i, k, step)
        error2 = work.decoded_error2(quantized)
        added = max(error2 - truncation2, 1e-300)
        room = limit2 - truncation2
        if error2 <= limit2:
            best = (quantized, error2)
            if loosened or added >= 0.97 * room:
                return quantized, error2, attempt
            loosened = True  # once: the noise model is a little pessimistic
            step *= min(1.5, 0.99 * room / added)
        elif best is not None:
            return best[0], best[1], attempt
        else:
            # the noise grows about linearly with D; aim a little inside and never stall
            step *= min(0.95, max(0.25, 0.97 * room / added))
    raise UnreachableTargetError(  # pragma: no cover
        f"could not meet the error target with ranks ({i}, {k})"
    )


def search_kg(
    work: Workspace, target_kg: float, select: Selection, shares: tuple[float, ...]
) -> tuple[Quantized, float, int]:
    """The smallest file found for a target KG error: see the module docstring."""
    limit2 = (target_kg * (1.0 - SAFETY) / 100.0) ** 2 * work.denominator2
    work.check_reachable(limit2)
    trials: dict[tuple[int, int], tuple[int, float]] = {}
    candidates = []
    for share in shares:
        choice = work.analysis.cheapest(target_kg * math.sqrt(share), select=select)
        if (choice.i, choice.k) not in candidates:
            candidates.append((choice.i, choice.k))
    if candidates:  # form the factors once, for the largest ranks, rather than growing them
        work.factors(max(i for i, _ in candidates), max(k for _, k in candidates))
    for i, k in candidates:
        room = limit2 - work.truncation_error2(i, k) - work.centroid_floor_error2
        if room <= 0:
            continue
        step = initial_step(work, i, k, room)
        trials[(i, k)] = (work.trial_bytes(work.quantize(i, k, step)), step)
    if not trials:  # the target is within rounding of zero error
        r1, r3 = work.analysis.max_ranks
        trials[(r1, r3)] = (0, initial_step(work, r1, r3, max(limit2, 1e-300)))
    (i, k), (_, step) = min(trials.items(), key=lambda item: item[1][0])
    quantized, error2, measured = meet(work, i, k, step, limit2)
    return quantized, error2, len(trials) + measured


def search_bpfv(
    work: Workspace, target_bpfv: float, select: Selection
) -> tuple[Quantized, float, int]:
    """The smallest KG error whose file fits ``target_bpfv``: bisection on log KG, sizing the
    trials at the fast zstd level, then the final level checked (and the error loosened a step
    at a time in the rare case that it packs larger)."""
    budget = target_bpfv * work.frame_count * work.vertex_count / 8.0

    def attempt(
        kg: float, shares: tuple[float, ...], level: int | None
    ) -> tuple[Quantized, float, int, int]:
        quantized, error2, trials = search_kg(work, kg, select, shares)
        return quantized, error2, trials, len(work.pack(quantized, error2, None, level)[0])

    trials = 0
    low, high = math.log(1e-4), math.log(100.0)  # KG percent
    best = attempt(100.0, QUICK_SHARES[:1], None)
    trials += best[2]
    if best[3] > budget:
        faces_bpfv = bits_per_frame_vertex(
            len(work.face_section[1]), work.frame_count, work.vertex_count
        )
        raise UnreachableTargetError(
            f"no file fits {target_bpfv} bpfv: even the coarsest one needs "
            f"{bits_per_frame_vertex(best[3], work.frame_count, work.vertex_count):.3f} bpfv "
            f"(the faces alone take {faces_bpfv:.3f})"
        )
    for _ in range(14):  # log KG to within about 1 %
        middle = 0.5 * (low + high)
        try:
            result = attempt(math.exp(middle), QUICK_SHARES, streams.SEARCH_LEVEL)
        except UnreachableTargetError:  # the centroids far from the origin cannot reach it
            low = middle  # behaves as "too large": smaller errors are out of reach too
            continue
        trials += result[2]
        if result[3] <= budget:
            high = middle
        else:
            low = middle
    while high < math.log(100.0):
        result = attempt(math.exp(high), QUICK_SHARES, None)
        trials += result[2]
        if result[3] <= budget:
            return result[0], result[1], trials
        high += 0.02
    return best[0], best[1], trials
