"""Writes the fixtures of tests/data/xdmf with tools nobody here wrote (README.md says what each
holds): VTK's own XDMF writer (vtkXdmfWriter) and meshio's time series writer. Needs VTK
(``pip install vtk`` or pyvista) and meshio; run from anywhere:

    python tests/data/xdmf/make.py
"""

from __future__ import annotations

import os
from pathlib import Path

import meshio
import numpy as np
import vtk
from vtkmodules.util.vtkAlgorithm import VTKPythonAlgorithmBase

HERE = Path(__file__).parent
POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0.5, 0]], dtype=np.float64)
# a triangle, a pentagon, a triangle (VTK 9.7's XDMF writer garbles quads in a Mixed topology)
CELLS = [(5, [0, 1, 2]), (7, [1, 4, 2, 0, 3]), (5, [0, 2, 3])]
STEPS = [0.0, 0.5, 1.25]


class Moving(VTKPythonAlgorithmBase):  # type: ignore[misc]  # VTK has no type information
    """A VTK source of an UnstructuredGrid whose points move by time / 8 (exact in 6 digits,
    as VTK writes inline XML values)."""

    def __init__(self) -> None:
        super().__init__(nInputPorts=0, nOutputPorts=1, outputType="vtkUnstructuredGrid")

    def RequestInformation(self, request, inputs, outputs):
        info = outputs.GetInformationObject(0)
        pipeline = vtk.vtkStreamingDemandDrivenPipeline
        for step in STEPS:
            info.Append(pipeline.TIME_STEPS(), step)
        info.Append(pipeline.TIME_RANGE(), STEPS[0])
        info.Append(pipeline.TIME_RANGE(), STEPS[-1])
        return 1

    def RequestData(self, request, inputs, outputs):
        info = outputs.GetInformationObject(0)
        pipeline = vtk.vtkStreamingDemandDrivenPipeline
        time = info.Get(pipeline.UPDATE_TIME_STEP()) if info.Has(pipeline.UPDATE_TIME_STEP()) else 0
        grid = vtk.vtkUnstructuredGrid.GetData(outputs)
        points = vtk.vtkPoints()
        points.SetDataTypeToDouble()
        for point in POINTS + time / 8:
            points.InsertNextPoint(*point)
        grid.SetPoints(points)
        grid.Allocate(len(CELLS))
        for kind, ids in CELLS:
            grid.InsertNextCell(kind, len(ids), ids)
        return 1


def vtk_series(name: str, light_data_limit: int) -> None:
    for old in (HERE / f"{name}.xmf", HERE / f"{name}.h5"):
        if old.exists():
            os.remove(old)  # VTK's writer does not replace an HDF5 file of other sizes
    source = Moving()  # kept alive while the writer runs it
    writer = vtk.vtkXdmfWriter()
    writer.SetInputConnection(source.GetOutputPort())
    writer.SetFileName(str(HERE / f"{name}.xmf"))
    writer.WriteAllTimeStepsOn()
    writer.SetLightDataLimit(light_data_limit)  # arrays above this many values go to HDF5
    if not writer.Write():
        raise SystemExit(f"VTK could not write {name}.xmf")


def main() -> None:
    vtk_series("moving", 1)
    vtk_series("moving_inline", 10**9)
    with meshio.xdmf.TimeSeriesWriter(HERE / "static.xdmf", data_format="XML") as writer:
        writer.write_points_cells(POINTS, [("triangle", np.array([[0, 1, 2], [0, 2, 3]]))])
        for time in STEPS:
            writer.write_data(time, point_data={"phi": np.arange(5.0) * time})


if __name__ == "__main__":
    main()
