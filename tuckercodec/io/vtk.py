"""VTK time series (``.pvd``): a ParaView collection of one ``.vtu`` file per time step, the
way simulation codes write a deforming mesh. The ``.vtu`` files are read and written with
meshio (the ``[vtk]`` extra); the ``.pvd`` index with the standard library's XML parser.

Reading: the ``.pvd`` must be ``<VTKFile type="Collection">`` with a ``<Collection>`` of
``<DataSet timestep=".." part=".." file=".."/>``; ``file`` is relative to the ``.pvd``'s folder
(or absolute). The frames are ordered by ``timestep``, which becomes the time codes, in the
simulation's own unit (the frame rate stays unknown); without timesteps the listed order holds.
One mesh per time step: several ``part`` values, or one timestep listed twice, are refused
(merge the parts first, ParaView's Merge Blocks). Each file must have the first one's points and
cells. Cells: triangles, quads and polygons become the faces, in the file's order (mixed sizes
padded with -1); vertex cells only mark points; a file of points only is a point sequence.
Lines, volume cells (tetrahedra, hexahedra...) and higher-order cells are refused: the codec
compresses surfaces (ParaView's Extract Surface makes one). Positions keep their precision
(float64 stays float64). meshio reads ``.vtu`` only: a ``.vtp`` (PolyData) is refused, and
XDMF is not read (meshio's XDMF time series holds one geometry and per-step data arrays, not a
moving mesh).

Hostile input: a ``.pvd`` larger than :data:`MAX_INDEX_BYTES`, or one that declares a DOCTYPE or
an ENTITY (the way to an entity-expansion attack; a ``.pvd`` needs neither), is refused before it
is parsed, as is a ``.vtu`` with either in its prolog. A listed file that is missing, not a
regular file or not VTK XML is named with the DataSet that lists it.

Writing ``out.pvd``: one ``.vtu`` per frame in the folder ``out/`` beside it (names from
:func:`.frames.frame_file_names`), zlib-compressed binary, Float32 when every position is a
float32 (exact either way), Float64 otherwise. Every target is checked first (never overwritten
without ``overwrite``), the frames are staged in a hidden folder and moved in whole
(:func:`~tuckercodec.atomic.atomic_folder`), and the ``.pvd`` is written last, atomically.
"""

from __future__ import annotations

import itertools
import re
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any
from xml.etree import ElementTree

import numpy as np

from ..atomic import atomic_folder, refuse_existing, write_atomic
from ..errors import InputError
from ..optional import import_optional
from ..reading import open_regular_file
from ..sequence import MeshSequence
from ..topology import face_table_problem
from .frames import frame_file_names
from .registry import ReadOptions, SequenceFormat, WriteOptions

#: The largest .pvd index read: about a million time steps, far beyond any real series.
MAX_INDEX_BYTES = 64 * 1024 * 1024
#: meshio's names of the cells kept as faces (one row per cell); "vertex" cells are skipped.
SURFACE_CELLS = ("triangle", "quad", "polygon")
_POINT_CELLS = ("vertex",)
#: XML declarations refused in a .pvd or a .vtu prolog: they open the door to entity expansion.
_DECLARATIONS = (b"<!DOCTYPE", b"<!ENTITY")
_PIECE = re.compile(rb"<Piece\b([^>]*)>")
_CELL_COUNT = re.compile(rb"""\bNumberOfCells\s*=\s*["']\s*(\d+)\s*["']""")


