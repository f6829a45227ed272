"""Sources for tests/test_io_isolated_frames.py, each a FrameSource that does one thing a C++
library may do while serving reads in a child: crash at a frame, hang, refuse a frame, fail
for a bug. The serving child of tuckercodec.io.isolation imports this module by name
(tests.support.streaming_hooks) from the caller's import path, where pytest puts the
repository's root."""

from __future__ import annotations

import ctypes
import os
import time
from pathlib import Path

import numpy as np

from tuckercodec import InputError
from tuckercodec.io.isolation import note
from tuckercodec.io.registry import ReadOptions
from tuckercodec.model.sources import FrameSource

FRAMES, VERTICES = 10, 5


def pid_file(path: Path) -> Path:
    """Where a source leaves the id of the process that opened it."""
    return Path(f"{path}.pid")


def expected(start: int, stop: int) -> np.ndarray:
    """What :class:`Frames` reads: each frame's positions are its number, plus the vertex's
    tenth."""
    frames = np.arange(start, stop, dtype=np.float64)[:, None, None]
    return frames + np.arange(VERTICES)[None, :, None] / 10 + np.zeros((1, 1, 3))


class Frames(FrameSource):
    """A healthy source of 10 frames of 5 vertices, with faces, rate and time codes."""

    def __init__(self, path: Path, options: ReadOptions):
        pid_file(path).write_text(str(os.getpid()))
        faces = [[0, 1, 2, 3], [2, 3, 4, -1]]
        codes = np.arange(FRAMES) * 2.0 + 1
        names = [f"f{n}" for n in range(FRAMES)]
        self._describe(path, FRAMES, VERTICES, faces, names, 30.0, codes)

    def _read(self, start: int, stop: int) -> np.ndarray:
        for frame in range(start, stop):
            note("object /hook", frame)
            self._frame(frame)
        return expected(start, stop)

    def _frame(self, frame: int) -> None:
        """What reading ``frame`` does beside returning it."""


class CrashAtSeven(Frames):
    def _frame(self, frame: int) -> None:
        if frame == 7:
            ctypes.string_at(0)


class RefuseFour(Frames):
    def _frame(self, frame: int) -> None:
        if frame == 4:
            raise InputError("object /hook: frame 4 is broken", path=self.path, frame=4)


class HangAtEight(Frames):
    def _frame(self, frame: int) -> None:
        if frame == 8:
            time.sleep(120)


class BugAtTwo(Frames):
    def _frame(self, frame: int) -> None:
        if frame == 2:
            raise ZeroDivisionError("a mistake in the reader")


class RefuseToOpen(Frames):
    def __init__(self, path: Path, options: ReadOptions):
        pid_file(path).write_text(str(os.getpid()))
        raise InputError("object /hook: not a mesh", path=path)
