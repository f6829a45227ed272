"""A bound on every vertex, or every bit: the Tucker part plus corrections (format 1.3, §6.9).

The KG error is an average; what a viewer sees is the worst vertex, and what an archive needs is
the input back. Both are met the same way: the decoded Tucker part (reconstructed in §8.1's exact
order, so that every decoder gets the same binary64 values) is corrected by one integer per
coordinate, on a grid of step at most 2D/sqrt(3) (each axis then errs by at most D/sqrt(3), so
a vertex by at most D) or on the ordered integers of the input's own floats (lossless).

Which Tucker part? A finer one leaves fewer and smaller corrections but costs more itself, so
the encoder tries a ladder of them (:func:`candidates`) and keeps the smallest whole file: with a
KG target too, only parts that meet it (a correction only moves a vertex nearer its original, so
the file still meets it). Where the Tucker part alone already keeps every vertex within D, with
room for §8's tolerance, the file needs no corrections and is written as before.

:class:`Corrector` is the one way in, for a file encoded whole and one in segments alike.
Everything is checked before the file is returned: every vertex of what a decoder returns is
measured (or every bit compared, :func:`measure`), and the corrections are read back from the
bytes (:func:`check_written`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import msgpack
import numpy as np

from ..decomposition.analysis import analyze
from ..errors import InternalError, UnreachableTargetError
from ..format import residual, streams
from ..format.container import parse_container
from ..format.limits import DEFAULT_LIMITS
from ..format.qmat import QuantizedMatrix
from ..format.reconstruction import reconstruct_frames, reconstruction_basis
from ..format.residual import FLOAT32, FLOAT64, GRID, Domain
from ..measures.distortion import Displacement, ErrorAccumulator, max_distance
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from . import promises, search
from .options import DEFAULT_TARGET_KG, EncodeOptions
from .segmented import SegmentedWorkspace
from .trial import Quantized
from .whole import Ranks, WholeWorkspace

#: The KG errors (percent) of the Tucker parts tried without a KG target: from far finer than
#: any usual target to coarse; the best two's geometric mean is tried last.
LADDER = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0)
#: The share of a ladder step's squared error given to truncation (the rest to quantization).
TRUNCATION_SHARE = 0.5
#: A grid's step is this much under 2D/sqrt(3): rounding of the correction itself has room.
GRID_ROOM = 1e-6
#: A part up to this much larger than the smallest is chosen if it has fewer U1 columns: §8.1's
#: product, most of a decode's time, grows with them, and the ladder's sizes are flat near the
#: smallest (samba lossless: 49.3 bpfv at 353 columns, 50.3 at 247, 53.2 at 144).
DECODE_SLACK = 0.03
#: The most U1 columns a lossless file's Tucker part has (unless no coarser part exists): its
#: decode is then about 2 * 128 multiply-adds per value in §8.1's product, a fraction of the
#: 80 ns a value that the lossless decode's target, 50 MB/s of float32 output on 2 cores
#: (``python -m tools.bench lossless``), allows.
LOSSLESS_COLUMNS = 128
#: zstd level of the corrections in the final file: above it, minutes for a percent or two.
CORRECTION_LEVEL = 9


@dataclass(frozen=True)
class InputCodebooks:
    """An input's codebooks in one domain (format 1.8), with what every Tucker part's
    corrections reuse: the input's positions in them, and their midpoints."""

    books: residual.Codebooks
    positions: tuple[np.ndarray | None, ...]
    middles: tuple[np.ndarray | None, ...]

    @classmethod
    def of(cls, ordered: np.ndarray) -> InputCodebooks | None:
        """Those of the ordered integers ``ordered`` (F', K, 3), or None where no axis has few
        enough distinct values (:func:`~..format.residual.codebooks_of`)."""
        books = residual.codebooks_of(ordered)
        if books is None:
            return None
        positions = tuple(
            None if book is None else np.searchsorted(book, ordered[..., axis])
            for axis, book in enumerate(books)
        )
        middles = tuple(None if book is None else residual.midpoints(book) for book in books)
        return cls(books, positions, middles)


