"""The USD format (``.usd``, ``.usda``, ``.usdc``): a UsdGeomMesh whose ``points`` carry time
samples, read and written with Pixar's usd-core (the ``usd`` extra; imported as ``pxr``).

Reading:

* The mesh is the prim ``--prim PATH`` names (:attr:`ReadOptions.prim`); without it, the only
  Mesh whose points are animated (two or more time samples), else the only Mesh. Several
  candidates, a path that is not a prim, or a prim that is not a Mesh are errors that list the
  stage's meshes.
* Frames are the points' time samples, in time order, and ``time_codes`` their times (stage
  time, after any layer offsets). Points without time samples give one frame, their default
  value, and no time codes.
* ``meters_per_unit`` and ``up_axis`` are the stage's ``metersPerUnit`` and ``upAxis``: as
  authored, else USD's fallbacks (0.01, Y), which is what an unauthored stage means.
* ``frame_rate`` is the stage's ``timeCodesPerSecond``, which is what turns a time code into
  seconds; ``framesPerSecond`` is only a playback hint, so where the two differ
  ``timeCodesPerSecond`` wins and every frame keeps its time in seconds. USD's own fallbacks
  apply: unauthored, it is ``framesPerSecond`` if that is authored, else 24.
* Faces are ``faceVertexCounts``/``faceVertexIndices`` in the file's order, polygons as rows
  padded with -1. A mesh whose ``orientation`` is ``leftHanded`` has each face's corners
  reversed (as USD's own Alembic plugin does), so that faces wind counter-clockwise seen from
  their front, like every other format's. Faces that change over time are refused, naming the
  first frame (index and time code) where they differ from frame 0.
* Positions are read as authored: in the prim's own space, without its transform or its
  parents' (``xformOps``, animated or not). A point cache's deformation lives in ``points``;
  applying a transform would change every float (so no exact round trip) and mix rigid motion
  into what the codec compresses. A stage whose mesh moves by an animated transform reads as
  the mesh standing still in its own space.
* A file USD cannot read, a time sample whose point count differs from frame 0's, NaN or Inf
  (naming frame, time code and vertex) are :class:`InputError`\\ s naming the file and prim.
  pxr's warnings are kept from the terminal. What pxr allocates while it reads is out of our
  hands: it checks the byte ranges of uncompressed arrays against the file, but a crafted
  ``.usdc`` can declare a compressed integer array (the faces) of any length, which pxr
  allocates before the data is found short (8 GiB in 27 s for 2^31 indices in a 1 KB file).
  So the file is read in a child process (:mod:`.isolation`) whose memory and time are
  capped, and which may crash without taking the caller along: each is an InputError.
  :func:`open_usd` reads the frames sample by sample, a range at a time, in a child that stays
  open (:mod:`.isolation`; :class:`StageFrames` is what it runs).
* Beside the points (:mod:`.usd_primvars`): primvars of vertex, varying, faceVarying and
  uniform interpolation are attributes (vertex, corner, face) named without ``primvars:``,
  indexed ones with their indices, of float, double or int values of 1 to 4 components, their
  role from the value type (texCoord, color, normal) or USD's names (``st``, ``displayColor``,
  ``normals``); ``constant`` primvars, other value types and ``elementSize`` > 1 are not read.
  ``primvars:normals``, else the ``normals`` attribute, is the normal attribute, frame 0's
  values if time-sampled. Other time-sampled vertex or uniform primvars, and ``velocities``,
  are fields read a range at a time; GeomSubsets of faces are face sets of their
  ``familyName``. Primvars are listed by name (pxr's order), ``velocities`` last.
* A stage reads only files inside its own folder: pxr resolves any asset path, absolute or
  ``../``, so before the stage opens, each layer's sublayers, references and payloads (in
  variants too) and its value clips (asset paths, manifests, templates) are resolved as pxr
  would, layer after layer, and one that leads out of the folder is refused naming the layer
  and the asset path (a file pxr would not find is not read, and passes; a variable
  expression, evaluated into a path, is refused).

Writing: a stage with the sequence's ``upAxis`` and ``metersPerUnit``; for a sequence that
carries none (an Alembic or point cache, an OBJ folder), Y and 0.01, USD's fallbacks (authored
because usdchecker requires it: the file means what an unauthored one would). ``defaultPrim``
``/Root``, an Xform ``/Root`` holding a Mesh named after the file (``horse.usdc`` gives
``/Root/horse``) with ``subdivisionScheme`` "none", float32 ``points`` and an ``extent``
sampled at the sequence's time codes, its faces as counts and indices, and
``timeCodesPerSecond`` = ``framesPerSecond`` = the frame rate (24, USD's default, for a
sequence without one, which then reads back at 24) with ``startTimeCode``/``endTimeCode``.
Attributes are primvars, face sets GeomSubsets, fields time-sampled primvars or
``velocities``, normals of an animated mesh recomputed per frame after frame 0
(:mod:`.usd_authoring`, whose :func:`cannot_keep` lists what a file loses: names USD refuses,
roles its types cannot say). ``.usda`` is text; ``.usdc`` and ``.usd`` are binary crate files.
The file is written to a hidden temporary name beside the target and put in place when complete
(:func:`~tuckercodec.system.atomic.atomic_path`). Writing runs in this process: the data is ours.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import InputError
from ..model.attributes import Field
from ..model.sequence import DEFAULT_FRAME_RATE, MeshSequence, float32_vertices
from ..model.sources import FrameByFrame, FrameSource
from ..system.atomic import atomic_path
from ..system.optional import import_optional
from ..system.reading import open_regular_file
from .common.polygons import (
    faces_from_polygons,
    first_change,
    polygons_from_faces,
    reverse_winding,
)
from .isolation import IsolatedFrames, note
from .registry import ReadOptions, WriteOptions
from .usd_authoring import cannot_keep as cannot_keep  # the format's hook, in the registry
from .usd_authoring import write_attached
from .usd_primvars import MeshReading

#: Where the written mesh lives: the root Xform (also the stage's defaultPrim).
ROOT = "/Root"
#: How many prim paths (or Alembic objects) an error lists before "and N more".
_LISTED = 8


#: The pxr modules this format uses.
_MODULES = ("Usd", "UsdGeom", "Sdf", "Tf", "Vt", "UsdUtils", "Ar")
#: The prim metadata of value clips that name files: the clip sets' dictionary, and the fields
#: of the older clip metadata.
_CLIP_FIELDS = ("clipAssetPaths", "clipManifestAssetPath", "clipTemplateAssetPath")
#: ... as the reading child imports them, before its memory is capped.
_PRELOAD = tuple(f"pxr.{name}" for name in _MODULES)


def _pxr(purpose: str) -> SimpleNamespace:
    """The pxr modules this format uses, or DependencyError naming the ``usd`` extra."""
    return SimpleNamespace(
        **{name: import_optional(f"pxr.{name}", "usd", purpose) for name in _MODULES}
    )


@contextmanager
def _quiet(pxr: SimpleNamespace) -> Iterator[None]:
    """Keep pxr's warnings and status messages of the block from the terminal: the errors that
    matter reach the caller as exceptions, and the rest is noise to the user of a file."""
    delegate = pxr.UsdUtils.CoalescingDiagnosticDelegate()
    try:
        yield
    finally:
        delegate.TakeUncoalescedDiagnostics()
        del delegate


def _errors(pxr: SimpleNamespace) -> tuple[type[BaseException], ...]:
    """What pxr raises on a damaged file: its Tf errors, and names or messages quoting bytes
    that are not UTF-8 (boost.python cannot turn them into ``str``)."""
    return (pxr.Tf.ErrorException, UnicodeError)


def _tf_message(error: BaseException) -> str:
    """The commentary of a pxr error, without its C++ function names and source lines."""
    texts = []
    for item in error.args:
        try:
            texts.append(str(getattr(item, "commentary", "")).strip())
        except UnicodeError:  # the message quotes the damaged bytes
            texts.append("(a message that is not UTF-8)")
    texts = [text for text in texts if text] or [str(error).strip() or type(error).__name__]
    return "; ".join(text[:200] for text in texts[:2])


def open_usd(path: Path, options: ReadOptions) -> FrameSource:
    """The frames of a UsdGeomMesh, read sample by sample in a child process that stays open
    (:mod:`.isolation`)."""
    return IsolatedFrames(StageFrames, path, options, "USD", "usd", _PRELOAD)


class StageFrames(FrameByFrame):
    """A UsdGeomMesh's points read sample by sample in this process (what the reading child
    runs): the stage, prim, time samples and faces at once, each frame's points when read."""

    def __init__(self, path: Path, options: ReadOptions):
        pxr = self._pxr = _pxr("reading USD files")
        try:
            open_regular_file(path, "a USD file").close()  # a folder or a pipe: a clear error
        except OSError as error:
            raise InputError(f"cannot read: {error.strerror or error}", path=path) from None
        self._file = path
        with _quiet(pxr):
            try:
                _confine(pxr, path)
                stage = pxr.Usd.Stage.Open(str(path), pxr.Usd.Stage.LoadAll)
            except _errors(pxr) as error:
                raise InputError(
                    f"cannot read as a USD file: {_tf_message(error)}", path=path
                ) from None
            if not stage:
                raise InputError("cannot read as a USD file", path=path)
            try:
                prim = _chosen_mesh(pxr, stage, options.prim, path)
            except _errors(pxr) as error:
                raise InputError(
                    f"cannot read its prims: {_tf_message(error)}", path=path
                ) from None
            self._stage, self._where = stage, f"prim {prim.GetPath()}"
            try:
                self._open_mesh(prim)
            except _errors(pxr) as error:
                raise InputError(
                    f"{self._where}: cannot read: {_tf_message(error)}", path=path
                ) from None

    def _open_mesh(self, prim: Any) -> None:
        """The time samples, frame 0 (for the vertex count), the faces and the rate."""
        pxr, where, path = self._pxr, self._where, self._file
        mesh = pxr.UsdGeom.Mesh(prim)
        self._points = mesh.GetPointsAttr()
        times = [float(time) for time in self._points.GetTimeSamples()]
        self._times = times
        # one frame when the points have no samples: their default, which EarliestTime reads
        self._frame_times = times or [pxr.Usd.TimeCode.EarliestTime()]
        self._first = self._frame(0)
        note(where)  # the faces, read from every frame if they may change
        faces = _faces(pxr, mesh, self._frame_times, times, len(self._first), where, path)
        left_handed = mesh.GetOrientationAttr().Get() == pxr.UsdGeom.Tokens.leftHanded
        self._carried = MeshReading(pxr, mesh, len(self._first), faces, left_handed, where, path)
        self._carried.read(self._frame_times[0])
        rate = float(self._stage.GetTimeCodesPerSecond())
        if not (np.isfinite(rate) and rate > 0):
            raise InputError(f"timeCodesPerSecond must be a positive number, got {rate}", path=path)
        codes = np.array(times) if times else None
        # what the stage means: its authored unit and up axis, else USD's fallbacks (0.01, Y)
        unit = float(pxr.UsdGeom.GetStageMetersPerUnit(self._stage))
        axis = str(pxr.UsdGeom.GetStageUpAxis(self._stage))
        try:
            self._describe(
                path,
                len(self._frame_times),
                len(self._first),
                faces,
                None,
                rate,
                codes,
                unit,
                axis,
                self._carried.attributes,
                self._carried.face_sets,
                [plan.primvar.name for plan in self._carried.fields],
            )
        except InputError as error:
            raise InputError(f"{where}: {error.reason}", path=path, frame=error.frame) from None

    def _frame(self, frame: int) -> np.ndarray:
        """Frame ``frame``'s points, (K, 3), finite."""
        where, path = self._where, self._file
        label = f"time code {self._times[frame]}" if self._times else "its default value"
        note(where, frame)  # where the library crashed, if it does
        try:
            value = self._points.Get(self._frame_times[frame])
        except _errors(self._pxr) as error:
            raise InputError(
                f"{where}: cannot read the points at {label}: {_tf_message(error)}",
                path=path,
                frame=frame,
            ) from None
        positions = _points(value, where, label, path, frame)
        if frame and len(positions) != self.vertex_count:
            raise InputError(
                f"{where}: {len(positions)} points at {label}, where frame 0 has "
                f"{self.vertex_count}: the vertex count must stay the same",
                path=path,
                frame=frame,
            )
        return positions

    def _read(self, start: int, stop: int) -> np.ndarray:
        with _quiet(self._pxr):
            return super()._read(start, stop)

    def _read_fields(self, start: int, stop: int) -> list[Field]:
        note(self._where, start)
        with _quiet(self._pxr):
            try:
                return self._carried.read_fields(self._frame_times[start:stop], start)
            except _errors(self._pxr) as error:
                raise InputError(
                    f"{self._where}: cannot read its fields: {_tf_message(error)}",
                    path=self._file,
                    frame=start,
                ) from None


