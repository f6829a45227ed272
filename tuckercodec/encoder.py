"""The encoder: a mesh sequence to a compressed file that meets the error asked for.

Three modes, one at a time: a target KG error (the default, 0.1), fixed ranks (i, k), or a target
size in bpfv (the smallest error that fits).

How a target KG error is met (errors are squared norms; E is the KG denominator's square):

1. The exact table (:mod:`tuckercodec.analysis`) gives the truncation error of every (i, k).
2. Quantization adds error. An error e in column a of U1 reaches the tensor multiplied by the
   norm of core slice a, so column a gets the step sqrt(D) / ||CORE[a, :, :]||; likewise U3's
   column b with ||CORE[:, :, b]||, the core gets sqrt(D), the centroids sqrt(D / K) (an error
   there moves all K vertices). Every stored number then adds about D/12 to the squared error,
   which is also the split that minimises the bits for a given error (reverse water-filling),
   so one number D sets the whole quantizer.
3. For a few splits of the error budget between truncation and quantization, the encoder picks
   the cheapest ranks whose truncation error fits the truncation share (by the exact table, or by
   the paper's bound with ``select="bound"``), sets D from the remaining share, and packs the
   result to count its real bytes. The smallest wins.
4. It then reconstructs exactly what the decoder will return, measures the KG error, and
   tightens D (or loosens it once, if there is room) until the decoded error is at most the
   target. The decoded error is never above the target.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ._version import __version__
from .analysis import Analysis, Selection, analyze
from .errors import UnreachableTargetError
from .format import faces, names, qmat, sections, streams
from .format.container import pack_container
from .format.header import header_map
from .format.qmat import QuantizedMatrix
from .format.reconstruction import factor_value_count, reconstruct_frames, reconstruction_basis
from .hosvd import project
from .rate import bpfv as bits_per_frame_vertex
from .sequence import MeshSequence
from .topology import mesh_parents

DEFAULT_TARGET_KG = 0.1
#: Shares of the squared error budget given to truncation in the search (the rest is quantization).
TRUNCATION_SHARES = (0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
#: Fewer shares while searching for a size target, where each trial is a whole encode.
QUICK_SHARES = (0.1, 0.3, 0.5)
#: The decoded error must stay this far (relative) below the target, so that a decoder whose
#: BLAS rounds differently (about 1e-15 relative) still meets it.
SAFETY = 1e-9
#: With fixed ranks, quantization may add this much to the truncation's squared error (KG +5 %).
RANKS_QUANTIZATION_SHARE = 1.05**2 - 1
#: With fixed ranks that lose nothing, the quantization error aimed for, in KG percent.
RANKS_FLOOR_KG = 1e-4
#: The largest |integer| a section may stream: after zigzag it must fit streams.MAX_PLANES bytes.
LARGEST_STREAMED = 2 ** (8 * streams.MAX_PLANES - 1) - 1
#: Bytes of positions reconstructed at once when measuring the error: bounds the memory.
BLOCK_BYTES = 2 << 20

Mode = Literal["kg", "ranks", "bpfv"]


@dataclass(frozen=True)
class EncodeReport:
    """What the encoder did and measured. Errors are KG errors (Karni-Gotsman, per-frame mean)."""

    mode: Mode
    target: float | None  # the KG target (mode "kg") or bpfv target (mode "bpfv")
    select: Selection
    ranks: tuple[int, int]
    kg: float  # of the decoded sequence against the input
    truncation_kg: float  # of the truncation alone, before quantization
    exact_ranks: tuple[int, int] | None  # the cheapest ranks by the exact table (mode "kg")
    bound_ranks: tuple[int, int] | None  # what the paper's bound alone would pick (mode "kg")
    total_bytes: int
    section_bytes: dict[str, int] = field(default_factory=dict)
    vertices: int = 0
    frames: int = 0
    seconds: float = 0.0
    trials: int = 0

    @property
    def bpfv(self) -> float:
        """Bits per frame per vertex of the whole file, header and connectivity included."""
        return bits_per_frame_vertex(self.total_bytes, self.frames, self.vertices)

    @property
    def connectivity_bpfv(self) -> float:
        """The faces section's share of :attr:`bpfv`."""
        return bits_per_frame_vertex(self.section_bytes.get("FACE", 0), self.frames, self.vertices)

    @property
    def raw_float32_bytes(self) -> int:
        """The positions as plain float32: F * K * 3 * 4 bytes (faces not counted)."""
        return self.frames * self.vertices * 12

    @property
    def ratio(self) -> float:
        """:attr:`raw_float32_bytes` over the whole file's size."""
        return self.raw_float32_bytes / self.total_bytes


