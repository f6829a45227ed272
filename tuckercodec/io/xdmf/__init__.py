"""XDMF time series (``.xdmf``, ``.xmf``): a temporal collection of grids, each with its own
geometry, the way VTK, ParaView and many simulation codes write a moving mesh. The XML is read
with the standard library; heavy data in HDF5 files through h5py (the ``[xdmf]`` extra, needed
only where a file names HDF data); data inline in the XML (``Format="XML"``) needs nothing.

Reading: the ``<Domain>``'s ``<Grid GridType="Collection" CollectionType="Temporal">`` (or a
single uniform grid: one frame), whose child grids are the frames, ordered by time: each
grid's ``<Time Value=..>``, or the collection's ``<Time TimeType="List">`` or ``"HyperSlab"``;
the times become the time codes (without any, the listed order holds). ``<Geometry>``: XYZ,
X_Y_Z, or XY (z = 0); positions keep their precision (``Precision="4"`` floats are float32).
``<Topology>``: Triangle, Quadrilateral, Polygon, Mixed (of triangles, quadrilaterals, polygons
and polyvertices) become faces in the file's order, rows padded with -1; Polyvertex gives a
point sequence; volume, line and higher-order topologies are refused. ``<DataItem>``s are read
as XML or HDF (``file.h5:/dataset``, relative to the .xdmf's folder), and ``Reference``s to
other elements (``/Xdmf/...`` paths) followed. ``xi:include`` is not followed.

A series whose time steps share one geometry (the same element, the same HDF dataset, or an
``xi:include`` of another grid's, as meshio's and FEniCS's time series are) is a static mesh
with changing point data, not a moving mesh: it is refused saying so. Several temporal
collections, or a spatial collection per step (several parts), are refused too. Steps are read
as their frames are asked for, a range at a time (:class:`XdmfFrames`); the check that no two
steps share a geometry then covers the steps read so far.

Hostile input: an ENTITY (or any other) declaration is refused by the parser, whatever the
encoding (:mod:`~tuckercodec.io.common.safe_xml`; a DOCTYPE alone, which XDMF files carry, is
harmless: the parser never fetches it); HDF5 files must lie inside the .xdmf's folder and keep
their data inside themselves (no external storage, virtual datasets or external links); every
count is checked against the data
before it is used; an HDF dataset must hold as many values as its ``Dimensions`` and store at
least 1/1032 of its size (no more than zlib can inflate), and one step's datasets inflate
within ``--max-memory`` together (:mod:`.items`). Errors name the .xdmf, the frame and the
grid. Writing is :mod:`.writer`'s.

A grid's ``<Attribute>``s centred on nodes or cells (one row per point or cell; a cell's value
goes to the face it is, a polyvertex's nowhere) are read as VTK's point and cell data are
(:mod:`~tuckercodec.io.common.data_arrays`): float ones animated fields read a range of steps at
a time, normals and UVs static attributes of the first step's values, integer ones static
attributes every later step must repeat; others (of more than 4 components, centred on edges or
grids) are noted in :attr:`XdmfFrames.skipped`.
"""

from .series import (
    XdmfFrames,
)

__all__ = [
    "XdmfFrames",
]