def _confine(pxr: SimpleNamespace, path: Path) -> None:
    """Refuse a stage whose layers lead out of its folder: every layer it composes (sublayers,
    references and payloads, in variants too) and every value clip, as pxr's resolver would
    find them, followed from layer to layer before the stage opens any of them. A file that is
    not found is not read by pxr either; a variable expression, which would be evaluated into
    a path, is refused."""
    folder = path.parent.resolve()
    pending, seen = [str(path)], set()
    while pending:
        identifier = pending.pop()
        if identifier in seen:
            continue
        seen.add(identifier)
        layer = pxr.Sdf.Layer.FindOrOpen(identifier)
        if not layer:
            continue  # Stage.Open says why, for the root; a missing layer adds nothing
        named = "it" if not seen - {identifier} else f"its layer {layer.identifier}"
        for asset, template in _dependencies(pxr, layer):
            if asset.startswith("`"):
                raise InputError(
                    f"{named} names the asset {asset[:80]!r}, a variable expression, which is "
                    "not followed: refused",
                    path=path,
                )
            anchored = pxr.Sdf.ComputeAssetPathRelativeToLayer(layer, asset)
            found = anchored.replace("#", "0") if template else _resolved(pxr, anchored)
            outer = pxr.Ar.SplitPackageRelativePathOuter(found)[0] if found else ""
            if outer and not Path(outer).resolve().is_relative_to(folder):
                raise InputError(
                    f"{named} names the asset {asset[:80]!r}, which leads out of the stage's "
                    f"folder ({folder}): refused (only files inside it are read)",
                    path=path,
                )
            if found and not template:
                pending.append(found)


