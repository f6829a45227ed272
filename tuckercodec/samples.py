"""The built-in sample sequence, shipped inside the package so that the codec can be tried
on a real animated mesh right after installation."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

SAMPLE_NAME = "cloth-vellum"


def sample_path() -> Path:
    """Path of the built-in sample: a simulated cloth, 60 frames of 3101 vertices (MIT licence,
    see ``cloth-vellum.LICENSE.txt`` beside it)."""
    return Path(str(resources.files("tuckercodec") / "data" / f"{SAMPLE_NAME}.npz"))
