"""The state of a segmented encode (:mod:`.segmented`): the passes over the input, the model
they leave in r dimensions, the quantization of a choice of ranks, and its decoded error (from
the model, or measured on the input)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..format import faces, names, qmat
from ..format.qmat import QuantizedMatrix
from ..format.reconstruction import factor_value_count, reconstruction_basis
from ..format.segments import (
    BASIS_OWN,
    BASIS_SHARED,
)
from ..io.streaming import FrameSource
from ..parallel import Executor, InProcessExecutor
from ..topology import MeshPrediction
from .passes import DecodedSegment, SegmentRange, measure_segment, project_segment, sketch_segment
from .plan import SegmentPlan
from .segment_model import (
    RankChoice,
    column_norms,
    mode1_rotation,
    model_error2,
    orthonormal_columns,
    segment_model,
)
from .workspace import LARGEST_STREAMED, column_steps

#: The seed of the range finder's Gaussian test matrices: fixed, so that the output is the same
#: bytes on every run and whatever runs the tasks.
SKETCH_SEED = 20261123
#: Measuring passes before giving up on the target (each one tightens D to what it measured).
MAX_MEASURING_PASSES = 6
#: Quantization may add this much to a fixed-ranks truncation's squared error (as unsegmented).
RANKS_QUANTIZATION_SHARE = 1.05**2 - 1
BASES = (BASIS_SHARED, BASIS_OWN)


@dataclass(eq=False)
class Quantized:
    """One quantization of the chosen ranks with the parameter D: what the file stores."""

    choice: RankChoice
    step: float
    shared_u1: QuantizedMatrix | None
    own_u1: list[QuantizedMatrix | None]
    u3: list[QuantizedMatrix]
    core: list[QuantizedMatrix]
    centroids: list[QuantizedMatrix]


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
            self.payload, self.params, mesh, "the shared basis (U1)", coding_tools=True
        )


class SegmentedEncode:
    """A segmented encode of one source: the passes' results and the choices made from them."""

    def __init__(
        self,
        source: FrameSource,
        plan: SegmentPlan,
        basis: str,
        executor: Executor,
        level: int,
        progress: Callable[[str], None] | None,
        fixed_basis: SharedBasis | None = None,
    ) -> None:
        self.source, self.plan, self.basis = source, plan, basis
        self.executor, self.level = executor, level
        self.say = progress or (lambda message: None)
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
        self._read_and_model()
        # the smaller connectivity codec; faces-traverse reorders the faces (§6.8)
        face = faces.encode_face_section(source.faces, self.vertex_count, level)
        self.face_codec = face.codec
        self.face_section = (face.params, face.payload)
        self.name_section = names.encode_names(source.frame_names, level)
        self.floor_step, self.floor_error2 = self._centroid_floor()

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

    # -- quantization and its error ------------------------------------------------------------

    def _basis(self, segment: int, columns: int) -> np.ndarray:
        """U1's leading ``columns`` for a segment: Q V, shared or the segment's own."""
        model = self.models[segment]
        q = self.shared_q if self.shared_q is not None else self.own_q[segment]
        return q @ model.rotation[:, :columns]

    def quantize(self, choice: RankChoice, step: float) -> Quantized:
        """Quantize ``choice`` with the single parameter D = ``step`` (see :mod:`.workspace`)."""
        root = math.sqrt(step)
        shared_u1 = None
        own_u1: list[QuantizedMatrix | None] = []
        if self.fixed_u1 is not None:
            shared_u1 = self.fixed_u1  # given: stored as it is
        elif self.basis == BASIS_SHARED:
            norms = column_norms(self.models, choice.ranks, choice.shared)
            shared_u1 = qmat.quantize(self._basis(0, choice.shared), column_steps(root, norms))
        u3, core, centroids = [], [], []
        for s, (model, (i, k)) in enumerate(zip(self.models, choice.ranks, strict=True)):
            block = model.core[:i, :, :k]
            if self.fixed_r is not None:  # the core in the given U~1's coordinates: R^-1 core
                block = np.linalg.solve(self.fixed_r[:i, :i], block.reshape(i, -1)).reshape(
                    block.shape
                )
            if self.basis == BASIS_OWN:
                norms = np.sqrt(np.square(block).sum(axis=(1, 2)))
                own_u1.append(qmat.quantize(self._basis(s, i), column_steps(root, norms)))
            else:
                own_u1.append(None)
            u3_norms = np.sqrt(np.square(block).sum(axis=(0, 1)))
            u3.append(qmat.quantize(model.u3[:, :k], column_steps(root, u3_norms)))
            core.append(qmat.quantize(block.reshape(-1, 1), np.array([root])))
            centroid_step = max(root / math.sqrt(self.vertex_count), self.floor_step)
            centroids.append(qmat.quantize(model.centroids, np.full(3, centroid_step)))
        return Quantized(choice, step, shared_u1, own_u1, u3, core, centroids)

    def decoded(self, quantized: Quantized) -> list[DecodedSegment]:
        """Each segment's factors as the decoder will have them (§6.3, §8)."""
        out = []
        for s, (model, (i, k)) in enumerate(zip(self.models, quantized.choice.ranks, strict=True)):
            core = quantized.core[s].values().reshape(i, 3, k)
            own = quantized.own_u1[s]
            out.append(
                DecodedSegment(
                    self.ranges[s],
                    reconstruction_basis(core, model.u2),
                    quantized.u3[s].values(),
                    quantized.centroids[s].values(),
                    None if own is None else own.values(),
                )
            )
        return out

    def model_error2(self, quantized: Quantized) -> float:
        """The decoded error from the r-dimensional model (:func:`.segment_model.model_error2`)."""
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

    def measured_error2(self, quantized: Quantized) -> float:
        """A pass over the input: the decoded sequence's exact squared error."""
        self.say(f"pass {self.passes + 1}: measuring the decoded error on the input")
        shared = None if quantized.shared_u1 is None else quantized.shared_u1.values()
        parts = self.decoded(quantized)
        total = sum(self._in_order(measure_segment, parts, self.source, shared))
        self.passes += 1
        return float(total)

    # -- the search ------------------------------------------------------------------------------

    def stored_values(self, choice: RankChoice) -> int:
        """The numbers the factors hold (that this encode quantizes: not a given basis)."""
        total = 0 if self.fixed_u1 is not None else self.vertex_count * choice.shared
        for model, (i, k) in zip(self.models, choice.ranks, strict=True):
            total += factor_value_count(
                0 if choice.shared else self.vertex_count, model.frames, i, k
            )
        return total

    def initial_step(self, choice: RankChoice, room2: float) -> float:
        """D whose quantization noise (about D/12 per stored number) fills ``room2``."""
        return 12.0 * room2 / self.stored_values(choice)
