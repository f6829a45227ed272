"""A glTF animation's frame rate, time codes and frame names, from the times its frames are
sampled at and the tuckercodec writer's record (the rules: :mod:`.reader`'s docstring)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...model.sequence import DEFAULT_FRAME_RATE


def timing(
    times: np.ndarray, animated: bool, extras: dict[str, Any], fps: float | None
) -> tuple[float | None, np.ndarray | None, list[str]]:
    """The frame rate, time codes and names of frames at ``times`` (see the module
    docstring)."""
    if not animated:
        static = dict(extras)
        static.pop("time_codes", None)  # one frame at time 0 whatever its time code
        recorded = _recorded(static, times)
        return recorded[0] if recorded else None, None, recorded[2] if recorded else []
    if fps is not None:
        return fps, _codes(times * fps), []
    recorded = _recorded(extras, times)
    if recorded is not None:
        return recorded
    if len(times) > 1:
        steps = np.diff(times)
        step = float(np.median(steps))
        if np.allclose(steps, step, rtol=1e-4, atol=1e-7):
            rate = 1.0 / step
            if abs(rate - round(rate)) < 1e-4 * rate:
                rate = float(round(rate))
            return rate, _codes(times * rate), []
    return DEFAULT_FRAME_RATE, _codes(times * DEFAULT_FRAME_RATE), []


def _recorded(
    extras: dict[str, Any], times: np.ndarray
) -> tuple[float | None, np.ndarray | None, list[str]] | None:
    """The writer's record of rate, time codes and names, if the keyframes are its times."""
    if "frame_rate" not in extras:
        return None
    rate, codes, names = extras["frame_rate"], extras.get("time_codes"), extras.get("frame_names")
    if rate is not None and not (
        isinstance(rate, (int, float)) and not isinstance(rate, bool) and rate > 0
    ):
        return None
    recorded = np.arange(len(times), dtype=np.float64)
    if codes is not None:
        if not isinstance(codes, list) or len(codes) != len(times):
            return None
        if not all(isinstance(c, (int, float)) and not isinstance(c, bool) for c in codes):
            return None
        recorded = np.array(codes, dtype=np.float64)
    with np.errstate(all="ignore"):
        seconds = (recorded / (rate or DEFAULT_FRAME_RATE)).astype(np.float32)
    if not np.array_equal(seconds, times.astype(np.float32)):
        return None
    if not (isinstance(names, list) and len(names) == len(times)):
        names = []
    return (
        None if rate is None else float(rate),
        None if codes is None else recorded,
        [str(name) for name in names],
    )


def _codes(codes: np.ndarray) -> np.ndarray | None:
    """Time codes, rounded to whole frames where within float32 noise of them; ``None`` when
    they are 0, 1, 2..."""
    whole = np.round(codes)
    codes = np.where(np.abs(codes - whole) < 1e-4, whole, codes)
    if np.array_equal(codes, np.arange(len(codes))):
        return None
    return codes
