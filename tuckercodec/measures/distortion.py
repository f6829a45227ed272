"""Error and rate measures of the dynamic-mesh compression literature.

Every function says which definition it computes. The default error is the KG error of
Karni and Gotsman (2004), the one every published comparison uses::

    KG = 100 * ||A - A~|| / ||A - E(A)||

where ||.|| is the Frobenius norm over all frames, vertices and axes, and E(A) holds each
frame's mean vertex position (the per-frame, per-axis mean over vertices). The seed paper's
formula reads as if E(A) held each vertex's mean position over time; that variant gives
different numbers and is available only by name (``mean="temporal"``).

The worst vertex (:func:`max_distance`, :data:`MAX_DISTANCE_DEFINITION`) is the largest
Euclidean distance between a vertex of the approximation and the same vertex of the original,
over every frame and vertex, in the sequence's own units (not a percentage), with the frame and
vertex where it is. :class:`ErrorAccumulator` measures it and the KG error together, in one pass
over blocks of frames, so that a long sequence (or one read a range of frames at a time) never
needs a difference array of its whole size.

The perception-correlated STED error of Váša and Skala (2011) is in
:mod:`tuckercodec.measures.perceptual`; the rate measure bpfv in :mod:`tuckercodec.measures.rate`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ..errors import InputError
from ..model.sequence import MeshSequence

KG_DEFINITION = "KG (Karni-Gotsman 2004): 100*||A-B||_F / ||A - per-frame vertex mean of A||_F"

MAX_DISTANCE_DEFINITION = (
    "the largest Euclidean distance ||A_fk - B_fk||_2 over frames f and vertices k, in the "
    "sequence's units; the first in frame-major order on ties"
)

MeanKind = Literal["frame", "temporal"]

#: The float64 bytes of the difference of one block of frames that :class:`ErrorAccumulator`
#: holds at a time (the block's other temporaries are of the same order).
BLOCK_BYTES = 16 * 2**20


def _positions(x: MeshSequence | np.ndarray) -> np.ndarray:
    array = x.vertices if isinstance(x, MeshSequence) else np.asarray(x, dtype=np.float64)
    if array.ndim != 3 or array.shape[2] != 3:
        raise ValueError(f"expected positions of shape (frames, vertices, 3), got {array.shape}")
    return array


def _pair(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    a, b = _positions(original), _positions(approx)
    if a.shape != b.shape:
        raise InputError(f"the sequences differ in shape: {a.shape} against {b.shape}")
    return a, b


def kg_denominator(original: MeshSequence | np.ndarray, *, mean: MeanKind = "frame") -> float:
    """||A - E(A)||_F: the norm the KG error divides by (see the module docstring)."""
    a = _positions(original)
    if mean == "frame":
        centred = a - a.mean(axis=1, keepdims=True)
    elif mean == "temporal":
        centred = a - a.mean(axis=0, keepdims=True)
    else:
        raise ValueError(f"mean must be 'frame' or 'temporal', got {mean!r}")
    norm = float(np.linalg.norm(centred))
    if norm == 0.0:
        raise _undefined_kg(mean)
    return norm


def _undefined_kg(mean: MeanKind) -> InputError:
    if mean == "frame":
        return InputError(
            "the KG error is undefined: every frame collapses to a single point, so the "
            "Karni-Gotsman denominator is zero"
        )
    return InputError(
        "the temporal-mean KG error is undefined: no vertex ever moves, so its denominator "
        "is zero (the Karni-Gotsman definition, mean='frame', is defined here)"
    )


def kg_error(
    original: MeshSequence | np.ndarray,
    approx: MeshSequence | np.ndarray,
    *,
    mean: MeanKind = "frame",
) -> float:
    """The KG error of ``approx`` against ``original``, in percent.

    ``mean="frame"`` (default) is the Karni-Gotsman definition; ``mean="temporal"`` divides by
    the distance from each vertex's temporal mean instead.
    """
    a, b = _pair(original, approx)
    return 100.0 * float(np.linalg.norm(a - b)) / kg_denominator(a, mean=mean)


def relative_error(original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray) -> float:
    """||A - B||_F / ||A||_F, uncentred (depends on where the scene's origin is)."""
    a, b = _pair(original, approx)
    norm = float(np.linalg.norm(a))
    if norm == 0.0:
        raise InputError("the relative error is undefined: every position of the original is 0")
    return float(np.linalg.norm(a - b)) / norm


@dataclass(frozen=True)
class Displacement:
    """The worst vertex: the largest Euclidean distance between matching vertices, in the
    sequence's units, and the frame and vertex where it is (:data:`MAX_DISTANCE_DEFINITION`)."""

    distance: float
    frame: int
    vertex: int

    @property
    def at(self) -> tuple[int, int]:
        """(frame, vertex), as ``EncodeReport.max_distance_at`` and the header's
        ``error.max_distance_at`` (spec §4.1) give it."""
        return (self.frame, self.vertex)


class WorstVertex:
    """The running worst vertex over blocks of frames: the first of equal distances, and the
    first NaN over any number (:data:`MAX_DISTANCE_DEFINITION`)."""

    def __init__(self) -> None:
        self.worst: Displacement | None = None

    def add_distances(self, distances: np.ndarray, numbers: np.ndarray) -> None:
        """Distances (n, K) of frames numbered ``numbers``."""
        if not distances.size:
            return
        index = int(np.argmax(distances))  # the first of equals (and the first NaN)
        frame, vertex = divmod(index, distances.shape[1])
        found = float(distances[frame, vertex])
        best = self.worst
        if (
            best is None
            or found > best.distance
            or (math.isnan(found) and not math.isnan(best.distance))
        ):
            self.worst = Displacement(found, int(numbers[frame]), int(vertex))

    def add(self, difference: np.ndarray, first_frame: int) -> None:
        """The difference (n, K, 3) of frames ``first_frame`` onwards (either sign)."""
        # (x*x + y*y) + z*z, as np.sum over the last axis adds them (and norm sums), but in
        # three passes over the frames rather than a reduction of every 3 values
        x, y, z = (difference[..., axis] for axis in range(3))
        squared = x * x
        squared += y * y
        squared += z * z
        np.sqrt(squared, out=squared)
        self.add_distances(squared, np.arange(first_frame, first_frame + len(difference)))

    def found(self) -> tuple[float, tuple[int, int]]:
        """(distance, (frame, vertex)) of the worst vertex added."""
        if self.worst is None:
            raise ValueError("no vertices have been compared")
        return self.worst.distance, self.worst.at


class ErrorAccumulator:
    """The KG error and the worst vertex of an approximation, measured in one pass over the
    frames, a block of frames at a time.

    Give it the frames in order, any number per call, with :meth:`add`; then read :attr:`kg`
    (:data:`KG_DEFINITION`, over every frame added: its denominator's per-frame mean makes it
    a sum over frames), :attr:`worst` (:data:`MAX_DISTANCE_DEFINITION`), :attr:`relative_error`
    and the per-frame series. Each call is cut into blocks of ``block_frames`` frames (by
    default as many as make :data:`BLOCK_BYTES` of float64 differences), so the memory it
    takes beyond its inputs is bounded by the block, not the sequence; what it keeps is a few
    numbers per frame.

    Frames are numbered as they come (0, 1, ... across calls) unless :meth:`add` is given
    their numbers (``frames=``), for instance a range of a longer sequence; the worst vertex's
    frame is then that number. On ties the first in the order given wins: the first in
    frame-major order (frame, then vertex) when the frames come in order.
    """

    def __init__(self, *, block_frames: int | None = None) -> None:
        if block_frames is not None and (isinstance(block_frames, bool) or block_frames < 1):
            raise ValueError(f"block_frames must be an integer >= 1, got {block_frames!r}")
        self.block_frames = block_frames
        self.vertex_count: int | None = None
        self._numbers: list[np.ndarray] = []  # the frames' numbers, as added
        self._squared: list[np.ndarray] = []  # per frame: sum over k of ||a_fk - b_fk||^2
        self._spread: list[np.ndarray] = []  # per frame: ||A_f - its vertex mean||^2
        self._energy: list[np.ndarray] = []  # per frame: ||A_f||^2
        self._largest: list[np.ndarray] = []  # per frame: max over k of ||a_fk - b_fk||
        self._worst = WorstVertex()
        self._next = 0  # the number of the next frame, when add is given none

    @property
    def frame_count(self) -> int:
        """Frames added so far."""
        return sum(len(n) for n in self._numbers)

    def add(
        self,
        original: MeshSequence | np.ndarray,
        approx: MeshSequence | np.ndarray,
        *,
        frames: Iterable[int] | None = None,
    ) -> None:
        """Add frames: ``original`` and ``approx`` of shape (n, K, 3) (any float type; read in
        blocks and converted to float64 a block at a time), the same K at every call.
        ``frames``: their numbers (default: those after the frames added so far)."""
        a = original.vertices if isinstance(original, MeshSequence) else original
        b = approx.vertices if isinstance(approx, MeshSequence) else approx
        a, b = np.asanyarray(a), np.asanyarray(b)
        if a.ndim != 3 or a.shape[2] != 3:
            raise ValueError(f"expected positions of shape (frames, vertices, 3), got {a.shape}")
        if a.shape != b.shape:
            raise InputError(f"the sequences differ in shape: {a.shape} against {b.shape}")
        if self.vertex_count is not None and a.shape[1] != self.vertex_count:
            raise InputError(
                f"these frames have {a.shape[1]} vertices, the frames before {self.vertex_count}"
            )
        count = a.shape[0]
        if frames is None:
            numbers = np.arange(self._next, self._next + count, dtype=np.int64)
        else:
            numbers = np.asarray(list(frames), dtype=np.int64).reshape(-1)
            if numbers.size != count:
                raise ValueError(f"{numbers.size} frame numbers given for {count} frames")
        self.vertex_count = a.shape[1]
        if count == 0:
            return
        self._next = int(numbers[-1]) + 1
        step = self.block_frames or max(1, BLOCK_BYTES // max(1, a.shape[1] * 24))
        for start in range(0, count, step):
            stop = min(start + step, count)
            self._add_block(
                np.asarray(a[start:stop], dtype=np.float64),
                np.asarray(b[start:stop], dtype=np.float64),
                numbers[start:stop],
            )

    def _add_block(self, a: np.ndarray, b: np.ndarray, numbers: np.ndarray) -> None:
        difference = a - b
        # each vertex's squared distance summed over x, y, z in that order, as
        # np.linalg.norm(axis=2) sums it, so that equal distances are equal here too
        squared = np.sum(difference * difference, axis=2)
        del difference
        self._squared.append(np.sum(squared, axis=1))
        distances = np.sqrt(squared)
        del squared
        largest = np.max(distances, axis=1) if distances.shape[1] else np.zeros(len(a))
        self._largest.append(largest)
        self._worst.add_distances(distances, numbers)
        del distances
        centred = a - a.mean(axis=1, keepdims=True) if a.shape[1] else a
        self._spread.append(np.sum(np.square(centred), axis=(1, 2)))
        del centred
        self._energy.append(np.sum(np.square(a), axis=(1, 2)))
        self._numbers.append(numbers)

    def _check(self) -> None:
        if not self._numbers:
            raise ValueError("no frames have been compared")

    @property
    def worst(self) -> Displacement:
        """The worst vertex of the frames added (:data:`MAX_DISTANCE_DEFINITION`)."""
        self._check()
        if self._worst.worst is None:  # frames without vertices
            raise ValueError("the frames compared have no vertices")
        return self._worst.worst

    @property
    def kg(self) -> float:
        """The KG error of the frames added (:data:`KG_DEFINITION`), in percent; an InputError
        if it is undefined (every frame a single point)."""
        self._check()
        spread = float(np.sum(np.concatenate(self._spread)))
        if spread == 0.0:
            raise _undefined_kg("frame")
        return 100.0 * math.sqrt(float(np.sum(self.per_frame_squared()))) / math.sqrt(spread)

    @property
    def relative_error(self) -> float:
        """||A - B||_F / ||A||_F over the frames added (uncentred, as :func:`relative_error`)."""
        self._check()
        energy = float(np.sum(np.concatenate(self._energy)))
        if energy == 0.0:
            raise InputError("the relative error is undefined: every position of the original is 0")
        return math.sqrt(float(np.sum(self.per_frame_squared()))) / math.sqrt(energy)

    @property
    def frame_numbers(self) -> np.ndarray:
        """The numbers of the frames added, in order."""
        self._check()
        return np.concatenate(self._numbers)

    def per_frame_squared(self) -> np.ndarray:
        """Each frame's ||A_f - B_f||_F^2, in the order added."""
        self._check()
        return np.concatenate(self._squared)

    def per_frame_kg(self) -> np.ndarray:
        """Each frame's share of the KG error, as :func:`per_frame_kg` (their squares sum to
        :attr:`kg` squared), in the order added."""
        self._check()
        spread = float(np.sum(np.concatenate(self._spread)))
        if spread == 0.0:
            raise _undefined_kg("frame")
        return 100.0 * np.sqrt(self.per_frame_squared()) / math.sqrt(spread)

    def per_frame_max_distance(self) -> np.ndarray:
        """Each frame's worst vertex distance, in the sequence's units, in the order added."""
        self._check()
        return np.concatenate(self._largest)


def compare(
    original: MeshSequence | np.ndarray,
    approx: MeshSequence | np.ndarray,
    *,
    block_frames: int | None = None,
) -> ErrorAccumulator:
    """An :class:`ErrorAccumulator` that has been given every frame of both sequences: the KG
    error, the worst vertex and the per-frame series from one pass."""
    measured = ErrorAccumulator(block_frames=block_frames)
    measured.add(original, approx)
    return measured


def max_distance(
    original: MeshSequence | np.ndarray,
    approx: MeshSequence | np.ndarray,
    *,
    block_frames: int | None = None,
) -> Displacement:
    """The worst vertex (:data:`MAX_DISTANCE_DEFINITION`): the largest Euclidean distance
    ||a_fk - b_fk||_2 over all frames f and vertices k, in the sequence's units, and its
    (frame, vertex), the first in frame-major order on ties. Computed a block of frames at a
    time (:class:`ErrorAccumulator`), so memory stays bounded for long sequences."""
    return compare(original, approx, block_frames=block_frames).worst


def max_vertex_displacement(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> Displacement:
    """The largest ||a_fk - b_fk||_2 over all frames f and vertices k, in scene units: the
    public API's name for :func:`max_distance`."""
    return max_distance(original, approx)


def per_frame_max_displacement(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> np.ndarray:
    """Each frame's worst vertex: max over k of ||a_fk - b_fk||_2, in scene units, shape (F,)."""
    return compare(original, approx).per_frame_max_distance()


def per_frame_kg(
    original: MeshSequence | np.ndarray, approx: MeshSequence | np.ndarray
) -> np.ndarray:
    """Each frame's share of the KG error: 100*||A_f - B_f|| / ||A - E(A)|| (whole-sequence
    Karni-Gotsman denominator), so that the squares of these values sum to KG**2."""
    a, b = _pair(original, approx)
    return 100.0 * np.linalg.norm((a - b).reshape(a.shape[0], -1), axis=1) / kg_denominator(a)
