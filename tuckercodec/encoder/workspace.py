"""One trial of the encoder's search: a truncation quantized with the single parameter D.

:class:`Workspace` holds the input, its analysis and everything every trial shares (the mesh
parents, the coded faces and names); :meth:`Workspace.quantize` turns ranks (i, k) and D into
the integers a file stores, :meth:`Workspace.decoded_error2` measures what a decoder will return
(with the format's own reconstruction, §8), and :meth:`Workspace.pack` makes the file. The
package docstring (:mod:`tuckercodec.encoder`) says how D sets every step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._version import __version__
from ..analysis import Analysis
from ..errors import UnreachableTargetError
from ..format import faces, names, qmat, sections, streams
from ..format.container import pack_container
from ..format.header import header_map
from ..format.qmat import QuantizedMatrix
from ..format.reconstruction import reconstruct_frames, reconstruction_basis
from ..hosvd import project
from ..sequence import MeshSequence
from ..topology import MeshPrediction
from . import rdo

#: The largest |integer| a section may stream: after zigzag it must fit streams.MAX_PLANES bytes.
LARGEST_STREAMED = 2 ** (8 * streams.MAX_PLANES - 1) - 1
#: Bytes of positions reconstructed at once when measuring the error: bounds the memory.
BLOCK_BYTES = 2 << 20


@dataclass
class Quantized:
    """One quantization of one truncation: everything the file stores but the faces."""

    i: int
    k: int
    step: float  # D
    u1: QuantizedMatrix
    u3: QuantizedMatrix
    core: QuantizedMatrix
    centroids: QuantizedMatrix


class Workspace:
    """The input, its analysis and the parts shared by every trial of the search."""

    def __init__(self, sequence: MeshSequence, analysis: Analysis, level: int) -> None:
        self.sequence = sequence
        self.analysis = analysis
        self.level = level
        self.vertex_count = sequence.vertex_count
        self.frame_count = sequence.frame_count
        # The KG denominator: each frame is centred, so ||A - E(A)|| is the centred tensor's norm.
        self.denominator2 = analysis.total_energy
        # U1's predictors: the mesh parents (1) and the decoded neighbours' mean (2)
        self.mesh = MeshPrediction(sequence.faces, self.vertex_count)
        self.parents = self.mesh.parents
        # the smaller connectivity codec; faces-traverse reorders the faces (§6.8)
        face = faces.encode_face_section(sequence.faces, self.vertex_count, level)
        self.face_codec = face.codec
        self.face_section = (face.params, face.payload)
        self.name_section = names.encode_names(sequence.frame_names, level)
        self.centroid_floor_step, self.centroid_floor_error2 = self._centroid_floor()
        self._u1 = np.zeros((self.vertex_count, 0))
        self._core = np.zeros((0, 3, 0))
        # how factors are rounded (rdo.py); the prediction trees it needs are made on first use
        self.rdo = rdo.DEFAULT
        self._u1_levels: rdo.Levels | None = None

    def truncation_error2(self, i: int, k: int) -> float:
        return float(self.analysis.error_table()[i, k])

    def factors(self, i: int, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """U1 (K, i), U3 (F, k) and the core (i, 3, k) of the truncation.

        U1's leading columns and the projection are the same for every rank, so they are formed
        once for the largest ranks asked for and sliced after.
        """
        decomposition = self.analysis.decomposition
        if i > self._u1.shape[1] or k > self._core.shape[2]:
            top_i = max(i, self._u1.shape[1])
            top_k = max(k, self._core.shape[2])
            self._u1 = decomposition.u1(top_i)
            self._core = project(
                decomposition.tensor, self._u1, decomposition.u2, decomposition.u3[:, :top_k]
            )
        return self._u1[:, :i], decomposition.u3[:, :k], self._core[:i, :, :k]

    def quantize(
        self, i: int, k: int, step: float, rounding: rdo.Settings | None = None
    ) -> Quantized:
        """Quantize the truncation (i, k) with the single parameter D = ``step`` (see above),
        rounding as ``rounding`` says (default :attr:`rdo`; the search's trials, which only
        rank truncations, may pass :data:`.rdo.NEAREST`, which costs nothing)."""
        rounding = self.rdo if rounding is None else rounding
        u1, u3, core = self.factors(i, k)
        root = math.sqrt(step)
        row_norms = np.sqrt(np.square(core).sum(axis=(1, 2)))
        column_norms = np.sqrt(np.square(core).sum(axis=(0, 1)))
        centroids = self._quantized_centroids(root / math.sqrt(self.vertex_count))
        return Quantized(
            i,
            k,
            step,
            self._rounded(u1, column_steps(root, row_norms), "U1", rounding),
            self._rounded(u3, column_steps(root, column_norms), "U3", rounding),
            self._rounded(core.reshape(-1, 1), np.array([root]), "CORE", rounding),
            centroids,
        )

    def _rounded(
        self, values: np.ndarray, steps: np.ndarray, section: str, rounding: rdo.Settings
    ) -> QuantizedMatrix:
        """qmat.quantize, or the rate-distortion choice of :mod:`.rdo` under the prediction
        ``section`` will be stored with (§6.6)."""
        if rounding.lam is None:
            return qmat.quantize(values, steps)
        if section == "U1":
            if self._u1_levels is None:
                self._u1_levels = rdo.Levels(self.parents)
            levels = self._u1_levels
        elif section == "U3":
            levels = rdo.Levels.chain(values.shape[0])
        else:
            levels = rdo.Levels.flat(values.shape[0])
        return rdo.quantize(values, steps, levels, rounding)

    def _quantized_centroids(self, step: float) -> QuantizedMatrix:
        """The centroids at ``step``, or at the smallest step whose integers fit the format
        (:attr:`centroid_floor_step`) if that is larger: the decoded-error check then makes the
        other factors finer to make up for it."""
        return qmat.quantize(
            self.analysis.centroids, np.full(3, max(step, self.centroid_floor_step))
        )

    def _centroid_floor(self) -> tuple[float, float]:
        """The smallest centroid step whose integers fit 32 bits (the first frame's values and
        the frame-to-frame differences, as streamed), and the squared error the centroids alone
        then add (each centroid error moves all K vertices)."""
        centroids = self.analysis.centroids
        largest = float(np.abs(centroids[0]).max())
        if centroids.shape[0] > 1:
            largest = max(largest, float(np.abs(np.diff(centroids, axis=0)).max()))
        step = float(np.float32(largest / LARGEST_STREAMED * 1.001))  # float32 as stored, with room
        if step == 0.0:
            return 0.0, 0.0
        rounded = np.rint(centroids / step) * step
        return step, self.vertex_count * float(np.square(centroids - rounded).sum())

    def check_reachable(self, limit2: float) -> None:
        """Refuse a target below what the centroids alone cost at their coarsest usable step:
        a sequence far from the origin, relative to its size, at a tight target."""
        if self.centroid_floor_error2 < limit2:
            return
        floor_kg = self.kg(self.centroid_floor_error2)
        raise UnreachableTargetError(
            "the sequence lies too far from the origin for this error target: its centroids "
            "(or their changes from frame to frame) reach "
            f"{LARGEST_STREAMED * self.centroid_floor_step:.6g}, "
            "the format stores them as 32-bit multiples of a step, and the finest step that fits "
            f"already costs a KG error of {floor_kg:.3g}. Move the sequence nearer the origin (the "
            "KG error does not depend on where it is), or ask for a larger KG error"
        )

    def decoded_error2(self, quantized: Quantized) -> float:
        """||decoded - input||**2, computed with the decoder's own reconstruction."""
        u1 = quantized.u1.values()
        u3 = quantized.u3.values()
        centroids = quantized.centroids.values()
        core = quantized.core.values().reshape(quantized.i, 3, quantized.k)
        basis = reconstruction_basis(core, self.analysis.decomposition.u2)
        total = 0.0
        vertices = self.sequence.vertices
        frames_at_once = max(1, BLOCK_BYTES // (24 * self.vertex_count))
        for start in range(0, self.frame_count, frames_at_once):
            block = slice(start, start + frames_at_once)
            difference = reconstruct_frames(u1, basis, u3[block], centroids[block])
            difference -= vertices[block]
            flat = difference.reshape(-1)
            total += float(flat @ flat)
        return total

    def kg(self, error2: float) -> float:
        return 100.0 * math.sqrt(error2 / self.denominator2)

    def sections(self, quantized: Quantized, level: int) -> list[tuple[dict[str, Any], bytes]]:
        """The file's sections, in the order of :data:`~.format.sections.WRITE_ORDER`."""
        coded = {"FACE": self.face_section}
        for section_id, matrix, parents, predict in (
            ("CENT", quantized.centroids, None, True),
            ("U3", quantized.u3, None, True),
            ("CORE", quantized.core, None, False),
            ("U1", quantized.u1, self.mesh, True),
        ):
            coded[section_id] = qmat.encode_matrix(
                matrix, parents, allow_predict=predict, level=level
            )
        if self.name_section is not None:
            coded["NAME"] = self.name_section
        return [
            (
                sections.entry(
                    section_id,
                    coded[section_id][0],
                    self.face_codec if section_id == "FACE" else None,
                ),
                coded[section_id][1],
            )
            for section_id in sections.WRITE_ORDER
            if section_id in coded
        ]

    def trial_bytes(self, quantized: Quantized) -> int:
        """The payload bytes at the fast search level: to compare trials, not the final size."""
        return sum(len(payload) for _, payload in self.sections(quantized, streams.SEARCH_LEVEL))

    def pack(
        self,
        quantized: Quantized,
        error2: float,
        target_kg: float | None,
        level: int | None = None,
    ) -> tuple[bytes, dict[str, int]]:
        """The file's bytes, and the size of each section (zstd ``level``: the final one unless
        given)."""
        header = header_map(
            vertices=self.vertex_count,
            frames=self.frame_count,
            ranks=(quantized.i, quantized.k),
            u2=self.analysis.decomposition.u2.reshape(-1).tolist(),
            kg=self.kg(error2),
            truncation_kg=self.kg(self.truncation_error2(quantized.i, quantized.k)),
            target_kg=target_kg,
            encoder=f"tuckercodec {__version__}",
            frame_rate=self.sequence.frame_rate,
        )
        packed = self.sections(quantized, self.level if level is None else level)
        sizes = {entry["id"]: len(payload) for entry, payload in packed}
        return pack_container(header, packed), sizes


def column_steps(root: float, norms: np.ndarray) -> np.ndarray:
    """sqrt(D) / norm per column; a column whose core slice is empty carries nothing (step 1)."""
    safe = np.where(norms > 0, norms, 1.0)
    return np.where(norms > 0, root / safe, 1.0)
