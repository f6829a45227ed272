"""The Alembic format (``.abc``): a PolyMesh's position samples, read and written with
alembic3d (the ``alembic`` extra), an UNOFFICIAL build of PyAlembic, the Alembic project's
Python bindings, packaged on PyPI by a third party (import name ``alembic3d``; not affiliated
with or supported by the Alembic project, ILM or Sony Pictures Imageworks). It reads and writes
Ogawa archives only (HDF5 ones are refused, saying how to convert them).

Reading:

* The object is the one ``--object PATH`` names (:attr:`ReadOptions.object_path`, its full
  name such as ``/root/mesh/meshShape``); without it, the only PolyMesh (or SubD, whose cage is
  the same data) in the archive. Several, none, or an object that is not one are errors that
  list the archive's meshes.
* Frames are its position samples in order. alembic3d's sample selector takes any number as
  a *time*, so each sample is asked for at its own time from the object's time sampling
  (uniform, cyclic or acyclic), checked first to increase and to select that very sample.
* ``frame_rate``, in this order: the exact rate tuckercodec writes in the archive's metadata
  (``tuckercodec_frame_rate``); the archive's DCC FPS hint (written by Maya, Houdini and
  Blender, to 6 decimals); 1/timePerCycle of a uniform time sampling (a whole or NTSC
  n*1000/1001 rate when within 1e-9 of one, or for the DCC FPS within its 6 decimals); else
  none. ``time_codes`` = sample time x rate (x 24 without a rate, so that
  :meth:`MeshSequence.seconds` gives the file's times), a value within 16 units in the last
  place of a multiple of 1e-6 taken as that multiple (whole frame numbers stay whole).
* Faces are the face counts and indices of the first sample, each face reversed, [a, b, c, d]
  to [d, c, b, a]: Alembic's faces wind clockwise (RenderMan's convention), and Alembic's own
  Maya plugins (AbcExport, AbcImport), Blender's importer ("Alembic's polygon winding order is
  clockwise") and USD's Alembic plugin ("Alembic is always left-handed") all reverse them so.
  So do we, reading and writing: our faces stay counter-clockwise. Faces that change between
  samples are refused, naming the first frame where they differ.
* Positions are read as stored, in the object's own space: no Xform is applied (see
  :mod:`.usd` for why).
* UVs, normals, arbitrary geom params, velocities and face sets become the sequence's
  attributes, fields and face sets (:mod:`.alembic_attached`), per-corner values reversed
  with their faces so that each corner keeps its value.
* A file Alembic cannot read, a sample whose point count differs, NaN or Inf are
  :class:`InputError`\\ s naming the file, the object and the frame; so are the library's crashes
  and runaway allocations on damaged files, as it reads in a child process (:mod:`.isolation`).
  :func:`open_alembic` reads the samples a range at a time, in a child that stays open
  (:mod:`.isolation`; :class:`ArchiveFrames` is what it runs).

Writing: an Ogawa archive holding an Xform ``/<name>`` (identity) and a PolyMesh
``/<name>/<name>Shape`` named after the file (``horse.abc`` gives ``/horse/horseShape``): the
faces (reversed, as above) in its first sample, float32 positions in every sample, and the
sequence's attributes, fields and face sets as :mod:`.alembic_plan` lays them out (UVs, normals
and velocities in the schema's own params, the rest as arbitrary geom params and FaceSet
objects; :func:`cannot_keep` lists what does not fit). Its time
sampling is uniform, starting at ``codes()[0] / rate`` and stepping by the codes' step / rate,
when the codes are evenly spaced and so read back exactly; otherwise acyclic, one time per
frame (code / rate), and where those times cannot give back every code exactly, the codes
themselves go in the mesh's user property ``tuckercodec_time_codes``. The rate (24 when the
sequence has none) is the archive's DCC FPS and, exactly, its ``tuckercodec_frame_rate``. The
file is written to a hidden temporary name beside the target, opened again to check its
samples, and put in place when complete (:func:`~tuckercodec.system.atomic.atomic_path`).
The library writes in a child process (:func:`~.isolation.write_isolated`): when a write fails
(a full disk) alembic3d raises, then aborts the process that releases the archive (a C++
exception out of a destructor), so a failure ends as an ``OSError`` naming the file (the
command line's exit code 1), with the temporary file removed, not as a dead process.
"""

