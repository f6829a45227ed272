"""What the Blender add-on does to arrays, kept apart from ``bpy`` so that it is tested anywhere:
which frame of a file a scene frame shows, the scene's
frame rate, and the frames of an export gathered with their topology checked."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..model.sequence import MeshSequence


def file_frames(
    scene_frames: np.ndarray, first: int, frame_count: int, time_codes: Sequence[float] | None
) -> np.ndarray:
    """The file's frames shown at ``scene_frames`` when its frame 0 is at scene frame
    ``first``: with the file's time codes (format 1.4), frame f at ``first + code_f - code_0``
    and shown until the next one starts (a missing sample holds the one before); without them,
    frame f at ``first + f``. Held at the first and last frames outside the file's range."""
    offsets = np.asarray(scene_frames) - first
    if time_codes is None:
        shown = offsets
    else:
        codes = np.asarray(time_codes, dtype=np.float64)
        shown = np.searchsorted(codes - codes[0], offsets, side="right") - 1
    return np.clip(shown, 0, frame_count - 1).astype(np.int64)


def file_frame(
    scene_frame: int, first: int, frame_count: int, time_codes: Sequence[float] | None = None
) -> int:
    """:func:`file_frames` of one scene frame."""
    return int(file_frames(np.array([scene_frame]), first, frame_count, time_codes)[0])


def scene_frames(first: int, frame_count: int, time_codes: Sequence[float] | None) -> int:
    """The number of scene frames a file spans from ``first``: to its last time code."""
    if time_codes is None:
        return frame_count
    return math.floor(time_codes[-1] - time_codes[0]) + 1


def placement(
    meters_per_unit: float | None, up_axis: str | None, scene_meters: float
) -> tuple[float, float]:
    """The object's (x rotation in radians, uniform scale) that shows a file in Blender's Z up
    scene in metres of ``scene_meters`` (the scene's unit scale): a Y-up file is turned a
    quarter about X (Y to Z, as Blender's glTF and USD importers do), and positions in a unit
    other than the scene's are scaled into it. Unknown (None) leaves each as it is."""
    rotation = math.pi / 2 if up_axis == "Y" else 0.0
    scale = 1.0 if meters_per_unit is None else meters_per_unit / scene_meters
    return rotation, scale


def scene_rate(frame_rate: float | None) -> tuple[int, float]:
    """Blender's ``(fps, fps_base)`` for a file's frame rate (fps / fps_base is the rate):
    29.97 is (30, 1.001); None or a non-positive rate leaves Blender's default 24."""
    if frame_rate is None or not math.isfinite(frame_rate) or frame_rate <= 0:
        return 24, 1.0
    fps = max(1, round(frame_rate))
    return fps, fps / frame_rate


class ExportFrames:
    """The frames of an export, gathered one at a time with their topology checked against the
    first: every frame must have the first frame's vertices and faces (a change is refused,
    naming the scene frame and the object)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.frames: list[np.ndarray] = []
        self.faces: np.ndarray | None = None
        self._first_frame = 0

    def add(self, scene_frame: int, vertices: np.ndarray, faces: np.ndarray) -> None:
        """One frame's vertices (K x 3 values) and (M, n) faces, at ``scene_frame``."""
        vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
        if self.faces is None:
            self.faces, self._first_frame = faces, scene_frame
        elif len(vertices) != len(self.frames[0]) or not np.array_equal(faces, self.faces):
            first = self._first_frame
            raise InputError(
                f"object {self.name!r} changes topology at frame {scene_frame}: "
                f"{len(vertices)} vertices and {len(faces)} faces, where frame {first} had "
                f"{len(self.frames[0])} and {len(self.faces)}"
                + ("" if len(faces) != len(self.faces) else " (different faces)")
                + "; a .tkc keeps one topology for every frame"
            )
        self.frames.append(vertices)

    def sequence(
        self,
        frame_rate: float | None,
        first_frame: int = 0,
        meters_per_unit: float | None = None,
        up_axis: str = "Z",
    ) -> MeshSequence:
        """The gathered frames as a sequence at ``frame_rate``: their time codes the scene's
        frame numbers from ``first_frame`` (a file imported again lands on the same frames),
        with the unit and up axis of the object's space."""
        if self.faces is None:
            raise InputError(f"object {self.name!r}: no frame to export")
        codes = first_frame + np.arange(len(self.frames), dtype=np.float64)
        return MeshSequence(
            np.stack(self.frames),
            self.faces,
            frame_rate=frame_rate,
            time_codes=codes,
            meters_per_unit=meters_per_unit,
            up_axis=up_axis,
        )