def _resolved(pxr: SimpleNamespace, anchored: str) -> str:
    """Where pxr's resolver finds an asset ("" where it finds none)."""
    return str(pxr.Ar.GetResolver().Resolve(anchored))


def _dependencies(pxr: SimpleNamespace, layer: Any) -> Iterator[tuple[str, bool]]:
    """The asset paths a layer's composition and value clips name, each with whether it is a
    clip template (``clip.#.usd``: a pattern of files, not one)."""
    for asset in layer.GetCompositionAssetDependencies():
        yield str(asset), False
    clips: list[dict[str, Any]] = []

    def visit(spec_path: Any) -> None:
        spec = layer.GetObjectAtPath(spec_path)
        if isinstance(spec, pxr.Sdf.PrimSpec):
            if spec.HasInfo("clips"):
                clips.extend(dict(clip) for clip in dict(spec.GetInfo("clips")).values())
            clips.append({name: spec.GetInfo(name) for name in _CLIP_FIELDS if spec.HasInfo(name)})

    layer.Traverse(pxr.Sdf.Path.absoluteRootPath, visit)
    for clip in clips:
        for key, value in clip.items():
            field = key.removeprefix("clip").lower()
            if field == "assetpaths":
                yield from ((str(item.path), False) for item in value)
            elif field == "manifestassetpath":
                yield str(value.path), False
            elif field == "templateassetpath":
                yield str(value), True


