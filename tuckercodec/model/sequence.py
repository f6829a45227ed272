"""The in-memory mesh sequence: F frames of K vertices sharing one set of faces."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .attributes import Attribute, FaceSet, Field, check_attached
from .topology import checked_face_table

#: Frames per second assumed where a format needs a rate and the sequence has none: 24, the
#: default of USD (timeCodesPerSecond), Blender and film.
DEFAULT_FRAME_RATE = 24.0

#: The up axes a sequence may name: USD's (UsdGeom allows only Y and Z), and glTF's Y. The
#: file format's header stores the same two (spec/FORMAT.md §4).
UP_AXES = ("Y", "Z")


def default_frame_names(count: int) -> list[str]:
    """``frame_00000``, ``frame_00001``...: the names of frames that have none of their own (a
    file without a NAME section, spec/FORMAT.md §6.5)."""
    return [f"frame_{n:05d}" for n in range(count)]


@dataclass(eq=False)
class MeshSequence:
    """A temporally coherent mesh sequence.

    Attributes:
        vertices: float64 array of shape (F, K, 3): frame, vertex, xyz. Vertex order is the order
            of the source files, never changed.
        faces: int64 array of shape (M, n) with 0-based vertex indices. Every face has n corners,
            except that a polygon with fewer corners than the widest face is padded with -1 at the
            end of its row (a mesh of triangles is simply (M, 3)). May be (0, 3) for a point cloud.
        frame_names: one name per frame (the source file name, or ``frame_00000``..., the
            default names of the format, ``spec/FORMAT.md`` §6.5).
        frame_rate: frames per second, if known.
        time_codes: each frame's time in frames (USD's time codes, a point cache's frame
            numbers): float64, strictly increasing; ``None`` means 0, 1, 2... A frame's time in
            seconds is its time code divided by the frame rate (:meth:`seconds`).
        meters_per_unit: the length of one unit of the positions in metres (USD's
            ``metersPerUnit``: 0.01 for centimetres, 1.0 for metres), if known.
        up_axis: ``"Y"`` or ``"Z"``, the axis that points up in the source, if known.
        attributes: static values per vertex, corner or face (UVs, normals, colours...),
            :class:`~.attributes.Attribute`; their corners and faces are in the order of
            :attr:`faces`.
        face_sets: named sets of faces (materials, groups), :class:`~.attributes.FaceSet`.
        fields: animated values per vertex or face (velocities, simulation data),
            :class:`~.attributes.Field`, one row per frame.
    """

    vertices: np.ndarray
    faces: np.ndarray
    frame_names: list[str] = field(default_factory=list)
    frame_rate: float | None = None
    time_codes: np.ndarray | None = None
    meters_per_unit: float | None = None
    up_axis: str | None = None
    attributes: list[Attribute] = field(default_factory=list)
    face_sets: list[FaceSet] = field(default_factory=list)
    fields: list[Field] = field(default_factory=list)

    def __post_init__(self) -> None:
        vertices = np.asarray(self.vertices)
        if vertices.ndim != 3 or vertices.shape[2] != 3:
            raise InputError(
                f"vertices must have shape (frames, vertices, 3), got {vertices.shape}"
            )
        if vertices.shape[0] < 1 or vertices.shape[1] < 1:
            raise InputError(
                f"a sequence needs at least one frame and one vertex, got {vertices.shape}"
            )
        if not np.issubdtype(vertices.dtype, np.number) or np.iscomplexobj(vertices):
            raise InputError(f"vertices must be real numbers, got dtype {vertices.dtype}")
        with np.errstate(over="ignore"):  # a long double beyond float64 becomes inf, named below
            self.vertices = np.ascontiguousarray(vertices, dtype=np.float64)
        bad = ~np.isfinite(self.vertices)
        if bad.any():
            f, k, _ = np.argwhere(bad)[0]
            raise InputError(f"vertex {k} has a non-finite coordinate", frame=int(f))

        self.faces = checked_face_table(self.faces, self.vertex_count)

        if not self.frame_names:
            self.frame_names = default_frame_names(self.frame_count)
        self.frame_names = [str(name) for name in self.frame_names]
        if len(self.frame_names) != self.frame_count:
            raise InputError(
                f"{len(self.frame_names)} frame names given for {self.frame_count} frames"
            )
        if self.frame_rate is not None and not (
            np.isfinite(self.frame_rate) and self.frame_rate > 0
        ):
            raise InputError(f"frame rate must be a positive number, got {self.frame_rate}")
        if self.time_codes is not None:
            self.time_codes = checked_time_codes(self.time_codes, self.frame_count)
        self.meters_per_unit = checked_meters_per_unit(self.meters_per_unit)
        self.up_axis = checked_up_axis(self.up_axis)
        self.attributes, self.face_sets = list(self.attributes), list(self.face_sets)
        self.fields = list(self.fields)
        check_attached(
            self.attributes,
            self.face_sets,
            self.fields,
            self.frame_count,
            self.vertex_count,
            self.faces,
        )

    @property
    def attached(self) -> bool:
        """Whether the sequence carries attributes, face sets or fields."""
        return bool(self.attributes or self.face_sets or self.fields)

    def attribute_named(self, name: str) -> Attribute:
        """The attribute named ``name`` (KeyError if none)."""
        for attribute in self.attributes:
            if attribute.name == name:
                return attribute
        raise KeyError(name)

    def field_named(self, name: str) -> Field:
        """The field named ``name`` (KeyError if none)."""
        for item in self.fields:
            if item.name == name:
                return item
        raise KeyError(name)

    @property
    def frame_count(self) -> int:
        """F, the number of frames."""
        return int(self.vertices.shape[0])

    @property
    def vertex_count(self) -> int:
        """K, the number of vertices of every frame."""
        return int(self.vertices.shape[1])

    def compact_vertices(self) -> np.ndarray:
        """The positions as float32 where that is exact (half the bytes, the same numbers),
        else as they are (float64): what a format that can store either should write."""
        with np.errstate(over="ignore"):  # a value beyond float32 becomes inf: not equal
            single = self.vertices.astype(np.float32)
        return single if np.array_equal(single, self.vertices) else self.vertices

    def codes(self) -> np.ndarray:
        """Each frame's time code: :attr:`time_codes`, or 0, 1, 2... when none are known."""
        if self.time_codes is not None:
            return self.time_codes.copy()
        return np.arange(self.frame_count, dtype=np.float64)

    def seconds(self) -> np.ndarray:
        """Each frame's time in seconds: its time code over the frame rate
        (:data:`DEFAULT_FRAME_RATE` when the sequence has none)."""
        return self.codes() / (self.frame_rate or DEFAULT_FRAME_RATE)

    def triangles(self) -> np.ndarray:
        """The faces as triangles, (T, 3): polygons are split into fans from their first corner."""
        if self.faces.shape[1] == 3:
            return self.faces.copy()
        parts = []
        for corner in range(1, self.faces.shape[1] - 1):
            tri = self.faces[:, [0, corner, corner + 1]]
            parts.append(tri[tri[:, 2] >= 0])
        return np.concatenate(parts) if parts else np.zeros((0, 3), dtype=np.int64)

    def __repr__(self) -> str:
        return (
            f"MeshSequence(frames={self.frame_count}, vertices={self.vertex_count}, "
            f"faces={self.faces.shape[0]})"
        )


