"""VTK time series (tuckercodec/io/vtk/): a ParaView .pvd of .vtp or .vtu files, read and
written in plain numpy (no extra library).

Round trips are exact (float32 and float64 positions, mixed polygons, time codes, names), in
.vtp (the default) and .vtu; series VTK itself wrote (tests/data/vtk) are read exactly, wherever
the tests run; where pyvista (VTK's Python package) is installed, VTK's own readers read what we
write, bit for bit. Every broken or hostile collection or frame ends in an InputError naming the
file (the frame's file, with its frame, where the fault is in one). The encodings of one file
are tests/test_io_vtk_xml.py's.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.support.inputs import expect_input_error, measure
from tests.support.sequences import grid_faces, shared_file, wave_sequence
from tuckercodec import InputError, MeshSequence, load_sequence, save_sequence
from tuckercodec.cli import main
from tuckercodec.io import vtk as vtk_format
from tuckercodec.io.registry import WriteOptions, format_named
from tuckercodec.io.vtk import series as vtk_series
from tuckercodec.io.vtk.datasets import DatasetWriter
from tuckercodec.system.atomic import NotOursError

DATA = Path(__file__).parent / "data" / "vtk"
FIXTURE = DATA / "series.pvd"
NO_FACES = np.zeros((0, 3), dtype=np.int64)


def exact(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit for bit equal float64 arrays."""
    return a.dtype == b.dtype == np.float64 and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def vtu_text(points: np.ndarray, cells: list[list[int]], types: list[int]) -> str:
    """A minimal ASCII .vtu of one piece."""
    connectivity = " ".join(str(i) for cell in cells for i in cell)
    offsets = " ".join(str(n) for n in np.cumsum([len(cell) for cell in cells]))
    coords = " ".join(repr(float(x)) for x in np.ravel(points))
    return f"""<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(cells)}">
      <Points>
        <DataArray type="Float64" NumberOfComponents="3" format="ascii">{coords}</DataArray>
      </Points>
      <Cells>
        <DataArray type="Int64" Name="connectivity" format="ascii">{connectivity}</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">{offsets}</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">{" ".join(map(str, types))}</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"""


def pvd_text(*datasets: str) -> str:
    """A .pvd collection of the given <DataSet .../> attribute strings."""
    rows = "\n".join(f"    <DataSet {attributes}/>" for attributes in datasets)
    return (
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n'
        f"{rows}\n  </Collection>\n</VTKFile>\n"
    )


SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=np.float64)


def series(tmp_path: Path, frames: list[str], timesteps: list[float] | None = None) -> Path:
    """A .pvd listing one .vtu per text of ``frames`` (in folder f/)."""
    (tmp_path / "f").mkdir(exist_ok=True)
    rows = []
    for number, text in enumerate(frames):
        (tmp_path / "f" / f"{number}.vtu").write_text(text)
        step = number if timesteps is None else timesteps[number]
        rows.append(f'timestep="{step}" part="0" file="f/{number}.vtu"')
    path = tmp_path / "s.pvd"
    path.write_text(pvd_text(*rows))
    return path


def square_frame(shift: float = 0.0, **changes) -> str:
    """An ASCII frame of two triangles over the unit square, moved by ``shift``."""
    points = changes.get("points", SQUARE + shift)
    cells = changes.get("cells", [[0, 1, 2], [0, 2, 3]])
    return vtu_text(points, cells, changes.get("types", [5] * len(cells)))


# ------------------------------------------------------------------------------------------
# round trips


def test_the_cloth_round_trips_exactly(cloth, tmp_path):
    path = tmp_path / "out.pvd"
    save_sequence(cloth, path)
    assert len(list((tmp_path / "out").glob("*.vtp"))) == 60  # PolyData: ParaView's surfaces
    back = load_sequence(path)
    assert exact(back.vertices, cloth.vertices) and np.array_equal(back.faces, cloth.faces)
    assert back.codes().tolist() == list(range(60)) and back.frame_names == cloth.frame_names
    assert back.frame_rate is None


