"""Writes the fixtures of tests/data/vtk with VTK's own XML writers (README.md says what each
holds). Needs VTK (``pip install vtk``, or pyvista, which brings it); run from anywhere:

    python tests/data/vtk/make.py
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import vtk

HERE = Path(__file__).parent

# the UnstructuredGrid series: float64 points, a triangle, a quad, a vertex, a pentagon, a triangle
POINTS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0.5, 0], [2.5, 2, 0]],
    dtype=np.float64,
)
CELLS = [(5, [0, 1, 2]), (9, [1, 4, 5, 2]), (1, [7]), (7, [4, 6, 7, 5, 2]), (5, [0, 2, 3])]
STEPS = [0.0, 0.25, 0.5]

# the PolyData: 9 points, a vertex, a triangle, a quad, a pentagon, a strip of 5 points
SURFACE = (
    np.array(
        [
            [0, 0, 0],
            [1, 0, 0],
            [1, 1, 0],
            [0, 1, 0],
            [2, 0, 0],
            [2, 1, 0],
            [3, 0.5, 0],
            [3, 2, 0],
            [4, 1, 0],
        ],
        dtype=np.float64,
    )
    + np.arange(27).reshape(9, 3) / 7
)  # sevenths: float64 values that float32 cannot hold
VERTS = [[8]]
POLYS = [[0, 1, 2], [1, 4, 5, 2], [4, 6, 7, 5, 2]]
STRIPS = [[0, 2, 3, 5, 7]]
SURFACE_STEPS = [0.0, 0.1, 0.2]

# every layout VTK writes, by file name: data mode, raw (not base64) appended, zlib, header
# type, byte order
LAYOUTS = {
    "ascii": ("ascii", False, False, 64, "little"),
    "binary32": ("binary", False, False, 32, "little"),
    "binary64": ("binary", False, False, 64, "little"),
    "binary32-zlib": ("binary", False, True, 32, "little"),
    "binary64-zlib": ("binary", False, True, 64, "little"),
    "appended-raw": ("appended", True, False, 64, "little"),
    "appended-raw-zlib32": ("appended", True, True, 32, "little"),
    "appended-raw-zlib64": ("appended", True, True, 64, "little"),
    "appended-base64": ("appended", False, False, 64, "little"),
    "appended-base64-zlib32": ("appended", False, True, 32, "little"),
    "bigendian-binary": ("binary", False, False, 64, "big"),
    "bigendian-appended-raw-zlib": ("appended", True, True, 64, "big"),
}

# every surface cell type of an UnstructuredGrid: triangle, pixel, strip, polygon, vertex,
# poly-vertex, quad
MIXED = [
    (5, [0, 1, 2]),
    (8, [0, 1, 3, 2]),
    (6, [2, 3, 4, 5, 6]),
    (7, [4, 6, 7, 5, 2]),
    (1, [7]),
    (2, [0, 8]),
    (9, [1, 4, 5, 2]),
]


def vtk_points(points: np.ndarray, double: bool) -> vtk.vtkPoints:
    out = vtk.vtkPoints()
    if double:
        out.SetDataTypeToDouble()
    for point in points:
        out.InsertNextPoint(*point)
    return out


def cell_array(cells: list[list[int]]) -> vtk.vtkCellArray:
    out = vtk.vtkCellArray()
    for cell in cells:
        out.InsertNextCell(len(cell), cell)
    return out


def grid(points: np.ndarray, cells: list[tuple[int, list[int]]]) -> vtk.vtkUnstructuredGrid:
    out = vtk.vtkUnstructuredGrid()
    out.SetPoints(vtk_points(points, True))
    for kind, ids in cells:
        out.InsertNextCell(kind, len(ids), ids)
    return out


def surface(points: np.ndarray, double: bool) -> vtk.vtkPolyData:
    out = vtk.vtkPolyData()
    out.SetPoints(vtk_points(points, double))
    out.SetVerts(cell_array(VERTS))
    out.SetPolys(cell_array(POLYS))
    out.SetStrips(cell_array(STRIPS))
    return out


# the series with point and cell data: DATA_STEPS time steps of the PolyData (and of the
# UnstructuredGrid of CELLS), each array's values a formula of the step number n
DATA_STEPS = [0.0, 0.5, 1.0]


def numbers(name: str, values: np.ndarray, kind: type = vtk.vtkFloatArray) -> vtk.vtkDataArray:
    """A VTK array named ``name`` of ``values`` (N, c)."""
    values = np.asarray(values).reshape(len(values), -1)
    out = kind()
    out.SetName(name)
    out.SetNumberOfComponents(values.shape[1])
    for row in values.tolist():
        out.InsertNextTuple(row)
    return out


def surface_data(n: int) -> vtk.vtkPolyData:
    """The PolyData at step n (float64 points) with its point and cell data (README.md)."""
    out = surface(SURFACE + np.array([0.5, -0.25, 1.0]) * DATA_STEPS[n], True)
    points, cells = out.GetPointData(), out.GetCellData()
    points.SetScalars(numbers("pressure", np.arange(9) * 0.25 + n))
    points.SetVectors(
        numbers("velocity", np.arange(27).reshape(9, 3) / 7 * (n + 1), vtk.vtkDoubleArray)
    )
    points.SetNormals(numbers("Normals", np.tile([0.0, 0.1 * n, 1.0], (9, 1))))
    points.SetTCoords(numbers("uv_map", SURFACE[:, :2] / 4))
    points.AddArray(numbers("ids", np.arange(9), vtk.vtkIdTypeArray))
    points.AddArray(numbers("stress", np.arange(54).reshape(9, 6) + n))
    cells.SetScalars(numbers("heat", np.arange(5) * 1.5 + n / 7, vtk.vtkDoubleArray))
    cells.AddArray(numbers("material", np.array([7, 1, 2, 3, 4]), vtk.vtkIntArray))
    return out


def grid_data(n: int) -> vtk.vtkUnstructuredGrid:
    """The UnstructuredGrid of CELLS at step n with its point and cell data (README.md)."""
    out = grid(POINTS + n, CELLS)
    out.GetPointData().AddArray(numbers("temperature", np.arange(8) / 3 + n, vtk.vtkDoubleArray))
    out.GetCellData().AddArray(numbers("heat", np.arange(5) + n * 0.5))
    return out


def write(writer: vtk.vtkXMLWriter, data: object, path: Path, layout: tuple[Any, ...]) -> None:
    """ParaView's default layout is ("appended", True, True, 64, "little")."""
    mode, raw, compress, header, order = layout
    path.parent.mkdir(parents=True, exist_ok=True)
    writer.SetInputData(data)
    writer.SetFileName(str(path))
    {"ascii": writer.SetDataModeToAscii, "binary": writer.SetDataModeToBinary}.get(
        mode, writer.SetDataModeToAppended
    )()
    writer.SetEncodeAppendedData(not raw)
    writer.SetHeaderTypeToUInt64() if header == 64 else writer.SetHeaderTypeToUInt32()
    writer.SetCompressorTypeToZLib() if compress else writer.SetCompressorTypeToNone()
    writer.SetByteOrderToBigEndian() if order == "big" else writer.SetByteOrderToLittleEndian()
    if not writer.Write():
        raise SystemExit(f"VTK could not write {path}")


