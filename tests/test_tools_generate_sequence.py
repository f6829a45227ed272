"""tools.generate.sequence: the generated sequences are what the scale benchmarks assume they are:
deterministic, of the size asked, with valid faces, made the same whatever the blocks, written
as readable .npy/.obj/.npz files, and neither trivial nor incompressible for the codec."""

from __future__ import annotations

import numpy as np
import pytest

from tools.generate import sequence as make_sequence
from tuckercodec import MeshSequence, decode, encode_with_report, kg_error, load_sequence

KINDS = make_sequence.KINDS


@pytest.mark.parametrize("kind", KINDS)
def test_the_same_seed_gives_the_same_bytes_and_another_seed_others(kind):
    first, faces = make_sequence.generate(kind, 700, 40, seed=5)
    again, faces_again = make_sequence.generate(kind, 700, 40, seed=5)
    other, _ = make_sequence.generate(kind, 700, 40, seed=6)
    assert first.tobytes() == again.tobytes()
    np.testing.assert_array_equal(faces, faces_again)
    assert not np.allclose(first, other, atol=1e-3)


@pytest.mark.parametrize(("kind", "vertices"), [("cloth", 4), ("cloth", 1001), ("body", 1237)])
def test_shape_is_exactly_what_was_asked_and_every_vertex_is_in_a_face(kind, vertices):
    positions, faces = make_sequence.generate(kind, vertices, 7)
    assert positions.shape == (7, vertices, 3) and positions.dtype == np.float32
    assert np.isfinite(positions).all()
    assert faces.shape[1] == 3 and faces.min() == 0 and faces.max() == vertices - 1
    assert np.unique(faces).size == vertices  # none left out
    assert (faces[:, 0] != faces[:, 1]).all() and (faces[:, 1] != faces[:, 2]).all()
    assert (faces[:, 0] != faces[:, 2]).all()
    corners = positions[0][faces].astype(np.float64)
    areas = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    assert areas.min() > 0


def test_the_body_is_closed_and_faces_outward():
    positions, faces = make_sequence.generate("body", 900, 1)
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    directed = {tuple(edge) for edge in edges.tolist()}
    assert len(directed) == len(edges)  # no edge twice the same way: one orientation
    assert all((b, a) in directed for a, b in directed)  # closed: each edge has its twin
    p = positions[0].astype(np.float64)[faces]
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6
    assert volume > 0.05  # outward normals give a positive volume (about 0.14 units^3)


def test_the_cloth_is_pinned_along_its_pole():
    positions, _ = make_sequence.generate("cloth", 600, 50)
    cloth = make_sequence.Cloth(600, 50, 1)
    pole = np.arange(600) % cloth.columns == 0
    moved = np.linalg.norm(positions[:, pole] - positions[:1, pole], axis=2)
    assert moved.max() < 2e-3  # only the noise (1e-4 of the model's size) moves it
    assert np.linalg.norm(positions[:, ~pole] - positions[:1, ~pole], axis=2).max() > 0.1


@pytest.mark.parametrize("kind", KINDS)
def test_any_frame_range_is_made_alone_exactly_as_with_the_others(kind, monkeypatch):
    monkeypatch.setattr(make_sequence, "BLOCK_VALUES", 3 * 500 * 4)  # blocks of 4 frames
    whole, _ = make_sequence.generate(kind, 500, 30, seed=2)
    part = make_sequence.make(kind, 500, 30, seed=2).frames(13, 17).astype(np.float32)
    np.testing.assert_array_equal(part, whole[13:17])


@pytest.mark.parametrize("kind", KINDS)
def test_the_motion_is_smooth_in_time(kind):
    positions, _ = make_sequence.generate(kind, 800, 60)
    speed = np.linalg.norm(np.diff(positions, axis=0), axis=2)
    jerk = np.linalg.norm(np.diff(positions, n=3, axis=0), axis=2)
    assert speed.mean() > 8 * jerk.mean()  # no kinks: a third difference far below the first


def test_npy_and_faces_obj_are_written_and_read_back(tmp_path):
    out = tmp_path / "body.npy"
    sequence = make_sequence.make("body", 400, 12, seed=3)
    paths = make_sequence.write(out, sequence)
    assert paths == [out, tmp_path / "body.faces.obj"]
    positions, faces = make_sequence.generate("body", 400, 12, seed=3)
    np.testing.assert_array_equal(np.load(out, mmap_mode="r"), positions)
    mesh = load_sequence(paths[1], progress=False)
    np.testing.assert_array_equal(mesh.faces, faces)
    np.testing.assert_allclose(mesh.vertices[0], positions[0], rtol=1e-7, atol=1e-7)
    with pytest.raises(FileExistsError):
        make_sequence.write(out, make_sequence.make("body", 400, 5, seed=4))
    make_sequence.write(out, make_sequence.make("body", 400, 5, seed=4), force=True)
    assert np.load(out).shape == (5, 400, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["body.faces.obj", "body.npy"]


def test_npz_is_read_by_load_sequence(tmp_path):
    out = tmp_path / "cloth.npz"
    make_sequence.write(out, make_sequence.make("cloth", 300, 9), npz=True)
    sequence = load_sequence(out, progress=False)
    positions, faces = make_sequence.generate("cloth", 300, 9)
    np.testing.assert_array_equal(sequence.vertices, positions)
    np.testing.assert_array_equal(sequence.faces, faces)
    assert [p.name for p in tmp_path.iterdir()] == ["cloth.npz"]


@pytest.mark.parametrize("kind", KINDS)
def test_the_codec_finds_real_content_more_of_it_in_a_longer_sequence(kind):
    ranks = []
    for frames in (40, 160):
        positions, faces = make_sequence.generate(kind, 1500, frames)
        sequence = MeshSequence(positions.astype(np.float64), faces)
        result = encode_with_report(sequence, target_kg=0.1)
        assert kg_error(sequence, decode(result.data)) <= 0.1
        i, k = result.report.ranks
        assert 8 <= i < 200 and 8 <= k < frames  # neither trivial nor full
        ranks.append(result.report.ranks)
    assert ranks[1][1] > ranks[0][1]  # four times the frames, more motion to keep


def test_the_command_line_writes_reports_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "c.npy"
    argv = ["--kind", "cloth", "--vertices", "200", "--frames", "5", "-o", str(out), "--quiet"]
    assert make_sequence.main(argv) == 0
    printed = capsys.readouterr().out
    assert "machine:" in printed and "5 frames x 200 vertices" in printed
    assert np.load(out).shape == (5, 200, 3)
    assert make_sequence.main(argv) == 1
    assert "already exists" in capsys.readouterr().err
    assert make_sequence.main([*argv, "--force", "--npz"]) == 0
    assert (tmp_path / "c.npz").exists()
    with pytest.raises(SystemExit):
        make_sequence.main(["--vertices", "50", "-o", str(tmp_path / "b.npy")])  # too few
    with pytest.raises(SystemExit):
        make_sequence.main(["-o", str(tmp_path / "b.txt")])
