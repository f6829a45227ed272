"""Higher-order SVD of a centred mesh sequence, computed for the exact error of every truncation.

The sequence is the tensor T of shape (K, 3, F): vertices, xyz, frames, each frame's centroid
removed. The HOSVD (the seed paper's Algorithm 1) gives orthonormal factors U1 (K x R1),
U2 (3 x 3), U3 (F x R3) and the core C = T x1 U1' x2 U2' x3 U3'. Because the factors are
orthonormal, the squared error of keeping ranks (i, 3, k) is exactly the energy of the core
outside the block C[:i, :, :k], so one decomposition gives the error of every truncation.

How it is computed, and why (see ../shared/NOTES.md for the measurements):

* Mode 1 is never decomposed in K dimensions. The eigenvectors V of the small Gram matrix
  X1'X1 (3F x 3F) are the right singular vectors of the mode-1 unfolding X1, and U1'X1 =
  diag(s) V', so the core needs no U1 at all. Columns of U1 are formed only for the ranks a
  caller asks for, and are re-orthonormalised then.
* The Gram matrix squares the condition number: its entries, and so its eigenvalues and the
  core rows diag(s) V' derived from them, are accurate only to eps * s_max**2 in absolute
  terms, which spoils the error of good approximations. So Z = X1 V is formed once more, and
  its own Gram matrix Z'Z, which is graded (entries scale as s_a * s_b) and keeps small
  energies to full relative precision, is Cholesky-factored: Z'Z = L L'. Then U1 = Z L^-T is
  orthonormal, its leading i columns span the same space as those of Z, and the core rows are
  exactly U1' X1 = L' V'. Measured against explicit reconstructions this is as accurate as a
  QR-based SVD (1e-13 relative at KG 0.01) for one extra Gram-sized product.
* When K < 3F the roles swap: the K x K Gram matrix gives U1 directly and the core rows are
  computed explicitly.
* Mode 3 uses the F x F Gram matrix, whose eigenvectors are orthonormal to machine precision;
  its energies are re-measured the same way.

All arithmetic is float64.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# Rows of X1 processed at once when measuring energies: bounds the scratch memory to
# ROW_BLOCK * 3F floats instead of a second copy of the tensor.
ROW_BLOCK = 4096

# Energies below this fraction of the largest are float64 rounding noise of the data itself.
NOISE_FLOOR = 1e-14


def centre_frames(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Remove each frame's centroid.

    Args:
        vertices: (F, K, 3) positions.

    Returns:
        ``(tensor, centroids)``: the centred tensor T of shape (K, 3, F), C-contiguous float64,
        and the centroids, (F, 3), such that ``vertices[f] == tensor[:, :, f] + centroids[f]``.
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    frames, count, _ = vertices.shape
    # A batched matrix product sums over the K vertices far faster than mean(axis=1).
    centroids = np.matmul(np.full((frames, 1, count), 1.0 / count), vertices)[:, 0, :]
    tensor = np.empty((count, 3, frames))
    np.subtract(vertices.transpose(1, 2, 0), centroids.T[None], out=tensor)
    return tensor, centroids


@dataclass(frozen=True, eq=False)
class HOSVD:
    """The HOSVD of a centred tensor, stored compactly enough to give every truncation.

    Attributes:
        tensor: T, (K, 3, F).
        u2: the mode-2 factor, (3, 3).
        u3: the mode-3 (time) factor, (F, R3), orthonormal columns.
        mode1_energy: energy of each mode-1 core row, (R1,): the squared singular values of
            the mode-1 unfolding up to rounding; sums of its tails are the discarded energies.
        mode3_energy: squared singular values of the mode-3 unfolding, descending, (R3,).
        core_energy: E[a, b], the squared core summed over mode 2, (R1, R3). Mode 2 is always
            kept whole, and the sum over it does not depend on U2.
    """

    tensor: np.ndarray
    u2: np.ndarray
    u3: np.ndarray
    mode1_energy: np.ndarray
    mode3_energy: np.ndarray
    core_energy: np.ndarray
    # How U1 is obtained: either its columns directly (K < 3F), or the right singular
    # vectors of X1 from which any leading columns of U1 can be formed (K >= 3F).
    _u1: np.ndarray | None
    _v1: np.ndarray | None

    @property
    def shape(self) -> tuple[int, int, int]:
        """(K, 3, F)."""
        k, three, f = self.tensor.shape
        return k, three, f

    @property
    def max_ranks(self) -> tuple[int, int]:
        """(R1, R3): the largest meaningful mode-1 and mode-3 ranks."""
        r1, r3 = self.core_energy.shape
        return r1, r3

    def u1(self, rank: int) -> np.ndarray:
        """The leading ``rank`` columns of U1, (K, rank), orthonormal to machine precision."""
        r1, _ = self.max_ranks
        if not 0 <= rank <= r1:
            raise ValueError(f"mode-1 rank must be in 0..{r1}, got {rank}")
        if self._u1 is not None:
            return self._u1[:, :rank].copy()
        assert self._v1 is not None  # one of the two is always set (see hosvd())
        k, _, f = self.shape
        x1 = self.tensor.reshape(k, 3 * f)
        scale = np.sqrt(self.mode1_energy[:rank])
        scale[scale == 0] = 1.0
        columns = (x1 @ self._v1[:, :rank]) / scale
        # Columns from tiny singular values carry rounding noise; orthonormalising them keeps
        # the leading ones (and their signs: R's diagonal is positive).
        return orthonormal_columns(columns)

    def truncate(self, i: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The truncated decomposition with ranks (i, 3, k).

        Returns:
            ``(core, u1, u2, u3)`` with core (i, 3, k) the orthogonal projection of T onto the
            factors: ``T ~ core x1 u1 x2 u2 x3 u3``.
        """
        r1, r3 = self.max_ranks
        if not (1 <= i <= r1 and 1 <= k <= r3):
            raise ValueError(f"ranks must be in 1..{r1} and 1..{r3}, got ({i}, {k})")
        u1 = self.u1(i)
        u3 = self.u3[:, :k].copy()
        core = project(self.tensor, u1, self.u2, u3)
        return core, u1, self.u2.copy(), u3


