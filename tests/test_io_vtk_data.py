"""VTK series' point and cell data (tuckercodec/io/vtk/data.py, io/common/data_arrays.py):
attributes and fields written and read back bit for bit, what cannot be kept named, series VTK
itself wrote (tests/data/vtk/README.md: datasurface, datagrid) read as their formulas say, what
we write read by VTK's own reader (pyvista) with the same point and cell data, and the real
cloth with a velocity field of its own positions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.support.inputs import expect_input_error
from tests.support.sequences import grid_faces, shared_file, wave_sequence
from tests.test_io_vtk_xml import DATA, SURFACE  # tests/data/vtk/make.py's PolyData
from tuckercodec import Attribute, FaceSet, Field, MeshSequence, load_sequence, save_sequence
from tuckercodec.io.registry import WriteOptions, format_named
from tuckercodec.io.vtk import PvdFrames, write_pvd
from tuckercodec.io.vtk.arrays import Layout
from tuckercodec.model.normals import recomputed_normals


def cannot_keep(seq: MeshSequence) -> list[str]:
    """The registry's cannot_keep of the vtk format."""
    hook = format_named("vtk").cannot_keep
    assert hook is not None
    return hook(seq)


STEPS = 3


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def attached_sequence(frames: int = 4, grid: int = 4) -> MeshSequence:
    """A moving grid with an attribute of every kind a VTK series keeps, and fields."""
    vertices = wave_sequence(frames, grid)
    faces = grid_faces(grid)
    vertex_count, face_count = vertices.shape[1], len(faces)
    rng = np.random.default_rng(5)
    return MeshSequence(
        vertices,
        faces,
        attributes=[
            Attribute("N", "vertex", rng.random((vertex_count, 3), np.float32), role="normal"),
            Attribute("st", "vertex", rng.random((vertex_count, 2)), role="uv"),
            Attribute("rest", "vertex", rng.random((vertex_count, 1), np.float32)),
            Attribute("material", "face", rng.integers(-3, 9, (face_count, 1), dtype=np.int32)),
            Attribute("tint", "face", rng.random((face_count, 4), np.float32), role="color"),
        ],
        fields=[
            Field("velocity", rng.random((frames, vertex_count, 3), np.float32), role="velocity"),
            Field("Colors", rng.random((frames, vertex_count, 3)), role="color"),
            Field("heat", rng.random((frames, face_count, 1)), domain="face"),
            Field("flux", rng.random((frames, face_count, 2), np.float32), domain="face"),
        ],
    )


def assert_same_attached(back: MeshSequence, seq: MeshSequence) -> None:
    assert sorted(a.name for a in back.attributes) == sorted(a.name for a in seq.attributes)
    for attribute in seq.attributes:
        assert back.attribute_named(attribute.name).same_as(attribute), attribute.name
    assert [f.name for f in back.fields] == [f.name for f in seq.fields]
    for item in seq.fields:
        found = back.field_named(item.name)
        assert (found.domain, found.role) == (item.domain, item.role)
        assert same_bits(found.values, item.values), item.name


@pytest.mark.parametrize("suffix", [".vtp", ".vtu"])
@pytest.mark.parametrize(
    "layout", [None, Layout(format="ascii"), Layout(format="binary", byte_order="BigEndian")]
)
def test_attributes_and_fields_round_trip_bit_for_bit(tmp_path, suffix, layout):
    seq = attached_sequence()
    write_pvd(seq, tmp_path / "a.pvd", WriteOptions(), frame_suffix=suffix, layout=layout)
    back = load_sequence(tmp_path / "a.pvd")
    assert np.array_equal(back.vertices, seq.vertices)
    assert np.array_equal(back.faces, seq.faces)
    assert_same_attached(back, seq)


def test_fields_are_read_a_range_at_a_time(tmp_path):
    seq = attached_sequence(frames=6)
    save_sequence(seq, tmp_path / "a.pvd")
    source = PvdFrames(tmp_path / "a.pvd")
    assert source.field_names == ["velocity", "Colors", "heat", "flux"]
    for start, stop in [(0, 2), (2, 6), (3, 4), (0, 6)]:
        for item, original in zip(source.read_fields(start, stop), seq.fields, strict=True):
            assert same_bits(item.values, original.values[start:stop])


def test_what_the_series_cannot_keep_is_named(tmp_path):
    seq = attached_sequence()
    corners = int((seq.faces >= 0).sum())
    table = np.array([[0.0, 0.0], [1.0, 1.0]], dtype=np.float32)
    seq.attributes += [
        Attribute("uv corners", "corner", np.zeros((corners, 2), np.float32), role="uv"),
        Attribute("indexed", "vertex", table, np.arange(seq.vertex_count) % 2, role="uv"),
    ]
    seq.face_sets = [FaceSet("cloth", np.array([0, 2, 3]), "materialBind")]
    lost = cannot_keep(seq)
    assert lost == [
        "attribute 'uv corners': per face corner",
        "attribute 'indexed': its indices (written one value per vertex)",
        "face set 'cloth' (materialBind)",
    ]
    save_sequence(seq, tmp_path / "a.pvd")
    back = load_sequence(tmp_path / "a.pvd")
    expanded = back.attribute_named("indexed")  # its values kept, one per vertex
    assert expanded.indices is None and same_bits(expanded.values, table[np.arange(16) % 2])
    assert "uv corners" not in [a.name for a in back.attributes] and not back.face_sets
    assert cannot_keep(attached_sequence()) == []


