"""One VTK XML dataset file, an UnstructuredGrid (``.vtu``) or a PolyData (``.vtp``): its
points and surface cells read into a face table, and written back, in plain numpy and the
standard library (the arrays' encodings are :mod:`.arrays`'s).

Reading, by the ``<VTKFile type=..>`` of the file (whatever its name's suffix):

* the points of every ``<Piece>`` (several pieces are joined, in order, as VTK joins them),
  Float32 or Float64 kept exactly (integers converted), all finite;
* UnstructuredGrid ``<Cells>`` (connectivity, offsets, types): triangles, quads and polygons
  become faces in the file's order (rows padded with -1), a pixel the quad it is (corners
  0, 1, 3, 2), a triangle strip its triangles as VTK splits it (vtkTriangleStrip: every second
  triangle flipped so all keep the strip's winding), and vertex and poly-vertex cells only mark
  points. Lines, volume cells and higher-order cells are refused: the codec compresses surfaces;
* PolyData ``<Polys>`` (faces), then ``<Strips>`` (split as above), in VTK's cell order;
  ``<Verts>`` only mark points; ``<Lines>`` are refused.

A DOCTYPE or any declaration (the way to an entity-expansion attack) is refused by the XML
parser itself (:mod:`~tuckercodec.io.common.safe_xml`), whatever the encoding. Raw appended data is
cut off before parsing, so the XML parser sees only the XML. Compressed arrays inflate
within what one read may decompress (``--max-memory``, :mod:`~tuckercodec.io.common.budget`), all
the file's arrays together. Every error is an
:class:`InputError` without a path (the caller names the file).

Writing (:class:`DatasetWriter`): one piece of the points and the faces (Polys, or cells of
types 5, 9 and 7), or, without faces, one vertex cell per point so that ParaView shows them;
the cells are encoded once for every frame of a series.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ...model.attributes import FACE, VERTEX
from ...model.sources import as_float64
from ..common.budget import Inflation, memory_ceiling
from ..common.data_arrays import SourceArray, TargetArray
from ..common.polygons import faces_from_polygons, polygons_from_faces
from ..common.safe_xml import parse_xml
from .arrays import Encoding, Layout, encode_array, file_encoding, read_array, type_name
from .data import PieceData, data_xml, quoted, read_piece_data

#: The dataset types read and written, by the suffix VTK gives their files.
DATASETS = {".vtu": "UnstructuredGrid", ".vtp": "PolyData"}
#: VTK cell types by number, for messages (vtkCellType.h); others are named by number.
CELL_NAMES = {
    1: "vertex",
    2: "poly_vertex",
    3: "line",
    4: "poly_line",
    5: "triangle",
    6: "triangle_strip",
    7: "polygon",
    8: "pixel",
    9: "quad",
    10: "tetra",
    11: "voxel",
    12: "hexahedron",
    13: "wedge",
    14: "pyramid",
    15: "pentagonal_prism",
    16: "hexagonal_prism",
    21: "quadratic_edge",
    22: "quadratic_triangle",
    23: "quadratic_quad",
    24: "quadratic_tetra",
    25: "quadratic_hexahedron",
    42: "polyhedron",
}
# What each surface cell becomes: nothing (a point marker), a polygon, strip triangles, a quad.
_MARKER, _POLYGON, _STRIP, _PIXEL = 0, 1, 2, 3
_KINDS = {1: _MARKER, 2: _MARKER, 5: _POLYGON, 6: _STRIP, 7: _POLYGON, 8: _PIXEL, 9: _POLYGON}
_EXACT_SIZES = {1: 1, 5: 3, 8: 4, 9: 4}
_LEAST_SIZES = {2: 1, 6: 3, 7: 3}
_LOOKUP = np.array([_KINDS.get(code, -1) for code in range(max(_KINDS) + 1)], dtype=np.int8)
_APPENDED = re.compile(rb"<AppendedData\b([^>]*)>\s*_")
_ENCODING = re.compile(rb"""\bencoding\s*=\s*["']([^"']*)["']""")
_INT64_MAX = np.iinfo(np.int64).max


@dataclass(eq=False)
class Dataset:
    """What one file holds: points, faces, and its point and cell arrays.

    Attributes:
        points: (K, 3) float64, finite.
        faces: (M, n) int64, -1 padded; (0, 3) without faces.
        arrays: by (domain, name): point arrays (one row per point) and cell arrays (one row
            per face: a strip's value repeated for each of its triangles; the values of
            vertex cells, which are no faces, left out).
        skipped: the notes of arrays not read (:mod:`.data`).
    """

    points: np.ndarray
    faces: np.ndarray
    arrays: dict[tuple[str, str], SourceArray] = field(default_factory=dict)
    skipped: list[str] = field(default_factory=list)


def read_dataset(data: bytes, inflation: Inflation | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The points ((K, 3) float64, finite) and face table ((M, n) int64, -1 padded; (0, 3)
    without faces) of the bytes of a ``.vtu`` or ``.vtp`` file (see the module docstring); its
    compressed arrays inflate within ``inflation`` (default: half the machine's memory)."""
    found = parse_dataset(data, inflation, wanted=set())
    return found.points, found.faces


