"""VTK time series (``.pvd``): a ParaView collection of one ``.vtp`` (PolyData) or ``.vtu``
(UnstructuredGrid) file per time step, the way simulation codes write a deforming mesh. Core:
the files are read and written by :mod:`.datasets` in plain numpy and the standard library, no
extra needed; the ``.pvd`` index is read with the standard library's XML parser.

Reading: the ``.pvd`` must be ``<VTKFile type="Collection">`` with a ``<Collection>`` of
``<DataSet timestep=".." part=".." file=".."/>``; ``file`` is relative to the ``.pvd``'s folder
and must lie inside it (an absolute path, or ``..`` or a symbolic link that leads out, is
refused). The frames are ordered by ``timestep``, which becomes the time codes, in the
simulation's own unit (the frame rate stays unknown); without timesteps the listed order holds.
One mesh per time step: several ``part`` values, or one timestep listed twice, are refused
(merge the parts first, ParaView's Merge Blocks), as are parallel files (``.pvtu``, ``.pvtp``).
Each file must have the first one's points and faces; what is read of each (every encoding VTK
writes; triangles, quads, polygons, strips; what is refused) is :mod:`.datasets`'s docstring.
Positions keep their precision (float64 stays float64). :class:`PvdFrames` reads the files as
their frames are asked for, a range at a time. XDMF is not read here.

Point and cell data (:mod:`.data`, :mod:`~tuckercodec.io.common.data_arrays` for the rules):
float arrays are animated fields (per vertex, or per face: a cell's value goes to the faces it
makes, a strip's to each of its triangles, a vertex cell's nowhere), read a range of steps at a
time (:meth:`PvdFrames.read_fields`); the active normals and texture coordinates are static
attributes of the first step's values; integer arrays static int32 attributes, which every
later step must repeat. Arrays of more than 4 components, strings and bits are not read: each
is noted in :attr:`PvdFrames.skipped`. Attributes list point arrays before cell arrays.

Hostile input: a ``.pvd`` larger than :data:`MAX_INDEX_BYTES` is refused before it is parsed;
one that declares a DOCTYPE or an ENTITY (the way to an entity-expansion attack; a ``.pvd``
needs neither) is refused by the parser, whatever its encoding, as is such a ``.vtu``/``.vtp``
(:mod:`~tuckercodec.io.common.safe_xml`). A listed file that is missing,
not a regular file or not VTK XML is named with the DataSet that lists it. Sizes inside a file
are checked before anything is allocated or inflated, and what one file's compressed arrays
inflate to is bounded by ``--max-memory`` (:attr:`~tuckercodec.io.registry.ReadOptions.max_memory`,
by default half the machine's memory; :mod:`.arrays`).

Writing ``out.pvd``: one ``.vtp`` per frame (:data:`FRAME_SUFFIX`; ``.vtu`` on request) in the
folder ``out/`` beside it (names from :func:`~tuckercodec.io.frames.frame_file_names`), in
ParaView's own layout (appended raw binary, zlib blocks, UInt64 headers), Float32 when every
position is a float32 (exact either way), Float64 otherwise. Vertex and face attributes and
fields are point and cell arrays of every file (static ones repeated), in their own types,
tagged with their role and whether they are static so that reading gives them back; the
normals and texture coordinates are VTK's active ones. What the files cannot hold (attributes
per face corner, the indices of indexed attributes, face sets) is listed by
:func:`cannot_keep`. PolyData is ParaView's surface type:
its surface filters (normals, smoothing, decimation) take it directly, where an UnstructuredGrid
first needs Extract Surface. Every target is checked first (never overwritten without
``overwrite``), the frames are staged in a hidden folder and moved in whole
(:func:`~tuckercodec.system.atomic.atomic_folder`), and the ``.pvd`` is written last, atomically.
"""

from .series import (
    FRAME_SUFFIX,
    MAX_INDEX_BYTES,
    PvdFrames,
    cannot_keep,
    write_pvd,
)

__all__ = [
    "FRAME_SUFFIX",
    "MAX_INDEX_BYTES",
    "PvdFrames",
    "cannot_keep",
    "write_pvd",
]
