"""The decoder: a compressed file back to vertex positions, all frames or any of them.

It follows ``spec/FORMAT.md`` step by step, over :mod:`tuckercodec.format`: the container (§2-5),
the header fields (§4), the sections (§6) and the reconstruction (§8)::

    positions[f, v, x] = sum_{a,c,b} U1[v, a] * CORE[a, c, b] * U2[x, c] * U3[f, b] + CENT[f, x]

Opening a :class:`Decoder` decodes the small factor matrices once (about K*i + F*k + 3*i*k
numbers); each frame then costs one (K x i) by (i x 3) product, so any frame range is decoded
without touching the others.
"""

from __future__ import annotations

import operator
import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .errors import FormatError
from .format import faces, names, qmat
from .format.container import Container, parse_container, read_file
from .format.header import FileInfo, read_header
from .format.limits import DEFAULT_LIMITS, Limits
from .format.reconstruction import reconstruct_frames, reconstruction_basis
from .sequence import MeshSequence
from .topology import mesh_parents

#: A compressed file: its bytes, or a path to read it from.
CompressedFile = bytes | bytearray | memoryview | str | os.PathLike[str]
#: Which frames to decode: one number, a slice, a range, numbers (a list or an integer array),
#: or all (``None``).
FrameSelection = int | slice | range | Sequence[int] | np.ndarray | None


def _bytes_of(
    source: CompressedFile, limits: Limits, *, header_only: bool = False
) -> bytes | memoryview:
    """The file's bytes: read from disk for a path (the one way, :func:`read_file`)."""
    if isinstance(source, (str, os.PathLike)):
        return read_file(source, limits, header_only=header_only)
    if isinstance(source, bytes):
        return source
    if isinstance(source, (bytearray, memoryview)):
        return memoryview(source).cast("B")
    raise TypeError(f"expected the bytes of a file or a path, got {type(source).__name__}")


class Decoder:
    """An opened compressed file: the header checked and the factor matrices decoded.

    Args:
        source: the whole file's bytes, or a path: then the file is read from disk (only a
            regular file, and no more than its preamble declares), and errors name it.
        limits: the decoder's limits (§7).

    Raises:
        FormatError: or one of its subclasses, with the rule broken and the field or offset at
            fault (and the path, for a file read from disk).
        InputError: a path that is a folder, a pipe or a device.
        OSError: a path that cannot be read.
    """

    def __init__(self, source: CompressedFile, *, limits: Limits = DEFAULT_LIMITS) -> None:
        self.path = os.fspath(source) if isinstance(source, (str, os.PathLike)) else None
        try:
            data = _bytes_of(source, limits)
            container = parse_container(data, limits)
            self.info = read_header(container, limits)
            self._decode_sections(container, data, limits)
        except FormatError as error:
            error.path = self.path
            raise

    def _decode_sections(
        self, container: Container, data: bytes | memoryview, limits: Limits
    ) -> None:
        """§5 steps 15-17: FACE, then U1, U3, CORE and CENT, then NAME."""
        vertices, frames = self.info.vertices, self.info.frames
        i, k = self.info.ranks

        def payload(section_id: str) -> memoryview:
            section = container.section(section_id)
            assert section is not None  # read_header found every required section
            return container.payload(data, section)

        def params(section_id: str) -> dict[str, object]:
            section = container.section(section_id)
            assert section is not None
            return section.params

        self.faces = faces.decode_faces(payload("FACE"), params("FACE"), vertices, "section FACE")

        def parents() -> np.ndarray:
            # K entries: made only after U1's payload has passed its CRC and zstd checks,
            # which bound K by the file's size, and only if a column of U1 is predicted
            return mesh_parents(self.faces, vertices)

        self.u1 = qmat.decode_matrix(payload("U1"), params("U1"), parents, "section U1").values()
        # U3 and CENT are predicted from the previous frame (parents None), CORE from nothing
        self.u3 = qmat.decode_matrix(payload("U3"), params("U3"), None, "section U3").values()
        core = qmat.decode_matrix(
            payload("CORE"), params("CORE"), None, "section CORE", allow_predict=False
        )
        self.core = core.values().reshape(i, 3, k)
        self.centroids = qmat.decode_matrix(
            payload("CENT"), params("CENT"), None, "section CENT"
        ).values()
        self.u2 = np.array(container.header["u2"], dtype=np.float64).reshape(3, 3)
        name_section = container.section("NAME")
        if name_section is None:
            self.frame_names = names.default_frame_names(frames)
        else:
            self.frame_names = names.decode_names(
                name_section.params,
                lambda: container.payload(data, name_section),
                frames,
                limits,
                "section NAME",
            )
        # CORE x2 U2 once: every frame then needs only U3's row and one product with U1.
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is R36, found per frame
            self._basis = reconstruction_basis(self.core, self.u2)

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
        """Decoded positions of the selected frames, (n, K, 3) float64 (§8)."""
        chosen = self._selected(frames)
        # Overflow is a property of the file, reported below as R36: numpy must not warn (or,
        # under np.seterr(all="raise"), raise FloatingPointError) before that check runs.
        with np.errstate(over="ignore", invalid="ignore"):
            positions = reconstruct_frames(
                self.u1, self._basis, self.u3[chosen], self.centroids[chosen]
            )
        if not np.isfinite(positions).all():  # finite factors whose products overflow
            raise FormatError(
                "the reconstruction overflows float64: the factors are out of range",
                rule="R36-reconstruction-finite",
                field="header.u2",
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
        in_time = chosen.size < self.info.frames and bool(np.all(np.diff(chosen) > 0))
        return MeshSequence(
            self.positions(chosen),
            self.faces,
            frame_names=[self.frame_names[n] for n in chosen],
            frame_rate=self.info.frame_rate,
            # a part in order keeps its frames' places in time (frame n at time code n)
            time_codes=np.asarray(chosen, dtype=np.float64) if in_time else None,
        )


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
        data = _bytes_of(source, limits, header_only=True)
        return read_header(parse_container(data, limits, whole=path is None), limits)
    except FormatError as error:
        error.path = path
        raise


__all__ = ["CompressedFile", "Decoder", "FileInfo", "FrameSelection", "decode", "info"]
