"""The Blender add-on ``tuckercodec_blender``: File > Import and File > Export of ``.tkc`` files.

*Import* (``bpy.ops.import_scene.tkc``) makes a mesh object with the file's faces and vertex
order, sets the scene's frame range and rate from the file, and plays it by decoding the frame
asked for when the frame changes (a ``frame_change_pre`` handler, one open
:class:`~tuckercodec.Decoder` per object: random access, nothing decoded up front), in the
viewport and in renders. Baked instead, the file is decoded once into a ``.pc2`` point cache
read by a Mesh Cache modifier, which any Blender plays without this add-on (at most
:data:`~tuckercodec.blender.meshes.BAKE_FRAMES` scene frames unless asked for more).

*Playback* opens only the files the user asked for in this session: the one an import opened,
or the path an object carries once the user runs *Enable .tkc Playback*
(``bpy.ops.object.tkc_enable_playback``, in the Object menu). A path saved in a ``.blend`` is
not opened when the file is loaded or its frames change: a ``.blend`` from elsewhere could name
any file, and decoding it costs time and memory. A file that fails is not opened again, frame
after frame, until the user asks again. Inside Blender the decoder's limits are
:data:`~tuckercodec.blender.meshes.BLENDER_LIMITS`.

*Layers*: an import gives the mesh the file's UV maps, colour and other attributes, custom
normals and material slots (its ``materialBind`` face sets), and sets its animated fields as
attributes at every frame it shows; an export keeps the same (:mod:`.mesh_layers`), an
attribute that changes over the frames becoming a field, and names what it cannot keep (edge
attributes, strings, matrices). Faces are imported smooth unless the file says which are flat.

*Export* (``bpy.ops.export_scene.tkc``) encodes the active object's evaluated mesh (armature,
shape keys, modifiers, simulations: whatever Blender evaluates) over the scene's frame range, in
object space, and reports the error and size reached; a change of topology is refused.

This module runs only inside Blender (it imports ``bpy``); the array work it needs is in
:mod:`tuckercodec.blender.meshes`, tested without Blender.
"""
# Blender reads an operator's properties from its class annotations, evaluated: no
# ``from __future__ import annotations`` here, and the annotations are calls, not types.
# mypy: disable-error-code="valid-type"

from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

import bpy
import numpy as np
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from ..decoder import Decoder
from ..encoder.options import DEFAULT_TARGET_KG
from ..errors import TuckerCodecError
from ..io.common.polygons import faces_from_polygons
from ..system.atomic import write_atomic
from .layers import may_animate
from .mesh_layers import put_fields, put_layers, read_layers, read_values
from .meshes import (
    BAKE_FRAMES,
    BLENDER_LIMITS,
    MAX_FRAME,
    ExportFrames,
    bake_pc2,
    bake_span,
    file_frame,
    loop_arrays,
    placement,
    scene_range,
    scene_rate,
)

#: The custom properties an imported object carries: the file it plays, the scene frame of the
#: file's frame 0, and whether it was baked to a point cache (then it is not played here).
PATH_PROPERTY = "tkc_path"
FIRST_FRAME_PROPERTY = "tkc_first_frame"
#: The unit and up axis of an imported file (format 1.4), which its object's space keeps.
UNIT_PROPERTY = "tkc_meters_per_unit"
AXIS_PROPERTY = "tkc_up_axis"
BAKED_PROPERTY = "tkc_baked"

#: Open decoders, by object (its session id): (absolute path, decoder, frame shown).
_OPEN: dict[int, tuple[str, Decoder, int | None]] = {}
#: The file each object may play, by session id: what this session's import opened, or what
#: the user enabled (:class:`EnablePlayback`). Any other path an object carries is not opened.
_ALLOWED: dict[int, str] = {}
#: Objects whose file failed, by session id, with the message printed: not tried again until
#: the user asks (an import, :class:`EnablePlayback`).
_FAILED: dict[int, str] = {}
#: Objects whose path, not enabled, was already named once (printed once, not every frame).
_WAITING: set[int] = set()

#: The object types whose evaluated geometry is a mesh (``to_mesh``): what Export takes.
GEOMETRY_TYPES = frozenset({"MESH", "CURVE", "SURFACE", "META", "FONT"})

_Handler = TypeVar("_Handler", bound=Callable[..., None])


def naming(path: Path, error: Exception) -> str:
    """An error's message naming the file at fault once (the decoder's errors name it)."""
    message = str(error)
    return message if str(path) in message else f"{path}: {message}"


