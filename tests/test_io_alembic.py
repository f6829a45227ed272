"""The Alembic format (tuckercodec/io/alembic.py): exact round trips, frame rate and time codes
from the time sampling, the clockwise faces of Alembic turned counter-clockwise, choosing a
mesh with --object, and broken or odd archives, each refused with an InputError that names
the file, the object and the frame."""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.inputs import expect_input_error
from tests.support.sequences import shared_file
from tuckercodec import DependencyError, InputError, MeshSequence
from tuckercodec.cli import main
from tuckercodec.io import load_sequence, save_sequence
from tuckercodec.io.alembic import CODES_KEY, RATE_KEY, codes_from_times

pytest.importorskip("alembic3d", reason="alembic3d (the 'alembic' extra) is not installed")
import imath
from alembic3d import Abc, AbcCoreAbstract, AbcGeom

WRAP = Abc.WrapExistingFlag.kWrapExisting
QUAD = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float32)


@pytest.fixture(scope="module")
def horse() -> MeshSequence:
    return load_sequence(shared_file("horse-gallop"), progress=False)


def exact(back: MeshSequence, seq: MeshSequence) -> bool:
    """The same float32 positions bit for bit, the same faces."""
    return np.array_equal(back.vertices, seq.vertices.astype(np.float32)) and np.array_equal(
        back.faces, seq.faces
    )


def polygon_sequence(rate: float | None = 30000 / 1001, codes=(-2.0, 0.5, 1.0, 7.25, 100.0)):
    """Quads and triangles (rows padded with -1) at uneven times."""
    faces = np.array([[0, 1, 2, 3], [1, 4, 2, -1], [4, 5, 6, 2], [6, 3, 2, -1]])
    vertices = np.random.default_rng(2).standard_normal((len(codes), 7, 3))
    return MeshSequence(vertices, faces, frame_rate=rate, time_codes=np.array(codes))


def raw_mesh(path: Path, name: str) -> tuple[np.ndarray, np.ndarray, int, Any]:
    """Face counts, face indices and sample count of an object as stored, and its sampling."""
    archive = Abc.IArchive(str(path))
    item = archive.getTop()
    for part in name.strip("/").split("/"):
        item = item.getChild(part)
    schema = AbcGeom.IPolyMesh(item, WRAP).getSchema()
    sample = schema.getValue(Abc.ISampleSelector(schema.getTimeSampling().getSampleTime(0)))
    counts, indices = np.asarray(sample.getFaceCounts()), np.asarray(sample.getFaceIndices())
    return counts, indices, schema.getNumSamples(), schema.getTimeSampling()


# ------------------------------------------------------------------------------------------
# round trips


def test_the_cloth_round_trips_exactly(cloth, tmp_path):
    path = tmp_path / "cloth.abc"
    save_sequence(cloth, path)
    back = load_sequence(path)
    assert exact(back, cloth)
    assert back.frame_rate == 24.0  # the sequence has none: the default, written and read
    assert back.time_codes is not None
    assert np.array_equal(back.time_codes, cloth.codes())
    assert path.read_bytes()[:5] == b"Ogawa"


@pytest.mark.parametrize(
    ("rate", "codes"),
    [
        (30000 / 1001, (-2.0, 0.5, 1.0, 7.25, 100.0)),  # uneven: acyclic sampling
        (25.0, (10.0, 10.5, 11.0, 11.5, 12.0)),  # half frames: uniform sampling
        (None, (0.0, 1.0, 2.0, 3.0, 4.0)),
        (24.0, (1 / 3, 2 / 3, 0.9999, 4 / 3, 8171.509356676778)),  # no time x 24 gives the last
    ],
)
def test_polygons_rates_and_time_codes_round_trip_exactly(tmp_path, rate, codes):
    seq = polygon_sequence(rate, codes)
    path = tmp_path / "poly.abc"
    save_sequence(seq, path)
    back = load_sequence(path)
    assert exact(back, seq)
    assert back.frame_rate == (rate or 24.0)
    assert back.time_codes is not None
    assert np.array_equal(back.time_codes, seq.codes())


def test_horse_gallop_round_trips_exactly(horse, tmp_path):
    """(Its reading speed is measured by tools.bench read --formats, not asserted here.)"""
    path = tmp_path / "horse.abc"
    save_sequence(horse, path)
    assert exact(load_sequence(path), horse)


