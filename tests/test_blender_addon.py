"""The Blender add-on (tuckercodec.blender): its array work and its zip anywhere, and the add-on
itself in headless Blender (the ``bpy`` wheel) where that is installed.

The Blender half runs one Blender session per module in a process of its own
(tests/support/blender_session.py), so that a crash of Blender fails these tests instead of
ending pytest; the session reports what Blender showed, and this module compares it with the
Python decoder.
"""

from __future__ import annotations

import base64
import dataclasses
import hashlib
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import pytest

import tuckercodec
from tests.support.compressed import chunked_file
from tests.support.inputs import measure
from tuckercodec import (
    Decoder,
    DependencyError,
    InputError,
    MeshSequence,
    kg_error,
    max_vertex_displacement,
)
from tuckercodec.blender import package
from tuckercodec.blender.meshes import (
    BAKE_FRAMES,
    BLENDER_LIMITS,
    MAX_FRAME,
    ExportFrames,
    bake_pc2,
    bake_span,
    file_frame,
    loop_arrays,
    placement,
    scene_frames,
    scene_range,
    scene_rate,
)
from tuckercodec.blender.package import ADDON_ID, build_own_wheel, manifest
from tuckercodec.cli import main
from tuckercodec.format.limits import DEFAULT_LIMITS
from tuckercodec.io.common.polygons import faces_from_polygons, polygons_from_faces
from tuckercodec.io.pointcache.pc2 import HEADER

SESSION = Path(__file__).parent / "support" / "blender_session.py"
#: The triangles of the crafted file the Blender session imports to weigh an import.
MANY_FACES = 1 << 18
NO_BPY = (
    "needs Blender's bpy module: pip install 'bpy<5' (the bpy 4.x wheels, for Python 3.11; "
    "about 370 MB)"
)

# ------------------------------------------------------------------------------------------
# the add-on's array work, without Blender


def test_faces_become_blender_polygons_and_come_back():
    # Blender's loops (vertex indices, polygon after polygon) and loop totals are the corner
    # counts and flat indices of io.common.polygons, which the add-on reads them with
    faces = np.array([[0, 1, 2, -1], [2, 1, 3, 4], [4, 3, 5, -1]])
    totals, loops = polygons_from_faces(faces)
    assert loops.tolist() == [0, 1, 2, 2, 1, 3, 4, 4, 3, 5]
    assert totals.tolist() == [3, 4, 3]
    np.testing.assert_array_equal(faces_from_polygons(totals, loops, 6), faces)
    triangles = np.array([[0, 1, 2], [2, 1, 3]])
    np.testing.assert_array_equal(
        faces_from_polygons(*polygons_from_faces(triangles), 4), triangles
    )


def test_scene_frames_map_to_the_files_frames_held_at_the_ends():
    assert [file_frame(f, 1, 60) for f in (1, 2, 60)] == [0, 1, 59]
    assert file_frame(-5, 1, 60) == 0 and file_frame(100, 1, 60) == 59
    assert file_frame(1001, 1001, 10) == 0


def test_the_scene_rate_is_the_files():
    assert scene_rate(24.0) == (24, 1.0)
    fps, base = scene_rate(29.97)
    assert fps == 30 and fps / base == pytest.approx(29.97)
    assert scene_rate(None) == (24, 1.0)


def test_an_export_refuses_a_change_of_topology_naming_the_frame_and_object():
    frames = ExportFrames("Cube")
    faces = np.array([[0, 1, 2]])
    frames.add(1, np.zeros((3, 3)), faces)
    frames.add(2, np.ones(9), faces)  # flat values, as foreach_get gives them
    with pytest.raises(InputError, match=r"'Cube' changes topology at frame 3:.*different faces"):
        frames.add(3, np.zeros((3, 3)), np.array([[0, 2, 1]]))
    with pytest.raises(InputError, match=r"'Cube' changes topology at frame 4: 4 vertices"):
        frames.add(4, np.zeros((4, 3)), faces)
    sequence = frames.sequence(25.0)
    assert sequence.vertices.shape == (2, 3, 3) and sequence.frame_rate == 25.0