# ------------------------------------------------------------------------------------------
# playback


def _played(obj: Any) -> bool:
    return bool(obj.type == "MESH" and PATH_PROPERTY in obj and not obj.get(BAKED_PROPERTY))


def _file(obj: Any) -> str:
    """The absolute path of the file ``obj`` carries (``ValueError`` if it carries no text)."""
    stored = obj.get(PATH_PROPERTY)
    if not isinstance(stored, str) or not stored:
        raise ValueError(f"object {obj.name!r}: its {PATH_PROPERTY} is not a file's path")
    return str(bpy.path.abspath(stored))


def allow(obj: Any) -> str:
    """Let ``obj`` play the file it carries (the user asked): its failure forgotten, so that
    the next frame opens it again. Returns the file's absolute path."""
    path = _file(obj)
    key = obj.session_uid
    _ALLOWED[key] = path
    _FAILED.pop(key, None)
    _WAITING.discard(key)
    return path


def show_frame(obj: Any, scene_frame: int) -> int:
    """Put the file's frame for ``scene_frame`` in ``obj``'s mesh; returns the file's frame.
    The object's decoder is opened at its first frame and kept; a frame already shown is not
    decoded again. Only a file the user allowed (:func:`allow`) is opened: another is a
    ``PermissionError``. Raises what the decoder raises, and ``ValueError`` when the mesh no
    longer has the file's vertex count."""
    path = _file(obj)
    key = obj.session_uid
    if _ALLOWED.get(key) != path:
        raise PermissionError(
            f"object {obj.name!r} carries {path}, which was not opened in this session: "
            "select it and run Object > Enable .tkc Playback to play it"
        )
    cached = _OPEN.get(key)
    if cached is None or cached[0] != path:
        cached = (path, Decoder(path, limits=BLENDER_LIMITS), None)
    decoder = cached[1]
    first = int(obj.get(FIRST_FRAME_PROPERTY, 1))
    frame = file_frame(scene_frame, first, decoder.frame_count, decoder.info.time_codes)
    mesh = obj.data
    if len(mesh.vertices) != decoder.info.vertices:
        raise ValueError(
            f"object {obj.name!r} has {len(mesh.vertices)} vertices, its file {path} "
            f"{decoder.info.vertices}: the mesh was edited, so it is not played"
        )
    if cached[2] != frame:
        positions = decoder.frame(frame).astype(np.float32)
        mesh.vertices.foreach_set("co", positions.reshape(-1))
        if decoder.field_names:  # the animated attributes follow the positions
            put_fields(mesh, decoder.fields([frame]))
        mesh.update()
    _OPEN[key] = (path, decoder, frame)
    return frame


def _persistent(handler: _Handler) -> _Handler:
    """``bpy.app.handlers.persistent``, typed: the handler stays when another .blend loads."""
    return cast(_Handler, bpy.app.handlers.persistent(handler))


def _forget() -> None:
    _OPEN.clear()
    _ALLOWED.clear()
    _FAILED.clear()
    _WAITING.clear()


@_persistent
def _on_frame_change(scene: Any, depsgraph: Any = None) -> None:
    """Before each frame is evaluated (viewport, render, ``frame_set``): every played object
    of the scene whose file the user allowed shows its file's frame. An object whose file is
    not allowed is named once, and not opened; a failure is printed once, and the file is not
    opened again until the user asks."""
    for obj in scene.objects:
        key = obj.session_uid
        if not _played(obj) or key in _FAILED:
            continue
        try:
            if _ALLOWED.get(key) != _file(obj):
                if key not in _WAITING:
                    _WAITING.add(key)
                    print(
                        f"tuckercodec: object {obj.name!r} carries {_file(obj)}, a path saved "
                        "in the .blend: not opened until you ask (select the object, Object > "
                        "Enable .tkc Playback)"
                    )
                continue
            show_frame(obj, scene.frame_current)
        except (TuckerCodecError, OSError, ValueError) as error:
            message = f"tuckercodec: object {obj.name!r}, frame {scene.frame_current}: {error}"
            _FAILED[key] = message
            _OPEN.pop(key, None)
            print(f"{message} (not tried again until you run Object > Enable .tkc Playback)")


@_persistent
def _on_load(*_: Any) -> None:
    """A new .blend: close the decoders of the last one, and forget what the user allowed: the
    paths the new file's objects carry are not opened until the user asks."""
    _forget()