def test_a_point_sequence_keeps_its_point_data_and_names_its_face_data(tmp_path):
    vertices = wave_sequence(3, 3)
    seq = MeshSequence(
        vertices,
        np.zeros((0, 3), np.int64),
        fields=[
            Field("v", np.ones((3, 9, 3))),
            Field("per face", np.zeros((3, 0, 1)), domain="face"),
        ],
    )
    assert cannot_keep(seq) == ["field 'per face': per face, of a mesh without faces"]
    save_sequence(seq, tmp_path / "p.pvd")
    back = load_sequence(tmp_path / "p.pvd")
    assert [f.name for f in back.fields] == ["v"]
    assert same_bits(back.fields[0].values, seq.fields[0].values)


# ------------------------------------------------------------------------------------------
# series VTK wrote


def test_a_polydata_series_vtk_wrote_is_read_with_its_point_and_cell_data():
    source = PvdFrames(DATA / "datasurface.pvd")
    seq = source.load()
    n = np.arange(STEPS)[:, None, None]
    # the active normals and texture coordinates: static, the first step's, bit for bit
    normals = seq.attribute_named("Normals")
    assert normals.role == "normal" and normals.domain == "vertex"
    assert same_bits(normals.values, np.tile(np.array([0, 0, 1], np.float32), (9, 1)))
    uv = seq.attribute_named("uv_map")
    assert uv.role == "uv" and same_bits(uv.values, (SURFACE[:, :2] / 4).astype(np.float32))
    ids = seq.attribute_named("ids")  # vtkIdType (Int64) ids, constant: int32
    assert same_bits(ids.values, np.arange(9, dtype=np.int32)[:, None])
    # the faces: 3 polygons, then the strip's 3 triangles; the vertex cell is no face
    assert len(seq.faces) == 6
    cells = np.array([1, 2, 3, 4, 4, 4])  # each face's cell in VTK's order (verts first)
    material = seq.attribute_named("material")
    assert material.domain == "face"
    assert same_bits(material.values, np.array([7, 1, 2, 3, 4], np.int32)[cells, None])
    pressure = seq.field_named("pressure")
    assert pressure.domain == "vertex" and pressure.role == "generic"
    rows = np.arange(STEPS)[:, None]
    assert same_bits(pressure.values, (np.arange(9) * 0.25 + rows).astype(np.float32)[..., None])
    velocity = seq.field_named("velocity")
    assert velocity.role == "velocity"
    assert same_bits(velocity.values, np.arange(27).reshape(9, 3) / 7 * (n + 1))
    heat = seq.field_named("heat")
    assert heat.domain == "face"
    assert same_bits(heat.values, (np.arange(5) * 1.5 + rows / 7)[:, cells, None])
    assert [f.name for f in seq.fields] == ["pressure", "velocity", "heat"]
    assert source.skipped == ["point array 'stress': 6 components (1 to 4 are kept)"]


def test_an_unstructured_grid_series_vtk_wrote_maps_cell_data_to_its_faces():
    seq = load_sequence(DATA / "datagrid.pvd")
    n = np.arange(STEPS)[:, None]
    assert len(seq.faces) == 4  # the vertex cell (cell 2) is no face
    heat = seq.field_named("heat")
    expected = (np.arange(5) + n * 0.5).astype(np.float32)[:, [0, 1, 3, 4], None]
    assert same_bits(heat.values, expected)
    assert same_bits(seq.field_named("temperature").values, (np.arange(8) / 3 + n)[..., None])


def test_the_same_name_on_points_and_cells_keeps_both(tmp_path):
    seq = MeshSequence(
        wave_sequence(2, 3),
        grid_faces(3),
        fields=[Field("p", np.ones((2, 9, 1))), Field("p2", np.full((2, 8, 1), 2.0), "face")],
    )
    save_sequence(seq, tmp_path / "a.pvd")
    for path in (tmp_path / "a").iterdir():  # as a solver names its point and cell arrays
        path.write_bytes(path.read_bytes().replace(b'Name="p2"', b'Name="p"'))
    source = PvdFrames(tmp_path / "a.pvd")
    back = source.load()
    assert [f.name for f in back.fields] == ["p", "p (cell)"]
    assert same_bits(back.fields[1].values, seq.fields[1].values)
    assert source.skipped == ["cell array 'p': named 'p (cell)', a point array has its name"]


