"""A textured, animated character through ``encode`` and ``decode`` on the command line: every
UV, colour, normal and material subset back bit for bit, the velocities within their target,
the faces in their order, read by pxr itself (a reader nobody here wrote)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tools.generate import textured_character

pxr = pytest.importorskip("pxr", reason="usd-core (the 'usd' extra) is not installed")
from pxr import Usd, UsdGeom  # noqa: E402

FRAMES = 12


def _mesh(path: Path) -> tuple[Usd.Stage, UsdGeom.Mesh]:
    stage = Usd.Stage.Open(str(path))
    prim = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    return stage, UsdGeom.Mesh(prim)


def _primvar(mesh: UsdGeom.Mesh, name: str, time: float) -> tuple[str, bytes, np.ndarray | None]:
    primvar = UsdGeom.PrimvarsAPI(mesh).GetPrimvar(name)
    values = np.asarray(primvar.Get(time))
    indices = np.asarray(primvar.GetIndices()) if primvar.IsIndexed() else None
    return str(primvar.GetInterpolation()), values.tobytes(), indices


def _tuckercodec(*args: str) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "tuckercodec", *args], capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr


@pytest.fixture(scope="module")
def round_trip(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    folder = tmp_path_factory.mktemp("character")
    source = folder / "character.usdc"
    assert textured_character.main(["-o", str(source), "--frames", str(FRAMES)]) == 0
    compressed = folder / "character.tkc"
    _tuckercodec("encode", str(source), "-o", str(compressed), "--field", "velocities=rel:0.5")
    back = folder / "back.usdc"
    _tuckercodec("decode", str(compressed), "-o", str(back))
    return source, compressed, back


def test_uvs_colours_normals_and_faces_come_back_bit_for_bit(round_trip):
    source, _, back = round_trip
    stage, original = _mesh(source)
    _, decoded = _mesh(back)
    start = stage.GetStartTimeCode()
    assert np.array_equal(
        np.asarray(original.GetFaceVertexIndicesAttr().Get()),
        np.asarray(decoded.GetFaceVertexIndicesAttr().Get()),
    )
    for name in ("st", "displayColor", "normals"):
        before, after = _primvar(original, name, start), _primvar(decoded, name, start)
        assert before[:2] == after[:2], name
        indices = before[2], after[2]
        assert (indices[0] is None) == (indices[1] is None), name
        if indices[0] is not None and indices[1] is not None:
            assert np.array_equal(indices[0], indices[1]), name


def test_material_subsets_come_back_with_their_family(round_trip):
    source, _, back = round_trip

    def subsets(path: Path) -> dict[str, tuple[str, list[int]]]:
        _, mesh = _mesh(path)
        found = UsdGeom.Subset.GetAllGeomSubsets(UsdGeom.Imageable(mesh.GetPrim()))
        return {
            s.GetPrim().GetName(): (
                str(s.GetFamilyNameAttr().Get()),
                list(s.GetIndicesAttr().Get()),
            )
            for s in found
        }

    assert subsets(back) == subsets(source)
    assert {family for family, _ in subsets(back).values()} == {"materialBind"}


def test_velocities_meet_their_target(round_trip):
    source, _, back = round_trip
    stage, original = _mesh(source)
    _, decoded = _mesh(back)
    codes = [stage.GetStartTimeCode() + f for f in range(FRAMES)]
    a = np.stack([np.asarray(original.GetVelocitiesAttr().Get(t), dtype=np.float64) for t in codes])
    b = np.stack([np.asarray(decoded.GetVelocitiesAttr().Get(t), dtype=np.float64) for t in codes])
    relative = 100 * np.linalg.norm(a - b) / np.linalg.norm(a - a.mean(axis=1, keepdims=True))
    assert 0 < relative <= 0.5


def test_info_lists_what_the_file_carries(round_trip):
    _, compressed, _ = round_trip
    done = subprocess.run(
        [sys.executable, "-m", "tuckercodec", "info", str(compressed)],
        capture_output=True,
        text=True,
        check=True,
    )
    for line in (
        "attribute 'st': corner, uv, f32 x 2",
        "attribute 'displayColor': face, color",
        "face sets: 2 sets, families materialBind",
        "field 'velocities': vertex, velocity, f32 x 3, mode tucker",
        "face order: kept as given",
    ):
        assert line in done.stdout, line
