"""Filling a size budget: the smallest D whose size fits, found with few sizes measured.

A size target's search (:func:`.search.search_bpfv`) sizes files at several D; each size costs
a pack, so D is found by secant steps in ln D (:func:`fill`), or, where the size is erratic in
D (zstd's strongest levels), by aiming at a line above the sizes measured (:func:`fill_erratic`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

import numpy as np

Item = TypeVar("Item")


@dataclass
class Filled(Generic[Item]):
    """A D whose size fits: the size, what was sized, and the size's slope in ln D there."""

    step: float
    size: float
    item: Item
    slope: float


def fill(
    size_of: Callable[[float], tuple[float, Item]],
    step: float,
    slope: float,
    window: tuple[float, float],
    limits: tuple[float, float],
    tries: int,
) -> tuple[Filled[Item] | None, int]:
    """The smallest D found whose size is at most ``window[1]``, and the sizes measured.

    Secant steps in ln D aimed at the window's middle: from ``slope`` (bytes per unit of ln D)
    until two sizes measure it, then between the nearest sizes either side of the window once
    both are known. Stops at the first size within the window, after ``tries`` sizes, or when
    the size stops being monotone at the resolution reached. D stays within ``limits``; a size
    of infinity means D is too small for the format. ``None`` if no D tried fits.
    """
    least, most = window
    aim = 0.5 * (least + most)
    low_limit, high_limit = (math.log(x) for x in limits)
    prior = slope
    points: list[tuple[float, float]] = []
    fits: tuple[float, float, Item] | None = None  # ln D, size, item: the smallest D that fits
    over: tuple[float, float] | None = None  # (ln D, size): the largest D found too large
    at = min(max(math.log(step), low_limit), high_limit)
    tried = 0
    while tried < tries:
        tried += 1
        size, item = size_of(math.exp(at))
        if math.isfinite(size):
            if points and at != points[-1][0]:
                measured = (size - points[-1][1]) / (at - points[-1][0])
                if measured < 0:
                    slope = measured
            points.append((at, size))
        if size <= most:
            if fits is None or at < fits[0]:
                fits = (at, size, item)
            if size >= least:
                break
        elif over is None or at > over[0]:
            over = (at, size)
        if fits is not None and over is not None:
            low, high = over[0], fits[0]
            if high - low < 1e-6:  # not monotone here: keep the smallest D that fits
                break
            if math.isfinite(over[1]):
                share = (over[1] - aim) / (over[1] - fits[1])
                at = low + min(0.9, max(0.1, share)) * (high - low)
            else:
                at = 0.5 * (low + high)
        else:
            move = (aim - size) / slope if math.isfinite(size) else 2.0
            moved = min(max(at + min(3.0, max(-3.0, move)), low_limit), high_limit)
            if moved == at:  # against a limit
                break
            at = moved
    if fits is None:
        return None, tried
    return Filled(math.exp(fits[0]), fits[1], fits[2], _slope(points, fits[0], prior)), tried


def _slope(points: list[tuple[float, float]], at: float, prior: float) -> float:
    """The size's slope in ln D near ``at``: the least-squares line's through the points
    (ln D, size) within 0.7 of it, or else through all of them, when they span at least 0.05
    (sizes a hair apart in D differ by noise alone), fitted again without the points more
    than 3 % below the line (lucky ones), and kept within a factor 3 of ``prior``."""
    for chosen in (_near(points, at), points):
        xs = np.array([x for x, _ in chosen])
        ys = np.array([y for _, y in chosen])
        if len(chosen) < 2 or np.ptp(xs) < 0.05:
            continue
        line = np.polyfit(xs, ys, 1)
        kept = ys >= 0.97 * np.polyval(line, xs)
        if kept.sum() >= 2 and np.ptp(xs[kept]) >= 0.05:
            line = np.polyfit(xs[kept], ys[kept], 1)
        fitted = float(line[0])
        return prior if fitted >= 0 else min(max(fitted, 3.0 * prior), prior / 3.0)
    return prior


def _near(points: list[tuple[float, float]], at: float) -> list[tuple[float, float]]:
    return [point for point in points if abs(point[0] - at) <= 0.7]


def fill_erratic(
    size_of: Callable[[float], tuple[float, Item]],
    model: tuple[float, float, float],
    window: tuple[float, float],
    limits: tuple[float, float],
    tries: int,
) -> tuple[Filled[Item] | None, int]:
    """As :func:`fill`, for a size that is erratic in D: the smallest D found whose size is
    at most ``window[1]`` (the smallest error: a lucky D may fit below the window), stopping
    at the first size within the window.

    zstd's strongest levels jump by several per cent between nearly equal inputs (samba's U1
    at 4 bpfv packs at level 19 to about 0.92 of its level-3 size, or, for about one D in
    two, to 0.86), so each D is aimed at a line above the sizes measured: the slope of their
    least-squares line once they span enough of ln D (until then ``model``'s, the trial
    sizes' (D, size, slope per unit of ln D)), through the highest of them. A lucky D, which
    packs smaller, then leaves the file short of the window, and the next D, aimed at the same
    line, draws again (a D already measured is moved by a hair).
    """
    least, most = window
    aim = 0.5 * (least + most)
    low, high = (math.log(x) for x in limits)
    prior = model[2]
    points: list[tuple[float, float]] = []
    fits: Filled[Item] | None = None
    at = math.log(model[0]) + (aim - model[1]) / prior
    for tried in range(1, tries + 1):
        at = min(max(at, low), high)
        while any(abs(at - other) < 1e-4 for other, _ in points):
            at -= 2e-3
        size, item = size_of(math.exp(at))
        if size <= most:
            if fits is None or at < math.log(fits.step):
                fits = Filled(math.exp(at), size, item, prior)
            if size >= least:
                return fits, tried
        if not math.isfinite(size):  # D too small for the format
            at += 1.0
            continue
        points.append((at, size))
        slope = _slope(points, at, prior)
        top = max(y - slope * x for x, y in _near(points, at))
        at = (aim - top) / slope
    return fits, tries
