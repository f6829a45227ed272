"""XDMF series' attributes (tuckercodec/io/xdmf): the sequence's vertex and face attributes and
fields written as node and cell <Attribute>s and read back bit for bit, VTK's own XDMF reader
(pyvista) reading them, cell values mapped to the faces of a Mixed topology, and a changing
integer attribute named."""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.sequences import grid_faces, wave_sequence
from tests.test_io_vtk_data import assert_same_attached, attached_sequence, same_bits
from tuckercodec import Attribute, InputError, MeshSequence, load_sequence, save_sequence
from tuckercodec.io.registry import format_named
from tuckercodec.io.xdmf import XdmfFrames

H5PY_MISSING = "the [xdmf] extra (h5py) is not installed"


def test_attributes_and_fields_round_trip_bit_for_bit(tmp_path):
    pytest.importorskip("h5py", reason=H5PY_MISSING)
    seq = attached_sequence(frames=5)
    save_sequence(seq, tmp_path / "a.xdmf")
    back = load_sequence(tmp_path / "a.xdmf")
    assert np.array_equal(back.vertices, seq.vertices)
    assert_same_attached(back, seq)
    source = XdmfFrames(tmp_path / "a.xdmf")
    for found, item in zip(source.read_fields(1, 4), seq.fields, strict=True):
        assert same_bits(found.values, item.values[1:4])
    hook = format_named("xdmf").cannot_keep
    assert hook is not None and hook(seq) == []


def test_vtks_own_xdmf_reader_reads_our_attributes(tmp_path):
    pytest.importorskip("h5py", reason=H5PY_MISSING)
    pyvista = pytest.importorskip("pyvista", reason="pyvista (VTK's Python package) is absent")
    seq = attached_sequence(frames=3)
    save_sequence(seq, tmp_path / "a.xdmf")
    reader = pyvista.XdmfReader(str(tmp_path / "a.xdmf"))
    for frame, time in enumerate(reader.time_values):
        reader.set_active_time_value(time)
        mesh = reader.read()
        arrays = [(a.name, a.domain, a.values) for a in seq.attributes]
        arrays += [(f.name, f.domain, f.values[frame]) for f in seq.fields]
        for name, domain, values in arrays:
            found = np.asarray((mesh.point_data if domain == "vertex" else mesh.cell_data)[name])
            found = found.reshape(len(values), -1)
            if values.shape[1] == 2:  # VTK pads a vector of 2 with a zero third component
                assert not found[:, 2:].any()
                found = found[:, :2]
            assert same_bits(found, values), name


def document(heat: list[str], ids: list[str]) -> str:
    """Two steps of a Mixed topology (a triangle, a polyvertex, a quad) with inline data."""
    grids = [
        f"""<Grid Name="s{step}"><Time Value="{step}"/>
<Topology TopologyType="Mixed" NumberOfElements="3">
<DataItem Dimensions="12" NumberType="Int" Format="XML">4 0 1 2 1 1 4 5 0 2 3 4</DataItem>
</Topology>
<Geometry GeometryType="XYZ"><DataItem Dimensions="5 3" Format="XML">
0 0 0 1 0 0 1 1 {step} 0 1 0 2 2 2</DataItem></Geometry>
<Attribute Name="heat" Center="Cell">
<DataItem Dimensions="3" Format="XML">{heat[step]}</DataItem></Attribute>
<Attribute Name="ids" Center="Node">
<DataItem Dimensions="5" NumberType="Int" Format="XML">{ids[step]}</DataItem></Attribute>
<Attribute Name="stress" Center="Node" AttributeType="Tensor">
<DataItem Dimensions="5 9" Format="XML">{" ".join(["1"] * 45)}</DataItem></Attribute>
<Attribute Name="edge" Center="Edge"><DataItem Dimensions="1" Format="XML">1</DataItem></Attribute>
</Grid>"""
        for step in range(2)
    ]
    return (
        '<?xml version="1.0"?><Xdmf Version="3.0"><Domain>'
        '<Grid GridType="Collection" CollectionType="Temporal">'
        + "".join(grids)
        + "</Grid></Domain></Xdmf>"
    )


def test_cell_values_follow_the_faces_and_integers_are_static(tmp_path):
    path = tmp_path / "m.xdmf"
    path.write_text(document(["1.5 9 2.5", "3.5 9 4.5"], ["0 1 2 3 4"] * 2))
    source = XdmfFrames(path)
    seq = source.load()
    assert seq.faces.tolist() == [[0, 1, 2, -1], [0, 2, 3, 4]]
    heat = seq.field_named("heat")
    assert heat.domain == "face" and heat.values[..., 0].tolist() == [[1.5, 2.5], [3.5, 4.5]]
    ids = seq.attribute_named("ids")
    assert same_bits(ids.values, np.arange(5, dtype=np.int32)[:, None])
    assert source.skipped == [
        "attribute 'edge': it is centred on edges (node and cell attributes are read)",
        "point array 'stress': 9 components (1 to 4 are kept)",
    ]


def test_an_integer_attribute_that_changes_is_refused_naming_the_step(tmp_path):
    path = tmp_path / "m.xdmf"
    path.write_text(document(["1 2 3"] * 2, ["0 1 2 3 4", "0 1 2 3 5"]))
    with pytest.raises(InputError, match="point array 'ids' differs from the first") as caught:
        load_sequence(path)
    assert (caught.value.path, caught.value.frame) == (str(path), 1)


def test_a_corner_attribute_is_named_as_not_kept():
    faces = grid_faces(3)
    seq = MeshSequence(
        wave_sequence(2, 3),
        faces,
        attributes=[Attribute("uv", "corner", np.zeros((faces.size, 2)), role="uv")],
    )
    hook = format_named("xdmf").cannot_keep
    assert hook is not None and hook(seq) == ["attribute 'uv': per face corner"]
