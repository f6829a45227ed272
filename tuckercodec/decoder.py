"""The decoder: a compressed file back to vertex positions, all frames or any of them.

It follows ``spec/FORMAT.md`` step by step, over :mod:`tuckercodec.format`: the container (§2-5),
the header fields (§4), the sections (§6) and the reconstruction (§8)::

    positions[f, v, x] = sum_{a,c,b} U1[v, a] * CORE[a, c, b] * U2[x, c] * U3[f, b] + CENT[f, x]

A file of format 1.0 is one decomposition; a segmented file (§6.7) is one per segment of frames,
sharing the faces and, usually, U1. Opening a :class:`Decoder` on a path reads the preamble and
header only; a frame's segment is read from disk (its sections' byte ranges) and decoded the
first time one of its frames is asked for, so frame t of a long file costs its segment, never
the whole file. Each frame then costs one (K x i) by (i x 3) product.

A file of format 1.3 with corrections (§6.9) is reconstructed in the one exact order of §8.1 and
each position then corrected by its integer; the integers are read a chunk of frames at a time.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import os
from collections import OrderedDict
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import FormatError
from .format import adaptive, attributes, face_order, face_sets, faces, names, qmat, residual
from .format.attachments import find_attachments
from .format.container import parse_container
from .format.disk import FileRanges, open_file_container, read_file
from .format.header import FileInfo, read_header
from .format.limits import DEFAULT_LIMITS, Limits, check_limit
from .format.reconstruction import reconstruct_frames, reconstruction_basis
from .format.sections import Section
from .format.segments import BASIS_OWN, BASIS_SHARED, SegmentEntry
from .model.attributes import Attribute, FaceSet, Field
from .model.sequence import MeshSequence, default_frame_names
from .model.topology import MeshPrediction
from .system import native

#: A compressed file: its bytes, or a path to read it from.
CompressedFile = bytes | bytearray | memoryview | str | os.PathLike[str]
#: Which frames to decode: one number, a slice, a range, numbers (a list or an integer array),
#: or all (``None``).
FrameSelection = int | slice | range | Sequence[int] | np.ndarray | None


def _bytes_of(source: CompressedFile) -> bytes | memoryview:
    """The bytes of a file given in memory."""
    if isinstance(source, bytes):
        return source
    if isinstance(source, (bytearray, memoryview)):
        return memoryview(source).cast("B")
    raise TypeError(f"expected the bytes of a file or a path, got {type(source).__name__}")


@dataclass(frozen=True, eq=False)
class SegmentFactors:
    """The dequantized factors of one segment (§6.3): frames ``start .. stop - 1`` are
    ``U1 (K x i) . CORE (i x 3 x k) x2 U2 x3 U3 (n x k) + CENT (n x 3)`` (§8)."""

    start: int
    stop: int
    u1: np.ndarray
    u3: np.ndarray
    core: np.ndarray
    centroids: np.ndarray
    u2: np.ndarray
    basis: np.ndarray  # CORE x2 U2, (i, 3, k), formed once for every frame of the segment
    #: U1's integers and steps, kept in a file with corrections for §8.1
    u1_quantized: qmat.QuantizedMatrix | None = None
    #: with corrections (§6.9): the section's checked layout and id, and what §8.1 takes
    corrections: residual.ResidualLayout | None = None
    residual_id: str = ""
    exact_u1: residual.ExactU1 | None = None
    exact_basis: np.ndarray | None = None
    #: format 1.8: the corrections' codebooks and their midpoints, once a frame has needed them
    #: (after §8.1's weights, in §5's order); kept, and dropped, with the segment
    codebooks: list[tuple[residual.Codebooks, tuple[np.ndarray | None, ...]]] = field(
        default_factory=list
    )


#: A segment's dequantized U3, CORE and CENT.
OtherFactors = tuple[np.ndarray, np.ndarray, np.ndarray]

#: Decoded segments a :class:`Decoder` keeps, most recent first: playback walks forward.
CACHED_SEGMENTS = 2
#: Decoded chunks of corrections kept (about a million integers each, §6.9).
CACHED_CHUNKS = 3
#: The fewest integers adaptively coded in U3, CORE and CENT that are decoded on a thread beside
#: U1's (about half a millisecond of work, several times what starting the thread costs).
BESIDE_U1 = 16384
#: Threads that correct chunks at once: the work is numpy's and zstd's, which release the GIL.
CHUNK_THREADS = min(4, os.cpu_count() or 1)


class Decoder:
    """An opened compressed file: the header checked, the factors decoded as frames need them.

    Args:
        source: the whole file's bytes, or a path: then only the preamble and header are read
            at first, and each segment's sections when one of its frames is asked for (only a
            regular file; errors name it). A file of format 1.0 is one segment, decoded and
            checked whole when it is opened.
        limits: the decoder's limits (§7).

    Raises:
        FormatError: or one of its subclasses, with the rule broken and the field or offset at
            fault (and the path, for a file read from disk). For a segmented file, a damaged
            segment is found when it is first decoded; :meth:`check` decodes every one.
        InputError: a path that is a folder, a pipe or a device.
        OSError: a path that cannot be read.
    """

    def __init__(self, source: CompressedFile, *, limits: Limits = DEFAULT_LIMITS) -> None:
        self.path = os.fspath(source) if isinstance(source, (str, os.PathLike)) else None
        self.limits = limits
        self._segments: OrderedDict[int, SegmentFactors] = OrderedDict()
        self._shared_u1: qmat.QuantizedMatrix | None = None
        self._shared_u1_values: np.ndarray | None = None  # dequantized once for every segment
        self._mesh: MeshPrediction | None = None
        self._chunks: OrderedDict[tuple[int, int], np.ndarray] = OrderedDict()
        #: each recent segment's codebooks (format 1.8) and their midpoints
        self._data: bytes | memoryview | FileRanges
        with self._naming_path():
            if isinstance(source, (str, os.PathLike)):
                self._container, self._data = open_file_container(source, limits)
            else:
                data = _bytes_of(source)
                self._container, self._data = parse_container(data, limits), data
            self.info = read_header(self._container, limits)
            self._index = self._segment_index()
            self._starts = np.array([segment.start for segment in self._index], dtype=np.int64)
            # a file decoded at once whose U3, CORE and CENT are decoded beside U1: their
            # thread started now, so that handing them to it later costs the open nothing
            self._early_pool: ThreadPoolExecutor | None = None
            if not self.segmented and self._others_beside(self._index[0]):
                self._early_pool = ThreadPoolExecutor(1)
                self._early_pool.submit(int)
            try:
                face = self._section("FACE")
                self.faces = faces.decode_face_section(
                    face.codec,
                    self._payload("FACE"),
                    face.params,
                    self.info.vertices,
                    "section FACE",
                    limits,
                    adaptive_coding=self._container.adaptive,  # §6.8's coder 1 only in 1.6
                    uniform_ranks=self._container.uniform_ranks,  # and its ranks 1 in 1.9
                )
                self._coded_faces = self.faces  # as FACE decodes them: U1's mesh's faces
                if not self.segmented:  # §5 steps 16-17 in order: U1, U3, CORE, CENT, NAME
                    self.segment_factors(0)
            finally:
                if self._early_pool is not None:
                    self._early_pool.shutdown()
                    self._early_pool = None
            self.frame_names = self._decode_names()
            if self._container.corrections and not self.segmented:
                self._segments[0] = self._with_corrections(self._segments[0], self._index[0])
            self._attached = find_attachments(self._container.sections)
            self.faces = self._faces_in_given_order()
            self.attributes: list[Attribute] = self._decode_attributes()
            self.face_sets: list[FaceSet] = self._decode_face_sets()

    @property
    def corrections(self) -> str | None:
        """The domain of the file's corrections (§6.9: ``"grid"``, ``"float32"`` or
        ``"float64"``), from its first segment; ``None`` for a file without them."""
        if not self._container.corrections:
            return None
        return self.segment_factors(0).corrections.domain  # type: ignore[union-attr]

    @contextmanager
    def _naming_path(self) -> Iterator[None]:
        try:
            yield
        except FormatError as error:
            error.path = self.path
            raise

    def _segment_index(self) -> tuple[SegmentEntry, ...]:
        """The segments (§6.7); a file of format 1.0 is one segment whose sections are U1, U3,
        CORE and CENT."""
        if self.info.segments:
            return self.info.segments
        u2 = tuple(float(x) for x in self._container.header["u2"])
        return (SegmentEntry(0, 0, self.info.frames, self.info.ranks, u2, BASIS_OWN),)

    @property
    def segmented(self) -> bool:
        """Whether the file is segmented (format 1.1, §6.7)."""
        return bool(self.info.segments)

    @property
    def segments(self) -> tuple[SegmentEntry, ...]:
        """The segment index: one entry for a file of format 1.0."""
        return self._index

    @property
    def bytes_read(self) -> int | None:
        """For a file opened from a path, how many of its bytes have been read so far."""
        return self._data.bytes_read if isinstance(self._data, FileRanges) else None

    def _section_id(self, segment: SegmentEntry, stem: str) -> str:
        if not self.segmented:
            return stem
        return segment.u1_section_id() if stem == "U1" else segment.section_id(stem)

    def _section(self, section_id: str) -> Section:
        section = self._container.section(section_id)
        assert section is not None  # read_header found every required section
        return section

    def _payload(self, section_id: str) -> memoryview:
        return self._container.payload(self._data, self._section(section_id))

    def _mesh_prediction(self) -> MeshPrediction:
        # K entries: made only after a U1 payload has passed its CRC and zstd checks, which
        # bound K by the file's size, and only if a column of U1 is predicted
        # (the parents of predictor 1 at once; predictor 2's steps only if a column uses it)
        if self._mesh is None:
            self._mesh = MeshPrediction(self._coded_faces, self.info.vertices)
        return self._mesh

    def _decode_u1(self, section_id: str) -> qmat.QuantizedMatrix:
        return qmat.decode_matrix(
            self._payload(section_id),
            self._section(section_id).params,
            self._mesh_prediction,
            f"section {section_id}",
            coding_tools=self._container.coding_tools,  # predictor 2 only in format 1.2
            adaptive_coding=self._container.adaptive,  # §6.14 only in format 1.6
        )

    def _decode_u1_values(
        self, section_id: str, beside: Callable[[], object] | None = None
    ) -> np.ndarray:
        """:meth:`_decode_u1`'s dequantized floats, for a file without corrections; ``beside``
        as :func:`qmat.decode_values` takes it."""
        return qmat.decode_values(
            self._payload(section_id),
            self._section(section_id).params,
            self._mesh_prediction,
            f"section {section_id}",
            coding_tools=self._container.coding_tools,
            adaptive_coding=self._container.adaptive,
            beside=beside,
        )

    def _others_beside(self, segment: SegmentEntry) -> bool:
        """Whether the segment's U3, CORE and CENT are decoded on a second thread while U1
        decodes, where that gains time: a segment with its own U1 and no corrections, in a
        file held in memory whose other factors hold many adaptively coded integers (§6.14),
        which the compiled core decodes one at a time with the GIL released."""
        return (
            segment.basis != BASIS_SHARED
            and not self._container.corrections
            and isinstance(self._data, (bytes, memoryview))  # FileRanges counts its reads
            and native.core() is not None
            and self._adaptive_integers(segment) >= BESIDE_U1
        )

    def _other_factors(self, segment: SegmentEntry) -> OtherFactors:
        """The segment's dequantized U3, CORE and CENT, in §5 step 16's order."""

        def matrix(stem: str, allow_predict: bool = True) -> np.ndarray:
            section_id = self._section_id(segment, stem)
            return qmat.decode_matrix(
                self._payload(section_id),
                self._section(section_id).params,
                None,  # U3 and CENT: the previous frame; CORE: nothing
                f"section {section_id}",
                allow_predict=allow_predict,
                coding_tools=self._container.coding_tools,  # predictor 3 only in 1.2
                adaptive_coding=self._container.adaptive,
            ).values()

        return matrix("U3"), matrix("CORE", allow_predict=False), matrix("CENT")

    def _u1_values_beside(self, segment: SegmentEntry) -> tuple[np.ndarray, OtherFactors | None]:
        """The segment's U1 (:meth:`_decode_u1_values`), and its U3, CORE and CENT
        (:meth:`_other_factors`) on a second thread meanwhile where :meth:`_others_beside`
        says so. ``None`` for the others where they are left to the caller. An error of U1
        comes first, as in §5 step 16's order (the others' thread is waited for)."""
        section_id = self._section_id(segment, "U1")
        if not self._others_beside(segment):
            return self._decode_u1_values(section_id), None
        with ExitStack() as stack:
            pool = self._early_pool or stack.enter_context(ThreadPoolExecutor(1))
            pending: list[Future[OtherFactors]] = []

            def start_others() -> None:
                # once U1's Python work is done and its stream decodes without the GIL: the
                # others' Python work then waits for no GIL, nor U1's for theirs
                if not pending:
                    pending.append(pool.submit(self._other_factors, segment))

            try:
                u1 = self._decode_u1_values(section_id, start_others)
            finally:
                for decoding in pending:  # its error, if any, comes after U1's
                    decoding.exception()
            return u1, pending[0].result() if pending else self._other_factors(segment)

    def _adaptive_integers(self, segment: SegmentEntry) -> int:
        """How many integers the segment's U3, CORE and CENT say they code adaptively (§6.14),
        from parameters not checked yet (anything else counts 0)."""
        count = 0
        for stem in ("U3", "CORE", "CENT"):
            params = self._section(self._section_id(segment, stem)).params
            shape = params.get("shape")
            if params.get("coder") == adaptive.CODER_ADAPTIVE and isinstance(shape, list):
                count += math.prod(n if isinstance(n, int) and n > 0 else 0 for n in shape)
        return count

    def segment_factors(self, number: int) -> SegmentFactors:
        """Segment ``number``'s dequantized factors, decoded (§5 step 16, in its order) and
        kept for the next frames; the shared U1 is decoded once for every segment."""
        cached = self._segments.get(number)
        if cached is not None:
            self._segments.move_to_end(number, last=False)
            return cached
        segment = self._index[number]
        i, k = segment.ranks
        with self._naming_path():
            u1_quantized: qmat.QuantizedMatrix | None
            decoded_others = None
            if segment.basis == BASIS_SHARED:
                if self._shared_u1_values is None and not self._container.corrections:
                    # no integers wanted: the floats straight from the stream
                    self._shared_u1_values = self._decode_u1_values("U1")
                    if all(other.basis == BASIS_SHARED for other in self._index):
                        self._mesh = None  # no other U1 to restore
                if self._shared_u1_values is None:
                    decoded = self._decode_u1("U1")
                    if all(other.basis == BASIS_SHARED for other in self._index):
                        self._mesh = None  # no other U1 to restore: free it before the values
                    self._shared_u1_values = decoded.values()
                    # its integers for §8.1: a large U1's are as large as its values
                    self._shared_u1 = decoded
                    del decoded
                shared = self._shared_u1
                u1_quantized = (
                    None
                    if shared is None
                    else qmat.QuantizedMatrix(shared.q[:, :i], shared.steps[:i])
                )
                u1 = self._shared_u1_values[:, :i]
            elif self._container.corrections:  # §8.1 multiplies U1's integers
                u1_quantized = self._decode_u1(self._section_id(segment, "U1"))
                u1 = u1_quantized.values()
            else:
                u1_quantized = None
                u1, decoded_others = self._u1_values_beside(segment)
            u3, core, centroids = (
                self._other_factors(segment) if decoded_others is None else decoded_others
            )
            core = core.reshape(i, 3, k)
        u2 = np.array(segment.u2, dtype=np.float64).reshape(3, 3)
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is R36, found per frame
            basis = reconstruction_basis(core, u2)
        factors = SegmentFactors(segment.start, segment.stop, u1, u3, core, centroids, u2, basis)
        if self._container.corrections:  # §8.1 multiplies U1's integers
            factors = dataclasses.replace(factors, u1_quantized=u1_quantized)
        if self._container.corrections and self.segmented:  # step 16s: then its RESD.s
            factors = self._with_corrections(factors, segment)
        self._segments[number] = factors
        self._segments.move_to_end(number, last=False)
        while len(self._segments) > CACHED_SEGMENTS:
            self._segments.popitem(last=True)
        return factors

    def _with_corrections(self, factors: SegmentFactors, segment: SegmentEntry) -> SegmentFactors:
        """§5 step 18: the segment's RESD layout (R40, R21) and CRC, with what §8.1 needs."""
        section_id = self._section_id(segment, residual.SECTION_STEM)
        section = self._section(section_id)
        with self._naming_path():
            layout = residual.read_layout(
                section.params,
                section.length,
                segment.stop - segment.start,
                self.info.vertices,
                self.limits,
                f"section {section_id}",
                adaptive_corrections=self._container.adaptive_corrections,
                codebooks=self._container.codebooks,
            )
            self._payload(section_id)  # the CRC (step 9), before any chunk is read
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is R36, per frame
            exact_basis = residual.exact_basis(factors.core, factors.u2)
        assert factors.u1_quantized is not None
        quantized = factors.u1_quantized
        return dataclasses.replace(
            factors,
            corrections=layout,
            residual_id=section_id,
            exact_u1=residual.ExactU1.of(quantized.q, quantized.steps),
            exact_basis=exact_basis,
            u1_quantized=None,  # kept as ExactU1 now
        )

    def _chunk(self, part: SegmentFactors, chunk: int, payload: memoryview) -> np.ndarray:
        """The restored integers of one chunk of a segment's corrections (R29)."""
        assert part.corrections is not None
        with self._naming_path():
            return residual.decode_chunk(
                payload, part.corrections, chunk, self.info.vertices, f"section {part.residual_id}"
            )

    def _codebooks_of(
        self, part: SegmentFactors
    ) -> tuple[residual.Codebooks, tuple[np.ndarray | None, ...]]:
        """A segment's codebooks (format 1.8, R29 and R47) and their midpoints, decoded at
        its first corrected frame and kept with its factors."""
        assert part.corrections is not None
        if not part.codebooks:
            with self._naming_path():
                books = residual.decode_codebooks(
                    self._payload(part.residual_id),
                    part.corrections,
                    f"section {part.residual_id}",
                )
            middles = tuple(None if book is None else residual.midpoints(book) for book in books)
            part.codebooks.append((books, middles))
        return part.codebooks[0]

    def _keep_chunk(self, key: tuple[int, int], values: np.ndarray) -> None:
        """Keep a chunk's integers for the next frames (the most recent few)."""
        self._chunks[key] = values
        self._chunks.move_to_end(key)
        while len(self._chunks) > CACHED_CHUNKS:
            self._chunks.popitem(last=False)

    def _corrected(
        self, number: int, part: SegmentFactors, local: np.ndarray, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Frames ``local`` (numbers within the segment) of a file with corrections: §8.1's
        exact reconstruction, corrected chunk by chunk (§6.9), written to ``out`` if given."""
        layout = part.corrections
        assert layout is not None and part.exact_u1 is not None and part.exact_basis is not None
        with self._naming_path(), np.errstate(over="ignore", invalid="ignore"):
            exact = residual.exact_frames(
                part.exact_u1,
                part.exact_basis,
                part.u3[local],
                part.centroids[local],
                layout.exponent,
                f"section {part.residual_id}",
            )
        books, middles = self._codebooks_of(part) if layout.codebooks else ((), ())
        out = np.empty_like(exact) if out is None else out
        chunks = local // layout.span
        needed = np.unique(chunks).tolist()
        payload = (
            self._payload(part.residual_id)
            if any((number, chunk) not in self._chunks for chunk in needed)
            else memoryview(b"")
        )

        def corrected(chunk: int) -> tuple[int, np.ndarray]:
            """One chunk's frames corrected: run on threads (numpy and zstd release the GIL),
            reading the cache but not changing it."""
            values = self._chunks.get((number, chunk))
            if values is None:
                values = self._chunk(part, chunk, payload)
            indices = np.flatnonzero(chunks == chunk)
            start, _ = layout.chunk_range(chunk)
            taken = _run_or_indices(local[indices] - start)
            rows = _run_or_indices(indices)  # the usual case: runs of frames, views not copies
            where = f"section {part.residual_id}"
            with self._naming_path():
                frames = exact[rows]
                stored = values[taken]
                if books:  # positions in the codebooks, as the domain's corrections
                    stored = residual.from_codebooks(
                        frames, stored, layout.kind, books, where, middles
                    )
                out[rows] = residual.correct(frames, stored, layout.kind, where)
            return chunk, values

        workers = min(len(needed), CHUNK_THREADS)
        if workers <= 1:
            done = [corrected(chunk) for chunk in needed]
        else:
            with ThreadPoolExecutor(workers) as pool:
                done = list(pool.map(corrected, needed))
        for chunk, values in done:
            self._keep_chunk((number, chunk), values)
        return out

    def check(self) -> None:
        """Decode every segment, so that any damaged section is found now (a file of format
        1.0 was checked whole when it was opened)."""
        for number in range(len(self._index)):
            part = self.segment_factors(number)
            if part.corrections is not None:  # every chunk's frame and values (R29, R41)
                self._corrected(number, part, np.arange(part.stop - part.start))
        self.fields()  # every field's sections

    # -- format 1.5: the faces' order, attributes, face sets and fields ---------------------------

    def _faces_in_given_order(self) -> np.ndarray:
        """The faces in the order they were given (ORDER, §6.10), or as FACE decodes them."""
        section = self._attached.order
        if section is None:
            return self.faces
        order = face_order.decode_face_order(
            self._container.payload(self._data, section),
            section.params,
            len(self.faces),
            "section ORDER",
        )
        return face_order.in_given_order(self.faces, order)

    def _decode_attributes(self) -> list[Attribute]:
        """Every ATTR.n, in order (§6.11): parameters, sizes, then the payload."""
        mesh = attributes.Mesh(self.info.vertices, self.faces)
        decoded = []
        for section in self._attached.attributes:
            where = f"section {section.id}"
            params = attributes.check_attribute_params(
                section.params, mesh, section.length, self.limits, where
            )
            payload = self._container.payload(self._data, section)
            decoded.append(attributes.decode_attribute(payload, params, mesh, where))
        attributes.check_unique_names(decoded, [s.id for s in self._attached.attributes])
        return decoded

    def _decode_face_sets(self) -> list[FaceSet]:
        section = self._attached.face_sets
        if section is None:
            return []
        return face_sets.decode_face_sets(
            self._container.payload(self._data, section),
            section.params,
            len(self.faces),
            self.limits,
            "section FSET",
        )

    @property
    def field_names(self) -> list[str]:
        """The names of the file's animated fields (format 1.5, §6.13), in order."""
        return [str(section.params.get("name")) for section in self._attached.fields]

    def fields(self, frames: FrameSelection = None) -> list[Field]:
        """The file's animated fields for the selected frames (each decoded to its target,
        §6.13), in order."""
        if not self._attached.fields:
            return []
        from .format.fields import check_unique_names, decode_field

        chosen = self._selected(frames)
        mesh = self._mesh_prediction()
        with self._naming_path():  # each field's name, checked with its parameters below
            check_unique_names(self.field_names)
        with self._naming_path():
            return [
                decode_field(
                    number,
                    self._container.section,
                    self._payload,
                    self.info.vertices,
                    len(self.faces),
                    self.info.frames,
                    mesh,
                    self.limits,
                    chosen,
                )
                for number in range(len(self._attached.fields))
            ]

    def _decode_names(self) -> list[str]:
        name_section = self._container.section("NAME")
        if name_section is None:
            return default_frame_names(self.info.frames)
        return names.decode_names(
            name_section.params,
            lambda: self._container.payload(self._data, name_section),
            self.info.frames,
            self.limits,
            "section NAME",
        )

    def _single(self) -> SegmentFactors:
        if self.segmented:
            raise ValueError(
                "a segmented file holds one decomposition per segment: use "
                "segment_factors(number) for each of Decoder.segments"
            )
        return self.segment_factors(0)

    @property
    def u1(self) -> np.ndarray:
        """U1 (K x i) of a file of one decomposition (format 1.0)."""
        return self._single().u1

    @property
    def u3(self) -> np.ndarray:
        """U3 (F x k) of a file of one decomposition."""
        return self._single().u3

    @property
    def core(self) -> np.ndarray:
        """The core (i x 3 x k) of a file of one decomposition."""
        return self._single().core

    @property
    def centroids(self) -> np.ndarray:
        """The centroids (F x 3) of a file of one decomposition."""
        return self._single().centroids

    @property
    def u2(self) -> np.ndarray:
        """U2 (3 x 3) of a file of one decomposition."""
        return self._single().u2

    @property
    def frame_count(self) -> int:
        """F."""
        return self.info.frames

    def frame_indices(self, frames: FrameSelection) -> np.ndarray:
        """The frame numbers a selection names, checked to exist; negative numbers count from
        the end, and a slice is clipped to the file's frames, like any slice."""
        count = self.frame_count
        if frames is None:
            return np.arange(count)
        if isinstance(frames, slice):
            return np.arange(count)[frames]
        if isinstance(frames, (str, bytes)):
            raise TypeError(f"frames must be frame numbers, a range or a slice, not {frames!r}")
        if isinstance(frames, range):
            ends = [frames[0], frames[-1]] if frames else []  # len() overflows past 2**63
            _check_frames_exist(ends, count)
            return np.arange(frames.start, frames.stop, frames.step, dtype=np.int64) % count
        numbers = _frame_numbers(frames)
        _check_frames_exist(numbers, count)
        return np.array(numbers, dtype=np.int64).reshape(-1) % count

    def _selected(self, frames: FrameSelection) -> np.ndarray:
        chosen = self.frame_indices(frames)
        if chosen.size == 0:
            raise ValueError(
                f"the selection {frames!r} names no frame of the file's 0..{self.frame_count - 1}"
            )
        return chosen

    def positions(self, frames: FrameSelection = None) -> np.ndarray:
        """Decoded positions of the selected frames, (n, K, 3) float64 (§8); each segment that
        holds one of them is read and decoded once."""
        chosen = self._selected(frames)
        check_limit(
            chosen.size * self.info.vertices,
            self.limits,
            "max_positions",
            what=f"{chosen.size} frames x {self.info.vertices} vertices of positions asked for",
            field="frames",
        )
        positions = np.empty((chosen.size, self.info.vertices, 3))
        owners = np.searchsorted(self._starts, chosen, side="right") - 1
        for number in np.unique(owners).tolist():
            picked = np.flatnonzero(owners == number)
            part = self.segment_factors(number)
            local = chosen[picked] - part.start
            # Overflow is a property of the file, reported below as R36: numpy must not warn
            # (or, under np.seterr(all="raise"), raise FloatingPointError) before that check.
            if part.corrections is not None:
                run = _run_or_indices(picked)
                if isinstance(run, slice):  # written where it goes
                    self._corrected(number, part, local, out=positions[run])
                else:
                    positions[picked] = self._corrected(number, part, local)
                continue
            with np.errstate(over="ignore", invalid="ignore"):
                if picked[-1] - picked[0] == picked.size - 1:  # a run: written where it goes
                    reconstruct_frames(
                        part.u1,
                        part.basis,
                        part.u3[local],
                        part.centroids[local],
                        out=positions[picked[0] : picked[-1] + 1],
                    )
                else:
                    positions[picked] = reconstruct_frames(
                        part.u1, part.basis, part.u3[local], part.centroids[local]
                    )
        if not np.isfinite(positions).all():  # finite factors whose products overflow
            field = "header.segments" if self.segmented else "header.u2"
            raise FormatError(
                "the reconstruction overflows float64: the factors are out of range",
                rule="R36-reconstruction-finite",
                field=field,
                path=self.path,
            )
        return positions

    def frame(self, index: int) -> np.ndarray:
        """One decoded frame, (K, 3)."""
        return self.positions([index])[0]

    def sequence(self, frames: FrameSelection = None) -> MeshSequence:
        """The selected frames as a :class:`MeshSequence` with the file's faces and names; a
        part of the file, in order, carries its frame numbers as time codes."""
        chosen = self._selected(frames)
        return MeshSequence(
            self.positions(chosen),
            self.faces,
            frame_names=[self.frame_names[n] for n in chosen],
            frame_rate=self.info.frame_rate,
            time_codes=selected_time_codes(self.info, chosen),
            meters_per_unit=self.info.meters_per_unit,
            up_axis=self.info.up_axis,
            attributes=self.attributes,
            face_sets=self.face_sets,
            fields=self.fields(chosen),
        )


def selected_time_codes(info: FileInfo, chosen: np.ndarray) -> np.ndarray | None:
    """The time codes of the frames ``chosen`` of a file: a selection in order keeps its
    frames' places in time, the file's codes (format 1.4) or else their numbers (frame n at
    time code n); ``None`` (0, 1, 2...) for the whole file without codes, or for frames out
    of order, which have no time of their own."""
    if not bool(np.all(np.diff(chosen) > 0)):
        return None
    if info.time_codes is not None:
        return np.asarray(info.time_codes, dtype=np.float64)[chosen]
    return np.asarray(chosen, dtype=np.float64) if chosen.size < info.frames else None


def _run_or_indices(indices: np.ndarray) -> slice | np.ndarray:
    """``indices`` as a slice when they are a run (each one more than the one before), for
    views instead of copies; else the indices themselves."""
    if indices.size and (indices.size == 1 or bool((np.diff(indices) == 1).all())):
        first = int(indices[0])
        return slice(first, first + indices.size)
    return indices


def _frame_numbers(frames: int | Sequence[int] | np.ndarray) -> list[int]:
    """A selection of frame numbers as Python ints (no overflow, whatever their size)."""
    if isinstance(frames, np.ndarray) and frames.dtype.kind in "iu":
        values: list[int] = frames.reshape(-1).tolist()
        return values
    # anything else is checked one item at a time: Python ints, numpy scalars, nothing else
    single: list[Any] = [frames] if np.ndim(frames) == 0 else list(frames)  # type: ignore[arg-type]
    if any(isinstance(n, (bool, np.bool_)) for n in single):
        raise TypeError(f"frame numbers must be integers, not booleans: {frames!r}")
    try:  # operator.index refuses floats and strings
        return [operator.index(n) for n in single]
    except TypeError:
        raise TypeError(f"frame numbers must be integers, got {frames!r}") from None


def _check_frames_exist(numbers: Sequence[int], count: int) -> None:
    for number in numbers:
        if not -count <= number < count:
            raise ValueError(f"frame {number} does not exist: the file has frames 0..{count - 1}")


def decode(
    source: CompressedFile, *, frames: FrameSelection = None, limits: Limits = DEFAULT_LIMITS
) -> MeshSequence:
    """Decode a compressed file (its bytes, or a path) into a :class:`MeshSequence`.

    Args:
        source: the whole file's bytes, or a path to read it from.
        frames: ``None`` for all frames, or a frame number, a slice, a range or a list of frame
            numbers; only those frames are reconstructed.
        limits: the decoder's limits.

    Raises:
        FormatError: the bytes are not a valid file (a subclass says how: truncated, checksum,
            unsupported version, limit; ``rule`` says which rule of the spec it breaks).
        ValueError: a selected frame does not exist, or the selection is empty.
        TypeError: ``frames`` is not frame numbers, a range or a slice.
    """
    return Decoder(source, limits=limits).sequence(frames)


def info(source: CompressedFile, *, limits: Limits = DEFAULT_LIMITS) -> FileInfo:
    """Read a file's header without decoding any section.

    ``source`` is the file's bytes, or a path: then only the preamble and header are read from
    disk, and the file's size is checked against the size the preamble declares.
    """
    path = os.fspath(source) if isinstance(source, (str, os.PathLike)) else None
    try:
        if isinstance(source, (str, os.PathLike)):
            data: bytes | memoryview = read_file(source, limits, header_only=True)
        else:
            data = _bytes_of(source)
        return read_header(parse_container(data, limits, whole=path is None), limits)
    except FormatError as error:
        error.path = path
        raise


__all__ = [
    "CompressedFile",
    "Decoder",
    "FileInfo",
    "FrameSelection",
    "SegmentFactors",
    "decode",
    "info",
]
