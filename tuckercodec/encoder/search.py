"""Meeting a target: the ranks and the quantization parameter D for an error or a size.

Longer than most modules because the size target's search lives beside the error target's
it builds on: its budget fillers (:func:`fill`, :func:`fill_erratic`) and its candidates.

:func:`search_kg` tries a few splits of the error budget between truncation and quantization
and keeps the smallest packed file; :func:`meet` then adjusts D until the decoded error is at
most the target; :func:`search_bpfv` ranks candidate truncations by the error they reach when
their D fills the size budget (trial sizes), then fills the budget with the winner's D on the
real file. The package docstring (:mod:`tuckercodec.encoder`) gives the method.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

from ..analysis import Selection
from ..errors import UnreachableTargetError
from ..format import streams
from ..format.reconstruction import factor_value_count
from ..rate import bpfv as bits_per_frame_vertex
from . import rdo
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
        # trials only rank truncations: nearest rounding, RDO is for the final meet()
        trials[(i, k)] = (work.trial_bytes(work.quantize(i, k, step, rdo.NEAREST)), step)
    if not trials:  # the target is within rounding of zero error
        r1, r3 = work.analysis.max_ranks
        trials[(r1, r3)] = (0, initial_step(work, r1, r3, max(limit2, 1e-300)))
    (i, k), (_, step) = min(trials.items(), key=lambda item: item[1][0])
    quantized, error2, measured = meet(work, i, k, step, limit2)
    return quantized, error2, len(trials) + measured


# ------------------------------------------------------------------------------------------
# a size target

#: A size target's file lies between FILL_LEAST and 1 times the budget (issue 13).
#: Each fill aims at the middle of its window: the packed size is only roughly monotone in D.
FILL_LEAST = 0.98
#: Trial sizes are filled to within this fraction below their aim, so that candidates compare
#: at nearly one size (their errors are then corrected to exactly that size).
TRIAL_WINDOW = 0.006
#: Sizes measured to fill one budget at one choice of ranks: trial sizes, then real files.
TRIAL_FILLS = 6
FINAL_FILLS = 6
#: The sections whose size D sets; the others (faces, names) are coded once.
QUANTIZED_SECTIONS = ("CENT", "U3", "CORE", "U1")
#: Final bytes of those sections per trial byte (level 19 with rate-distortion rounding, over
#: the trials' fast level with nearest rounding), about as measured on the shared sequences. It
#: only sets the trials' aim: the final fill measures real files.
TRIAL_RATIO = 0.9
#: First guesses of the size's slope, in bytes per stored number per unit of ln D (about half
#: a bit per doubling of D at high rates) and per unit of ln KG (a bit per halving).
SLOPE_PER_VALUE = -0.06
KG_SLOPE_PER_VALUE = -0.15
#: Shares of the squared error given to truncation among the candidates of a size target.
SIZE_SHARES = (0.1, 0.2, 0.3, 0.45, 0.6)
#: Rounds of moves to neighbouring ranks (i and k apart, by a tenth, then halving).
NEIGHBOUR_ROUNDS = 1
#: The smallest KG error a size target asks for (a larger budget is not filled).
LOWEST_KG = 1e-4
#: The largest KG error a size target tries (above it, the file is as coarse as it gets).
HIGHEST_KG = 100.0

Item = TypeVar("Item")


@dataclass
class Filled(Generic[Item]):
    """A D whose size fits: the size, what was sized, and the size's slope in ln D there."""

    step: float
    size: float
    item: Item
    slope: float