@dataclass(frozen=True)
class EncodeResult:
    """The file's bytes and the report of how they were made."""

    data: bytes
    report: EncodeReport


@dataclass
class _Quantized:
    """One quantization of one truncation: everything the file stores but the faces."""

    i: int
    k: int
    step: float  # D
    u1: QuantizedMatrix
    u3: QuantizedMatrix
    core: QuantizedMatrix
    centroids: QuantizedMatrix


class _Workspace:
    """The input, its analysis and the parts shared by every trial of the search."""

    def __init__(self, sequence: MeshSequence, analysis: Analysis, level: int) -> None:
        self.sequence = sequence
        self.analysis = analysis
        self.level = level
        self.vertex_count = sequence.vertex_count
        self.frame_count = sequence.frame_count
        # The KG denominator: each frame is centred, so ||A - E(A)|| is the centred tensor's norm.
        self.denominator2 = analysis.total_energy
        self.parents = mesh_parents(sequence.faces, self.vertex_count)
        self.face_section = faces.encode_faces(sequence.faces, level)
        self.name_section = names.encode_names(sequence.frame_names, level)
        self.centroid_floor_step, self.centroid_floor_error2 = self._centroid_floor()
        self._u1 = np.zeros((self.vertex_count, 0))
        self._core = np.zeros((0, 3, 0))

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

    def quantize(self, i: int, k: int, step: float) -> _Quantized:
        """Quantize the truncation (i, k) with the single parameter D = ``step`` (see above)."""
        u1, u3, core = self.factors(i, k)
        root = math.sqrt(step)
        row_norms = np.sqrt(np.square(core).sum(axis=(1, 2)))
        column_norms = np.sqrt(np.square(core).sum(axis=(0, 1)))
        centroids = self._quantized_centroids(root / math.sqrt(self.vertex_count))
        return _Quantized(
            i,
            k,
            step,
            qmat.quantize(u1, _steps(root, row_norms)),
            qmat.quantize(u3, _steps(root, column_norms)),
            qmat.quantize(core.reshape(-1, 1), np.array([root])),
            centroids,
        )

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

    def decoded_error2(self, quantized: _Quantized) -> float:
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

    def sections(self, quantized: _Quantized, level: int) -> list[tuple[dict[str, Any], bytes]]:
        """The file's sections, in the order of :data:`~.format.sections.WRITE_ORDER`."""
        coded = {"FACE": self.face_section}
        for section_id, matrix, parents, predict in (
            ("CENT", quantized.centroids, None, True),
            ("U3", quantized.u3, None, True),
            ("CORE", quantized.core, None, False),
            ("U1", quantized.u1, self.parents, True),
        ):
            coded[section_id] = qmat.encode_matrix(
                matrix, parents, allow_predict=predict, level=level
            )
        if self.name_section is not None:
            coded["NAME"] = self.name_section
        return [
            (sections.entry(section_id, coded[section_id][0]), coded[section_id][1])
            for section_id in sections.WRITE_ORDER
            if section_id in coded
        ]

    def trial_bytes(self, quantized: _Quantized) -> int:
        """The payload bytes at the fast search level: to compare trials, not the final size."""
        return sum(len(payload) for _, payload in self.sections(quantized, streams.SEARCH_LEVEL))

    def pack(
        self,
        quantized: _Quantized,
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


def _steps(root: float, norms: np.ndarray) -> np.ndarray:
    """sqrt(D) / norm per column; a column whose core slice is empty carries nothing (step 1)."""
    safe = np.where(norms > 0, norms, 1.0)
    return np.where(norms > 0, root / safe, 1.0)


# ------------------------------------------------------------------------------------------
# meeting a target


def _initial_step(work: _Workspace, i: int, k: int, budget2: float) -> float:
    """D such that the quantization noise, about D/12 per stored number, fills ``budget2``."""
    return 12.0 * budget2 / factor_value_count(work.vertex_count, work.frame_count, i, k)


def _meet(
    work: _Workspace, i: int, k: int, step: float, limit2: float
) -> tuple[_Quantized, float, int]:
    """Adjust D so that the decoded squared error is at most ``limit2``, as loose as it can be.

    Returns the quantization, its decoded squared error and the number of measurements.
    """
    # The error no choice of D removes: the truncation's, and the centroids' at their coarsest
    # usable step (zero unless the sequence lies far from the origin).
    truncation2 = work.truncation_error2(i, k) + work.centroid_floor_error2
    best: tuple[_Quantized, float] | None = None
    loosened = False
    for attempt in range(1, 40):
        quantized = work.quantize(i, k, step)
        error2 = work.decoded_error2(quantized)
        added = max(error2 - truncation2, 1e-300)
        room = limit2 - truncation2
        if error2 <= limit2:
            best = (quantized, error2)
            if loosened or added >= 0.97 * room:
                return quantized, error2, attempt
            loosened = True  # once: the noise model is a little pessimistic
            step *= min(1.5, 0.99 * room / added)
        elif best is not None:
            return best[0], best[1], attempt
        else:
            # the noise grows about linearly with D; aim a little inside and never stall
            step *= min(0.95, max(0.25, 0.97 * room / added))
    raise UnreachableTargetError(  # pragma: no cover
        f"could not meet the error target with ranks ({i}, {k})"
    )


def _search_kg(
    work: _Workspace, target_kg: float, select: Selection, shares: tuple[float, ...]
) -> tuple[_Quantized, float, int]:
    """The smallest file found for a target KG error: see the module docstring."""
    limit2 = (target_kg * (1.0 - SAFETY) / 100.0) ** 2 * work.denominator2
    work.check_reachable(limit2)
    trials: dict[tuple[int, int], tuple[int, float]] = {}
    candidates = []
    for share in shares:
        choice = work.analysis.cheapest(target_kg * math.sqrt(share), select=select)
        if (choice.i, choice.k) not in candidates:
            candidates.append((choice.i, choice.k))
    if candidates:  # form the factors once, for the largest ranks, rather than growing them
        work.factors(max(i for i, _ in candidates), max(k for _, k in candidates))
    for i, k in candidates:
        room = limit2 - work.truncation_error2(i, k) - work.centroid_floor_error2
        if room <= 0:
            continue
        step = _initial_step(work, i, k, room)
        trials[(i, k)] = (work.trial_bytes(work.quantize(i, k, step)), step)
    if not trials:  # the target is within rounding of zero error
        r1, r3 = work.analysis.max_ranks
        trials[(r1, r3)] = (0, _initial_step(work, r1, r3, max(limit2, 1e-300)))
    (i, k), (_, step) = min(trials.items(), key=lambda item: item[1][0])
    quantized, error2, measured = _meet(work, i, k, step, limit2)
    return quantized, error2, len(trials) + measured


# ------------------------------------------------------------------------------------------
# the public entry points


def _check_modes(
    target_kg: float | None, ranks: tuple[int, int] | None, target_bpfv: float | None
) -> Mode:
    given = [
        name
        for name, value in (
            ("target_kg", target_kg),
            ("ranks", ranks),
            ("target_bpfv", target_bpfv),
        )
        if value is not None
    ]
    if len(given) > 1:
        raise ValueError(f"give one of target_kg, ranks and target_bpfv, not {' and '.join(given)}")
    for name, value in (("target_kg", target_kg), ("target_bpfv", target_bpfv)):
        if value is not None and not (
            isinstance(value, (int, float, np.floating))
            and not isinstance(value, bool)
            and math.isfinite(value)
            and value > 0
        ):
            raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    if ranks is not None:
        return "ranks"
    return "bpfv" if target_bpfv is not None else "kg"


def encode_with_report(
    sequence: MeshSequence,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    select: Selection = "exact",
    level: int = streams.DEFAULT_LEVEL,
    analysis: Analysis | None = None,
) -> EncodeResult:
    """Encode a sequence; the file's bytes and a report of ranks, errors and sizes.

    Args:
        sequence: the mesh sequence (any number of frames; not every frame a single point).
        target_kg: the largest KG error allowed for the decoded sequence, in percent (default
            0.1 when no mode is given).
        ranks: fixed ranks (i, k); quantization then adds at most about 5 % to the KG error of
            the truncation.
        target_bpfv: the largest whole-file size in bits per frame per vertex; the smallest KG
            error that fits is chosen, down to a KG error of 1e-4 (a larger budget is not filled).
        select: ``"exact"`` chooses ranks by the exact error table, ``"bound"`` by the seed
            paper's bound alone.
        level: zstd level of the sections (1-22).
        analysis: the sequence's :func:`~tuckercodec.analyze` result, if already computed.

    Raises:
        InputError: the sequence cannot be encoded (every frame a single point, or coordinates
            float64 cannot square).
        UnreachableTargetError: no file of the format meets the target: a ``target_bpfv``
            below the coarsest file's size, or an error target too small for the format's
            32-bit integers (centroids far from the origin, or a target within rounding of 0).
        ValueError: a mode argument that is out of range (ranks, a non-positive target).
    """
    start = time.perf_counter()
    mode = _check_modes(target_kg, ranks, target_bpfv)
    if select not in ("exact", "bound"):
        raise ValueError(f"select must be 'exact' or 'bound', got {select!r}")
    if not isinstance(sequence, MeshSequence):
        raise TypeError(f"expected a MeshSequence, got {type(sequence).__name__}")
    analysis = analyze(sequence) if analysis is None else analysis
    work = _Workspace(sequence, analysis, level)
    exact_ranks = bound_ranks = None
    target: float | None = None

    if mode == "ranks":
        i, k = _checked_ranks(ranks, analysis)
        truncation2 = work.truncation_error2(i, k)
        floor2 = (RANKS_FLOOR_KG / 100.0) ** 2 * work.denominator2
        budget2 = max(
            RANKS_QUANTIZATION_SHARE * truncation2, floor2, 1.01 * work.centroid_floor_error2
        )
        quantized, error2, trials = _meet(
            work, i, k, _initial_step(work, i, k, budget2), truncation2 + budget2
        )
        target_for_header = None
    elif mode == "kg":
        target = DEFAULT_TARGET_KG if target_kg is None else float(target_kg)
        exact, bound = analysis.cheapest(target), analysis.cheapest(target, select="bound")
        exact_ranks, bound_ranks = (exact.i, exact.k), (bound.i, bound.k)
        quantized, error2, trials = _search_kg(work, target, select, TRUNCATION_SHARES)
        target_for_header = target
    else:
        assert target_bpfv is not None  # the mode says so
        target = float(target_bpfv)
        quantized, error2, trials = _search_bpfv(work, target, select)
        target_for_header = None

    data, sizes = work.pack(quantized, error2, target_for_header)
    report = EncodeReport(
        mode=mode,
        target=target,
        select=select,
        ranks=(quantized.i, quantized.k),
        kg=work.kg(error2),
        truncation_kg=work.kg(work.truncation_error2(quantized.i, quantized.k)),
        exact_ranks=exact_ranks,
        bound_ranks=bound_ranks,
        total_bytes=len(data),
        section_bytes=sizes,
        vertices=work.vertex_count,
        frames=work.frame_count,
        seconds=time.perf_counter() - start,
        trials=trials,
    )
    return EncodeResult(data, report)


def _checked_ranks(ranks: Any, analysis: Analysis) -> tuple[int, int]:
    r1, r3 = analysis.max_ranks
    try:
        i, k = (int(r) for r in ranks)
        valid = all(float(a) == b for a, b in zip(ranks, (i, k), strict=True))
    except (TypeError, ValueError):
        valid = False
    if not valid or not (1 <= i <= r1 and 1 <= k <= r3):
        raise ValueError(
            f"ranks must be two integers with 1 <= i <= {r1} and 1 <= k <= {r3}, got {ranks!r}"
        )
    return i, k


def _search_bpfv(
    work: _Workspace, target_bpfv: float, select: Selection
) -> tuple[_Quantized, float, int]:
    """The smallest KG error whose file fits ``target_bpfv``: bisection on log KG, sizing the
    trials at the fast zstd level, then the final level checked (and the error loosened a step
    at a time in the rare case that it packs larger)."""
    budget = target_bpfv * work.frame_count * work.vertex_count / 8.0

    def attempt(
        kg: float, shares: tuple[float, ...], level: int | None
    ) -> tuple[_Quantized, float, int, int]:
        quantized, error2, trials = _search_kg(work, kg, select, shares)
        return quantized, error2, trials, len(work.pack(quantized, error2, None, level)[0])

    trials = 0
    low, high = math.log(1e-4), math.log(100.0)  # KG percent
    best = attempt(100.0, QUICK_SHARES[:1], None)
    trials += best[2]
    if best[3] > budget:
        faces_bpfv = bits_per_frame_vertex(
            len(work.face_section[1]), work.frame_count, work.vertex_count
        )
        raise UnreachableTargetError(
            f"no file fits {target_bpfv} bpfv: even the coarsest one needs "
            f"{bits_per_frame_vertex(best[3], work.frame_count, work.vertex_count):.3f} bpfv "
            f"(the faces alone take {faces_bpfv:.3f})"
        )
    for _ in range(14):  # log KG to within about 1 %
        middle = 0.5 * (low + high)
        try:
            result = attempt(math.exp(middle), QUICK_SHARES, streams.SEARCH_LEVEL)
        except UnreachableTargetError:  # the centroids far from the origin cannot reach it
            low = middle  # behaves as "too large": smaller errors are out of reach too
            continue
        trials += result[2]
        if result[3] <= budget:
            high = middle
        else:
            low = middle
    while high < math.log(100.0):
        result = attempt(math.exp(high), QUICK_SHARES, None)
        trials += result[2]
        if result[3] <= budget:
            return result[0], result[1], trials
        high += 0.02
    return best[0], best[1], trials


def encode(
    sequence: MeshSequence,
    *,
    target_kg: float | None = None,
    ranks: tuple[int, int] | None = None,
    target_bpfv: float | None = None,
    select: Selection = "exact",
) -> bytes:
    """Encode a sequence into the bytes of a file (``spec/FORMAT.md``).

    One mode at a time: ``target_kg`` (default 0.1, a KG error in percent that the decoded
    sequence never exceeds), ``ranks`` (i, k), or ``target_bpfv`` (the smallest error that fits).
    :func:`encode_with_report` also says what was chosen and measured.
    """
    return encode_with_report(
        sequence, target_kg=target_kg, ranks=ranks, target_bpfv=target_bpfv, select=select
    ).data


__all__ = ["EncodeReport", "EncodeResult", "encode", "encode_with_report"]
