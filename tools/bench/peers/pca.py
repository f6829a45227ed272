"""The seed paper's section 2.4 baseline: PCA of the F x 3K matrix of centred frames, given this
codec's quantization (one parameter D; per-entry noise D/12, steps scaled by the singular values)
and packing (zigzag, byte planes, zstd 19, mesh prediction of the basis vectors, time prediction
of the coefficients), in this codec's container, with the same search of the
truncation/quantization split on real bytes."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from tools.bench.peers.base import Context, Trial, timed_trial
from tools.common import resident_peak
from tuckercodec import MeshSequence, internal

#: Shares of the squared error budget left to quantization, as in tuckercodec's encoder.
PCA_SHARES = (0.1, 0.2, 0.3, 0.45, 0.6, 0.75)


class _PcaModel:
    """The PCA of the F x 3K matrix of centred frames, and its quantized, packed form."""

    def __init__(self, sequence: MeshSequence, context: Context) -> None:
        self.sequence = sequence
        self.context = context
        frames, vertices = sequence.frame_count, sequence.vertex_count
        matrix = context.tensor.transpose(2, 0, 1).reshape(frames, 3 * vertices)
        left, self.sigma, right_t = np.linalg.svd(matrix, full_matrices=False)
        self.coefficients = left * self.sigma[None, :]  # F x r: frame f = sum_j A[f, j] * basis_j
        self.basis = right_t  # r x 3K, orthonormal rows
        energy = self.sigma**2
        # tails[r]: the squared error of rank r
        self.tails = np.concatenate([np.cumsum(energy[::-1])[::-1], [0.0]])
        # the same connectivity codec and mesh prediction as tuckercodec's (format 1.2)
        self.mesh = internal.mesh_prediction(sequence.faces, vertices)
        self.parents = self.mesh.parents
        self.faces = internal.faces.encode_face_section(sequence.faces, vertices)

    def quantize(self, rank: int, step: float) -> tuple[internal.qmat.QuantizedMatrix, ...]:
        root = math.sqrt(step)
        vertices = self.sequence.vertex_count
        sigma = np.maximum(self.sigma[:rank], np.finfo(float).tiny)
        # each basis vector as three columns (x, y, z) of a K-row matrix, predicted over the mesh
        basis = (
            self.basis[:rank]
            .reshape(rank, vertices, 3)
            .transpose(1, 0, 2)
            .reshape(vertices, 3 * rank)
        )
        basis_q = internal.qmat.quantize(basis, np.repeat(root / sigma, 3))
        coefficients_q = internal.qmat.quantize(self.coefficients[:, :rank], np.full(rank, root))
        centroids_q = internal.qmat.quantize(
            self.context.centroids, np.full(3, root / math.sqrt(vertices))
        )
        return basis_q, coefficients_q, centroids_q

    def positions(self, rank: int, basis_q, coefficients_q, centroids_q) -> np.ndarray:
        vertices = self.sequence.vertex_count
        basis = (
            basis_q.values()
            .reshape(vertices, rank, 3)
            .transpose(1, 0, 2)
            .reshape(rank, 3 * vertices)
        )
        frames = coefficients_q.values() @ basis
        return frames.reshape(-1, vertices, 3) + centroids_q.values()[:, None, :]

    def pack(self, rank: int, parts, level: int) -> bytes:
        basis_q, coefficients_q, centroids_q = parts
        face = self.faces
        known = internal.sections.entry  # the entry of a section this codec defines
        qmat_entry = {"critical": True, "codec": internal.sections.QMAT}  # PCA's own sections
        centroid_params, centroid_payload = internal.qmat.encode_matrix(
            centroids_q, None, level=level
        )
        sections = [
            (known("FACE", face.params, face.codec), face.payload),
            (known("CENT", centroid_params), centroid_payload),
        ]
        for section_id, matrix, parents in (
            ("COEF", coefficients_q, None),
            ("BASE", basis_q, self.mesh),
        ):
            params, payload = internal.qmat.encode_matrix(matrix, parents, level=level)
            sections.append(({"id": section_id, **qmat_entry, **params}, payload))
        header = {
            "vertices": self.sequence.vertex_count,
            "frames": self.sequence.frame_count,
            "pca_rank": rank,
            # the module's old name, kept: the string is part of every PCA file measured, so
            # another would change the sizes BENCHMARKS.md gives
            "encoder": "tools/peers.py PCA baseline",
        }
        return internal.pack_container(header, sections)

    def unpack(self, data: bytes) -> np.ndarray:
        """Decode a file written by :meth:`pack` from its bytes alone (CRCs checked)."""
        container = internal.parse_container(data)
        rank = container.header["pca_rank"]

        def matrix(section_id: str, parents: Any) -> internal.qmat.QuantizedMatrix:
            entry = container.section(section_id)
            assert entry is not None, f"pack() writes a {section_id} section"
            return internal.qmat.decode_matrix(
                container.payload(data, entry),
                entry.params,
                parents,
                section_id,
                coding_tools=container.coding_tools,  # predictors 2 and 3 (format 1.2)
            )

        return self.positions(
            rank, matrix("BASE", self.mesh), matrix("COEF", None), matrix("CENT", None)
        )

    def encode(self, target: float) -> bytes:
        """The smallest file found whose decoded KG error is at most ``target``."""
        limit2 = (target / 100.0 * self.context.centred_norm) ** 2 * (1 - 1e-9)
        vertices, frames = self.sequence.vertex_count, self.sequence.frame_count
        best: tuple[int, int, float] | None = None  # (bytes at the search level, rank, step)
        for share in PCA_SHARES:
            rank = int(np.argmax(self.tails <= (1 - share) * limit2))
            room = limit2 - self.tails[rank]
            if rank == 0 or room <= 0:
                continue
            step = 12.0 * room / (3 * vertices * rank + frames * rank + 3 * frames)
            rank, step, parts = self._meet(rank, step, limit2)
            size = len(self.pack(rank, parts, internal.streams.SEARCH_LEVEL))
            if best is None or size < best[0]:
                best = (size, rank, step)
        if best is None:
            raise ValueError(f"PCA cannot meet KG {target} (the target is within rounding of zero)")
        _, rank, step = best
        return self.pack(rank, self.quantize(rank, step), internal.streams.DEFAULT_LEVEL)

    def _meet(self, rank: int, step: float, limit2: float):
        """Shrink D until the decoded squared error is within ``limit2``."""
        original = self.sequence.vertices
        for _ in range(40):
            parts = self.quantize(rank, step)
            error2 = float(np.square(self.positions(rank, *parts) - original).sum())
            if error2 <= limit2:
                return rank, step, parts
            room = limit2 - self.tails[rank]
            added = max(error2 - self.tails[rank], 1e-300)
            step *= min(0.95, max(0.25, 0.97 * room / added))
        raise ValueError("PCA could not meet the error target")  # pragma: no cover


def run_pca(sequence: MeshSequence, targets: list[float], context: Context) -> list[Trial]:
    # The SVD is the same for every target: made once, its time added to every encode's, and
    # its peak memory taken into every trial's.
    with resident_peak() as memory:
        start = time.perf_counter()
        model = _PcaModel(sequence, context)
        svd_seconds = time.perf_counter() - start

    def trial_at(target: float) -> Trial:
        def encode() -> tuple[bytes, int, bytes]:
            data = model.encode(target)
            return data, len(model.faces[1]), data

        trial = timed_trial(
            "pca", f"KG<={target:g}", encode, lambda data: model.unpack(data), target
        )
        trial.setup_seconds = svd_seconds
        if trial.peak_bytes is not None and memory["peak"] is not None:
            trial.peak_bytes = max(trial.peak_bytes, memory["peak"])
        return trial

    return [trial_at(target) for target in targets]
