"""Writing XDMF time series: ``out.xdmf`` (the XML) and ``out.h5`` beside it (the heavy data,
HDF5 through h5py: the ``[xdmf]`` extra).

One temporal collection of one uniform grid per frame, each with its own ``<Geometry>`` (XYZ,
``Precision="4"`` when every position is a float32, exact either way, else 8), its
``<Time Value>`` (the time code) and its ``Name`` (the frame's name); every grid's
``<Topology>`` reads the one ``/topology`` dataset (Triangle, Quadrilateral, Mixed for polygons
or mixed sizes, Polyvertex for a point sequence). The attribute names are XDMF 2's, which XDMF 3
readers accept too, so that VTK's and ParaView's XDMF readers read it. Vertex and face
attributes and fields are ``<Attribute>``s of every grid (``Center="Node"`` or ``"Cell"``,
Scalar, or Vector for 2 to 4 components, in their own types, tagged with their role
and whether they are static): a static one's grids all read one dataset (``/static/<i>``), a
field's each its frame's (``/field/<i>/<frame>``); what cannot be kept is :func:`cannot_keep`'s.
Both targets are checked first (never overwritten without ``overwrite``); the .h5 is written
under a hidden name and put in place whole (:func:`~tuckercodec.system.atomic.atomic_path`), then
the .xdmf, atomically.
"""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ...model.attributes import VERTEX
from ...model.sequence import MeshSequence
from ...system.atomic import atomic_path, refuse_existing, write_atomic
from ...system.optional import import_optional
from ..common.data_arrays import (
    ROLE_TAG,
    STATIC_TAG,
    TargetArray,
    arrays_to_write,
    cannot_keep_arrays,
)
from ..registry import WriteOptions


