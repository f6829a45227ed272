"""The PC2 point cache (``.pc2``): 3ds Max's Point Cache 2, read and written by Blender's
Mesh Cache modifier, Maya and Houdini. Positions only, in plain numpy.

Layout, all little-endian (as in Blender's ``MOD_meshcache_pc2.cc``)::

    offset  size  field
    0       12    signature   b"POINTCACHE2\\0"
    12      4     version     int32, 1
    16      4     numPoints   int32, K
    20      4     startFrame  float32
    24      4     sampleRate  float32, frames between two samples
    28      4     numSamples  int32, F
    32      12FK  positions   float32 x, y, z of K points, frame after frame

Sample i is at frame ``startFrame + i * sampleRate``: these are the sequence's time codes (PC2 has
no frames per second, so the frame rate stays unknown). Writing takes the start frame and the sample
rate from the time codes (0, 1, 2... when the sequence has none), so they survive a PC2 to PC2 round
trip; time codes that are not evenly spaced cannot be written as PC2. The faces come from ``--faces
MESH`` (:func:`~tuckercodec.io.pointcache.cache_faces`); without it the points are a point sequence.
Frames are read by offset, a range at a time (:class:`Pc2Frames`).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ...errors import InputError
from ...model.sequence import MeshSequence
from ...system.atomic import atomic_output
from ..registry import ReadOptions, WriteOptions
from . import POINT_BYTES, CacheFrames, check_counts, check_size, float32_positions

SIGNATURE = b"POINTCACHE2\0"
VERSION = 1
HEADER = struct.Struct("<12siiffi")  # signature, version, numPoints, start, sampleRate, samples
#: How far time codes may stray from an even spacing (as a fraction of the step) and still be
#: written as a start frame and a sample rate, which are float32 anyway.
_SPACING_TOLERANCE = 1e-6


class Pc2Frames(CacheFrames):
    """The frames of a PC2 point cache, read by offset: positions, time codes ``startFrame +
    i * sampleRate``, and the faces of ``options.faces`` (none without it).

    The header's counts must account for exactly the file's size, checked before anything
    is allocated; the error says whether the file is truncated or has trailing bytes.
    """

    _what = "a PC2 point cache"

    def __init__(self, path: Path, options: ReadOptions):
        stream, raw, file_size = self._open_header(path, HEADER.size)
        stream.close()
        signature, version, points, start, step, frames = HEADER.unpack(raw)
        if signature != SIGNATURE:
            raise InputError(
                f"is not a PC2 point cache: it starts with {signature!r}, not {SIGNATURE!r}",
                path=path,
            )
        if version != VERSION:
            raise InputError(
                f"is PC2 version {version}; only version {VERSION} is defined", path=path
            )
        check_counts(frames, points, path)
        check_size(
            HEADER.size + frames * points * POINT_BYTES,
            file_size,
            f"a {HEADER.size}-byte header and {frames} samples of {points} points",
            path,
        )
        codes = _time_codes(start, step, frames, path)
        self._positions_at(path, options, HEADER.size, "<f4", (frames, points), (None, codes))


def _time_codes(start: float, step: float, frames: int, path: Path) -> np.ndarray:
    """Each sample's frame number, ``start + i * step``, from the header's float32 fields."""
    if not np.isfinite(start):
        raise InputError(f"its startFrame is {start}, not a number", path=path)
    if frames > 1 and not (np.isfinite(step) and step > 0):
        raise InputError(
            f"its sampleRate is {step}: the samples' frames must increase, so it must be a "
            "positive number",
            path=path,
        )
    if frames == 1:  # a single sample's sampleRate is never used, so it may be anything
        return np.array([start], dtype=np.float64)
    return start + np.arange(frames, dtype=np.float64) * step


def write_pc2(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence's positions as a PC2 point cache, atomically.

    startFrame is the first time code and sampleRate the step between two (0 and 1 for a
    sequence without time codes; 1 for a single frame). The faces, frame names and frame
    rate are not kept: PC2 holds positions only.
    """
    start, step = _start_and_step(seq.codes(), path)
    positions = float32_positions(seq, "<f4", path)
    header = HEADER.pack(SIGNATURE, VERSION, seq.vertex_count, start, step, seq.frame_count)
    with atomic_output(path, overwrite=options.overwrite) as stream:
        stream.write(header)
        stream.write(positions.tobytes())


def _start_and_step(codes: np.ndarray, path: Path) -> tuple[float, float]:
    """startFrame and sampleRate for time codes that must be evenly spaced."""
    start = float(codes[0])
    step = float(codes[1] - codes[0]) if len(codes) > 1 else 1.0
    expected = start + np.arange(len(codes), dtype=np.float64) * step
    off = np.flatnonzero(np.abs(codes - expected) > _SPACING_TOLERANCE * step)
    if off.size:
        frame = int(off[0])
        raise InputError(
            f"time code {codes[frame]} is not {expected[frame]}: {path.name} (PC2) can only "
            "hold evenly spaced frames (a startFrame and a sampleRate); write .npz or .usd to "
            "keep these time codes",
            frame=frame,
        )
    with np.errstate(over="ignore"):
        fields = np.array([start, step], dtype=np.float32)
    if not np.isfinite(fields).all():
        raise InputError(
            f"time codes from {start} in steps of {step} are beyond the range of the float32 "
            f"startFrame and sampleRate of {path.name}"
        )
    return float(fields[0]), float(fields[1])