def read_pvd(path: Path, options: ReadOptions) -> MeshSequence:
    """A sequence from a ParaView ``.pvd`` collection of ``.vtu`` files (see the module
    docstring); the format takes no read options."""
    meshio = import_optional("meshio", "vtk", "reading VTK time series (.pvd)")
    entries = _collection(path)
    vertices: np.ndarray | None = None
    faces = np.zeros((0, 3), dtype=np.int64)
    first = entries[0].file
    for index, entry in enumerate(entries):
        points, cells = _read_vtu(meshio, entry.file, path, index)
        if vertices is None:
            vertices = np.empty((len(entries), *points.shape), dtype=np.float64)
            faces = cells
        elif len(points) != vertices.shape[1]:
            raise InputError(
                f"has {len(points)} points but the first frame ({first}) has "
                f"{vertices.shape[1]}: every frame of {path.name} must have the same points",
                path=entry.file,
                frame=index,
            )
        elif not np.array_equal(cells, faces):
            raise InputError(
                f"its cells differ from the first frame's ({first}): every frame of "
                f"{path.name} must have the same cells",
                path=entry.file,
                frame=index,
            )
        vertices[index] = points
    assert vertices is not None
    timed = entries[0].timestep is not None
    codes = np.array([entry.timestep for entry in entries], dtype=np.float64) if timed else None
    try:
        return MeshSequence(
            vertices, faces, frame_names=[entry.name for entry in entries], time_codes=codes
        )
    except InputError as error:
        raise InputError(error.reason, path=path, frame=error.frame) from None


@dataclass(frozen=True)
class _Entry:
    """One DataSet of a collection: its time step (``None`` if not given), file and name."""

    timestep: float | None
    file: Path
    name: str

    def sort_key(self) -> float:
        return 0.0 if self.timestep is None else self.timestep


def _collection(path: Path) -> list[_Entry]:
    """The DataSets of a .pvd, ordered by time step; the index is checked before parsing."""
    try:
        stream = open_regular_file(path, "a ParaView .pvd collection")
    except OSError as error:
        raise InputError(f"cannot read: {error.strerror or error}", path=path) from None
    with stream:
        data = stream.read(MAX_INDEX_BYTES + 1)
    if len(data) > MAX_INDEX_BYTES:
        raise InputError(
            f"is larger than {MAX_INDEX_BYTES} bytes, far more than an index of time steps needs",
            path=path,
        )
    _refuse_declarations(data, path)
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as error:
        raise InputError(f"is not well-formed XML: {error}", path=path) from None
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise InputError(
            f'is not a ParaView collection: its root is <{root.tag} type="{root.get("type")}">, '
            'not <VTKFile type="Collection">',
            path=path,
        )
    datasets = root.findall("./Collection/DataSet")
    if not datasets:
        raise InputError(
            "lists no <DataSet> in a <Collection>: there is nothing to read", path=path
        )
    entries = [_entry(dataset, number, path) for number, dataset in enumerate(datasets)]
    _check_parts(datasets, path)
    timed = [entry.timestep is not None for entry in entries]
    if any(timed) and not all(timed):
        missing = timed.index(False)
        raise InputError(
            f"DataSet {missing} has no timestep while others do: which time is it?", path=path
        )
    if all(timed):
        entries.sort(key=_Entry.sort_key)
        for before, after in itertools.pairwise(entries):
            if before.timestep == after.timestep:
                raise InputError(
                    f"lists timestep {after.timestep} twice ({before.file.name} and "
                    f"{after.file.name}): one mesh per time step is read",
                    path=path,
                )
    return entries


def _refuse_declarations(data: bytes, path: Path) -> None:
    """Refuse XML whose prolog holds a DOCTYPE or ENTITY declaration."""
    for declaration in _DECLARATIONS:
        if declaration in data:
            raise InputError(
                f"declares {declaration.decode()[1:]}, which VTK files never need: refused, "
                "as the way to an entity-expansion attack",
                path=path,
            )


def _entry(dataset: ElementTree.Element, number: int, path: Path) -> _Entry:
    """The time step and resolved file of DataSet ``number``."""
    name = dataset.get("file")
    if not name:
        raise InputError(f"DataSet {number} has no file attribute", path=path)
    text = dataset.get("timestep")
    timestep = None
    if text is not None:
        try:
            timestep = float(text)
        except ValueError:
            raise InputError(
                f"DataSet {number} ({name}) has timestep {text!r}, not a number", path=path
            ) from None
        if not np.isfinite(timestep):
            raise InputError(f"DataSet {number} ({name}) has timestep {text!r}", path=path)
    file = Path(name.replace("\\", "/"))
    file = file if file.is_absolute() else path.parent / file
    suffix = file.suffix.lower()
    if suffix != ".vtu":
        hint = (
            "meshio (the [vtk] extra) reads .vtu, not .vtp: save the series as .vtu (ParaView)"
            if suffix == ".vtp"
            else "a .pvd read here lists .vtu files"
        )
        raise InputError(f"DataSet {number} names {name!r}: {hint}", path=path)
    return _Entry(timestep, file, file.stem)