#: Cholesky QR's result is accepted when Q'Q is this close to the identity (entrywise).
ORTHONORMAL_TOLERANCE = 1e-13


def orthonormal_columns(columns: np.ndarray) -> np.ndarray:
    """Q of the thin QR factorisation of ``columns`` with R's diagonal positive.

    Cholesky QR twice (R from the Cholesky factor of the Gram matrix, then once more on the
    result) costs two Gram matrices and two triangular solves, all level-3 BLAS, about a
    third of Householder QR's time on a tall U1 (samba's 9,971 x 363: 0.33 s -> 0.1 s). Its
    columns are orthonormal to rounding when the columns are not nearly dependent, which
    holds for X1 V / s (orthogonal in exact arithmetic); a noise column that breaks the
    Cholesky factorisation, or a result further than :data:`ORTHONORMAL_TOLERANCE` from
    orthonormal, falls back to Householder QR.
    """
    import scipy.linalg  # here: 0.2-0.4 s at start-up that every command would pay

    q = columns
    try:
        for _ in range(2):
            gram = q.T @ q
            upper = np.linalg.cholesky(gram).T  # R, with a positive diagonal
            q = scipy.linalg.solve_triangular(upper, q.T, trans="T", lower=False).T
        check = q.T @ q
        np.fill_diagonal(check, np.diag(check) - 1.0)
        if q.size and np.abs(check).max() <= ORTHONORMAL_TOLERANCE:
            return np.ascontiguousarray(q)
    except np.linalg.LinAlgError:
        pass
    q, r = np.linalg.qr(columns)
    signs = np.sign(np.diag(r))
    signs[signs == 0] = 1.0
    return np.asarray(q * signs)


def project(tensor: np.ndarray, u1: np.ndarray, u2: np.ndarray, u3: np.ndarray) -> np.ndarray:
    """The core T x1 u1' x2 u2' x3 u3' for orthonormal factors."""
    k, _, f = tensor.shape
    reduced = (u1.T @ tensor.reshape(k, 3 * f)).reshape(-1, 3, f)  # i, 3, F
    reduced = reduced @ u3  # i, 3, k
    return np.einsum("acb,cd->adb", reduced, u2)


def reconstruct(core: np.ndarray, u1: np.ndarray, u2: np.ndarray, u3: np.ndarray) -> np.ndarray:
    """The tensor core x1 u1 x2 u2 x3 u3, shape (K, 3, F)."""
    small = np.einsum("adb,cd->acb", core, u2) @ u3.T  # i, 3, F
    i, _, f = small.shape
    return (u1 @ small.reshape(i, 3 * f)).reshape(u1.shape[0], 3, f)


def hosvd(tensor: np.ndarray) -> HOSVD:
    """Decompose a centred (K, 3, F) tensor. See the module docstring for the method."""
    tensor = np.ascontiguousarray(tensor, dtype=np.float64)
    _, three, f = tensor.shape
    if three != 3:
        raise ValueError(f"expected a (K, 3, F) tensor, got {tensor.shape}")

    u3, mode3_energy = _mode3(tensor)
    u2 = _mode2(tensor)
    u1, v1, mode1_energy, rows = _mode1(tensor)

    # Core energy summed over mode 2: sum_c (Y[a, c, :] @ u3[:, b])**2, Y the mode-1 core rows.
    r1, r3 = rows.shape[0], u3.shape[1]
    projected = (rows.reshape(r1 * 3, f) @ u3).reshape(r1, 3, r3)
    core_energy = np.square(projected).sum(axis=1)
    return HOSVD(tensor, u2, u3, mode1_energy, mode3_energy, core_energy, u1, v1)