def test_the_written_archive_is_what_the_docstring_says(tmp_path):
    seq = polygon_sequence(25.0, (10.0, 10.5, 11.0, 11.5, 12.0))
    path = tmp_path / "my-cloth.abc"
    save_sequence(seq, path)
    counts, indices, samples, sampling = raw_mesh(path, "/my_cloth/my_clothShape")
    # stored clockwise: each face reversed
    assert counts.tolist() == [4, 3, 4, 3]
    assert indices.tolist() == [3, 2, 1, 0, 2, 4, 1, 2, 6, 5, 4, 2, 3, 6]
    kind = sampling.getTimeSamplingType()
    assert samples == 5 and kind.isUniform() and kind.getTimePerCycle() == 0.5 / 25
    assert sampling.getSampleTime(0) == 10.0 / 25
    info = Abc.GetArchiveInfo(Abc.IArchive(str(path)))
    assert info["dccFPS"] == 25.0 and info["appName"].startswith("tuckercodec ")
    # acyclic where the codes are uneven, the exact codes beside where times cannot hold them
    save_sequence(polygon_sequence(24.0, (0.0, 1 / 3, 1.0, 2.0, 3.0)), tmp_path / "u.abc")
    _, _, _, sampling = raw_mesh(tmp_path / "u.abc", "/u/uShape")
    assert sampling.getTimeSamplingType().isAcyclic()
    assert np.array_equal(codes_from_times(np.array([1 / 72]), 24.0), [1 / 3])


def test_a_point_sequence_round_trips(tmp_path):
    seq = MeshSequence(np.random.default_rng(3).standard_normal((3, 5, 3)), np.zeros((0, 3)))
    save_sequence(seq, tmp_path / "p.abc")
    back = load_sequence(tmp_path / "p.abc")
    assert exact(back, seq) and back.faces.shape == (0, 3)


def test_nothing_is_replaced_without_overwrite(cloth, tmp_path):
    path = tmp_path / "out.abc"
    path.write_bytes(b"old")
    with pytest.raises(FileExistsError, match="--force"):
        save_sequence(cloth, path)
    assert path.read_bytes() == b"old"
    save_sequence(cloth, path, overwrite=True)
    assert exact(load_sequence(path), cloth)
    assert [p.name for p in tmp_path.iterdir()] == ["out.abc"]


# ------------------------------------------------------------------------------------------
# a write that fails: the disk fills
#
# alembic3d raises when a write fails, then aborts the process (SIGABRT, a C++ exception thrown
# from the archive's destructors) once its objects are released; so it writes in a child.

REPOSITORY = Path(__file__).resolve().parents[1]
#: The file size the writer may reach: a few samples of the sequence below, not all of them.
FILE_LIMIT = 64 * 1024


def _small_file_limit() -> None:  # in the child, before it runs: the disk "fills" at 64 KiB
    import resource
    import signal

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_LIMIT, FILE_LIMIT))


