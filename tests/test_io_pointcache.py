"""The PC2 and MDD point caches (tuckercodec/io/pointcache/): exact round
trips, the header fields and times kept, the faces from ``--faces``, the layouts real exporters
write, and broken or crafted files.

The files that stand for "real" ones are built here byte for byte the way Blender's exporters
build them (``struct.pack('<12siiffi', b'POINTCACHE2\\0', 1, ...)`` for PC2; for MDD
``pack('>2i', ...)``, the times as ``frame / fps`` packed as big-endian float32, and before
Blender 2.80 an uncounted rest frame), not with the writer under test.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.support.inputs import expect_input_error, measure
from tests.support.properties import PROPERTY
from tests.support.sequences import grid_faces, shared_file, wave_sequence
from tuckercodec import InputError, MeshSequence, load_sequence, save_sequence
from tuckercodec.cli import main
from tuckercodec.io.pointcache.mdd import frame_timing
from tuckercodec.io.samples import sample_path
from tuckercodec.model.sequence import DEFAULT_FRAME_RATE

# ------------------------------------------------------------------------------------------
# files as exporters write them


def pc2_bytes(positions: np.ndarray, start: float = 0.0, rate: float = 1.0, **header) -> bytes:
    """A PC2 file as Blender's and 3ds Max's exporters write it; ``header`` overrides fields."""
    fields = {
        "signature": b"POINTCACHE2\0",
        "version": 1,
        "points": positions.shape[1],
        "start": start,
        "rate": rate,
        "frames": positions.shape[0],
    }
    fields.update(header)
    head = struct.pack("<12siiffi", *fields.values())
    return head + np.asarray(positions, dtype="<f4").tobytes()


def mdd_bytes(positions: np.ndarray, times: np.ndarray | None = None, frames: int | None = None):
    """An MDD file as Blender's MDD add-on writes it (times ``i / 25`` by default)."""
    count = positions.shape[0] if frames is None else frames
    if times is None:
        times = np.array([i / 25.0 for i in range(count)])
    head = struct.pack(">2i", count, positions.shape[1])
    return head + np.asarray(times, ">f4").tobytes() + np.asarray(positions, ">f4").tobytes()


def moving(frames: int = 5, points: int = 7) -> np.ndarray:
    """float32-exact positions of a small moving point set."""
    return wave_sequence(frames, 3)[:, :points].astype(np.float32).astype(np.float64)


@pytest.fixture(scope="module")
def horse() -> MeshSequence:
    return load_sequence(shared_file("horse-gallop"), progress=False)


def exact(back: MeshSequence, seq: MeshSequence) -> bool:
    """The positions came back as the sequence's float32, bit for bit."""
    return np.array_equal(
        back.vertices.astype(np.float32).view(np.uint32),
        seq.vertices.astype(np.float32).view(np.uint32),
    )


# ------------------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("suffix", [".pc2", ".mdd"])
def test_the_cloth_round_trips_exactly_with_its_faces_from_a_mesh_file(cloth, tmp_path, suffix):
    path = tmp_path / f"cloth{suffix}"
    save_sequence(cloth, path)
    points = load_sequence(path)
    assert exact(points, cloth) and points.faces.shape == (0, 3)  # a point sequence
    for faces_file in (sample_path(), _first_frame_obj(cloth, tmp_path)):  # .npz and OBJ
        back = load_sequence(path, faces=faces_file)
        assert exact(back, cloth) and np.array_equal(back.faces, cloth.faces)
    assert load_sequence(path).codes().tolist() == list(range(60))


def _first_frame_obj(seq: MeshSequence, folder: Path) -> Path:
    save_sequence(MeshSequence(seq.vertices[:1], seq.faces), folder / "mesh", progress=False)
    return next((folder / "mesh").glob("*.obj"))


@pytest.mark.parametrize("suffix", [".pc2", ".mdd"])
def test_horse_gallop_round_trips_exactly(horse, tmp_path, suffix):
    path = tmp_path / f"horse{suffix}"
    mesh = _first_frame_obj(horse, tmp_path)
    save_sequence(horse, path)
    back = load_sequence(path, faces=mesh)  # its speed: python -m tools.bench read --formats
    assert exact(back, horse) and np.array_equal(back.faces, horse.faces)
    assert back.vertices.shape == (48, 8431, 3)