def listing(paths: list[str]) -> str:
    """Prim paths or object names for a message: the first few, and how many more."""
    if not paths:
        return "none"
    shown = ", ".join(paths[:_LISTED])
    return shown + (f" and {len(paths) - _LISTED} more" if len(paths) > _LISTED else "")


def _chosen_mesh(pxr: SimpleNamespace, stage: Any, wanted: str | None, path: Path) -> Any:
    """The Mesh prim to read: the one ``wanted`` names, or the only (animated) one."""
    meshes = [prim for prim in stage.Traverse() if prim.IsA(pxr.UsdGeom.Mesh)]
    names = [str(prim.GetPath()) for prim in meshes]
    if wanted is not None:
        valid, _ = pxr.Sdf.Path.IsValidPathString(wanted)
        prim_path = pxr.Sdf.Path(wanted) if valid else None
        if prim_path is None or not (prim_path.IsAbsolutePath() and prim_path.IsPrimPath()):
            raise InputError(
                f"--prim {wanted!r} is not the absolute path of a prim (such as /Root/mesh); "
                f"the meshes are: {listing(names)}",
                path=path,
            )
        prim = stage.GetPrimAtPath(prim_path)
        if not prim:
            raise InputError(
                f"there is no prim {wanted}; the meshes are: {listing(names)}", path=path
            )
        if not prim.IsA(pxr.UsdGeom.Mesh):
            kind = prim.GetTypeName() or "typeless"
            raise InputError(
                f"prim {wanted} is a {kind} prim, not a Mesh; the meshes are: {listing(names)}",
                path=path,
            )
        return prim
    animated = [
        prim for prim in meshes if pxr.UsdGeom.Mesh(prim).GetPointsAttr().GetNumTimeSamples() > 1
    ]
    candidates = animated or meshes
    if len(candidates) == 1:
        return candidates[0]
    if not candidates:
        raise InputError("holds no Mesh prim (UsdGeomMesh)", path=path)
    which = "meshes with animated points" if animated else "meshes"
    raise InputError(
        f"holds {len(candidates)} {which}: {listing([str(p.GetPath()) for p in candidates])}; "
        "choose one with --prim PATH",
        path=path,
    )