@pytest.fixture
def full_tmpfs(tmp_path):
    """A 64 KiB tmpfs (needs root and mount; else skipped), unmounted after the test."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root: the file-size limit test covers the rest")
    folder = tmp_path / "full"
    folder.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={FILE_LIMIT}", "tmpfs", str(folder)],
        capture_output=True,
        text=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip() or mounted.returncode}")
    try:
        yield folder
    finally:
        subprocess.run(["umount", str(folder)], check=False)


def _convert_into(folder: Path, tmp_path: Path, limit: bool) -> subprocess.CompletedProcess[str]:
    """``tuckercodec convert`` of 40 frames of 600 vertices (about 290 KB of positions) to
    ``folder/out.abc``, in a new process."""
    source = tmp_path / "in.npz"
    vertices = np.random.default_rng(5).standard_normal((40, 600, 3))
    save_sequence(MeshSequence(vertices, np.array([[0, 1, 2], [2, 3, 4]])), source)
    return subprocess.run(
        [sys.executable, "-m", "tuckercodec", "convert", str(source), str(folder / "out.abc")],
        cwd=REPOSITORY,
        capture_output=True,
        text=True,
        timeout=300,
        preexec_fn=_small_file_limit if limit else None,
        check=False,
    )


@pytest.mark.parametrize("disk", ["file size limit", "full tmpfs"])
def test_a_full_disk_is_one_line_and_exit_1_leaving_nothing(disk, tmp_path, request):
    if disk == "full tmpfs":
        folder = request.getfixturevalue("full_tmpfs")
    else:
        folder = tmp_path / "out"
        folder.mkdir()
    done = _convert_into(folder, tmp_path, limit=disk == "file size limit")
    assert done.returncode == 1, done.stderr  # not killed by a signal (-6: SIGABRT)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"tuckercodec: {folder / 'out.abc'}: "), lines
    assert "Alembic could not write it" in lines[0]
    if disk == "full tmpfs":
        assert "no space left on device" in lines[0]
    assert list(folder.iterdir()) == []  # neither the output nor its staging file


def _aborting_writer(path: Path, arrays: dict[str, Any], values: dict[str, Any]) -> None:
    """What alembic3d does when the disk fills as the archive is released on return."""
    path.write_bytes(b"Ogawa, half")
    os.abort()


def test_a_writer_that_aborts_is_an_oserror_naming_the_output(cloth, tmp_path, monkeypatch):
    from tuckercodec.io import alembic

    monkeypatch.setattr(alembic, "write_archive_file", _aborting_writer)  # run in the child
    with pytest.raises(OSError, match=r"Alembic library died writing it \(SIGABRT\)") as raised:
        save_sequence(cloth, tmp_path / "out.abc")
    assert raised.value.filename == str(tmp_path / "out.abc")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------------
# archives made here with alembic3d: other writers' conventions


def make_archive(
    path: Path,
    meshes: dict[str, list[Any]],
    *,
    rate: float | None = None,
    sampling: object | None = None,
    extra_objects: bool = False,
) -> Path:
    """An archive with one PolyMesh ``/<name>/<name>Shape`` per entry: its samples, each
    positions or (positions, counts, indices). ``rate`` writes a DCC FPS (not ours);
    ``sampling`` is the meshes' time sampling (default uniform 1/24 s from 0)."""
    archive = (
        Abc.OArchive(str(path))
        if rate is None
        else Abc.CreateArchiveWithInfo(str(path), rate, "test writer", "")
    )
    index = archive.addTimeSampling(sampling or AbcCoreAbstract.TimeSampling(1 / 24, 0.0))
    keep = []
    for name, samples in meshes.items():
        xform = AbcGeom.OXform(archive.getTop(), name)
        mesh = AbcGeom.OPolyMesh(xform, f"{name}Shape", index)
        for sample in samples:
            points, *topology = sample if isinstance(sample, tuple) else (sample,)
            arrays = [imath.V3fArrayFromBuffer(np.ascontiguousarray(points, np.float32))]
            if topology:
                counts, indices = (np.asarray(a, dtype=np.int32) for a in topology)
                arrays += [imath.IntArrayFromBuffer(indices), imath.IntArrayFromBuffer(counts)]
            mesh.getSchema().set(AbcGeom.OPolyMeshSchemaSample(*arrays))
        keep += [xform, mesh]
    if extra_objects:
        keep.append(AbcGeom.OPoints(archive.getTop(), "cloud", index))
        keep.append(AbcGeom.OXform(archive.getTop(), "empty"))
    del keep, archive  # the archive is written when its last object goes
    return path


def quad_samples(count: int, **changes: Any) -> list[Any]:
    """``count`` samples of a moving quad (two triangles, clockwise as Alembic stores them)."""
    samples: list[Any] = [(QUAD, [3, 3], [2, 1, 0, 3, 2, 0])]
    samples += [QUAD + frame for frame in range(1, count)]
    for frame, replacement in changes.items():
        samples[int(frame.lstrip("f"))] = replacement
    return samples


def test_faces_are_read_counter_clockwise(tmp_path):
    path = make_archive(tmp_path / "a.abc", {"quad": quad_samples(3)})
    seq = load_sequence(path)
    assert seq.faces.tolist() == [[0, 1, 2], [0, 2, 3]]
    normal = np.cross(*(seq.vertices[0][seq.faces[0][1:]] - seq.vertices[0][seq.faces[0][0]]))
    assert normal[2] > 0  # the quad lies in z = 0 and faces +z, as its stored clockwise order says