def test_pc2_keeps_its_start_frame_and_sample_rate(tmp_path):
    original = pc2_bytes(moving(6), start=10.5, rate=0.25)  # Blender: sub-frame sampling
    (tmp_path / "in.pc2").write_bytes(original)
    seq = load_sequence(tmp_path / "in.pc2")
    assert seq.time_codes is not None
    assert seq.time_codes.tolist() == [10.5, 10.75, 11.0, 11.25, 11.5, 11.75]
    assert seq.frame_rate is None  # PC2 has no frames per second
    save_sequence(seq, tmp_path / "out.pc2")
    assert (tmp_path / "out.pc2").read_bytes() == original  # header and positions, every byte


@pytest.mark.parametrize("rate", [np.inf, np.nan, -1.0, 0.0])
def test_a_single_samples_sample_rate_is_never_used(tmp_path, rate):
    """One sample has no step to check, so any sampleRate reads (an infinite one made
    0 x inf a NaN, and a warning, found by the fuzzer)."""
    (tmp_path / "one.pc2").write_bytes(pc2_bytes(moving(1), start=7.0, rate=rate))
    seq = load_sequence(tmp_path / "one.pc2")
    assert seq.time_codes is not None and seq.time_codes.tolist() == [7.0]


@pytest.mark.parametrize(
    "times",
    [
        [i / 25.0 for i in range(6)],  # Blender's MDD add-on, its default fps
        [i / 24.0 for i in range(6)],
        [i * 1001 / 30000 for i in range(6)],  # 29.97 NTSC
        [(100 + i) / 60.0 for i in range(6)],  # a range that starts later
        [0.0, 0.1, 0.35, 0.5, 2.0, 2.25],  # uneven: no frame rate reproduces them
        [1e-3 * i + 5e3 for i in range(6)],  # steps near float32's resolution
    ],
)
def test_an_mdd_round_trip_keeps_the_times_bit_for_bit(tmp_path, times):
    original = mdd_bytes(moving(6), np.array(times))
    (tmp_path / "in.mdd").write_bytes(original)
    seq = load_sequence(tmp_path / "in.mdd")
    assert np.array_equal(
        (seq.codes() / seq.frame_rate).astype(np.float32), np.array(times, np.float32)
    )
    save_sequence(seq, tmp_path / "out.mdd")
    assert (tmp_path / "out.mdd").read_bytes() == original


@PROPERTY
@given(st.lists(st.floats(-1e6, 1e6, width=32), min_size=1, max_size=8, unique=True))
def test_any_increasing_times_are_kept_bit_for_bit(times):
    stamps = np.sort(np.array(times, dtype=np.float32))
    rate, codes = frame_timing(stamps.astype(np.float64), Path("t.mdd"))
    assert codes is not None
    back = np.asarray(codes / (rate or DEFAULT_FRAME_RATE)).astype(np.float32)
    assert np.array_equal(back.view(np.uint32), stamps.view(np.uint32))


def test_mdd_times_give_the_frame_rate_and_whole_frame_numbers(tmp_path):
    (tmp_path / "a.mdd").write_bytes(mdd_bytes(moving(4), np.array([i / 25 for i in range(4)])))
    seq = load_sequence(tmp_path / "a.mdd")
    assert seq.time_codes is not None
    assert seq.frame_rate == 25.0 and seq.time_codes.tolist() == [0, 1, 2, 3]
    ntsc = np.array([(10 + i) * 1001 / 30000 for i in range(4)])
    (tmp_path / "b.mdd").write_bytes(mdd_bytes(moving(4), ntsc))
    seq = load_sequence(tmp_path / "b.mdd")
    assert seq.frame_rate == pytest.approx(29.97, abs=1e-3)
    assert seq.time_codes is not None
    assert seq.time_codes.tolist() == [10, 11, 12, 13]


def test_mdd_times_that_do_not_increase_carry_no_timing(tmp_path):
    # some exporters write one constant time for every frame
    (tmp_path / "c.mdd").write_bytes(mdd_bytes(moving(3), np.full(3, 0.1)))
    seq = load_sequence(tmp_path / "c.mdd")
    assert seq.frame_rate is None and seq.time_codes is None
    assert np.array_equal(seq.vertices, moving(3))


def test_an_mdd_with_blenders_old_uncounted_rest_frame_skips_it(tmp_path):
    frames = moving(4)
    rest = frames[:1]  # Blender < 2.80 wrote the first frame once more, before the frames
    data = mdd_bytes(np.concatenate([rest, frames]), frames=4)
    (tmp_path / "old.mdd").write_bytes(data)
    seq = load_sequence(tmp_path / "old.mdd")
    assert np.array_equal(seq.vertices, frames) and seq.frame_rate == 25.0


