"""A VTK time series: the .pvd index read and checked (:class:`PvdFrames` reads its frames a range
at a time) and written (:func:`write_pvd`)."""

from __future__ import annotations

import itertools
import os
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

import numpy as np

from ...errors import InputError
from ...model.attributes import FACE, NORMAL, VERTEX, Field
from ...model.normals import recomputed_normals
from ...model.sequence import MeshSequence
from ...model.sources import FrameSource
from ...system.atomic import atomic_folder, refuse_existing, write_atomic
from ...system.reading import inside_folder, open_input, open_regular_file
from ..common.data_arrays import TargetArray, arrays_to_write, cannot_keep_arrays, plan_arrays
from ..common.safe_xml import parse_xml
from ..frames import frame_file_names
from ..registry import ReadOptions, WriteOptions
from .arrays import Layout
from .datasets import DATASETS, Dataset, DatasetWriter, parse_dataset

#: The largest .pvd index read: about a million time steps, far beyond any real series.
MAX_INDEX_BYTES = 64 * 1024 * 1024
#: The frames' files written by default: PolyData, ParaView's own type for surfaces.
FRAME_SUFFIX = ".vtp"
_PARALLEL = (".pvtu", ".pvtp")


class PvdFrames(FrameSource):
    """The frames of a ParaView ``.pvd`` collection, read file by file: the index and the
    first file at once, each other file when its frame is read, checked against the first
    (see the module docstring)."""

    def __init__(self, path: Path, options: ReadOptions | None = None):
        self._options = options or ReadOptions()
        self._entries = _collection(path)
        _refuse_repeated_files(self._entries, path)
        first = _read_frame(self._entries[0].file, path, 0, self._options, None)
        self._points = first.points
        try:
            self._plan = plan_arrays(first.arrays.values())
        except InputError as error:
            raise InputError(error.reason, path=self._entries[0].file, frame=0) from None
        #: the notes of the point and cell arrays not read (:mod:`~..common.data_arrays`)
        self.skipped = first.skipped + self._plan.skipped
        self._first_rows = self._step_rows(first, 0)
        timed = self._entries[0].timestep is not None
        codes = [entry.timestep for entry in self._entries] if timed else None
        names = [entry.name for entry in self._entries]
        self._describe(
            path,
            len(self._entries),
            len(self._points),
            first.faces,
            names,
            None,
            codes,
            attributes=self._plan.attributes,
            field_names=self._plan.field_names,
        )

    def _read(self, start: int, stop: int) -> np.ndarray:
        # frames are gathered as read, not into one array sized by the index: an index may
        # list far more frames than its files hold
        frames: list[np.ndarray] = []
        first = self._entries[0].file
        pvd = Path(self.path or "")
        for index in range(start, stop):
            entry = self._entries[index]
            if index == 0:
                frames.append(self._points)
                continue
            found = _read_frame(entry.file, pvd, index, self._options, set(self._plan.repeated))
            points, cells = found.points, found.faces
            try:
                self._plan.check_repeated({k: a.values for k, a in found.arrays.items()})
            except InputError as error:
                raise InputError(error.reason, path=entry.file, frame=index) from None
            if len(points) != self.vertex_count:
                raise InputError(
                    f"has {len(points)} points but the first frame ({first}) has "
                    f"{self.vertex_count}: every frame of {pvd.name} must have the same points",
                    path=entry.file,
                    frame=index,
                )
            if not np.array_equal(cells, self.faces):
                raise InputError(
                    f"its cells differ from the first frame's ({first}): every frame of "
                    f"{pvd.name} must have the same cells",
                    path=entry.file,
                    frame=index,
                )
            frames.append(np.asarray(points, dtype=np.float64))
        return np.stack(frames)

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        steps = []
        wanted = self._plan.wanted()
        for index in range(start, stop):
            if index == 0:
                steps.append(self._first_rows)
                continue
            entry = self._entries[index]
            found = _read_frame(entry.file, Path(self.path or ""), index, self._options, wanted)
            steps.append(self._step_rows(found, index))
        return self._plan.fields(steps)  # each step's rows checked by _step_rows

    def _step_rows(self, found: Dataset, index: int) -> list[np.ndarray]:
        """One step's rows of each field, its integer arrays checked against the first's."""
        counts = {VERTEX: len(found.points), FACE: len(found.faces)}
        arrays = {key: array.values for key, array in found.arrays.items()}
        try:
            return self._plan.step_rows(arrays, counts)
        except InputError as error:
            raise InputError(error.reason, path=self._entries[index].file, frame=index) from None