def _points(value: Any, where: str, label: str, path: Path, frame: int) -> np.ndarray:
    """One frame's points as a finite (K, 3) array."""
    if value is None:
        raise InputError(
            f"{where}: no points at {label} (blocked or unset)", path=path, frame=frame
        )
    positions = np.asarray(value)
    if positions.ndim != 2 or positions.shape[1] != 3 or positions.dtype.kind != "f":
        raise InputError(
            f"{where}: points at {label} are not 3D points (dtype {positions.dtype}, shape "
            f"{positions.shape})",
            path=path,
            frame=frame,
        )
    if len(positions) == 0:
        raise InputError(f"{where}: no points at {label}", path=path, frame=frame)
    bad = ~np.isfinite(positions)
    if bad.any():
        vertex = int(np.argwhere(bad)[0][0])
        raise InputError(
            f"{where}: vertex {vertex} has a non-finite coordinate at {label}",
            path=path,
            frame=frame,
        )
    return positions


def _faces(
    pxr: SimpleNamespace,
    mesh: Any,
    frame_times: list[Any],
    times: list[float],
    vertex_count: int,
    where: str,
    path: Path,
) -> np.ndarray:
    """The faces of frame 0, checked to stay the same in every frame, counter-clockwise."""
    counts, indices = mesh.GetFaceVertexCountsAttr(), mesh.GetFaceVertexIndicesAttr()

    def topology(time: Any) -> tuple[np.ndarray, np.ndarray]:
        found, listed = counts.Get(time), indices.Get(time)
        if (found is None) != (listed is None):
            missing = "faceVertexCounts" if found is None else "faceVertexIndices"
            raise InputError(f"{where}: has faces but no {missing}", path=path)
        if found is None:
            return np.zeros(0, np.int32), np.zeros(0, np.int32)
        return np.asarray(found), np.asarray(listed)

    varying = counts.ValueMightBeTimeVarying() or indices.ValueMightBeTimeVarying()
    first, frame = first_change(lambda n: topology(frame_times[n]), len(frame_times), varying)
    if frame is not None:
        raise InputError(
            f"{where}: the faces change at time code {times[frame]} (faceVertexCounts or "
            "faceVertexIndices differ from frame 0's); a sequence keeps one set of faces",
            path=path,
            frame=frame,
        )
    try:
        faces = faces_from_polygons(first[0], first[1], vertex_count)
    except InputError as error:
        raise InputError(f"{where}: {error.reason}", path=path) from None
    if mesh.GetOrientationAttr().Get() == pxr.UsdGeom.Tokens.leftHanded:
        faces = reverse_winding(faces)
    return faces