class InputMemo:
    """What the corrections of the last input a goal corrected need per domain, whatever the
    Tucker part: its ordered integers and its codebooks (format 1.8). The search corrects the
    same frames for every part it tries."""

    def __init__(self) -> None:
        self._original: np.ndarray | None = None  # held, so that its identity stays its own
        self._ordered: dict[Domain, np.ndarray] = {}
        self._books: dict[Domain, InputCodebooks | None] = {}

    def _for(self, original: np.ndarray) -> None:
        if self._original is not original:
            self._original, self._ordered, self._books = original, {}, {}

    def ordered(self, original: np.ndarray, domain: Domain) -> np.ndarray:
        """The ordered integers of ``original`` in the lossless ``domain``."""
        self._for(original)
        if domain not in self._ordered:
            self._ordered[domain] = residual.ordered_in(original, domain)
        return self._ordered[domain]

    def codebooks(self, original: np.ndarray, domain: Domain) -> InputCodebooks | None:
        """The codebooks of ``original`` in ``domain``, or None where it has none."""
        self._for(original)
        if domain not in self._books:
            self._books[domain] = InputCodebooks.of(self.ordered(original, domain))
        return self._books[domain]


@dataclass(frozen=True)
class Goal:
    """What the corrections must achieve: a bound D on every vertex (one grid domain), or the
    input's bits (every lossless domain its values fit, the smallest file chosen, with
    ``codebooks`` (format 1.8) where they make it smaller)."""

    domains: tuple[Domain, ...]
    bound: float | None = None  # D, in the sequence's units
    codebooks: bool = False
    memo: InputMemo = field(default_factory=InputMemo, compare=False, repr=False)

    @property
    def lossless(self) -> bool:
        return self.bound is None


def lossless_domains(values: np.ndarray) -> tuple[Domain, ...]:
    """Every lossless domain whose ordered integers hold each of ``values`` exactly, bit for
    bit: binary32 if they are binary32 values; the fewest decimal places, and the fewest
    significant digits, that give each value back as text would (an OBJ written with %.6f or
    %g); and binary64, which holds anything."""
    found = [domain for domain in _candidates(values) if _holds(values, domain)]
    return (*found, Domain(FLOAT64))


def _holds(values: np.ndarray, domain: Domain) -> bool:
    """Whether ``domain``'s ordered integers give every value back, bit for bit."""
    ordered = residual.ordered_in(values, domain)
    with np.errstate(all="ignore"):
        back = residual.correct(values, ordered - ordered, domain, "input")
    return bool(np.array_equal(back.view(np.int64), values.view(np.int64)))


