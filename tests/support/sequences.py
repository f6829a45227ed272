"""Sequences for the tests: synthetic animations, and the real sequences of ../shared/data
when present (a test that needs an absent one is skipped, saying why)."""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import tuckercodec
from tuckercodec import EncodeResult, MeshSequence
from tuckercodec.io.samples import sheet_triangles, wave_sheet

#: ../shared/data beside the repository, or the folder TUCKERCODEC_SHARED_DATA names (a git
#: worktree elsewhere than the repository's folder).
SHARED_DATA = Path(
    os.environ.get("TUCKERCODEC_SHARED_DATA")
    or Path(__file__).resolve().parents[3] / "shared" / "data"
)


def shared_file(name: str) -> Path:
    """A file of ../shared/data, or skip the test saying why it is not there."""
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(
            f"{path} is absent: the real test sequences live in ../shared/data beside the repo"
        )
    return path


@functools.cache
def shared_sequence(name: str) -> MeshSequence:
    """A sequence of ../shared/data as :func:`tuckercodec.load_sequence` reads it (or skip),
    read once per test process: its arrays are read-only, since the tests that ask share it."""
    sequence = tuckercodec.load_sequence(shared_file(name), progress=False)
    sequence.vertices.flags.writeable = False
    sequence.faces.flags.writeable = False
    return sequence


@functools.cache
def shared_encoded(name: str) -> EncodeResult:
    """:func:`shared_sequence` encoded at KG 0.1, the default target, once per test process (or
    skip): the JavaScript decoder's, the topology's, the viewer's and the segmented encoder's
    tests of the real files all start from this one encode (samba's takes about 10 s)."""
    return tuckercodec.encode_with_report(shared_sequence(name), target_kg=0.1)


def shared_case(name: str) -> Any:
    """``name`` as the parameter of a test that starts from :func:`shared_encoded`: marked slow,
    and in the xdist group of that name, so that under pytest-xdist (``--dist loadgroup``) every
    test of one sequence runs in the worker that encoded it once."""
    return pytest.param(name, marks=[pytest.mark.slow, pytest.mark.xdist_group(name)])


def load_shared_npz(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(V, F) of a sequence in ../shared/data, or skip."""
    with np.load(shared_file(name), allow_pickle=False) as data:
        return data["V"], data["F"]


def wave_sequence(frames: int = 24, grid: int = 9, seed: int = 0) -> np.ndarray:
    """A real-looking synthetic animation (:func:`tuckercodec.io.samples.wave_sheet`) plus a little
    noise so that no rank is exactly zero. Shape (frames, grid*grid, 3)."""
    rng = np.random.default_rng(seed)
    out = wave_sheet(frames, grid)
    return out + 1e-4 * rng.standard_normal(out.shape)


def grid_faces(grid: int = 9) -> np.ndarray:
    """Triangles of the grid sheet used by :func:`wave_sequence`."""
    return sheet_triangles(grid)
