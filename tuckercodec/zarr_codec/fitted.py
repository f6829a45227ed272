"""The fitted mode of the codec: one per-vertex basis U1 for every chunk, held by the codec's
configuration (as a zstd dictionary is), so that each chunk stores only its own part.

A chunk of the usual mode is a whole .tkc file, and 86-90 % of it is its own U1 (chicken in
100-frame chunks: 1.73 times the .tkc of the whole sequence). A fitted codec is made from the
array before it is written (:func:`fit_array`, behind ``TuckerZarrCodec.fit`` and
``TuckerNumcodec.fit``): :func:`tuckercodec.encoder.segmented.fit_basis` finds a U1 with which
every chunk of ``chunk_frames`` frames meets the target on its own. Each chunk is then encoded
with it (:meth:`tuckercodec.encoder.Encoder.encode_segments`, ``shared_basis=...``): a
segmented .tkc (format 1.1) whose U1 section is the basis's, byte for byte.

Layout of a fitted chunk: that .tkc with the payload bytes of its U1 section cut out, and
nothing else changed::

    signature, preamble, header (its table still lists U1: offset, length, CRC-32), header CRC,
    the sections before U1 (FACE, empty), the sections after U1 (CENT.0, U3.0, CORE.0, ...)

so its preamble's ``total_length`` exceeds its byte count by exactly the U1 section's length.
Decoding puts the basis's payload back where the table says (:meth:`FittedBasis.complete`),
after checking that the table's length, CRC-32 and parameters are the basis's: a chunk written
with another basis is refused with a ValueError that names the configuration's basis, and the
completed file is checked by the decoder like any other (its section CRCs included).

A chunk of any length can use the basis (a shared U1 may have up to K columns, more than 3F:
spec §6.7), an edge chunk shorter than the others too. A chunk that cannot meet the target with
it (frames added after the fit whose motion it does not span) is stored as the usual mode stores
it, a whole .tkc with its own U1: the guarantee never depends on the fit. A whole file is told
apart by its ``total_length``, which equals its byte count. Point chunks stay point chunks
(:mod:`.chunk`).

In the configuration the basis is ``basis``, the base64 of one msgpack map ``{"params": the U1
table entry's codec parameters, "payload": its bytes}``, and ``basis_sha256``, the SHA-256 of
that msgpack (checked when the configuration is read). Base64 costs 4/3 of the binary basis in
``zarr.json``.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import math
import zlib
from dataclasses import dataclass, field
from typing import Any, ClassVar

import msgpack
import numpy as np

from ..encoder import EncodeOptions, Encoder
from ..encoder.segmented import SharedBasis, fit_basis
from ..errors import FormatError, InputError
from ..format.container import parse_container
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource, SequenceFrames

#: The configuration keys of a fitted codec (beside ``target_kg``).
BASIS_KEYS = ("basis", "basis_sha256")
_U1 = "U1"
#: Keys of a section-table entry that are not the codec's parameters.
_ENTRY_KEYS = frozenset({"id", "critical", "codec", "offset", "length", "crc32"})


@dataclass(frozen=True)
class FittedBasis:
    """A shared U1 (:class:`~tuckercodec.encoder.segmented.SharedBasis`) and its configuration
    text. Two are equal when their texts are (the configuration is what zarr compares)."""

    text: str
    sha256: str
    shared: SharedBasis = field(compare=False, repr=False)

    @classmethod
    def of(cls, shared: SharedBasis) -> FittedBasis:
        """The configuration of a basis found by ``fit_basis`` (or ``shared_basis_of``)."""
        packed = msgpack.packb(
            {"params": shared.params, "payload": shared.payload}, use_bin_type=True
        )
        text = base64.b64encode(packed).decode("ascii")
        return cls(text, hashlib.sha256(packed).hexdigest(), shared)

    @classmethod
    def parse(cls, text: Any, sha256: Any) -> FittedBasis:
        """The basis of a configuration's ``basis`` and ``basis_sha256``.

        Raises:
            ValueError: one without the other, text that is not base64 of one msgpack map of
                ``params`` and ``payload``, or a SHA-256 that does not match (a damaged or
                edited configuration); the message names the basis.
        """
        if not isinstance(text, str) or not isinstance(sha256, str):
            raise ValueError(
                "a fitted tuckercodec configuration has both 'basis' (base64 text) and "
                f"'basis_sha256' (hex text); got basis {type(text).__name__} and basis_sha256 "
                f"{type(sha256).__name__}"
            )
        try:
            packed = base64.b64decode(text.encode("ascii"), validate=True)
        except (binascii.Error, UnicodeEncodeError) as error:
            raise ValueError(f"the codec's basis is not base64 text ({error})") from None
        digest = hashlib.sha256(packed).hexdigest()
        if digest != sha256.lower():
            raise ValueError(
                f"the codec's basis does not match its basis_sha256 ({digest} against "
                f"{sha256}): the configuration was damaged or edited"
            )
        try:
            content = msgpack.unpackb(packed, raw=False, strict_map_key=True, use_list=True)
        except (ValueError, TypeError, msgpack.UnpackException) as error:
            raise ValueError(f"the codec's basis is not one msgpack map ({error})") from None
        if (
            not isinstance(content, dict)
            or set(content) != {"params", "payload"}
            or not isinstance(content["params"], dict)
            or not isinstance(content["payload"], bytes)
        ):
            raise ValueError("the codec's basis is not a map of 'params' and 'payload' bytes")
        shared = SharedBasis(content["params"], content["payload"])
        _shape(shared)
        return cls(text, sha256, shared)

    @property
    def vertices(self) -> int:
        """K, the vertices of the array it was fitted to (the rows of U1)."""
        return _shape(self.shared)[0]

    @property
    def columns(self) -> int:
        """c, the basis's columns (a chunk's segment uses its leading ones)."""
        return _shape(self.shared)[1]

    @property
    def payload(self) -> bytes:
        """The U1 section's bytes as stored: what every fitted chunk leaves out."""
        return self.shared.payload

    def config(self) -> dict[str, str]:
        """``basis`` and ``basis_sha256``, for the codec's configuration."""
        return {"basis": self.text, "basis_sha256": self.sha256}

    def describe(self) -> str:
        """A short form for a codec's repr: its size and the start of its SHA-256."""
        return f"<basis of {self.vertices} x {self.columns}, sha256 {self.sha256[:12]}...>"

    def encode(self, sequence: MeshSequence, target_kg: float) -> bytes:
        """The whole segmented .tkc of ``sequence`` (one segment) with this basis as its U1.

        Raises:
            UnreachableTargetError: the basis does not span the sequence's motion well enough
                for ``target_kg`` (the caller then stores the chunk with its own basis).
        """
        options = EncodeOptions(target_kg=target_kg, segment_frames=sequence.frame_count)
        encoder = Encoder(options)
        return encoder.encode_segments(SequenceFrames(sequence), shared_basis=self.shared).data

    def cut(self, data: bytes) -> bytes:
        """A file encoded by :meth:`encode`, without its U1 payload: the fitted chunk."""
        container = parse_container(data)
        entry = container.section(_U1)
        start = -1 if entry is None else entry.file_offset(container.data_start)
        if entry is None or data[start : start + entry.length] != self.payload:
            raise RuntimeError("the encoder did not store the given basis as the file's U1")
        return data[:start] + data[start + entry.length :]

    def complete(self, data: bytes) -> bytes:
        """The whole .tkc of a fitted chunk (its U1 payload put back); any other bytes as
        they are (a whole file, a point chunk, or damage the decoder will name).

        Raises:
            ValueError: the chunk's U1 entry is not this basis (its length, CRC-32 or
                parameters differ): it was written with another basis.
        """
        return complete_file(data, self)