def float32_vertices(
    seq: MeshSequence, path: str | os.PathLike[str], dtype: str = "<f4"
) -> np.ndarray:
    """The positions as float32 (of byte order ``dtype``), as most formats store them; a
    position beyond float32's range, which would become infinite, is an InputError naming
    the frame and vertex."""
    with np.errstate(over="ignore"):
        values = seq.vertices.astype(dtype)
    bad = ~np.isfinite(values)
    if bad.any():
        frame, vertex, _ = (int(i) for i in np.argwhere(bad)[0])
        raise InputError(
            f"vertex {vertex} is beyond the range of float32, in which the file stores positions",
            path=path,
            frame=frame,
        )
    return values


def float32_seconds(seq: MeshSequence, path: str | os.PathLike[str]) -> np.ndarray:
    """Each frame's time in seconds as float32, as glTF and MDD store it; an InputError naming
    the frame where float32 cannot hold a time, or rounds two frames onto the same time (time
    codes far from 0: float32 has 24 bits)."""
    return float32_times(seq.seconds(), path)


def float32_times(seconds: np.ndarray, path: str | os.PathLike[str]) -> np.ndarray:
    """``seconds`` (each frame's time, increasing) as float32; an InputError naming the frame
    (and ``path``, the file to be written) where float32 cannot hold a time or rounds two
    frames onto the same one."""
    with np.errstate(over="ignore"):
        times = np.asarray(seconds, dtype=np.float64).astype(np.float32)
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        raise InputError(
            "its time is beyond the range of float32, in which the file stores times",
            path=path,
            frame=int(bad[0]),
        )
    same = np.flatnonzero(np.diff(times) <= 0)
    if same.size:
        frame = int(same[0]) + 1
        raise InputError(
            f"frames {frame - 1} and {frame} fall on the same float32 time, {times[frame]} s, "
            "in which the file stores times: time codes this far from 0 need more precision",
            path=path,
            frame=frame,
        )
    return times


def checked_time_codes(values: np.ndarray, frame_count: int) -> np.ndarray:
    """Time codes as float64, one per frame, finite and strictly increasing."""
    codes = np.asarray(values)
    if codes.shape != (frame_count,) or not np.issubdtype(codes.dtype, np.number):
        raise InputError(
            f"time codes must be {frame_count} numbers, one per frame, got dtype "
            f"{codes.dtype} shape {codes.shape}"
        )
    codes = np.array(codes, dtype=np.float64)
    bad = np.flatnonzero(~np.isfinite(codes))
    if bad.size:
        raise InputError(f"time code {codes[bad[0]]} is not finite", frame=int(bad[0]))
    steps = np.flatnonzero(np.diff(codes) <= 0)
    if steps.size:
        frame = int(steps[0]) + 1
        raise InputError(
            f"time codes must increase: {codes[frame]} follows {codes[frame - 1]}", frame=frame
        )
    return codes


def checked_meters_per_unit(value: object) -> float | None:
    """A length unit in metres: ``None``, or a positive finite number (as a float)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
        raise InputError(f"meters per unit must be a positive number, got {value!r}")
    unit = float(value)
    if not (np.isfinite(unit) and unit > 0):
        raise InputError(f"meters per unit must be a positive number, got {unit}")
    return unit


def checked_up_axis(value: object) -> str | None:
    """An up axis: ``None``, or ``"Y"`` or ``"Z"`` (either case)."""
    if value is None:
        return None
    axis = value.upper() if isinstance(value, str) else value
    if axis not in UP_AXES:
        raise InputError(f"the up axis must be Y or Z, got {value!r}")
    return str(axis)