def _descending_eigh(gram: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    values, vectors = np.linalg.eigh(gram)
    return np.clip(values[::-1], 0.0, None), np.ascontiguousarray(vectors[:, ::-1])


def _column_energy(matrix: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """||matrix @ basis[:, j]||**2 for every j, by row blocks to bound memory."""
    energy = np.zeros(basis.shape[1])
    for start in range(0, matrix.shape[0], ROW_BLOCK):
        block = matrix[start : start + ROW_BLOCK] @ basis
        energy += np.square(block, out=block).sum(axis=0)
    return energy


def _sort_by_energy(energy: np.ndarray, *arrays: np.ndarray) -> list[np.ndarray]:
    """Re-measured energies can swap order among near-equal values; keep them descending."""
    order = np.argsort(-energy, kind="stable")
    return [energy[order]] + [a[:, order] for a in arrays]


def _mode3(tensor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """U3 (F x R3) and the mode-3 energies, R3 = min(F, 3K)."""
    k, _, f = tensor.shape
    frames_as_columns = tensor.reshape(3 * k, f)  # X3 transposed, a free view
    if f <= 3 * k:
        _, u3 = _descending_eigh(frames_as_columns.T @ frames_as_columns)
    else:
        # More frames than coordinates (tiny meshes): the thin SVD is cheap and exact here.
        u3 = np.linalg.svd(frames_as_columns.T, full_matrices=False)[0]
    energy = _column_energy(frames_as_columns, u3)
    energy, u3 = _sort_by_energy(energy, u3)
    return np.ascontiguousarray(u3), energy


def _mode2(tensor: np.ndarray) -> np.ndarray:
    """U2 (3 x 3) from the 3 x 3 Gram matrix of the mode-2 unfolding."""
    gram = np.einsum("kcf,kdf->cd", tensor, tensor)
    return _descending_eigh(gram)[1]


def _mode1(
    tensor: np.ndarray,
) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray, np.ndarray]:
    """Mode-1 energies and the core rows U1' X1, (R1, 3F); plus U1 itself or V1 to form it."""
    k, _, f = tensor.shape
    x1 = tensor.reshape(k, 3 * f)
    if k < 3 * f:
        _, u1 = _descending_eigh(x1 @ x1.T)
        rows = u1.T @ x1
        energy = np.einsum("aj,aj->a", rows, rows)
        order = np.argsort(-energy, kind="stable")
        return np.ascontiguousarray(u1[:, order]), None, energy[order], rows[order]

    _, v1 = _descending_eigh(x1.T @ x1)
    # Z = X1 V has orthogonal columns of norms s_a in exact arithmetic. Its own Gram matrix
    # M = Z'Z is graded (entries scale as s_a * s_b), so unlike X1'X1 it keeps small energies
    # to full relative precision. With M = L L' (Cholesky), U1 = Z L^-T is orthonormal, spans
    # the same leading columns as Z, and the core rows are U1' X1 = L' V'.
    gram_z = _gram_of_product(x1, v1)
    energy = np.diag(gram_z).copy()
    order = np.argsort(-energy, kind="stable")
    v1, gram_z = v1[:, order], gram_z[np.ix_(order, order)]
    rows = _rows_from_graded_gram(gram_z, v1)
    return None, np.ascontiguousarray(v1), np.square(rows).sum(axis=1), rows


def _gram_of_product(matrix: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """(matrix @ basis)' (matrix @ basis), by row blocks to bound memory."""
    gram = np.zeros((basis.shape[1], basis.shape[1]))
    for start in range(0, matrix.shape[0], ROW_BLOCK):
        block = matrix[start : start + ROW_BLOCK] @ basis
        gram += block.T @ block
    return gram


def _rows_from_graded_gram(gram_z: np.ndarray, v1: np.ndarray) -> np.ndarray:
    """Core rows L' V' from the graded Gram matrix of Z = X1 V (see :func:`_mode1`).

    Columns whose energy is below 1e-14 of the largest (rounding noise of float64 data) are
    left out of the Cholesky factorisation, which they could break; their rows are taken from
    the eigenvectors of what remains of them once the leading columns are projected out.
    """
    n = gram_z.shape[0]
    energy = np.diag(gram_z)
    head = int(np.sum(energy > NOISE_FLOOR * energy[0])) if n and energy[0] > 0 else 0
    rows = np.zeros((n, v1.shape[0]))
    while head > 0:
        try:
            lower = np.linalg.cholesky(gram_z[:head, :head])
            break
        except np.linalg.LinAlgError:  # not positive definite to rounding: shrink the head
            head = head * 9 // 10
    if head == 0:
        lower = np.zeros((0, 0))
    coupling = np.linalg.solve(lower, gram_z[:head, head:]) if head else np.zeros((0, n))
    rows[:head] = lower.T @ v1[:, :head].T + coupling @ v1[:, head:].T
    if head < n:
        remainder = gram_z[head:, head:] - coupling.T @ coupling
        mu, w = _descending_eigh(remainder)
        rows[head:] = np.sqrt(mu)[:, None] * (w.T @ v1[:, head:].T)
    return rows