def parse_dataset(
    data: bytes,
    inflation: Inflation | None = None,
    wanted: set[tuple[str, str]] | None = None,
) -> Dataset:
    """The :class:`Dataset` of the bytes of a ``.vtu`` or ``.vtp`` file, with the point and
    cell arrays in ``wanted`` (by (domain, name); ``None``: all of them)."""
    root, encoding = _parse(data, inflation or Inflation(memory_ceiling(None)))
    kind = root.get("type", "")
    if root.tag != "VTKFile" or kind not in DATASETS.values():
        raise InputError(
            f'holds <{root.tag} type="{kind}">: the series reads UnstructuredGrid (.vtu) and '
            "PolyData (.vtp) files"
        )
    grid = root.find(kind)
    pieces = [] if grid is None else grid.findall("Piece")
    if not pieces:
        raise InputError(f"has no <{kind}><Piece>: there is nothing to read")
    points, counts, corners, datas = [], [], [], []
    start = 0
    for number, piece in enumerate(pieces):
        label = f"piece {number}: " if len(pieces) > 1 else ""
        try:
            piece_points = _points(piece, encoding)
            reader = _unstructured if kind == "UnstructuredGrid" else _poly
            sizes, flat, face_cells, cells = reader(piece, encoding)
            piece_data = read_piece_data(
                piece, encoding, {VERTEX: len(piece_points), FACE: cells}, wanted
            )
        except InputError as error:
            raise InputError(label + error.reason) from None
        if flat.size and flat.min() < 0:  # -1 would pass for the face table's padding
            raise InputError(f"{label}a cell has a negative point index {int(flat.min())}")
        if len(pieces) > 1 and flat.size and flat.max() >= len(piece_points):
            raise InputError(  # it would name a point of the next piece
                f"{label}a cell has the point index {int(flat.max())}, outside "
                f"0..{len(piece_points) - 1}"
            )
        points.append(piece_points)
        counts.append(sizes)
        corners.append(flat + start if start else flat)
        datas.append(_on_faces(piece_data, face_cells))
        start += len(piece_points)
    vertices = points[0] if len(points) == 1 else np.concatenate(points)
    if len(vertices) == 0:
        raise InputError("has no points")
    bad = ~np.isfinite(vertices)
    if bad.any():
        vertex = int(np.argwhere(bad)[0, 0])
        raise InputError(f"point {vertex} has a non-finite coordinate")
    if len(counts) > 1:
        faces = faces_from_polygons(np.concatenate(counts), np.concatenate(corners), len(vertices))
    else:
        faces = faces_from_polygons(counts[0], corners[0], len(vertices))
    arrays, skipped = _joined(datas)
    if not len(faces):
        skipped += [
            f"cell array {name!r}: the mesh has no faces" for d, name in arrays if d == FACE
        ]
        arrays = {key: value for key, value in arrays.items() if key[0] != FACE}
    return Dataset(vertices, faces, arrays, skipped)


def _on_faces(piece: PieceData, face_cells: np.ndarray) -> PieceData:
    """The piece's cell arrays with one row per face (``face_cells``: each face's cell)."""
    arrays = {
        key: value
        if key[0] != FACE
        else SourceArray(value.name, FACE, value.values[face_cells], value.role, value.static)
        for key, value in piece.arrays.items()
    }
    return PieceData(arrays, piece.skipped)


def _joined(pieces: list[PieceData]) -> tuple[dict[tuple[str, str], SourceArray], list[str]]:
    """The arrays of several pieces joined, in order (those every piece holds alike)."""
    if len(pieces) == 1:
        return pieces[0].arrays, list(pieces[0].skipped)
    skipped = [note for piece in pieces for note in piece.skipped]
    arrays = {}
    for key, first in pieces[0].arrays.items():
        parts = [piece.arrays.get(key) for piece in pieces]
        if any(
            part is None
            or part.values.dtype != first.values.dtype
            or part.values.shape[1] != first.values.shape[1]
            for part in parts
        ):
            where = "point" if key[0] == VERTEX else "cell"
            skipped.append(f"{where} array {key[1]!r}: not alike in every piece")
            continue
        values = np.concatenate([part.values for part in parts if part is not None])
        arrays[key] = SourceArray(first.name, first.domain, values, first.role, first.static)
    return arrays, skipped