def test_a_face_table_becomes_blenders_loop_starts_and_corners_in_order():
    faces = np.array([[0, 1, 2, -1], [2, 1, 3, 4], [4, 3, 5, -1]])
    starts, corners = loop_arrays(faces)
    assert starts.dtype == corners.dtype == np.int32
    assert starts.tolist() == [0, 3, 7]
    assert corners.tolist() == [0, 1, 2, 2, 1, 3, 4, 4, 3, 5]
    assert [a.size for a in loop_arrays(np.zeros((0, 3), np.int64))] == [0, 0]


def spread_file(spans: float = 199_999.0, first: float = 0.0) -> bytes:
    """A small file whose 24 time codes spread over ``spans`` scene frames from ``first``: 24
    frames of 81 vertices (a 9 x 9 grid) that a bake holds over every scene frame between."""
    rows = np.arange(81)
    grid = np.stack([rows % 9, rows // 9, np.zeros(81)], axis=1).astype(np.float64)
    frames = np.stack([grid + np.array([0, 0, 0.1 * f]) for f in range(24)])
    faces = np.array(
        [[r * 9 + c, r * 9 + c + 1, r * 9 + c + 10] for r in range(8) for c in range(8)]
    )
    codes = first + np.round(np.linspace(0.0, spans, 24))
    return tuckercodec.encode(MeshSequence(frames, faces, time_codes=codes), target_kg=0.5)


def test_a_bake_is_bounded_and_holds_one_frame_in_memory_whatever_its_span(tmp_path):
    """24 time codes spread over 200,000 scene frames: a bake is refused beyond Max Bake
    Frames, naming the span and the limit; asked for, it writes the whole cache holding one
    frame at a time (decoding every frame shown first took 1.08 GB for a 194 MB cache)."""
    (tmp_path / "spread.tkc").write_bytes(spread_file())
    decoder = Decoder(tmp_path / "spread.tkc", limits=BLENDER_LIMITS)
    cache = tmp_path / "spread.pc2"
    with pytest.raises(
        InputError, match=f"24 frames span 200000 scene frames, beyond the {BAKE_FRAMES}"
    ):
        bake_pc2(decoder, cache, 1)
    assert not cache.exists()
    assert bake_span(decoder, 1, 200_000) == 200_000
    error, _, peak = measure(lambda: bake_pc2(decoder, cache, 1, max_frames=200_000))
    assert error is None, error
    written = cache.stat().st_size
    assert written == HEADER.size + 200_000 * 81 * 12
    assert peak < 2_000_000, peak  # a frame and a chunk of frame numbers, not 194 MB
    baked = tuckercodec.load_sequence(cache, progress=False)
    codes = decoder.info.time_codes
    for scene in (0, 1, 8695, 8696, 199_999):  # 8696: the second time code, then held
        expected = decoder.frame(file_frame(1 + scene, 1, 24, codes)).astype(np.float32)
        np.testing.assert_array_equal(baked.vertices[scene].astype(np.float32), expected)
    with pytest.raises(FileExistsError):
        bake_pc2(decoder, cache, 1, max_frames=200_000)


def test_frames_beyond_blenders_are_refused_before_an_import_makes_anything():
    """A first time code of 2**31 overflowed the object's 32-bit property half-way through
    an import; every end is checked against Blender's frames first."""
    assert scene_range(1.0, 60, None) == (1, 60)
    assert scene_range(1001.0, 12, [1001.0, 1013.0]) == (1001, 1013)
    assert scene_range(-MAX_FRAME, 1, None) == (-MAX_FRAME, -MAX_FRAME)
    for first, count, codes in [
        (2.0**31, 2, [2.0**31, 2.0**31 + 1]),
        (MAX_FRAME, 2, None),
        (1.0, 3, [0.0, 1.0, 2.0 * MAX_FRAME]),
        (float("nan"), 1, None),
        (-float("inf"), 1, None),
    ]:
        with pytest.raises(InputError, match=r"beyond Blender's frames \(-1048574 to 1048574\)"):
            scene_range(first, count, codes)


def test_blenders_decoder_limits_are_no_looser_than_the_defaults(cloth):
    for field in dataclasses.fields(BLENDER_LIMITS):
        assert getattr(BLENDER_LIMITS, field.name) <= getattr(DEFAULT_LIMITS, field.name)
    assert BLENDER_LIMITS.max_header_bytes <= 1 << 20
    assert BLENDER_LIMITS.max_section_bytes <= 1 << 29
    data = tuckercodec.encode(cloth, target_kg=0.5)
    assert Decoder(data, limits=BLENDER_LIMITS).frame(59).shape == (3101, 3)


# ------------------------------------------------------------------------------------------
# the zip, without Blender


def test_the_manifest_lists_the_extension_its_platforms_and_wheels():
    text = manifest(["linux-x64", "windows-x64"], ["a-1-py3-none-any.whl"])
    parsed = tomllib.loads(text)
    assert parsed["id"] == ADDON_ID == "tuckercodec_blender"
    assert parsed["version"] == tuckercodec.__version__
    assert parsed["type"] == "add-on" and parsed["blender_version_min"] == "4.2.0"
    assert parsed["platforms"] == ["linux-x64", "windows-x64"]
    assert parsed["wheels"] == ["./wheels/a-1-py3-none-any.whl"]


def test_the_own_wheel_holds_the_package_and_a_record_that_checks(tmp_path):
    wheel = build_own_wheel(tmp_path)
    assert wheel.name == f"tuckercodec-{tuckercodec.__version__}-py3-none-any.whl"
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        info = f"tuckercodec-{tuckercodec.__version__}.dist-info"
        record = archive.read(f"{info}/RECORD").decode().splitlines()
        for line in record:
            name, digest, size = line.rsplit(",", 2)
            if name == f"{info}/RECORD":
                continue
            data = archive.read(name)
            expected = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=")
            assert digest == f"sha256={expected.decode()}" and int(size) == len(data), name
    assert {line.rsplit(",", 2)[0] for line in record} == names
    for needed in (
        "tuckercodec/decoder.py",
        "tuckercodec/blender/addon.py",
        "tuckercodec/py.typed",
    ):
        assert needed in names
    assert not any("__pycache__" in name or name.endswith(".pyc") for name in names)


def test_the_own_wheel_takes_only_declared_files_never_hidden_ones_or_links(tmp_path):
    """A developer's package folder holds more than the package: a ``.env``, editor and
    tool files, links to files elsewhere. The wheel takes the Python modules and pyproject's
    package data only, no hidden file or folder, and follows no symbolic link."""
    source = tmp_path / "src" / "tuckercodec"
    shutil.copytree(
        Path(tuckercodec.__file__).parent,
        source,
        symlinks=True,
        ignore=shutil.ignore_patterns("__pycache__"),
    )
    elsewhere = tmp_path / "elsewhere"
    (elsewhere / "pkg").mkdir(parents=True)
    (elsewhere / "secret.py").write_text("TOKEN = 'tkc-test-secret'\n")
    (elsewhere / "pkg" / "__init__.py").write_text("TOKEN = 'tkc-test-secret'\n")
    (source / ".env").write_text("API_TOKEN=tkc-test-secret\n")
    (source / "blender" / ".env").write_text("API_TOKEN=tkc-test-secret\n")
    (source / ".idea").mkdir()
    (source / ".idea" / "workspace.py").write_text("")
    (source / ".hidden.py").write_text("")
    (source / "web" / "vendor" / "three" / ".DS_Store").write_bytes(b"\0")
    (source / "notes.txt").write_text("not package data")  # no pattern declares it
    (source / "linked.py").symlink_to(elsewhere / "secret.py")
    (source / "linked_package").symlink_to(elsewhere / "pkg", target_is_directory=True)
    (source / "web" / "vendor" / "three" / "linked.js").symlink_to(elsewhere / "secret.py")
    wheel = build_own_wheel(tmp_path, root=source)
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        shipped = b"".join(archive.read(name) for name in names)
    assert "tkc-test-secret" not in shipped.decode("latin-1")
    for stray in (".env", ".idea", ".hidden.py", ".DS_Store", "notes.txt", "linked"):
        assert not any(stray in name for name in names), (stray, sorted(names))
    for needed in ("tuckercodec/decoder.py", "tuckercodec/py.typed", "tuckercodec/data/"):
        assert any(name.startswith(needed) for name in names), needed
    assert "tuckercodec/web/vendor/three/LICENSE" in names


def test_the_wheels_patterns_are_pyprojects_package_data():
    config = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    declared = config["tool"]["setuptools"]["package-data"]["tuckercodec"]
    assert tuple(declared) == package.PACKAGE_DATA


def test_the_command_refuses_an_existing_zip_before_any_work(tmp_path, capsys):
    existing = tmp_path / "addon.zip"
    existing.write_bytes(b"mine")
    assert main(["blender-addon", str(existing)]) == 1
    err = capsys.readouterr().err
    assert "already exists" in err and "--force" in err and len(err.splitlines()) == 1
    assert existing.read_bytes() == b"mine"


def _fake_downloads(platform_name, folder):
    """Stand-in for pip download: one empty 'wheel' per requirement, as pip names them."""
    target = folder / platform_name
    target.mkdir()
    tag = "win_amd64" if platform_name == "windows-x64" else "manylinux_2_17_x86_64"
    wheels = [target / f"{name}-1.0-cp311-cp311-{tag}.whl" for name in ("msgpack", "scipy")]
    wheels.append(folder / "zstandard-1.0-py3-none-any.whl")  # the same file for every platform
    for wheel in wheels:
        wheel.write_bytes(platform_name.encode())
    return wheels


def test_the_zip_holds_the_manifest_the_loader_and_each_wheel_once(tmp_path, monkeypatch):
    monkeypatch.setattr(package, "download_wheels", _fake_downloads)
    written = package.write_addon_zip(tmp_path / "addon.zip", ["linux-x64", "windows-x64"])
    with zipfile.ZipFile(written.path) as archive:
        names = archive.namelist()
        parsed = tomllib.loads(archive.read("blender_manifest.toml").decode())
        loader = archive.read("__init__.py").decode()
    assert parsed["platforms"] == ["linux-x64", "windows-x64"]
    assert parsed["wheels"] == [f"./wheels/{name}" for name in written.wheels]
    assert len(written.wheels) == 6  # tuckercodec, 2 + 2 platform wheels, zstandard once
    assert sorted(names) == sorted(
        ["blender_manifest.toml", "__init__.py"] + [f"wheels/{name}" for name in written.wheels]
    )
    assert "from tuckercodec.blender.addon import register, unregister" in loader
    assert written.size == (tmp_path / "addon.zip").stat().st_size


def test_a_failed_download_names_the_platform_and_leaves_no_zip(tmp_path, monkeypatch):
    said = "ERROR: No matching distribution found for scipy<1.17,>=1.11"
    monkeypatch.setattr(
        subprocess,  # the module package.py calls pip through
        "run",
        lambda *args, **kwargs: subprocess.CompletedProcess(args, 1, stdout="", stderr=said),
    )
    with pytest.raises(DependencyError, match=r"wheels for macos-arm64 .*No matching distribution"):
        package.write_addon_zip(tmp_path / "addon.zip", ["macos-arm64"])
    assert list(tmp_path.iterdir()) == []


def test_an_unknown_platform_is_refused_before_any_work(tmp_path):
    with pytest.raises(ValueError, match="unknown platform 'amiga-68k'"):
        package.write_addon_zip(tmp_path / "addon.zip", ["amiga-68k"])
    assert list(tmp_path.iterdir()) == []
    assert package.current_platform() in package.PLATFORM_TAGS


# ------------------------------------------------------------------------------------------
# the add-on in headless Blender

needs_bpy = pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason=NO_BPY)


class Session(NamedTuple):
    """What one Blender session did (tests/support/blender_session.py)."""

    tkc: Path  # the file imported
    work: Path  # its folder, where the session exported and baked
    report: dict[str, Any]  # session.json
    arrays: dict[str, np.ndarray]  # session.npz: faces, evaluated vertices by scene frame
    stdout: str  # Blender's reports


@pytest.fixture(scope="module")
def session(cloth, tmp_path_factory) -> Session:
    """The zip built by the command line, and one Blender session that installs it, plays the
    cloth (encoded at KG 0.1, at 29.97 fps) and exports it back."""
    work = tmp_path_factory.mktemp("blender")
    tkc = work / "cloth.tkc"
    tkc.write_bytes(tuckercodec.encode(dataclasses.replace(cloth, frame_rate=29.97), target_kg=0.1))
    (work / "film.tkc").write_bytes(tuckercodec.encode(_film(cloth), target_kg=0.5))
    (work / "far.tkc").write_bytes(spread_file(23.0, first=2.0**31))
    (work / "spread.tkc").write_bytes(spread_file())
    (work / "many_faces.tkc").write_bytes(chunked_file(1 << 16, 2, 1, face_count=MANY_FACES))
    addon = work / "tuckercodec_blender.zip"
    assert main(["blender-addon", str(addon)]) == 0
    environment = {name: value for name, value in os.environ.items() if name != "PYTHONPATH"}
    environment["BLENDER_USER_RESOURCES"] = str(work / "user")  # not the user's own Blender
    done = subprocess.run(
        [sys.executable, str(SESSION), str(addon), str(tkc), str(work)],
        capture_output=True,
        text=True,
        env=environment,
        cwd=work,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, f"the Blender session failed:\n{done.stdout}\n{done.stderr}"
    report = json.loads((work / "session.json").read_text())
    with np.load(work / "session.npz") as arrays:
        return Session(tkc, work, report, dict(arrays), done.stdout)


@needs_bpy
def test_blender_installs_the_zip_with_its_own_wheels(session):
    report = session.report
    assert report["install"] == ["FINISHED"] and report["enabled"]
    # the package came from the wheel the zip bundles, not from this checkout
    site = Path(report["extensions_folder"]) / ".local" / "lib"
    assert Path(report["tuckercodec_file"]).is_relative_to(site)
    assert report["tuckercodec_file"].endswith("site-packages/tuckercodec/__init__.py")


#: Run with the extension's site-packages first on the path: the bundled wheels alone decode
#: and encode (in Blender the host's modules may win: here the test venv has its own scipy).
BUNDLED_CHECK = """
import json, sys
import msgpack, scipy, scipy.linalg, zstandard
import tuckercodec
decoder = tuckercodec.Decoder(sys.argv[1])
sequence = decoder.sequence()
result = tuckercodec.encode_with_report(sequence, target_kg=0.5)
print(json.dumps({
    "files": [module.__file__ for module in (msgpack, scipy, zstandard, tuckercodec)],
    "kg": tuckercodec.kg_error(sequence, tuckercodec.decode(result.data)),
}))
"""


@needs_bpy
def test_the_bundled_wheels_decode_and_encode_on_their_own(session):
    local = Path(session.report["extensions_folder"]) / ".local" / "lib"
    site = next(local.glob("python*/site-packages"))
    assert {"scipy", "msgpack", "zstandard", "tuckercodec"} <= {p.name for p in site.iterdir()}
    environment = {**os.environ, "PYTHONPATH": str(site)}
    done = subprocess.run(
        [sys.executable, "-c", BUNDLED_CHECK, str(session.tkc)],
        capture_output=True,
        text=True,
        env=environment,
        cwd=session.work,  # not this checkout, which `python -c` would put first on the path
        check=False,
    )
    assert done.returncode == 0, done.stderr
    checked = json.loads(done.stdout)
    assert all(Path(file).is_relative_to(site) for file in checked["files"]), checked["files"]
    assert 0 < checked["kg"] <= 0.5


@needs_bpy
def test_an_imported_tkc_plays_the_decoders_frames(session):
    tkc, _, report, arrays, stdout = session
    decoder = Decoder(tkc)
    np.testing.assert_array_equal(arrays["faces"], decoder.faces)
    assert report["frame_range"] == [1, 60]
    assert report["fps"] == pytest.approx(29.97)
    for key in (key for key in arrays if key.startswith("frame_")):
        frame = int(key.removeprefix("frame_"))
        expected = decoder.frame(frame - 1).astype(np.float32)
        np.testing.assert_array_equal(arrays[key], expected, err_msg=f"scene frame {frame}")
    assert "decoded on demand" in stdout


@needs_bpy
def test_a_render_plays_the_decoders_frames(session):
    """What the render's own depsgraph evaluated at each frame it rendered (Cycles)."""
    assert session.report["rendered"] == ["render_0005.png", "render_0006.png"]
    decoder = Decoder(session.tkc)
    for frame in (5, 6):
        expected = decoder.frame(frame - 1).astype(np.float32)
        np.testing.assert_array_equal(session.arrays[f"render_{frame}"], expected)


@needs_bpy
def test_a_saved_blend_plays_its_paths_only_when_asked(session):
    """A path saved in a .blend is not opened when the .blend opens or its frames change: a
    crafted .blend could name any file, decoded at the first frame change with no prompt.
    Enable .tkc Playback opens it; a file that fails is tried once, not at every frame."""
    report, arrays = session.report, session.arrays
    expected = Decoder(session.tkc).frame(32).astype(np.float32)
    assert report["opened_unasked"] == []
    assert not np.array_equal(arrays["reopened_33_unasked"], expected)  # the mesh as saved
    np.testing.assert_array_equal(arrays["reopened_33"], expected)
    assert "object 'stranger'" in report["enable"] and "broken.tkc" in report["enable"]
    assert sorted(report["opened_asked"]) == ["broken.tkc", "cloth.tkc"]  # each once
    assert "not opened until you ask" in session.stdout


@needs_bpy
def test_frames_beyond_blenders_and_a_bake_beyond_its_limit_are_refused_leaving_nothing(session):
    report = session.report
    assert "beyond Blender's frames (-1048574 to 1048574)" in report["far"]
    assert "far.tkc" in report["far"] and report["far_objects"] == 0
    assert f"span 200000 scene frames, beyond the {BAKE_FRAMES}" in report["spread"]
    assert report["spread_objects"] == 0 and not report["spread_cache"]


@needs_bpy
def test_an_import_builds_the_mesh_from_arrays_not_python_lists(session):
    """A mesh of many faces costs the import about what decoding them costs: the faces go to
    Blender as arrays, not as a Python list per face (2**18 faces: 21 MiB of lists, and more
    for ``from_pydata``'s tuples, against a 6 MiB face table)."""
    report = session.report
    assert report["many_faces"] == MANY_FACES
    face_table = MANY_FACES * 3 * 8  # the decoder's int64 table
    extra = report["many_faces_import_bytes"] - report["many_faces_decoding_bytes"]
    assert extra < 2 * face_table, (report["many_faces_import_bytes"], face_table)


@needs_bpy
def test_a_baked_import_plays_from_a_point_cache(session):
    tkc, work, report, arrays, _ = session
    assert report["bake"] == ["FINISHED"] and report["baked_modifiers"] == ["MESH_CACHE"]
    assert (work / "cloth.pc2").exists()
    expected = Decoder(tkc).frame(19).astype(np.float32)
    np.testing.assert_array_equal(arrays["baked_20"], expected)


@needs_bpy
def test_an_exported_object_meets_its_target_against_what_was_imported(session):
    tkc, work, report, _, stdout = session
    assert report["export"] == ["FINISHED"]
    imported, exported = Decoder(tkc), Decoder(work / "exported.tkc")
    assert exported.info.frames == 60 and exported.info.vertices == 3101
    assert exported.info.frame_rate == pytest.approx(29.97)
    np.testing.assert_array_equal(exported.faces, imported.faces)
    measured = kg_error(imported.positions(), exported.positions())
    assert 0 < measured <= 0.5
    assert "Exported 'cloth' to exported.tkc: 60 frames of 3101 vertices, KG error" in stdout


@needs_bpy
def test_the_exports_other_targets_are_met(session):
    assert session.report["export_modes"] == [["FINISHED"]] * 3
    imported = Decoder(session.tkc).positions().astype(np.float32)  # what Blender held
    assert Decoder(session.work / "bpfv.tkc").info.bpfv <= 1.0
    assert Decoder(session.work / "ranks.tkc").info.ranks == (6, 4)
    bounded = Decoder(session.work / "bounded.tkc")
    assert kg_error(imported, bounded.positions()) <= 1.0
    assert max_vertex_displacement(imported, bounded.positions()).distance <= 0.05


@needs_bpy
def test_the_export_refuses_an_existing_file_and_a_change_of_topology(session):
    _, work, report, _, _ = session
    assert "exported.tkc: already exists" in report["export_again"]
    assert "object 'Sphere' changes topology at frame 4" in report["topology"]
    assert not (work / "sphere.tkc").exists()
    assert re.search(r"'Camera[.\d]*' \(CAMERA\): select a mesh, curve or text", report["camera"])


def _film(cloth: MeshSequence) -> MeshSequence:
    """12 frames of the cloth as a film cache (format 1.4): time codes from 1001 with 1007
    missing, in centimetres, Y up, at 24 fps."""
    codes = np.delete(np.arange(1001.0, 1014.0), 6)
    return MeshSequence(
        cloth.vertices[:12],
        cloth.faces,
        frame_rate=24.0,
        time_codes=codes,
        meters_per_unit=0.01,
        up_axis="Y",
    )


def test_a_files_time_codes_place_its_frames_on_the_scene():
    codes = [1001.0, 1002.0, 1004.0]  # 1003 missing: frame 1 held there
    assert [file_frame(f, 1001, 3, codes) for f in (1000, 1001, 1002, 1003, 1004, 1010)] == [
        0,
        0,
        1,
        1,
        2,
        2,
    ]
    assert file_frame(5, 1, 3, codes) == 2  # placed from another first frame
    assert scene_frames(1001, 3, codes) == 4 and scene_frames(1, 3, None) == 3


def test_a_files_unit_and_up_axis_place_the_object():
    rotation, scale = placement(0.01, "Y", 1.0)
    assert rotation == pytest.approx(np.pi / 2) and scale == 0.01
    assert placement(1.0, "Z", 1.0) == (0.0, 1.0)
    assert placement(None, None, 0.01) == (0.0, 1.0)  # unknown: left as it is
    assert placement(1.0, None, 0.01) == (0.0, 100.0)  # metres in a centimetre scene


@needs_bpy
def test_a_film_cache_plays_at_its_time_codes_turned_and_scaled_into_the_scene(session):
    report, arrays = session.report, session.arrays
    assert report["film_range"] == [1001, 1013]
    assert report["film_rotation"] == pytest.approx([np.pi / 2, 0.0, 0.0])  # Y up to Z up
    assert report["film_scale"] == pytest.approx([0.01] * 3)  # centimetres in a metre scene
    decoder = Decoder(session.work / "film.tkc")
    shown = {1001: 0, 1006: 5, 1007: 5, 1008: 6, 1013: 11}  # 1007 holds the frame before
    for scene_frame, frame in shown.items():
        expected = decoder.frame(frame).astype(np.float32)
        np.testing.assert_array_equal(arrays[f"film_{scene_frame}"], expected)
        np.testing.assert_array_equal(arrays[f"film_baked_{scene_frame}"], expected)


@needs_bpy
def test_an_export_keeps_the_scene_frames_unit_and_axis_of_the_objects_space(session):
    assert session.report["film_export"] == ["FINISHED"]
    exported = Decoder(session.work / "film_export.tkc").info
    # every scene frame 1001..1013 (1007 holding the frame before), at its own number
    assert exported.time_codes == tuple(float(f) for f in range(1001, 1014))
    assert (exported.meters_per_unit, exported.up_axis) == (0.01, "Y")  # the file's space
    plain = Decoder(session.work / "exported.tkc").info  # an object without a file's space
    assert (plain.meters_per_unit, plain.up_axis) == (1.0, "Z")
    assert plain.time_codes == tuple(float(f) for f in range(1, 61))


@needs_bpy
def test_a_damaged_file_is_refused_naming_it(session):
    message = session.report["broken"]
    assert message.count("broken.tkc") == 1 and message.endswith("[R01-signature]\n")
