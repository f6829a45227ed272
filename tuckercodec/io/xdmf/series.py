"""An XDMF time series read a range of frames at a time (:class:`XdmfFrames`): the temporal
collection's steps, each grid's geometry and topology checked against the first."""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ...model.attributes import FACE, VERTEX, Field
from ...model.sources import FrameSource, as_float64
from ...system.reading import open_input
from ..common.data_arrays import ROLE_TAG, STATIC_TAG, SourceArray, plan_arrays
from ..common.polygons import faces_from_polygons
from ..common.safe_xml import parse_xml
from ..registry import ReadOptions
from .items import XINCLUDE, HeavyData, References, lower, read_item, resolve

_FIXED = {"triangle": 3, "quadrilateral": 4}
#: XDMF's Mixed topology codes: polyvertex and polygon are followed by their point count.
_POLYVERTEX, _POLYGON, _TRIANGLE, _QUADRILATERAL = 1, 3, 4, 5


class XdmfFrames(FrameSource):
    """The frames of an XDMF temporal collection, read time step by time step (see the module
    docstring): the XML at once, with the first step's points and faces, each other step's
    geometry (an HDF5 dataset, or the XML's inline data) when its frame is read."""

    _transient: ClassVar[tuple[str, ...]] = ("_heavy", "_root", "_steps", "_sources")
    _heavy: HeavyData | None = None
    _root: References | None = None
    _steps: list[_Step] | None = None
    _sources: dict[object, int] | None = None

    def __init__(self, path: Path, options: ReadOptions | None = None):
        self._file, self._options = path, options or ReadOptions()
        _, steps = self._tree()
        self._topology = np.zeros(0, dtype=np.int64)
        self._face_cells, self._cell_count = np.zeros(0, dtype=np.int64), 0
        self._skipped: list[str] = []
        faces = np.zeros((0, 3), dtype=np.int64)
        self._points, faces = self._step(0, steps[0], faces, None)
        first = self._arrays(0, steps[0], None)
        try:
            self._plan = plan_arrays(first.values())
        except InputError as error:
            raise InputError(error.reason, path=path, frame=0) from None
        #: the notes of the attributes (XDMF's point and cell data) not read
        self.skipped = self._skipped + self._plan.skipped
        self._first_rows = self._rows(0, first, len(faces))
        timed = steps[0].time is not None
        codes = [step.time for step in steps] if timed else None
        names = [step.name for step in steps]
        if not (all(names) and len(set(names)) == len(names)):
            names = []
        self._describe(
            path,
            len(steps),
            len(self._points),
            faces,
            names,
            None,
            codes,
            attributes=self._plan.attributes,
            field_names=self._plan.field_names,
        )

    def _tree(self) -> tuple[References, list[_Step]]:
        """The parsed XML (with its References' follower) and its steps (parsed again after
        unpickling)."""
        if self._root is None or self._steps is None:
            self._root = References(_parse(self._file))
            self._steps = _steps(self._root.root, self._file)
        return self._root, self._steps

    def _step(
        self, index: int, step: _Step, faces: np.ndarray, count: int | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """A step's points and faces, checked against the first step's ``faces`` and vertex
        ``count`` (``None``: this is the first step)."""
        root, _ = self._tree()
        if self._heavy is None:
            self._heavy = HeavyData(self._file.parent, self._options.inflation())
        else:  # what one step's datasets may inflate to, together
            self._heavy.inflation = self._options.inflation()
        if self._sources is None:
            self._sources = {}
        try:
            points, source = _geometry(step.grid, root, self._heavy)
            first = self._sources.setdefault(source, index)
            if first != index:
                raise _shared(first, index, source)
            values, kind = _topology_values(step.grid, root, self._heavy)
            if count is None or not np.array_equal(values, self._topology):
                step_faces, face_cells, cells = _faces(values, kind, step.grid, len(points))
                if count is not None and not np.array_equal(step_faces, faces):
                    raise InputError("its faces differ from the first time step's")
                self._topology, faces = values, step_faces
                self._face_cells, self._cell_count = face_cells, cells
            if count is not None and len(points) != count:
                raise InputError(
                    f"has {len(points)} points but the first time step has {count}: every "
                    "step must have the same points"
                )
        except InputError as error:
            where = f"time step {index} (grid {step.name!r})"
            raise InputError(f"{where}: {error.reason}", path=self._file, frame=index) from None
        return points, faces

    def _read(self, start: int, stop: int) -> np.ndarray:
        _, steps = self._tree()
        vertices = np.empty((stop - start, self.vertex_count, 3), dtype=np.float64)
        for index in range(start, stop):
            if index == 0:
                vertices[0] = self._points
            else:
                step = steps[index]
                vertices[index - start] = self._step(index, step, self.faces, self.vertex_count)[0]
                if self._plan.repeated:
                    arrays = self._arrays(index, step, set(self._plan.repeated))
                    try:
                        self._plan.check_repeated({k: a.values for k, a in arrays.items()})
                    except InputError as error:
                        raise self._at(index, step, error) from None
        return vertices

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        _, steps = self._tree()
        rows = []
        for index in range(start, stop):
            if index == 0:
                rows.append(self._first_rows)
                continue
            arrays = self._arrays(index, steps[index], self._plan.wanted())
            rows.append(self._rows(index, arrays, len(self.faces)))
        return self._plan.fields(rows)

    def _rows(
        self, index: int, arrays: dict[tuple[str, str], SourceArray], face_count: int
    ) -> list[np.ndarray]:
        """Step ``index``'s rows of each field, checked."""
        _, steps = self._tree()
        values = {key: array.values for key, array in arrays.items()}
        try:
            return self._plan.step_rows(values, {VERTEX: len(self._points), FACE: face_count})
        except InputError as error:
            raise self._at(index, steps[index], error) from None

    def _at(self, index: int, step: _Step, error: InputError) -> InputError:
        """``error`` of step ``index``, naming the .xdmf, the frame and the grid."""
        where = f"time step {index} (grid {step.name!r})"
        return InputError(f"{where}: {error.reason}", path=self._file, frame=index)

    def _arrays(
        self, index: int, step: _Step, wanted: set[tuple[str, str]] | None
    ) -> dict[tuple[str, str], SourceArray]:
        """The ``<Attribute>``s of a step's grid (those in ``wanted``, by (domain, name);
        ``None``: all, noting in :attr:`_skipped` those not read), cell values mapped to the
        faces."""
        root, _ = self._tree()
        assert self._heavy is not None  # opened by _step, which reads every step first
        self._heavy.inflation = self._options.inflation()
        skipped: list[str] = []
        try:
            arrays = _grid_arrays(
                step.grid,
                root,
                self._heavy,
                {VERTEX: len(self._points), FACE: self._cell_count},
                self._face_cells,
                wanted,
                skipped,
            )
        except InputError as error:
            raise self._at(index, step, error) from None
        if wanted is None:
            self._skipped = skipped
        return arrays


def _shared(first: int, index: int, source: object) -> InputError:
    shown = f"{source[0]}:{source[1]}" if isinstance(source, tuple) else "one <DataItem>"
    return InputError(
        f"shares its geometry ({shown}) with time step {first}: a series whose steps share one "
        "geometry is a static mesh with changing point data, not a moving mesh; a moving mesh "
        "has a <Geometry> with its own positions at each time step"
    )


@dataclass(frozen=True)
class _Step:
    """One frame: its time (``None`` if not given), grid and name."""

    time: float | None
    grid: ElementTree.Element
    name: str


def _parse(path: Path) -> ElementTree.Element:
    """The root element; declarations are refused by the parser."""
    stream = open_input(path, "an XDMF file")
    with stream:
        data = stream.read()
    try:
        root = parse_xml(data, "XDMF", doctype=True)
    except InputError as error:
        raise InputError(error.reason, path=path) from None
    if root.tag != "Xdmf" or root.find("Domain") is None:
        raise InputError(f"is not XDMF: its root is <{root.tag}>, not <Xdmf><Domain>", path=path)
    return root


def _steps(root: ElementTree.Element, path: Path) -> list[_Step]:
    """The frames' grids in time order."""
    domain = root.find("Domain")
    assert domain is not None
    grids = domain.findall("Grid")
    temporal = [
        grid
        for grid in grids
        if lower(grid, "GridType") == "collection" and lower(grid, "CollectionType") == "temporal"
    ]
    if len(temporal) > 1:
        raise InputError(
            f"holds {len(temporal)} temporal collections: one moving mesh is read", path=path
        )
    if temporal:
        children = temporal[0].findall("Grid")
        if any(child.tag in XINCLUDE for child in temporal[0]):
            raise InputError("its temporal collection takes grids by xi:include", path=path)
        times = _listed_times(temporal[0], len(children), path)
    elif len(grids) == 1 and lower(grids[0], "GridType", default="uniform") == "uniform":
        children, times = grids, [None]
    else:
        raise InputError(
            'has no <Grid GridType="Collection" CollectionType="Temporal"> (nor one uniform '
            "grid) in its <Domain>",
            path=path,
        )
    if not children:
        raise InputError("its temporal collection holds no <Grid>", path=path)
    steps = []
    for number, child in enumerate(children):
        kind = lower(child, "GridType", default="uniform")
        if kind != "uniform":
            raise InputError(
                f"grid {number} of the temporal collection is a {kind} grid: one mesh per time "
                "step is read; merge the parts first (ParaView: Merge Blocks)",
                path=path,
            )
        time = times[number] if times[number] is not None else _grid_time(child, number, path)
        steps.append(_Step(time, child, child.get("Name", "")))
    timed = [step.time is not None for step in steps]
    if any(timed) and not all(timed):
        raise InputError(f"grid {timed.index(False)} has no time while others do", path=path)
    if all(timed):
        steps.sort(key=lambda step: step.time or 0.0)
        for before, after in itertools.pairwise(steps):
            if before.time == after.time:
                raise InputError(f"lists time {after.time} twice: one mesh per time", path=path)
    return steps


def _number(text: str | None, what: str, path: Path) -> float:
    try:
        value = float(text or "")
    except ValueError:
        raise InputError(f"{what} {text!r} is not a number", path=path) from None
    if not np.isfinite(value):
        raise InputError(f"{what} is {text!r}", path=path)
    return value


def _grid_time(grid: ElementTree.Element, number: int, path: Path) -> float | None:
    time = grid.find("Time")
    if time is None:
        return None
    if lower(time, "TimeType", "Type", default="single") != "single":
        raise InputError(f"grid {number}'s <Time> is not a single value", path=path)
    return _number(time.get("Value"), f"grid {number}'s time", path)


def _listed_times(collection: ElementTree.Element, count: int, path: Path) -> list[float | None]:
    """The times a collection's own <Time> lists (List or HyperSlab), or none."""
    time = collection.find("Time")
    kind = "" if time is None else lower(time, "TimeType", "Type", default="single")
    if time is None or kind == "single":
        return [None] * count
    item = time.find("DataItem")
    if kind not in ("list", "hyperslab") or item is None or lower(item, "Format") == "hdf":
        raise InputError(
            f"its collection's <Time> is of type {kind!r}: List and HyperSlab of XML values "
            "are read",
            path=path,
        )
    values = [_number(text, "a listed time", path) for text in (item.text or "").split()]
    if kind == "hyperslab":
        if len(values) != 3:
            raise InputError("a HyperSlab <Time> needs start, stride and count", path=path)
        values = [values[0] + values[1] * n for n in range(count)]
    if len(values) != count:
        raise InputError(f"its <Time> lists {len(values)} times for {count} grids", path=path)
    return list(values)


def _child(grid: ElementTree.Element, tag: str, root: References) -> ElementTree.Element:
    element = grid.find(tag)
    if element is None:
        if any(child.tag in XINCLUDE for child in grid):
            extra = (
                ": every step takes one geometry from another grid, so this is a static mesh "
                "with changing point data, not a moving mesh"
                if tag == "Geometry"
                else ""
            )
            raise InputError(f"takes its <{tag}> by xi:include, which is not followed{extra}")
        raise InputError(f"has no <{tag}>")
    return resolve(element, root)


def _geometry(
    grid: ElementTree.Element, root: References, heavy: HeavyData
) -> tuple[np.ndarray, object]:
    """The grid's points (K, 3) float64, finite, and the identity of their source."""
    geometry = _child(grid, "Geometry", root)
    kind = lower(geometry, "GeometryType", "Type", default="xyz")
    items = geometry.findall("DataItem")
    if kind in ("xyz", "xy"):
        width = len(kind)
        if len(items) != 1:
            raise InputError(f"its {kind.upper()} <Geometry> has {len(items)} DataItems, not 1")
        values, dims, source = read_item(items[0], root, heavy, "Geometry")
        if values.size % width or (len(dims) > 1 and dims[-1] != width):
            raise InputError(f"its Geometry's Dimensions {dims} are not (points, {width})")
        points = np.zeros((values.size // width, 3))
        points[:, :width] = as_float64(values).reshape(-1, width)
    elif kind == "x_y_z":
        if len(items) != 3:
            raise InputError(f"its X_Y_Z <Geometry> has {len(items)} DataItems, not 3")
        parts = [read_item(item, root, heavy, "Geometry") for item in items]
        if len({part[0].size for part in parts}) != 1:
            raise InputError("its X, Y and Z DataItems differ in length")
        points = as_float64(np.stack([part[0] for part in parts], axis=1))
        source = tuple(part[2] for part in parts)
    else:
        raise InputError(f"has a {kind.upper()} <Geometry>: XYZ, X_Y_Z and XY are read")
    if len(points) == 0:
        raise InputError("has no points")
    bad = ~np.isfinite(points)
    if bad.any():
        raise InputError(f"point {int(np.argwhere(bad)[0, 0])} has a non-finite coordinate")
    return points, source


def _topology_values(
    grid: ElementTree.Element, root: References, heavy: HeavyData
) -> tuple[np.ndarray, str]:
    """The grid's topology type and its values as int64."""
    topology = _child(grid, "Topology", root)
    kind = lower(topology, "TopologyType", "Type")
    item = topology.find("DataItem")
    if kind == "polyvertex" and item is None:
        return np.zeros(0, dtype=np.int64), kind
    if item is None:
        raise InputError(f"its {kind} <Topology> has no <DataItem>")
    values = read_item(item, root, heavy, "Topology")[0]
    if values.dtype.kind not in "iu":
        raise InputError(f"its Topology holds {values.dtype.name} values, not integers")
    if values.dtype == np.uint64 and values.size and values.max() > np.iinfo(np.int64).max:
        raise InputError("its Topology holds a value beyond the range of Int64")
    offset = lower(topology, "BaseOffset", default="0")
    values = values.astype(np.int64) - (int(offset) if offset.lstrip("-").isdigit() else 0)
    return values, kind


def _faces(
    values: np.ndarray, kind: str, grid: ElementTree.Element, count: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """The face table of a topology's values, each face's cell, and the number of cells."""
    topology = grid.find("Topology")
    assert topology is not None
    if kind == "polyvertex":
        return np.zeros((0, 3), dtype=np.int64), np.zeros(0, dtype=np.int64), count
    if kind in _FIXED or kind == "polygon":
        width = _FIXED.get(kind) or int(lower(topology, "NodesPerElement", default="0") or 0)
        if width < 3 or values.size % width:
            raise InputError(f"its {kind} Topology of {values.size} values has no {width}-gons")
        sizes, flat = np.full(values.size // width, width), values
        cells, face_cells = len(sizes), np.arange(len(sizes), dtype=np.int64)
    elif kind == "mixed":
        sizes, flat, face_cells, cells = _mixed(values)
    else:
        raise InputError(
            f"has a {kind} Topology: only surfaces are read (Triangle, Quadrilateral, Polygon, "
            "Mixed of these); extract the surface first (ParaView: Extract Surface)"
        )
    return faces_from_polygons(sizes, flat, count), face_cells, cells


def _mixed(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Corner counts and corners of a Mixed topology (each cell: its code, for a polygon or
    polyvertex its point count, then its points; polyvertices only mark points), each face's
    cell, and the number of cells."""
    for code, size in ((_TRIANGLE, 3), (_QUADRILATERAL, 4)):  # one cell type: at numpy speed
        if values.size % (size + 1) == 0 and (values[:: size + 1] == code).all():
            table = values.reshape(-1, size + 1)[:, 1:]
            cells = len(table)
            return np.full(cells, size), table.reshape(-1), np.arange(cells, dtype=np.int64), cells
    numbers = values.tolist()
    sizes, starts, face_cells = [], [], []
    at = cells = 0
    while at < len(numbers):
        code = numbers[at]
        if code in (_POLYGON, _POLYVERTEX):
            size = numbers[at + 1] if at + 1 < len(numbers) else -1
            at += 2
        elif code in (_TRIANGLE, _QUADRILATERAL):
            size, at = 3 if code == _TRIANGLE else 4, at + 1
        else:
            raise InputError(
                f"its Mixed Topology holds a cell of XDMF type {code}: only surfaces are read "
                "(triangles, quadrilaterals, polygons); extract the surface first"
            )
        if size < 0 or at + size > len(numbers):
            raise InputError("its Mixed Topology ends inside a cell: truncated")
        if code != _POLYVERTEX:
            sizes.append(size)
            starts.append(at)
            face_cells.append(cells)
        at += size
        cells += 1
    counts = np.array(sizes, dtype=np.int64)
    index = np.repeat(np.array(starts, dtype=np.int64) - np.cumsum(counts) + counts, counts)
    return counts, values[index + np.arange(index.size)], np.array(face_cells, np.int64), cells


#: XDMF attribute types whose values are one row per element with this many components (a
#: Vector's width is its Dimensions', 2 to 4, as meshio and this package write them).
_WIDTHS = {"scalar": 1, "tensor": 9, "tensor6": 6}


def _grid_arrays(
    grid: ElementTree.Element,
    root: References,
    heavy: HeavyData,
    counts: dict[str, int],
    face_cells: np.ndarray,
    wanted: set[tuple[str, str]] | None,
    skipped: list[str],
) -> dict[tuple[str, str], SourceArray]:
    """The grid's node- and cell-centred ``<Attribute>``s (``counts``: its points and cells),
    cell values mapped to the faces (``face_cells``); others noted in ``skipped``."""
    arrays: dict[tuple[str, str], SourceArray] = {}
    for number, element in enumerate(grid.findall("Attribute")):
        attribute = resolve(element, root)
        name = attribute.get("Name", "")
        center = lower(attribute, "Center", default="node")
        domain = {"node": VERTEX, "cell": FACE}.get(center)
        label = f"attribute {name!r}" if name else f"attribute {number}"
        if domain is None or not name:
            reason = "it has no name" if not name else f"it is centred on {center}s"
            if wanted is None:
                skipped.append(f"{label}: {reason} (node and cell attributes are read)")
            continue
        if wanted is not None and (domain, name) not in wanted:
            continue
        items = attribute.findall("DataItem")
        if len(items) != 1:
            if wanted is None:
                skipped.append(f"{label}: {len(items)} DataItems (one is read)")
            continue
        values = read_item(items[0], root, heavy, f"Attribute {name!r}")[0]
        count = counts[domain]
        width = values.size // count if count else 0
        kind = lower(attribute, "AttributeType", "Type", default="scalar")
        if not count or values.size != count * width or _WIDTHS.get(kind, width) != width:
            raise InputError(
                f"{label} holds {values.size} values ({kind}), not a row per "
                f"{'point' if domain == VERTEX else 'cell'} of the {count}"
            )
        if (domain, name) in arrays:
            raise InputError(f"the grid has two {center} attributes named {name!r}")
        table = values.reshape(count, width)
        if domain == FACE:
            table = table[face_cells]
        role = attribute.get(ROLE_TAG)  # else plan_arrays goes by the name
        static = attribute.get(STATIC_TAG) == "1"
        arrays[domain, name] = SourceArray(name, domain, table, role, static)
    if not len(face_cells):
        face_keys = [key for key in arrays if key[0] == FACE]
        if wanted is None:
            skipped.extend(f"cell attribute {key[1]!r}: the mesh has no faces" for key in face_keys)
        for key in face_keys:
            del arrays[key]
    return arrays
