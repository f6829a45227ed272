"""The pictures of one comparison: arguments checked, odd meshes drawn, files written atomically."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec.reports.plots import (  # matplotlib is imported on use
    plot_frame_errors,
    render_frame,
)

pytest.importorskip("matplotlib")

PNG = b"\x89PNG\r\n\x1a\n"


def test_frame_errors_of_one_frame_and_bad_series(tmp_path):
    path = tmp_path / "one.png"
    plot_frame_errors(np.array([0.5]), np.array([0.01]), path)  # one frame: drawn as a point
    assert path.read_bytes()[:8] == PNG
    with pytest.raises(FileExistsError):
        plot_frame_errors(np.array([0.5]), np.array([0.01]), path)
    plot_frame_errors(np.zeros(4), np.zeros(4), path, overwrite=True)  # no error at all
    for kg, worst in (
        (np.zeros(3), np.zeros(4)),
        (np.zeros(0), np.zeros(0)),
        (np.zeros((2, 2)), np.zeros((2, 2))),
    ):
        with pytest.raises(ValueError, match="per-frame"):
            plot_frame_errors(kg, worst, tmp_path / "bad.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.png"]


def test_render_draws_meshes_flat_sheets_and_point_clouds(tmp_path):
    frame = wave_sequence(1, 6)[0]
    errors = np.linspace(0, 1, len(frame))
    render_frame(frame, grid_faces(6), tmp_path / "shaded.png")
    render_frame(frame, grid_faces(6), tmp_path / "errors.png", errors=errors, up="z")
    flat = frame * [1, 1, 0]  # one axis of zero extent: still equal scaling, no warning
    render_frame(flat, grid_faces(6), tmp_path / "flat.png", errors=np.zeros(len(frame)))
    render_frame(frame, np.zeros((0, 3), dtype=np.int64), tmp_path / "points.png", errors=errors)
    for name in ("shaded", "errors", "flat", "points"):
        assert (tmp_path / f"{name}.png").read_bytes()[:8] == PNG


def test_render_checks_its_arguments(tmp_path):
    frame = wave_sequence(1, 3)[0]
    with pytest.raises(ValueError, match="per-vertex errors"):
        render_frame(frame, grid_faces(3), tmp_path / "x.png", errors=np.zeros(2))
    with pytest.raises(ValueError, match="up must be"):
        render_frame(frame, grid_faces(3), tmp_path / "x.png", up="w")
    with pytest.raises(ValueError, match="shape"):
        render_frame(frame[:, :2], grid_faces(3), tmp_path / "x.png")
    assert not list(tmp_path.iterdir())