def test_rates_from_other_writers(tmp_path):
    # the DCC FPS hint (6 decimals: NTSC recognised), a uniform sampling's rate, or none
    sampling = AbcCoreAbstract.TimeSampling(1001 / 30000, 1001 / 30000)
    ntsc = load_sequence(
        make_archive(
            tmp_path / "a.abc", {"q": quad_samples(3)}, rate=30000 / 1001, sampling=sampling
        )
    )
    assert ntsc.time_codes is not None
    assert ntsc.frame_rate == 30000 / 1001 and ntsc.time_codes.tolist() == [1.0, 2.0, 3.0]
    sampling = AbcCoreAbstract.TimeSampling(1 / 25, 4 / 25)
    pal = load_sequence(make_archive(tmp_path / "b.abc", {"q": quad_samples(2)}, sampling=sampling))
    assert pal.time_codes is not None
    assert pal.frame_rate == 25.0 and pal.time_codes.tolist() == [4.0, 5.0]
    times = AbcCoreAbstract.TimeVector()
    times.extend([0.5, 0.75, 2.0])
    acyclic = AbcCoreAbstract.TimeSampling(
        AbcCoreAbstract.TimeSamplingType(AbcCoreAbstract.AcyclicFlag.kAcyclic), times
    )
    loose = load_sequence(
        make_archive(tmp_path / "c.abc", {"q": quad_samples(3)}, sampling=acyclic)
    )
    assert loose.time_codes is not None
    assert loose.frame_rate is None and loose.time_codes.tolist() == [12.0, 18.0, 48.0]
    assert loose.seconds().tolist() == [0.5, 0.75, 2.0]


def test_kept_time_codes_are_used_only_where_they_agree_with_the_times(tmp_path):
    codes = np.array([0.0, 1 / 3, 1.0, 2.0, 8171.509356676778])  # no time x 24 gives the last
    path = tmp_path / "k.abc"
    save_sequence(polygon_sequence(24.0, tuple(codes)), path)
    data = path.read_bytes()
    assert CODES_KEY.encode() in data and RATE_KEY.encode() in data
    kept = load_sequence(path).time_codes
    assert kept is not None and np.array_equal(kept, codes)
    # a kept code that disagrees with its sample's time is not believed: the times rule
    at = data.find(codes.tobytes())
    assert at > 0
    path.write_bytes(data[:at] + np.array([0.0, 999.0]).tobytes() + data[at + 16 :])
    back = load_sequence(path).time_codes
    assert back is not None
    assert back[1] == 1 / 3 and abs(back[4] - codes[4]) < 1e-9 * codes[4]


# ------------------------------------------------------------------------------------------
# choosing a mesh


def test_several_meshes_need_object_and_object_chooses(tmp_path):
    path = make_archive(
        tmp_path / "s.abc", {"a": quad_samples(2), "b": quad_samples(4)}, extra_objects=True
    )
    error = expect_input_error(lambda: load_sequence(path), path, match="--object")
    assert "holds 2 meshes: /a/aShape, /b/bShape" in str(error)
    assert load_sequence(path, object_path="/b/bShape").frame_count == 4
    for wanted, message in [
        ("/b", r"object /b is not a PolyMesh \(AbcGeom_Xform_v3\)"),
        ("/cloud", r"object /cloud is not a PolyMesh \(AbcGeom_Points_v1\)"),
        ("/nothing", "there is no object /nothing"),
        ("bShape", "there is no object bShape"),
    ]:
        error = expect_input_error(
            functools.partial(load_sequence, path, object_path=wanted), path, match=message
        )
        assert "the meshes are: /a/aShape, /b/bShape" in str(error)


def test_an_archive_without_meshes_says_so(tmp_path):
    path = make_archive(tmp_path / "e.abc", {}, extra_objects=True)
    expect_input_error(lambda: load_sequence(path), path, match="holds no PolyMesh")


def test_object_does_not_apply_to_other_formats(cloth, tmp_path):
    path = tmp_path / "c.npz"
    save_sequence(cloth, path)
    with pytest.raises(InputError, match=r"--object \(object_path\) does not apply.*alembic"):
        load_sequence(path, object_path="/c/cShape")


# ------------------------------------------------------------------------------------------
# odd and broken archives


def test_faces_that_change_are_refused_naming_the_frame(tmp_path):
    samples = quad_samples(4, f2=(QUAD, [4], [3, 2, 1, 0]))
    path = make_archive(tmp_path / "t.abc", {"a": samples})
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=2,
        match=r"object /a/aShape: the faces change at time 0\.083",
    )


def test_a_point_count_that_changes_is_refused_naming_the_frame(tmp_path):
    path = make_archive(tmp_path / "t.abc", {"a": quad_samples(3, f1=QUAD[:3])})
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=1,
        match="object /a/aShape: 3 positions at time 0.041666666666666664 s, where frame 0 has 4",
    )


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_non_finite_position_names_the_frame_and_vertex(tmp_path, value):
    bad = QUAD.copy()
    bad[2, 0] = value
    path = make_archive(tmp_path / "n.abc", {"a": quad_samples(3, f2=bad)})
    expect_input_error(
        lambda: load_sequence(path),
        path,
        frame=2,
        match="object /a/aShape: vertex 2 has a non-finite coordinate",
    )