class EnablePlayback(bpy.types.Operator):
    """Play the .tkc files that the selected objects (or every object of the scene) carry, as
    saved in the .blend: they are opened now, and again after a failure"""

    bl_idname = "object.tkc_enable_playback"
    bl_label = "Enable .tkc Playback"
    bl_options = {"REGISTER", "UNDO"}  # noqa: RUF012 - Blender reads a set here

    all_objects: BoolProperty(
        name="All Objects",
        default=False,
        description="Every object of the scene that carries a .tkc file, not the selected ones",
    )

    def execute(self, context: Any) -> set[str]:
        chosen = context.scene.objects if self.all_objects else context.selected_objects
        played = [obj for obj in chosen if _played(obj)]
        if not played:
            self.report({"ERROR"}, "no object that plays a .tkc file (select one)")
            return {"CANCELLED"}
        failed = []
        for obj in played:
            try:
                path = allow(obj)
                show_frame(obj, context.scene.frame_current)
            except (TuckerCodecError, OSError, ValueError) as error:
                _FAILED[obj.session_uid] = str(error)
                _OPEN.pop(obj.session_uid, None)
                failed.append(f"object {obj.name!r}: {error}")
                continue
            self.report({"INFO"}, f"object {obj.name!r} plays {path}")
        if failed:
            self.report({"ERROR"}, "; ".join(failed))
            return {"CANCELLED"} if len(failed) == len(played) else {"FINISHED"}
        return {"FINISHED"}


# ------------------------------------------------------------------------------------------
# import


def _mesh_of(name: str, positions: np.ndarray, faces: np.ndarray) -> Any:
    """A new mesh of ``positions`` and the face table ``faces``, in their order (loops are
    the faces' corners, face by face), built from arrays: ``Mesh.from_pydata`` turns every
    coordinate and corner into a Python object first, minutes and GiBs for a mesh of millions
    of faces, where ``foreach_set`` copies the arrays as they are."""
    starts, corners = loop_arrays(faces)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(positions.shape[0])
    mesh.vertices.foreach_set("co", positions.astype(np.float32).ravel())
    mesh.loops.add(corners.size)
    mesh.polygons.add(starts.size)
    mesh.polygons.foreach_set("loop_start", starts)
    mesh.polygons.foreach_set("vertices", corners)
    # the edges are the faces' sides, found by Blender (as from_pydata asks for them)
    mesh.update(calc_edges=starts.size > 0)
    return mesh


def _new_object(context: Any, name: str, decoder: Decoder) -> tuple[Any, list[str]]:
    """A mesh object with the file's vertex order and faces (in the file's order: Blender's
    loops are the file's corners), its attributes, face sets and frame 0 of its fields
    (:func:`~.mesh_layers.put_layers`), showing frame 0, linked into the active collection,
    selected and active; and the notes on what was not imported as it is."""
    mesh = _mesh_of(name, decoder.frame(0), decoder.faces)
    notes = put_layers(mesh, decoder.attributes, decoder.face_sets, decoder.faces)
    if decoder.field_names:
        notes += put_fields(mesh, decoder.fields([0]))
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    context.collection.objects.link(obj)
    for other in context.view_layer.objects:
        other.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj, notes


def _stored_path(source: Path) -> str:
    """The path an object keeps: relative to the saved .blend (``//...``, so that the two move
    together), else absolute."""
    absolute = str(source.resolve())
    if not bpy.data.filepath:
        return absolute
    try:
        return str(bpy.path.relpath(absolute))
    except ValueError:  # another drive than the .blend's, on Windows
        return absolute


def _cache_path(source: Path) -> Path:
    """Where a bake writes: beside the .blend (beside the ``.tkc`` while it is unsaved)."""
    folder = Path(bpy.path.abspath("//")) if bpy.data.filepath else source.parent
    return folder / f"{source.stem}.pc2"


def _bake_pc2(obj: Any, decoder: Decoder, cache: Path, first: int, options: Any) -> None:
    """Decode the file into the ``.pc2`` ``cache`` (:func:`~.meshes.bake_pc2`) and play it with
    a Mesh Cache modifier instead of the handler."""
    bake_pc2(decoder, cache, first, overwrite=options.overwrite, max_frames=options.max_bake_frames)
    modifier = obj.modifiers.new("tuckercodec point cache", "MESH_CACHE")
    modifier.cache_format = "PC2"
    modifier.filepath = str(cache)
    modifier.frame_start = first
    obj[BAKED_PROPERTY] = True