def test_an_integer_array_that_changes_is_refused_naming_the_step(tmp_path):
    seq = MeshSequence(
        wave_sequence(3, 3),
        grid_faces(3),
        attributes=[Attribute("ids", "vertex", np.arange(9, dtype=np.int32))],
    )
    write_pvd(seq, tmp_path / "a.pvd", WriteOptions(), layout=Layout(format="ascii"))
    step = tmp_path / "a" / "frame_00002.vtp"
    text = step.read_text().replace(' tuckercodec_static="1"', "")
    step.write_text(text.replace("0 1 2 3 4 5 6 7 8", "0 1 2 3 4 5 6 7 9"))
    (tmp_path / "a" / "frame_00000.vtp").write_text(
        (tmp_path / "a" / "frame_00000.vtp").read_text().replace(' tuckercodec_static="1"', "")
    )
    source = PvdFrames(tmp_path / "a.pvd")
    assert source.read_fields(0, 2) == []  # no fields: nothing read
    expect_input_error(
        lambda: source.load(),
        step,
        match="point array 'ids' differs from the first step's",
        frame=2,
    )


def write_temperature_series(folder: Path) -> None:
    """``folder/a.pvd``: 3 ascii steps (their text is easy to spoil) with a point field
    ``temp`` of zeros."""
    seq = MeshSequence(
        wave_sequence(3, 3), grid_faces(3), fields=[Field("temp", np.zeros((3, 9, 1)))]
    )
    write_pvd(seq, folder / "a.pvd", WriteOptions(), layout=Layout(format="ascii"))


def test_a_field_missing_from_a_later_step_is_named(tmp_path):
    write_temperature_series(tmp_path)
    step = tmp_path / "a" / "frame_00001.vtp"
    step.write_text(step.read_text().replace('Name="temp"', 'Name="other"'))
    expect_input_error(
        lambda: load_sequence(tmp_path / "a.pvd"),
        step,
        match="has no point array 'temp', which the first step has",
        frame=1,
    )


def test_a_non_finite_field_value_is_named(tmp_path):
    write_temperature_series(tmp_path)
    step = tmp_path / "a" / "frame_00002.vtp"
    text = step.read_text()
    start = text.index('Name="temp"')
    at = text.index("0.0", start)
    step.write_text(text[:at] + "nan" + text[at + 3 :])
    expect_input_error(
        lambda: load_sequence(tmp_path / "a.pvd"),
        step,
        match="point array 'temp' has a non-finite value at vertex 0",
        frame=2,
    )


# ------------------------------------------------------------------------------------------
# VTK's own reader, and the real cloth


def test_vtks_own_reader_reads_our_point_and_cell_data(tmp_path):
    pyvista = pytest.importorskip(
        "pyvista", reason="pyvista (VTK's Python package) is not installed: VTK's own readers"
    )
    seq = attached_sequence(frames=3)
    for suffix in (".vtp", ".vtu"):
        path = tmp_path / f"w{suffix[1:]}.pvd"
        write_pvd(seq, path, WriteOptions(), frame_suffix=suffix)
        reader = pyvista.PVDReader(path)
        for frame, time in enumerate(reader.time_values):
            reader.set_active_time_value(time)
            mesh = reader.read()[0]
            for attribute in seq.attributes:
                data = mesh.point_data if attribute.domain == "vertex" else mesh.cell_data
                found = np.asarray(data[attribute.name]).reshape(attribute.values.shape)
                expected = attribute.values
                if frame and attribute.role == "normal":  # later frames': moved with the mesh
                    expected = recomputed_normals(seq.vertices[frame], seq.faces, attribute)
                assert same_bits(found, expected), (attribute.name, frame)
            for item in seq.fields:
                data = mesh.point_data if item.domain == "vertex" else mesh.cell_data
                found = np.asarray(data[item.name]).reshape(item.values.shape[1:])
                assert same_bits(found, item.values[frame]), item.name
            assert mesh.point_data.active_normals_name == "N"
            assert mesh.point_data.active_texture_coordinates_name == "st"


def test_the_cloth_keeps_a_velocity_field_of_its_own_positions(tmp_path):
    with np.load(shared_file("cloth-vellum.npz"), allow_pickle=False) as data:
        positions, faces = data["V"], data["F"]
    rate = 24.0  # the file has no rate: the default
    velocity = (np.gradient(positions.astype(np.float64), axis=0) * rate).astype(np.float32)
    seq = MeshSequence(
        positions, faces, frame_rate=rate, fields=[Field("velocity", velocity, role="velocity")]
    )
    save_sequence(seq, tmp_path / "cloth.pvd")
    back = load_sequence(tmp_path / "cloth.pvd")
    assert np.array_equal(back.vertices, positions.astype(np.float64))
    assert back.fields[0].role == "velocity"
    assert same_bits(back.fields[0].values, velocity)
