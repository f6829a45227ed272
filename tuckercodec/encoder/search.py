"""Meeting a target: the ranks and the quantization parameter D for an error, ranks or a size.

Written once, against the trial protocol of :mod:`.trial`, for a whole sequence in memory
(:class:`~.whole.WholeWorkspace`) and for segments read in passes
(:class:`~.segmented.workspace.SegmentedWorkspace`):

* :func:`search_kg` tries a few splits of the error budget between truncation and quantization
  and keeps the smallest trial file;
* :func:`meet` then adjusts D until the decoded error is at most the target (on the workspace's
  model of the error, then measured, until the measurement meets it);
* :func:`encode_ranks` meets an error a little above fixed ranks' truncation;
* :func:`search_bpfv` ranks candidate truncations by the error they reach when their D fills a
  size budget (trial sizes), then fills the budget with the winner's D on the real file.

The package docstring (:mod:`tuckercodec.encoder`) gives the method. Every function returns the
quantization, its measured squared error and the number of trials and measurements it made.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any, Generic

from ..errors import UnreachableTargetError
from ..measures.rate import bpfv as bits_per_frame_vertex
from .fill import fill, fill_erratic
from .trial import Choice, Quantized, Workspace

Outcome = tuple[Quantized[Any], float, int]

# ------------------------------------------------------------------------------------------
# an error target

#: Shares of the squared error budget given to truncation in the search (the rest is
#: quantization): the cheapest ranks for each are tried, and the smallest trial file wins.
TRUNCATION_SHARES = (0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
#: The decoded error must stay this far (relative) below the target, so that a decoder whose
#: BLAS rounds differently (about 1e-15 relative) still meets it.
SAFETY = 1e-9
#: Adjustments of D in one :func:`meet` before giving up (each at least 5 %; 10 or fewer are
#: usual).
MAX_ADJUSTMENTS = 39
#: meet() is done when quantization fills this much of its room (closer is not worth a trial).
CLOSE_ENOUGH = 0.97
#: The noise model is a little pessimistic: once the error meets the target, D is loosened
#: once, by at most this factor, aiming this far inside the room.
LOOSEN_AT_MOST, LOOSEN_AIM = 1.5, 0.99
#: Above the target, D shrinks in proportion to the excess (the noise grows about linearly with
#: D), aimed a little inside, by at least 2 % (never stalls) and at most 4 times (never
#: overshoots on a noisy first measure).
TIGHTEN_AIM, TIGHTEN_LEAST, TIGHTEN_MOST = 0.985, 0.98, 0.25
#: The noise model's D fills 0.97-1.02 of quantization's room once rounded (rate-distortion
#: rounding included); started this far inside, meet() is usually done on its first
#: quantization instead of its third (above, then too far below, then loosened).
FIRST_AIM = 0.985
#: The valley's neighbours whose trial is within this factor of the valley's are met too
#: (:func:`search_kg`): trials at the first step rank truncations within a few per cent.
FINALIST_MARGIN = 1.03
#: Passes that measure the error on the input before giving up on the target (a modelled error
#: only: each one tightens D by what it measured above the model).
MAX_MEASURING_PASSES = 6
#: With fixed ranks, quantization may add this much to the truncation's squared error (KG +5 %).
RANKS_QUANTIZATION_SHARE = 1.05**2 - 1
#: With fixed ranks that lose nothing, the quantization error aimed for, in KG percent.
RANKS_FLOOR_KG = 1e-4


def meet(
    work: Workspace[Choice], choice: Choice, step: float, limit2: float
) -> tuple[Quantized[Choice], float, int]:
    """Adjust D so that the decoded squared error is at most ``limit2``, as loose as it can be:
    on the workspace's model of the error, then measured; each measurement above the limit
    tightens the model's limit by the excess and tries again."""
    fixed2 = work.truncation_error2(choice) + work.floor_error2
    model_limit2 = limit2 - work.model_margin * max(limit2 - fixed2, 0.0)
    adjustments = 0
    for _ in range(MAX_MEASURING_PASSES):
        quantized, modelled2, tried = _meet_in_model(work, choice, step, model_limit2)
        adjustments += tried
        if work.exact_model:
            return quantized, modelled2, adjustments
        measured2 = work.measured_error2(quantized)
        if measured2 <= limit2:
            return quantized, measured2, adjustments
        work.say(
            f"measured KG {work.kg(measured2):.6g} above the target: finer steps, and another pass"
        )
        model_limit2 -= 1.01 * (measured2 - modelled2) + 1e-12 * limit2
        step = quantized.step * 0.9
        if model_limit2 <= fixed2:
            break
    raise UnreachableTargetError(
        "the encoder could not meet the error target: its model of the error misses too much "
        "of the decoded error (segmented: the sketch misses too much of the sequence; ask for "
        "a larger error, or longer segments)"
    )


