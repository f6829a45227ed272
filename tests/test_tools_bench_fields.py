"""tools.bench fields and tools.generate.simulation: their pieces on a tiny synthetic series
(a 6 x 6 grid of vertices, 25 quads, 8 frames of a travelling wave), untimed.

SZ3 and zfp (``pip install '.[bench]'``) and meshio (the simulation's writer) are tested only
where they are installed, and skip saying so elsewhere.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import tuckercodec
from tools import bench
from tools.bench import fields
from tools.generate import simulation

SIDE = 6
FRAMES = 8


def _grid_series() -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Coordinates (N, 2), quads, point data and cell data (each (F, n, c) float64)."""
    rows, cols = np.meshgrid(np.arange(SIDE), np.arange(SIDE), indexing="ij")
    coordinates = np.stack([cols.ravel(), rows.ravel()], axis=1).astype(np.float64) * 0.1
    quads = np.array(
        [
            [r * SIDE + c, (r + 1) * SIDE + c, (r + 1) * SIDE + c + 1, r * SIDE + c + 1]
            for r in range(SIDE - 1)
            for c in range(SIDE - 1)
        ],
        dtype=np.int64,
    )
    times = np.arange(FRAMES)[:, None]
    phase = coordinates[:, 0][None, :] * 7.0 - times * 0.4
    displacement = np.stack([np.sin(phase), 0.5 * np.cos(phase)], axis=2) * 1e-6
    centres = coordinates[quads].mean(axis=1)[:, 0][None, :] * 7.0 - times * 0.4
    stress = np.stack([np.sin(centres), np.cos(centres), np.sin(2 * centres)], axis=2) * 3e7
    return coordinates, quads, {"u": displacement}, {"stress": stress}


@pytest.fixture(scope="module")
def series(tmp_path_factory):
    """The synthetic series written as a .pvd by tuckercodec, and its fields."""
    coordinates, quads, point_data, cell_data = _grid_series()
    positions = np.repeat(simulation.vtk_points(coordinates)[None], FRAMES, axis=0)
    items = [tuckercodec.Field(name, v, "vertex") for name, v in point_data.items()]
    items += [tuckercodec.Field(name, v, "face") for name, v in cell_data.items()]
    items.append(tuckercodec.Field("constant", np.full((FRAMES, SIDE * SIDE, 1), 2.5), "vertex"))
    path = tmp_path_factory.mktemp("series") / "grid.pvd"
    tuckercodec.save_sequence(tuckercodec.MeshSequence(positions, quads, fields=items), path)
    return path, items


def test_a_series_fields_are_read_as_the_files_hold_them(series):
    path, items = series
    read, mesh = fields.fields_of(path, None)
    assert mesh is not None
    by_name = {item.name: item for item in read}
    for item in items:
        assert by_name[item.name].domain == item.domain
        assert np.array_equal(by_name[item.name].values, item.values)
    first, _ = fields.fields_of(path, 3)
    assert all(item.values.shape[0] == 3 for item in first)


def test_the_bounds_are_fractions_of_the_range_and_a_constant_field_has_none():
    values = np.array([[[-1.0], [3.0]]])
    assert fields.bounds_of(tuckercodec.Field("f", values, "vertex")) == pytest.approx([4e-3, 4e-4])
    assert fields.bounds_of(tuckercodec.Field("c", np.ones((2, 3, 1)), "vertex")) == []
    assert fields.tucker_targets([]) == ["rel:1", "rel:0.1", "lossless"]


def test_every_tuckercodec_target_is_met_on_the_decoded_values(series):
    path, _ = series
    for item in fields.fields_of(path, None)[0]:
        found = fields.measures(item, fields.fields_of(path, None)[1], ["tuckercodec"], 1, False)
        assert [m.target for m in found] == fields.tucker_targets(fields.bounds_of(item))
        assert all(m.met for m in found), [(m.target, m.error) for m in found]
        assert all(m.size > 0 and m.encode_seconds >= 0 for m in found)
        lossless = found[-1]
        assert lossless.mode == "exact" and lossless.error == "bit-exact"


def test_a_decoded_field_off_its_target_is_a_miss():
    values = np.linspace(0.0, 1.0, 24).reshape(2, 12, 1)
    item = tuckercodec.Field("f", values, "vertex")
    off = values + 0.01
    error, met = fields._judged(item, tuckercodec.internal.FieldTarget(max_error=0.005), off)
    assert not met and error.startswith("max-abs 0.01")
    assert fields._judged(item, tuckercodec.internal.FieldTarget(max_error=0.02), off)[1]
    assert not fields._judged(item, tuckercodec.internal.FieldTarget(lossless=True), off)[1]
    last_bit = values.copy()
    last_bit.view(np.uint64)[0, 3, 0] ^= 1
    assert not fields._judged(item, tuckercodec.internal.FieldTarget(lossless=True), last_bit)[1]
    assert not fields._judged(item, tuckercodec.internal.FieldTarget(relative=0.1), off * 2)[1]


