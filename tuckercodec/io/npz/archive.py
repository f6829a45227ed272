"""Reading an ``.npz`` archive safely, for :mod:`tuckercodec.io.npz`: :class:`NpzArchive`
(members by key), the check of each member's sizes against the file and of its ``.npy`` header
against the member (:func:`member_header`, before anything is allocated), ``.npy`` headers
themselves (:func:`npy_header`, shared with :mod:`.npy`), and the checks of the keys beside
``V``. Never pickle.
"""

from __future__ import annotations

import math
import os
import tokenize
import warnings
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np

from ...errors import InputError
from ...model.topology import face_table_problem
from ...system.reading import open_input
from ..common.budget import Inflation, memory_ceiling

# What zipfile and numpy.lib.format raise on a damaged archive or member (ValueError: numpy's
# header checks; NotImplementedError: a zip feature such as strong encryption; TokenError: numpy
# runs a 1.0/2.0 header through tokenize, which raises it at an unclosed bracket; SyntaxError:
# np.dtype parses a comma string such as ',<f8' with ast.literal_eval and lets it through).
ZIP_ERRORS = (
    OSError,
    EOFError,
    zipfile.BadZipFile,
    zlib.error,
    ValueError,
    NotImplementedError,
    tokenize.TokenError,
    SyntaxError,
)


class NpzArchive:
    """An open .npz archive: its members by key (numpy's naming: the member "V.npy", or a bare
    "V", is the key "V"), each key present once, and key V present. The deflated members read
    whole inflate within ``inflation``, together (default: half the machine's memory)."""

    def __init__(self, path: Path, inflation: Inflation | None = None):
        self.path = path
        self.inflation = inflation or Inflation(memory_ceiling(None))
        self.stream = open_input(path, "an .npz archive")
        try:
            if self.stream.read(2) != b"PK":  # an .npz is a zip archive of .npy arrays
                raise InputError("is not an .npz archive (not a zip file)", path=path)
            self.size = os.fstat(self.stream.fileno()).st_size
            try:
                self.stream.seek(0)
                self.zip = zipfile.ZipFile(self.stream)
            except ZIP_ERRORS as error:
                raise InputError(f"cannot read as an .npz archive: {error}", path=path) from None
            self.members: dict[str, list[zipfile.ZipInfo]] = {}
            for info in self.zip.infolist():
                self.members.setdefault(info.filename.removesuffix(".npy"), []).append(info)
            if "V" not in self.members:
                raise InputError(
                    f"missing key 'V' (vertex positions, frames x vertices x 3); "
                    f"the archive has {sorted(self.members)}",
                    path=path,
                )
        except BaseException:
            self.close()
            raise

    def info(self, key: str) -> zipfile.ZipInfo:
        """The member of a key the archive holds, refused if it holds it twice."""
        if len(self.members[key]) > 1:
            raise InputError(f"holds key {key!r} twice: which one is meant?", path=self.path)
        return self.members[key][0]

    def array(self, key: str) -> np.ndarray:
        """A key's array, read whole (checked before allocating, and a deflated one against
        what the archive may still inflate; CRC checked)."""
        info = self.info(key)
        member_header(self.zip, info, key, self.size, self.path)
        if info.compress_type == zipfile.ZIP_DEFLATED:
            # zipfile inflates a member no further than the size it declares
            self.inflation.take(info.file_size, f"key {key!r} ({info.filename})", self.path)
        return _npz_member(self.zip, info, key, self.path)

    def metadata(
        self, frame_count: int, vertex_count: int
    ) -> tuple[np.ndarray, list[str], float | None, np.ndarray | None]:
        """Faces (key F), frame names, frame rate and time codes, where the archive has them."""
        faces = np.zeros((0, 3), dtype=np.int64)
        if "F" in self.members:
            faces = _npz_faces(self.array("F"), vertex_count, self.path)
        names: list[str] = []
        if "frame_files" in self.members:
            names = _npz_names(self.array("frame_files"), frame_count, self.path)
        rate = None
        if "frame_rate" in self.members:
            rate = _npz_rate(self.array("frame_rate"), self.path)
        codes = self.array("time_codes") if "time_codes" in self.members else None
        return faces, names, rate, codes

    def scene(self) -> tuple[float | None, str | None]:
        """Keys meters_per_unit (one positive number) and up_axis (one string), where the
        archive has them; their values are checked where the source is described."""
        unit: float | None = None
        if "meters_per_unit" in self.members:
            values = self.array("meters_per_unit")
            if values.dtype.kind not in "fiu" or values.size != 1:
                raise InputError(
                    f"key 'meters_per_unit' must be one number, got dtype {values.dtype} "
                    f"shape {values.shape}",
                    path=self.path,
                )
            unit = float(values.reshape(()))
        axis: str | None = None
        if "up_axis" in self.members:
            values = self.array("up_axis")
            if values.dtype.kind != "U" or values.size != 1:
                raise InputError(
                    f"key 'up_axis' must be one string, got dtype {values.dtype} "
                    f"shape {values.shape}",
                    path=self.path,
                )
            axis = str(values.reshape(()))
        return unit, axis

    def close(self) -> None:
        if hasattr(self, "zip"):
            self.zip.close()
        self.stream.close()

    def __enter__(self) -> NpzArchive:
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()