def _candidates(values: np.ndarray) -> Iterator[Domain]:
    """Binary32, then the fewest places and the fewest digits that hold a sample of the
    values (most scales are ruled out on the sample, cheaply), as binary64 and, for binary32
    values, as binary32."""
    yield Domain(FLOAT32)
    sample = np.ascontiguousarray(values.reshape(-1)[:: max(1, values.size // 4096)])
    for name, (_, least, most) in residual.SCALES.items():
        for scale in range(least, most + 1):
            domain = Domain(name, scale=scale)
            if _holds(sample, domain):
                yield domain
                break


@dataclass
class Corrected:
    """A Tucker part with its corrections: the integers, the exact reconstruction they correct
    and the RESD section they pack to (``None`` when no correction is needed)."""

    quantized: Quantized[Any]
    domain: Domain | None
    section: tuple[dict[str, Any], bytes] | None
    tucker_bytes: int
    kg: float | None = None  # the ladder's KG error this part was quantized for

    @property
    def total_bytes(self) -> int:
        return self.tucker_bytes + (len(self.section[1]) if self.section is not None else 0)


def exact_positions(quantized: Quantized[Any], u2: np.ndarray) -> tuple[np.ndarray, int]:
    """Every frame of a whole file's Tucker part as §8.1 reconstructs it (F, K, 3), and the
    exponent e it is reconstructed with."""
    (factors,) = quantized.segments
    assert factors.u1 is not None
    return exact_segment(factors.u1, factors.core, factors.u3, factors.centroids, u2)


def exact_segment(
    u1: QuantizedMatrix,
    core: QuantizedMatrix,
    u3: QuantizedMatrix,
    centroids: QuantizedMatrix,
    u2: np.ndarray,
) -> tuple[np.ndarray, int]:
    """One decomposition's frames as §8.1 reconstructs them, with the exponent e that keeps
    its integer product exact and most precise
    (:func:`~tuckercodec.format.residual.choose_exponent`)."""
    exact_u1 = residual.ExactU1.of(u1.q, u1.steps)
    i = u1.q.shape[1]
    u3_values = u3.values()
    basis = residual.exact_basis(core.values().reshape(i, 3, u3_values.shape[1]), u2)
    scaled = residual.scaled_weights(exact_u1, basis, u3_values)
    largest = float(np.abs(scaled).max()) if scaled.size else 0.0
    exponent = residual.choose_exponent(exact_u1, largest)
    while not residual.weights_fit(exact_u1, residual.integer_weights(scaled, exponent)):
        exponent += 1  # rounding took a weight over: one step coarser
    positions = residual.exact_frames(exact_u1, basis, u3_values, centroids.values(), exponent)
    return positions, exponent


def integers_for(exact: np.ndarray, original: np.ndarray, goal: Goal, domain: Domain) -> np.ndarray:
    """The corrections that take ``exact`` to ``original`` in ``domain``: every bit, or, on a
    grid, only the vertices farther than D (their integers nearest; everyone else's 0)."""
    integers = residual.residuals_of(exact, original, domain)
    if goal.lossless:
        return integers
    assert goal.bound is not None
    distance = np.sqrt(np.square(exact - original).sum(axis=2))
    integers[distance <= goal.bound * (1.0 - GRID_ROOM)] = 0
    return integers


@dataclass
class Packed:
    """Corrections in the format's terms: the domain, the RESD section, the integers it stores
    and its codebooks (format 1.8; ``None`` without)."""

    domain: Domain
    section: tuple[dict[str, Any], bytes]
    integers: np.ndarray
    books: residual.Codebooks | None = None


def corrected_positions(
    exact: np.ndarray,
    integers: np.ndarray,
    domain: Domain,
    books: residual.Codebooks | None = None,
) -> np.ndarray:
    """What a decoder returns for these corrections (§6.9's arithmetic), through the codebooks
    if any."""
    if books is not None:
        integers = residual.from_codebooks(exact, integers, domain, books, "corrections")
    return residual.correct(exact, integers, domain, "corrections")


def correct(
    quantized: Quantized[Any],
    goal: Goal,
    original: np.ndarray,
    u2: np.ndarray,
    plain_positions: np.ndarray,
    tucker_bytes: int,
    level: int,
) -> Corrected:
    """The corrections one Tucker part needs, and their size packed at ``level``.

    ``plain_positions`` is the part as §8 decodes it: when every vertex there is within D, less
    §8's tolerance (any decoder's positions are that close to it), no correction is needed.
    Otherwise the corrections are sized on these positions, which §8.1's exact ones differ from
    by rounding only: the same sizes, at a fraction of the time (:func:`final_section` makes
    the real ones for the part chosen)."""
    if not goal.lossless:
        assert goal.bound is not None
        distance, _ = worst_vertex(plain_positions, original)
        if distance <= goal.bound - tolerance(plain_positions):
            return Corrected(quantized, None, None, tucker_bytes)
    # lossless: the smallest of the domains the values fit
    packed = smallest_section(plain_positions, original, goal, goal.domains, level)
    return Corrected(quantized, packed.domain, packed.section, tucker_bytes)


def smallest_section(
    exact: np.ndarray,
    original: np.ndarray,
    goal: Goal,
    domains: Iterable[Domain],
    level: int,
    *,
    exponent: int = 0,
    predict: int | None = None,
    adaptive_coding: bool = False,
) -> Packed:
    """Of ``domains``, the one whose corrections from ``exact`` to ``original`` pack smallest
    at zstd ``level`` (the first of equal sizes), with the goal's codebooks (format 1.8) where
    they make the section smaller: the domain, its RESD section (§6.9), its integers and its
    codebooks. The one place the corrections are put in the format's terms, for sizing a part
    and for the file, whole or in segments. With ``adaptive_coding`` (the file's final
    sections), the section chosen is packed again with the adaptive chunks of format 1.7 tried
    too (:func:`~..format.residual.encode_section`)."""
    best: Packed | None = None
    for domain in domains:
        if goal.lossless:  # the input's side of e is the same for every part
            integers = goal.memo.ordered(original, domain) - residual.ordered_in(exact, domain)
        else:
            integers = integers_for(exact, original, goal, domain)
        section = residual.encode_section(
            integers, domain, level, exponent=exponent, predict=predict
        )
        if best is None or len(section[1]) < len(best.section[1]):
            best = Packed(domain, section, integers)
    assert best is not None
    # codebooks hold the same positions in every domain: they are tried in the one whose
    # integers packed smallest, which also stores them in the fewest bits
    found = goal.memo.codebooks(original, best.domain) if goal.codebooks else None
    if found is not None and goal.lossless:
        domain = best.domain
        ordered = goal.memo.ordered(original, domain)
        integers = residual.codebook_integers(
            best.integers, ordered, found.books, found.positions, found.middles
        )
        section = residual.encode_section(
            integers, domain, level, exponent=exponent, predict=predict, codebooks=found.books
        )
        if _size(section) < _size(best.section):
            best = Packed(domain, section, integers, found.books)
    if adaptive_coding:  # the chosen zstd section, or its adaptive twin (not packed again)
        best.section = residual.with_adaptive_chunks(
            best.section, best.integers, best.domain, exponent=exponent, predict=predict
        )
    return best


def described(domain: Domain, section: tuple[dict[str, Any], bytes]) -> str:
    """The domain as a report names it, and the axes with a codebook (format 1.8) if any."""
    books = section[0].get("codebooks", [])
    axes = [name for name, book in zip("xyz", books, strict=False) if book[0]]
    return domain.describe() + (f" with codebooks on {', '.join(axes)}" if axes else "")


def _size(section: tuple[dict[str, Any], bytes]) -> int:
    """A section's bytes in the file: its payload and its parameters."""
    return len(section[1]) + len(msgpack.packb(section[0]))


def tolerance(reference: np.ndarray) -> float:
    """How far (Euclidean) a conforming decoder's vertex may be from the reference's on a file
    without corrections: §8's per-value tolerance on each of three axes."""
    return math.sqrt(3.0) * (1e-9 * float(np.abs(reference).max()) + 1e-12)


def worst_vertex(positions: np.ndarray, original: np.ndarray) -> tuple[float, tuple[int, int]]:
    """The worst vertex of ``positions`` against ``original`` (the metric's
    :func:`~tuckercodec.measures.distortion.max_distance`): its Euclidean distance, and (frame,
    vertex)."""
    worst = max_distance(original, positions)
    return worst.distance, worst.at


def measure(decoded: np.ndarray, original: np.ndarray, goal: Goal) -> Displacement:
    """The worst vertex of ``decoded`` (a whole file's frames, or a segment's), with the
    promise of ``goal`` checked on them: bit for bit (:func:`.promises.check_lossless`), or
    every vertex within the bound (:func:`.promises.check_bound`). The one place either is
    checked, for both kinds of file."""
    worst = max_distance(original, decoded)
    if goal.lossless:
        promises.check_lossless(decoded, original)
    else:
        promises.check_bound(worst, goal.bound)
    return worst


__all__ = [
    "CORRECTION_LEVEL",
    "LADDER",
    "TRUNCATION_SHARE",
    "Corrected",
    "CorrectedFile",
    "Corrector",
    "Goal",
    "check_written",
    "correct",
    "corrected_positions",
    "measure",
    "search_whole",
    "worst_vertex",
]


# -- the search over Tucker parts (a whole file) -----------------------------------------------


def search_whole(work: WholeWorkspace, options: EncodeOptions, goal: Goal) -> tuple[Corrected, int]:
    """The Tucker part whose file, corrections included, is smallest (sizes at the search's
    fast zstd level), and the number of parts tried."""
    original = work.sequence.vertices
    u2 = work.analysis.decomposition.u2
    tried: dict[float, Corrected] = {}

    def attempt(quantized: Quantized[Ranks]) -> Corrected:
        plain = plain_positions(quantized, u2)
        tucker_bytes = len(work.pack(quantized, 0.0, None, streams.SEARCH_LEVEL)[0])
        return correct(quantized, goal, original, u2, plain, tucker_bytes, streams.SEARCH_LEVEL)

    if options.ranks is not None:
        return attempt(search.encode_ranks(work, options.ranks)[0]), 1
    if options.target_kg is not None:  # every part meets the KG target itself
        best: Corrected | None = None
        for divisor in (1.0, 2.0, 4.0):
            candidate = attempt(search.search_kg(work, options.target_kg / divisor)[0])
            tried[divisor] = candidate
            if best is not None and candidate.total_bytes >= best.total_bytes:
                break
            best = candidate
            if candidate.section is None:  # no corrections needed: nothing finer is smaller
                break
        assert best is not None
        return best, len(tried)
    ladder = list(LADDER)
    if goal.lossless:  # no part too slow to decode, while a coarser one is there instead
        fast = [kg for kg in ladder if work.ranks_for(kg, TRUNCATION_SHARE)[0] <= LOSSLESS_COLUMNS]
        ladder = fast or ladder[-1:]
    for kg in ladder:
        part = quick_part(work, kg)
        if part is not None:
            tried[kg] = attempt(part)
            tried[kg].kg = kg
    if not tried:
        raise UnreachableTargetError("no Tucker part of this sequence can be quantized")
    ranked = sorted(tried, key=lambda kg: tried[kg].total_bytes)
    if len(ranked) > 1:
        middle = math.sqrt(ranked[0] * ranked[1])
        fits = work.ranks_for(middle, TRUNCATION_SHARE)[0] <= LOSSLESS_COLUMNS
        part = quick_part(work, middle) if fits or not goal.lossless else None
        if part is not None:
            tried[middle] = attempt(part)
            tried[middle].kg = middle
    smallest = min(candidate.total_bytes for candidate in tried.values())
    # within DECODE_SLACK of the smallest, the part of fewest U1 columns: it decodes fastest
    near = [kg for kg in tried if tried[kg].total_bytes <= (1 + DECODE_SLACK) * smallest]
    chosen = min(near, key=lambda kg: (tried[kg].quantized.choice[0], tried[kg].total_bytes))
    return tried[chosen], len(tried)


def quick_part(work: WholeWorkspace, kg: float) -> Quantized[Ranks] | None:
    """A Tucker part of about KG error ``kg``: the cheapest ranks for a share of it, quantized
    for the rest (no closed loop: the corrections make up whatever it misses)."""
    limit2 = (kg / 100.0) ** 2 * work.denominator2
    choice = work.ranks_for(kg, TRUNCATION_SHARE)
    room = limit2 - work.truncation_error2(choice) - work.floor_error2
    if room <= 0:
        return None
    work.prepare([choice])
    return work.quantize(choice, work.initial_step(choice, room))


def plain_positions(quantized: Quantized[Any], u2: np.ndarray) -> np.ndarray:
    """Every frame as §8 reconstructs a file without corrections (any summation order)."""
    (factors,) = quantized.segments
    assert factors.u1 is not None
    u1 = factors.u1.values()
    u3 = factors.u3.values()
    core = factors.core.values().reshape(u1.shape[1], 3, u3.shape[1])
    return reconstruct_frames(u1, reconstruction_basis(core, u2), u3, factors.centroids.values())


def final_section(
    corrected: Corrected,
    goal: Goal,
    original: np.ndarray,
    u2: np.ndarray,
    level: int,
    adaptive_coding: bool = True,
) -> tuple[tuple[dict[str, Any], bytes], np.ndarray, np.ndarray] | None:
    """The chosen part's corrections on §8.1's exact positions, packed for the file at the
    final level (capped at :data:`CORRECTION_LEVEL`) with the predictor the search chose, and
    with ``adaptive_coding`` (format 1.7) adaptive chunks where they gain enough; the integers
    and the positions they decode to; ``None`` if the part needs none."""
    if corrected.section is None or corrected.domain is None:
        return None
    exact, exponent = exact_positions(corrected.quantized, u2)
    predict = int(corrected.section[0]["predict"])
    packed = smallest_section(
        exact,
        original,
        goal,
        (corrected.domain,),
        min(level, CORRECTION_LEVEL),
        exponent=exponent,
        predict=predict,
        adaptive_coding=adaptive_coding,
    )
    decoded = corrected_positions(exact, packed.integers, packed.domain, packed.books)
    return packed.section, packed.integers, decoded


def check_written(
    data: bytes, integers: np.ndarray, section_id: str = residual.SECTION_STEM
) -> None:
    """Read a RESD section back from the packed file as a decoder does (§5 step 18, §6.9) and
    check that it holds ``integers``: the positions the encoder measured are then what every
    decoder returns, since §8.1 and §6.9 leave no freedom in the arithmetic."""
    container = parse_container(data, DEFAULT_LIMITS)
    entry = container.section(section_id)
    assert entry is not None
    payload = container.payload(data, entry)
    frames, vertices = integers.shape[:2]
    where = f"section {section_id}"
    layout = residual.read_layout(
        entry.params,
        entry.length,
        frames,
        vertices,
        DEFAULT_LIMITS,
        where,
        adaptive_corrections=container.adaptive_corrections,
        codebooks=container.codebooks,
    )
    for chunk in range(len(layout.planes)):
        start, stop = layout.chunk_range(chunk)
        stored = residual.decode_chunk(payload, layout, chunk, vertices, where)
        if not np.array_equal(stored, integers[start:stop]):
            raise InternalError(
                f"the corrections of frames {start}..{stop - 1} read back differently from what "
                "was packed"
            )


# -- a segmented file (§6.7): corrections per segment -------------------------------------------


def goal_of_blocks(options: EncodeOptions, blocks: Iterable[np.ndarray]) -> Goal:
    """The goal from the frames, given a block at a time: the bounding box's diagonal (and the
    largest coordinate) for a bound, or the lossless domains that hold every block."""
    low = np.full(3, np.inf)
    high = np.full(3, -np.inf)
    domains: tuple[Domain, ...] | None = None
    largest = 0.0
    for block in blocks:
        if options.lossless:
            held = lossless_domains(block)
            domains = held if domains is None else tuple(d for d in domains if d in held)
            continue
        low = np.minimum(low, block.min(axis=(0, 1)))
        high = np.maximum(high, block.max(axis=(0, 1)))
        largest = max(largest, float(np.abs(block).max()))
    if options.lossless:
        assert domains is not None
        return Goal(domains, codebooks=options.features.codebooks)
    bound = options.max_error_length(float(np.linalg.norm(high - low)))
    assert bound is not None
    return Goal((Domain(GRID, step=_grid_step(bound, largest)),), bound)


def _grid_step(bound: float, largest: float) -> float:
    """A grid's step for the bound D on positions reaching ``largest``, or
    ``UnreachableTargetError`` if float64 cannot resolve D there (a grid finer than a few of
    the positions' ulps cannot be met reliably)."""
    resolvable = 64 * np.spacing(largest) if largest > 0 else 0.0
    if not bound > resolvable:
        raise UnreachableTargetError(
            f"no file can keep every vertex within {bound:.6g}: the positions reach "
            f"{largest:.6g}, where float64 itself resolves only about {np.spacing(largest):.3g} "
            f"(a bound must be above {resolvable:.3g}); ask for a larger bound, or --lossless"
        )
    return float(2.0 * bound / math.sqrt(3.0) * (1.0 - GRID_ROOM))


@dataclass
class SegmentCorrections:
    """Every segment's RESD.s and what the corrected file measures."""

    sections: list[tuple[dict[str, Any], bytes]]
    integers: list[np.ndarray]
    error2: float
    worst: Displacement
    domains: list[Domain]


def correct_segments(
    work: SegmentedWorkspace,
    quantized: Quantized[Any],
    goal: Goal,
    level: int,
    adaptive_coding: bool = True,
) -> SegmentCorrections:
    """A pass over the input: each segment's §8.1 positions, its corrections (the smallest of
    the goal's domains, with ``adaptive_coding`` adaptive chunks where they gain enough) and the
    error of the corrected file, measured on them."""
    work.say(f"pass {work.passes + 1}: correcting every segment")
    measured = ErrorAccumulator()
    out = SegmentCorrections([], [], 0.0, Displacement(0.0, 0, 0), [])
    for number, part in enumerate(work.decoded(quantized)):
        factors = quantized.segments[number]
        i = part.basis.shape[0]
        u1 = factors.u1
        if u1 is None:  # the shared basis's first i columns
            assert quantized.shared_u1 is not None
            shared = quantized.shared_u1
            u1 = QuantizedMatrix(shared.q[:, :i], shared.steps[:i])
        exact, exponent = exact_segment(
            u1, factors.core, factors.u3, factors.centroids, work.models[number].u2
        )
        original = work.source.read(part.segment.start, part.segment.stop)
        packed = smallest_section(
            exact,
            original,
            goal,
            goal.domains,
            min(level, CORRECTION_LEVEL),
            exponent=exponent,
            adaptive_coding=adaptive_coding,
        )
        decoded = corrected_positions(exact, packed.integers, packed.domain, packed.books)
        measure(decoded, original, goal)
        measured.add(original, decoded, frames=range(part.segment.start, part.segment.stop))
        out.sections.append(packed.section)
        out.integers.append(packed.integers)
        out.domains.append(packed.domain)
    work.passes += 1
    out.worst = measured.worst
    out.error2 = float(np.sum(measured.per_frame_squared()))
    return out


# -- the one way in: a file that keeps its promise ----------------------------------------------


@dataclass
class CorrectedFile:
    """A file made with corrections, packed and checked: its Tucker part, what it measures
    and what the report says of it."""

    quantized: Quantized[Any]
    #: the RESD section's (a whole file, ``None`` if it needs none) or each segment's RESD.s
    sections: list[tuple[dict[str, Any], bytes]] | None
    error2: float  # the decoded squared error, corrections applied
    worst: Displacement  # the decoded worst vertex, corrections applied
    bound: float | None  # the bound D asked for, as a length (``None``: lossless)
    trials: int  # the Tucker parts tried, or the search's trials
    domains: str | None  # the domains of the corrections, as the report names them
    data: bytes = b""
    sizes: dict[str, int] = field(default_factory=dict)


#: What packs a corrected file (the encoder's, which decides the header's claims).
Pack = Callable[[CorrectedFile], tuple[bytes, dict[str, int]]]


class Corrector:
    """The one way into the corrections for a bound on every vertex (``max_error``) or
    lossless, for a file encoded whole and one in segments alike.

    Made before the work (one pass over the input, ``block_frames`` at a time: the bound as a
    length, or the lossless domains the input fits), so that a bound no file can resolve is
    refused before the passes; :meth:`file` then makes the file on a workspace, checks each
    promise on what it decodes to (:func:`measure`), packs it with ``pack`` and checks the
    corrections in the bytes (:func:`check_written`).
    """

    def __init__(
        self,
        options: EncodeOptions,
        frames: FrameSource | MeshSequence,
        block_frames: int | None = None,
    ) -> None:
        self.options = options
        #: whether the corrections may be adaptive streams (format 1.7, flag bit 4)
        self.adaptive_corrections = options.features.adaptive_corrections
        if isinstance(frames, MeshSequence):
            self.goal = goal_of_blocks(options, [frames.vertices])
        else:
            step = frames.frame_count if block_frames is None else block_frames
            starts = range(0, frames.frame_count, step)
            blocks = (frames.read(a, min(frames.frame_count, a + step)) for a in starts)
            self.goal = goal_of_blocks(options, blocks)

    def file(self, work: WholeWorkspace | SegmentedWorkspace, pack: Pack) -> CorrectedFile:
        """The smallest file found that keeps the promise, packed by ``pack`` and checked."""
        if isinstance(work, WholeWorkspace):
            fixed, written = self._whole(work)
        else:
            fixed, written = self._segments(work)
        fixed.data, fixed.sizes = pack(fixed)
        for section_id, integers in written:
            check_written(fixed.data, integers, section_id)
        return fixed

    def _whole(self, work: WholeWorkspace) -> tuple[CorrectedFile, list[tuple[str, np.ndarray]]]:
        """The smallest Tucker part plus its corrections (:func:`search_whole`), on §8.1's
        exact positions."""
        goal, original = self.goal, work.sequence.vertices
        chosen, trials = search_whole(work, self.options, goal)
        u2 = work.analysis.decomposition.u2
        final = final_section(
            chosen, goal, original, u2, self.options.level, self.adaptive_corrections
        )
        written: list[tuple[str, np.ndarray]] = []
        sections = None
        if final is not None:
            section, integers, decoded = final
            sections, written = [section], [(residual.SECTION_STEM, integers)]
        else:
            decoded = plain_positions(chosen.quantized, u2)
        worst = measure(decoded, original, goal)
        error2 = float(np.square(decoded - original).sum())
        domain = described(chosen.domain, sections[0]) if chosen.domain and sections else None
        return CorrectedFile(
            chosen.quantized, sections, error2, worst, goal.bound, trials, domain
        ), written

    def _segments(
        self, work: SegmentedWorkspace
    ) -> tuple[CorrectedFile, list[tuple[str, np.ndarray]]]:
        """The Tucker part for the KG target, or for the KG error whose part made the smallest
        file of the first segment encoded whole; then a pass that corrects every segment."""
        options, goal = self.options, self.goal
        if options.ranks is not None:
            quantized, _, trials = search.encode_ranks(work, options.ranks)
        else:
            kg = options.target_kg
            if kg is None:
                first, frames = work.ranges[0], work.source
                head = MeshSequence(frames.read(first.start, first.stop), frames.faces)
                whole = WholeWorkspace(head, analyze(head), streams.SEARCH_LEVEL, "exact")
                chosen, _ = search_whole(whole, options, goal)
                kg = chosen.kg if chosen.kg is not None else DEFAULT_TARGET_KG
            quantized, _, trials = search.search_kg(work, kg)
        fixed = correct_segments(work, quantized, goal, options.level, self.adaptive_corrections)
        written = [
            (f"{residual.SECTION_STEM}.{number}", integers)
            for number, integers in enumerate(fixed.integers)
        ]
        domains = ", ".join(
            sorted(
                {
                    described(d, section)
                    for d, section in zip(fixed.domains, fixed.sections, strict=True)
                }
            )
        )
        return CorrectedFile(
            quantized, fixed.sections, fixed.error2, fixed.worst, goal.bound, trials, domains
        ), written
