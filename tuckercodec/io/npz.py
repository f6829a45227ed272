"""The ``.npz`` sequence format: one NumPy archive holding the whole sequence.

Keys: ``V`` positions (frames, vertices, 3), optionally ``F`` faces (0-based, -1 padding),
``frame_files`` (one name per frame), ``frame_rate`` and ``time_codes``. It is read with
:mod:`zipfile` and ``numpy.lib.format``, never with pickle, and every declared size is checked
against the file before anything is allocated.
"""

from __future__ import annotations

import math
import os
import tokenize
import warnings
import zipfile
import zlib
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..atomic import atomic_output
from ..errors import InputError
from ..reading import open_input
from ..sequence import MeshSequence
from ..topology import face_table_problem
from .registry import ReadOptions, SequenceFormat, WriteOptions


def read_npz(path: Path, options: ReadOptions | None = None) -> MeshSequence:
    """A sequence from an .npz archive (keys V, optional F, frame_files, frame_rate,
    time_codes); the archive format takes no read options.

    The archive is read with :mod:`zipfile` and each array with ``numpy.lib.format``, never
    with pickle. A member must be a ``.npy`` array, stored or deflated (what ``np.savez`` and
    ``np.savez_compressed`` write), not encrypted, and present once. Before an array is
    allocated, the shape and dtype in its header must account for exactly the bytes of its
    member, and the member's sizes must be possible for the file: a header that claims a
    billion vertices in a small file is refused without allocating anything, and reading
    every byte of the member makes zipfile check its CRC.
    """
    stream = open_input(path, "an .npz archive")
    with stream:
        if stream.read(2) != b"PK":  # an .npz is a zip archive of .npy arrays
            raise InputError("is not an .npz archive (not a zip file)", path=path)
        try:
            stream.seek(0)
            archive = zipfile.ZipFile(stream)
        except _ZIP_ERRORS as error:
            raise InputError(f"cannot read as an .npz archive: {error}", path=path) from None
        with archive:
            return _read_npz(archive, os.fstat(stream.fileno()).st_size, path)


# What zipfile and numpy.lib.format raise on a damaged archive or member (ValueError: numpy's
# header checks; NotImplementedError: a zip feature such as strong encryption; TokenError: numpy
# runs a 1.0/2.0 header through tokenize, which raises it at an unclosed bracket; SyntaxError:
# np.dtype parses a comma string such as ',<f8' with ast.literal_eval and lets it through).
_ZIP_ERRORS = (
    OSError,
    EOFError,
    zipfile.BadZipFile,
    zlib.error,
    ValueError,
    NotImplementedError,
    tokenize.TokenError,
    SyntaxError,
)


def _read_npz(archive: zipfile.ZipFile, size: int, path: Path) -> MeshSequence:
    """The sequence in an open .npz archive of ``size`` bytes."""
    members: dict[str, list[zipfile.ZipInfo]] = {}
    for info in archive.infolist():
        # numpy's naming: the member "V.npy" (or a bare "V") is the key "V"
        members.setdefault(info.filename.removesuffix(".npy"), []).append(info)

    def member(key: str) -> np.ndarray:
        if len(members[key]) > 1:
            raise InputError(f"holds key {key!r} twice: which one is meant?", path=path)
        return _npz_member(archive, members[key][0], key, size, path)

    if "V" not in members:
        raise InputError(
            f"missing key 'V' (vertex positions, frames x vertices x 3); "
            f"the archive has {sorted(members)}",
            path=path,
        )
    vertices = _npz_vertices(member("V"), path)
    faces = np.zeros((0, 3), dtype=np.int64)
    if "F" in members:
        faces = _npz_faces(member("F"), vertices.shape[1], path)
    names: list[str] = []
    if "frame_files" in members:
        names = _npz_names(member("frame_files"), len(vertices), path)
    rate = None
    if "frame_rate" in members:
        rate = _npz_rate(member("frame_rate"), path)
    codes = member("time_codes") if "time_codes" in members else None
    try:
        return MeshSequence(vertices, faces, frame_names=names, frame_rate=rate, time_codes=codes)
    except InputError as error:
        raise InputError(error.reason, path=path, frame=error.frame) from None


