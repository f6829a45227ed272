"""One trial of the encoder's search, and what a workspace must offer to be searched.

A trial is a choice of ranks quantized with the single parameter D (:class:`Quantized`). The
search (:mod:`.search`) is written once against :class:`Workspace`, which two classes implement:
:class:`~.whole.WholeWorkspace` (the sequence in memory, one decomposition, format 1.0) and
:class:`~.segmented.workspace.SegmentedWorkspace` (segments read in passes, format 1.1). The
search only ever asks a workspace to choose ranks, quantize, size a trial, estimate, model or
measure an error, and pack a file; how each does so is its own business.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from typing import Any, Generic, Protocol, TypeVar

from ..format.qmat import QuantizedMatrix

#: Final bytes of the quantized sections per trial byte (level 19 with rate-distortion rounding,
#: over the trials' fast level with nearest rounding), about as measured on the shared
#: sequences. It only sets a size target's trial aim: the final fill measures real files.
TRIAL_RATIO = 0.9

#: A choice of ranks: (i, k) for a whole file, :class:`~.segmented.model.SegmentRanks` for
#: a segmented one. Hashable, so the search can tell choices apart.
Choice = TypeVar("Choice", bound=Hashable)


@dataclass(eq=False)
class QuantizedSegment:
    """One decomposition's quantized factors: its own U1 (``None`` where a shared U1 serves),
    U3, the core (one column) and the centroids."""

    u1: QuantizedMatrix | None
    u3: QuantizedMatrix
    core: QuantizedMatrix
    centroids: QuantizedMatrix


@dataclass(eq=False)
class Quantized(Generic[Choice]):
    """A choice of ranks quantized with D = ``step``: every number the file stores but the
    faces and names. A whole file is one segment with its own U1."""

    choice: Choice
    step: float
    segments: list[QuantizedSegment]
    shared_u1: QuantizedMatrix | None = None
    #: The decoded vertex farthest from the input and its (frame, vertex), once a workspace
    #: has measured it alongside the error (a whole file's :meth:`decoded_error2`).
    worst: tuple[float, tuple[int, int]] | None = None


class Workspace(Protocol[Choice]):
    """The input as a search sees it (squared errors throughout; E the KG denominator's
    square)."""

    vertex_count: int
    frame_count: int
    #: E: the energy of the centred sequence.
    denominator2: float
    #: The error no choice of D removes: the centroids' at their coarsest usable step.
    floor_error2: float
    #: The stored coded faces (params, payload): part of every file's size.
    face_section: tuple[dict[str, Any], bytes]
    #: Whether :meth:`modelled_error2` is the decoded error itself (no measuring needed).
    exact_model: bool
    #: Where the model is not exact: the share of quantization's room its limit keeps inside
    #: the target, so that a measurement rarely finds the model's choice above it.
    model_margin: float
    #: Truncation shares to try when none of the usual ones leaves room for quantization.
    late_shares: tuple[float, ...]
    #: Whether a KG search meets the valley's close neighbours too (measuring is cheap enough).
    meets_finalists: bool
    #: A size target's first fill: the numbers that scale its first guess of the size's slope,
    #: and the least room its trials leave quantization, as a share of the lowest error's square.
    first_fill_values: int
    first_room_floor: float

    def kg(self, error2: float) -> float:
        """The KG error, in percent, of a squared error."""
        ...

    def check_reachable(self, limit2: float) -> None:
        """``UnreachableTargetError`` if the centroids alone cost more than ``limit2``."""
        ...

    def ranks_for(self, kg: float, share: float) -> Choice | None:
        """The cheapest ranks whose truncation error is at most ``share`` of a KG error
        ``kg``'s square (``None`` if none is)."""
        ...

    def fixed_choice(self, ranks: tuple[int, int]) -> Choice:
        """The choice for fixed ranks (i, k); ``ValueError`` for ranks the input cannot have."""
        ...

    def resolve_finer(self) -> bool:
        """When no usual share of the budget leaves room for quantization: look at the input
        more closely if the workspace can (a segmented encode sketches again with more
        columns), True if it did; the search then starts over."""
        ...

    def largest_choice(self, limit2: float, target_kg: float) -> tuple[Choice, float]:
        """When no share of the budget leaves room for quantization: the largest ranks and the
        D to start from (``UnreachableTargetError`` if even they miss ``limit2``)."""
        ...

    def prepare(self, choices: Sequence[Choice]) -> None:
        """Get ready to quantize these choices (a whole workspace forms the factors once)."""
        ...

    def neighbours(self, choice: Choice, fraction: float) -> list[Choice]:
        """Choices near ``choice`` (ranks apart by about ``fraction``) for a size target to try."""
        ...

    def truncation_error2(self, choice: Choice) -> float:
        """The truncation's squared error."""
        ...

    def stored_values(self, choice: Choice) -> int:
        """How many numbers the choice's factors store (quantized by this encode)."""
        ...

    def initial_step(self, choice: Choice, room2: float) -> float:
        """D whose quantization noise, about D/12 per stored number, fills ``room2``."""
        ...

    def quantize(self, choice: Choice, step: float, *, trial: bool = False) -> Quantized[Choice]:
        """The choice quantized with D = ``step`` (``trial``: as cheaply as ranking needs)."""
        ...

    def trial_bytes(self, quantized: Quantized[Choice]) -> int:
        """The payload bytes at the fast zstd level: to compare trials, not a file's size."""
        ...

    def trial_size(self, quantized: Quantized[Choice]) -> float:
        """The whole file's size predicted from a trial (fast level, nearest rounding)."""
        ...

    def estimated_error2(self, quantized: Quantized[Choice]) -> float:
        """A cheap estimate of the decoded squared error: ranks a size target's candidates."""
        ...

    def modelled_error2(self, quantized: Quantized[Choice]) -> float:
        """The decoded squared error D is steered by."""
        ...

    def measured_error2(self, quantized: Quantized[Choice]) -> float:
        """The decoded squared error, exactly: what the file's header states."""
        ...

    def pack(
        self,
        quantized: Quantized[Choice],
        error2: float,
        target_kg: float | None,
        level: int | None = None,
    ) -> tuple[bytes, dict[str, int]]:
        """The file's bytes and each section's size (zstd ``level``: the final one unless
        given)."""
        ...

    def say(self, message: str) -> None:
        """Progress for the user (a segmented encode's passes); may do nothing."""
        ...
