"""What the Blender add-on does to arrays and files, kept apart from ``bpy`` so that it is tested
anywhere: which frame of a file a scene frame shows and the scene frames a file spans (within
Blender's), the scene's frame rate, the decoder's limits inside Blender, the point cache a baked
import writes, and the frames of an export gathered with their topology checked."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..decoder import Decoder
from ..errors import InputError
from ..format.limits import Limits
from ..io.common.polygons import polygons_from_faces
from ..io.pointcache.pc2 import HEADER, SIGNATURE, VERSION
from ..model.attributes import Attribute, FaceSet
from ..model.sequence import MeshSequence
from ..system.atomic import atomic_output
from .layers import split_animated

#: Blender's frame numbers run from -MAX_FRAME to MAX_FRAME (MINAFRAME and MAXFRAME in its
#: source); the object keeps its first frame in a 32-bit custom property.
MAX_FRAME = 1_048_574
#: The scene frames a baked import writes unless it is asked for more (Max Bake Frames): a
#: file of a few time codes may span any number of frames, each a full frame of the cache.
BAKE_FRAMES = 10_000
#: The scene frames a bake decides at a time (which file frame each shows).
_BAKE_CHUNK = 4096
#: The decoder's limits inside Blender, for an import and for playback: what a mesh object in
#: Blender holds and plays (8 Mi vertices, 16 Mi faces, Blender's frame count), a header of at
#: most 1 MiB (a 16 MiB header of empty maps costs about 1.3 GiB to parse), sections of at most
#: 512 MiB decompressed and 32 Mi factor values (256 MiB): what a small crafted file can make
#: Blender allocate is bounded by these, a fraction of the defaults' GiBs, which suit files of
#: a few GiB of positions on the command line.
BLENDER_LIMITS = Limits(
    max_header_bytes=1 << 20,
    max_vertices=1 << 23,
    max_frames=1 << 20,
    max_positions=1 << 28,
    max_faces=1 << 24,
    max_face_width=64,
    max_sections=1 << 14,
    max_segments=1 << 12,
    max_section_bytes=1 << 29,
    max_factor_values=1 << 25,
)


def loop_arrays(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The arrays a Blender mesh is built from for the face table ``faces``, in its order: each
    face's first loop (``loop_start``) and every loop's vertex, face by face, both int32."""
    counts, corners = polygons_from_faces(faces)
    starts = np.zeros(counts.size, dtype=np.int32)
    np.cumsum(counts[:-1], out=starts[1:])
    return starts, corners


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


def scene_range(
    first: float, frame_count: int, time_codes: Sequence[float] | None
) -> tuple[int, int]:
    """The first and last scene frames of a file whose frame 0 is at ``first`` (the import's
    First Frame, or the file's first time code): an InputError when they are beyond Blender's
    frames (:data:`MAX_FRAME`), checked before anything is made: a first time code of 2**31
    overflowed the object's 32-bit property half-way through an import."""
    span = frame_count - 1 if time_codes is None else time_codes[-1] - time_codes[0]
    ends = (first, first + span)
    if all(math.isfinite(end) and abs(end) <= MAX_FRAME + 1 for end in ends):
        start = round(first)
        last = start + scene_frames(start, frame_count, time_codes) - 1
        if start >= -MAX_FRAME and last <= MAX_FRAME:
            return start, last
    raise InputError(
        f"its frames would lie at scene frames {ends[0]:.17g} to {ends[1]:.17g}, beyond "
        f"Blender's frames ({-MAX_FRAME} to {MAX_FRAME}): import it with Use File Time "
        "Codes off and a First Frame within them"
    )


def bake_span(decoder: Decoder, first: int, max_frames: int = BAKE_FRAMES) -> int:
    """The scene frames a bake of ``decoder``'s file from ``first`` writes; an InputError,
    naming the span and the limit, beyond ``max_frames``."""
    count = decoder.frame_count
    span = scene_frames(first, count, decoder.info.time_codes)
    if span > max_frames:
        raise InputError(
            f"its {count} frames span {span} scene frames, beyond the {max_frames} a bake "
            f"writes (a cache of {span * decoder.info.vertices * 12} bytes): raise Max Bake "
            "Frames to bake them all, or play the file instead",
            path=decoder.path,
        )
    return span


def bake_pc2(
    decoder: Decoder,
    cache: Path,
    first: int,
    *,
    overwrite: bool = False,
    max_frames: int = BAKE_FRAMES,
) -> int:
    """Write ``cache``, a ``.pc2`` of one sample per scene frame from ``first`` (the frame the
    add-on's playback shows there: a .pc2 is evenly spaced, so uneven time codes become held
    frames), atomically; returns the number of frames written. The frames a file spans are
    counted first and refused beyond ``max_frames``, naming both; then each file frame is
    decoded once and written as often as it is held, so that memory holds one frame whatever
    the span (decoding every frame shown first took 1.08 GB for a 194 MB cache)."""
    codes, count = decoder.info.time_codes, decoder.frame_count
    span = bake_span(decoder, first, max_frames)
    header = HEADER.pack(SIGNATURE, VERSION, decoder.info.vertices, 0.0, 1.0, span)
    with atomic_output(cache, overwrite=overwrite) as stream:
        stream.write(header)
        decoded, data = -1, b""
        for start in range(0, span, _BAKE_CHUNK):
            scene = first + np.arange(start, min(start + _BAKE_CHUNK, span))
            for frame in file_frames(scene, first, count, codes).tolist():
                if frame != decoded:
                    with np.errstate(over="ignore"):
                        positions = decoder.frame(frame).astype("<f4")
                    if not np.isfinite(positions).all():
                        raise InputError(
                            f"frame {frame} has a position beyond float32, which a .pc2 holds",
                            path=decoder.path,
                            frame=frame,
                        )
                    decoded, data = frame, positions.tobytes()
                stream.write(data)
    return span


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
    naming the scene frame and the object). Beside them, the first frame's attributes and
    face sets, and by name the values at every frame of the attributes that may be animated
    (:attr:`animated`): those that change become fields."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.frames: list[np.ndarray] = []
        self.faces: np.ndarray | None = None
        self._first_frame = 0
        self.attributes: list[Attribute] = []
        self.face_sets: list[FaceSet] = []
        self.animated: dict[str, list[np.ndarray]] = {}
        #: What the export cannot keep (edge attributes, strings...), named.
        self.dropped: list[str] = []

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
        with the unit and up axis of the object's space, the attributes and face sets, and the
        attributes whose values changed over the frames as fields."""
        if self.faces is None:
            raise InputError(f"object {self.name!r}: no frame to export")
        codes = first_frame + np.arange(len(self.frames), dtype=np.float64)
        static, fields = split_animated(self.attributes, self.animated)
        return MeshSequence(
            np.stack(self.frames),
            self.faces,
            frame_rate=frame_rate,
            time_codes=codes,
            meters_per_unit=meters_per_unit,
            up_axis=up_axis,
            attributes=static,
            face_sets=self.face_sets,
            fields=fields,
        )