# Deflate turns at most about 1032 bytes into one bit less than 8 (1029 measured on zeros), so a
# deflated member that claims more than this many times its compressed size is lying.
_MAX_DEFLATE_RATIO = 1100


def _npz_member(
    archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, size: int, path: Path
) -> np.ndarray:
    """Read one array of an archive of ``size`` bytes, checking its header before allocating.

    Object arrays (which would need pickle), members that are not .npy arrays, sizes the file
    cannot hold and headers that do not account for exactly the member's bytes are errors.
    """
    _check_member_sizes(info, key, size, path)
    magic = np.lib.format.MAGIC_PREFIX
    # numpy warns about what it meets in a header: one it must rewrite the Python 2 way ("3L",
    # a stray line break), a deprecated dtype alias ('a' for 'S')... The file is read as numpy
    # reads it and judged by the checks here, so its warnings are only noise for the user of a
    # data file (and exceptions under -W error, as the tests run).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            with archive.open(info) as stream:
                if stream.read(len(magic)) != magic:
                    raise InputError(f"key {key!r} is not a NumPy array (.npy) member", path=path)
            with archive.open(info) as stream:
                shape, dtype = _npy_header(stream, key, path)
                data_size = info.file_size - stream.tell()
            if dtype.hasobject:
                raise InputError(
                    f"key {key!r} holds Python objects (needs pickle, which is never loaded for "
                    "safety)",
                    path=path,
                )
            if any(length < 0 for length in shape):
                raise InputError(f"key {key!r} declares a negative shape {shape}", path=path)
            declared = math.prod(shape) * dtype.itemsize  # Python ints: no overflow
            if declared != data_size:
                raise InputError(
                    f"key {key!r} declares shape {shape} of {dtype} ({declared} bytes) but its "
                    f"member holds {data_size} bytes after the header",
                    path=path,
                )
            # every byte of the member is read, so zipfile checks the CRC at the end
            with archive.open(info) as stream:
                return np.lib.format.read_array(stream, allow_pickle=False)
        except _ZIP_ERRORS as error:
            if isinstance(error, InputError):
                raise
            raise InputError(f"key {key!r} cannot be read: {error}", path=path) from None


def _check_member_sizes(info: zipfile.ZipInfo, key: str, size: int, path: Path) -> None:
    """Refuse a member that is encrypted, oddly compressed, or whose sizes the file cannot hold."""
    if info.flag_bits & 0x1:
        raise InputError(f"key {key!r} is encrypted: an .npz never is", path=path)
    if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        raise InputError(
            f"key {key!r} is compressed with zip method {info.compress_type}; an .npz holds only "
            f"stored ({zipfile.ZIP_STORED}) or deflated ({zipfile.ZIP_DEFLATED}) members",
            path=path,
        )
    if info.header_offset + info.compress_size > size:
        raise InputError(
            f"key {key!r} claims {info.compress_size} bytes at offset {info.header_offset}, "
            f"beyond the end of the file ({size} bytes): the file is truncated or damaged",
            path=path,
        )
    if info.compress_type == zipfile.ZIP_STORED and info.file_size != info.compress_size:
        raise InputError(
            f"key {key!r} is stored uncompressed but claims {info.file_size} bytes in "
            f"{info.compress_size}: the archive is damaged",
            path=path,
        )
    if info.file_size > _MAX_DEFLATE_RATIO * max(info.compress_size, 1):
        raise InputError(
            f"key {key!r} claims {info.file_size} bytes from {info.compress_size} compressed, "
            "more than deflate can expand: the archive is damaged or crafted",
            path=path,
        )


def _npy_header(stream: IO[bytes], key: str, path: Path) -> tuple[tuple[int, ...], np.dtype]:
    """The shape and dtype in the header of an .npy member, read without its data."""
    version = np.lib.format.read_magic(stream)
    if version not in ((1, 0), (2, 0)):  # 3.0 is for Unicode field names, which V, F... lack
        raise InputError(
            f"key {key!r} is in .npy format {version[0]}.{version[1]}, not 1.0 or 2.0", path=path
        )
    read = np.lib.format.read_array_header_1_0
    if version == (2, 0):
        read = np.lib.format.read_array_header_2_0
    try:
        shape, _, dtype = read(stream)
    except _ZIP_ERRORS:
        raise  # turned into an InputError by the caller
    except Exception as error:
        # The header is a Python literal from the file, and numpy's checks of it let through
        # whatever the literal provokes: TypeError sorting keys of mixed types ({b'x': 1,
        # 'descr': ...}), and who knows what else. Any of them means a bad header.
        raise InputError(
            f"key {key!r} cannot be read: a bad .npy header ({type(error).__name__}: {error})",
            path=path,
        ) from None
    return tuple(shape), dtype