def _check_parts(datasets: list[ElementTree.Element], path: Path) -> None:
    """Refuse a collection of several parts per time step (several meshes)."""
    parts = sorted({dataset.get("part", "0") for dataset in datasets})
    if len(parts) > 1:
        raise InputError(
            f"holds several parts per time step ({', '.join(parts[:5])}): one mesh is read; "
            "merge the parts first (ParaView: Merge Blocks)",
            path=path,
        )


def _read_vtu(
    meshio: ModuleType, file: Path, pvd: Path, index: int
) -> tuple[np.ndarray, np.ndarray]:
    """The points (K, 3) float64 and faces of one .vtu frame, checked."""
    try:
        stream = open_regular_file(file, "a .vtu file")
    except OSError as error:
        raise InputError(
            f"cannot read it (listed by {pvd}): {error.strerror or error}", path=file, frame=index
        ) from None
    with stream:
        data = stream.read()
    start = data.find(b"<VTKFile")
    if start < 0:
        raise InputError(
            f"is not a VTK XML file (listed by {pvd}): it has no <VTKFile> element",
            path=file,
            frame=index,
        )
    try:
        _refuse_declarations(data[:start], file)
    except InputError as error:
        raise InputError(error.reason, path=file, frame=index) from None
    appended = data.find(b"<AppendedData")
    declared = _declared_cells(data if appended < 0 else data[:appended])
    try:
        # the format's own reader: meshio.read() prints and calls sys.exit on a ReadError
        mesh = meshio.vtu.read(str(file))
    except Exception as error:  # meshio raises anything at all on a damaged file
        raise InputError(
            f"meshio cannot read it as a .vtu file: {type(error).__name__}: {error}",
            path=file,
            frame=index,
        ) from None
    points = _points(mesh, file, index)
    faces = _faces(mesh, declared, file, index)
    problem = face_table_problem(faces, len(points))
    if problem is not None:
        raise InputError(problem.message, path=file, frame=index)
    return points, faces


def _declared_cells(xml: bytes) -> int | None:
    """The cells the file's <Piece> elements declare, to notice any meshio leaves out."""
    counts = []
    for attributes in _PIECE.findall(xml):
        match = _CELL_COUNT.search(attributes)
        if match is None:
            return None
        counts.append(int(match.group(1)))
    return sum(counts) if counts else None


def _points(mesh: Any, file: Path, index: int) -> np.ndarray:
    """The mesh's points as float64 (K, 3), finite."""
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] != 3 or points.dtype.kind not in "fiu":
        raise InputError(
            f"its points have shape {points.shape} and dtype {points.dtype}, not (points, 3) "
            "numbers",
            path=file,
            frame=index,
        )
    if len(points) == 0:
        raise InputError("has no points", path=file, frame=index)
    points = points.astype(np.float64)
    bad = ~np.isfinite(points)
    if bad.any():
        vertex = int(np.argwhere(bad)[0, 0])
        raise InputError(f"point {vertex} has a non-finite coordinate", path=file, frame=index)
    return points