def _refuse_repeated_files(entries: list[_Entry], path: Path) -> None:
    """Each frame must have a file of its own: an index that lists one file many times would
    read it again for every listing."""
    seen: dict[Path, int] = {}
    for index, entry in enumerate(entries):
        key = entry.file.resolve()
        if key in seen:
            raise InputError(
                f"lists {entry.file.name} for frames {seen[key]} and {index}: each time step "
                "must have a file of its own",
                path=path,
                frame=index,
            )
        seen[key] = index


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
    stream = open_input(path, "a ParaView .pvd collection")
    with stream:
        # read(n) reserves n bytes at once: ask for no more than the file holds
        size = os.fstat(stream.fileno()).st_size
        data = stream.read(min(size, MAX_INDEX_BYTES) + 1)
    if len(data) > MAX_INDEX_BYTES:
        raise InputError(
            f"is larger than {MAX_INDEX_BYTES} bytes, far more than an index of time steps needs",
            path=path,
        )
    try:
        root = parse_xml(data, "VTK")
    except InputError as error:
        raise InputError(error.reason, path=path) from None
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
    try:
        inside_folder(path.parent, name)
    except InputError as error:
        raise InputError(f"DataSet {number} {error.reason}", path=path) from None
    file = path.parent / name.replace("\\", "/")
    suffix = file.suffix.lower()
    if suffix in _PARALLEL:
        raise InputError(
            f"DataSet {number} names {name!r}, a parallel file of pieces: merge the pieces "
            "into one mesh first (ParaView: Merge Blocks, then save as .vtp or .vtu)",
            path=path,
        )
    if suffix not in DATASETS:
        raise InputError(
            f"DataSet {number} names {name!r}: a .pvd read here lists .vtp or .vtu files "
            "(VTK XML PolyData or UnstructuredGrid)",
            path=path,
        )
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


def _read_frame(
    file: Path,
    pvd: Path,
    index: int,
    options: ReadOptions,
    wanted: set[tuple[str, str]] | None,
) -> Dataset:
    """The points (K, 3) float64, faces and the ``wanted`` arrays (``None``: all) of one
    .vtp/.vtu frame, checked; its compressed arrays inflate within ``options.max_memory``,
    together."""
    try:
        stream = open_regular_file(file, "a VTK XML file")
    except OSError as error:
        raise InputError(
            f"cannot read it (listed by {pvd}): {error.strerror or error}", path=file, frame=index
        ) from None
    with stream:
        data = stream.read()
    if b"<VTKFile" not in data:
        raise InputError(
            f"is not a VTK XML file (listed by {pvd}): it has no <VTKFile> element",
            path=file,
            frame=index,
        )
    try:
        return parse_dataset(data, options.inflation(), wanted)
    except InputError as error:
        raise InputError(error.reason, path=file, frame=index) from None


def write_pvd(
    seq: MeshSequence,
    path: Path,
    options: WriteOptions,
    *,
    frame_suffix: str = FRAME_SUFFIX,
    layout: Layout | None = None,
) -> None:
    """Write ``path`` (.pvd) and one file per frame in the folder named after its stem.

    ``frame_suffix`` is ``".vtp"`` (PolyData, the default) or ``".vtu"`` (UnstructuredGrid);
    ``layout`` how arrays are stored (ParaView's default layout when ``None``). Every target is
    checked before any work; the frames are staged and moved in whole and the .pvd written
    last, atomically. Time steps are the time codes (0, 1, 2... without them).
    """
    if frame_suffix not in DATASETS:
        raise ValueError(f"frame_suffix must be one of {sorted(DATASETS)}, not {frame_suffix!r}")
    folder = path.with_suffix("")
    if folder == path:
        raise ValueError(f"{path}: a .pvd needs a name with a suffix, for its frames' folder")
    names = frame_file_names(seq.frame_names, frame_suffix)
    refuse_existing([path], options.overwrite)  # before the frames are written
    try:
        targets = arrays_to_write(seq)
    except InputError as error:
        raise InputError(error.reason, path=path) from None
    writer = DatasetWriter(seq.faces, seq.vertex_count, DATASETS[frame_suffix], layout)
    points = seq.compact_vertices()  # float32 where exact, else float64
    with atomic_folder(folder, names, overwrite=options.overwrite) as staging:
        for index, name in enumerate(names):
            data = _moving_normals(seq, targets, index)
            (staging / name).write_bytes(writer(points[index], data, index))
    write_atomic(path, _index_xml(folder.name, names, seq.codes()), overwrite=options.overwrite)


def cannot_keep(seq: MeshSequence) -> list[str]:
    """What a VTK series cannot keep of ``seq`` (the format's ``cannot_keep``): attributes per
    face corner, the indices of indexed attributes (written one value per element), face
    sets."""
    return cannot_keep_arrays(seq)


def _moving_normals(seq: MeshSequence, targets: list[TargetArray], frame: int) -> list[TargetArray]:
    """The arrays of ``frame``: static normals are the stored ones at frame 0 and recomputed
    from each later frame's positions (the normals of a moving mesh move with it)."""
    if frame == 0:
        return targets
    moved = []
    for target in targets:
        if target.static and target.role == NORMAL and target.domain == VERTEX:
            attribute = seq.attribute_named(target.name)
            values = recomputed_normals(seq.vertices[frame], seq.faces, attribute)
            if attribute.indices is not None:
                values = values[attribute.indices]
            values = values.astype(attribute.values.dtype, copy=False)  # each frame's one type
            target = TargetArray(target.name, target.domain, target.role, values, None)
        moved.append(target)
    return moved


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
