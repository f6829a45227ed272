"""The MDD point cache (``.mdd``): LightWave's Motion Designer format, read and written by
Blender (Mesh Cache modifier, MDD add-on), 3ds Max, Maya and Houdini. Positions only, in plain
numpy.

Layout, all big-endian (as in Blender's ``MOD_meshcache_mdd.cc`` and its MDD add-on)::

    offset  size  field
    0       4     numFrames  int32, F
    4       4     numPoints  int32, K
    8       4F    times      float32, each frame's time in seconds
    8+4F    12FK  positions  float32 x, y, z of K points, frame after frame

Times: the sequence's frame rate is the rate that reproduces the file's float32 times exactly
from whole frame numbers, preferring the usual rates (24, 25, 30, 29.97...), and its time codes
are those frame numbers; times no such rate reproduces keep their seconds at a rate of
``1 / (median step)``. Writing stores ``float32(time_code / frame_rate)`` (24 frames per second
when the sequence has no rate, frames 0, 1, 2... when it has no time codes), so an MDD to MDD
round trip keeps the times bit for bit. Times that do not increase (some exporters write one
constant) carry no timing: the frames are read as 0, 1, 2... with no rate.

Blender's MDD exporter before 2.80 wrote a "rest frame" (a copy of the first frame) before the
frames, without counting it in numFrames: a file exactly one frame longer than its header says is
read as that layout, and the uncounted rest frame is skipped. Any other size mismatch is an error.
The faces come from ``--faces MESH`` (:func:`~tuckercodec.io.pointcache.cache_faces`). Frames are
read by offset, a range at a time (:class:`MddFrames`).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ...errors import InputError
from ...model.sequence import DEFAULT_FRAME_RATE, MeshSequence, float32_seconds
from ...system.atomic import atomic_output
from ..registry import ReadOptions, WriteOptions
from . import POINT_BYTES, CacheFrames, check_counts, check_size, float32_positions, read_floats

HEADER = struct.Struct(">ii")  # numFrames, numPoints
#: Frame rates tried first when working out the rate of a file's times: film, PAL, NTSC (and
#: their NTSC-style 1000/1001 variants), and their multiples and fractions.
COMMON_RATES = (
    24.0,
    25.0,
    30.0,
    24000 / 1001,
    30000 / 1001,
    48.0,
    50.0,
    60.0,
    60000 / 1001,
    12.0,
    15.0,
    100.0,
    120.0,
    240.0,
)


class MddFrames(CacheFrames):
    """The frames of an MDD point cache, read by offset: positions, the frame rate and time
    codes its times imply (see the module docstring), and the faces of ``options.faces``.

    The header's counts must account for exactly the file's size (or one uncounted rest frame
    more), checked before anything is allocated.
    """

    _what = "an MDD point cache"

    def __init__(self, path: Path, options: ReadOptions):
        stream, raw, file_size = self._open_header(path, HEADER.size)
        with stream:
            frames, points = HEADER.unpack(raw)
            check_counts(frames, points, path)
            declared = HEADER.size + 4 * frames + frames * points * POINT_BYTES
            rest_frame = file_size == declared + points * POINT_BYTES
            if not rest_frame:
                check_size(
                    declared,
                    file_size,
                    f"an 8-byte header, {frames} times and {frames} frames of {points} points",
                    path,
                )
            times = read_floats(stream, frames, ">f4", path)
        # Blender's old exporter: an uncounted copy of the first frame before the frames
        offset = HEADER.size + 4 * frames + (points * POINT_BYTES if rest_frame else 0)
        timing = frame_timing(times, path)
        self._positions_at(path, options, offset, ">f4", (frames, points), timing)


def frame_timing(times: np.ndarray, path: Path) -> tuple[float | None, np.ndarray | None]:
    """The frame rate and time codes that reproduce the float32 ``times`` (seconds) exactly;
    ``(None, None)`` for times that do not increase."""
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        raise InputError(f"its time is {times[bad[0]]}, not a number", path=path, frame=int(bad[0]))
    if len(times) == 1:  # no step to find a rate from: keep the seconds at the default rate
        return None, times * DEFAULT_FRAME_RATE
    steps = np.diff(times)
    if not (steps > 0).all():
        return None, None
    step = float(np.median(steps))
    with np.errstate(all="ignore"):  # a crafted step (1e-45 s) makes a rate beyond float64
        derived = float(f"{np.float64(1) / step:.6g}")  # the typical step's rate, 6 digits
        near = [rate for rate in COMMON_RATES if abs(rate * step - 1) < 1e-3]
        rates = [*near, derived, *COMMON_RATES] if np.isfinite(derived) else list(COMMON_RATES)
        for rate in rates:
            codes = np.rint(times * rate)
            if _reproduces(codes, rate, times):
                return rate, codes
        codes = times * derived  # frames that are not whole: the seconds are kept all the same
        if np.isfinite(derived) and _reproduces(codes, derived, times):
            return derived, codes
    return 1.0, times.copy()  # time codes in seconds, one per second: always exact


def _reproduces(codes: np.ndarray, rate: float, times: np.ndarray) -> bool:
    """Whether writing ``codes`` at ``rate`` gives back the float32 ``times`` bit for bit."""
    if not (np.diff(codes) > 0).all():
        return False
    written = (codes / rate).astype(">f4")
    return bool(np.array_equal(written.view(np.uint32), times.astype(">f4").view(np.uint32)))


def write_mdd(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence's positions and times as an MDD point cache, atomically.

    Each frame's time is ``float32(time_code / frame_rate)`` seconds (frames 0, 1, 2... and
    24 frames per second where the sequence has no time codes or rate). The faces and frame
    names are not kept: MDD holds positions only.
    """
    positions = float32_positions(seq, ">f4", path)
    times = float32_seconds(seq, path).astype(">f4")
    with atomic_output(path, overwrite=options.overwrite) as stream:
        stream.write(HEADER.pack(seq.frame_count, seq.vertex_count))
        stream.write(times.tobytes())
        stream.write(positions.tobytes())