class ImportTKC(bpy.types.Operator, ImportHelper):
    """Open a tuckercodec file (.tkc) as an animated mesh"""

    bl_idname = "import_scene.tkc"
    bl_label = "Import tuckercodec (.tkc)"
    bl_options = {"REGISTER", "UNDO", "PRESET"}  # noqa: RUF012 - Blender reads a set here

    filename_ext = ".tkc"
    filter_glob: StringProperty(default="*.tkc", options={"HIDDEN"})
    first_frame: IntProperty(
        name="First Frame",
        default=1,
        min=-MAX_FRAME,
        max=MAX_FRAME,
        description="The scene frame that shows the file's frame 0",
    )
    use_time_codes: BoolProperty(
        name="Use File Time Codes",
        default=True,
        description=(
            "Where the file has time codes (format 1.4), play each frame at its own: frame 0 "
            "at its code (1001 for a film cache) instead of at First Frame, and a missing "
            "sample holds the frame before"
        ),
    )
    convert_axes: BoolProperty(
        name="Convert Unit and Up Axis",
        default=True,
        description=(
            "Where the file records them, scale the object from the file's unit into the "
            "scene's and turn a Y-up file to Blender's Z up"
        ),
    )
    set_scene: BoolProperty(
        name="Set Scene Frames",
        default=True,
        description="Set the scene's frame range and frame rate to the file's",
    )
    bake: BoolProperty(
        name="Bake to Point Cache",
        default=False,
        description=(
            "Decode every frame into a .pc2 beside the .blend, played by a Mesh Cache modifier: "
            "plays without this add-on, but the cache is as large as the uncompressed frames"
        ),
    )
    overwrite: BoolProperty(
        name="Overwrite Cache", default=False, description="Replace a .pc2 that exists"
    )
    max_bake_frames: IntProperty(
        name="Max Bake Frames",
        default=BAKE_FRAMES,
        min=1,
        max=2 * MAX_FRAME + 1,
        description=(
            "The most scene frames a bake writes (a file of a few frames may span many, each "
            "a whole frame of the cache): a file that spans more is refused, saying how many"
        ),
    )

    def execute(self, context: Any) -> set[str]:
        source = Path(self.filepath)
        obj = None
        try:
            decoder = Decoder(source, limits=BLENDER_LIMITS)
            info = decoder.info
            # everything checked before anything is made: no half-imported object
            first_code = float(self.first_frame)
            if self.use_time_codes and info.time_codes is not None:
                first_code = info.time_codes[0]
            first, last = scene_range(first_code, info.frames, info.time_codes)
            cache = _cache_path(source) if self.bake else None
            if cache is not None:
                bake_span(decoder, first, self.max_bake_frames)
                if cache.exists() and not self.overwrite:
                    raise FileExistsError(f"{cache} already exists (set Overwrite Cache)")
            obj, notes = _new_object(context, source.stem, decoder)
            obj[PATH_PROPERTY] = _stored_path(source)
            obj[FIRST_FRAME_PROPERTY] = first
            # the object's own space is the file's: an export of it says so again
            if info.meters_per_unit is not None:
                obj[UNIT_PROPERTY] = info.meters_per_unit
            if info.up_axis is not None:
                obj[AXIS_PROPERTY] = info.up_axis
            if self.convert_axes:
                scale_length = context.scene.unit_settings.scale_length
                rotation, scale = placement(info.meters_per_unit, info.up_axis, scale_length)
                obj.rotation_euler[0] = rotation
                obj.scale = (scale, scale, scale)
            if self.set_scene:
                scene = context.scene
                scene.frame_start, scene.frame_end = first, last
                if info.frame_rate is not None:  # else the scene keeps its own rate
                    scene.render.fps, scene.render.fps_base = scene_rate(info.frame_rate)
            how = "decoded on demand"
            if cache is not None:
                _bake_pc2(obj, decoder, cache, first, self)
                how = f"baked to {cache}"
            else:
                allow(obj)  # the user opened this file: the object plays it
                show_frame(obj, context.scene.frame_current)
        except (TuckerCodecError, OSError, ValueError) as error:
            if obj is not None:  # a bake that failed half-way: no object left behind
                mesh = obj.data
                bpy.data.objects.remove(obj)
                bpy.data.meshes.remove(mesh)
            self.report({"ERROR"}, naming(source, error))
            return {"CANCELLED"}
        rate = "unknown rate" if info.frame_rate is None else f"{info.frame_rate:g} fps"
        for note in notes:
            self.report({"WARNING"}, f"{source.name}: {note}")
        self.report(
            {"INFO"},
            f"Imported {source.name}: {info.frames} frames of {info.vertices} vertices, "
            f"{len(decoder.faces)} faces, {rate}, {how}",
        )
        return {"FINISHED"}