def _parse(data: bytes, inflation: Inflation) -> tuple[ElementTree.Element, Encoding]:
    """The root element, with raw appended data cut off before the XML parser sees it."""
    start = data.find(b"<VTKFile")
    if start < 0:
        raise InputError("is not a VTK XML file: it has no <VTKFile> element")
    cut = data.find(b"<AppendedData", start)
    appended: memoryview | None = None
    base64 = False
    xml = data
    if cut >= 0:
        match = _APPENDED.match(data, cut)
        if match is None:
            raise InputError("its <AppendedData> does not begin with the _ marker")
        found = _ENCODING.search(match.group(1))
        encoding = found.group(1).decode("ascii", "replace") if found else "raw"
        if encoding not in ("raw", "base64"):
            raise InputError(f"its <AppendedData> has encoding {encoding!r}, not raw or base64")
        base64 = encoding == "base64"
        end = data.rfind(b"</AppendedData>")
        stop = end if end >= match.end() else len(data)
        while base64 and stop > match.end() and data[stop - 1] in b" \t\r\n":
            stop -= 1
        appended = memoryview(data)[match.end() : stop]  # a view: the data is not copied
        xml = data[:cut] + b"</VTKFile>"  # the appended data is the root's last child
    root = parse_xml(xml, "VTK")
    return root, file_encoding(root, appended, base64, inflation)


def _count(piece: ElementTree.Element, name: str, default: str | None = "0") -> int:
    """A count attribute of a <Piece>."""
    text = piece.get(name, default)
    if text is None or not text.strip().isdigit():
        raise InputError(f"<Piece> has {name}={text!r}, not a count")
    return int(text)


def _points(piece: ElementTree.Element, encoding: Encoding) -> np.ndarray:
    """The piece's points as (K, 3) float64."""
    count = _count(piece, "NumberOfPoints", None)
    element = piece.find("Points/DataArray")
    if element is None:
        if count:
            raise InputError(f"declares {count} points but has no <Points><DataArray>")
        return np.zeros((0, 3), dtype=np.float64)
    values = read_array(element, encoding, "Points", components=3, count=count)
    return as_float64(values).reshape(count, 3)


def _arrays(
    parent: ElementTree.Element | None, names: tuple[str, ...], what: str
) -> list[ElementTree.Element]:
    """The named <DataArray> children of a cells element."""
    found = {} if parent is None else {a.get("Name"): a for a in parent.findall("DataArray")}
    missing = [name for name in names if name not in found]
    if missing:
        raise InputError(f"<{what}> has no DataArray named {missing[0]!r}")
    return [found[name] for name in names]


def _ints(values: np.ndarray, what: str) -> np.ndarray:
    """Integer values as int64 (the values a mesh uses all fit)."""
    if values.dtype.kind not in "iu":
        raise InputError(f"{what}: holds {values.dtype.name} values, not integers")
    if values.dtype == np.uint64 and values.size and values.max() > _INT64_MAX:
        raise InputError(f"{what}: holds a value beyond the range of Int64")
    return values.astype(np.int64, copy=False)


