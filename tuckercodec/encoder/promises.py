"""What a file promises: one step that checks each promise, and one that says what the header
claims of them.

An encode promises at most three things, which the header's ``error`` map states (spec §4.1):

* a KG error at most the target (mode ``"kg"``: the target given, or the default);
* every decoded vertex within a distance of the input's (``max_error``, as a length);
* the input's values, bit for bit (``lossless``).

The search (:mod:`.search`) and the corrections (:mod:`.corrections`) do the work of meeting
them. The steps here check each on what was measured, for a file encoded whole and one in
segments alike: :func:`check_kg` (from :func:`header_claims`, for every file), and
:func:`check_bound` and :func:`check_lossless` (from the corrections' one measuring step).
:func:`header_claims` is the one place that decides what the header claims. A file whose
measurement breaks a promise is never returned.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InternalError, UnreachableTargetError
from ..measures.distortion import Displacement
from .options import EncodeOptions


@dataclass(frozen=True)
class HeaderClaims:
    """The promise fields of a header's ``error`` map: the KG target (``None``: none), and the
    keys that follow it (the worst vertex, the bound and the lossless claim of a file made
    with corrections; empty for any other)."""

    target_kg: float | None
    error: dict[str, Any]


def kg_target(options: EncodeOptions) -> float | None:
    """The KG error a file made with ``options`` promises: mode ``"kg"``'s target (with or
    without a bound), else none (fixed ranks, a size, a bound alone, lossless)."""
    return options.kg_target if options.mode == "kg" else None


def check_kg(options: EncodeOptions, kg: float) -> None:
    """The KG promise, on the KG error measured on the decoded file. The search meets the
    target with room to spare, and corrections only move vertices nearer, so a miss is a bug:
    an ``InternalError``."""
    target = kg_target(options)
    if target is not None and kg > target:
        raise InternalError(f"the file's KG error {kg:.6g} is above the target {target}")


def check_bound(worst: Displacement, bound: float | None) -> None:
    """The worst-vertex promise (``max_error``), on the decoded file's worst vertex.

    ``UnreachableTargetError`` if it is farther than ``bound``: the corrections' grid is finer
    than the bound, so only positions float64 cannot resolve to the bound miss it."""
    if bound is not None and worst.distance > bound:
        raise UnreachableTargetError(
            f"vertex {worst.vertex} of frame {worst.frame} decodes {worst.distance:.6g} from "
            f"the input, above the bound {bound:.6g}: float64 cannot resolve this bound on "
            "these positions"
        )


def check_lossless(decoded: np.ndarray, original: np.ndarray) -> None:
    """The lossless promise: ``decoded`` is ``original`` bit for bit. The corrections of a
    lossless domain restore every bit by construction, so a difference is a bug: an
    ``InternalError`` naming the first (frame, vertex) that differs."""
    if not np.array_equal(decoded.view(np.int64), original.view(np.int64)):
        mismatch = np.argwhere(decoded.view(np.int64) != original.view(np.int64))[0]
        raise InternalError(
            f"the lossless file does not decode to the input's bits (frame {mismatch[0]}, "
            f"vertex {mismatch[1]})"
        )


def header_claims(
    options: EncodeOptions,
    kg: float,
    worst: Displacement | None = None,
    bound: float | None = None,
) -> HeaderClaims:
    """What the header of a file made with ``options`` claims, given its measured KG error
    ``kg`` and, for a file made with corrections, its worst vertex ``worst`` and the bound
    ``bound`` asked for (a length; ``None`` when lossless). The KG promise is checked first
    (:func:`check_kg`): a header never states a target its file misses."""
    check_kg(options, kg)
    error: dict[str, Any] = {}
    if options.corrections:  # the worst vertex measured, what was asked and whether lossless
        assert worst is not None
        error = {
            "max_distance": worst.distance,
            "max_distance_at": [worst.frame, worst.vertex],
            "target_max_distance": bound,
            "lossless": options.lossless,
        }
    return HeaderClaims(kg_target(options), error)


__all__ = [
    "HeaderClaims",
    "check_bound",
    "check_kg",
    "check_lossless",
    "header_claims",
    "kg_target",
]