from __future__ import annotations

import errno
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from .._version import __version__
from ..errors import InputError
from ..model.attributes import Field
from ..model.sequence import DEFAULT_FRAME_RATE, MeshSequence, float32_vertices
from ..model.sources import FrameByFrame, FrameSource
from ..system.atomic import atomic_path
from ..system.optional import import_optional
from ..system.reading import open_regular_file
from .alembic_attached import Mesh, read_attached
from .alembic_plan import cannot_keep as cannot_keep  # the format's registry hook
from .alembic_plan import plan
from .alembic_writing import ParamWriter, pack_plan, unpack_plan
from .common.polygons import (
    faces_from_polygons,
    first_change,
    polygons_from_faces,
    reverse_winding,
)
from .isolation import IsolatedFrames, note, write_isolated
from .registry import ReadOptions, WriteOptions
from .usd import listing, prim_name

#: What alembic3d raises on a damaged archive: Alembic's exceptions (RuntimeError), names and
#: metadata that are not UTF-8, and a size it cannot allocate.
_LIBRARY_ERRORS = (RuntimeError, UnicodeError, MemoryError, OverflowError)
#: The first bytes of an HDF5 file: an Alembic archive of the old back end.
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
#: The modules of alembic3d (and the imath it brings) that :func:`_alembic` returns.
_MODULES = ("alembic3d.Abc", "alembic3d.AbcGeom", "alembic3d.AbcCoreAbstract", "imath")


def _alembic(purpose: str) -> SimpleNamespace:
    """The alembic3d modules (and the imath they bring), or DependencyError naming the extra."""
    Abc, AbcGeom, AbcA, imath = (import_optional(name, "alembic", purpose) for name in _MODULES)
    return SimpleNamespace(Abc=Abc, AbcGeom=AbcGeom, AbcA=AbcA, imath=imath)


def _message(error: BaseException) -> str:
    """An Alembic exception's text on one line, without its repeated "ERROR: EXCEPTION:"."""
    text = " ".join(str(error).replace("ERROR: EXCEPTION:", ":").split())
    return text[:300] or type(error).__name__


def open_alembic(path: Path, options: ReadOptions) -> FrameSource:
    """The frames of a PolyMesh, read sample by sample in a child process that stays open
    (:mod:`.isolation`)."""
    return IsolatedFrames(ArchiveFrames, path, options, "Alembic", "alembic", _MODULES)