def _npz_vertices(values: np.ndarray, path: Path) -> np.ndarray:
    """Key V as float64 (F, K, 3); a (K, 3) array is one frame."""
    if values.dtype.kind not in "fiu":
        raise InputError(f"key 'V' must hold real numbers, got dtype {values.dtype}", path=path)
    if values.ndim == 2:
        values = values[np.newaxis]
    if values.ndim != 3 or values.shape[2] != 3 or values.shape[0] < 1 or values.shape[1] < 1:
        raise InputError(
            f"key 'V' must have shape (frames, vertices, 3), got {values.shape}", path=path
        )
    with np.errstate(over="ignore"):  # a long double beyond float64 becomes inf, named below
        values = values.astype(np.float64)
    bad = ~np.isfinite(values)
    if bad.any():
        frame, vertex, _ = (int(i) for i in np.argwhere(bad)[0])
        raise InputError(
            f"key 'V': vertex {vertex} has a non-finite coordinate", path=path, frame=frame
        )
    return values


def _npz_faces(values: np.ndarray, vertex_count: int, path: Path) -> np.ndarray:
    """Key F as int64 (M, n), 0-based, -1 padding."""
    if values.size == 0:
        return np.zeros((0, 3), dtype=np.int64)
    if values.dtype.kind not in "iu":
        raise InputError(
            f"key 'F' must hold integer vertex indices, got dtype {values.dtype}", path=path
        )
    if values.ndim != 2 or values.shape[1] < 3:
        raise InputError(
            f"key 'F' must have shape (faces, corners >= 3), got {values.shape}", path=path
        )
    problem = face_table_problem(values, vertex_count)  # before the cast: uint64 wraps to -1
    if problem is not None:
        one_based = problem.kind == "index" and int(values.max()) == vertex_count
        hint = " (it looks 1-based; F must be 0-based)" if one_based else ""
        raise InputError(f"key 'F': {problem.message}{hint}", path=path)
    return values.astype(np.int64)


def _npz_names(values: np.ndarray, frame_count: int, path: Path) -> list[str]:
    """Key frame_files as one string per frame."""
    if values.dtype.kind not in "US" or values.ndim != 1 or len(values) != frame_count:
        raise InputError(
            f"key 'frame_files' must be {frame_count} strings (one per frame), "
            f"got dtype {values.dtype} shape {values.shape}",
            path=path,
        )
    if values.dtype.kind == "S":
        try:
            return [name.decode("utf-8") for name in values.tolist()]
        except UnicodeDecodeError:
            raise InputError(
                "key 'frame_files' holds names that are not UTF-8", path=path
            ) from None
    return [str(name) for name in values.tolist()]


def _npz_rate(values: np.ndarray, path: Path) -> float:
    """Key frame_rate as a positive number of frames per second."""
    if values.dtype.kind not in "fiu" or values.size != 1:
        raise InputError(
            f"key 'frame_rate' must be one number, got dtype {values.dtype} shape {values.shape}",
            path=path,
        )
    rate = float(values.reshape(()))
    if not (np.isfinite(rate) and rate > 0):
        raise InputError(f"key 'frame_rate' must be a positive number, got {rate}", path=path)
    return rate


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
    # np.savez adds ".npz" to a file *name* without it, so it gets an open file instead
    with atomic_output(path, overwrite=options.overwrite) as stream:
        np.savez(stream, **arrays)


FORMAT = SequenceFormat(
    name="npz",
    suffixes=(".npz",),
    description=(
        "NumPy archive: V (frames, vertices, 3), F faces, frame_files, frame_rate, time_codes"
    ),
    read=read_npz,
    write=write_npz,
    carries=frozenset({"float64", "faces", "polygons", "frame_names", "frame_rate", "time_codes"}),
)