def collection(path: Path, files: list[str], steps: list[float], order: list[int]) -> None:
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    lines += [  # in the given order, which may not be the time order
        f'    <DataSet timestep="{steps[n]}" group="" part="0" file="{files[n]}"/>' for n in order
    ]
    lines += ["  </Collection>", "</VTKFile>", ""]
    path.write_text("\n".join(lines))


def main() -> None:
    paraview = LAYOUTS["appended-raw-zlib64"]
    for number, step in enumerate(STEPS):
        moved = POINTS + np.array([0.1, 0.2, 0.3]) * step * np.arange(1, 9)[:, None] / 3
        write(
            vtk.vtkXMLUnstructuredGridWriter(),
            grid(moved, CELLS),
            HERE / "series" / f"step{number}.vtu",
            paraview,
        )
    collection(HERE / "series.pvd", [f"series/step{n}.vtu" for n in range(3)], STEPS, [1, 0, 2])
    for number, step in enumerate(SURFACE_STEPS):
        moved = SURFACE + np.array([0.5, -0.25, 1.0]) * step
        path = HERE / "surface" / f"step{number}.vtp"
        write(vtk.vtkXMLPolyDataWriter(), surface(moved, False), path, paraview)
    files = [f"surface/step{n}.vtp" for n in range(3)]
    collection(HERE / "surface.pvd", files, SURFACE_STEPS, [0, 1, 2])
    for name, layout in LAYOUTS.items():
        path = HERE / "encodings" / f"{name}.vtp"
        write(vtk.vtkXMLPolyDataWriter(), surface(SURFACE, True), path, layout)
    write(vtk.vtkXMLUnstructuredGridWriter(), grid(SURFACE, MIXED), HERE / "cells.vtu", paraview)
    for number in range(len(DATA_STEPS)):
        path = HERE / "datasurface" / f"step{number}.vtp"
        write(vtk.vtkXMLPolyDataWriter(), surface_data(number), path, paraview)
        path = HERE / "datagrid" / f"step{number}.vtu"
        write(vtk.vtkXMLUnstructuredGridWriter(), grid_data(number), path, paraview)
    for name, suffix in (("datasurface", "vtp"), ("datagrid", "vtu")):
        files = [f"{name}/step{n}.{suffix}" for n in range(3)]
        collection(HERE / f"{name}.pvd", files, DATA_STEPS, [0, 1, 2])


if __name__ == "__main__":
    main()
