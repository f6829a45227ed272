"""A field's Tucker decomposition (§6.13 mode tucker) and the exact error of its truncations.

The positions' HOSVD (:mod:`..decomposition.hosvd`) generalised to c components: the field
less each frame's per-component mean over the elements is the tensor T (N, c, F); its factors
U1 (N x R1), U2 (c x c) and U3 (F x R3) come from the Gram matrices of its unfoldings, and,
the factors being orthonormal, the squared error of keeping ranks (i, c, k) is the energy of
T less that of the core block C[:i, :, :k]. Mode 2 is always kept whole.

Energies come from the Gram matrices, accurate to about 1e-16 of the largest: enough for the
relative errors a field is given (the encoder measures the decoded field anyway).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..decomposition.hosvd import orthonormal_columns


def _descending_eigh(gram: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    values, vectors = np.linalg.eigh(gram)
    return np.clip(values[::-1], 0.0, None), np.ascontiguousarray(vectors[:, ::-1])


@dataclass(eq=False)
class FieldDecomposition:
    """The HOSVD of a field's centred tensor, kept compactly enough to give every truncation.

    Attributes:
        tensor: T, (N, c, F).
        mean: each frame's per-component mean, (F, c).
        u2: (c, c); u3: (F, R3), orthonormal columns.
        captured: captured[a, b], the energy of the core block C[:a+1, :, :b+1].
        energy: ||T||**2.
    """

    tensor: np.ndarray
    mean: np.ndarray
    u2: np.ndarray
    u3: np.ndarray
    captured: np.ndarray
    energy: float
    _u1: np.ndarray | None  # U1's columns (N < cF), or
    _v1: np.ndarray | None  # the right singular vectors of X1 that form them
    _s1: np.ndarray  # the singular values of X1
    _formed: tuple[np.ndarray, np.ndarray] | None = None  # U1 and the core, largest ranks

    @property
    def max_ranks(self) -> tuple[int, int]:
        r1, r3 = self.captured.shape
        return r1, r3

    def truncation_error2(self, i: int, k: int) -> float:
        """The squared error of the truncation to ranks (i, c, k), unquantized."""
        return max(0.0, self.energy - float(self.captured[i - 1, k - 1]))

    def u1(self, rank: int) -> np.ndarray:
        """The leading ``rank`` columns of U1, (N, rank)."""
        if self._u1 is not None:
            return self._u1[:, :rank].copy()
        assert self._v1 is not None
        n, c, f = self.tensor.shape
        scale = self._s1[:rank].copy()
        scale[scale == 0] = 1.0
        return orthonormal_columns((self.tensor.reshape(n, c * f) @ self._v1[:, :rank]) / scale)

    def factors(self, i: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """U1 (N, i), U3 (F, k) and the core (i, c, k) projected onto them.

        U1's leading columns and the projection are the same for every rank, so they are
        formed once for the largest ranks asked for and sliced after (ask for the largest
        first: :meth:`prepare`)."""
        if self._formed is None or i > self._formed[0].shape[1] or k > self._formed[1].shape[2]:
            top_i = max(i, 0 if self._formed is None else self._formed[0].shape[1])
            top_k = max(k, 0 if self._formed is None else self._formed[1].shape[2])
            n, c, f = self.tensor.shape
            u1 = self.u1(top_i)
            reduced = (u1.T @ self.tensor.reshape(n, c * f)).reshape(top_i, c, f)
            reduced = reduced @ self.u3[:, :top_k]  # (i, c, k)
            self._formed = (u1, np.einsum("adb,dx->axb", reduced, self.u2))
        u1, core = self._formed
        return u1[:, :i], self.u3[:, :k].copy(), np.ascontiguousarray(core[:i, :, :k])

    def prepare(self, choices: list[tuple[int, int]]) -> None:
        """Form the factors once for the largest of ``choices``."""
        if choices:
            self.factors(max(i for i, _ in choices), max(k for _, k in choices))


def centred(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(T, mean)``: the field (F, N, c) less each frame's per-component mean, as (N, c, F)
    float64, and the means (F, c)."""
    values = np.asarray(values, dtype=np.float64)
    frames, count, _ = values.shape
    # a batched product sums over the N elements faster than mean(axis=1)
    mean = np.matmul(np.full((frames, 1, count), 1.0 / count), values)[:, 0, :]
    tensor = np.ascontiguousarray((values - mean[:, None, :]).transpose(1, 2, 0))
    return tensor, mean


def decompose(values: np.ndarray) -> FieldDecomposition:
    """The HOSVD of a field (F, N, c)."""
    tensor, mean = centred(values)
    n, c, f = tensor.shape
    x3 = tensor.reshape(n * c, f)  # frames as columns
    if f <= n * c:
        _, u3 = _descending_eigh(x3.T @ x3)
    else:
        u3 = np.linalg.svd(x3.T, full_matrices=False)[0]
    u2 = _descending_eigh(np.einsum("ncf,ndf->cd", tensor, tensor))[1]
    x1 = tensor.reshape(n, c * f)
    u1: np.ndarray | None = None
    v1: np.ndarray | None = None
    if n < c * f:
        energy1, u1 = _descending_eigh(x1 @ x1.T)
        rows = u1.T @ x1  # the core rows U1' X1
    else:
        energy1, v1 = _descending_eigh(x1.T @ x1)
        rows = np.sqrt(energy1)[:, None] * v1.T  # U1' X1 = S V'
    r1 = rows.shape[0]
    projected = (rows.reshape(r1 * c, f) @ u3).reshape(r1, c, u3.shape[1])
    core_energy = np.square(projected).sum(axis=1)
    captured = core_energy.cumsum(axis=0).cumsum(axis=1)
    return FieldDecomposition(
        tensor,
        mean,
        u2,
        np.ascontiguousarray(u3),
        captured,
        float(np.square(tensor).sum()),
        u1,
        v1,
        np.sqrt(energy1),
    )


def cheapest_ranks(decomposition: FieldDecomposition, limit2: float) -> tuple[int, int]:
    """The ranks (i, k) whose truncation error is within ``limit2`` with the fewest stored
    values N*i + F*k + c*i*k (the full ranks when none is)."""
    n, c, f = decomposition.tensor.shape
    r1, r3 = decomposition.max_ranks
    error2 = decomposition.energy - decomposition.captured
    i = np.arange(1, r1 + 1)[:, None]
    k = np.arange(1, r3 + 1)[None, :]
    cost = (n * i + f * k + c * i * k).astype(np.float64)
    cost[error2 > limit2] = np.inf
    if not np.isfinite(cost).any():
        return r1, r3
    a, b = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return int(a) + 1, int(b) + 1