def _cell_array(
    parent: ElementTree.Element | None, encoding: Encoding, what: str, cells: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The connectivity, end offsets and sizes of ``cells`` cells, checked."""
    connectivity_element, offsets_element = _arrays(parent, ("connectivity", "offsets"), what)
    offsets = _ints(read_array(offsets_element, encoding, f"{what} offsets", count=cells), what)
    connectivity = _ints(read_array(connectivity_element, encoding, f"{what} connectivity"), what)
    sizes = np.diff(offsets, prepend=0)
    if sizes.size and sizes.min() < 0:
        cell = int(np.flatnonzero(sizes < 0)[0])
        raise InputError(f"{what}: the offset of cell {cell} is less than the one before it")
    end = int(offsets[-1]) if offsets.size else 0
    if end != connectivity.size:
        raise InputError(
            f"{what}: the offsets end at {end} but the connectivity holds {connectivity.size} "
            "point indices"
        )
    return connectivity, offsets, sizes


def _not_surface(count: int, name: str) -> InputError:
    return InputError(
        f"holds {count} {name} cells: only surfaces are read (triangles, quads, polygons); "
        "extract the surface first (ParaView: Extract Surface)"
    )


def _unstructured(
    piece: ElementTree.Element, encoding: Encoding
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The face corner counts, corners and cells (each face's) of an UnstructuredGrid piece,
    and its number of cells."""
    cells = _count(piece, "NumberOfCells")
    element = piece.find("Cells")
    if element is None and cells == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty, 0
    connectivity, offsets, sizes = _cell_array(element, encoding, "Cells", cells)
    (types_element,) = _arrays(element, ("types",), "Cells")
    types = _ints(read_array(types_element, encoding, "Cells types", count=cells), "Cells")
    known = (types >= 0) & (types < len(_LOOKUP))
    known[known] = _LOOKUP[types[known]] >= 0
    if not known.all():
        code = int(types[np.flatnonzero(~known)[0]])
        raise _not_surface(int((types == code).sum()), CELL_NAMES.get(code, f"type {code}"))
    for code, size in _EXACT_SIZES.items():
        wrong = np.flatnonzero((types == code) & (sizes != size))
        if wrong.size:
            cell = int(wrong[0])
            raise InputError(f"cell {cell} is a {CELL_NAMES[code]} of {sizes[cell]} points")
    for code, least in _LEAST_SIZES.items():
        wrong = np.flatnonzero((types == code) & (sizes < least))
        if wrong.size:
            cell = int(wrong[0])
            raise InputError(
                f"cell {cell} is a {CELL_NAMES[code]} of {sizes[cell]} points, fewer than {least}"
            )
    return (*_corners(connectivity, offsets, sizes, _LOOKUP[types]), cells)


def _poly(
    piece: ElementTree.Element, encoding: Encoding
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The face corner counts, corners and cells (each face's) of a PolyData piece (its
    polygons, then its strips), and its number of cells (VTK numbers its verts, lines, polygons
    and strips in that order, which its cell data follows)."""
    lines = _count(piece, "NumberOfLines")
    if lines:
        raise _not_surface(lines, "line")
    counts, corners, face_cells = [], [], []
    first = _count(piece, "NumberOfVerts")
    for section, kind, least in (("Polys", _POLYGON, 3), ("Strips", _STRIP, 3)):
        cells = _count(piece, f"NumberOf{section}")
        if cells == 0:
            continue
        connectivity, offsets, sizes = _cell_array(piece.find(section), encoding, section, cells)
        if sizes.min() < least:
            cell = int(np.argmin(sizes))
            raise InputError(f"{section}: cell {cell} has {sizes[cell]} points, fewer than 3")
        kinds = np.full(cells, kind, dtype=np.int8)
        section_counts, section_corners, section_cells = _corners(
            connectivity, offsets, sizes, kinds
        )
        counts.append(section_counts)
        corners.append(section_corners)
        face_cells.append(section_cells + first)
        first += cells
    if not counts:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty, first
    return np.concatenate(counts), np.concatenate(corners), np.concatenate(face_cells), first


def _corners(
    connectivity: np.ndarray, offsets: np.ndarray, sizes: np.ndarray, kinds: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The corner count of each face, the corners of all faces, in the cells' order, and
    each face's cell: markers dropped, strips split into triangles, pixels reordered as
    quads."""
    if (kinds == _POLYGON).all():
        return sizes, connectivity, np.arange(len(kinds), dtype=np.int64)
    rows = np.where(kinds == _STRIP, sizes - 2, kinds != _MARKER).astype(np.int64)
    row_cell = np.repeat(np.arange(len(kinds)), rows)
    step = np.arange(row_cell.size) - (np.cumsum(rows) - rows)[row_cell]  # triangle in strip
    row_kind = kinds[row_cell]
    strip = row_kind == _STRIP
    counts = np.where(strip, 3, sizes[row_cell])
    base = (offsets - sizes)[row_cell] + np.where(strip, step, 0)
    corner_row = np.repeat(np.arange(counts.size), counts)
    corner = np.arange(corner_row.size) - (np.cumsum(counts) - counts)[corner_row]
    # vtkTriangleStrip::DecomposeStrip: odd triangles (p[i+1], p[i], p[i+2])
    flip = (strip & (step % 2 == 1))[corner_row] & (corner < 2)
    corner = np.where(flip, 1 - corner, corner)
    pixel = (row_kind == _PIXEL)[corner_row] & (corner >= 2)  # pixel corners 0 1 3 2
    corner = np.where(pixel, 5 - corner, corner)
    return counts, connectivity[base[corner_row] + corner], row_cell.astype(np.int64)


# ------------------------------------------------------------------------------------------
# writing


class DatasetWriter:
    """Writes frames of one mesh as ``.vtu`` or ``.vtp`` files: the cells are encoded once,
    then each call encodes only the points.

    Args:
        faces: the face table (-1 padded; no rows for a point sequence).
        vertex_count: the number of points.
        kind: ``"PolyData"`` or ``"UnstructuredGrid"``.
        layout: how arrays are stored (:class:`~.arrays.Layout`; ParaView's by default).
    """

    def __init__(
        self, faces: np.ndarray, vertex_count: int, kind: str, layout: Layout | None = None
    ) -> None:
        if kind not in DATASETS.values():
            raise ValueError(f"kind must be one of {sorted(DATASETS.values())}, not {kind!r}")
        self.kind, self.layout = kind, layout or Layout()
        if len(faces):
            counts, flat = polygons_from_faces(faces)
            types = np.where(counts == 3, 5, np.where(counts == 4, 9, 7))
        else:  # a point sequence: one vertex cell per point
            counts = np.ones(vertex_count, dtype=np.int32)
            flat, types = np.arange(vertex_count), np.ones(vertex_count)
        offsets = np.cumsum(counts, dtype=np.int64)
        index = np.int32 if offsets.size == 0 or offsets[-1] <= np.iinfo(np.int32).max else np.int64
        arrays = [("connectivity", flat.astype(index)), ("offsets", offsets.astype(index))]
        if kind == "UnstructuredGrid":
            arrays.append(("types", types.astype(np.uint8)))
            self.section = "Cells"
            self.counts = f'NumberOfCells="{len(counts)}"'
        else:
            self.section = "Polys" if len(faces) else "Verts"
            sizes = dict.fromkeys(("Verts", "Lines", "Strips", "Polys"), 0)
            sizes[self.section] = len(counts)
            self.counts = " ".join(f'NumberOf{name}="{n}"' for name, n in sizes.items())
        self.cells = [
            (name, values.dtype, encode_array(values, self.layout)) for name, values in arrays
        ]

    def __call__(
        self,
        points: np.ndarray,
        data: list[TargetArray] | None = None,
        frame: int = 0,
    ) -> bytes:
        """The file of one frame: ``points`` (K, 3), float32 or float64, stored as they are,
        and the arrays of ``data`` (point and cell arrays by their domain) at ``frame``."""
        layout = self.layout
        appended: list[bytes] = []
        offset = 0

        def element(name: str, dtype: np.dtype, values: np.ndarray | bytes, extra: str = "") -> str:
            """One <DataArray> of ``values`` (or of their encoding, given as bytes)."""
            nonlocal offset
            encoded = (
                values if isinstance(values, bytes) else encode_array(values.reshape(-1), layout)
            )
            head = f'<DataArray type="{type_name(dtype)}" Name="{quoted(name)}"{extra}'
            if layout.format == "appended":
                appended.append(encoded)
                head += f' format="appended" offset="{offset}"/>'
                offset += len(encoded)
                return head
            return f'{head} format="{layout.format}">\n{encoded.decode("ascii")}\n</DataArray>'

        point_xml = element("Points", points.dtype, points, ' NumberOfComponents="3"')
        cell_xml = "\n".join(element(name, dtype, data) for name, dtype, data in self.cells)
        targets = data or []
        point_data = data_xml(
            [t for t in targets if t.domain == VERTEX], frame, element, "PointData"
        )
        cell_data = data_xml([t for t in targets if t.domain == FACE], frame, element, "CellData")
        version = "1.0" if layout.header == "UInt64" else "0.1"  # as VTK writes them
        compressor = (
            ' compressor="vtkZLibDataCompressor"'
            if layout.compress and layout.format != "ascii"
            else ""
        )
        head = (
            f'<?xml version="1.0"?>\n<VTKFile type="{self.kind}" version="{version}" '
            f'byte_order="{layout.byte_order}" header_type="{layout.header}"{compressor}>\n'
            f'<{self.kind}>\n<Piece NumberOfPoints="{len(points)}" {self.counts}>\n'
            f"{point_data}{cell_data}<Points>\n{point_xml}\n</Points>\n"
            f"<{self.section}>\n{cell_xml}\n"
            f"</{self.section}>\n</Piece>\n</{self.kind}>\n"
        )
        if not appended:
            return (head + "</VTKFile>\n").encode("utf-8")
        encoding = "base64" if layout.base64 else "raw"
        return b"".join(
            [
                head.encode("utf-8"),
                f'<AppendedData encoding="{encoding}">\n_'.encode("ascii"),
                *appended,
                b"\n</AppendedData>\n</VTKFile>\n",
            ]
        )
