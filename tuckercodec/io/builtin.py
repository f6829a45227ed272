"""The built-in sequence formats: one entry each, with its names, what it keeps and its
functions (trimesh-style, one loader callable per format: ``open`` for a file that holds a
whole sequence, ``read_frame`` for one frame per file; and the writer). The table lives here,
one place for all, and :func:`.registry.formats` imports it on first use, so that importing
:mod:`tuckercodec` imports no format module. Each format's own module says what it reads and
writes, and how.
"""

from __future__ import annotations

from . import (
    alembic,
    gltf,
    meshes,
    obj_attribute_writer,
    obj_attributes,
    usd,
    vtk,
    xdmf,
    zarr_store,
)
from .npz import NpzFrames, cannot_keep_npz, npy, write_npz
from .pointcache import mdd, pc2
from .registry import SequenceFormat
from .xdmf.writer import cannot_keep as cannot_keep_xdmf
from .xdmf.writer import write_xdmf

#: What each format keeps of a sequence beyond float32 positions (``SequenceFormat.carries``).
_EVERYTHING = frozenset(
    {
        "float64",
        "faces",
        "polygons",
        "frame_names",
        "frame_rate",
        "time_codes",
        "meters_per_unit",
        "up_axis",
    }
)
_SERIES = frozenset({"float64", "faces", "polygons", "frame_names", "time_codes"})
_SCENE = frozenset({"faces", "frame_rate", "time_codes"})

#: Every built-in format, in the order ``tuckercodec formats`` lists them.
FORMATS = (
    SequenceFormat(
        name="obj",
        suffixes=(".obj",),
        description="Wavefront OBJ, one frame per file (a folder of them, or a glob)",
        read_frame=obj_attributes.read_obj_frame,
        write_frame=obj_attribute_writer.obj_frame_writer,
        cannot_keep=obj_attribute_writer.cannot_keep,
        # exact text (repr) unless a precision is asked for; the frame names are the file names
        carries=frozenset({"float64", "faces", "polygons", "frame_names"}),
    ),
    SequenceFormat(
        name="npz",
        suffixes=(".npz",),
        description=(
            "NumPy archive: V (frames, vertices, 3), F faces, frame_files, frame_rate, "
            "time_codes, meters_per_unit, up_axis, attributes, face sets, fields"
        ),
        open=NpzFrames,
        write=write_npz,
        cannot_keep=cannot_keep_npz,
        carries=_EVERYTHING,
    ),
    SequenceFormat(
        name="npy",
        suffixes=(".npy",),
        description="NumPy array of positions (frames, vertices, 3), float32 or float64",
        open=npy.NpyFrames,
        write=npy.write_npy,
        cannot_keep=npy.cannot_keep,
        read_options=frozenset({"faces"}),
        carries=frozenset({"float64"}),
    ),
    SequenceFormat(
        name="usd",
        suffixes=(".usd", ".usda", ".usdc"),
        description="USD stage: a UsdGeomMesh with time-sampled points (--prim to choose one)",
        open=usd.open_usd,
        write=usd.write_usd,
        read_options=frozenset({"prim"}),
        extra="usd",
        carries=_SCENE | {"meters_per_unit", "up_axis"},
        cannot_keep=usd.cannot_keep,
    ),
    SequenceFormat(
        name="alembic",
        suffixes=(".abc",),
        description=(
            "Alembic archive (Ogawa): a PolyMesh's position samples (--object to choose one)"
        ),
        open=alembic.open_alembic,
        write=alembic.write_alembic,
        cannot_keep=alembic.cannot_keep,
        read_options=frozenset({"object_path"}),
        extra="alembic",
        carries=_SCENE,
    ),
    SequenceFormat(
        name="pc2",
        suffixes=(".pc2",),
        description="PC2 point cache (Blender, 3ds Max, Maya): positions, start frame, sample rate",
        open=pc2.Pc2Frames,
        write=pc2.write_pc2,
        read_options=frozenset({"faces"}),
        carries=frozenset({"time_codes"}),
    ),
    SequenceFormat(
        name="mdd",
        suffixes=(".mdd",),
        description="MDD point cache (LightWave, Blender, Houdini): positions, times in seconds",
        open=mdd.MddFrames,
        write=mdd.write_mdd,
        read_options=frozenset({"faces"}),
        carries=frozenset({"frame_rate", "time_codes"}),
    ),
    SequenceFormat(
        name="gltf",
        suffixes=(".glb", ".gltf"),
        description="glTF 2.0 morph animation (frame 0 the mesh, frames as morph targets)",
        open=gltf.GltfFrames,
        write=gltf.write_gltf,
        # a static glTF is one frame, so a folder of .glb frames reads one frame per file
        read_frame=gltf.read_gltf_frame,
        read_options=frozenset({"object_path", "fps"}),
        carries=frozenset({"faces", "frame_names", "frame_rate", "time_codes"}),
        cannot_keep=gltf.cannot_keep,
    ),
    SequenceFormat(
        name="vtk",
        suffixes=(".pvd",),
        description="VTK time series: a ParaView .pvd of .vtp or .vtu files, one per time step",
        open=vtk.PvdFrames,
        write=vtk.write_pvd,
        cannot_keep=vtk.cannot_keep,
        carries=_SERIES,
    ),
    SequenceFormat(
        name="xdmf",
        suffixes=(".xdmf", ".xmf"),
        description="XDMF time series: a temporal collection of grids, HDF5 or XML data (h5py)",
        open=xdmf.XdmfFrames,
        write=write_xdmf,
        cannot_keep=cannot_keep_xdmf,
        extra="xdmf",
        carries=_SERIES,
    ),
    SequenceFormat(
        name="zarr",
        suffixes=(".zarr",),
        description=(
            "zarr store (a folder): array 'vertices' (frames, vertices, 3), faces, attributes"
        ),
        open=zarr_store.ZarrFrames,
        write=zarr_store.write_zarr,
        cannot_keep=zarr_store.cannot_keep,
        extra="zarr",
        folder=True,
        carries=_EVERYTHING,
    ),
    SequenceFormat(
        name="mesh",
        suffixes=(".ply", ".off", ".stl", ".3mf", ".dae"),  # .glb/.gltf: the gltf format
        description="one frame per file, read with trimesh in the file's vertex order",
        read_frame=meshes.read_mesh_frame,
    ),
)