def test_broken_faces_are_refused_naming_the_object(tmp_path):
    samples = quad_samples(2, f0=(QUAD, [3, 3], [2, 1, 0, 3, 2, 9]))
    path = make_archive(tmp_path / "f.abc", {"a": samples})
    expect_input_error(
        lambda: load_sequence(path),
        path,
        match="object /a/aShape: face 1 has a vertex index 9 outside 0..3",
    )


def _good_archive(tmp_path: Path) -> bytes:
    path = tmp_path / "good.abc"
    save_sequence(polygon_sequence(), path)
    return path.read_bytes()


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda good: good[: len(good) // 2], "cannot read as an Alembic archive"),
        (lambda good: good[:100], "cannot read as an Alembic archive"),
        (lambda good: b"", "cannot read as an Alembic archive"),
        (lambda good: bytes(range(256)) * 8, "cannot read as an Alembic archive"),
        (lambda good: b"\x89HDF\r\n\x1a\n" + bytes(500), "HDF5 Alembic archive.*abcconvert"),
    ],
)
def test_a_truncated_or_garbage_archive_is_refused_quietly(tmp_path, make, message, capfd):
    path = tmp_path / "bad.abc"
    path.write_bytes(make(_good_archive(tmp_path)))
    expect_input_error(lambda: load_sequence(path), path, match=message)
    assert capfd.readouterr().err == ""


def test_an_object_name_that_is_not_utf8_is_refused(tmp_path):
    path = make_archive(tmp_path / "n.abc", {"named": quad_samples(2)})
    data = path.read_bytes()
    assert data.count(b"namedShape") == 1
    path.write_bytes(data.replace(b"namedShape", b"nam\xffdShape"))  # same length: sound file
    expect_input_error(lambda: load_sequence(path), path, match="cannot read as an Alembic")


def test_a_missing_alembic3d_names_the_extra(cloth, tmp_path, monkeypatch):
    path = tmp_path / "c.abc"
    save_sequence(cloth, path)
    monkeypatch.setitem(sys.modules, "alembic3d.Abc", None)  # import alembic3d.Abc now fails
    with pytest.raises(DependencyError, match=r"pip install 'tuckercodec\[alembic\]'"):
        load_sequence(path)
    with pytest.raises(DependencyError, match=r"tuckercodec\[alembic\]"):
        save_sequence(cloth, tmp_path / "d.abc")
    assert not (tmp_path / "d.abc").exists()


# ------------------------------------------------------------------------------------------
# interop and the command line


@pytest.mark.skipif(
    shutil.which("abcls") is None or shutil.which("abcecho") is None,
    reason="Alembic's command-line tools (abcls, abcecho) are not installed: no Debian package "
    "ships them (Debian's 'alembic' is SQLAlchemy's migration tool); build Alembic with "
    "USE_BINARIES to run this",
)
def test_alembics_own_tools_list_the_object_and_its_samples(cloth, tmp_path):
    path = tmp_path / "cloth.abc"
    save_sequence(cloth, path)
    listed = subprocess.run(
        ["abcls", "-r", str(path)], capture_output=True, text=True, check=True
    ).stdout
    assert "clothShape" in listed
    echoed = subprocess.run(
        ["abcecho", str(path)], capture_output=True, text=True, check=True
    ).stdout
    assert "/cloth/clothShape" in echoed and "60 samples" in echoed


def test_the_cli_encodes_decodes_and_converts_alembic(cloth, tmp_path, capsys):
    abc, packed, again = tmp_path / "out.abc", tmp_path / "x.tkc", tmp_path / "y.abc"
    assert main(["convert", "sample", str(abc)]) == 0
    assert main(["encode", str(abc), "-o", str(packed), "--kg", "0.5"]) == 0
    assert main(["decode", str(packed), "-o", str(again)]) == 0
    assert load_sequence(again).frame_count == 60
    path = make_archive(tmp_path / "two.abc", {"a": quad_samples(2), "b": quad_samples(3)})
    assert main(["convert", str(path), str(tmp_path / "b.usda"), "--object", "/b/bShape"]) == 0
    assert load_sequence(tmp_path / "b.usda").frame_count == 3
    assert main(["convert", str(path), str(tmp_path / "c.npz")]) == 4
    assert "--object" in capsys.readouterr().err
