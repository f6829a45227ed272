"""What every format shares: reading options, time codes, convert, and the registry."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tuckercodec import (
    Decoder,
    InputError,
    MeshSequence,
    decode,
    encode,
    load_sequence,
    save_sequence,
)
from tuckercodec.cli import main
from tuckercodec.io import formats
from tuckercodec.io.registry import COMMON_OPTIONS, OPTION_FLAGS, ReadOptions


@pytest.fixture
def wave(tmp_path):
    path = tmp_path / "wave.npz"
    np.savez(path, V=wave_sequence(12, 6), F=grid_faces(6))
    return path


def test_time_codes_are_checked_and_give_seconds():
    vertices = wave_sequence(4, 3)
    seq = MeshSequence(
        vertices, grid_faces(3), frame_rate=25.0, time_codes=np.array([10, 11, 12, 14])
    )
    assert seq.codes().tolist() == [10, 11, 12, 14]
    assert seq.seconds().tolist() == pytest.approx([0.4, 0.44, 0.48, 0.56])
    assert MeshSequence(vertices, grid_faces(3)).seconds()[1] == pytest.approx(1 / 24)
    with pytest.raises(InputError, match=r"frame 2: time codes must increase: 1\.0 follows 2\.0"):
        MeshSequence(vertices, grid_faces(3), time_codes=np.array([0, 2, 1, 3]))
    with pytest.raises(InputError, match="frame 1: time code nan is not finite"):
        MeshSequence(vertices, grid_faces(3), time_codes=np.array([0, np.nan, 1, 3]))
    with pytest.raises(InputError, match="must be 4 numbers"):
        MeshSequence(vertices, grid_faces(3), time_codes=np.array([0, 1]))


def test_npz_keeps_time_codes_and_frame_rate(tmp_path):
    seq = MeshSequence(
        wave_sequence(3, 3), grid_faces(3), frame_rate=30, time_codes=np.array([5, 6, 8])
    )
    save_sequence(seq, tmp_path / "t.npz")
    back = load_sequence(tmp_path / "t.npz")
    assert back.time_codes is not None
    assert back.time_codes.tolist() == [5, 6, 8] and back.frame_rate == 30


def test_a_decoded_part_keeps_its_place_in_time():
    decoder = Decoder(encode(MeshSequence(wave_sequence(12, 6), grid_faces(6)), target_kg=1.0))
    assert decoder.sequence().time_codes is None
    kept = decoder.sequence(slice(3, 6)).time_codes
    assert kept is not None and kept.tolist() == [3, 4, 5]
    assert decoder.sequence([5, 2]).time_codes is None  # not in time order: no time codes


def test_an_option_the_format_does_not_use_is_refused_by_name(wave, tmp_path):
    with pytest.raises(InputError, match=r"wave\.npz: --prim \(prim\) does not apply to"):
        load_sequence(wave, prim="/World/mesh")
    save_sequence(load_sequence(wave), tmp_path / "frames")
    with pytest.raises(InputError, match=r"--fps \(fps\) does not apply to a folder of frames"):
        load_sequence(tmp_path / "frames", fps=30)


def test_every_option_has_a_flag_and_a_format_that_uses_it():
    assert set(OPTION_FLAGS) | COMMON_OPTIONS == set(vars(ReadOptions()))
    assert not set(OPTION_FLAGS) & COMMON_OPTIONS
    used = set().union(*(f.read_options for f in formats()))
    assert used <= set(OPTION_FLAGS)


def test_max_memory_applies_to_every_source_and_must_be_positive(wave, tmp_path):
    assert ReadOptions(prim="/m", max_memory=10).given() == ["prim"]
    save_sequence(load_sequence(wave), tmp_path / "frames")
    for source in (wave, tmp_path / "frames"):
        assert load_sequence(source, max_memory=2**30).frame_count == 12
    with pytest.raises(ValueError, match="max_memory must be a positive number of bytes"):
        load_sequence(wave, max_memory=0)


def test_every_format_is_described_once():
    names = [f.name for f in formats()]
    assert len(names) == len(set(names))
    for found in formats():
        assert found.suffixes and all(s.startswith(".") and s == s.lower() for s in found.suffixes)
        assert (found.open is not None) or (found.read_frame is not None), found.name
        parts = {"float64", "faces", "polygons", "frame_names", "frame_rate", "time_codes"}
        parts |= {"meters_per_unit", "up_axis"}
        assert found.carries <= parts
        assert "polygons" not in found.carries or "faces" in found.carries


def test_convert_writes_the_target_format_and_says_what_it_loses(wave, tmp_path, capsys):
    out = tmp_path / "frames"
    assert main(["convert", str(wave), str(out)]) == 0
    printed = capsys.readouterr().out
    assert "12 frames, 36 vertices" in printed and "a folder of OBJ files" in printed
    assert "not carried" not in printed  # OBJ text is exact and the names are the file names
    back = load_sequence(out)
    assert np.array_equal(back.vertices, load_sequence(wave).vertices)

    timed = tmp_path / "timed.npz"
    save_sequence(MeshSequence(wave_sequence(3, 3), grid_faces(3), frame_rate=30), timed)
    assert main(["convert", str(timed), str(tmp_path / "timed")]) == 0
    assert "not carried by the output's format: frame rate" in capsys.readouterr().out


def test_convert_never_overwrites_without_force(wave, tmp_path, capsys):
    target = tmp_path / "copy.npz"
    target.write_bytes(b"precious")
    assert main(["convert", str(wave), str(target)]) == 1
    assert "exists" in capsys.readouterr().err
    assert target.read_bytes() == b"precious"
    assert main(["convert", str(wave), str(target), "--force"]) == 0
    assert load_sequence(target).frame_count == 12


def test_convert_reads_a_compressed_file_and_points_to_encode_for_one(wave, tmp_path, capsys):
    packed = tmp_path / "wave.tkc"
    assert main(["encode", str(wave), "-o", str(packed)]) == 0
    assert main(["convert", str(packed), str(tmp_path / "back.npz")]) == 0
    assert load_sequence(tmp_path / "back.npz").frame_count == 12
    capsys.readouterr()
    assert main(["convert", str(wave), str(tmp_path / "x.tkc")]) == 2
    assert "use 'tuckercodec encode'" in capsys.readouterr().err
    assert not (tmp_path / "x.tkc").exists()


def test_a_read_option_given_to_the_wrong_format_exits_4(wave, tmp_path, capsys):
    assert main(["encode", str(wave), "-o", str(tmp_path / "x.tkc"), "--object", "/a"]) == 4
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--object (object_path) does not apply" in err
    assert not (tmp_path / "x.tkc").exists()


def test_convert_names_polygons_that_a_triangle_format_splits(tmp_path, capsys):
    square = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]], dtype=np.float64)
    seq = MeshSequence(np.concatenate([square, square + 0.5]), np.array([[0, 1, 2, 3]]))
    save_sequence(seq, tmp_path / "quad.npz")
    assert main(["convert", str(tmp_path / "quad.npz"), str(tmp_path / "quad.glb")]) == 0
    assert "polygons (split into triangles)" in capsys.readouterr().out
    assert load_sequence(tmp_path / "quad.glb").faces.shape == (2, 3)
    assert main(["convert", str(tmp_path / "quad.npz"), str(tmp_path / "quad.pvd")]) == 0
    assert "not carried" not in capsys.readouterr().out


def test_formats_lists_every_format_with_its_options_and_extra(capsys):
    assert main(["formats"]) == 0
    out = capsys.readouterr().out
    for found in formats():
        assert f"{found.name}: {' '.join(found.suffixes)}" in out
    assert "reading options: --prim" in out
    assert "pip install 'tuckercodec[usd]'" in out


def test_convert_of_positions_beyond_float32_names_the_loss_without_a_warning(tmp_path, capsys):
    vertices = np.zeros((2, 4, 3))
    vertices[:, 1, 0] = vertices[:, 2, 1] = vertices[:, 3, 2] = 1.0
    vertices[1, 3, 2] = 1e39
    save_sequence(MeshSequence(vertices, np.array([[0, 1, 2]])), tmp_path / "big.npz")
    assert main(["convert", str(tmp_path / "big.npz"), str(tmp_path / "big.pvd")]) == 0
    assert "float64" not in capsys.readouterr().out  # .pvd keeps float64: nothing lost


@pytest.mark.parametrize("suffix", [".glb", ".mdd"])
def test_times_that_float32_cannot_tell_apart_are_refused_naming_the_frame(tmp_path, suffix):
    codes = 1e9 + np.arange(4.0)  # 24 bits of float32 cannot separate these seconds
    seq = MeshSequence(wave_sequence(4, 3), grid_faces(3), frame_rate=24, time_codes=codes)
    with pytest.raises(InputError, match="frame 1: frames 0 and 1 fall on the same float32"):
        save_sequence(seq, tmp_path / f"late{suffix}")
    assert not (tmp_path / f"late{suffix}").exists()


def test_the_compressed_file_keeps_time_codes(tmp_path, capsys):
    # format 1.4 keeps them (the file said it did not before)
    timed = tmp_path / "timed.npz"
    seq = MeshSequence(wave_sequence(12, 6), grid_faces(6), time_codes=np.arange(101.0, 113.0))
    save_sequence(seq, timed)
    assert main(["encode", str(timed), "-o", str(tmp_path / "t.tkc"), "--kg", "1"]) == 0
    assert "not kept" not in capsys.readouterr().out
    back = decode(tmp_path / "t.tkc")
    np.testing.assert_array_equal(back.time_codes, np.arange(101.0, 113.0))


@pytest.mark.parametrize("name", ["out.obj", "out.ply", "out.vtu"])
def test_a_file_name_no_format_writes_is_refused_not_made_a_folder(wave, tmp_path, name, capsys):
    assert main(["convert", str(wave), str(tmp_path / name)]) == 2
    assert "no format writes a sequence as one" in capsys.readouterr().err
    assert not (tmp_path / name).exists()
    with pytest.raises(ValueError, match="'tuckercodec formats' lists them"):
        save_sequence(load_sequence(wave), tmp_path / name)
    with pytest.raises(ValueError, match=r"one \.tkc file"):  # encode_file writes those
        save_sequence(load_sequence(wave), tmp_path / "out.tkc")


@pytest.mark.parametrize("suffix", [".usdc", ".abc", ".pc2", ".glb"])
def test_a_position_beyond_float32_is_refused_by_every_float32_writer(tmp_path, suffix):
    pytest.importorskip("pxr" if suffix == ".usdc" else "numpy", reason="usd-core is absent")
    pytest.importorskip("alembic3d" if suffix == ".abc" else "numpy", reason="no alembic3d")
    vertices = wave_sequence(3, 3)
    vertices[2, 4, 1] = 1e39  # a float64 that float32 would make infinite
    seq = MeshSequence(vertices, grid_faces(3))
    with pytest.raises(InputError, match="frame 2: vertex 4 is beyond the range of float32"):
        save_sequence(seq, tmp_path / f"far{suffix}")
    assert list(tmp_path.iterdir()) == []  # nothing written, not even a temporary file


def test_precision_is_refused_where_the_output_is_not_obj_text(wave, tmp_path, capsys):
    packed = tmp_path / "w.tkc"
    assert main(["encode", str(wave), "-o", str(packed), "--kg", "1"]) == 0
    capsys.readouterr()
    for argv in (
        ["decode", str(packed), "-o", str(tmp_path / "w.glb"), "--precision", "5"],
        ["convert", str(wave), str(tmp_path / "w.abc"), "--precision", "5"],
    ):
        assert main(argv) == 2
        assert "--precision applies to OBJ frames" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.tkc", "wave.npz"]
    assert main(["convert", str(wave), str(tmp_path / "objs"), "--precision", "5"]) == 0


@pytest.mark.parametrize("suffix", [".glb", ".gltf", ".pc2", ".mdd", ".pvd", ".xdmf", ".npz"])
def test_an_empty_file_is_refused_naming_it(tmp_path, suffix):
    empty = tmp_path / f"empty{suffix}"
    empty.write_bytes(b"")
    with pytest.raises(InputError, match=rf"empty\{suffix}: .*(empty|shorter|not)"):
        load_sequence(empty)