def fitted_gap(data: bytes) -> tuple[int, int] | None:
    """Where a fitted chunk's U1 payload goes and its length, or ``None`` for anything else:
    a file whose ``total_length`` exceeds its byte count by exactly its shared U1's length."""
    try:
        container = parse_container(data, whole=False)
    except FormatError:
        return None  # not a .tkc head: the decoder says what it is
    entry = container.section(_U1)
    missing = container.total_length - len(data)
    if not container.segmented or entry is None or missing <= 0 or entry.length != missing:
        return None
    return entry.file_offset(container.data_start), entry.length


def complete_file(data: bytes, basis: FittedBasis | None) -> bytes:
    """The whole .tkc of a chunk: a fitted chunk with ``basis``'s payload put back, anything
    else unchanged.

    Raises:
        ValueError: a fitted chunk and no basis (a codec without the configuration's basis),
            or a fitted chunk whose U1 entry is not ``basis``.
    """
    gap = fitted_gap(data)
    if gap is None:
        return data
    start, length = gap
    if basis is None:
        raise ValueError(
            f"this chunk was written by a fitted tuckercodec codec: its U1 section ({length} "
            "bytes) is the basis in the codec's configuration ('basis'), which this codec does "
            "not have; read the array with the configuration it was written with"
        )
    entry = parse_container(data, whole=False).section(_U1)
    assert entry is not None  # fitted_gap found it
    params = {key: value for key, value in entry.params.items() if key not in _ENTRY_KEYS}
    if (
        length != len(basis.payload)
        or entry.crc32 != zlib.crc32(basis.payload)
        or params != basis.shared.params
    ):
        raise ValueError(
            f"the chunk was written with another basis than the codec's (its U1 section: "
            f"{length} bytes, CRC-32 {entry.crc32:08x}; the configuration's basis "
            f"{basis.sha256[:12]}...: {len(basis.payload)} bytes, CRC-32 "
            f"{zlib.crc32(basis.payload):08x}): the configuration's basis was changed or the "
            "chunk belongs to another array"
        )
    return data[:start] + basis.payload + data[start:]