# ------------------------------------------------------------------------------------------
# export


def _mesh_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    """A Blender mesh's vertex coordinates (K x 3, float32) and faces (M, n) padded with -1."""
    coordinates = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", coordinates)
    loops = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loops)
    totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    # Blender keeps each polygon's loops together, in polygon order (its face offsets): the
    # corner counts and flat indices USD and Alembic give, read by the same function
    return coordinates.reshape(-1, 3), faces_from_polygons(totals, loops, len(mesh.vertices))


def gather_frames(context: Any, obj: Any, layers: bool = True) -> ExportFrames:
    """``obj``'s evaluated mesh at every frame of the scene's range, the scene's current frame
    restored afterwards; with ``layers``, the first frame's attributes, custom normals and
    material slots (:func:`~.mesh_layers.read_layers`) and, at every frame, the values of the
    attributes that may be animated. Raises ``InputError`` naming the frame where the topology
    changes."""
    scene = context.scene
    frames = ExportFrames(obj.name)
    current = scene.frame_current
    try:
        for number in range(scene.frame_start, scene.frame_end + 1):
            scene.frame_set(number)
            evaluated = obj.evaluated_get(context.evaluated_depsgraph_get())
            mesh = evaluated.to_mesh()
            try:
                frames.add(number, *_mesh_arrays(mesh))
                if layers:
                    _gather_layers(frames, evaluated, mesh)
            finally:
                evaluated.to_mesh_clear()
    finally:
        scene.frame_set(current)
    return frames


def _gather_layers(frames: ExportFrames, evaluated: Any, mesh: Any) -> None:
    """At the first frame, the mesh's layers; at each, the values of those that may change (an
    attribute gone or resized at a frame stays static, frame 0's values)."""
    if len(frames.frames) == 1:
        slots = [slot.material.name if slot.material else None for slot in evaluated.material_slots]
        kept = read_layers(mesh, slots)
        frames.attributes, frames.face_sets, frames.dropped = kept
        frames.animated = {a.name: [] for a in kept.attributes if may_animate(a)}
    for name, gathered in list(frames.animated.items()):
        layer = mesh.attributes.get(name)
        values = None if layer is None else read_values(layer)
        if values is None or (
            gathered and (values.shape, values.dtype) != (gathered[0].shape, gathered[0].dtype)
        ):
            del frames.animated[name]
        else:
            gathered.append(values)