def write_xdmf(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write ``path`` (.xdmf or .xmf) and its heavy data beside it (same name, ``.h5``)."""
    h5py = import_optional("h5py", "xdmf", "writing XDMF (its HDF5 heavy data)")
    heavy = path.with_suffix(".h5")
    if heavy == path:
        raise ValueError(f"{path}: an XDMF file needs a name other than its heavy data's (.h5)")
    refuse_existing([path, heavy], options.overwrite)
    try:
        targets = arrays_to_write(seq)
    except InputError as error:
        raise InputError(error.reason, path=path) from None
    points = seq.compact_vertices()  # float32 where exact, else float64
    kind, topology, attributes = _topology(seq.faces, seq.vertex_count)
    with (
        atomic_path(heavy, overwrite=options.overwrite) as temporary,
        h5py.File(temporary, "w") as file,
    ):
        file.create_dataset("topology", data=topology)
        for index in range(seq.frame_count):
            file.create_dataset(f"points/{index:06d}", data=points[index])
        for number, target in enumerate(targets):
            if target.static:
                file.create_dataset(f"static/{number}", data=target.at(0))
            else:
                for index in range(seq.frame_count):
                    file.create_dataset(f"field/{number}/{index:06d}", data=target.at(index))
    xml = _xml(seq, heavy.name, kind, topology, attributes, points.dtype, targets)
    write_atomic(path, xml, overwrite=options.overwrite)


def _topology(faces: np.ndarray, vertex_count: int) -> tuple[str, np.ndarray, dict[str, str]]:
    """The topology type, its values and its attributes for a face table."""
    if len(faces) == 0:
        values = np.arange(vertex_count)
        return "Polyvertex", _narrow(values), {"NumberOfElements": str(vertex_count)}
    sizes = (faces >= 0).sum(axis=1)
    count = {"NumberOfElements": str(len(faces))}
    if (sizes == faces.shape[1]).all() and faces.shape[1] in (3, 4):
        return ("Triangle" if faces.shape[1] == 3 else "Quadrilateral"), _narrow(faces), count
    # Mixed: each cell's XDMF code (4 triangle, 5 quadrilateral, 3 polygon + its size), corners
    polygon = (sizes != 3) & (sizes != 4)
    head = np.where(polygon, 2, 1)
    ends = np.cumsum(head + sizes)
    starts = ends - head - sizes
    values = np.empty(int(ends[-1]) if len(ends) else 0, dtype=np.int64)
    values[starts] = np.where(sizes == 3, 4, np.where(sizes == 4, 5, 3))
    values[starts[polygon] + 1] = sizes[polygon]
    corners = np.repeat(starts + head - (np.cumsum(sizes) - sizes), sizes)
    values[corners + np.arange(corners.size)] = faces[faces >= 0]
    return "Mixed", _narrow(values), count


def _narrow(values: np.ndarray) -> np.ndarray:
    """Int32 where every value fits, as most XDMF writers store topologies."""
    small = values.size == 0 or values.max() <= np.iinfo(np.int32).max
    return values.astype(np.int32 if small else np.int64)


def _xml(
    seq: MeshSequence,
    heavy: str,
    kind: str,
    topology: np.ndarray,
    attributes: dict[str, str],
    point_type: np.dtype,
    targets: list[TargetArray],
) -> bytes:
    """The XDMF document of the written heavy data."""
    root = ElementTree.Element("Xdmf", Version="3.0")
    domain = ElementTree.SubElement(root, "Domain")
    collection = ElementTree.SubElement(
        domain, "Grid", Name="frames", GridType="Collection", CollectionType="Temporal"
    )
    topology_item = {
        "Dimensions": " ".join(map(str, topology.shape)),
        "NumberType": "Int",
        "Precision": str(topology.dtype.itemsize),
        "Format": "HDF",
    }
    for index, (name, code) in enumerate(zip(seq.frame_names, seq.codes(), strict=True)):
        grid = ElementTree.SubElement(collection, "Grid", Name=name, GridType="Uniform")
        ElementTree.SubElement(grid, "Time", Value=repr(float(code)))
        element = ElementTree.SubElement(grid, "Topology", {"TopologyType": kind, **attributes})
        item = ElementTree.SubElement(element, "DataItem", topology_item)
        item.text = f"{heavy}:/topology"
        geometry = ElementTree.SubElement(grid, "Geometry", GeometryType="XYZ")
        item = ElementTree.SubElement(
            geometry,
            "DataItem",
            Dimensions=f"{seq.vertex_count} 3",
            NumberType="Float",
            Precision=str(point_type.itemsize),
            Format="HDF",
        )
        item.text = f"{heavy}:/points/{index:06d}"
        for number, target in enumerate(targets):
            _attribute_xml(grid, target, heavy, number, index)
    ElementTree.indent(root)
    return ElementTree.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"


#: XDMF's attribute type of each component count: Vector for 2 to 4, as meshio writes them
#: (VTK's XDMF reader reads 4 components as they are and pads 2 with a zero third; its
#: Matrix is one row for the whole grid).


def _attribute_xml(
    grid: ElementTree.Element, target: TargetArray, heavy: str, number: int, frame: int
) -> None:
    """The ``<Attribute>`` of ``target`` at ``frame`` in ``grid``: a static one reads one
    dataset at every step, a field its frame's."""
    values = target.at(frame)
    element = ElementTree.SubElement(
        grid,
        "Attribute",
        {
            "Name": target.name,
            "AttributeType": "Scalar" if values.shape[1] == 1 else "Vector",
            "Center": "Node" if target.domain == VERTEX else "Cell",
            ROLE_TAG: target.role,
        },
    )
    if target.static:
        element.set(STATIC_TAG, "1")
    item = ElementTree.SubElement(
        element,
        "DataItem",
        Dimensions=" ".join(map(str, values.shape)),
        NumberType="Float" if values.dtype.kind == "f" else "Int",
        Precision=str(values.dtype.itemsize),
        Format="HDF",
    )
    dataset = f"static/{number}" if target.static else f"field/{number}/{frame:06d}"
    item.text = f"{heavy}:/{dataset}"


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What an XDMF series cannot keep of ``seq`` (the format's ``cannot_keep``): attributes
    per face corner, the indices of indexed attributes (written one value per element), face
    sets."""
    return cannot_keep_arrays(seq)