def test_writing_without_time_codes_numbers_the_frames_from_0(tmp_path):
    seq = MeshSequence(moving(3), np.zeros((0, 3), int))
    save_sequence(seq, tmp_path / "a.pc2")
    head = struct.unpack("<12siiffi", (tmp_path / "a.pc2").read_bytes()[:32])
    assert head == (b"POINTCACHE2\0", 1, 7, 0.0, 1.0, 3)
    save_sequence(seq, tmp_path / "a.mdd")
    data = (tmp_path / "a.mdd").read_bytes()
    assert struct.unpack(">2i3f", data[:20]) == (3, 7, 0.0, np.float32(1 / 24), np.float32(2 / 24))
    one = MeshSequence(moving(1), np.zeros((0, 3), int), time_codes=np.array([7.0]))
    save_sequence(one, tmp_path / "one.pc2")
    kept = load_sequence(tmp_path / "one.pc2").time_codes
    assert kept is not None and kept.tolist() == [7.0]


def test_time_codes_pc2_cannot_hold_are_refused_naming_the_frame(tmp_path):
    seq = MeshSequence(moving(4), np.zeros((0, 3), int), time_codes=np.array([0, 1, 2, 4]))
    with pytest.raises(InputError, match=r"frame 3: time code 4\.0 is not 3\.0: .* evenly"):
        save_sequence(seq, tmp_path / "a.pc2")
    assert not (tmp_path / "a.pc2").exists()
    save_sequence(seq, tmp_path / "a.mdd")  # MDD keeps each frame's time
    kept = load_sequence(tmp_path / "a.mdd").time_codes
    assert kept is not None and kept.tolist() == [0, 1, 2, 4]


@pytest.mark.parametrize("suffix", [".pc2", ".mdd"])
def test_writing_refuses_what_float32_cannot_hold_and_never_overwrites(tmp_path, suffix):
    path = tmp_path / f"a{suffix}"
    huge = moving(3)
    huge[2, 4, 1] = 1e300
    with pytest.raises(InputError, match="frame 2: vertex 4 is beyond the range of float32"):
        save_sequence(MeshSequence(huge, np.zeros((0, 3), int)), path)
    assert not path.exists()
    path.write_bytes(b"precious")
    with pytest.raises(FileExistsError):
        save_sequence(MeshSequence(moving(3), np.zeros((0, 3), int)), path)
    assert path.read_bytes() == b"precious"


# ------------------------------------------------------------------------------------------
# --faces


def test_faces_from_a_mesh_of_another_vertex_count_name_both_files(tmp_path):
    cache = tmp_path / "c.pc2"
    cache.write_bytes(pc2_bytes(moving(3, 7)))
    mesh = tmp_path / "grid.npz"
    np.savez(mesh, V=wave_sequence(1, 3), F=grid_faces(3))  # 9 vertices
    error = expect_input_error(lambda: load_sequence(cache, faces=mesh), cache)
    assert f"holds 7 points but the --faces mesh {mesh} has 9 vertices" in str(error)


def test_faces_from_a_file_without_faces_or_no_file_are_errors(tmp_path):
    cache = tmp_path / "c.mdd"
    cache.write_bytes(mdd_bytes(moving(3, 7)))
    points = tmp_path / "points.npz"
    np.savez(points, V=moving(1, 7))
    error = expect_input_error(lambda: load_sequence(cache, faces=points), points)
    assert "has no faces to give the points of the cache" in str(error)
    missing = tmp_path / "nothing.obj"
    expect_input_error(lambda: load_sequence(cache, faces=missing), missing, match="no such")


# ------------------------------------------------------------------------------------------
# broken and crafted files: one per rule, each an InputError naming the file


def _pc2(tmp_path, data: bytes) -> Path:
    path = tmp_path / "bad.pc2"
    path.write_bytes(data)
    return path