def test_the_peers_layouts_put_time_fastest_and_rows_of_the_grid_together():
    values = np.arange(FRAMES * SIDE * SIDE * 2, dtype=np.float64).reshape(FRAMES, SIDE**2, 2)
    flat = fields.peer_layout(values, grid=False)
    assert flat is not None and flat.shape == (2, SIDE**2, FRAMES)
    assert flat[1, 7, 3] == values[3, 7, 1]
    grid = fields.peer_layout(values, grid=True)
    assert grid is not None and grid.shape == (2, SIDE, SIDE, FRAMES)
    assert grid[1, 2, 4, 5] == values[5, 2 * SIDE + 4, 1]  # element row * side + column
    assert fields.peer_layout(values[:, :-1], grid=True) is None  # 35 elements: no square


@pytest.mark.parametrize(("coder", "module"), [("sz3", "pysz"), ("zfp", "zfpy")])
@pytest.mark.parametrize("grid", [False, True])
def test_a_peer_meets_its_bound_in_either_layout(coder, module, grid, series):
    pytest.importorskip(module, reason=f"{module} is not installed (pip install '.[bench]')")
    for item in fields.fields_of(series[0], None)[0]:
        for bound in fields.bounds_of(item):
            measure = fields.measure_peer(item, coder, bound, 1, grid)
            if item.domain == "face":  # 25 faces: a square too
                assert measure is not None
            assert measure is not None and measure.met, (item.name, bound, measure)
            assert measure.coder == coder + (" (grid)" if grid else "") and measure.size > 0


def test_the_suite_prints_a_row_per_measure_and_names_an_absent_simulation(
    series, tmp_path, monkeypatch, capsys
):
    monkeypatch.setattr(fields, "SIMULATION", tmp_path / "absent.pvd")
    args = ["fields", str(series[0]), "--simulation", "--coders", "tuckercodec", "--repeats", "1"]
    assert bench.main(args) == 0
    lines = capsys.readouterr().out.splitlines()
    rows = [line for line in lines if line.startswith("| grid |")]
    assert len(rows) == 5 + 5 + 3  # u and stress: 2 relative, 2 bounds, lossless; constant: 3
    assert not [row for row in rows if "misses" in row]
    u_lossless = next(row for row in rows if "| u |" in row and "lossless" in row)
    assert "| vertex (2, float64) |" in u_lossless and "bit-exact" in u_lossless
    absent = next(line for line in lines if line.startswith("| absent.pvd |"))
    assert "tools/generate/simulation.py" in absent


def test_the_simulation_pieces_shape_the_solvers_arrays_for_vtk():
    points = simulation.vtk_points(np.array([[1.0, 2.0], [3.0, 4.0]]))
    assert points.shape == (2, 3) and points.dtype == np.float64 and not points[:, 2].any()
    assert simulation.cell_values(np.arange(12.0).reshape(2, 1, 6, 1), 2).shape == (2, 6)
    entries = [(0.0, "frames/a.vtu"), (1.4184162865339505e-08, 'frames/b"&.vtu')]
    root = ET.fromstring(simulation.pvd_text(entries))
    dataset = root.findall("./Collection/DataSet")
    assert [float(d.get("timestep", "")) for d in dataset] == [t for t, _ in entries]  # exact
    assert [d.get("file") for d in dataset] == [name for _, name in entries]


def test_the_simulation_series_reads_back_bit_for_bit(tmp_path):
    pytest.importorskip("meshio", reason="meshio is not installed (the simulation's writer)")
    coordinates, quads, point_data, cell_data = _grid_series()
    steps = [
        (0.5 * k, {n: v[k] for n, v in point_data.items()}, {n: v[k] for n, v in cell_data.items()})
        for k in range(FRAMES)
    ]
    pvd = simulation.write_series(tmp_path, coordinates, quads, steps)
    sequence = tuckercodec.load_sequence(pvd)
    assert np.array_equal(sequence.faces, quads)
    read = {item.name: item for item in sequence.fields}
    assert np.array_equal(read["u"].values, point_data["u"]) and read["u"].domain == "vertex"
    assert np.array_equal(read["stress"].values, cell_data["stress"])
    assert read["stress"].domain == "face"