def _meet_in_model(
    work: Workspace[Choice], choice: Choice, step: float, limit2: float
) -> tuple[Quantized[Choice], float, int]:
    """D as loose as the model allows with the modelled error within ``limit2``; the
    quantization, its modelled error and the number of trials."""
    # The error no choice of D removes: the truncation's, and the centroids' at their coarsest
    # usable step (zero unless the sequence lies far from the origin).
    fixed2 = work.truncation_error2(choice) + work.floor_error2
    best: tuple[Quantized[Choice], float] | None = None
    loosened = False
    for attempt in range(1, MAX_ADJUSTMENTS + 1):
        quantized = work.quantize(choice, step)
        error2 = work.modelled_error2(quantized)
        added = max(error2 - fixed2, 1e-300)
        room = limit2 - fixed2
        if error2 <= limit2:
            best = (quantized, error2)
            if loosened or added >= CLOSE_ENOUGH * room:
                return quantized, error2, attempt
            loosened = True
            step *= min(LOOSEN_AT_MOST, LOOSEN_AIM * room / added)
        elif best is not None:
            return best[0], best[1], attempt
        else:
            step *= min(TIGHTEN_LEAST, max(TIGHTEN_MOST, TIGHTEN_AIM * room / added))
    raise UnreachableTargetError(  # pragma: no cover
        f"could not meet the error target with the ranks {choice}"
    )


def search_kg(
    work: Workspace[Choice], target_kg: float, shares: tuple[float, ...] = TRUNCATION_SHARES
) -> tuple[Quantized[Choice], float, int]:
    """The smallest file found for a target KG error: see the module docstring."""
    limit2 = (target_kg * (1.0 - SAFETY) / 100.0) ** 2 * work.denominator2
    work.check_reachable(limit2)
    choices = _distinct(work.ranks_for(target_kg, share) for share in shares)
    work.prepare(choices)
    candidates: list[tuple[Choice, float]] = []
    for choice in choices:
        room = limit2 - work.truncation_error2(choice) - work.floor_error2
        if room > 0:
            candidates.append((choice, work.initial_step(choice, room)))
    if not candidates and shares != work.late_shares and work.resolve_finer():
        return search_kg(work, target_kg, shares)  # a closer look at the input: start over
    if not candidates and work.late_shares and shares != work.late_shares:
        return search_kg(work, target_kg, work.late_shares)
    if not candidates:  # the target is within rounding of zero error, or a basis leaves no room
        choice, step = work.largest_choice(limit2, target_kg)
        quantized, error2, adjustments = meet(work, choice, step * FIRST_AIM, limit2)
        return quantized, error2, adjustments
    sizes: dict[int, int] = {}

    def trial_size(index: int) -> int:
        # trials only rank truncations: the cheap quantization, the size from the integers
        if index not in sizes:
            choice, step = candidates[index]
            sizes[index] = work.trial_bytes(work.quantize(choice, step, trial=True))
        return sizes[index]

    valley = _valley(trial_size, len(candidates))
    # A trial is quantized at its first step, before meet() moves D to what the target
    # really allows; how far D moves differs between truncations, so the valley's neighbours
    # whose trials come close are met too, and the smallest met file wins.
    finalists = [valley] + [
        index
        for index in (valley - 1, valley + 1)
        if work.meets_finalists
        and index in sizes
        and sizes[index] <= FINALIST_MARGIN * sizes[valley]
    ]
    best: tuple[int, Quantized[Choice], float] | None = None
    adjustments = 0
    for index in finalists:
        choice, step = candidates[index]
        quantized, error2, tried = meet(work, choice, step * FIRST_AIM, limit2)
        adjustments += tried
        size = work.trial_bytes(quantized)
        if best is None or size < best[0]:
            best = (size, quantized, error2)
    assert best is not None  # the valley itself is always a finalist
    return best[1], best[2], len(sizes) + adjustments


def _valley(size: Callable[[int], int], count: int) -> int:
    """The index of the smallest of ``count`` sizes, found by walking downhill from the
    middle. The trial size over the shares of the budget given to truncation falls, then
    rises (fewer ranks cost less until quantization's room runs out), so the first index
    whose next is no smaller is the least, in three or four trials rather than all eight."""
    here = (count - 1) // 2
    direction = 1 if here + 1 < count and size(here + 1) < size(here) else -1
    while 0 <= here + direction < count and size(here + direction) < size(here):
        here += direction
    return here


def _distinct(choices: Iterable[Choice | None]) -> list[Choice]:
    """The choices in their order, each once, without the ``None`` of a share none fits."""
    out: list[Choice] = []
    for choice in choices:
        if choice is not None and choice not in out:
            out.append(choice)
    return out