def test_float64_positions_time_codes_names_and_polygons_are_kept(tmp_path):
    vertices = wave_sequence(4, 3)  # float64 values float32 cannot hold
    faces = np.array([[0, 1, 4, -1, -1], [1, 2, 5, 4, -1], [3, 4, 7, 6, -1], [4, 5, 8, 7, 6]])
    seq = MeshSequence(
        vertices,
        faces,
        frame_names=["a", "b", "c", "d"],
        time_codes=np.array([0.1, 0.2, 0.30000000000000004, 7.5]),
    )
    save_sequence(seq, tmp_path / "p.pvd")
    back = load_sequence(tmp_path / "p.pvd")
    assert exact(back.vertices, vertices) and np.array_equal(back.faces, faces)
    assert back.time_codes is not None
    assert back.time_codes.tolist() == [0.1, 0.2, 0.30000000000000004, 7.5]
    assert back.frame_names == ["a", "b", "c", "d"]


def test_a_point_sequence_round_trips(tmp_path):
    seq = MeshSequence(wave_sequence(3, 3), NO_FACES)
    save_sequence(seq, tmp_path / "p.pvd")
    back = load_sequence(tmp_path / "p.pvd")
    assert exact(back.vertices, seq.vertices) and back.faces.shape == (0, 3)


def test_horse_gallop_round_trips_exactly(tmp_path):
    horse = load_sequence(shared_file("horse-gallop"), progress=False)
    save_sequence(horse, tmp_path / "horse.pvd")
    back = load_sequence(tmp_path / "horse.pvd")  # its speed: python -m tools.bench read --formats
    assert exact(back.vertices, horse.vertices) and np.array_equal(back.faces, horse.faces)
    assert back.frame_names == [f"horse-gallop-{n:02d}" for n in range(1, 49)]


def test_files_vtk_itself_wrote_are_read_exactly():
    # tests/data/vtk/README.md: ParaView's default layout, written by VTK's own writer
    seq = load_sequence(FIXTURE)
    base = np.array(
        [
            [0, 0, 0],
            [1, 0, 0],
            [1, 1, 0],
            [0, 1, 0],
            [2, 0, 0],
            [2, 1, 0],
            [3, 0.5, 0],
            [2.5, 2, 0],
        ],
        dtype=np.float64,
    )
    assert seq.time_codes is not None
    assert seq.time_codes.tolist() == [0.0, 0.25, 0.5]  # sorted: the .pvd lists 0.25 first
    assert seq.frame_names == ["step0", "step1", "step2"]
    for number, step in enumerate([0.0, 0.25, 0.5]):
        expected = base + np.array([0.1, 0.2, 0.3]) * step * np.arange(1, 9)[:, None] / 3
        assert exact(seq.vertices[number], expected)
    # the vertex cell (a point marker) is not a face; the others keep the file's order
    assert seq.faces.tolist() == [
        [0, 1, 2, -1, -1],
        [1, 4, 5, 2, -1],
        [4, 6, 7, 5, 2],
        [0, 2, 3, -1, -1],
    ]