def prim_name(stem: str) -> str:
    """A name for the written prim or object, from a file name's stem: letters, digits and
    underscores, not starting with a digit; "mesh" if nothing is left."""
    name = re.sub(r"[^A-Za-z0-9_]", "_", stem)
    if not name.strip("_"):
        return "mesh"
    return "_" + name if name[0].isdigit() else name


def write_usd(seq: MeshSequence, path: Path, options: WriteOptions) -> None:
    """Write the sequence as a USD stage (see the module docstring), atomically."""
    pxr = _pxr("writing USD files")
    positions = float32_vertices(seq, path)  # an infinity is refused, not written
    with _quiet(pxr):
        stage = _stage(pxr, seq, positions, prim_name(path.stem))
        # ".usd" may hold either encoding (USD_DEFAULT_FILE_FORMAT picks one): ask for crate
        arguments = {"format": "usdc"} if path.suffix.lower() == ".usd" else {}
        with atomic_path(path, overwrite=options.overwrite) as temporary:
            try:
                written = stage.GetRootLayer().Export(str(temporary), "", arguments)
            except _errors(pxr) as error:
                raise OSError(f"{path}: USD could not write it: {_tf_message(error)}") from None
            if not written:
                raise OSError(f"{path}: USD could not write it")


def _stage(pxr: SimpleNamespace, seq: MeshSequence, vertices: np.ndarray, name: str) -> Any:
    """An in-memory stage holding the sequence (its float32 ``vertices``) as a time-sampled
    Mesh under /Root."""
    Usd, UsdGeom, Vt = pxr.Usd, pxr.UsdGeom, pxr.Vt
    stage = Usd.Stage.CreateInMemory()
    axis = UsdGeom.Tokens.z if seq.up_axis == "Z" else UsdGeom.Tokens.y
    UsdGeom.SetStageUpAxis(stage, axis)
    unit = seq.meters_per_unit or UsdGeom.LinearUnits.centimeters  # USD's fallback, 0.01
    UsdGeom.SetStageMetersPerUnit(stage, unit)
    root = UsdGeom.Xform.Define(stage, ROOT)
    stage.SetDefaultPrim(root.GetPrim())
    mesh = UsdGeom.Mesh.Define(stage, f"{ROOT}/{name}")
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    counts, indices = polygons_from_faces(seq.faces)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    points, extent = mesh.CreatePointsAttr(), mesh.CreateExtentAttr()
    codes = seq.codes()
    for frame, code in enumerate(codes.tolist()):
        positions = vertices[frame]
        time = Usd.TimeCode(code)
        points.Set(Vt.Vec3fArray.FromNumpy(positions), time)
        bounds = np.stack([positions.min(axis=0), positions.max(axis=0)])
        extent.Set(Vt.Vec3fArray.FromNumpy(bounds), time)
    write_attached(pxr, mesh, seq, vertices, codes.tolist())
    rate = seq.frame_rate or DEFAULT_FRAME_RATE
    stage.SetTimeCodesPerSecond(rate)
    stage.SetFramesPerSecond(rate)
    stage.SetStartTimeCode(float(codes[0]))
    stage.SetEndTimeCode(float(codes[-1]))
    return stage
