"""A textured animated mesh authored with pxr, as a DCC exports one: the input of the end-to-end
demo of attributes (UVs, normals, colours, materials, velocities through a ``.tkc``).

From the cloth shipped with the package (``cloth-vellum.npz``, MIT: 60 frames of 3101 vertices,
5912 triangles; ``--input`` another ``.npz`` with ``V`` (frames, vertices, 3) and ``F``), it
writes a USD stage (``-o OUT.usda`` or ``.usdc``) whose ``/Root/character`` Mesh has:

* ``points`` and ``extent`` sampled at every frame (time codes 0, 1, 2... at 24 per second);
* ``primvars:st`` (``texCoord2f[]``, faceVarying, indexed: one uv per vertex, the corners'
  indices naming them): frame 0 projected on its two widest axes, in [0, 1];
* ``primvars:normals`` (``normal3f[]``, vertex), sampled at every frame: each frame's
  area-weighted vertex normals, as a DCC bakes them;
* ``primvars:displayColor`` (``color3f[]``, uniform): one colour per face, its material's
  shaded along the uv's second axis;
* two GeomSubsets of family ``materialBind`` (a partition: stripes of frame 0 across the first
  uv axis), ``red`` and ``blue``, each bound to a UsdPreviewSurface of its colour;
* ``velocities`` (``vector3f[]``), sampled at every frame: central differences of the points
  (one-sided at the ends) times the frame rate.

``--frames N`` keeps the first N frames. The file is written beside its name and moved in
when complete; an existing one is replaced only with ``--force``. Needs usd-core (the ``usd``
extra).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from tuckercodec.internal import refuse_existing, sample_path

FPS = 24.0
#: The stripes of the two materials across the first uv axis.
STRIPES = 4
MATERIALS = {"red": (0.8, 0.15, 0.1), "blue": (0.1, 0.25, 0.8)}
MESH = "/Root/character"


def vertex_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals of a triangle mesh (0, 0, 1 where none is defined)."""
    corners = points[triangles].astype(np.float64)
    face = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    summed = np.zeros((len(points), 3))
    for corner in range(3):
        np.add.at(summed, triangles[:, corner], face)
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    normals = np.where(length > 0, summed / np.where(length > 0, length, 1), [0.0, 0.0, 1.0])
    return normals.astype(np.float32)


def planar_uvs(points: np.ndarray) -> np.ndarray:
    """Each vertex projected on the two widest axes of ``points``' bounding box, in [0, 1]."""
    low, high = points.min(axis=0), points.max(axis=0)
    axes = np.argsort(high - low)[::-1][:2]
    span = np.where(high - low > 0, high - low, 1.0)[axes]
    return ((points[:, axes] - low[axes]) / span).astype(np.float32)


def velocities(frames: np.ndarray) -> np.ndarray:
    """Central differences of the positions (one-sided at the ends) times :data:`FPS`."""
    if len(frames) == 1:
        return np.zeros_like(frames, dtype=np.float32)
    return (np.gradient(frames.astype(np.float64), axis=0) * FPS).astype(np.float32)


