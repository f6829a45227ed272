"""Readers for tests/test_io_isolation.py that each do one thing a C++ library may do to the
process reading a file: crash, allocate without end, hang, print, raise. The reading child of
tuckercodec.io.isolation imports this module by name (tests.support.isolation_hooks) from the
caller's import path, where pytest puts the repository's root."""

from __future__ import annotations

import ctypes
import os
import time
from pathlib import Path

import numpy as np

from tuckercodec import DependencyError, InputError, MeshSequence
from tuckercodec.io.isolation import note
from tuckercodec.io.registry import ReadOptions


def pid_file(path: Path) -> Path:
    """Where a hook leaves the id of the process that runs it."""
    return Path(f"{path}.pid")


def crash(path: Path, options: ReadOptions) -> MeshSequence:
    """A real segmentation fault, as alembic3d's on a damaged archive."""
    note("object /a/aShape", 3)
    ctypes.string_at(0)
    raise AssertionError("unreachable")


def allocate(path: Path, options: ReadOptions) -> MeshSequence:
    """An allocation of what a crafted file declares: 1 GiB, which the system would give (the
    pages are never touched) but the test's cap of 0.5 GiB does not."""
    note("prim /World/big", 1)
    np.empty(1 << 30, dtype=np.uint8)
    raise AssertionError("1 GiB was allocated")


def allocate_and_wrap(path: Path, options: ReadOptions) -> MeshSequence:
    """The same, caught and raised again as an InputError, as the Alembic reader does."""
    try:
        return allocate(path, options)
    except MemoryError:
        raise InputError("prim /World/big: cannot read: MemoryError", path=path) from None


def hang(path: Path, options: ReadOptions) -> MeshSequence:
    """A read that never ends."""
    pid_file(path).write_text(str(os.getpid()))
    note("object /slow", 2)
    time.sleep(120)
    raise AssertionError("not killed")


def fail(path: Path, options: ReadOptions) -> MeshSequence:
    """The reader's own refusal, with every attribute set."""
    raise InputError(f"object {options.object_path}: broken", path=path, line=3, frame=7)


def missing(path: Path, options: ReadOptions) -> MeshSequence:
    """A library that is not installed."""
    raise DependencyError("reading Nothing files needs 'nothing': pip install 'tuckercodec[x]'")


def bug(path: Path, options: ReadOptions) -> MeshSequence:
    """A mistake in the reader, not in the file."""
    scale = 1 / len(options.given())  # no options: ZeroDivisionError
    return MeshSequence(np.zeros((1, 1, 3)) * scale, np.zeros((0, 3)))


def chatty(path: Path, options: ReadOptions) -> MeshSequence:
    """A reader whose library prints to both of the process's outputs, and succeeds."""
    os.write(1, b"a library's message on stdout\n")
    os.write(2, b"a library's message on stderr\n")
    print("and Python's print")
    faces = np.array([[0, 1, 2, 3], [1, 4, 2, -1]])
    vertices = np.random.default_rng(1).standard_normal((3, 5, 3)).astype(np.float32)
    return MeshSequence(
        vertices.astype(np.float64),
        faces,
        frame_names=["a", "b", str(os.getpid())],
        frame_rate=30000 / 1001,
        time_codes=np.array([0.5, 1 / 3 + 1, 1e9]),
    )