# Deflate turns at most about 1032 bytes into one bit less than 8 (1029 measured on zeros), so a
# deflated member that claims more than this many times its compressed size is lying.
_MAX_DEFLATE_RATIO = 1100


def _npz_member(
    archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, path: Path
) -> np.ndarray:
    """Read one array of an archive whose header :func:`member_header` has checked."""
    try:
        # every byte of the member is read, so zipfile checks the CRC at the end
        with warnings.catch_warnings(), archive.open(info) as stream:
            warnings.simplefilter("ignore")  # see npy_header
            return np.lib.format.read_array(stream, allow_pickle=False)
    except ZIP_ERRORS as error:
        raise InputError(f"key {key!r} cannot be read: {error}", path=path) from None


def member_header(
    archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, size: int, path: Path
) -> NpyHeader:
    """The header of the .npy array in a member of an archive of ``size`` bytes, checked to
    declare exactly the member's bytes; nothing of the array is read."""
    _check_member_sizes(info, key, size, path)
    label = f"key {key!r}"
    try:
        with archive.open(info) as stream:
            if stream.read(len(np.lib.format.MAGIC_PREFIX)) != np.lib.format.MAGIC_PREFIX:
                raise InputError(f"{label} is not a NumPy array (.npy) member", path=path)
        with archive.open(info) as stream:
            header = npy_header(stream, label, path)
    except InputError:
        raise
    except ZIP_ERRORS as error:
        raise InputError(f"{label} cannot be read: {error}", path=path) from None
    data_size = info.file_size - header.size
    declared = header.data_bytes()
    if declared != data_size:
        raise InputError(
            f"{label} declares shape {header.shape} of {header.dtype} ({declared} bytes) but its "
            f"member holds {data_size} bytes after the header",
            path=path,
        )
    return header


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


@dataclass(frozen=True)
class NpyHeader:
    """What the header of an .npy array declares, and its own size in bytes (where the data
    starts)."""

    shape: tuple[int, ...]
    fortran_order: bool
    dtype: np.dtype
    size: int

    def data_bytes(self) -> int:
        """The bytes of data the header declares (Python integers: no overflow)."""
        return math.prod(self.shape) * self.dtype.itemsize

    def positions(self) -> tuple[int, int] | None:
        """Frames and vertices of an array of positions, shaped (frames, vertices, 3) or
        (vertices, 3) for one frame; ``None`` for any other shape."""
        shape = (1, *self.shape) if len(self.shape) == 2 else self.shape
        if len(shape) != 3 or shape[2] != 3 or shape[0] < 1 or shape[1] < 1:
            return None
        return shape[0], shape[1]


def npy_header(stream: IO[bytes], label: str, path: str | os.PathLike[str]) -> NpyHeader:
    """The header of the .npy array at the stream's position, read without its data and
    checked: format 1.0 or 2.0, no Python objects, no negative length. ``label`` names the
    array in errors ("key 'V'", "its array")."""
    start = stream.tell()
    # numpy warns about what it meets in a header: one it must rewrite the Python 2 way ("3L",
    # a stray line break), a deprecated dtype alias ('a' for 'S')... The file is read as numpy
    # reads it and judged by the checks here, so its warnings are only noise for the user of a
    # data file (and exceptions under -W error, as the tests run).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            version = np.lib.format.read_magic(stream)
            if version not in ((1, 0), (2, 0)):  # 3.0: Unicode field names, which V, F... lack
                raise InputError(
                    f"{label} is in .npy format {version[0]}.{version[1]}, not 1.0 or 2.0",
                    path=path,
                )
            read = np.lib.format.read_array_header_1_0
            if version == (2, 0):
                read = np.lib.format.read_array_header_2_0
            shape, fortran_order, dtype = read(stream)
        except InputError:
            raise
        except ZIP_ERRORS as error:
            raise InputError(f"{label} cannot be read: {error}", path=path) from None
        except Exception as error:
            # The header is a Python literal from the file, and numpy's checks of it let
            # through whatever the literal provokes: TypeError sorting keys of mixed types
            # ({b'x': 1, 'descr': ...}), and who knows what else. Any of them: a bad header.
            raise InputError(
                f"{label} cannot be read: a bad .npy header ({type(error).__name__}: {error})",
                path=path,
            ) from None
    if dtype.hasobject:
        raise InputError(
            f"{label} holds Python objects (needs pickle, which is never loaded for safety)",
            path=path,
        )
    if any(length < 0 for length in shape):
        raise InputError(f"{label} declares a negative shape {tuple(shape)}", path=path)
    return NpyHeader(tuple(shape), bool(fortran_order), dtype, stream.tell() - start)


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
    # numpy stores each character as a 32-bit code point it does not check: one beyond
    # Unicode makes tolist() raise SystemError, and a lone surrogate cannot be written as UTF-8
    points = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("=")).view(np.uint32)
    if np.any((points > 0x10FFFF) | ((points >= 0xD800) & (points <= 0xDFFF))):
        raise InputError(
            "key 'frame_files' holds characters that are not Unicode (a code point above "
            "U+10FFFF, or a surrogate)",
            path=path,
        )
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