def _shape(shared: SharedBasis) -> tuple[int, int]:
    shape = shared.params.get("shape")
    if (
        isinstance(shape, list)
        and len(shape) == 2
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in shape)
    ):
        return int(shape[0]), int(shape[1])
    raise ValueError(f"the codec's basis has no shape [vertices, columns]: {shape!r}")


class ArrayFrames(FrameSource):
    """An array of shape (frames, vertices, 3) (numpy, zarr, dask or any array with ``shape``,
    ``dtype`` and slicing) as a :class:`~tuckercodec.model.sources.FrameSource`.

    A zarr or dask array is read a chunk of frames at a time (its ``chunks``) and the last one
    read is kept, since the encoder's passes read blocks of at most 16 frames in order: each
    pass decodes every chunk of the array once. Nothing holds the whole array as float64.
    """

    _transient: ClassVar[tuple[str, ...]] = ("_kept",)
    _kept: tuple[int, int, np.ndarray] | None = None

    def __init__(self, array: Any) -> None:
        shape = tuple(getattr(array, "shape", ()))
        try:
            dtype = np.dtype(array.dtype)
        except (AttributeError, TypeError):
            raise InputError(f"not an array with a dtype: {type(array).__name__}") from None
        if len(shape) != 3 or shape[2] != 3:
            raise InputError(
                f"the tuckercodec codec is fitted to an array of shape (frames, vertices, 3), "
                f"not {shape}"
            )
        if dtype.kind != "f":
            raise InputError(f"the tuckercodec codec encodes floating-point positions, not {dtype}")
        self._array = array
        self._bounds = _frame_chunk_bounds(array, int(shape[0]))
        self._describe(None, int(shape[0]), int(shape[1]), np.zeros((0, 3), dtype=np.int64))

    def _read(self, start: int, stop: int) -> np.ndarray:
        if self._bounds is None:
            return np.asarray(self._array[start:stop])
        pieces = []
        first = int(np.searchsorted(self._bounds, start, side="right")) - 1
        for index in range(first, len(self._bounds) - 1):
            low, high = int(self._bounds[index]), int(self._bounds[index + 1])
            if low >= stop:
                break
            if self._kept is None or self._kept[0] != low:
                self._kept = None  # the chunk before is dropped first
                self._kept = (low, high, np.asarray(self._array[low:high]))
            pieces.append(self._kept[2][max(start, low) - low : min(stop, high) - low])
        return pieces[0] if len(pieces) == 1 else np.concatenate(pieces)


def _frame_chunk_bounds(array: Any, frames: int) -> np.ndarray | None:
    """Where the array's chunks of frames start (and the end): a zarr array's ``chunks`` are
    ints, a dask array's tuples of sizes; ``None`` for an array in memory."""
    if isinstance(array, np.ndarray):
        return None
    chunks = getattr(array, "chunks", None)
    if not isinstance(chunks, tuple) or not chunks:
        return None
    first = chunks[0]
    if isinstance(first, tuple) and all(isinstance(n, int) and n >= 1 for n in first):
        sizes = list(first)
    elif isinstance(first, int) and first >= 1:
        sizes = [first] * math.ceil(frames / first)
    else:
        return None
    bounds = np.minimum(np.concatenate([[0], np.cumsum(sizes)]), frames)
    return np.unique(bounds)


def fit_array(
    array: Any, *, target_kg: float, chunk_frames: int, max_memory: int | None = None
) -> FittedBasis:
    """The basis of a fitted codec for ``array`` (frames, vertices, 3), to be chunked by
    ``chunk_frames`` frames: every chunk of it then meets ``target_kg`` with the basis alone.

    Raises:
        InputError: an array of another shape or dtype, a non-finite position (naming the
            frame), or every frame a single point.
        ValueError: ``chunk_frames`` that is not an integer >= 1.
    """
    if isinstance(chunk_frames, bool) or not isinstance(chunk_frames, (int, np.integer)):
        raise ValueError(f"chunk_frames must be an integer >= 1, got {chunk_frames!r}")
    if chunk_frames < 1:
        raise ValueError(f"chunk_frames must be an integer >= 1, got {chunk_frames!r}")
    with ArrayFrames(array) as source:
        shared = fit_basis(
            source,
            target_kg=target_kg,
            segment_frames=int(chunk_frames),
            max_memory=max_memory,
        )
    return FittedBasis.of(shared)