def fill(
    size_of: Callable[[float], tuple[float, Item]],
    step: float,
    slope: float,
    window: tuple[float, float],
    limits: tuple[float, float],
    tries: int,
) -> tuple[Filled[Item] | None, int]:
    """The smallest D found whose size is at most ``window[1]``, and the sizes measured.

    Secant steps in ln D aimed at the window's middle: from ``slope`` (bytes per unit of ln D)
    until two sizes measure it, then between the nearest sizes either side of the window once
    both are known. Stops at the first size within the window, after ``tries`` sizes, or when
    the size stops being monotone at the resolution reached. D stays within ``limits``; a size
    of infinity means D is too small for the format. ``None`` if no D tried fits.
    """
    least, most = window
    aim = 0.5 * (least + most)
    low_limit, high_limit = (math.log(x) for x in limits)
    prior = slope
    points: list[tuple[float, float]] = []
    fits: tuple[float, float, Item] | None = None  # ln D, size, item: the smallest D that fits
    over: tuple[float, float] | None = None  # (ln D, size): the largest D found too large
    at = min(max(math.log(step), low_limit), high_limit)
    tried = 0
    while tried < tries:
        tried += 1
        size, item = size_of(math.exp(at))
        if math.isfinite(size):
            if points and at != points[-1][0]:
                measured = (size - points[-1][1]) / (at - points[-1][0])
                if measured < 0:
                    slope = measured
            points.append((at, size))
        if size <= most:
            if fits is None or at < fits[0]:
                fits = (at, size, item)
            if size >= least:
                break
        elif over is None or at > over[0]:
            over = (at, size)
        if fits is not None and over is not None:
            low, high = over[0], fits[0]
            if high - low < 1e-6:  # not monotone here: keep the smallest D that fits
                break
            if math.isfinite(over[1]):
                share = (over[1] - aim) / (over[1] - fits[1])
                at = low + min(0.9, max(0.1, share)) * (high - low)
            else:
                at = 0.5 * (low + high)
        else:
            move = (aim - size) / slope if math.isfinite(size) else 2.0
            moved = min(max(at + min(3.0, max(-3.0, move)), low_limit), high_limit)
            if moved == at:  # against a limit
                break
            at = moved
    if fits is None:
        return None, tried
    return Filled(math.exp(fits[0]), fits[1], fits[2], _slope(points, fits[0], prior)), tried


def _slope(points: list[tuple[float, float]], at: float, prior: float) -> float:
    """The size's slope in ln D near ``at``: the least-squares line's through the points
    (ln D, size) within 0.7 of it, or else through all of them, when they span at least 0.05
    (sizes a hair apart in D differ by noise alone), fitted again without the points more
    than 3 % below the line (lucky ones), and kept within a factor 3 of ``prior``."""
    for chosen in (_near(points, at), points):
        xs = np.array([x for x, _ in chosen])
        ys = np.array([y for _, y in chosen])
        if len(chosen) < 2 or np.ptp(xs) < 0.05:
            continue
        line = np.polyfit(xs, ys, 1)
        kept = ys >= 0.97 * np.polyval(line, xs)
        if kept.sum() >= 2 and np.ptp(xs[kept]) >= 0.05:
            line = np.polyfit(xs[kept], ys[kept], 1)
        fitted = float(line[0])
        return prior if fitted >= 0 else min(max(fitted, 3.0 * prior), prior / 3.0)
    return prior


def _near(points: list[tuple[float, float]], at: float) -> list[tuple[float, float]]:
    return [point for point in points if abs(point[0] - at) <= 0.7]


def fill_erratic(
    size_of: Callable[[float], tuple[float, Item]],
    model: tuple[float, float, float],
    window: tuple[float, float],
    limits: tuple[float, float],
    tries: int,
) -> tuple[Filled[Item] | None, int]:
    """As :func:`fill`, for a size that is erratic in D: the smallest D found whose size is
    at most ``window[1]`` (the smallest error: a lucky D may fit below the window), stopping
    at the first size within the window.

    zstd's strongest levels jump by several per cent between nearly equal inputs (samba's U1
    at 4 bpfv packs at level 19 to about 0.92 of its level-3 size, or, for about one D in
    two, to 0.86), so each D is aimed at a line above the sizes measured: the slope of their
    least-squares line once they span enough of ln D (until then ``model``'s, the trial
    sizes' (D, size, slope per unit of ln D)), through the highest of them. A lucky D, which
    packs smaller, then leaves the file short of the window, and the next D, aimed at the same
    line, draws again (a D already measured is moved by a hair).
    """
    least, most = window
    aim = 0.5 * (least + most)
    low, high = (math.log(x) for x in limits)
    prior = model[2]
    points: list[tuple[float, float]] = []
    fits: Filled[Item] | None = None
    at = math.log(model[0]) + (aim - model[1]) / prior
    for tried in range(1, tries + 1):
        at = min(max(at, low), high)
        while any(abs(at - other) < 1e-4 for other, _ in points):
            at -= 2e-3
        size, item = size_of(math.exp(at))
        if size <= most:
            if fits is None or at < math.log(fits.step):
                fits = Filled(math.exp(at), size, item, prior)
            if size >= least:
                return fits, tried
        if not math.isfinite(size):  # D too small for the format
            at += 1.0
            continue
        points.append((at, size))
        slope = _slope(points, at, prior)
        top = max(y - slope * x for x, y in _near(points, at))
        at = (aim - top) / slope
    return fits, tries