class ArchiveFrames(FrameByFrame):
    """A PolyMesh's position samples read one by one in this process (what the reading child
    runs): the archive, object, sample times, faces and rate at once, each frame's positions
    when read."""

    def __init__(self, path: Path, options: ReadOptions):
        abc = self._abc = _alembic("reading Alembic files")
        try:
            with open_regular_file(path, "an Alembic archive") as stream:
                head = stream.read(len(_HDF5_SIGNATURE))
        except OSError as error:
            raise InputError(f"cannot read: {error.strerror or error}", path=path) from None
        if head == _HDF5_SIGNATURE:
            raise InputError(
                "is an HDF5 Alembic archive; only Ogawa archives are read (convert it with "
                "Alembic's abcconvert -toOgawa)",
                path=path,
            )
        try:
            archive = abc.Abc.IArchive(str(path))
            meshes, others = _objects(abc, archive)
        except _LIBRARY_ERRORS as error:
            raise InputError(
                f"cannot read as an Alembic archive: {_message(error)}", path=path
            ) from None
        name = _chosen_mesh(list(meshes), others, options.object_path, path)
        self._file, self._archive, self._where = path, archive, f"object {name}"
        try:
            self._open_mesh(meshes[name])
        except InputError:
            raise
        except _LIBRARY_ERRORS as error:
            raise InputError(f"object {name}: cannot read: {_message(error)}", path=path) from None

    def _open_mesh(self, item: Any) -> None:
        """The sample times, frame 0 (for the vertex count), the faces, rate and time codes."""
        abc, where, path = self._abc, self._where, self._file
        kind = abc.AbcGeom.IPolyMesh if abc.AbcGeom.IPolyMesh.matches(item.getHeader()) else None
        kind = kind or abc.AbcGeom.ISubD
        schema = kind(item, abc.Abc.WrapExistingFlag.kWrapExisting).getSchema()
        self._positions = schema.getPositionsProperty()
        count = self._positions.getNumSamples()
        if count < 1:
            raise InputError(f"{where}: has no position samples", path=path)
        sampling = self._positions.getTimeSampling()
        times = np.array([sampling.getSampleTime(index) for index in range(count)], dtype=float)
        check_times(sampling, times, where, path)
        self._times = times
        self._selectors = [
            abc.Abc.ISampleSelector(time, abc.Abc.ISampleSelector.TimeIndexType.kNearIndex)
            for time in times.tolist()
        ]
        self._first = self._frame(0)
        note(where)  # the faces, read from every sample if they may change
        faces = _faces(schema, self._selectors, times, len(self._first), where, path)
        rate = frame_rate(abc, self._archive, sampling)
        codes = kept_codes(abc, schema, codes_from_times(times, rate or DEFAULT_FRAME_RATE))
        mesh = Mesh(path, where, faces, len(self._first), self._selectors)
        attached = read_attached(abc, item, schema, mesh)
        self._fields = attached.fields
        try:
            self._describe(
                path,
                count,
                len(self._first),
                faces,
                None,
                rate,
                codes,
                attributes=attached.attributes,
                face_sets=attached.face_sets,
                field_names=[reader.name for reader in attached.fields],
            )
        except InputError as error:
            raise InputError(f"{where}: {error.reason}", path=path, frame=error.frame) from None

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        note(self._where, start)  # where the library crashed, if it does
        try:
            return [reader.read(start, stop) for reader in self._fields]
        except _LIBRARY_ERRORS as error:
            raise InputError(
                f"{self._where}: cannot read its fields: {_message(error)}",
                path=self._file,
                frame=start,
            ) from None

    def _frame(self, frame: int) -> np.ndarray:
        """Frame ``frame``'s positions, (K, 3), finite."""
        where, path, time = self._where, self._file, self._times[frame]
        note(where, frame)  # where the library crashed, if it does
        try:
            sample = np.asarray(self._positions.getValue(self._selectors[frame]))
        except _LIBRARY_ERRORS as error:
            raise InputError(
                f"{where}: cannot read sample {frame}: {_message(error)}", path=path, frame=frame
            ) from None
        if sample.ndim != 2 or sample.shape[1] != 3 or sample.dtype.kind != "f" or not sample.size:
            raise InputError(
                f"{where}: sample {frame} holds no 3D positions (dtype {sample.dtype}, shape "
                f"{sample.shape})",
                path=path,
                frame=frame,
            )
        if frame and len(sample) != self.vertex_count:
            raise InputError(
                f"{where}: {len(sample)} positions at time {time} s, where frame 0 has "
                f"{self.vertex_count}: the vertex count must stay the same",
                path=path,
                frame=frame,
            )
        bad = ~np.isfinite(sample)
        if bad.any():
            raise InputError(
                f"{where}: vertex {int(np.argwhere(bad)[0][0])} has a non-finite coordinate "
                f"at time {time} s",
                path=path,
                frame=frame,
            )
        return sample


