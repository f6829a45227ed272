"""The search's workspace for a segmented encode (format 1.1): the passes over the input, the
model they leave in r dimensions, the quantization of a choice of ranks, its decoded error (from
the model, or measured on the input), and the file's bytes.

:class:`SegmentedWorkspace` implements the trial protocol (:class:`..trial.Workspace`), so the
one search of :mod:`..search` meets targets with segments as it does for a whole sequence.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._version import __version__
from ...errors import InputError, UnreachableTargetError
from ...format import names, qmat, residual, streams
from ...format.container import pack_container
from ...format.header import KG_DEFINITION_ID, scene_keys
from ...format.qmat import QuantizedMatrix
from ...format.reconstruction import factor_value_count, reconstruction_basis
from ...format.sections import KNOWN_SECTIONS
from ...format.sections import entry as section_entry
from ...format.segments import (
    BASIS_OWN,
    BASIS_SHARED,
    SEGMENT_WRITE_ORDER,
    SEGMENTED,
    SEGMENTED_MINOR,
    segment_map,
    segment_section_id,
)
from ...model.sources import FrameSource
from ...model.topology import MeshPrediction
from ...system.memory import human_bytes
from ...system.parallel import Background, Executor, InProcessExecutor
from .. import attachments, estimate
from ..plan import SegmentPlan
from ..trial import TRIAL_RATIO, Quantized, QuantizedSegment
from ..versions import NEWEST, Features
from ..whole import LARGEST_STREAMED, column_steps, encoded_factor
from .model import (
    SegmentRanks,
    cheapest_ranks,
    column_norms,
    fixed_ranks,
    mode1_rotation,
    model_error2,
    orthonormal_columns,
    segment_model,
)
from .passes import DecodedSegment, SegmentRange, measure_segment, project_segment, sketch_segment

#: The seed of the range finder's Gaussian test matrices: fixed, so that the output is the same
#: bytes on every run and whatever runs the tasks.
SKETCH_SEED = 20261123
#: Truncation shares tried when none of the usual ones fits: a basis that leaves little room
#: (a given one, or a small sketch) spends most of the budget on truncation.
LATE_SHARES = (0.8, 0.9, 0.95, 0.98)
#: The bytes of a segmented file's header beside the payloads (the section table and the segment
#: index), as a size target's trials predict them. An early guess, and low: the shared
#: sequences' headers take about 550 + 500 per segment (chicken in 13 segments: 7,075 bytes
#: against 4,300). It only sets where the trials aim, 1-2 % of the budget too high; the final
#: fill packs real files, so no file exceeds its budget. Kept because the trials' aim decides the
#: bytes of segmented size-target files, which must not move without a reason of their own.
HEADER_BYTES, HEADER_BYTES_PER_SEGMENT = 400, 300

#: A section as :meth:`SegmentedWorkspace.sections` gives it: its table entry and payload.
Section = tuple[dict[str, Any], bytes]


@dataclass(frozen=True)
class SharedBasis:
    """A shared U1 given rather than found: the U1 section of a segmented file, as stored
    (``params`` of its table entry and its ``payload``). Encoding with it writes that section
    unchanged, so that files encoded with one basis share those bytes exactly (the zarr codec
    keeps them once, in its configuration)."""

    params: dict[str, Any]
    payload: bytes

    def matrix(self, mesh: MeshPrediction) -> QuantizedMatrix:
        """The quantized U1, its mesh prediction undone (any predictor: the file that held it
        set the coding tools flag if it needed it, and so will this encode's)."""
        return qmat.decode_matrix(
            self.payload,
            self.params,
            mesh,
            "the shared basis (U1)",
            coding_tools=True,
            adaptive_coding=True,
        )


class SegmentedWorkspace:
    """A segmented encode of one source: the passes' results and the choices made from them."""

    #: the model's error is confirmed by a pass over the input
    exact_model = False
    #: the model's own limit is the target's (each measuring pass tightens it by its miss)
    model_margin = 0.0
    late_shares: tuple[float, ...] = LATE_SHARES
    #: each measure is a pass over the input: the search meets its valley alone
    meets_finalists = False
    #: a size target's first trials leave quantization at least the lowest error's square
    first_room_floor = 1.0

    def __init__(
        self,
        source: FrameSource,
        plan: SegmentPlan,
        basis: str,
        executor: Executor,
        level: int,
        progress: Callable[[str], None] | None,
        fixed_basis: SharedBasis | None = None,
        *,
        face_order: str = "auto",
        keep: bool = True,
        features: Features = NEWEST,
    ) -> None:
        self.source, self.plan, self.basis = source, plan, basis
        # the format features the file may use (:attr:`..options.EncodeOptions.format_version`)
        self.features = features
        self.executor, self.level = executor, level
        self._progress = progress
        self.vertex_count, self.frame_count = source.vertex_count, source.frame_count
        self.ranges = [SegmentRange(a, b, plan.block_frames) for a, b in plan.bounds]
        self.passes = 0
        # U1's predictors: the mesh parents (1) and the decoded neighbours' mean (2)
        self.mesh = MeshPrediction(source.faces, self.vertex_count)
        self.parents = self.mesh.parents
        self.fixed_basis = fixed_basis
        self.fixed_u1: QuantizedMatrix | None = None
        self.fixed_r: np.ndarray | None = None
        if fixed_basis is not None:
            self.fixed_u1 = fixed_basis.matrix(self.mesh)
            if self.fixed_u1.q.shape[0] != self.vertex_count or basis != BASIS_SHARED:
                raise ValueError(
                    f"the shared basis is for {self.fixed_u1.q.shape[0]} vertices and a shared "
                    f"basis; this encode has {self.vertex_count} and basis {basis!r}"
                )
        # The faces' coding (Python loops, 14 s for 200,000 faces) needs nothing from the
        # passes: it runs in a thread beside them, while the workers, or BLAS in process, read
        # and multiply. The smaller connectivity codec; faces-traverse reorders them (§6.8).
        coding = Background(
            attachments.coded_faces,
            source.faces,
            self.vertex_count,
            source.attributes if keep else [],
            source.face_sets if keep else [],
            [],  # fields per face are read with the frames: the order follows the others
            level,
            face_order,
            features,
            name="faces",
        )
        self._read_and_model()
        face, attached = coding.result()
        # the sections of format 1.5 (ORDER, ATTR.n, FSET, then any field's)
        self.attached = attached
        self.face_codec = face.codec
        self.face_section = (face.params, face.payload)
        self.name_section = names.encode_names(source.frame_names, level)
        self.floor_step, self.floor_error2 = self._centroid_floor()
        # about the numbers the largest ranks store: the first guess of the size's slope in KG
        self.first_fill_values = self.vertex_count * self.frame_count
        fixed = len(self.face_section[1]) + sum(len(payload) for _, payload in attached)
        fixed += 0 if self.name_section is None else len(self.name_section[1])
        if fixed_basis is not None:
            fixed += len(fixed_basis.payload)
        self._coded_once = fixed  # payload bytes no choice of D changes
        self._u1_predictors: dict[int, estimate.U1Predictors] = {}
        # the sections of the quantization packed last, its level, and the packing (in a
        # thread when begun ahead): the next pack of the same quantization takes them
        self._packing: tuple[Quantized[SegmentRanks], int, Background[list[Section]]] | None = None

    # -- the passes that learn the sequence ----------------------------------------------------

    def _read_and_model(self) -> None:
        columns, shared = self.plan.sketch_columns, self.basis == BASIS_SHARED
        if self.fixed_u1 is not None:
            columns = 0  # the basis is given: pass 1 only measures centroids and energies
        self.say(f"pass 1: sketching {len(self.ranges)} segments ({columns} columns)")
        centroids, energies = [], []
        total: np.ndarray | None = None
        own_bases: list[np.ndarray] = []
        if shared and isinstance(self.executor, InProcessExecutor):
            # in process, every segment adds into one sum: one K x r array, not two (workers
            # return their segment's sketch, summed here in segment order)
            total = np.zeros((self.vertex_count, columns), order="F")
        for sketch in self._in_order(
            sketch_segment, self.ranges, self.source, columns, SKETCH_SEED, total
        ):
            centroids.append(sketch.centroids)
            energies.append(sketch.energies)
            if not shared:
                own_bases.append(orthonormal_columns(sketch.sketch))
            elif total is None:
                total = sketch.sketch
            elif sketch.sketch is not total:
                total += sketch.sketch  # in place: the sum is K x r
        self.passes += 1
        self.denominator2 = float(sum(float(e.sum()) for e in energies))
        if not (math.isfinite(self.denominator2) and self.denominator2 > 0):
            raise InputError(
                "every frame is a single point (or the coordinates are too large to square): the "
                "KG error has no denominator",
                path=self.source.path,
            )
        self.say("pass 2: projecting every frame on the sketch's basis")
        if self.fixed_u1 is None:
            self.shared_q = orthonormal_columns(total) if total is not None else None
        del total
        if self.fixed_u1 is not None:
            # U~1 = Q R: the first i columns of Q span the first i of U~1, so the error table in
            # Q's coordinates (rotation I) is the table of U~1's columns; cores convert by R
            basis = self.fixed_u1.values()
            self.shared_q, self.fixed_r = np.linalg.qr(basis)
        jobs = [(r, None if shared else own_bases[s]) for s, r in enumerate(self.ranges)]
        coefficients = list(self._in_order(project_segment, jobs, self.source, self.shared_q))
        self.passes += 1
        self.own_q = own_bases
        if self.fixed_r is not None:
            rotations = [np.eye(self.fixed_r.shape[0])] * len(coefficients)
        elif shared:
            rotation = mode1_rotation(np.concatenate(coefficients, axis=2))
            rotations = [rotation] * len(coefficients)
        else:
            rotations = [mode1_rotation(w) for w in coefficients]
        self.models = [
            segment_model(r.start, w, v, e, c)
            for r, w, v, e, c in zip(
                self.ranges, coefficients, rotations, energies, centroids, strict=True
            )
        ]
        if self.fixed_u1 is None:
            for model in self.models:  # no more columns of U1 than the file's arrays fit
                model.error_table = model.error_table[: self.plan.max_rank + 1]

    def resolve_finer(self) -> bool:
        """Sketch again with twice the columns, up to the most the plan allows (K, 3F or the
        memory), when no usual share of the budget leaves quantization room: the sketch is what
        limits then (a target the whole encoder meets needs U1 ranks the sketch does not
        resolve). True if it did; False with a given basis, or at the most columns."""
        plan = self.plan
        if self.fixed_u1 is not None or plan.sketch_columns >= plan.most_columns:
            return False
        if plan.max_rank < plan.sketch_columns:  # the file's arrays, not the sketch, limit
            return False
        wider = plan.with_columns(2 * plan.sketch_columns)
        self.say(
            f"the sketch of {plan.sketch_columns} columns leaves no room for the target: "
            f"sketching again with {wider.sketch_columns}"
        )
        self.plan = wider
        self._read_and_model()
        self._u1_predictors.clear()
        self._packing = None
        return True

    def _in_order(
        self, function: Callable[..., Any], items: list[Any], *common: Any
    ) -> Iterator[Any]:
        """``function(item, *common)`` for each item, yielded in the items' order as the
        executor finishes them (so that sums are made in a fixed order, and a result is dropped
        as soon as it is used)."""
        waiting: dict[int, Any] = {}
        next_index = 0
        finished = self.executor.as_completed(function, items, *common)
        try:
            for completed in finished:
                if completed.error is not None:
                    raise completed.error
                waiting[completed.index] = completed.value
                while next_index in waiting:
                    yield waiting.pop(next_index)
                    next_index += 1
        finally:
            finished.close()

    def _centroid_floor(self) -> tuple[float, float]:
        """The smallest centroid step whose integers fit 32 bits, and the error it then adds
        (as for one segment: :meth:`.workspace.Workspace._centroid_floor`)."""
        largest = 0.0
        for model in self.models:
            centroids = model.centroids
            largest = max(largest, float(np.abs(centroids[0]).max()))
            if len(centroids) > 1:
                largest = max(largest, float(np.abs(np.diff(centroids, axis=0)).max()))
        step = float(np.float32(largest / LARGEST_STREAMED * 1.001))
        if step == 0.0:
            return 0.0, 0.0
        error2 = sum(
            float(np.square(m.centroids - np.rint(m.centroids / step) * step).sum())
            for m in self.models
        )
        return step, self.vertex_count * error2

    @property
    def basis_vertices(self) -> int:
        """K where the ranks' cost counts a shared U1's columns (K each); 0 when the basis is
        given, and so already paid for."""
        return 0 if self.fixed_u1 is not None else self.vertex_count

    def kg(self, error2: float) -> float:
        return 100.0 * math.sqrt(error2 / self.denominator2)

    def say(self, message: str) -> None:
        """A line of progress (as each pass starts), if the caller asked for them."""
        if self._progress is not None:
            self._progress(message)

    def check_reachable(self, limit2: float) -> None:
        if self.floor_error2 >= limit2:
            raise UnreachableTargetError(
                "the sequence lies too far from the origin for this error target: its centroids "
                "are stored as 32-bit multiples of a step, and the finest step that fits already "
                f"costs a KG error of {self.kg(self.floor_error2):.3g}"
            )

    # -- choosing ranks ----------------------------------------------------------------------------

    def ranks_for(self, kg: float, share: float) -> SegmentRanks | None:
        """The ranks that store the fewest numbers with a truncation error within ``share`` of
        KG ``kg``'s square (:func:`.model.cheapest_ranks`)."""
        limit2 = (kg / 100.0) ** 2 * self.denominator2
        return cheapest_ranks(
            self.models, self.basis_vertices, self.basis == BASIS_SHARED, share * limit2
        )

    def fixed_choice(self, ranks: tuple[int, int]) -> SegmentRanks:
        """(i, k) in every segment, each cut to what its segment can hold."""
        return fixed_ranks(self.models, self.basis == BASIS_SHARED, *ranks)

    def largest_choice(self, limit2: float, target_kg: float) -> tuple[SegmentRanks, float]:
        """The largest ranks the model holds, if their truncation leaves room for quantization."""
        largest = self.fixed_choice((self.vertex_count, self.frame_count))
        if largest.truncation2 + self.floor_error2 >= limit2:
            limit, advice = self._binding_limit()
            raise UnreachableTargetError(
                f"a KG error of {target_kg:g} is below what {limit} resolves (KG "
                f"{self.kg(largest.truncation2):.3g} at its largest ranks). {advice}"
            )
        room = limit2 - largest.truncation2 - self.floor_error2
        return largest, self.initial_step(largest, room)

    def _binding_limit(self) -> tuple[str, str]:
        """What bounds the ranks of this encode, and what to do about it, for a refusal."""
        plan = self.plan
        memory = f"{human_bytes(plan.memory)} (max_memory, --max-memory)"
        more_memory = "Allow more memory, or ask for a larger error"
        if self.fixed_basis is not None:
            return "the given basis", "Ask for a larger error, or fit a basis for this target"
        if plan.max_rank < plan.sketch_columns:
            return (
                f"a U1 of {plan.max_rank} columns, the most whose file fits the memory allowed, "
                f"{memory}, for {self.vertex_count} vertices",
                more_memory,
            )
        if plan.columns_limited_by == "memory":
            return (
                f"a sketch of {plan.sketch_columns} columns, the most that fit the memory "
                f"allowed, {memory}, for {self.vertex_count} vertices",
                more_memory,
            )
        size = (
            f"its {self.vertex_count} vertices"
            if plan.columns_limited_by == "K"
            else f"three times its {self.frame_count} frames"
        )
        return (
            f"a sketch of {plan.sketch_columns} columns, every direction of the sequence ({size})",
            "Ask for a larger error",
        )

    def prepare(self, choices: Sequence[SegmentRanks]) -> None:
        """Nothing to form ahead: the model holds every factor."""

    def neighbours(self, choice: SegmentRanks, fraction: float) -> list[SegmentRanks]:
        """None: the Lagrangian choice already balances the segments' ranks."""
        return []

    def truncation_error2(self, choice: SegmentRanks) -> float:
        return choice.truncation2

    def stored_values(self, choice: SegmentRanks) -> int:
        """The numbers the factors hold (that this encode quantizes: not a given basis)."""
        total = 0 if self.fixed_u1 is not None else self.vertex_count * choice.shared
        for model, (i, k) in zip(self.models, choice.ranks, strict=True):
            total += factor_value_count(
                0 if choice.shared else self.vertex_count, model.frames, i, k
            )
        return total

    def initial_step(self, choice: SegmentRanks, room2: float) -> float:
        """D whose quantization noise (about D/12 per stored number) fills ``room2``."""
        return 12.0 * room2 / self.stored_values(choice)

    # -- quantization and its error ------------------------------------------------------------

    def _basis(self, segment: int, columns: int) -> np.ndarray:
        """U1's leading ``columns`` for a segment: Q V, shared or the segment's own."""
        model = self.models[segment]
        q = self.shared_q if self.shared_q is not None else self.own_q[segment]
        return q @ model.rotation[:, :columns]

    def quantize(
        self, choice: SegmentRanks, step: float, *, trial: bool = False
    ) -> Quantized[SegmentRanks]:
        """Quantize ``choice`` with the single parameter D = ``step`` (see :mod:`..whole`);
        to the nearest integers, trial or not."""
        root = math.sqrt(step)
        shared_u1 = None
        if self.fixed_u1 is not None:
            shared_u1 = self.fixed_u1  # given: stored as it is
        elif self.basis == BASIS_SHARED:
            norms = column_norms(self.models, choice.ranks, choice.shared)
            shared_u1 = qmat.quantize(self._basis(0, choice.shared), column_steps(root, norms))
        segments = []
        for s, (model, (i, k)) in enumerate(zip(self.models, choice.ranks, strict=True)):
            block = model.core[:i, :, :k]
            if self.fixed_r is not None:  # the core in the given U~1's coordinates: R^-1 core
                block = np.linalg.solve(self.fixed_r[:i, :i], block.reshape(i, -1)).reshape(
                    block.shape
                )
            own_u1 = None
            if self.basis == BASIS_OWN:
                norms = np.sqrt(np.square(block).sum(axis=(1, 2)))
                own_u1 = qmat.quantize(self._basis(s, i), column_steps(root, norms))
            u3_norms = np.sqrt(np.square(block).sum(axis=(0, 1)))
            centroid_step = max(root / math.sqrt(self.vertex_count), self.floor_step)
            segments.append(
                QuantizedSegment(
                    own_u1,
                    qmat.quantize(model.u3[:, :k], column_steps(root, u3_norms)),
                    qmat.quantize(block.reshape(-1, 1), np.array([root])),
                    qmat.quantize(model.centroids, np.full(3, centroid_step)),
                )
            )
        return Quantized(choice, step, segments, shared_u1)

    def decoded(self, quantized: Quantized[SegmentRanks]) -> list[DecodedSegment]:
        """Each segment's factors as the decoder will have them (§6.3, §8)."""
        out = []
        for s, (model, (i, k), factors) in enumerate(
            zip(self.models, quantized.choice.ranks, quantized.segments, strict=True)
        ):
            core = factors.core.values().reshape(i, 3, k)
            out.append(
                DecodedSegment(
                    self.ranges[s],
                    reconstruction_basis(core, model.u2),
                    factors.u3.values(),
                    factors.centroids.values(),
                    None if factors.u1 is None else factors.u1.values(),
                )
            )
        return out

    def modelled_error2(self, quantized: Quantized[SegmentRanks]) -> float:
        """The decoded error from the r-dimensional model (:func:`.model.model_error2`)."""
        total = 0.0
        shared = None
        if quantized.shared_u1 is not None:
            assert self.shared_q is not None
            u1 = quantized.shared_u1.values()
            shared = (self.shared_q.T @ u1, u1.T @ u1, u1.sum(axis=0))
        for s, part in enumerate(self.decoded(quantized)):
            i = part.basis.shape[0]
            if shared is not None:
                projection, gram, sums = shared[0][:, :i], shared[1][:i, :i], shared[2][:i]
            else:
                own = part.own_u1
                assert own is not None
                projection, gram, sums = self.own_q[s].T @ own, own.T @ own, own.sum(axis=0)
            total += model_error2(
                self.models[s],
                projection,
                gram,
                sums,
                self.vertex_count,
                part.basis,
                part.u3,
                part.centroids,
            )
        return total

    # the model ranks a size target's candidates too
    estimated_error2 = modelled_error2

    def measured_error2(self, quantized: Quantized[SegmentRanks]) -> float:
        """A pass over the input: the decoded sequence's exact squared error."""
        self.say(f"pass {self.passes + 1}: measuring the decoded error on the input")
        shared = None if quantized.shared_u1 is None else quantized.shared_u1.values()
        parts = self.decoded(quantized)
        # A measure is most often the search's last step before the file: its sections are
        # packed meanwhile (zstd at the final level, which releases the GIL), while this
        # process would otherwise only wait for the workers' pass. Wasted only if the
        # measure misses the target, which costs another pass anyway.
        self._packed_sections(quantized, self.level, wait=False)
        total = sum(self._in_order(measure_segment, parts, self.source, shared))
        self.passes += 1
        return float(total)

    # -- the file ----------------------------------------------------------------------------------

    def _packed_sections(
        self, quantized: Quantized[SegmentRanks], level: int, *, wait: bool = True
    ) -> list[Section]:
        """:meth:`sections`, kept for the next call with the same quantization and level (a
        pack after the measure, or after a size target's fill packed the same): begun in a
        thread and returned empty if not ``wait``, else waited for and returned (a copy)."""
        held = self._packing
        if held is None or held[0] is not quantized or held[1] != level:
            packing = Background(self.sections, quantized, level, name="sections")
            self._packing = held = (quantized, level, packing)
        return list(held[2].result()) if wait else []

    def sections(self, quantized: Quantized[SegmentRanks], level: int) -> list[Section]:
        """The file's sections in the order the reference encoder writes them (§6.7): FACE,
        the shared U1, each segment's CENT, U3, CORE (and U1), then NAME."""
        out: list[Section] = [
            (section_entry("FACE", self.face_section[0], self.face_codec), self.face_section[1])
        ]
        if self.fixed_basis is not None:  # a given basis: its section, byte for byte
            out.append((_entry("U1", self.fixed_basis.params), self.fixed_basis.payload))
        elif quantized.shared_u1 is not None:
            params, payload = encoded_factor(quantized.shared_u1, self.mesh, self.features, level)
            out.append((_entry("U1", params), payload))
        for s, factors in enumerate(quantized.segments):
            matrices: dict[str, tuple[QuantizedMatrix, MeshPrediction | None, bool]] = {
                "CENT": (factors.centroids, None, True),
                "U3": (factors.u3, None, True),
                "CORE": (factors.core, None, False),
            }
            if factors.u1 is not None:
                matrices["U1"] = (factors.u1, self.mesh, True)
            for stem in SEGMENT_WRITE_ORDER:
                if stem not in matrices:
                    continue
                matrix, parents, predict = matrices[stem]
                params, payload = encoded_factor(matrix, parents, self.features, level, predict)
                out.append((_entry(segment_section_id(stem, s), params, stem), payload))
        if self.name_section is not None:
            out.append((_entry("NAME", self.name_section[0]), self.name_section[1]))
        return out[:1] + self.attached + out[1:]

    def trial_bytes(self, quantized: Quantized[SegmentRanks]) -> int:
        """The quantized sections' bytes estimated from their integers (:mod:`..estimate`),
        and those coded once: to compare trials, not the final size."""
        bits = 0.0
        if self.fixed_basis is None and quantized.shared_u1 is not None:
            bits += self._predictors(-1).bits(quantized.shared_u1.q)
        for s, factors in enumerate(quantized.segments):
            bits += estimate.segment_bits(factors, self._predictors(s), self.features.coding_tools)
        return round(bits / 8.0) + self._coded_once

    def _predictors(self, segment: int) -> estimate.U1Predictors:
        """U1's predictors kept between trials: the shared U1's (-1) or a segment's own."""
        if segment not in self._u1_predictors:
            self._u1_predictors[segment] = estimate.U1Predictors(
                self.mesh, coding_tools=self.features.coding_tools, pushes=self.features.adaptive
            )
        return self._u1_predictors[segment]

    def trial_size(self, quantized: Quantized[SegmentRanks]) -> float:
        """The payloads at the fast level (the quantized ones scaled by :data:`TRIAL_RATIO`)
        and the header as :data:`HEADER_BYTES` predicts it: packed, as a size target's fill
        is calibrated on packed sizes."""
        packed = sum(len(p) for _, p in self.sections(quantized, streams.SEARCH_LEVEL))
        variable = packed - self._coded_once
        header = HEADER_BYTES + HEADER_BYTES_PER_SEGMENT * len(self.ranges)
        return header + self._coded_once + TRIAL_RATIO * variable

    def pack(
        self,
        quantized: Quantized[SegmentRanks],
        error2: float,
        target_kg: float | None,
        level: int | None = None,
        *,
        corrections: list[tuple[dict[str, Any], bytes]] | None = None,
        claims: dict[str, Any] | None = None,
    ) -> tuple[bytes, dict[str, int]]:
        """The file's bytes and each section kind's size, the segments' summed (zstd
        ``level``: the final one unless given). ``corrections``: each segment's RESD.s
        parameters and payload (format 1.3, §6.9); ``claims``: more keys of the header's
        ``error`` map."""
        segments = [
            segment_map(model.frames, ranks, model.u2.reshape(-1).tolist(), self.basis)
            for model, ranks in zip(self.models, quantized.choice.ranks, strict=True)
        ]
        header: dict[str, Any] = {
            "vertices": self.vertex_count,
            "frames": self.frame_count,
            "segments": segments,
            "error": {
                "kg": self.kg(error2),
                "definition": KG_DEFINITION_ID,
                "truncation_kg": self.kg(quantized.choice.truncation2),
                "target_kg": target_kg,
                **(claims or {}),
            },
            "encoder": f"tuckercodec {__version__}",
        }
        if self.source.frame_rate is not None:
            header["frame_rate"] = float(self.source.frame_rate)
        source = self.source
        # format 1.4's time and scene keys, last (pack_container raises the minor for them)
        header.update(
            scene_keys(self.frame_count, source.time_codes, source.meters_per_unit, source.up_axis)
        )
        packed = self._packed_sections(quantized, self.level if level is None else level)
        flags, minor = SEGMENTED, SEGMENTED_MINOR
        if corrections is not None:  # before NAME, as in a whole file
            at = next((n for n, (e, _) in enumerate(packed) if e["id"] == "NAME"), len(packed))
            entries = [
                (
                    {
                        "id": segment_section_id(residual.SECTION_STEM, number),
                        "critical": True,
                        "codec": residual.RESIDUAL,
                        **params,
                    },
                    payload,
                )
                for number, (params, payload) in enumerate(corrections)
            ]
            packed[at:at] = entries
            flags, minor = SEGMENTED | residual.CORRECTIONS, residual.CORRECTIONS_MINOR
        sizes: dict[str, int] = {}
        for entry, payload in packed:
            stem = entry["id"].split(".")[0]
            sizes[stem] = sizes.get(stem, 0) + len(payload)
        data = pack_container(header, packed, flags=flags, minor=minor)
        return data, sizes


def _entry(section_id: str, params: dict[str, Any], stem: str | None = None) -> dict[str, Any]:
    """A section-table entry: the kind of ``stem`` (the section's own id if not given)."""
    kind = KNOWN_SECTIONS[stem or section_id]
    return {"id": section_id, "critical": kind.critical, "codec": kind.codec, **params}