def _mdd(tmp_path, data: bytes) -> Path:
    path = tmp_path / "bad.mdd"
    path.write_bytes(data)
    return path


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"POINTCACHE2\0\1\0", r"is 14 bytes, shorter than the 32-byte header"),
        (pc2_bytes(moving(2), signature=b"POINTCACHE3\0"), r"not a PC2 .*b'POINTCACHE3\\x00'"),
        (pc2_bytes(moving(2), version=2), "is PC2 version 2; only version 1"),
        (pc2_bytes(moving(2), points=-7), r"negative point count \(-7\)"),
        (pc2_bytes(moving(2), frames=-1), r"negative frame count \(-1\)"),
        (pc2_bytes(moving(2)[:0], points=7), "declares 0 frames"),
        (pc2_bytes(moving(2)[:, :0]), "declares 0 points"),
        (pc2_bytes(moving(2))[:-5], r"truncated: .* make 200 bytes, but the file has 195 \(5 "),
        (pc2_bytes(moving(2)) + b"\0" * 3, "has 3 trailing bytes: .* 200 bytes, but .* 203"),
        (pc2_bytes(moving(2), rate=0.0), "sampleRate is 0.0: .* must be a positive number"),
        (pc2_bytes(moving(2), start=float("nan")), "startFrame is nan, not a number"),
    ],
)
def test_a_broken_pc2_is_refused_saying_why(tmp_path, data, message):
    path = _pc2(tmp_path, data)
    expect_input_error(lambda: load_sequence(path), path, match=message)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"\0\0\0\2\0", "is 5 bytes, shorter than the 8-byte header"),
        (mdd_bytes(moving(2))[:4] + struct.pack(">i", -3), r"negative point count \(-3\)"),
        (struct.pack(">2i", -2, 7), r"negative frame count \(-2\)"),
        (struct.pack(">2i", 0, 7), "declares 0 frames"),
        (mdd_bytes(moving(2))[:-1], r"truncated: .* make 184 bytes, but .* 183 \(1 missing\)"),
        (mdd_bytes(moving(2)) + b"\0", r"has 1 trailing bytes: .* 184 bytes, but .* 185"),
    ],
)
def test_a_broken_mdd_is_refused_saying_why(tmp_path, data, message):
    path = _mdd(tmp_path, data)
    expect_input_error(lambda: load_sequence(path), path, match=message)


@pytest.mark.parametrize("suffix", [".pc2", ".mdd"])
def test_counts_far_beyond_the_file_are_refused_before_allocating(tmp_path, suffix):
    big = 2**31 - 1
    if suffix == ".pc2":
        path = _pc2(tmp_path, pc2_bytes(moving(1), points=big, frames=big))
    else:
        path = _mdd(tmp_path, struct.pack(">2i", big, big) + b"\0" * 64)
    error, _, peak = measure(lambda: load_sequence(path))
    assert isinstance(error, InputError) and "is truncated" in str(error), error
    assert peak < 1_000_000, peak  # memory, not seconds: the same on any machine


@pytest.mark.parametrize("suffix", [".pc2", ".mdd"])
def test_a_non_finite_position_names_its_frame_and_vertex(tmp_path, suffix):
    positions = moving(4)
    positions[2, 5, 0] = np.inf
    writer = pc2_bytes if suffix == ".pc2" else mdd_bytes
    path = (tmp_path / "nan").with_suffix(suffix)
    path.write_bytes(writer(positions))
    expect_input_error(
        lambda: load_sequence(path), path, frame=2, match="vertex 5 has a non-finite coordinate"
    )


def test_a_non_finite_mdd_time_names_its_frame(tmp_path):
    path = _mdd(tmp_path, mdd_bytes(moving(3), np.array([0.0, np.nan, 1.0])))
    expect_input_error(lambda: load_sequence(path), path, frame=1, match="its time is nan")


# ------------------------------------------------------------------------------------------
# the command line


def test_the_cli_converts_encodes_and_decodes_point_caches(cloth, tmp_path, capsys):
    cache = tmp_path / "cloth.pc2"
    assert main(["convert", "sample", str(cache)]) == 0
    assert "not carried by the output's format: faces" in capsys.readouterr().out
    mesh = _first_frame_obj(cloth, tmp_path)
    packed = tmp_path / "x.tkc"
    assert main(["encode", str(cache), "--faces", str(mesh), "-o", str(packed)]) == 0
    out = tmp_path / "out.mdd"
    assert main(["decode", str(packed), "-o", str(out)]) == 0
    decoded = load_sequence(out, faces=mesh)
    assert decoded.vertices.shape == (60, 3101, 3) and decoded.faces.shape == (5912, 3)


def test_an_option_given_to_the_wrong_format_exits_4(tmp_path, capsys):
    cache = tmp_path / "c.pc2"
    cache.write_bytes(pc2_bytes(moving(3)))
    mesh = tmp_path / "mesh.npz"
    np.savez(mesh, V=moving(1), F=np.array([[0, 1, 2]]))
    packed = tmp_path / "x.tkc"
    assert main(["encode", str(cache), "--prim", "/World/a", "-o", str(packed)]) == 4
    assert "--prim (prim) does not apply to pc2 files" in capsys.readouterr().err
    assert main(["encode", str(mesh), "--faces", str(mesh), "-o", str(packed)]) == 4
    assert "--faces (faces) does not apply" in capsys.readouterr().err
    assert not packed.exists()