def _objects(abc: SimpleNamespace, archive: Any) -> tuple[dict[str, Any], dict[str, str]]:
    """Every PolyMesh and SubD object of the archive by full name, and the schema of every
    other object by full name."""
    meshes, others = {}, {}
    stack = [archive.getTop()]
    while stack:  # depth first, children in their order (no recursion: any depth)
        item = stack.pop()
        children = [item.getChild(index) for index in range(item.getNumChildren())]
        stack.extend(reversed(children))
        header = item.getHeader()
        if abc.AbcGeom.IPolyMesh.matches(header) or abc.AbcGeom.ISubD.matches(header):
            meshes[item.getFullName()] = item
        else:
            others[item.getFullName()] = item.getMetaData().get("schema") or "no schema"
    return meshes, others


def _chosen_mesh(names: list[str], others: dict[str, str], wanted: str | None, path: Path) -> str:
    """The full name of the mesh object to read: ``wanted``, or the only one."""
    if wanted is not None:
        if wanted in names:
            return wanted
        if wanted in others:
            raise InputError(
                f"object {wanted} is not a PolyMesh ({others[wanted]}); the meshes are: "
                f"{listing(names)}",
                path=path,
            )
        raise InputError(
            f"there is no object {wanted}; the meshes are: {listing(names)}", path=path
        )
    if len(names) == 1:
        return names[0]
    if not names:
        raise InputError("holds no PolyMesh (or SubD) object", path=path)
    raise InputError(
        f"holds {len(names)} meshes: {listing(names)}; choose one with --object PATH",
        path=path,
    )


def _faces(
    schema: Any,
    selectors: list[Any],
    times: np.ndarray,
    vertex_count: int,
    where: str,
    path: Path,
) -> np.ndarray:
    """The faces of the first sample, the same in every sample, counter-clockwise."""
    counts, indices = schema.getFaceCountsProperty(), schema.getFaceIndicesProperty()

    def topology(selector: Any) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(counts.getValue(selector)), np.asarray(indices.getValue(selector))

    varying = not (counts.isConstant() and indices.isConstant())
    first, frame = first_change(lambda n: topology(selectors[n]), len(selectors), varying)
    if frame is not None:
        raise InputError(
            f"{where}: the faces change at time {times[frame]} s (face counts or indices "
            "differ from frame 0's); a sequence keeps one set of faces",
            path=path,
            frame=frame,
        )
    try:
        return reverse_winding(faces_from_polygons(first[0], first[1], vertex_count))
    except InputError as error:
        raise InputError(f"{where}: {error.reason}", path=path) from None


