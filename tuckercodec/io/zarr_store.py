"""Zarr stores (a folder named ``*.zarr``): an array of positions (frames, vertices, 3), read
and written with zarr (the ``zarr`` extra), zarr format 2 or 3.

Reading: the store's root array, or in a group the array ``vertices``, of real numbers (any
dtype zarr reads as one); with a group, optionally an integer array ``faces`` (M, n), 0-based,
-1 padding, and the attributes ``frame_rate`` (a number), ``frame_names`` (one string per
frame), ``time_codes`` (one number per frame), ``meters_per_unit`` (a number) and ``up_axis``
(``Y`` or ``Z``); attributes, face sets and fields as the arrays ``attribute/<i>/values``,
``attribute/<i>/indices``, ``face_set/<i>``, ``field/<i>`` and the attribute ``attached``, the
JSON description that names them (:mod:`~tuckercodec.io.common.attached_keys`, as in an
``.npz``; attributes and face sets read whole at opening, fields a range at a time).
Frames are read chunk by chunk: a range reads
only the chunks it overlaps (:class:`ZarrFrames`), so a store larger than memory streams. A
chunk larger than :data:`MAX_CHUNK_BYTES` is refused (it would be read whole for one frame), or
than ``--max-memory`` if less (it is decompressed whole), and so are faces beyond either.
A missing chunk reads as the array's fill value, as zarr defines it: the writer here uses NaN,
so a lost chunk is an error, not zeros.

Writing ``out.zarr``: a zarr format 3 group holding ``vertices`` (float32 where exact, else
float64; chunked by :data:`CHUNK_FRAMES` frames, each chunk all vertices; zarr's default
compressor), ``faces`` (int64, when the sequence has faces), the attributes above, and the
sequence's attributes, face sets and fields, bit for bit (fields chunked as the positions).
The store is written in a hidden folder beside the target and renamed into place when complete
(:func:`~tuckercodec.system.atomic.atomic_store`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from ..errors import InputError
from ..model.attributes import Field
from ..model.sequence import MeshSequence
from ..model.sources import FrameSource
from ..system.atomic import atomic_store
from ..system.optional import import_optional
from .common.attached_keys import DESCRIPTION, Attached, attached_arrays, read_attached
from .common.budget import memory_ceiling
from .registry import ReadOptions, WriteOptions

#: Frames per chunk of a written store.
CHUNK_FRAMES = 100
#: The largest chunk read, decompressed: 1 GiB.
MAX_CHUNK_BYTES = 2**30
#: The name of the positions in a group.
VERTICES = "vertices"


def _zarr(purpose: str) -> Any:
    return import_optional("zarr", "zarr", purpose)


class ZarrFrames(FrameSource):
    """The frames of a zarr store, read chunk by chunk (see the module docstring)."""

    _transient: ClassVar[tuple[str, ...]] = ("_array",)
    _array: Any = None

    def __init__(self, path: Path, options: ReadOptions | None = None):
        self._file = path
        node = _open(path)
        array, group = (node, None) if _is_array(node) else (_member(node, VERTICES, path), node)
        if not _is_array(array):
            raise InputError(f"its {VERTICES!r} is a group, not an array", path=path)
        shape, dtype = tuple(array.shape), np.dtype(array.dtype)
        name = "its array" if group is None else f"array {VERTICES!r}"
        if dtype.kind not in "fiu":
            raise InputError(f"{name} holds {dtype} values, not real numbers", path=path)
        if len(shape) != 3 or shape[2] != 3:
            raise InputError(f"{name} has shape {shape}, not (frames, vertices, 3)", path=path)
        largest = min(MAX_CHUNK_BYTES, memory_ceiling((options or ReadOptions()).max_memory))
        chunk = math.prod(array.chunks) * dtype.itemsize
        if chunk > largest:
            raise InputError(
                f"{name} has chunks {tuple(array.chunks)} of {chunk} bytes, more than the "
                f"{largest} read at once (--max-memory, at most {MAX_CHUNK_BYTES}): rechunk it "
                "by frames",
                path=path,
            )
        self._array = array
        faces: object = np.zeros((0, 3), dtype=np.int64)
        attributes: dict[str, Any] = {}
        attached = Attached([], [], [])
        if group is not None:
            attributes = dict(group.attrs)
            if "faces" in group:
                faces = _faces(_member(group, "faces", path), path, largest)
            attached = _attached(group, attributes, shape[0], shape[1], faces, path, largest)
        self._fields = attached.fields
        self._describe(
            path,
            shape[0],
            shape[1],
            faces,
            _attribute(attributes, "frame_names", path),
            _attribute(attributes, "frame_rate", path),
            _attribute(attributes, "time_codes", path),
            _attribute(attributes, "meters_per_unit", path),
            _attribute(attributes, "up_axis", path),
            attached.attributes,
            attached.face_sets,
            [entry.name for entry in attached.fields],
        )

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        group = _open(self._file)
        fields = []
        for entry in self._fields:
            try:
                values = np.asarray(group[entry.key][start:stop])
            except Exception as error:  # zarr and its codecs raise many kinds
                raise InputError(
                    f"array {entry.key!r} cannot be read: {type(error).__name__}: {error}",
                    path=self._file,
                    frame=start,
                ) from None
            try:
                fields.append(entry.field(values))
            except InputError as error:
                frame = None if error.frame is None else start + error.frame
                raise InputError(
                    f"array {entry.key!r}: {error.reason}", path=self._file, frame=frame
                ) from None
        return fields

    def _read(self, start: int, stop: int) -> np.ndarray:
        if self._array is None:
            node = _open(self._file)
            self._array = node if _is_array(node) else _member(node, VERTICES, self._file)
        try:
            return np.asarray(self._array[start:stop])
        except Exception as error:  # zarr and its codecs raise many kinds on a damaged chunk
            raise InputError(
                f"frames {start} to {stop - 1} cannot be read: {type(error).__name__}: {error}",
                path=self._file,
                frame=start,
            ) from None


def _attached(
    group: Any,
    attributes: dict[str, Any],
    frames: int,
    vertices: int,
    faces: object,
    path: Path,
    largest: int,
) -> Attached:
    """The group's attributes, face sets (read whole, within ``largest`` bytes each) and
    field entries (their arrays' shapes and chunks checked), from its description."""
    text = attributes.get(DESCRIPTION)
    if text is None:
        return Attached([], [], [])
    if not isinstance(text, str):
        raise InputError(f"its attribute {DESCRIPTION!r} is not a string (JSON)", path=path)

    def array(key: str) -> np.ndarray:
        if key not in group:
            raise InputError("is missing")
        member = group[key]
        if not _is_array(member) or math.prod(member.shape) * 8 > largest:
            raise InputError(f"is not an array of at most {largest} bytes")
        return np.asarray(member[...])

    try:
        attached = read_attached(text, array)
    except InputError as error:
        raise InputError(error.reason, path=path) from None
    face_count = np.asarray(faces).shape[0]
    for entry in attached.fields:
        member = group.get(entry.key, None)
        count = vertices if entry.domain == "vertex" else face_count
        shape = tuple(member.shape) if _is_array(member) else None
        if member is None or shape is None or len(shape) != 3 or shape[:2] != (frames, count):
            raise InputError(
                f"its array {entry.key!r} (field {entry.name!r}) has shape {shape}, not "
                f"({frames}, {count}, components)",
                path=path,
            )
        if math.prod(member.chunks) * np.dtype(member.dtype).itemsize > largest:
            raise InputError(
                f"its array {entry.key!r} has chunks of more than {largest} bytes", path=path
            )
    return attached


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What a zarr store cannot keep of ``seq``: nothing, every attribute, face set and field
    is kept bit for bit."""
    return []


def _open(path: Path) -> Any:
    """The store's root node (an array or a group), opened read-only."""
    zarr = _zarr("reading zarr stores")
    if not path.is_dir():
        raise InputError("is not a zarr store (a folder)", path=path)
    try:
        return zarr.open(store=str(path), mode="r")
    except Exception as error:  # a missing or damaged zarr.json / .zarray / .zgroup
        raise InputError(
            f"cannot read as a zarr store: {type(error).__name__}: {error}", path=path
        ) from None


def _is_array(node: Any) -> bool:
    return hasattr(node, "chunks") and hasattr(node, "shape")


def _member(group: Any, name: str, path: Path) -> Any:
    try:
        return group[name]
    except KeyError:
        members = sorted(group.keys()) if hasattr(group, "keys") else []
        raise InputError(
            f"holds no array {name!r} (positions, frames x vertices x 3); its members are "
            f"{members}",
            path=path,
        ) from None
    except Exception as error:
        raise InputError(
            f"cannot read its {name!r}: {type(error).__name__}: {error}", path=path
        ) from None


def _faces(array: Any, path: Path, largest: int) -> np.ndarray:
    """The ``faces`` array, (M, n) integers of at most ``largest`` bytes as int64 (checked as
    faces by the caller)."""
    if not _is_array(array):
        raise InputError("its 'faces' is a group, not an array", path=path)
    if np.dtype(array.dtype).kind not in "iu" or len(array.shape) != 2:
        raise InputError(
            f"its 'faces' must be integers of shape (faces, corners), got {array.dtype} "
            f"{tuple(array.shape)}",
            path=path,
        )
    if math.prod(array.shape) * 8 > largest:
        raise InputError(
            f"its 'faces' {tuple(array.shape)} are too many to read (more than {largest} bytes "
            "of int64: --max-memory)",
            path=path,
        )
    try:
        faces = np.asarray(array[...])
    except Exception as error:
        raise InputError(
            f"its 'faces' cannot be read: {type(error).__name__}: {error}", path=path
        ) from None
    return faces


def _attribute(attributes: dict[str, Any], name: str, path: Path) -> Any:
    """An attribute's value for the description (checked there), or ``None``."""
    value = attributes.get(name)
    if value is None:
        return None
    if name in ("frame_rate", "meters_per_unit"):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"its attribute {name} is {value!r}, not a number", path=path)
        return float(value)
    if name == "up_axis":
        if not isinstance(value, str):
            raise InputError(f"its attribute up_axis is {value!r}, not a string", path=path)
        return value
    if not isinstance(value, list):
        raise InputError(f"its attribute {name} is not a list, one item per frame", path=path)
    if name == "frame_names":
        return [str(item) for item in value]
    if not all(isinstance(item, (int, float)) and not isinstance(item, bool) for item in value):
        raise InputError(f"its attribute {name} holds an item that is not a number", path=path)
    return np.array(value, dtype=np.float64)