@dataclass
class Candidate:
    """Ranks whose trial size fills the aim at D = ``step``, with the error estimated there."""

    i: int
    k: int
    step: float
    slope: float
    error2: float


def estimated_error2(work: Workspace, quantized: Quantized) -> float:
    """The decoded squared error, from the truncation's and each factor's rounding errors
    weighted as the reconstruction weighs them (U1 and U3 orthonormal; the cross terms,
    averaging out, left out). Cheap next to reconstructing every frame; ranks candidates."""
    i, k = quantized.i, quantized.k
    u1, u3, core = work.factors(i, k)
    rows = np.square(core).sum(axis=(1, 2))
    columns = np.square(core).sum(axis=(0, 1))
    error2 = work.truncation_error2(i, k)
    error2 += float(np.square(quantized.u1.values() - u1).sum(axis=0) @ rows)
    error2 += float(np.square(quantized.u3.values() - u3).sum(axis=0) @ columns)
    error2 += float(np.square(quantized.core.values().reshape(-1) - core.reshape(-1)).sum())
    centroids = quantized.centroids.values() - work.analysis.centroids
    return error2 + work.vertex_count * float(np.square(centroids).sum())


def search_bpfv(
    work: Workspace, target_bpfv: float, select: Selection
) -> tuple[Quantized, float, int]:
    """The smallest KG error found whose whole file fits ``target_bpfv``, filling at least
    :data:`FILL_LEAST` of it where the budget allows.

    1. A first KG error whose trial file (the cheapest ranks for a third of it, D from the
       noise model; the fast zstd level, nearest rounding, scaled by :data:`TRIAL_RATIO`)
       fills the budget.
    2. Candidate ranks, the cheapest for shares of that error (:data:`SIZE_SHARES`), then
       their neighbours: each gets the D whose trial file fills the budget, and the
       estimated error there (:func:`estimated_error2`); the smallest wins.
    3. The winner's D is filled on the real file: the final zstd level, rate-distortion
       rounding, every section and the header. The file never exceeds the budget.
    """
    pixels = work.frame_count * work.vertex_count
    budget = target_bpfv * pixels / 8.0
    aim = 0.5 * (FILL_LEAST + 1.0) * budget
    trial_window = (aim * (1.0 - TRIAL_WINDOW), aim)
    lowest2 = (LOWEST_KG / 100.0) ** 2 * work.denominator2
    floor2 = work.centroid_floor_error2
    counted = 0

    def trial_sizes(i: int, k: int) -> Callable[[float], tuple[float, Quantized | None]]:
        def size_of(step: float) -> tuple[float, Quantized | None]:
            try:
                quantized = work.quantize(i, k, step, rdo.NEAREST)
            except (UnreachableTargetError, ValueError):  # D too small for the format
                return math.inf, None
            data, sizes = work.pack(quantized, 0.0, None, streams.SEARCH_LEVEL)
            variable = sum(sizes.get(name, 0) for name in QUANTIZED_SECTIONS)
            return len(data) - (1.0 - TRIAL_RATIO) * variable, quantized

        return size_of

    def step_limits(i: int, k: int) -> tuple[float, float]:
        return (
            initial_step(work, i, k, 0.01 * lowest2),
            initial_step(work, i, k, (HIGHEST_KG / 10.0) ** 2 * work.denominator2),
        )

    # 1. a first error: the trial file of the cheapest ranks for a third of it
    def kg_size(log_kg: float) -> tuple[float, float]:
        kg = math.exp(log_kg)
        choice = work.analysis.cheapest(kg * math.sqrt(0.3), select=select)
        room = max((kg / 100.0) ** 2 * work.denominator2 * 0.7 - floor2, 1e-3 * lowest2)
        size, _ = trial_sizes(choice.i, choice.k)(initial_step(work, choice.i, choice.k, room))
        return size, kg

    # fill() works on exp(ln KG): KG plays D's part, the size falls as it grows
    r1, r3 = work.analysis.max_ranks
    first, tried = fill(
        lambda kg: kg_size(math.log(kg)),
        1.0,
        KG_SLOPE_PER_VALUE * factor_value_count(work.vertex_count, work.frame_count, r1, r3),
        (0.8 * aim, aim),
        (LOWEST_KG, HIGHEST_KG),
        8,
    )
    counted += tried
    if first is None:  # even the coarsest trial is too large: the real file decides
        return _coarsest(work, target_bpfv, budget, select, counted)
    kg = first.item

    # 2. candidate ranks, each with the D that fills the trial aim
    memo: dict[tuple[int, int], Candidate | None] = {}
    best: Candidate | None = None

    def evaluate(i: int, k: int) -> Candidate | None:
        nonlocal best, counted
        if (i, k) in memo:
            return memo[(i, k)]
        fixed2 = work.truncation_error2(i, k) + floor2
        memo[(i, k)] = None
        if best is not None and fixed2 >= best.error2:
            return None  # its truncation alone loses
        room = max((kg / 100.0) ** 2 * work.denominator2 - fixed2, 0.1 * fixed2, lowest2)
        values = factor_value_count(work.vertex_count, work.frame_count, i, k)
        filled, tried = fill(
            trial_sizes(i, k),
            initial_step(work, i, k, room),
            SLOPE_PER_VALUE * values,
            trial_window,
            step_limits(i, k),
            TRIAL_FILLS,
        )
        counted += tried
        if filled is None or filled.item is None:
            return None
        quantization2 = estimated_error2(work, filled.item) - fixed2
        # corrected to the aim: the quantization error grows about as D
        quantization2 *= math.exp((aim - filled.size) / filled.slope)
        candidate = Candidate(i, k, filled.step, filled.slope, fixed2 + max(quantization2, 0.0))
        memo[(i, k)] = candidate
        if best is None or candidate.error2 < best.error2:
            best = candidate
        return candidate

    for share in SIZE_SHARES:
        choice = work.analysis.cheapest(kg * math.sqrt(share), select=select)
        evaluate(choice.i, choice.k)
    if best is None:
        return _coarsest(work, target_bpfv, budget, select, counted)
    work.factors(best.i, best.k)
    fraction = 0.1
    for _ in range(NEIGHBOUR_ROUNDS):
        centre = best
        di, dk = max(1, round(fraction * centre.i)), max(1, round(fraction * centre.k))
        for i, k in (
            (centre.i + di, centre.k),
            (centre.i - di, centre.k),
            (centre.i, centre.k + dk),
            (centre.i, centre.k - dk),
        ):
            if 1 <= i <= r1 and 1 <= k <= r3:
                evaluate(i, k)
        if best is centre:
            fraction *= 0.5
    assert best is not None

    # 3. the winner's D filled on the real file
    i, k = best.i, best.k
    estimate2 = best.error2

    def real_size(step: float) -> tuple[float, Quantized | None]:
        try:
            quantized = work.quantize(i, k, step)
        except (UnreachableTargetError, ValueError):
            return math.inf, None
        return len(work.pack(quantized, estimate2, None)[0]), quantized

    filled, tried = fill_erratic(
        real_size,
        (best.step, aim, best.slope),
        (FILL_LEAST * budget, budget),
        step_limits(i, k),
        FINAL_FILLS,
    )
    counted += tried
    if filled is None or filled.item is None:
        return _coarsest(work, target_bpfv, budget, select, counted)
    quantized = filled.item
    error2 = work.decoded_error2(quantized)
    # the header holds the measured error: a float, so the same size (checked cheaply)
    if (
        len(work.pack(quantized, error2, None, streams.SEARCH_LEVEL)[0])
        != len(work.pack(quantized, estimate2, None, streams.SEARCH_LEVEL)[0])
        and len(work.pack(quantized, error2, None)[0]) > budget
    ):  # pragma: no cover
        return _coarsest(work, target_bpfv, budget, select, counted)
    return quantized, error2, counted


def _coarsest(
    work: Workspace, target_bpfv: float, budget: float, select: Selection, counted: int
) -> tuple[Quantized, float, int]:
    """The file at KG 100 if it fits the budget; otherwise no file does."""
    quantized, error2, trials = search_kg(work, HIGHEST_KG, select, QUICK_SHARES[:1])
    size = len(work.pack(quantized, error2, None)[0])
    if size <= budget:
        return quantized, error2, counted + trials
    faces_bpfv = bits_per_frame_vertex(
        len(work.face_section[1]), work.frame_count, work.vertex_count
    )
    raise UnreachableTargetError(
        f"no file fits {target_bpfv} bpfv: even the coarsest one needs "
        f"{bits_per_frame_vertex(size, work.frame_count, work.vertex_count):.3f} bpfv "
        f"(the faces alone take {faces_bpfv:.3f})"
    )