def author(path: Path, frames: np.ndarray, triangles: np.ndarray) -> None:
    """Write the stage (see the module docstring) to ``path`` as it stands."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt

    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetDefaultPrim(UsdGeom.Xform.Define(stage, "/Root").GetPrim())
    stage.SetTimeCodesPerSecond(FPS)
    stage.SetFramesPerSecond(FPS)
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(len(frames) - 1)
    mesh = UsdGeom.Mesh.Define(stage, MESH)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.full(len(triangles), 3, np.int32)))
    flat = np.ascontiguousarray(triangles.reshape(-1), dtype=np.int32)
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(flat))
    primvars = UsdGeom.PrimvarsAPI(mesh)

    uvs = planar_uvs(frames[0])
    st = primvars.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, "faceVarying")
    st.Set(Vt.Vec2fArray.FromNumpy(uvs))
    st.SetIndices(Vt.IntArray.FromNumpy(flat))

    face_uv = uvs[triangles].mean(axis=1)
    stripe = np.minimum((face_uv[:, 0] * STRIPES).astype(int), STRIPES - 1) % 2
    shade = 0.6 + 0.4 * face_uv[:, 1:2]
    palette = np.array(list(MATERIALS.values()), dtype=np.float32)
    colors = (palette[stripe] * shade).astype(np.float32)
    color = primvars.CreatePrimvar("displayColor", Sdf.ValueTypeNames.Color3fArray, "uniform")
    color.Set(Vt.Vec3fArray.FromNumpy(colors))

    points, extent = mesh.CreatePointsAttr(), mesh.CreateExtentAttr()
    normals = primvars.CreatePrimvar("normals", Sdf.ValueTypeNames.Normal3fArray, "vertex")
    moving = mesh.CreateVelocitiesAttr()
    speeds = velocities(frames)
    for frame, positions in enumerate(frames):
        time = Usd.TimeCode(frame)
        positions = np.ascontiguousarray(positions, dtype=np.float32)
        points.Set(Vt.Vec3fArray.FromNumpy(positions), time)
        bounds = np.stack([positions.min(axis=0), positions.max(axis=0)])
        extent.Set(Vt.Vec3fArray.FromNumpy(bounds), time)
        normals.Set(Vt.Vec3fArray.FromNumpy(vertex_normals(positions, triangles)), time)
        moving.Set(Vt.Vec3fArray.FromNumpy(speeds[frame]), time)

    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim())
    for number, (name, rgb) in enumerate(MATERIALS.items()):
        material = UsdShade.Material.Define(stage, f"/Root/Looks/{name}")
        shader = UsdShade.Shader.Define(stage, f"/Root/Looks/{name}/surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*rgb))
        material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        faces = np.flatnonzero(stripe == number).astype(np.int32)
        subset = UsdGeom.Subset.CreateGeomSubset(
            mesh,
            name,
            UsdGeom.Tokens.face,
            Vt.IntArray.FromNumpy(faces),
            UsdShade.Tokens.materialBind,
            UsdGeom.Tokens.partition,
        )
        UsdShade.MaterialBindingAPI.Apply(subset.GetPrim()).Bind(material)
    if not stage.GetRootLayer().Export(str(path)):
        raise OSError(f"{path}: USD could not write it")


def write(output: Path, frames: np.ndarray, triangles: np.ndarray, force: bool) -> None:
    """Author the stage beside ``output`` and move it in when complete."""
    refuse_existing([output], force)
    temporary = output.with_name(f".{output.stem}.{os.getpid()}.tmp{output.suffix}")
    try:
        author(temporary, frames, triangles)
        os.replace(temporary, output)
    finally:
        temporary.unlink(missing_ok=True)


def main(argv: list[str] | None = None) -> int:
    """Read the cloth, write the stage; returns the exit status."""
    parser = argparse.ArgumentParser(
        prog="python -m tools.generate.textured_character",
        description=__doc__.splitlines()[0],
    )
    parser.add_argument("-o", "--output", type=Path, required=True, help="OUT.usda or OUT.usdc")
    parser.add_argument("--input", type=Path, help="an .npz with V and F (default: the cloth)")
    parser.add_argument("--frames", type=int, help="keep the first N frames (default: all)")
    parser.add_argument("--force", action="store_true", help="replace an existing output")
    args = parser.parse_args(argv)
    if args.output.suffix not in (".usda", ".usdc", ".usd"):
        parser.error("the output must end in .usda, .usdc or .usd")
    if args.frames is not None and args.frames < 1:
        parser.error("--frames must be at least 1")
    with np.load(args.input or sample_path()) as data:
        frames = np.asarray(data["V"])[: args.frames]
        triangles = np.asarray(data["F"], dtype=np.int64)
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        parser.error(f"F must be (triangles, 3), got {triangles.shape}")
    try:
        write(args.output, frames, triangles, args.force)
    except (FileExistsError, FileNotFoundError, NotADirectoryError, OSError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    print(
        f"wrote {args.output}: {len(frames)} frames x {frames.shape[1]} vertices, "
        f"{len(triangles)} triangles, st, normals, displayColor, velocities, "
        f"{len(MATERIALS)} material subsets"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
