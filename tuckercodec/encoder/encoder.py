"""The :class:`Encoder`: one set of options, any number of sequences, and the one place that
decides whether a sequence is encoded whole (format 1.0) or in segments (format 1.1), and
whether the sequence fits the format version asked for (:mod:`.versions`).

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

from ..decomposition.analysis import Analysis, analyze
from ..errors import InternalError
from ..format.adaptive import ADAPTIVE_MINOR, uses_adaptive
from ..format.attachments import ATTACHMENTS_MINOR
from ..format.container import PREAMBLE, SCENE_MINOR, SIGNATURE
from ..format.header import scene_keys
from ..format.sections import CODING_TOOLS_MINOR, uses_coding_tools
from ..format.sections import entry as section_entry
from ..format.segments import BASIS_OWN, SEGMENTED_MINOR
from ..model.attributes import Field
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource, SequenceFrames
from ..model.topology import MeshPrediction
from ..system.memory import memory_allowed
from ..system.parallel import Executor, InProcessExecutor, open_executor
from . import corrections, promises, search
from .options import EncodeOptions
from .plan import needs_segments, plan_segments
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
        self._refuse_newer_data(frames)
        if self.segments(frames.frame_count, frames.vertex_count):
            self.options.features.require(
                SEGMENTED_MINOR,
                "a sequence larger than max_memory",
                "it is encoded in segments, spec §6.7",
                "give a larger max_memory",
            )
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
        the file holds the section byte for byte. ``FormatVersionError`` where
        ``format_version`` is below 1.1, or below what the basis's section uses."""
        start = time.perf_counter()
        options = self.options
        if options.select != "exact":
            raise ValueError("a segmented encode chooses its ranks by the exact error (select)")
        self._refuse_newer_data(frames)
        features = options.features
        features.require(
            SEGMENTED_MINOR, "encode_segments", "segmented files, spec §6.7", "encode it whole"
        )
        if shared_basis is not None:
            self._refuse_newer_basis(shared_basis)
        memory = memory_allowed(options.max_memory)
        plan = plan_segments(
            frames.frame_count,
            frames.vertex_count,
            segment_frames=options.segment_frames,
            max_memory=memory,
            faces=len(frames.faces),
            basis_own=options.basis == BASIS_OWN,
            level=options.level,
        )
        corrector = None
        if options.corrections:  # a pass for the bound's length or the lossless domains
            corrector = corrections.Corrector(options, frames, plan.block_frames)
        with self._executor() as executor:
            work = SegmentedWorkspace(
                frames,
                plan,
                options.basis,
                executor,
                options.level,
                self.progress,
                shared_basis,
                face_order=options.face_order,
                keep=options.attachments,
                features=features,
            )
            if options.attachments and frames.field_names:
                fields = frames.read_fields(0, frames.frame_count)  # whole: see §6.13
                work.attached += self._field_sections(fields, work.mesh)
            if corrector is not None:
                return self._corrected(work, corrector, start)
            quantized, error2, trials = self._search(work)
        return self._result(work, quantized, error2, start, trials)

    def _encode_whole(self, sequence: MeshSequence, analysis: Analysis | None) -> EncodeResult:
        """One decomposition of the sequence in memory (format 1.0)."""
        start = time.perf_counter()
        options = self.options
        # The faces' coding (Python loops) runs beside the decomposition (BLAS, which releases
        # the GIL): on two cores about the shorter of the two is saved. The same bytes.
        with ThreadPoolExecutor(max_workers=1) as pool:
            connectivity = pool.submit(
                Connectivity.of,
                sequence,
                options.level,
                options.face_order,
                options.attachments,
                options.features,
            )
            analysis = analyze(sequence) if analysis is None else analysis
            coded = connectivity.result()
        work = WholeWorkspace(
            sequence, analysis, options.level, options.select, coded, options.features
        )
        if options.attachments and sequence.fields:
            work.attached += self._field_sections(sequence.fields, coded.mesh)
        if options.corrections:
            return self._corrected(work, corrections.Corrector(options, sequence), start)
        quantized, error2, trials = self._search(work)
        extra: dict[str, Any] = {}
        if options.mode == "kg":  # what each way of choosing ranks alone would pick
            exact = analysis.cheapest(options.kg_target)
            bound = analysis.cheapest(options.kg_target, select="bound")
            extra = {"exact_ranks": (exact.i, exact.k), "bound_ranks": (bound.i, bound.k)}
        extra["max_distance"], extra["max_distance_at"] = work.worst_vertex(quantized)
        return self._result(work, quantized, error2, start, trials, **extra)

    def _refuse_newer_data(self, frames: FrameSource) -> None:
        """Refuse a sequence whose data the format version asked for cannot hold: its time
        and scene keys (1.4) or, kept, its attributes, face sets and fields (1.5). Nothing is
        dropped unasked: every decoder of 1.x reads the positions of such files anyway (§10)."""
        features = self.options.features
        scene = scene_keys(
            frames.frame_count, frames.time_codes, frames.meters_per_unit, frames.up_axis
        )
        if scene:
            features.require(
                SCENE_MINOR,
                f"the sequence's {', '.join(sorted(scene))}",
                "header keys, spec §4, that decoders of 1.0 to 1.3 ignore",
                "remove them from the sequence",
            )
        if self.options.attachments:
            carried = [
                name
                for name, present in (
                    ("attributes", frames.attributes),
                    ("face sets", frames.face_sets),
                    ("fields", frames.field_names),
                )
                if present
            ]
            if carried:
                features.require(
                    ATTACHMENTS_MINOR,
                    f"the sequence's {' and '.join(carried)}",
                    "ancillary sections, spec §6.10 to §6.13, that decoders of 1.0 to 1.4 skip",
                    "attachments=False (--no-attributes) to write the positions and faces alone",
                )

    def _refuse_newer_basis(self, shared_basis: SharedBasis) -> None:
        """Refuse a given shared basis whose section, copied byte for byte, uses a feature
        newer than the format version asked for."""
        features = self.options.features
        entry = section_entry("U1", shared_basis.params)
        if uses_coding_tools([entry]):
            features.require(
                CODING_TOOLS_MINOR,
                "the shared basis",
                "U1's predictor 2, spec §6.2",
                "a basis of an older file",
            )
        if uses_adaptive([entry]):
            features.require(
                ADAPTIVE_MINOR,
                "the shared basis",
                "adaptive coding, spec §6.14",
                "a basis of an older file",
            )

    def _field_sections(
        self, fields: list[Field], mesh_prediction: MeshPrediction
    ) -> list[tuple[dict[str, Any], bytes]]:
        """The sections of every animated field, each meeting its own target (format 1.5)."""
        from .fields import FieldTarget, encode_field

        packed: list[tuple[dict[str, Any], bytes]] = []
        for number, item in enumerate(fields):
            target = FieldTarget.parse(self.options.target_of_field(item.name))
            mesh = mesh_prediction if item.domain == "vertex" else None
            encoded = encode_field(item, number, target, mesh, self.options.level)
            packed += encoded.sections
        return packed

    def _corrected(
        self,
        work: WholeWorkspace | SegmentedWorkspace,
        corrector: corrections.Corrector,
        start: float,
    ) -> EncodeResult:
        """A bound on every vertex, or lossless (format 1.3 where corrections are needed), the
        same for either workspace: the file the corrections make, check and read back
        (:class:`.corrections.Corrector`), packed with the header's claims (:meth:`_pack`)."""

        def pack(fixed: corrections.CorrectedFile) -> tuple[bytes, dict[str, int]]:
            return self._pack(work, fixed.quantized, fixed.error2, fixed)

        fixed = corrector.file(work, pack)
        return self._report(
            work,
            fixed.data,
            fixed.sizes,
            start,
            kg=work.kg(fixed.error2),
            **self._shape(work, fixed.quantized, fixed.trials),
            max_distance=fixed.worst.distance,
            max_distance_at=fixed.worst.at,
            max_error=fixed.bound,
            lossless=self.options.lossless,
            corrections=fixed.domains,
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
        work: WholeWorkspace | SegmentedWorkspace,
        quantized: Quantized[Any],
        error2: float,
        start: float,
        trials: int,
        **report: Any,
    ) -> EncodeResult:
        """Pack a file without corrections and report on it; ``report``: the fields only a
        whole encode knows."""
        data, sizes = self._pack(work, quantized, error2)
        return self._report(
            work,
            data,
            sizes,
            start,
            kg=work.kg(error2),
            **self._shape(work, quantized, trials),
            **report,
        )

    def _pack(
        self,
        work: WholeWorkspace | SegmentedWorkspace,
        quantized: Quantized[Any],
        error2: float,
        fixed: corrections.CorrectedFile | None = None,
    ) -> tuple[bytes, dict[str, int]]:
        """The file's bytes and section sizes, for every kind of file: what its header claims
        (the KG target, and the worst vertex, bound and lossless claim of a file made with
        corrections) decided by :func:`.promises.header_claims`, which checks the KG promise."""
        if fixed is None:
            stated = promises.header_claims(self.options, work.kg(error2))
            packed = work.pack(quantized, error2, stated.target_kg, claims=stated.error)
        else:
            stated = promises.header_claims(self.options, work.kg(error2), fixed.worst, fixed.bound)
            packed = work.pack(
                quantized,
                error2,
                stated.target_kg,
                corrections=fixed.sections,
                claims=stated.error,
            )
        self._check_version(packed[0])
        return packed

    def _check_version(self, data: bytes) -> None:
        """The file's minor version is at most the one asked for: every feature newer was
        refused or left unused before, so a file above it is a bug."""
        _, minor, *_ = PREAMBLE.unpack_from(data, len(SIGNATURE))
        features = self.options.features
        if minor > features.minor:
            raise InternalError(
                f"the encoder wrote a file of format 1.{minor}, newer than format_version "
                f"{features.version}"
            )

    def _shape(
        self, work: WholeWorkspace | SegmentedWorkspace, quantized: Quantized[Any], trials: int
    ) -> dict[str, Any]:
        """The report's fields that depend on the kind of file: the ranks (a segmented file's:
        the shared basis's columns or the largest i, and the largest k), the truncation's KG
        error, how ranks were chosen, the trials (a segmented encode's passes counted) and the
        segments."""
        choice = quantized.choice
        if isinstance(work, WholeWorkspace):
            return {
                "ranks": choice,
                "truncation_kg": work.kg(work.truncation_error2(choice)),
                "select": self.options.select,
                "trials": trials,
            }
        return {
            "ranks": (
                choice.shared or max(i for i, _ in choice.ranks),
                max(k for _, k in choice.ranks),
            ),
            "truncation_kg": work.kg(choice.truncation2),
            "select": "exact",
            "trials": trials + work.passes,
            "segments": len(work.models),
            "basis": self.options.basis,
        }

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