def write_alembic(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as an Ogawa Alembic archive (see the module docstring), atomically,
    in a child process (:func:`.isolation.write_isolated`): alembic3d aborts the process that
    releases an archive whose write failed (a full disk), so only the child may hold one."""
    rate, name = seq.frame_rate or DEFAULT_FRAME_RATE, prim_name(path.stem)
    positions = float32_vertices(seq, path)  # an infinity is refused, not written
    attached, attached_arrays = pack_plan(plan(seq))
    arrays = {"positions": positions, "faces": seq.faces, "codes": seq.codes()}
    with atomic_path(path, overwrite=options.overwrite) as temporary:
        write_isolated(
            write_archive_file,
            temporary,
            arrays | attached_arrays,
            {"name": name, "rate": rate, "attached": attached},
            shown=path,
            library="Alembic",
            extra="alembic",
            preload=_MODULES,
        )


def write_archive_file(path: Path, arrays: dict[str, np.ndarray], values: dict[str, Any]) -> None:
    """Write the archive and check that it holds every sample (what the writing child runs).

    Raises:
        OSError: the library failed, or wrote fewer samples.
    """
    abc = _alembic("writing Alembic files")
    name, positions = values["name"], arrays["positions"]
    try:
        params = ParamWriter(abc, unpack_plan(values["attached"], arrays))
        _write_archive(abc, arrays, path, name, values["rate"], params)
        written = _written_samples(abc, path, f"/{name}/{name}Shape")
    except _LIBRARY_ERRORS as error:
        raise OSError(errno.EIO, f"Alembic could not write it: {_message(error)}") from None
    if written != len(positions):
        raise OSError(errno.EIO, f"Alembic wrote {written} of {len(positions)} samples")


def _write_archive(
    abc: SimpleNamespace,
    arrays: dict[str, np.ndarray],
    path: Path,
    name: str,
    rate: float,
    params: ParamWriter,
) -> None:
    """Write the archive of ``arrays`` (float32 positions, faces, time codes) and ``params``
    (attributes, fields, face sets); it is complete once every object is released, on
    return."""
    positions, codes = arrays["positions"], arrays["codes"]
    metadata = abc.AbcA.MetaData()
    metadata.set(RATE_KEY, repr(rate))
    archive = abc.Abc.CreateArchiveWithInfo(
        str(path), rate, f"tuckercodec {__version__}", "", abc.Abc.Argument(metadata)
    )
    sampling, exact = time_sampling(abc, codes, rate)
    xform = abc.AbcGeom.OXform(archive.getTop(), name)
    xform.getSchema().set(abc.AbcGeom.XformSample())  # identity, constant
    sampling_index = archive.addTimeSampling(sampling)
    mesh = abc.AbcGeom.OPolyMesh(xform, f"{name}Shape", sampling_index)
    schema = mesh.getSchema()
    if not exact:
        kept = abc.Abc.ODoubleArrayProperty(schema.getUserProperties(), CODES_KEY)
        kept.setValue(abc.imath.DoubleArrayFromBuffer(codes))
    counts, indices = polygons_from_faces(reverse_winding(arrays["faces"]))
    params.name_uvs(schema)
    for frame in range(len(positions)):
        points = abc.imath.V3fArrayFromBuffer(positions[frame])  # a copy
        if frame == 0:
            topology = (abc.imath.IntArrayFromBuffer(a) for a in (indices, counts))
            sample = abc.AbcGeom.OPolyMeshSchemaSample(points, *topology)
        else:  # the faces stay: Alembic repeats the previous sample's
            sample = abc.AbcGeom.OPolyMeshSchemaSample(points)
        params.fill(sample, frame)
        schema.set(sample)
    params.write_beside(schema, sampling_index, len(positions))


def _written_samples(abc: SimpleNamespace, path: Path, name: str) -> int:
    """How many position samples the object ``name`` of a written archive holds (0: none)."""
    meshes, _ = _objects(abc, abc.Abc.IArchive(str(path)))
    if name not in meshes:
        return 0
    schema = abc.AbcGeom.IPolyMesh(meshes[name], abc.Abc.WrapExistingFlag.kWrapExisting)
    return int(schema.getSchema().getPositionsProperty().getNumSamples())


# ------------------------------------------------------------------------------------------
# time: sample times to and from time codes and a frame rate (the conventions are the module
# docstring's), shared by the reader and the writer


#: The archive metadata key that holds the exact frame rate (the DCC FPS key keeps 6 decimals).
RATE_KEY = "tuckercodec_frame_rate"
#: The mesh's user property that holds the exact time codes, written only where no sample
#: times give them back exactly (time x rate cannot reach every float).
CODES_KEY = "tuckercodec_time_codes"


def check_times(sampling: Any, times: np.ndarray, where: str, path: Path) -> None:
    """Refuse sample times that do not increase, or that do not select their own sample."""
    bad = np.flatnonzero(~np.isfinite(times))
    if bad.size:
        frame = int(bad[0])
        raise InputError(f"{where}: sample {frame} has the time {times[frame]}", path=path)
    steps = np.flatnonzero(np.diff(times) <= 0)
    if steps.size:
        frame = int(steps[0]) + 1
        raise InputError(
            f"{where}: the time of sample {frame} ({times[frame]} s) does not follow sample "
            f"{frame - 1}'s ({times[frame - 1]} s)",
            path=path,
            frame=frame,
        )
    for frame, time in enumerate(times.tolist()):
        if sampling.getNearIndex(time, len(times)) != frame:  # a read by time would miss it
            raise InputError(
                f"{where}: the time of sample {frame} ({time} s) selects another sample",
                path=path,
                frame=frame,
            )


def frame_rate(abc: SimpleNamespace, archive: Any, sampling: Any) -> float | None:
    """Frames per second: ours, the DCC's, or the uniform sampling's (module docstring)."""
    metadata = archive.getTop().getMetaData()
    for key, tolerance in ((RATE_KEY, 0.0), ("_ai_DCC_FPS", 5e-7)):  # DCC FPS: 6 decimals
        try:
            rate = float(metadata.get(key))
        except (TypeError, ValueError):
            continue
        if math.isfinite(rate) and rate > 0:
            return _usual_rate(rate, tolerance)
    kind = sampling.getTimeSamplingType()
    if not kind.isUniform() or not kind.getTimePerCycle() > 0:
        return None
    rate = 1.0 / kind.getTimePerCycle()
    return _usual_rate(rate, 1e-9 * rate) if math.isfinite(rate) else None


def _usual_rate(rate: float, tolerance: float) -> float:
    """A whole or NTSC (n*1000/1001) rate within ``tolerance`` of ``rate``, else ``rate``."""
    for candidate in (float(round(rate)), round(rate * 1.001) * 1000 / 1001):
        if candidate > 0 and abs(rate - candidate) <= tolerance:
            return candidate
    return rate


def kept_codes(abc: SimpleNamespace, schema: Any, codes: np.ndarray) -> np.ndarray:
    """The exact time codes tuckercodec kept beside the times (:data:`CODES_KEY`), where they
    agree with the times, else ``codes``."""
    user = schema.getUserProperties()
    header = user.getPropertyHeader(CODES_KEY) if user.valid() else None
    if header is None or not abc.Abc.IDoubleArrayProperty.matches(header):
        return codes
    kept = np.asarray(abc.Abc.IDoubleArrayProperty(user, CODES_KEY).getValue(), dtype=np.float64)
    if kept.shape != codes.shape or not np.all(
        np.abs(kept - codes) <= 1e-6 * np.maximum(1.0, np.abs(codes))
    ):
        return codes  # stale or foreign: the times are what the file says
    return kept


def codes_from_times(times: np.ndarray, rate: float) -> np.ndarray:
    """Time codes of sample times: time x rate, a value within a few units in the last place
    of a multiple of 1e-6 taken as that multiple, so that frame numbers come out whole (the
    multiplication and the sampling's own arithmetic round by an ulp or two)."""
    codes = np.asarray(times, dtype=np.float64) * rate
    snapped = np.round(codes, 6)
    close = np.abs(codes - snapped) <= 16 * np.spacing(np.abs(codes))
    return np.where(close, snapped, codes)


def time_sampling(abc: SimpleNamespace, codes: np.ndarray, rate: float) -> tuple[Any, bool]:
    """A uniform time sampling if it gives back exactly these codes, else an acyclic one; and
    whether its times give back the codes exactly."""
    AbcA = abc.AbcA
    start = float(codes[0]) / rate
    step = (float(codes[1]) - float(codes[0])) / rate if len(codes) > 1 else 1.0 / rate
    # what Alembic's TimeSampling::getSampleTime computes for a uniform sampling
    uniform = start + step * np.arange(len(codes), dtype=np.float64)
    if step > 0 and np.array_equal(codes_from_times(uniform, rate), codes):
        return AbcA.TimeSampling(step, start), True
    times = codes / rate
    vector = AbcA.TimeVector()
    vector.extend(times.tolist())
    kind = AbcA.TimeSamplingType(AbcA.AcyclicFlag.kAcyclic)
    return AbcA.TimeSampling(kind, vector), np.array_equal(codes_from_times(times, rate), codes)