def encode_ranks(
    work: Workspace[Choice], ranks: tuple[int, int]
) -> tuple[Quantized[Choice], float, int]:
    """Fixed ranks: quantization adds at most :data:`RANKS_QUANTIZATION_SHARE` to the
    truncation's squared error (or, where the truncation loses nothing, KG
    :data:`RANKS_FLOOR_KG`)."""
    choice = work.fixed_choice(ranks)
    truncation2 = work.truncation_error2(choice)
    floor2 = (RANKS_FLOOR_KG / 100.0) ** 2 * work.denominator2
    budget2 = max(RANKS_QUANTIZATION_SHARE * truncation2, floor2, 1.01 * work.floor_error2)
    return meet(work, choice, work.initial_step(choice, budget2), truncation2 + budget2)


# ------------------------------------------------------------------------------------------
# a size target

#: A size target's file lies between FILL_LEAST and 1 times the budget: it uses what it is given.
#: Each fill aims at the middle of its window: the packed size is only roughly monotone in D.
FILL_LEAST = 0.98
#: Trial sizes are filled to within this fraction below their aim, so that candidates compare
#: at nearly one size (their errors are then corrected to exactly that size).
TRIAL_WINDOW = 0.006
#: Sizes measured to fill one budget at one choice of ranks: trial sizes, then real files;
#: and KG errors tried for the first error whose trial file fills the budget.
TRIAL_FILLS = 6
FINAL_FILLS = 6
FIRST_FILLS = 8
#: The first error's trial fills this window of the aim (a rough start for the candidates).
FIRST_WINDOW = 0.8
#: The first error's trial: the cheapest ranks for this share of its square, quantization the
#: rest (written out: 1 - 0.3 is not 0.7 in binary, and the trials must not move).
FIRST_SHARE, FIRST_QUANTIZATION_SHARE = 0.3, 0.7
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
#: The coarsest file's search: the cheapest ranks for this share of KG 100.
COARSEST_SHARES = (0.1,)


@dataclass
class Candidate(Generic[Choice]):
    """Ranks whose trial size fills the aim at D = ``step``, with the error estimated there."""

    choice: Choice
    step: float
    slope: float
    error2: float


