"""The .npz archive as a sequence: :class:`NpzFrames` reads its positions a range at a time after
checking every member's header, and :func:`write_npz` writes one."""

from __future__ import annotations

import copy
import struct
import zipfile
from pathlib import Path
from typing import IO, Any, ClassVar

import numpy as np

from ...errors import InputError
from ...model.attributes import Field
from ...model.sequence import MeshSequence
from ...model.sources import RawFrames, read_into
from ...system.atomic import atomic_output
from ...system.reading import open_input
from ..common.attached_keys import DESCRIPTION, Attached, attached_arrays, read_attached
from ..registry import ReadOptions, WriteOptions
from .archive import ZIP_ERRORS, NpzArchive, member_header

#: A zip local file header: signature, 22 bytes, then the lengths of the name and extra field.
_LOCAL_HEADER = struct.Struct("<4s22xHH")
_LOCAL_SIGNATURE = b"PK\x03\x04"


class NpzFrames(RawFrames):
    """Key V of an .npz archive read in place (see the module docstring); the archive format
    takes no read options."""

    _transient: ClassVar[tuple[str, ...]] = ("_member", "_archive", "_stream", "_whole")
    _what = "an .npz archive"
    _vertex_label = "key 'V': "
    _member: IO[bytes] | None = None
    _archive: zipfile.ZipFile | None = None
    #: Key V read whole: for :meth:`load`, or in Fortran order (read on first use)
    _whole: np.ndarray | None = None
    #: The fields' values, read whole on the first :meth:`read_fields`
    _field_values: list[np.ndarray] | None

    def __init__(self, path: Path, options: ReadOptions | None = None):
        # what the arrays read whole may inflate to: the metadata's, held, then V's when read
        self._inflation = (options or ReadOptions()).inflation()
        with NpzArchive(path, self._inflation) as archive:
            info = archive.info("V")
            header = member_header(archive.zip, info, "V", archive.size, path)
            if header.dtype.kind not in "fiu":
                raise InputError(
                    f"key 'V' must hold real numbers, got dtype {header.dtype}", path=path
                )
            shape = header.positions()
            if shape is None:
                raise InputError(
                    f"key 'V' must have shape (frames, vertices, 3), got {header.shape}",
                    path=path,
                )
            faces, names, rate, codes = archive.metadata(*shape)
            unit, axis = archive.scene()
            attached = self._attached(archive, shape[0], shape[1], faces, path)
            self._name = info.filename
            self._deflated = info.compress_type == zipfile.ZIP_DEFLATED
            self._scattered = header.fortran_order and shape[0] > 1
            self._offset = header.size  # in the member
            self._data_start = 0  # where a stored member's bytes start in the file
            if not self._deflated:
                self._data_start = _data_start(archive.stream, info, archive.size, path)
        self._file, self._dtype = path, header.dtype
        self._fields, self._field_values = attached.fields, None
        self._describe(
            path,
            *shape,
            faces,
            names,
            rate,
            codes,
            unit,
            axis,
            attached.attributes,
            attached.face_sets,
            [entry.name for entry in attached.fields],
        )

    @staticmethod
    def _attached(
        archive: NpzArchive, frames: int, vertices: int, faces: object, path: Path
    ) -> Attached:
        """The attributes, face sets and field entries of the archive (none without its
        description), each field's shape checked from its header."""
        if DESCRIPTION not in archive.members:
            return Attached([], [], [])
        text = archive.array(DESCRIPTION)
        if text.dtype.kind != "U" or text.size != 1:
            raise InputError(
                f"key {DESCRIPTION!r} must be one string, got dtype {text.dtype} shape "
                f"{text.shape}",
                path=path,
            )

        def array(key: str) -> np.ndarray:
            if key not in archive.members:
                raise InputError("is missing")
            return archive.array(key)

        try:
            attached = read_attached(str(text.reshape(())), array)
        except InputError as error:
            raise InputError(error.reason, path=path) from None
        face_count = np.asarray(faces).shape[0]
        for entry in attached.fields:
            if entry.key not in archive.members:
                raise InputError(f"key {entry.key!r} is missing", path=path)
            header = member_header(
                archive.zip, archive.info(entry.key), entry.key, archive.size, path
            )
            count = vertices if entry.domain == "vertex" else face_count
            if len(header.shape) != 3 or header.shape[:2] != (frames, count):
                raise InputError(
                    f"key {entry.key!r} (field {entry.name!r}) has shape {header.shape}, not "
                    f"({frames}, {count}, components)",
                    path=path,
                )
        return attached

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        if self._field_values is None:  # read whole on first use (CRC checked), then kept
            with NpzArchive(self._file, copy.copy(self._inflation)) as archive:
                self._field_values = [archive.array(entry.key) for entry in self._fields]
        fields = []
        for entry, values in zip(self._fields, self._field_values, strict=True):
            try:
                fields.append(entry.field(values[start:stop]))
            except InputError as error:
                frame = None if error.frame is None else start + error.frame
                raise InputError(
                    f"key {entry.key!r}: {error.reason}", path=self._file, frame=frame
                ) from None
        return fields

    def load(self, progress: bool = False) -> MeshSequence:
        """The whole sequence, key V read in one piece through zipfile, which checks its CRC."""
        self._whole = self._read_whole()
        try:
            return super().load()
        finally:
            self._whole = None

    def _read(self, start: int, stop: int) -> np.ndarray:
        if self._scattered and self._whole is None:
            self._whole = self._read_whole()
        if self._whole is not None:
            return self._whole[start:stop]
        return super()._read(start, stop)

    def _read_whole(self) -> np.ndarray:
        """Key V as the file stores it, (F, K, 3) (every byte read: CRC checked)."""
        with NpzArchive(self._file, copy.copy(self._inflation)) as archive:
            values = archive.array("V")
        if values.size != self.frame_count * self.vertex_count * 3:
            raise InputError("has changed since it was opened", path=self._file)
        return values.reshape(self.frame_count, self.vertex_count, 3)

    def _read_at(self, offset: int, into: memoryview) -> None:
        if not self._deflated:
            super()._read_at(self._data_start + offset, into)
            return
        try:
            if self._member is None:
                self._stream = open_input(self._file, self._what)
                self._archive = zipfile.ZipFile(self._stream)
                self._member = self._archive.open(self._name)
            # forward: decompresses from where the last read stopped; backward: from the start
            self._member.seek(offset)
            read_into(self._member, into, self._file)
        except InputError:
            raise
        except ZIP_ERRORS as error:
            raise InputError(f"key 'V' cannot be read: {error}", path=self._file) from None


