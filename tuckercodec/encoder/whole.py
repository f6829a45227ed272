"""The search's workspace for a sequence encoded whole: one decomposition, format 1.0.

:class:`WholeWorkspace` implements the trial protocol (:class:`.trial.Workspace`) for a sequence
in memory. It holds the input, its analysis and everything every trial shares (the mesh parents,
the coded faces and names); :meth:`~WholeWorkspace.quantize` turns ranks (i, k) and D into the
integers a file stores, :meth:`~WholeWorkspace.decoded_error2` measures what a decoder will
return (with the format's own reconstruction, §8), and :meth:`~WholeWorkspace.pack` makes the
file. The package docstring (:mod:`tuckercodec.encoder`) says how D sets every step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._version import __version__
from ..decomposition.analysis import Analysis, Selection
from ..decomposition.hosvd import project
from ..errors import UnreachableTargetError
from ..format import names, qmat, residual, sections, streams
from ..format.container import FORMAT_MINOR, pack_container
from ..format.header import header_map, scene_keys
from ..format.qmat import QuantizedMatrix
from ..format.reconstruction import factor_value_count, reconstruct_frames, reconstruction_basis
from ..measures.distortion import WorstVertex
from ..model.sequence import MeshSequence
from ..model.topology import MeshPrediction
from . import attachments, estimate, rdo
from .trial import TRIAL_RATIO, Quantized, QuantizedSegment
from .versions import NEWEST, Features

#: The largest |integer| a section may stream: after zigzag it must fit streams.MAX_PLANES bytes.
LARGEST_STREAMED = 2 ** (8 * streams.MAX_PLANES - 1) - 1
#: Bytes of positions reconstructed at once when measuring the error: bounds the memory.
BLOCK_BYTES = 2 << 20


#: A whole file's choice of ranks: (i, k).
Ranks = tuple[int, int]
#: The sections whose size D sets; the others (faces, names) are coded once.
QUANTIZED_SECTIONS = ("CENT", "U3", "CORE", "U1")
#: The least room a size target's first trials leave quantization, as a share of the lowest
#: error's square (:class:`.trial.Workspace`; the segmented workspace's is 1).
FIRST_ROOM_FLOOR = 1e-3


@dataclass(frozen=True)
class Connectivity:
    """What a file's faces and names cost, the same for every trial: U1's mesh predictors,
    the coded FACE section (the smaller codec; faces-traverse reorders the faces, §6.8) and
    the coded NAME section. Python-bound, and independent of the analysis (BLAS-bound), so an
    encoder can make both at once (:meth:`of` in a thread)."""

    mesh: MeshPrediction
    face_codec: str
    face_section: tuple[dict[str, Any], bytes]
    name_section: tuple[dict[str, Any], bytes] | None
    #: the sections of format 1.5 coded once (ORDER, ATTR.n, FSET): empty without attachments
    attached: tuple[tuple[dict[str, Any], bytes], ...] = ()

    @classmethod
    def of(
        cls,
        sequence: MeshSequence,
        level: int,
        face_order: str = "auto",
        keep: bool = True,
        features: Features = NEWEST,
    ) -> Connectivity:
        """The connectivity of ``sequence``, its sections at zstd ``level``; with ``keep``, its
        attributes and face sets too, the faces in the order ``face_order`` decides
        (:func:`.attachments.keeps_face_order`), coded as ``features`` allow."""
        face, attached = attachments.coded_faces(
            sequence.faces,
            sequence.vertex_count,
            sequence.attributes if keep else [],
            sequence.face_sets if keep else [],
            sequence.fields if keep else [],
            level,
            face_order,
            features,
        )
        return cls(
            MeshPrediction(sequence.faces, sequence.vertex_count),
            face.codec,
            (face.params, face.payload),
            names.encode_names(sequence.frame_names, level),
            tuple(attached),
        )


class WholeWorkspace:
    """The input, its analysis and the parts shared by every trial of the search."""

    #: D is first adjusted on the model of :meth:`estimated_error2` (within 0.3 % of the
    #: decoded error on the shared sequences, and twenty times cheaper at samba's size), then
    #: the decoded error is measured, once where the model holds
    exact_model = False
    #: the model aims this share of quantization's room inside the target, so that its
    #: misses rarely cost another pass
    model_margin = 0.003
    #: none: the exact table always leaves quantization room, but within rounding of zero error
    late_shares: tuple[float, ...] = ()
    #: measuring decodes the sequence in memory: the search meets the valley's neighbours too
    meets_finalists = True
    first_room_floor = FIRST_ROOM_FLOOR

    def resolve_finer(self) -> bool:
        """False: the whole sequence's decomposition is exact already."""
        return False

    def __init__(
        self,
        sequence: MeshSequence,
        analysis: Analysis,
        level: int,
        select: Selection,
        connectivity: Connectivity | None = None,
        features: Features = NEWEST,
    ) -> None:
        self.sequence = sequence
        # the format features the file may use (:attr:`.options.EncodeOptions.format_version`)
        self.features = features
        self.analysis = analysis
        self.level = level
        self.select: Selection = select
        self.vertex_count = sequence.vertex_count
        self.frame_count = sequence.frame_count
        # the time and scene keys the sequence carries (format 1.4), empty if none
        self.scene = scene_keys(
            self.frame_count, sequence.time_codes, sequence.meters_per_unit, sequence.up_axis
        )
        # The KG denominator: each frame is centred, so ||A - E(A)|| is the centred tensor's norm.
        self.denominator2 = analysis.total_energy
        if connectivity is None:
            connectivity = Connectivity.of(sequence, level, features=features)
        # U1's predictors: the mesh parents (1) and the decoded neighbours' mean (2)
        self.mesh = connectivity.mesh
        self.parents = self.mesh.parents
        self.face_codec = connectivity.face_codec
        self.face_section = connectivity.face_section
        self.name_section = connectivity.name_section
        # the sections of format 1.5 (ORDER, ATTR.n, FSET, then the fields' FLD.n...)
        self.attached = list(connectivity.attached)
        self.centroid_floor_step, self.floor_error2 = self._centroid_floor()
        r1, r3 = analysis.max_ranks
        self.first_fill_values = factor_value_count(self.vertex_count, self.frame_count, r1, r3)
        self._u1 = np.zeros((self.vertex_count, 0))
        self._core = np.zeros((0, 3, 0))
        # how factors are rounded (rdo.py); the prediction trees it needs are made on first use
        self.rdo = rdo.DEFAULT
        self._u1_levels: rdo.Levels | None = None
        self._u1_predictors = estimate.U1Predictors(
            self.mesh, coding_tools=features.coding_tools, pushes=features.adaptive
        )

    # -- choosing ranks ------------------------------------------------------------------------

    def truncation_error2(self, choice: Ranks) -> float:
        i, k = choice
        return float(self.analysis.error_table()[i, k])

    def ranks_for(self, kg: float, share: float) -> Ranks:
        """The cheapest (i, k) whose KG error is at most ``kg`` sqrt(``share``), by the exact
        table or the paper's bound (:attr:`select`)."""
        choice = self.analysis.cheapest(kg * math.sqrt(share), select=self.select)
        return choice.i, choice.k

    def fixed_choice(self, ranks: tuple[int, int]) -> Ranks:
        r1, r3 = self.analysis.max_ranks
        i, k = ranks
        if not (1 <= i <= r1 and 1 <= k <= r3):
            raise ValueError(
                f"ranks must be two integers with 1 <= i <= {r1} and 1 <= k <= {r3}, got {ranks!r}"
            )
        return i, k

    def largest_choice(self, limit2: float, target_kg: float) -> tuple[Ranks, float]:
        """The full ranks, which lose nothing, with D for the whole limit."""
        largest = self.analysis.max_ranks
        return largest, self.initial_step(largest, max(limit2, 1e-300))

    def prepare(self, choices: Sequence[Ranks]) -> None:
        """Form the factors once, for the largest ranks, rather than growing them."""
        if choices:
            self.factors(max(i for i, _ in choices), max(k for _, k in choices))

    def neighbours(self, choice: Ranks, fraction: float) -> list[Ranks]:
        """i and k moved by ``fraction`` of themselves (at least 1), within the ranks."""
        i, k = choice
        r1, r3 = self.analysis.max_ranks
        di, dk = max(1, round(fraction * i)), max(1, round(fraction * k))
        moves = ((i + di, k), (i - di, k), (i, k + dk), (i, k - dk))
        return [(a, b) for a, b in moves if 1 <= a <= r1 and 1 <= b <= r3]

    def stored_values(self, choice: Ranks) -> int:
        return factor_value_count(self.vertex_count, self.frame_count, *choice)

    def initial_step(self, choice: Ranks, room2: float) -> float:
        return 12.0 * room2 / self.stored_values(choice)

    # -- quantizing ------------------------------------------------------------------------------

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

    def quantize(self, choice: Ranks, step: float, *, trial: bool = False) -> Quantized[Ranks]:
        """Quantize the truncation (i, k) with the single parameter D = ``step`` (see above),
        rounding as :attr:`rdo` says, or, for a ``trial`` (which only ranks truncations), to the
        nearest integer, which costs nothing."""
        rounding = rdo.NEAREST if trial else self.rdo
        i, k = choice
        u1, u3, core = self.factors(i, k)
        root = math.sqrt(step)
        row_norms = np.sqrt(np.square(core).sum(axis=(1, 2)))
        column_norms = np.sqrt(np.square(core).sum(axis=(0, 1)))
        centroids = self._quantized_centroids(root / math.sqrt(self.vertex_count))
        segment = QuantizedSegment(
            self._rounded(u1, column_steps(root, row_norms), "U1", rounding),
            self._rounded(u3, column_steps(root, column_norms), "U3", rounding),
            self._rounded(core.reshape(-1, 1), np.array([root]), "CORE", rounding),
            centroids,
        )
        return Quantized((i, k), step, [segment])

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
            # the predictors the trials keep (:mod:`.estimate`): the file's likely ones
            nearest = qmat.quantize(values, steps)
            predict, push = self._u1_predictors.kept(nearest.q)
            return rdo.quantize_mesh(
                values, steps, self._u1_levels, self.mesh, predict, push, rounding, nearest
            )
        if section == "U3":
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
        if self.floor_error2 < limit2:
            return
        floor_kg = self.kg(self.floor_error2)
        raise UnreachableTargetError(
            "the sequence lies too far from the origin for this error target: its centroids "
            "(or their changes from frame to frame) reach "
            f"{LARGEST_STREAMED * self.centroid_floor_step:.6g}, "
            "the format stores them as 32-bit multiples of a step, and the finest step that fits "
            f"already costs a KG error of {floor_kg:.3g}. Move the sequence nearer the origin (the "
            "KG error does not depend on where it is), or ask for a larger KG error"
        )

    # -- its error -------------------------------------------------------------------------------

    def decoded_error2(self, quantized: Quantized[Ranks]) -> float:
        """||decoded - input||**2, computed with the decoder's own reconstruction. The worst
        vertex is found in the same pass and kept on ``quantized`` (:meth:`worst_vertex`)."""
        (i, k), (factors,) = quantized.choice, quantized.segments
        assert factors.u1 is not None  # a whole file's U1 is its own
        u1 = factors.u1.values()
        u3 = factors.u3.values()
        centroids = factors.centroids.values()
        core = factors.core.values().reshape(i, 3, k)
        basis = reconstruction_basis(core, self.analysis.decomposition.u2)
        total = 0.0
        worst = WorstVertex()
        vertices = self.sequence.vertices
        frames_at_once = max(1, BLOCK_BYTES // (24 * self.vertex_count))
        for start in range(0, self.frame_count, frames_at_once):
            block = slice(start, start + frames_at_once)
            difference = reconstruct_frames(u1, basis, u3[block], centroids[block])
            difference -= vertices[block]
            flat = difference.reshape(-1)
            total += float(flat @ flat)
            worst.add(difference, start)
        quantized.worst = worst.found()
        return total

    def worst_vertex(self, quantized: Quantized[Ranks]) -> tuple[float, tuple[int, int]]:
        """The decoded vertex farthest from the input (Euclidean distance) and its (frame,
        vertex), with the decoder's own reconstruction (measured with the error if it was)."""
        if quantized.worst is None:
            self.decoded_error2(quantized)
        assert quantized.worst is not None
        return quantized.worst

    measured_error2 = decoded_error2

    def estimated_error2(self, quantized: Quantized[Ranks]) -> float:
        """The decoded squared error, from the truncation's and each factor's rounding errors
        weighted as the reconstruction weighs them (U1 and U3 orthonormal; the cross terms,
        averaging out, left out). Cheap next to reconstructing every frame; ranks candidates."""
        (i, k), (factors,) = quantized.choice, quantized.segments
        assert factors.u1 is not None
        u1, u3, core = self.factors(i, k)
        rows = np.square(core).sum(axis=(1, 2))
        columns = np.square(core).sum(axis=(0, 1))
        error2 = self.truncation_error2((i, k))
        error2 += float(np.square(factors.u1.values() - u1).sum(axis=0) @ rows)
        error2 += float(np.square(factors.u3.values() - u3).sum(axis=0) @ columns)
        error2 += float(np.square(factors.core.values().reshape(-1) - core.reshape(-1)).sum())
        centroids = factors.centroids.values() - self.analysis.centroids
        return error2 + self.vertex_count * float(np.square(centroids).sum())

    modelled_error2 = estimated_error2

    def kg(self, error2: float) -> float:
        return 100.0 * math.sqrt(error2 / self.denominator2)

    def say(self, message: str) -> None:
        """A whole encode makes no passes to report."""

    # -- the file ----------------------------------------------------------------------------------

    def sections(
        self, quantized: Quantized[Ranks], level: int
    ) -> list[tuple[dict[str, Any], bytes]]:
        """The file's sections, in the order of :data:`~.format.sections.WRITE_ORDER`."""
        (factors,) = quantized.segments
        coded = {"FACE": self.face_section}
        for section_id, matrix, parents, predict in (
            ("CENT", factors.centroids, None, True),
            ("U3", factors.u3, None, True),
            ("CORE", factors.core, None, False),
            ("U1", factors.u1, self.mesh, True),
        ):
            assert matrix is not None  # a whole file's U1 is its own
            coded[section_id] = encoded_factor(matrix, parents, self.features, level, predict)
        if self.name_section is not None:
            coded["NAME"] = self.name_section
        packed = [
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
        return packed[:1] + self.attached + packed[1:]

    def trial_bytes(self, quantized: Quantized[Ranks]) -> int:
        """The quantized sections' bytes estimated from their integers (:mod:`.estimate`), and
        the coded faces': to compare trials, not the final size."""
        (factors,) = quantized.segments
        bits = estimate.segment_bits(factors, self._u1_predictors, self.features.coding_tools)
        return round(bits / 8.0) + len(self.face_section[1])

    def trial_size(self, quantized: Quantized[Ranks]) -> float:
        """The file packed at the fast level, its quantized sections scaled by
        :data:`TRIAL_RATIO` to what the final level and rounding make of them."""
        data, sizes = self.pack(quantized, 0.0, None, streams.SEARCH_LEVEL)
        variable = sum(sizes.get(name, 0) for name in QUANTIZED_SECTIONS)
        return len(data) - (1.0 - TRIAL_RATIO) * variable

    def pack(
        self,
        quantized: Quantized[Ranks],
        error2: float,
        target_kg: float | None,
        level: int | None = None,
        *,
        corrections: list[tuple[dict[str, Any], bytes]] | None = None,
        claims: dict[str, Any] | None = None,
    ) -> tuple[bytes, dict[str, int]]:
        """The file's bytes, and the size of each section (zstd ``level``: the final one unless
        given). ``corrections``: the RESD section's parameters and payload (one; format 1.3,
        §6.9), as a segmented file's are given; ``claims``: more keys of the header's ``error``
        map (:func:`.promises.header_claims`)."""
        header = header_map(
            vertices=self.vertex_count,
            frames=self.frame_count,
            ranks=quantized.choice,
            u2=self.analysis.decomposition.u2.reshape(-1).tolist(),
            kg=self.kg(error2),
            truncation_kg=self.kg(self.truncation_error2(quantized.choice)),
            target_kg=target_kg,
            encoder=f"tuckercodec {__version__}",
            frame_rate=self.sequence.frame_rate,
            claims=claims,
            scene=self.scene,
        )
        packed = self.sections(quantized, self.level if level is None else level)
        flags, minor = 0, FORMAT_MINOR
        if corrections is not None:
            (correction,) = corrections
            entry = {"id": residual.SECTION_STEM, "critical": True, "codec": residual.RESIDUAL}
            at = next((n for n, (e, _) in enumerate(packed) if e["id"] == "NAME"), len(packed))
            packed.insert(at, ({**entry, **correction[0]}, correction[1]))
            flags, minor = residual.CORRECTIONS, residual.CORRECTIONS_MINOR
        sizes = {entry["id"]: len(payload) for entry, payload in packed}
        return pack_container(header, packed, flags=flags, minor=minor), sizes


def encoded_factor(
    matrix: QuantizedMatrix,
    parents: MeshPrediction | None,
    features: Features,
    level: int,
    allow_predict: bool = True,
) -> tuple[dict[str, Any], bytes]:
    """A position factor's qmat section (§6.3) with the coding tools and the adaptive coder
    that ``features`` allow: how a file's factors are coded, whole or in segments."""
    return qmat.encode_matrix(
        matrix,
        parents,
        allow_predict=allow_predict,
        coding_tools=features.coding_tools,
        level=level,
        adaptive_coding=features.adaptive,
    )


def column_steps(root: float, norms: np.ndarray) -> np.ndarray:
    """sqrt(D) / norm per column; a column whose core slice is empty carries nothing (step 1)."""
    safe = np.where(norms > 0, norms, 1.0)
    return np.where(norms > 0, root / safe, 1.0)