def test_vtks_own_readers_read_what_is_written(tmp_path):
    pyvista = pytest.importorskip(
        "pyvista", reason="pyvista (VTK's Python package) is not installed: VTK's own readers"
    )
    vertices = wave_sequence(3, 3)
    faces = np.array([[0, 1, 4, -1], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    seq = MeshSequence(vertices, faces, time_codes=np.array([0.5, 1.5, 4.0]))
    save_sequence(seq, tmp_path / "w.pvd")
    reader = pyvista.PVDReader(tmp_path / "w.pvd")
    assert reader.time_values == [0.5, 1.5, 4.0]
    for number, step in enumerate(reader.time_values):
        reader.set_active_time_value(step)
        grid = reader.read()[0]
        assert exact(np.asarray(grid.points), vertices[number])
        cells = [list(grid.get_cell(i).point_ids) for i in range(grid.n_cells)]
        assert cells == [[i for i in row if i >= 0] for row in faces.tolist()]


# ------------------------------------------------------------------------------------------
# writing: checked first, atomic


def test_writing_never_overwrites_and_checks_every_target_first(tmp_path):
    seq = MeshSequence(wave_sequence(12, 3), grid_faces(3))
    path = tmp_path / "out.pvd"
    path.write_text("precious")
    with pytest.raises(FileExistsError):
        save_sequence(seq, path)
    assert path.read_text() == "precious" and not (tmp_path / "out").exists()
    path.unlink()
    (tmp_path / "out").mkdir()
    taken = tmp_path / "out" / f"{seq.frame_names[7]}.vtp"
    taken.write_text("precious")
    with pytest.raises(FileExistsError):
        save_sequence(seq, path)
    assert not path.exists() and list((tmp_path / "out").iterdir()) == [taken]
    with pytest.raises(NotOursError, match="not written by tuckercodec"):
        save_sequence(seq, path, overwrite=True)  # the frames' folder is not the tool's
    assert not path.exists() and list((tmp_path / "out").iterdir()) == [taken]
    taken.unlink()
    save_sequence(seq, path, overwrite=True)
    assert load_sequence(path).frame_count == 12


def test_a_failure_while_writing_leaves_nothing(tmp_path, monkeypatch):
    written: list[np.ndarray] = []

    def failing_write(self, points, *arrays):
        if len(written) == 2:
            raise OSError("disk full")
        written.append(points)
        return real_write(self, points, *arrays)

    real_write = DatasetWriter.__call__
    monkeypatch.setattr(DatasetWriter, "__call__", failing_write)
    with pytest.raises(OSError, match="disk full"):
        save_sequence(MeshSequence(wave_sequence(5, 3), grid_faces(3)), tmp_path / "x.pvd")
    assert list(tmp_path.iterdir()) == []


def test_vtk_series_need_no_extra_library(tmp_path, monkeypatch):
    for module in ("meshio", "vtk", "pyvista", "h5py"):
        monkeypatch.setitem(sys.modules, module, None)  # importing any of them fails
    assert format_named("vtk").extra is None
    assert load_sequence(FIXTURE).frame_count == 3
    save_sequence(MeshSequence(wave_sequence(2, 3), grid_faces(3)), tmp_path / "x.pvd")
    assert main(["convert", str(tmp_path / "x.pvd"), str(tmp_path / "x.npz")]) == 0


def test_vtu_frames_round_trip_too(tmp_path):
    vertices = wave_sequence(3, 3)
    faces = np.array([[0, 1, 4, -1], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    for seq in (MeshSequence(vertices, faces), MeshSequence(vertices, NO_FACES)):
        path = tmp_path / f"u{len(seq.faces)}.pvd"
        vtk_format.write_pvd(seq, path, WriteOptions(), frame_suffix=".vtu")
        assert sorted(p.suffix for p in path.with_suffix("").glob("frame*")) == [".vtu"] * 3
        back = load_sequence(path)
        assert exact(back.vertices, vertices) and np.array_equal(back.faces, seq.faces)
    with pytest.raises(ValueError, match="frame_suffix"):
        vtk_format.write_pvd(seq, tmp_path / "v.pvd", WriteOptions(), frame_suffix=".vtk")


def test_the_cli_converts_to_and_from_a_vtk_series(tmp_path, capsys):
    source = tmp_path / "wave.npz"
    np.savez(source, V=wave_sequence(12, 6), F=grid_faces(6))
    out = tmp_path / "wave.pvd"
    assert main(["convert", str(source), str(out)]) == 0
    assert "not carried" not in capsys.readouterr().out  # float64 positions kept
    packed = tmp_path / "x.tkc"
    assert main(["encode", str(out), "-o", str(packed)]) == 0
    assert main(["decode", str(packed), "-o", str(tmp_path / "back.pvd")]) == 0
    assert load_sequence(tmp_path / "back.pvd").vertices.shape == (12, 36, 3)
    assert main(["encode", str(out), "--faces", str(out), "-o", str(packed), "--force"]) == 4


# ------------------------------------------------------------------------------------------
# broken and hostile collections


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("<VTKFile", "is not well-formed XML"),
        ('<VTKFile type="UnstructuredGrid"/>', r'root is <VTKFile type="UnstructuredGrid">'),
        ('<VTKFile type="Collection"><Collection/></VTKFile>', "lists no <DataSet>"),
        (pvd_text('timestep="0"'), "DataSet 0 has no file attribute"),
        (pvd_text('timestep="soon" file="a.vtu"'), r"DataSet 0 \(a.vtu\) has timestep 'soon'"),
        (pvd_text('timestep="nan" file="a.vtu"'), r"has timestep 'nan'"),
        (pvd_text('timestep="0" file="a.vtu"', 'file="b.vtu"'), "DataSet 1 has no timestep"),
        (pvd_text('timestep="1" file="a.vtu"', 'timestep="1.0" file="b.vtu"'), "1.0 twice"),
        (pvd_text('part="0" file="a.vtu"', 'part="1" file="b.vtu"'), r"several parts .*Merge"),
        (pvd_text('file="a.pvtp"'), r"a parallel file of pieces: merge"),
        (pvd_text('file="a.obj"'), "lists .vtp or .vtu files"),
    ],
)
def test_a_broken_collection_is_refused_saying_why(tmp_path, text, message):
    path = tmp_path / "bad.pvd"
    path.write_text(text)
    expect_input_error(lambda: load_sequence(path), path, match=message)


def test_entity_declarations_are_refused_before_parsing(tmp_path):
    laughs = (
        '<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
        '<!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">]>\n'
        '<VTKFile type="Collection"><Collection><DataSet file="&lol2;.vtu"/></Collection></VTKFile>'
    )
    path = tmp_path / "lol.pvd"
    path.write_text(laughs)
    expect_input_error(lambda: load_sequence(path), path, match="declares !DOCTYPE, which VTK")
    frame = tmp_path / "f" / "0.vtu"
    pvd = series(tmp_path, [square_frame()])
    frame.write_text(square_frame().replace("<VTKFile", '<!DOCTYPE x [<!ENTITY e "e">]>\n<VTKFile'))
    expect_input_error(lambda: load_sequence(pvd), frame, frame=0, match="declares !DOCTYPE")


LAUGHS = "".join(f'<!ENTITY lol{n} "{f"&lol{n - 1};" * 10 if n else "lol"}">' for n in range(10))


def test_declarations_are_refused_by_the_parser_whatever_comes_first(tmp_path):
    """An entity bomb: a comment before the DOCTYPE, or UTF-16, hid it from a byte filter,
    and the entities expanded."""
    pvd = series(tmp_path, [square_frame()])
    frame = tmp_path / "f" / "0.vtu"
    hidden = f"<!-- <VTKFile --><!DOCTYPE x [{LAUGHS}]>\n<VTKFile"
    frame.write_text(square_frame().replace("<VTKFile", hidden, 1))
    error, _, peak = measure(lambda: load_sequence(pvd))
    assert isinstance(error, InputError) and error.path == str(frame), error
    assert "declares !DOCTYPE, which VTK files never need" in str(error) and peak < 10**7
    laughs = (
        f'<?xml version="1.0" encoding="UTF-16"?>\n<!DOCTYPE lolz [{LAUGHS}]>\n'
        '<VTKFile type="Collection"><Collection><DataSet file="&lol9;.vtu"/></Collection>'
        "</VTKFile>"
    )
    path = tmp_path / "lol.pvd"
    path.write_bytes(laughs.encode("utf-16"))
    error, _, peak = measure(lambda: load_sequence(path))
    assert isinstance(error, InputError) and error.path == str(path), error
    assert "declares !DOCTYPE, which VTK files never need" in str(error) and peak < 10**7


def test_an_index_beyond_the_size_limit_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(vtk_series, "MAX_INDEX_BYTES", 100)
    path = tmp_path / "big.pvd"
    path.write_text(pvd_text(*['file="a.vtu"'] * 10))
    expect_input_error(lambda: load_sequence(path), path, match="is larger than 100 bytes")


def test_a_listed_file_that_is_missing_or_not_vtk_is_named(tmp_path):
    pvd = series(tmp_path, [square_frame(), square_frame(1.0)])
    (tmp_path / "f" / "1.vtu").unlink()
    missing = tmp_path / "f" / "1.vtu"
    error = expect_input_error(lambda: load_sequence(pvd), missing, frame=1, match="cannot read")
    assert str(pvd) in str(error)
    (tmp_path / "f" / "1.vtu").write_text("root:x:0:0:root:/root:/bin/bash\n")
    expect_input_error(lambda: load_sequence(pvd), missing, frame=1, match="not a VTK XML file")


def test_a_listed_file_outside_the_folder_is_refused(tmp_path, capsys):
    """Confinement: a .pvd may list only files inside its own folder, so a crafted one cannot
    read another file of the machine."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.vtp").write_text(square_frame())
    (tmp_path / "sub" / "link.vtp").symlink_to(tmp_path / "a.vtp")
    pvd = tmp_path / "sub" / "s.pvd"
    for name, message in [
        ("../a.vtp", "DataSet 1 names '../a.vtp', which leads out of its folder"),
        (str(tmp_path / "a.vtp"), "DataSet 1 names .*, an absolute path"),
        ("/etc/passwd.vtp", "DataSet 1 names '/etc/passwd.vtp', an absolute path"),
        ("link.vtp", "DataSet 1 names 'link.vtp', which leads out of its folder"),
    ]:
        pvd.write_text(pvd_text('timestep="0" file="link0.vtp"', f'timestep="1" file="{name}"'))
        expect_input_error(lambda: load_sequence(pvd), pvd, match=message)
    assert main(["convert", str(pvd), str(tmp_path / "o.npz")]) == 4
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "s.pvd" in lines[0] and "link.vtp" in lines[0]


def test_a_damaged_frame_is_an_input_error_not_a_library_traceback(tmp_path):
    save_sequence(MeshSequence(wave_sequence(3, 3), grid_faces(3)), tmp_path / "d.pvd")
    frame = tmp_path / "d" / "frame_00001.vtp"
    data = frame.read_bytes()
    frame.write_bytes(data[: data.index(b"<Polys")])
    expect_input_error(
        lambda: load_sequence(tmp_path / "d.pvd"), frame, frame=1, match="not well-formed XML"
    )
    frame.write_bytes(data[:-60])  # into the compressed cells
    expect_input_error(lambda: load_sequence(tmp_path / "d.pvd"), frame, frame=1, match="truncated")


def test_topology_that_changes_is_refused_naming_the_frame(tmp_path):
    more = np.vstack([SQUARE, [[2, 2, 0]]])
    pvd = series(tmp_path, [square_frame(), square_frame(0.5), square_frame(points=more)])
    error = expect_input_error(
        lambda: load_sequence(pvd), tmp_path / "f" / "2.vtu", frame=2, match="has 5 points"
    )
    assert "the first frame" in str(error) and "0.vtu" in str(error)
    pvd = series(tmp_path, [square_frame(), square_frame(0.5, cells=[[0, 1, 3], [1, 2, 3]])])
    expect_input_error(
        lambda: load_sequence(pvd),
        tmp_path / "f" / "1.vtu",
        frame=1,
        match="its cells differ from the first frame's",
    )


def test_cells_that_are_not_surfaces_are_refused_and_none_are_lost(tmp_path):
    tetra = square_frame(cells=[[0, 1, 2, 3]], types=[10])
    pvd = series(tmp_path, [tetra])
    frame = tmp_path / "f" / "0.vtu"
    expect_input_error(
        lambda: load_sequence(pvd), frame, frame=0, match=r"1 tetra cells: .*Extract"
    )
    lines = square_frame(cells=[[0, 1], [1, 2, 3]], types=[3, 4])
    series(tmp_path, [lines])
    expect_input_error(lambda: load_sequence(pvd), frame, frame=0, match="1 line cells")
    unknown = square_frame(cells=[[0, 1, 2]], types=[77])
    series(tmp_path, [unknown])
    expect_input_error(lambda: load_sequence(pvd), frame, frame=0, match="1 type 77 cells")


def test_strips_and_pixels_are_read_as_the_faces_they_are(tmp_path):
    # a strip 0 1 3 2 is the triangles (0 1 3) and (3 1 2): every second one flipped, as VTK
    # splits strips; a pixel's corners 0 1 3 2 go round the quad 0 1 2 3
    pvd = series(tmp_path, [square_frame(cells=[[0, 1, 3, 2], [0, 1, 3, 2]], types=[6, 8])])
    assert load_sequence(pvd).faces.tolist() == [[0, 1, 3, -1], [3, 1, 2, -1], [0, 1, 2, 3]]


def test_vertex_cells_alone_give_a_point_sequence(tmp_path):
    markers: dict[str, Any] = {"cells": [[0], [1], [2], [3]], "types": [1] * 4}
    pvd = series(tmp_path, [square_frame(**markers), square_frame(1.0, **markers)])
    seq = load_sequence(pvd)
    assert seq.faces.shape == (0, 3) and exact(seq.vertices[1], SQUARE + 1.0)
    pvd = series(tmp_path, [square_frame(**markers), square_frame(1.0)])
    expect_input_error(  # the first frame has no faces, the second two triangles
        lambda: load_sequence(pvd), tmp_path / "f" / "1.vtu", frame=1, match="cells differ"
    )


@pytest.mark.parametrize(
    ("cells", "message"),
    [([[0, 1, 7]], r"face 0 has a vertex index 7 outside 0\.\.3"), ([[0, -1, 2]], "negative")],
)
def test_a_cell_naming_a_point_that_does_not_exist_is_refused(tmp_path, cells, message):
    pvd = series(tmp_path, [square_frame(cells=cells)])
    expect_input_error(lambda: load_sequence(pvd), tmp_path / "f" / "0.vtu", frame=0, match=message)


def test_a_non_finite_point_names_its_frame_and_point(tmp_path):
    bad = SQUARE.copy()
    bad[2, 1] = np.nan
    pvd = series(tmp_path, [square_frame(), square_frame(points=bad)])
    expect_input_error(
        lambda: load_sequence(pvd),
        tmp_path / "f" / "1.vtu",
        frame=1,
        match="point 2 has a non-finite coordinate",
    )


def test_positions_beyond_float32_are_written_as_float64_without_a_warning(tmp_path):
    # the float32 trial cast overflowed with a RuntimeWarning (an error under pytest, and a
    # stray stderr line in the CLI) although Float64 keeps the value exactly
    vertices = np.zeros((2, 4, 3))
    vertices[:, 1, 0] = vertices[:, 2, 1] = vertices[:, 3, 2] = 1.0
    vertices[1, 3, 2] = 1e39
    seq = MeshSequence(vertices, np.array([[0, 1, 2], [0, 2, 3]]))
    save_sequence(seq, tmp_path / "big.pvd")
    assert np.array_equal(load_sequence(tmp_path / "big.pvd").vertices, vertices)


def test_one_file_listed_for_two_time_steps_is_refused(tmp_path):
    path = series(tmp_path, [square_frame(), square_frame(0.5)])
    path.write_text(pvd_text('timestep="0" file="f/0.vtu"', 'timestep="1" file="./f/0.vtu"'))
    with pytest.raises(InputError, match=r"s\.pvd, frame 1: lists 0\.vtu for frames 0 and 1"):
        load_sequence(path)
