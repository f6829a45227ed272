"""Alembic's time: sample times to and from time codes and a frame rate (the conventions
are :mod:`.alembic`'s docstring's). Apart from :mod:`.alembic` because the reader and the
writer share it and it needs no archive open, only the time sampling alembic3d gives."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import InputError

#: The archive metadata key that holds the exact frame rate (the DCC FPS key keeps 6 decimals).
RATE_KEY = "tuckercodec_frame_rate"
#: The mesh's user property that holds the exact time codes, written only where no sample
#: times give them back exactly (time x rate cannot reach every float).
CODES_KEY = "tuckercodec_time_codes"


def check_times(sampling: Any, times: np.ndarray, where: str, path: Path) -> None:
    """Refuse sample times that do not increase, or that do not select their own sample."""
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        frame = int(bad[0])
        raise InputError(f"{where}: sample {frame} has the time {times[frame]}", path=path)
    steps = np.flatnonzero(np.diff(times) <= 0)
    if steps.size:
        frame = int(steps[0]) + 1
        raise InputError(
            f"{where}: the time of sample {frame} ({times[frame]} s) does not follow sample "
            f"{frame - 1}'s ({times[frame - 1]} s)",
            path=path,
            frame=frame,
        )
    for frame, time in enumerate(times.tolist()):
        if sampling.getNearIndex(time, len(times)) != frame:  # a read by time would miss it
            raise InputError(
                f"{where}: the time of sample {frame} ({time} s) selects another sample",
                path=path,
                frame=frame,
            )


def frame_rate(abc: SimpleNamespace, archive: Any, sampling: Any) -> float | None:
    """Frames per second: ours, the DCC's, or the uniform sampling's (module docstring)."""
    metadata = archive.getTop().getMetaData()
    for key, tolerance in ((RATE_KEY, 0.0), ("_ai_DCC_FPS", 5e-7)):  # DCC FPS: 6 decimals
        try:
            rate = float(metadata.get(key))
        except (TypeError, ValueError):
            continue
        if math.isfinite(rate) and rate > 0:
            return _usual_rate(rate, tolerance)
    kind = sampling.getTimeSamplingType()
    if not kind.isUniform() or not kind.getTimePerCycle() > 0:
        return None
    rate = 1.0 / kind.getTimePerCycle()
    return _usual_rate(rate, 1e-9 * rate) if math.isfinite(rate) else None


def _usual_rate(rate: float, tolerance: float) -> float:
    """A whole or NTSC (n*1000/1001) rate within ``tolerance`` of ``rate``, else ``rate``."""
    for candidate in (float(round(rate)), round(rate * 1.001) * 1000 / 1001):
        if candidate > 0 and abs(rate - candidate) <= tolerance:
            return candidate
    return rate


def kept_codes(abc: SimpleNamespace, schema: Any, codes: np.ndarray) -> np.ndarray:
    """The exact time codes tuckercodec kept beside the times (:data:`CODES_KEY`), where they
    agree with the times, else ``codes``."""
    user = schema.getUserProperties()
    header = user.getPropertyHeader(CODES_KEY) if user.valid() else None
    if header is None or not abc.Abc.IDoubleArrayProperty.matches(header):
        return codes
    kept = np.asarray(abc.Abc.IDoubleArrayProperty(user, CODES_KEY).getValue(), dtype=np.float64)
    if kept.shape != codes.shape or not np.all(
        np.abs(kept - codes) <= 1e-6 * np.maximum(1.0, np.abs(codes))
    ):
        return codes  # stale or foreign: the times are what the file says
    return kept


def codes_from_times(times: np.ndarray, rate: float) -> np.ndarray:
    """Time codes of sample times: time x rate, a value within a few units in the last place
    of a multiple of 1e-6 taken as that multiple, so that frame numbers come out whole (the
    multiplication and the sampling's own arithmetic round by an ulp or two)."""
    codes = np.asarray(times, dtype=np.float64) * rate
    snapped = np.round(codes, 6)
    close = np.abs(codes - snapped) <= 16 * np.spacing(np.abs(codes))
    return np.where(close, snapped, codes)


def time_sampling(abc: SimpleNamespace, codes: np.ndarray, rate: float) -> tuple[Any, bool]:
    """A uniform time sampling if it gives back exactly these codes, else an acyclic one; and
    whether its times give back the codes exactly."""
    AbcA = abc.AbcA
    start = float(codes[0]) / rate
    step = (float(codes[1]) - float(codes[0])) / rate if len(codes) > 1 else 1.0 / rate
    # what Alembic's TimeSampling::getSampleTime computes for a uniform sampling
    uniform = start + step * np.arange(len(codes), dtype=np.float64)
    if step > 0 and np.array_equal(codes_from_times(uniform, rate), codes):
        return AbcA.TimeSampling(step, start), True
    times = codes / rate
    vector = AbcA.TimeVector()
    vector.extend(times.tolist())
    kind = AbcA.TimeSamplingType(AbcA.AcyclicFlag.kAcyclic)
    return AbcA.TimeSampling(kind, vector), np.array_equal(codes_from_times(times, rate), codes)
