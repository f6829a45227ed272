"""Rate-distortion analysis of truncated HOSVD: the seed paper's method, and the exact table.

For every N-rank (i, 3, k) this module gives:

* the exact KG error, from the core's energy (no reconstruction);
* the paper's estimate (its eq. 10-12): the squared error is bounded by the discarded squared
  singular values of the mode-1 unfolding plus those of the mode-3 unfolding;
* psi, the estimator's error (our reading of the paper's eq. 13): ``kg_bound - kg``, in KG
  units, never negative;
* the paper's rate model (its eq. 14): S = i*K + 9 + k*F + 3*i*k stored floats, and the
  reduction rate Theta = S / (3*K*F).

All errors are KG errors with the Karni-Gotsman denominator (each frame's centroid removed);
see :mod:`tuckercodec.measures.distortion`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from ..errors import InputError
from ..model.sequence import MeshSequence
from ..system import native
from .hosvd import HOSVD, centre_frames, hosvd

Selection = Literal["exact", "bound"]
#: How ranks may be selected: by the exact error table, or by the seed paper's bound alone.
SELECTIONS: tuple[Selection, ...] = get_args(Selection)
#: How ranks are selected unless told otherwise.
DEFAULT_SELECTION: Selection = "exact"


@dataclass(frozen=True)
class RankChoice:
    """One truncation (i, 3, k) with its cost and errors."""

    i: int
    k: int
    floats: int  # S, the paper's stored-float count
    rate: float  # Theta = S / (3KF)
    kg: float  # exact KG error of the truncation
    kg_bound: float  # the paper's estimate (an upper bound)


@dataclass(frozen=True)
class Curve:
    """A rate-distortion curve: parallel arrays, ordered by increasing rate.

    ``i``/``k`` are the ranks of each point (for PCA, ``k`` is 0 and ``i`` is the PCA rank).
    ``kg_bound`` is NaN where no estimate applies.
    """

    i: np.ndarray
    k: np.ndarray
    floats: np.ndarray
    rate: np.ndarray
    kg: np.ndarray
    kg_bound: np.ndarray

    def __len__(self) -> int:
        return len(self.rate)


def stored_floats(
    i: np.ndarray | int, k: np.ndarray | int, vertices: int, frames: int
) -> np.ndarray:
    """S = i*K + 9 + k*F + 3*i*k: the floats of U1 (K x i), U2 (3 x 3), U3 (F x k), core."""
    return (
        np.asarray(i, dtype=np.int64) * vertices
        + 9
        + np.asarray(k, dtype=np.int64) * frames
        + (3 * np.asarray(i, dtype=np.int64) * np.asarray(k, dtype=np.int64))
    )


class Analysis:
    """The exact rate-distortion table of a mesh sequence. Build it with :func:`analyze`.

    Ranks are counts of kept columns: ``1 <= i <= max_ranks[0]``, ``1 <= k <= max_ranks[1]``.
    """

    def __init__(self, decomposition: HOSVD, centroids: np.ndarray) -> None:
        self.decomposition = decomposition
        self.centroids = centroids
        k_vertices, _, frames = decomposition.shape
        self.vertex_count = k_vertices
        self.frame_count = frames
        energy = decomposition.core_energy
        # The KG denominator: the tensor is centred per frame, so ||T - E(T)|| = ||T|| = ||C||.
        self.total_energy = float(energy.sum())
        if self.total_energy == 0.0:
            raise InputError(
                "the KG error is undefined: every frame collapses to a single point, so the "
                "Karni-Gotsman denominator is zero"
            )
        self._error2 = discarded_energy(energy)
        self._kg = 100.0 * np.sqrt(self._error2 / self.total_energy)
        bound2 = _bound_energy(decomposition.mode1_energy, decomposition.mode3_energy)
        self._kg_bound = 100.0 * np.sqrt(np.minimum(bound2, self.total_energy) / self.total_energy)
        for table in (self._error2, self._kg, self._kg_bound):
            table.flags.writeable = False  # handed out by the *_table methods, never copied
        r1, r3 = decomposition.max_ranks
        ii, kk = np.meshgrid(np.arange(r1 + 1), np.arange(r3 + 1), indexing="ij")
        self._floats = stored_floats(ii, kk, k_vertices, frames)

    # ----- single entries -------------------------------------------------------------------
    @property
    def max_ranks(self) -> tuple[int, int]:
        """(R1, R3) = (min(K, 3F), min(F, 3K)): the largest ranks with any meaning."""
        return self.decomposition.max_ranks

    def _check(self, i: int, k: int) -> None:
        r1, r3 = self.max_ranks
        if not (1 <= i <= r1 and 1 <= k <= r3):
            raise ValueError(
                f"ranks must satisfy 1 <= i <= {r1} and 1 <= k <= {r3}, got ({i}, {k})"
            )

    def kg(self, i: int, k: int) -> float:
        """Exact KG error of the truncation (i, 3, k), in percent."""
        self._check(i, k)
        return float(self._kg[i, k])

    def kg_bound(self, i: int, k: int) -> float:
        """The paper's estimate of the KG error of (i, 3, k): an upper bound."""
        self._check(i, k)
        return float(self._kg_bound[i, k])

    def psi(self, i: int, k: int) -> float:
        """The estimator's error: kg_bound(i, k) - kg(i, k), in KG units."""
        return self.kg_bound(i, k) - self.kg(i, k)

    def floats(self, i: int, k: int) -> int:
        """S(i, k), the paper's count of stored floats."""
        self._check(i, k)
        return int(self._floats[i, k])

    def rate(self, i: int, k: int) -> float:
        """Theta(i, k) = S / (3KF), the paper's reduction rate."""
        return self.floats(i, k) / (3 * self.vertex_count * self.frame_count)

    def choice(self, i: int, k: int) -> RankChoice:
        """Everything known about (i, 3, k)."""
        return RankChoice(
            i, k, self.floats(i, k), self.rate(i, k), self.kg(i, k), self.kg_bound(i, k)
        )

    # ----- whole tables ---------------------------------------------------------------------
    def error_table(self) -> np.ndarray:
        """Squared truncation error ||T - T~||**2 for every kept (i, k), shape (R1+1, R3+1)."""
        return self._error2

    def kg_table(self) -> np.ndarray:
        """Exact KG error of every (i, k), shape (R1+1, R3+1); row/column 0 keep nothing."""
        return self._kg

    def kg_bound_table(self) -> np.ndarray:
        """The paper's estimated KG error of every (i, k), shape (R1+1, R3+1)."""
        return self._kg_bound

    def psi_table(self) -> np.ndarray:
        """kg_bound - kg for every (i, k)."""
        return self.kg_bound_table() - self.kg_table()

    def rate_table(self) -> np.ndarray:
        """Theta of every (i, k), shape (R1+1, R3+1)."""
        return self._floats / (3 * self.vertex_count * self.frame_count)

    # ----- choosing ranks -------------------------------------------------------------------
    def cheapest(self, target_kg: float, *, select: Selection = DEFAULT_SELECTION) -> RankChoice:
        """The (i, 3, k) with the fewest stored floats whose KG error is at most ``target_kg``.

        ``select="exact"`` uses the exact table; ``select="bound"`` uses the paper's estimate
        alone (the seed method), which is never cheaper. Ties in size go to the lower error.
        Raises ``ValueError`` for a target that is not a positive number.
        """
        if not (isinstance(target_kg, (int, float, np.floating)) and np.isfinite(target_kg)):
            raise ValueError(f"target KG error must be a finite number, got {target_kg!r}")
        if target_kg <= 0:
            raise ValueError(f"target KG error must be positive, got {target_kg}")
        judged = self._judged(select)
        # Always feasible: the full ranks (R1, R3) discard nothing, so their error is 0.
        feasible = judged <= target_kg
        feasible[0, :] = False
        feasible[:, 0] = False
        cost = np.where(feasible, self._floats, np.iinfo(np.int64).max)
        candidates = np.argwhere(cost == cost.min())
        errors = judged[candidates[:, 0], candidates[:, 1]]
        i, k = (int(v) for v in candidates[int(np.argmin(errors))])
        return self.choice(i, k)

    def _judged(self, select: Selection) -> np.ndarray:
        """The table ranks are chosen by: the exact KG errors, or the paper's bound."""
        if select not in SELECTIONS:
            raise ValueError(f"select must be 'exact' or 'bound', got {select!r}")
        return self.kg_table() if select == "exact" else self.kg_bound_table()

    def rd_curve(self, *, select: Selection = DEFAULT_SELECTION) -> Curve:
        """The rate-distortion curve (the paper's Algorithm 2): the Pareto front of all
        (i, k), those no other truncation beats in both stored floats and error.

        ``select="bound"`` builds the front from the estimate, as the seed method would; the
        curve still carries the exact error of each point.
        """
        judged = self._judged(select)
        i_grid, k_grid = np.meshgrid(
            np.arange(1, self.max_ranks[0] + 1), np.arange(1, self.max_ranks[1] + 1), indexing="ij"
        )
        ii, kk = i_grid.ravel(), k_grid.ravel()
        floats = self._floats[ii, kk]
        errors = judged[ii, kk]
        order = np.lexsort((errors, floats))  # by size, then by error
        ii, kk, floats, errors = ii[order], kk[order], floats[order], errors[order]
        best_before = np.minimum.accumulate(np.concatenate([[np.inf], errors[:-1]]))
        front = errors < best_before
        ii, kk = ii[front], kk[front]
        return Curve(
            i=ii,
            k=kk,
            floats=self._floats[ii, kk],
            rate=self._floats[ii, kk] / (3 * self.vertex_count * self.frame_count),
            kg=self.kg_table()[ii, kk],
            kg_bound=self.kg_bound_table()[ii, kk],
        )

    def pca_curve(self) -> Curve:
        """The PCA reference (the paper's section 2.4): each centred frame is a row of the
        F x 3K frame unfolding, approximated at rank r by its truncated SVD. The error of
        rank r is exactly the discarded mode-3 energy; the cost is r*(3K + F) floats."""
        energy3 = self.decomposition.mode3_energy
        r = np.arange(1, len(energy3) + 1)
        tail = _tail_sums(energy3)[1:]
        floats = r * (3 * self.vertex_count + self.frame_count)
        return Curve(
            i=r,
            k=np.zeros_like(r),
            floats=floats,
            rate=floats / (3 * self.vertex_count * self.frame_count),
            kg=100.0 * np.sqrt(tail / self.total_energy),
            kg_bound=np.full(len(r), np.nan),
        )

    # ----- the truncated decomposition itself -----------------------------------------------
    def truncate(self, i: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(core, u1, u2, u3)`` of the truncation (i, 3, k): see :meth:`HOSVD.truncate`."""
        self._check(i, k)
        return self.decomposition.truncate(i, k)

    def __repr__(self) -> str:
        r1, r3 = self.max_ranks
        return (
            f"Analysis(frames={self.frame_count}, vertices={self.vertex_count}, "
            f"max_ranks=({r1}, {r3}))"
        )


def analyze(sequence: MeshSequence | np.ndarray) -> Analysis:
    """Remove each frame's centroid, decompose, and tabulate every truncation's error.

    Args:
        sequence: a :class:`MeshSequence`, or positions of shape (frames, vertices, 3).

    Raises:
        InputError: a single frame (nothing moves in time to decompose), or every frame a single
            point (the KG error is undefined).
    """
    vertices = sequence.vertices if isinstance(sequence, MeshSequence) else np.asarray(sequence)
    if vertices.ndim != 3 or vertices.shape[2] != 3:
        raise InputError(f"positions must have shape (frames, vertices, 3), got {vertices.shape}")
    if vertices.shape[0] < 1 or vertices.shape[1] < 1:
        raise InputError(
            f"a sequence needs at least one frame and one vertex, got {vertices.shape}"
        )
    # one pass: the largest |coordinate| is NaN or infinite where a coordinate is
    largest = _max_abs(vertices) if vertices.dtype == np.float64 else None
    if not (np.isfinite(vertices).all() if largest is None else math.isfinite(largest)):
        raise InputError("the positions contain a non-finite coordinate")
    with np.errstate(over="ignore"):
        # the squares sum to at most size * largest**2: summed only where that could overflow
        could_overflow = largest is None or largest * largest * vertices.size > 1e300
        if could_overflow and not np.isfinite(np.square(vertices).sum()):
            raise InputError(
                "the coordinates are too large: their squared norm overflows float64 (rescale them)"
            )
    tensor, centroids = centre_frames(vertices)
    _check_resolvable(vertices, tensor, largest)
    return Analysis(hosvd(tensor), centroids)


#: Below this, squares of coordinates (and so every energy) underflow float64's normal range.
SMALLEST_COORDINATE = 1e-140
#: A shape smaller than this, relative to its distance from the origin, is float64 rounding.
SMALLEST_RELATIVE_SHAPE = 1e-11


def _check_resolvable(
    vertices: np.ndarray, tensor: np.ndarray, largest: float | None = None
) -> None:
    """Refuse positions whose shape float64 cannot resolve, with a message that says why
    (``largest``: the largest |coordinate|, if known)."""
    largest = _max_abs(vertices) if largest is None else largest
    spread = _max_abs(tensor)  # the farthest vertex from its frame's centroid
    if spread == 0.0:
        return  # every frame exactly a point: Analysis names the zero KG denominator
    if largest < SMALLEST_COORDINATE:
        raise InputError(
            f"the coordinates are too small: the largest is {largest:.3g}, and their squares "
            "underflow float64 (rescale them)"
        )
    if spread < SMALLEST_RELATIVE_SHAPE * largest:
        raise InputError(
            f"every frame is a single point to float64's precision: no vertex is farther than "
            f"{spread:.3g} from its frame's centroid, while the coordinates reach {largest:.3g}, "
            "so the shape that the KG error measures is rounding noise"
        )


def _max_abs(values: np.ndarray) -> float:
    """``np.abs(values).max()`` (exact in any order), in one pass without a temporary where
    the compiled core runs."""
    core = native.core()
    if (
        core is not None
        and values.size
        and values.dtype == np.float64
        and values.flags.c_contiguous
    ):
        return float(core.max_abs(values))
    return float(np.abs(values).max())


def _tail_sums(values: np.ndarray) -> np.ndarray:
    """t[n] = sum(values[n:]) for n = 0..len, summed from the small end (no cancellation)."""
    return np.concatenate([np.cumsum(values[::-1])[::-1], [0.0]])


def discarded_energy(energy: np.ndarray) -> np.ndarray:
    """err2[i, k] = sum of energy[a, b] over a >= i or b >= k, for i in 0..R1, k in 0..R3.

    Split as (rows a >= i) + (rows a < i, columns b >= k): both parts are sums of non-negative
    terms, so small errors are not the difference of two large numbers.
    """
    r1, r3 = energy.shape
    row_tails = _tail_sums(energy.sum(axis=1))  # (R1+1,)
    column_tails = np.zeros((r1, r3 + 1))
    column_tails[:, :r3] = np.cumsum(energy[:, ::-1], axis=1)[:, ::-1]
    head_rows = np.zeros((r1 + 1, r3 + 1))
    np.cumsum(column_tails, axis=0, out=head_rows[1:])
    return row_tails[:, None] + head_rows


def _bound_energy(mode1_energy: np.ndarray, mode3_energy: np.ndarray) -> np.ndarray:
    """The paper's bound on the squared error: discarded mode-1 plus discarded mode-3 energy."""
    return _tail_sums(mode1_energy)[:, None] + _tail_sums(mode3_energy)[None, :]
