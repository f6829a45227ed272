"""The :class:`Encoder`: one set of options, any number of sequences, and the one place that
decides whether a sequence is encoded whole (format 1.0) or in segments (format 1.1).

Every way into the encoder goes through here: :func:`tuckercodec.encode` and
:func:`~tuckercodec.encode_with_report`, :func:`tuckercodec.encode_file`, ``batch``, the zarr
codecs and the ``encode`` command all build an :class:`Encoder` from
:class:`~.options.EncodeOptions`. The choice made, a workspace (:mod:`.whole` or
:mod:`.segmented`) goes through the one search (:mod:`.search`) and packs the file.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from ..analysis import Analysis, analyze
from ..errors import InternalError
from ..format import residual, streams
from ..io.streaming import FrameSource, SequenceFrames
from ..parallel import Executor, InProcessExecutor, open_executor
from ..sequence import MeshSequence
from . import corrections, search
from .options import DEFAULT_TARGET_KG, EncodeOptions
from .plan import default_max_memory, needs_segments, plan_segments
from .results import EncodeReport, EncodeResult
from .segmented import SegmentedWorkspace, SharedBasis
from .trial import Quantized, Workspace
from .whole import Connectivity, WholeWorkspace

Progress = Callable[[str], None]


class Encoder:
    """Encodes mesh sequences as its :class:`~.options.EncodeOptions` say.

    Args:
        options: what to encode for (default: a KG error of 0.1).
        executor: where a segmented encode's passes run, if not where ``options.jobs`` or
            ``options.scheduler`` say (the bytes written do not depend on it).
        progress: called with a line of text as each pass of a segmented encode starts.
    """

    def __init__(
        self,
        options: EncodeOptions | None = None,
        *,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> None:
        self.options = EncodeOptions() if options is None else options
        if not isinstance(self.options, EncodeOptions):
            raise TypeError(f"expected EncodeOptions, got {type(self.options).__name__}")
        self.executor = executor
        self.progress = progress

    def segments(self, frame_count: int, vertex_count: int) -> bool:
        """Whether a sequence of this size is encoded in segments: when ``segment_frames`` is
        given, or when encoding it whole would not fit ``max_memory``."""
        return needs_segments(
            frame_count,
            vertex_count,
            segment_frames=self.options.segment_frames,
            max_memory=self.options.max_memory,
        )

    def encode(self, sequence: MeshSequence) -> bytes:
        """The bytes of a file (``spec/FORMAT.md``) holding ``sequence``."""
        return self.encode_with_report(sequence).data

    def encode_with_report(
        self, sequence: MeshSequence, *, analysis: Analysis | None = None
    ) -> EncodeResult:
        """The file's bytes and a report of ranks, errors and sizes; ``analysis``: the
        sequence's :func:`~tuckercodec.analyze` result, if already computed (used whole)."""
        if not isinstance(sequence, MeshSequence):
            raise TypeError(f"expected a MeshSequence, got {type(sequence).__name__}")
        return self.encode_source(SequenceFrames(sequence), analysis=analysis)

    def encode_source(
        self, frames: FrameSource, *, analysis: Analysis | None = None
    ) -> EncodeResult:
        """Encode an opened sequence (:func:`tuckercodec.io.open_frames`): whole when
        :meth:`segments` says no, else in segments read a range of frames at a time."""
        if self.segments(frames.frame_count, frames.vertex_count):
            return self.encode_segments(frames)
        if self.options.jobs is not None or self.options.scheduler is not None:
            self._say(
                "note: --jobs and --scheduler run the passes of a segmented encode; this "
                "sequence is encoded whole, in this process (give --segment-frames to segment it)"
            )
        return self._encode_whole(frames.load(), analysis)

    def encode_segments(
        self, frames: FrameSource, *, shared_basis: SharedBasis | None = None
    ) -> EncodeResult:
        """Encode in segments (format 1.1), however small the sequence: ``segment_frames``
        frames each (default 250). With ``shared_basis`` (the U1 section of another segmented
        file, :func:`~.segmented.shared_basis_of`), every segment uses its leading columns and
        the file holds the section byte for byte."""
        start = time.perf_counter()
        options = self.options
        if options.select != "exact":
            raise ValueError("a segmented encode chooses its ranks by the exact error (select)")
        memory = default_max_memory() if options.max_memory is None else options.max_memory
        plan = plan_segments(
            frames.frame_count,
            frames.vertex_count,
            segment_frames=options.segment_frames,
            max_memory=memory,
        )
        goal = None
        if options.corrections:  # a pass for the bound's length or the lossless domains
            goal = corrections.goal_of_source(options, frames, plan.block_frames)
        with self._executor() as executor:
            work = SegmentedWorkspace(
                frames, plan, options.basis, executor, options.level, self.progress, shared_basis
            )
            if goal is not None:
                return self._segments_corrected(work, frames, goal, start)
            quantized, error2, trials = self._search(work)
        choice = quantized.choice
        largest_i = choice.shared or max(i for i, _ in choice.ranks)
        return self._result(
            work,
            quantized,
            error2,
            start,
            ranks=(largest_i, max(k for _, k in choice.ranks)),
            truncation2=choice.truncation2,
            select="exact",
            trials=trials + work.passes,
            segments=len(work.models),
            basis=options.basis,
        )

    def _encode_whole(self, sequence: MeshSequence, analysis: Analysis | None) -> EncodeResult:
        """One decomposition of the sequence in memory (format 1.0)."""
        start = time.perf_counter()
        options = self.options
        # The faces' coding (Python loops) runs beside the decomposition (BLAS, which releases
        # the GIL): on two cores about the shorter of the two is saved. The same bytes.
        with ThreadPoolExecutor(max_workers=1) as pool:
            connectivity = pool.submit(Connectivity.of, sequence, options.level)
            analysis = analyze(sequence) if analysis is None else analysis
            coded = connectivity.result()
        work = WholeWorkspace(sequence, analysis, options.level, options.select, coded)
        if options.corrections:
            return self._encode_corrected(work, start)
        quantized, error2, trials = self._search(work)
        extra: dict[str, Any] = {}
        if options.mode == "kg":  # what each way of choosing ranks alone would pick
            exact = analysis.cheapest(options.kg_target)
            bound = analysis.cheapest(options.kg_target, select="bound")
            extra = {"exact_ranks": (exact.i, exact.k), "bound_ranks": (bound.i, bound.k)}
        extra["max_distance"], extra["max_distance_at"] = work.worst_vertex(quantized)
        return self._result(
            work,
            quantized,
            error2,
            start,
            ranks=quantized.choice,
            truncation2=work.truncation_error2(quantized.choice),
            select=options.select,
            trials=trials,
            **extra,
        )

    def _encode_corrected(self, work: WholeWorkspace, start: float) -> EncodeResult:
        """A bound on every vertex, or lossless (format 1.3 where corrections are needed):
        the smallest Tucker part plus corrections (:mod:`.corrections`), packed, then decoded
        and checked before it is returned."""
        options = self.options
        sequence = work.sequence
        goal = corrections.goal_of(options, sequence)
        chosen, trials = corrections.search_whole(work, options, goal)
        u2 = work.analysis.decomposition.u2
        final = corrections.final_section(chosen, goal, sequence.vertices, u2, options.level)
        quantized = chosen.quantized
        target_kg = options.target_kg if options.mode == "kg" else None
        section, integers = None, None
        if final is not None:
            section, integers, decoded = final
        else:
            decoded = corrections.plain_positions(quantized, u2)
        distance, where = corrections.worst_vertex(decoded, sequence.vertices)
        difference = decoded - sequence.vertices
        error2 = float(np.square(difference).sum())
        claims = {
            "max_distance": distance,
            "max_distance_at": [where[0], where[1]],
            "target_max_distance": goal.bound,
            "lossless": goal.lossless,
        }
        data, sizes = work.pack(quantized, error2, target_kg, correction=section, claims=claims)
        # the promise, checked on the positions measured and on the bytes returned
        corrections.verify(decoded, sequence.vertices, goal if section else None, goal.bound)
        if integers is not None:
            corrections.check_written(data, integers)
        if target_kg is not None and work.kg(error2) > target_kg:
            raise InternalError(
                f"the corrected file's KG error {work.kg(error2):.6g} is above the target "
                f"{target_kg}"
            )
        return self._report(
            work,
            data,
            sizes,
            start,
            select=options.select,
            ranks=quantized.choice,
            kg=work.kg(error2),
            truncation_kg=work.kg(work.truncation_error2(quantized.choice)),
            trials=trials,
            max_distance=distance,
            max_distance_at=where,
            max_error=goal.bound,
            lossless=goal.lossless,
            corrections=chosen.domain.describe() if chosen.domain and section else None,
        )

    def _segments_corrected(
        self, work: SegmentedWorkspace, frames: FrameSource, goal: corrections.Goal, start: float
    ) -> EncodeResult:
        """A segmented file with corrections (format 1.3): the Tucker part for the KG target,
        or for the KG error whose part made the smallest file of the first segment encoded
        whole; then a pass that corrects every segment, measured and read back."""
        options = self.options
        if options.ranks is not None:
            quantized, _, trials = search.encode_ranks(work, options.ranks)
        else:
            kg = options.target_kg
            if kg is None:
                first = work.ranges[0]
                head = MeshSequence(frames.read(first.start, first.stop), frames.faces)
                whole = WholeWorkspace(head, analyze(head), streams.SEARCH_LEVEL, "exact")
                chosen, _ = corrections.search_whole(whole, options, goal)
                kg = chosen.kg if chosen.kg is not None else DEFAULT_TARGET_KG
            quantized, _, trials = search.search_kg(work, kg)
        fixed = corrections.correct_segments(work, quantized, goal, options.level)
        claims = {
            "max_distance": fixed.worst.distance,
            "max_distance_at": list(fixed.worst.at),
            "target_max_distance": goal.bound,
            "lossless": goal.lossless,
        }
        target_kg = options.target_kg if options.mode == "kg" else None
        data, sizes = work.pack(
            quantized, fixed.error2, target_kg, corrections=fixed.sections, claims=claims
        )
        for number, integers in enumerate(fixed.integers):
            corrections.check_written(data, integers, f"{residual.SECTION_STEM}.{number}")
        if target_kg is not None and work.kg(fixed.error2) > target_kg:
            raise InternalError(
                f"the corrected file's KG error {work.kg(fixed.error2):.6g} is above the target "
                f"{target_kg}"
            )
        choice = quantized.choice
        names = sorted({domain.describe() for domain in fixed.domains})
        return self._report(
            work,
            data,
            sizes,
            start,
            select="exact",
            ranks=(
                choice.shared or max(i for i, _ in choice.ranks),
                max(k for _, k in choice.ranks),
            ),
            kg=work.kg(fixed.error2),
            truncation_kg=work.kg(choice.truncation2),
            trials=trials + work.passes,
            segments=len(work.models),
            basis=options.basis,
            max_distance=fixed.worst.distance,
            max_distance_at=fixed.worst.at,
            max_error=goal.bound,
            lossless=goal.lossless,
            corrections=", ".join(names),
        )

    def _report(
        self,
        work: Workspace[Any],
        data: bytes,
        sizes: dict[str, int],
        start: float,
        **fields: Any,
    ) -> EncodeResult:
        """The file and its report: the mode and sizes every encode states, and ``fields``."""
        return EncodeResult(
            data,
            EncodeReport(
                mode=self.options.mode,
                target=self.options.target,
                total_bytes=len(data),
                section_bytes=sizes,
                vertices=work.vertex_count,
                frames=work.frame_count,
                seconds=time.perf_counter() - start,
                **{"exact_ranks": None, "bound_ranks": None, **fields},
            ),
        )

    def _search(self, work: Workspace[Any]) -> tuple[Quantized[Any], float, int]:
        """The mode's search, the same for either workspace."""
        options = self.options
        if options.ranks is not None:
            return search.encode_ranks(work, options.ranks)
        if options.target_bpfv is not None:
            return search.search_bpfv(work, options.target_bpfv)
        return search.search_kg(work, options.kg_target)

    def _result(
        self,
        work: Workspace[Any],
        quantized: Quantized[Any],
        error2: float,
        start: float,
        *,
        ranks: tuple[int, int],
        truncation2: float,
        **report: Any,
    ) -> EncodeResult:
        """Pack the file (its header states the KG target of an error target only) and report
        on it; ``report``: the fields only one kind of workspace knows."""
        options = self.options
        header_target = options.kg_target if options.mode == "kg" else None
        data, sizes = work.pack(quantized, error2, header_target)
        return self._report(
            work,
            data,
            sizes,
            start,
            ranks=ranks,
            kg=work.kg(error2),
            truncation_kg=work.kg(truncation2),
            **report,
        )

    def _say(self, line: str) -> None:
        if self.progress is not None:
            self.progress(line)

    @contextlib.contextmanager
    def _executor(self) -> Iterator[Executor]:
        """The executor given, or one for ``jobs``/``scheduler`` (closed after), or this
        process."""
        if self.executor is not None:
            yield self.executor
        elif self.options.jobs is None and self.options.scheduler is None:
            yield InProcessExecutor()
        else:
            with open_executor(self.options.jobs, self.options.scheduler) as executor:
                yield executor
