"""The passes of a segmented encode over the input, one task per segment.

Each task reads its segment's frames a block at a time from a
:class:`~tuckercodec.model.sources.FrameSource` (which it may have been sent, pickled, by an
executor) and returns small results, or one K x r matrix for the sketch. The blocks and the order
of every sum are fixed by the plan, never by the number of workers, so the output is the same
bytes whichever executor runs the tasks.

1. :func:`sketch_segment`: the centroids and energy of every frame, and the segment's part of
   the randomized range finder's sketch Y = sum_t X_t Omega_t (X_t the centred frame, K x 3;
   Omega_t, 3 x r, Gaussian, drawn from the seed and the frame's number, so that it is the same
   whoever draws it).
2. :func:`project_segment`: W_t = Q' X_t for an orthonormal Q (K x r) spanning the sketch: the
   whole sequence in r dimensions, small enough to decompose in memory.
3. :func:`measure_segment`: the squared error of the decoded segment against the input, with
   the decoder's own reconstruction (§8): the closed loop that guarantees the target.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...decomposition.hosvd import centre_frames
from ...format.reconstruction import reconstruct_frames
from ...model.sources import FrameSource
from ..plan import blocks


@dataclass(frozen=True)
class SegmentRange:
    """A task's segment: its frames ``start .. stop - 1`` and how many to read at once."""

    start: int
    stop: int
    block_frames: int


@dataclass(frozen=True)
class Sketch:
    """What the first pass learns of one segment."""

    centroids: np.ndarray  # (n, 3)
    energies: np.ndarray  # (n,): ||X_t||^2 of each centred frame
    sketch: np.ndarray  # (K, r): sum over the segment's frames of X_t Omega_t


def random_test_matrix(frames: range, columns: int, seed: int) -> np.ndarray:
    """Omega for ``frames``, (3n, r) in the row order of a (K, 3, n) block reshaped to (K, 3n):
    row x*n + t is row x of Omega_t. Omega_t depends only on the seed and the frame's number."""
    parts = [np.random.default_rng([seed, frame]).standard_normal((3, columns)) for frame in frames]
    return np.stack(parts, axis=1).reshape(3 * len(frames), columns)


def sketch_segment(
    segment: SegmentRange,
    source: FrameSource,
    columns: int,
    seed: int,
    into: np.ndarray | None = None,
) -> Sketch:
    """Pass 1 over one segment (see the module docstring). The sketch is added ``into`` a
    Fortran-order K x r array when one is given (the caller's running sum, in process: no
    second K x r array), else into a new one that is returned."""
    # imported here: scipy.linalg costs 0.17 s, which every command (and every isolated read's
    # child) would pay at start-up; only a segmented encode needs it
    from scipy.linalg import blas

    centroids, energies = [], []
    # Fortran order: BLAS adds each block's product into it in place (no K x r temporary), and
    # the QR that orthonormalises the sum works on it in place too
    sketch = np.zeros((source.vertex_count, columns), order="F") if into is None else into
    for start, stop in blocks(segment.start, segment.stop, segment.block_frames):
        tensor, block_centroids = centre_frames(source.read(start, stop))
        count = stop - start
        centroids.append(block_centroids)
        energies.append(np.einsum("vxt,vxt->t", tensor, tensor))
        flat = tensor.reshape(tensor.shape[0], 3 * count)
        if columns == 0:  # only the centroids and energies are wanted
            continue
        omega = random_test_matrix(range(start, stop), columns, seed)
        # sketch += flat @ omega, as BLAS's C = A B + C on the transposed views
        blas.dgemm(1.0, flat.T, omega.T, beta=1.0, c=sketch, trans_a=1, trans_b=1, overwrite_c=1)
    return Sketch(np.concatenate(centroids), np.concatenate(energies), sketch)


def project_segment(
    job: tuple[SegmentRange, np.ndarray | None],
    source: FrameSource,
    shared_basis: np.ndarray | None,
) -> np.ndarray:
    """Pass 2 over one segment: Q' X_t for each frame, (r, 3, n), with the segment's own Q if
    the job carries one, else the shared Q."""
    segment, own_basis = job
    basis = own_basis if own_basis is not None else shared_basis
    assert basis is not None  # every segment has a basis, its own or the shared one
    parts = []
    for start, stop in blocks(segment.start, segment.stop, segment.block_frames):
        tensor, _ = centre_frames(source.read(start, stop))
        count = stop - start
        parts.append((basis.T @ tensor.reshape(tensor.shape[0], 3 * count)).reshape(-1, 3, count))
    return np.concatenate(parts, axis=2)


@dataclass(frozen=True)
class DecodedSegment:
    """One segment's dequantized factors, as a decoder will have them (§6.3, §8), and the
    segment they reconstruct."""

    segment: SegmentRange
    basis: np.ndarray  # CORE x2 U2, (i, 3, k)
    u3: np.ndarray  # (n, k)
    centroids: np.ndarray  # (n, 3)
    own_u1: np.ndarray | None  # (K, i) for a segment with its own basis, else None


def measure_segment(
    decoded: DecodedSegment, source: FrameSource, shared_u1: np.ndarray | None
) -> float:
    """Pass 3 over one segment: ||decoded - input||^2, reconstructing a block of frames at a
    time exactly as the decoder does (§8): the leading i columns of the shared U1, or the
    segment's own."""
    total = 0.0
    segment = decoded.segment
    i = decoded.basis.shape[0]
    if decoded.own_u1 is not None:
        used = decoded.own_u1
    else:
        assert shared_u1 is not None  # a segment without its own basis uses the shared one
        used = shared_u1[:, :i]
    for start, stop in blocks(segment.start, segment.stop, segment.block_frames):
        rows = slice(start - segment.start, stop - segment.start)
        difference = reconstruct_frames(
            used, decoded.basis, decoded.u3[rows], decoded.centroids[rows]
        )
        difference -= source.read(start, stop)
        flat = difference.reshape(-1)
        total += float(flat @ flat)
    return total
