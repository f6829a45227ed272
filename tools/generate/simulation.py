"""A real simulation's animated point and cell data as a VTK time series (``.pvd`` of ``.vtu``
files), the input of ``python -m tools.bench fields --simulation``.

The solver is SfePy (BSD-3-Clause, https://sfepy.org), which nobody on this project wrote: its
shipped example ``sfepy/examples/linear_elasticity/elastodynamic.py`` (an iron plate hit at
1 m/s, linear elastodynamics, Newmark time stepping) run in 2D, plane strain, on a 5 mm x 5 mm
plate of 61 x 61 nodes (3,721 vertices, 3,600 quads), every one of its 91 steps saved, as its
own docstring suggests (``-d "dims=(5e-3, 5e-3), shape=(61, 61), save_times='all'"``). SfePy
writes an HDF5 file; each step is then written as a ``.vtu`` by meshio (binary, zlib), values
float64 bit for bit as the solver gave them:

* point data ``u``, ``du``, ``ddu``: displacement, velocity and acceleration (2 components);
* cell data ``cauchy_strain`` and ``cauchy_stress`` (3 components: xx, yy, xy), each cell's
  average, which the reader gives to the quad that the cell is.

The mesh is 2D: its quads are the faces, its points get z = 0. The ``.pvd`` lists the steps at
the solver's times (seconds). Nothing here is committed (the series is about 30 MB); it goes
into a cache folder, by default :data:`DEFAULT_FOLDER`.

Needs SfePy and meshio, which the project does not depend on: install them in a scratch
environment and run this module with that environment's Python, from the repository root::

    python -m venv /tmp/simvenv
    /tmp/simvenv/bin/pip install sfepy==2026.3 meshio==5.3.5
    /tmp/simvenv/bin/python -m tools.generate.simulation [--out FOLDER] [--shape 61]

It imports neither tuckercodec nor anything outside numpy, SfePy, meshio and the standard
library, so that environment needs nothing else.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

#: Where the series goes unless told: the benchmarks' cache of large inputs.
DEFAULT_FOLDER = Path("~/.cache/tuckercodec-bench/sfepy-elastodynamic").expanduser()
#: The collection's file name inside the folder; the steps are in ``frames/`` beside it.
PVD_NAME = "elastodynamic.pvd"
#: SfePy's example, relative to its package.
EXAMPLE = Path("examples") / "linear_elasticity" / "elastodynamic.py"
#: The example's parameters: its 2D run, every step saved.
DEFINE = "dims=(5e-3, 5e-3), shape=({shape}, {shape}), save_times='all', output_dir={out!r}"


def solve(workdir: Path, shape: int) -> Path:
    """Run SfePy's elastodynamics example in ``workdir``; the HDF5 file it writes."""
    import sfepy

    example = Path(sfepy.__file__).parent / EXAMPLE
    define = DEFINE.format(shape=shape, out=str(workdir))
    command = [sys.executable, "-m", "sfepy.scripts.simple", str(example), "-d", define]
    subprocess.run(command, check=True, cwd=workdir, stdout=subprocess.DEVNULL)
    written = sorted(workdir.glob("*.h5"))
    if len(written) != 1:
        raise SystemExit(f"SfePy wrote {len(written)} .h5 files in {workdir}, expected one")
    return written[0]


def vtk_points(coordinates: np.ndarray) -> np.ndarray:
    """The solver's (N, 2) or (N, 3) coordinates as VTK's (N, 3) points (z = 0 in 2D)."""
    points = np.zeros((coordinates.shape[0], 3), dtype=np.float64)
    points[:, : coordinates.shape[1]] = coordinates
    return points


def cell_values(data: np.ndarray, cells: int) -> np.ndarray:
    """SfePy's per-cell averages, shaped (cells, 1, c, 1), as (cells, c)."""
    return np.ascontiguousarray(data.reshape(cells, -1))


def pvd_text(entries: list[tuple[float, str]]) -> str:
    """A ParaView collection of ``(time, relative file)`` entries; times in repr, exact."""
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    lines += [
        f'    <DataSet timestep="{time!r}" part="0" file={quoteattr(name)}/>'
        for time, name in entries
    ]
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def write_series(
    folder: Path,
    coordinates: np.ndarray,
    quads: np.ndarray,
    steps: list[tuple[float, dict[str, np.ndarray], dict[str, np.ndarray]]],
) -> Path:
    """Write ``steps`` (time, point data, cell data) over one quad mesh as ``folder/`` +
    :data:`PVD_NAME` and ``folder/frames/step_NNNN.vtu`` (meshio, binary, zlib); the .pvd."""
    import meshio

    frames = folder / "frames"
    frames.mkdir(parents=True, exist_ok=True)
    points = vtk_points(coordinates)
    entries = []
    for number, (time, point_data, cell_data) in enumerate(steps):
        name = f"frames/step_{number:04d}.vtu"
        mesh = meshio.Mesh(
            points,
            [("quad", quads)],
            point_data=point_data,
            cell_data={key: [value] for key, value in cell_data.items()},
        )
        meshio.vtu.write(str(folder / name), mesh, binary=True, compression="zlib")
        entries.append((float(time), name))
    pvd = folder / PVD_NAME
    partial = pvd.with_suffix(".pvd.partial")
    partial.write_text(pvd_text(entries), encoding="utf-8")
    os.replace(partial, pvd)  # the collection last: a series is whole once it lists the steps
    return pvd


def read_solution(h5: Path) -> tuple[np.ndarray, np.ndarray, list[Any]]:
    """The coordinates, the quads and every step (time, point data, cell data) of SfePy's
    HDF5 output, values as stored (float64)."""
    from sfepy.discrete.fem import Mesh
    from sfepy.discrete.fem.meshio import HDF5MeshIO

    mesh = Mesh.from_file(str(h5))
    quads = np.asarray(mesh.get_conn("2_4"), dtype=np.int64)
    reader = HDF5MeshIO(str(h5))
    numbers, times, _ = reader.read_times()
    steps = []
    for number, time in zip(numbers, times, strict=True):
        point_data, cell_data = {}, {}
        for name, item in reader.read_data(int(number)).items():
            values = np.asarray(item.data, dtype=np.float64)
            if item.mode == "vertex":
                point_data[name] = np.ascontiguousarray(values)
            else:
                cell_data[name] = cell_values(values, quads.shape[0])
        steps.append((float(time), point_data, cell_data))
    return np.asarray(mesh.coors, dtype=np.float64), quads, steps


def main(argv: list[str] | None = None) -> int:
    """Solve, convert, and print where the series is."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_FOLDER, help="the series' folder")
    parser.add_argument("--shape", type=int, default=61, help="nodes along each side (61)")
    args = parser.parse_args(argv)
    if (args.out / PVD_NAME).exists():
        print(f"{args.out / PVD_NAME} exists: remove the folder to make it again")
        return 0
    with tempfile.TemporaryDirectory() as scratch:
        h5 = solve(Path(scratch), args.shape)
        coordinates, quads, steps = read_solution(h5)
    pvd = write_series(args.out, coordinates, quads, steps)
    print(f"{pvd}: {len(steps)} steps, {coordinates.shape[0]} vertices, {quads.shape[0]} quads")
    return 0


if __name__ == "__main__":
    sys.exit(main())