def write_zarr(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as a zarr format 3 group (see the module docstring), atomically."""
    zarr = _zarr("writing zarr stores")
    values = seq.compact_vertices()
    attributes: dict[str, Any] = {"frame_names": seq.frame_names}
    if seq.frame_rate is not None:
        attributes["frame_rate"] = seq.frame_rate
    if seq.time_codes is not None:
        attributes["time_codes"] = seq.time_codes.tolist()
    if seq.meters_per_unit is not None:
        attributes["meters_per_unit"] = seq.meters_per_unit
    if seq.up_axis is not None:
        attributes["up_axis"] = seq.up_axis
    with atomic_store(path, overwrite=options.overwrite) as staging:
        group = zarr.create_group(store=str(staging), zarr_format=3)
        frames = min(CHUNK_FRAMES, seq.frame_count)
        vertices = group.create_array(
            VERTICES,
            shape=values.shape,
            chunks=(frames, seq.vertex_count, 3),
            dtype=values.dtype,
            fill_value=np.nan,  # a lost chunk reads as NaN, which reading refuses
        )
        for start in range(0, seq.frame_count, frames):
            vertices[start : start + frames] = values[start : start + frames]
        if seq.faces.shape[0]:
            group.create_array("faces", data=np.asarray(seq.faces, dtype=np.int64))
        description, arrays = attached_arrays(seq)
        for key, values in arrays.items():
            if key.startswith("field/"):  # chunked by frames, as the positions
                chunks = (frames, *values.shape[1:])
                group.create_array(key, shape=values.shape, chunks=chunks, dtype=values.dtype)
                group[key][...] = values
            else:
                group.create_array(key, data=values)
        if description:
            attributes[DESCRIPTION] = description
        group.attrs.update(attributes)