class ExportTKC(bpy.types.Operator, ExportHelper):
    """Encode the active object's animation over the scene's frame range into a .tkc"""

    bl_idname = "export_scene.tkc"
    bl_label = "Export tuckercodec (.tkc)"
    bl_options = {"REGISTER", "PRESET"}  # noqa: RUF012 - Blender reads a set here

    filename_ext = ".tkc"
    filter_glob: StringProperty(default="*.tkc", options={"HIDDEN"})
    mode: EnumProperty(
        name="Target",
        items=(
            ("KG", "KG Error", "The largest KG error (percent) the decoded animation may have"),
            ("BPFV", "Size", "The largest file size, in bits per frame per vertex"),
            ("RANKS", "Ranks", "Fixed ranks (i, k) of the decomposition"),
        ),
        default="KG",
    )
    kg: FloatProperty(name="KG Error (%)", default=DEFAULT_TARGET_KG, min=1e-6, precision=4)
    bpfv: FloatProperty(name="Bits per Frame per Vertex", default=2.0, min=1e-3)
    rank_i: IntProperty(name="Rank i (vertices)", default=16, min=1)
    rank_k: IntProperty(name="Rank k (frames)", default=8, min=1)
    max_error: FloatProperty(
        name="Max Vertex Error",
        default=0.0,
        min=0.0,
        description=(
            "Also bound every decoded vertex's distance from the input, in object units "
            "(0: no bound; not with a size target)"
        ),
    )
    overwrite: BoolProperty(
        name="Overwrite",
        default=False,
        description="Replace a file that exists (the file browser asks first)",
    )
    keep_layers: BoolProperty(
        name="UVs, Attributes and Materials",
        default=True,
        description=(
            "Keep the UV maps, colour and other attributes (point, corner and face), custom "
            "normals and material slots; attributes that change over the frames become "
            "animated fields"
        ),
    )

    def invoke(self, context: Any, event: Any) -> set[str]:
        self.overwrite = True  # the file browser shows an existing name in red and asks
        result: set[str] = ExportHelper.invoke(self, context, event)
        return result

    def _options(self) -> Any:
        from ..encoder import EncodeOptions

        bound = self.max_error if self.max_error > 0 else None
        if self.mode == "BPFV":
            return EncodeOptions(target_bpfv=self.bpfv, max_error=bound)
        if self.mode == "RANKS":
            return EncodeOptions(ranks=(self.rank_i, self.rank_k), max_error=bound)
        return EncodeOptions(target_kg=self.kg, max_error=bound)

    def execute(self, context: Any) -> set[str]:
        from ..encoder import encode_with_report

        obj = context.active_object
        target = Path(self.filepath)
        if obj is None or obj.type not in GEOMETRY_TYPES:
            what = "no active object" if obj is None else f"object {obj.name!r} ({obj.type})"
            self.report({"ERROR"}, f"{what}: select a mesh, curve or text object to export")
            return {"CANCELLED"}
        try:
            options = self._options()
            if target.exists() and not self.overwrite:
                raise FileExistsError("already exists (set overwrite to replace it)")
            scene = context.scene
            render, units = scene.render, scene.unit_settings
            # the object's space: an imported file's (its unit and axis, kept on the object),
            # else the scene's (Z up, its unit scale in metres unless it has no unit system)
            unit = None if units.system == "NONE" else units.scale_length
            frames = gather_frames(context, obj, self.keep_layers)
            sequence = frames.sequence(
                render.fps / render.fps_base,
                first_frame=scene.frame_start,  # the time codes: the scene's frame numbers
                meters_per_unit=obj.get(UNIT_PROPERTY, unit),
                up_axis=obj.get(AXIS_PROPERTY, "Z"),
            )
            result = encode_with_report(sequence, options=options)
            write_atomic(target, result.data, overwrite=self.overwrite)
        except (TuckerCodecError, OSError, ValueError) as error:
            self.report({"ERROR"}, naming(target, error))
            return {"CANCELLED"}
        for dropped in frames.dropped:
            self.report({"WARNING"}, f"{target.name}: not kept: {dropped}")
        report = result.report
        worst = "" if report.max_distance is None else f", worst vertex {report.max_distance:.6g}"
        self.report(
            {"INFO"},
            f"Exported {obj.name!r} to {target.name}: {report.frames} frames of "
            f"{report.vertices} vertices, KG error {report.kg:.6g} %{worst}, "
            f"{report.total_bytes} bytes ({report.bpfv:.3f} bpfv, ranks {report.ranks})",
        )
        return {"FINISHED"}


# ------------------------------------------------------------------------------------------
# registration


def _import_menu(self: Any, context: Any) -> None:
    self.layout.operator(ImportTKC.bl_idname, text="tuckercodec (.tkc)")


def _export_menu(self: Any, context: Any) -> None:
    self.layout.operator(ExportTKC.bl_idname, text="tuckercodec (.tkc)")


def _object_menu(self: Any, context: Any) -> None:
    self.layout.operator(EnablePlayback.bl_idname)


_CLASSES = (ImportTKC, ExportTKC, EnablePlayback)


def register() -> None:
    """Register the operators, their menu entries and the playback handlers."""
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(_import_menu)
    bpy.types.TOPBAR_MT_file_export.append(_export_menu)
    bpy.types.VIEW3D_MT_object.append(_object_menu)
    handlers = bpy.app.handlers
    for handler_list, handler in (
        (handlers.frame_change_pre, _on_frame_change),
        (handlers.load_post, _on_load),
    ):
        if handler not in handler_list:
            handler_list.append(handler)


def unregister() -> None:
    """Undo :func:`register` and close every decoder."""
    handlers = bpy.app.handlers
    for handler_list, handler in (
        (handlers.frame_change_pre, _on_frame_change),
        (handlers.load_post, _on_load),
    ):
        if handler in handler_list:
            handler_list.remove(handler)
    bpy.types.VIEW3D_MT_object.remove(_object_menu)
    bpy.types.TOPBAR_MT_file_export.remove(_export_menu)
    bpy.types.TOPBAR_MT_file_import.remove(_import_menu)
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
    _forget()


__all__ = [
    "EnablePlayback",
    "ExportTKC",
    "ImportTKC",
    "allow",
    "gather_frames",
    "register",
    "show_frame",
    "unregister",
]