def _data_start(stream: IO[bytes], info: zipfile.ZipInfo, size: int, path: Path) -> int:
    """Where a stored member's bytes start in the file: after its local header."""
    stream.seek(info.header_offset)
    raw = stream.read(_LOCAL_HEADER.size)
    if len(raw) != _LOCAL_HEADER.size or raw[:4] != _LOCAL_SIGNATURE:
        raise InputError("key 'V' has no local header where the archive says", path=path)
    _, name_length, extra_length = _LOCAL_HEADER.unpack(raw)
    start = info.header_offset + _LOCAL_HEADER.size + name_length + extra_length
    if start + info.compress_size > size:
        raise InputError(
            f"key 'V' ends beyond the end of the file ({size} bytes): the file is truncated",
            path=path,
        )
    return start


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What an ``.npz`` cannot keep of ``seq``: nothing, every attribute, face set and field is
    kept bit for bit."""
    return []


def write_npz(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as an .npz archive, atomically."""
    arrays: dict[str, Any] = {
        "V": np.asarray(seq.vertices, dtype=np.float64),
        "F": np.asarray(seq.faces, dtype=np.int64),
        "frame_files": np.array(seq.frame_names, dtype=str),
    }
    if seq.frame_rate is not None:
        arrays["frame_rate"] = np.float64(seq.frame_rate)
    if seq.time_codes is not None:
        arrays["time_codes"] = np.asarray(seq.time_codes, dtype=np.float64)
    if seq.meters_per_unit is not None:
        arrays["meters_per_unit"] = np.float64(seq.meters_per_unit)
    if seq.up_axis is not None:
        arrays["up_axis"] = np.array(seq.up_axis, dtype=str)
    description, attached = attached_arrays(seq)
    if description:
        arrays[DESCRIPTION] = np.array(description, dtype=str)
        arrays.update(attached)
    # np.savez adds ".npz" to a file *name* without it, so it gets an open file instead
    with atomic_output(path, overwrite=options.overwrite) as stream:
        np.savez(stream, **arrays)