def _faces(mesh: Any, declared: int | None, file: Path, index: int) -> np.ndarray:
    """The 2-D cells as a face table in the file's order, rows padded with -1."""
    blocks: list[np.ndarray] = []
    total = 0
    for block in mesh.cells:
        data = block.data
        total += len(data)
        if block.type in _POINT_CELLS:
            continue
        if block.type not in SURFACE_CELLS:
            raise InputError(
                f"holds {len(data)} {block.type} cells: only surfaces are read (triangles, "
                "quads, polygons); extract the surface first (ParaView: Extract Surface)",
                path=file,
                frame=index,
            )
        block_faces = np.asarray(data, dtype=np.int64)
        if (block_faces < 0).any():  # -1 would pass for the face table's padding
            raise InputError(
                f"a {block.type} cell has a negative point index", path=file, frame=index
            )
        blocks.append(block_faces)
    if declared is not None and total != declared:
        raise InputError(
            f"declares {declared} cells but meshio read {total}: it holds cells of a type "
            "meshio does not know",
            path=file,
            frame=index,
        )
    if not blocks:
        return np.zeros((0, 3), dtype=np.int64)
    width = max(block.shape[1] for block in blocks)
    rows = sum(len(block) for block in blocks)
    faces = np.full((rows, width), -1, dtype=np.int64)
    row = 0
    for block in blocks:
        faces[row : row + len(block), : block.shape[1]] = block
        row += len(block)
    return faces


def write_pvd(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write ``path`` (.pvd) and one .vtu per frame in the folder named after its stem.

    Every target is checked before any work; the frames are staged and moved in whole and the
    .pvd written last, atomically. Time steps are the time codes (0, 1, 2... without them).
    """
    meshio = import_optional("meshio", "vtk", "writing VTK time series (.pvd)")
    folder = path.with_suffix("")
    if folder == path:
        raise ValueError(f"{path}: a .pvd needs a name with a suffix, for its frames' folder")
    names = frame_file_names(seq.frame_names, ".vtu")
    refuse_existing([path], options.overwrite)  # before the frames are written
    cells = _cell_blocks(seq.faces, seq.vertex_count)
    points = seq.vertices
    single = points.astype(np.float32)
    if np.array_equal(single, points):  # float32 positions: half the size, still exact
        points = single
    with atomic_folder(folder, names, overwrite=options.overwrite) as staging:
        for index, name in enumerate(names):
            mesh = meshio.Mesh(points[index], cells)
            meshio.vtu.write(str(staging / name), mesh, binary=True, compression="zlib")
    write_atomic(path, _index_xml(folder.name, names, seq.codes()), overwrite=options.overwrite)


def _cell_blocks(faces: np.ndarray, vertex_count: int) -> list[tuple[str, np.ndarray]]:
    """meshio cell blocks of the face table: runs of rows with the same corner count, in
    order (triangles, quads, or polygons of n corners); for a point sequence, one vertex cell
    per point (ParaView draws only points that are cells, and meshio reads no cell-less file)."""
    if faces.shape[0] == 0:
        return [("vertex", np.arange(vertex_count, dtype=np.int64)[:, np.newaxis])]
    corners = (faces >= 0).sum(axis=1)
    breaks = np.flatnonzero(np.diff(corners)) + 1
    blocks = []
    for start, stop in zip(
        np.concatenate([[0], breaks]), np.concatenate([breaks, [len(faces)]]), strict=True
    ):
        count = int(corners[start])
        kind = {3: "triangle", 4: "quad"}.get(count, "polygon")
        blocks.append((kind, np.ascontiguousarray(faces[start:stop, :count])))
    return blocks


def _index_xml(folder: str, names: list[str], codes: np.ndarray) -> bytes:
    """The .pvd collection listing ``folder/name`` at each time code."""
    root = ElementTree.Element(
        "VTKFile", type="Collection", version="0.1", byte_order="LittleEndian"
    )
    collection = ElementTree.SubElement(root, "Collection")
    for name, code in zip(names, codes, strict=True):
        ElementTree.SubElement(
            collection,
            "DataSet",
            timestep=repr(float(code)),  # the shortest text that reads back exactly
            group="",
            part="0",
            file=f"{folder}/{name}",
        )
    ElementTree.indent(root)
    return ElementTree.tostring(root, encoding="utf-8", xml_declaration=True) + b"\n"


FORMAT = SequenceFormat(
    name="vtk",
    suffixes=(".pvd",),
    description="VTK time series: a ParaView .pvd of .vtu files (meshio), one per time step",
    read=read_pvd,
    write=write_pvd,
    extra="vtk",
    carries=frozenset({"float64", "faces", "frame_names", "time_codes"}),
)