class _SizeSearch(Generic[Choice]):
    """The state of one size target's search (:func:`search_bpfv`)."""

    def __init__(self, work: Workspace[Choice], target_bpfv: float) -> None:
        self.work = work
        self.target_bpfv = target_bpfv
        self.pixels = work.frame_count * work.vertex_count
        self.budget = target_bpfv * self.pixels / 8.0
        self.aim = 0.5 * (FILL_LEAST + 1.0) * self.budget
        self.lowest2 = (LOWEST_KG / 100.0) ** 2 * work.denominator2
        self.counted = 0
        self.memo: dict[Choice, Candidate[Choice] | None] = {}
        self.best: Candidate[Choice] | None = None

    def trial_sizes(self, choice: Choice) -> Callable[[float], tuple[float, Any]]:
        """The predicted file size at D, and the trial's quantization (``None`` if D is too
        small for the format)."""

        def size_of(step: float) -> tuple[float, Quantized[Choice] | None]:
            try:
                quantized = self.work.quantize(choice, step, trial=True)
                return self.work.trial_size(quantized), quantized
            except (UnreachableTargetError, ValueError):  # D too small for the format
                return math.inf, None

        return size_of

    def step_limits(self, choice: Choice) -> tuple[float, float]:
        """The D a fill may try: from a hundredth of the lowest error's square to KG 10."""
        work = self.work
        return (
            work.initial_step(choice, 0.01 * self.lowest2),
            work.initial_step(choice, (HIGHEST_KG / 10.0) ** 2 * work.denominator2),
        )

    def first_error(self) -> float | None:
        """A KG error whose trial file (the cheapest ranks for :data:`FIRST_SHARE` of it, D
        from the noise model) fills the budget; ``None`` if even the coarsest is too large."""
        work = self.work

        def kg_size(kg: float) -> tuple[float, float]:
            choice = work.ranks_for(kg, FIRST_SHARE)
            if choice is None:
                return math.inf, kg
            room = max(
                (kg / 100.0) ** 2 * work.denominator2 * FIRST_QUANTIZATION_SHARE
                - work.floor_error2,
                work.first_room_floor * self.lowest2,
            )
            return self.trial_sizes(choice)(work.initial_step(choice, room))[0], kg

        # fill() works on KG as on D: the size falls as it grows
        first, tried = fill(
            kg_size,
            1.0,
            KG_SLOPE_PER_VALUE * work.first_fill_values,
            (FIRST_WINDOW * self.aim, self.aim),
            (LOWEST_KG, HIGHEST_KG),
            FIRST_FILLS,
        )
        self.counted += tried
        return None if first is None else first.item

    def evaluate(self, choice: Choice, kg: float) -> None:
        """The D whose trial size fills the aim for ``choice``, and the error estimated there;
        kept as :attr:`best` if smallest."""
        if choice in self.memo:
            return
        work = self.work
        fixed2 = work.truncation_error2(choice) + work.floor_error2
        self.memo[choice] = None
        if self.best is not None and fixed2 >= self.best.error2:
            return  # its truncation alone loses
        room = max((kg / 100.0) ** 2 * work.denominator2 - fixed2, 0.1 * fixed2, self.lowest2)
        filled, tried = fill(
            self.trial_sizes(choice),
            work.initial_step(choice, room),
            SLOPE_PER_VALUE * work.stored_values(choice),
            (self.aim * (1.0 - TRIAL_WINDOW), self.aim),
            self.step_limits(choice),
            TRIAL_FILLS,
        )
        self.counted += tried
        if filled is None or filled.item is None:
            return
        quantization2 = work.estimated_error2(filled.item) - fixed2
        # corrected to the aim: the quantization error grows about as D
        quantization2 *= math.exp((self.aim - filled.size) / filled.slope)
        candidate = Candidate(choice, filled.step, filled.slope, fixed2 + max(quantization2, 0.0))
        self.memo[choice] = candidate
        if self.best is None or candidate.error2 < self.best.error2:
            self.best = candidate

    def final_fill(self, best: Candidate[Choice]) -> Quantized[Choice] | None:
        """The winner's D filled on the real file: the final zstd level and rounding, every
        section and the header. ``None`` if no D tried fits."""
        work = self.work

        def real_size(step: float) -> tuple[float, Quantized[Choice] | None]:
            try:
                quantized = work.quantize(best.choice, step)
            except (UnreachableTargetError, ValueError):
                return math.inf, None
            return len(work.pack(quantized, best.error2, None)[0]), quantized

        filled, tried = fill_erratic(
            real_size,
            (best.step, self.aim, best.slope),
            (FILL_LEAST * self.budget, self.budget),
            self.step_limits(best.choice),
            FINAL_FILLS,
        )
        self.counted += tried
        return None if filled is None else filled.item

    def coarsest(self) -> Outcome:
        """The file at KG 100 if it fits the budget; otherwise no file does."""
        work = self.work
        quantized, error2, trials = search_kg(work, HIGHEST_KG, COARSEST_SHARES)
        size = len(work.pack(quantized, error2, None)[0])
        if size <= self.budget:
            return quantized, error2, self.counted + trials
        faces_bpfv = bits_per_frame_vertex(
            len(work.face_section[1]), work.frame_count, work.vertex_count
        )
        raise UnreachableTargetError(
            f"no file fits {self.target_bpfv} bpfv: even the coarsest one needs "
            f"{bits_per_frame_vertex(size, work.frame_count, work.vertex_count):.3f} bpfv "
            f"(the faces alone take {faces_bpfv:.3f})"
        )


def search_bpfv(
    work: Workspace[Choice], target_bpfv: float
) -> tuple[Quantized[Choice], float, int]:
    """The smallest KG error found whose whole file fits ``target_bpfv``, filling at least
    :data:`FILL_LEAST` of it where the budget allows.

    1. A first KG error whose trial file (the cheapest ranks for :data:`FIRST_SHARE` of it, D
       from the noise model; the fast zstd level, nearest rounding, sized as the workspace
       predicts the final file) fills the budget.
    2. Candidate ranks, the cheapest for shares of that error (:data:`SIZE_SHARES`), then
       their neighbours: each gets the D whose trial file fills the budget, and the
       estimated error there; the smallest wins.
    3. The winner's D is filled on the real file: the final zstd level, rate-distortion
       rounding, every section and the header. The file never exceeds the budget.
    """
    search = _SizeSearch(work, target_bpfv)
    kg = search.first_error()
    if kg is None:  # even the coarsest trial is too large: the real file decides
        return search.coarsest()
    for share in SIZE_SHARES:
        choice = work.ranks_for(kg, share)
        if choice is not None:
            search.evaluate(choice, kg)
    if search.best is None:
        return search.coarsest()
    fraction = 0.1
    for _ in range(NEIGHBOUR_ROUNDS):
        centre = search.best
        for choice in work.neighbours(centre.choice, fraction):
            search.evaluate(choice, kg)
        if search.best is centre:
            fraction *= 0.5
    best = search.best
    quantized = search.final_fill(best)
    if quantized is None:
        return search.coarsest()
    # the header then states the measured error instead of the estimate the fill packed with:
    # msgpack writes every Python float as 9 bytes, so the file keeps the size measured
    return quantized, work.measured_error2(quantized), search.counted
