"""One headless Blender session (the ``bpy`` module) for tests/test_blender_addon.py, run as a
script in a process of its own so that a crash of Blender cannot take pytest with it::

    python tests/support/blender_session.py ADDON.zip FILE.tkc WORKDIR

It installs the add-on's zip as Blender installs an extension from disk, imports FILE.tkc,
reads the evaluated vertices at several scene frames, exports the object back, tries the
refusals (an existing file, a change of topology), imports a baked copy, renders two frames,
refuses files beyond Blender's frames and a bake beyond its limit, saves and reopens the .blend
(whose paths are played only once playback is enabled), and writes what it saw
to WORKDIR/session.npz (arrays) and WORKDIR/session.json (the rest), for the test to judge.
Nothing here compares: the test does, against the Python decoder in its own process.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import bpy
import numpy as np

#: The scene frames read back (the file's frame 0 is at scene frame 1): forward, back, the ends.
FRAMES = (1, 2, 17, 45, 60, 30)
ADDON_MODULE = "bl_ext.user_default.tuckercodec_blender"
#: The exports besides the first (kg 0.5), by file name: a size target, fixed ranks, and a KG
#: target with a bound on every vertex.
EXPORT_MODES: dict[str, dict[str, Any]] = {
    "bpfv.tkc": {"mode": "BPFV", "bpfv": 1.0},
    "ranks.tkc": {"mode": "RANKS", "rank_i": 6, "rank_k": 4},
    "bounded.tkc": {"mode": "KG", "kg": 1.0, "max_error": 0.05},
}


def evaluated_vertices(obj: Any) -> np.ndarray:
    """``obj``'s evaluated vertex coordinates, (K, 3) float32."""
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    values = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", values)
    return values.reshape(-1, 3)


def polygons(mesh: Any) -> np.ndarray:
    """A mesh's faces as (M, 3) vertex indices (the sample is triangles)."""
    loops = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    return loops.reshape(-1, 3)


def install(addon: Path) -> dict[str, Any]:
    """Install and enable the extension; where its tuckercodec was imported from."""
    result = bpy.ops.extensions.package_install_files(
        filepath=str(addon), repo="user_default", enable_on_install=True
    )
    enabled = ADDON_MODULE in bpy.context.preferences.addons
    return {
        "install": sorted(result),
        "enabled": enabled,
        "tuckercodec_file": sys.modules["tuckercodec"].__file__ if enabled else None,
        "extensions_folder": bpy.utils.user_resource("EXTENSIONS"),
    }


def play(tkc: Path, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """Import ``tkc`` and read the evaluated vertices at :data:`FRAMES`."""
    assert bpy.ops.import_scene.tkc(filepath=str(tkc)) == {"FINISHED"}
    obj = bpy.context.active_object
    scene = bpy.context.scene
    arrays["faces"] = polygons(obj.data)
    for frame in FRAMES:
        scene.frame_set(frame)
        arrays[f"frame_{frame}"] = evaluated_vertices(obj)
    return {
        "object": obj.name,
        "frame_range": [scene.frame_start, scene.frame_end],
        "fps": scene.render.fps / scene.render.fps_base,
    }


def render(obj: Any, work: Path, arrays: dict[str, np.ndarray]) -> list[str]:
    """Render scene frames 5 and 6 (Cycles, 8 x 8 pixels, one sample) and keep ``obj``'s
    vertices as the render's own depsgraph evaluated them at each frame; the images written."""
    scene = bpy.context.scene

    def seen(scene: Any, depsgraph: Any) -> None:
        mesh = obj.evaluated_get(depsgraph).data
        values = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", values)
        arrays[f"render_{scene.frame_current}"] = values.reshape(-1, 3)

    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.render.resolution_x = scene.render.resolution_y = 8
    scene.frame_start, scene.frame_end = 5, 6
    scene.render.filepath = str(work / "render_")
    bpy.app.handlers.frame_change_post.append(seen)
    try:
        bpy.ops.render.render(animation=True)
    finally:
        bpy.app.handlers.frame_change_post.remove(seen)
    return sorted(path.name for path in work.glob("render_*.png"))


def reopened(name: str, work: Path, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """Save the .blend with a stranger beside object ``name``: a plane carrying a path it never
    played here (as a crafted .blend would), to WORKDIR/broken.tkc. Open it again (the decoders
    closed, the handler kept), change frames, read ``name`` at scene frame 33 (no file may be
    opened: nobody asked); then enable playback of both and change frames again (the cloth
    plays, the stranger fails once and is not tried again). Every Decoder the add-on makes is
    counted."""
    bpy.ops.mesh.primitive_plane_add()
    stranger = bpy.context.active_object
    stranger.name = "stranger"
    stranger["tkc_path"] = str(work / "broken.tkc")
    blend = str(work / "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    bpy.ops.wm.open_mainfile(filepath=blend)
    addon: Any = sys.modules["tuckercodec.blender.addon"]
    original, opened = addon.Decoder, []

    def counted(source: Any, *args: Any, **kwargs: Any) -> Any:
        opened.append(Path(source).name)
        return original(source, *args, **kwargs)

    addon.Decoder = counted
    scene, seen = bpy.context.scene, dict[str, Any]()
    try:
        for frame in (34, 35, 33):
            scene.frame_set(frame)
        arrays["reopened_33_unasked"] = evaluated_vertices(bpy.data.objects[name])
        seen["opened_unasked"] = list(opened)
        for obj in bpy.context.view_layer.objects:
            obj.select_set(obj.name in (name, "stranger"))
        try:
            seen["enable"] = str(sorted(bpy.ops.object.tkc_enable_playback()))
        except (RuntimeError, AttributeError) as error:  # the stranger's file is refused
            seen["enable"] = str(error)
        scene.frame_set(33)
        arrays["reopened_33"] = evaluated_vertices(bpy.data.objects[name])
        for frame in (34, 35, 36):
            scene.frame_set(frame)
        seen["opened_asked"] = opened[len(seen["opened_unasked"]) :]
    finally:
        addon.Decoder = original
    return seen


def hostile(work: Path) -> dict[str, Any]:
    """Import WORKDIR/far.tkc (a first time code of 2**31) and bake WORKDIR/spread.tkc (24
    time codes over 200,000 scene frames): what each refusal said and the objects each left."""
    seen: dict[str, Any] = {}
    for name, options in (("far", {}), ("spread", {"bake": True})):
        before = len(bpy.data.objects)
        seen[name] = refusal(
            lambda name=name, options=options: bpy.ops.import_scene.tkc(
                filepath=str(work / f"{name}.tkc"), **options
            )
        )
        seen[f"{name}_objects"] = len(bpy.data.objects) - before
    seen["spread_cache"] = (work / "spread.pc2").exists()
    return seen


def many_faces(work: Path) -> dict[str, Any]:
    """Import WORKDIR/many_faces.tkc (2**18 triangles) with tracemalloc tracing Python's
    allocations: the peak of opening the file and decoding its faces and frame 0 as the add-on
    does, then the peak of the import itself, beyond what was held before it."""
    import tracemalloc

    from tuckercodec import Decoder
    from tuckercodec.blender.meshes import BLENDER_LIMITS

    path = work / "many_faces.tkc"
    tracemalloc.start()
    try:
        decoder = Decoder(path, limits=BLENDER_LIMITS)
        decoder.faces, decoder.frame(0)
        decoding = tracemalloc.get_traced_memory()[1]
        del decoder
        tracemalloc.reset_peak()
        held = tracemalloc.get_traced_memory()[0]
        assert bpy.ops.import_scene.tkc(filepath=str(path)) == {"FINISHED"}
        importing = tracemalloc.get_traced_memory()[1] - held
    finally:
        tracemalloc.stop()
    return {
        "many_faces": len(bpy.context.active_object.data.polygons),
        "many_faces_decoding_bytes": decoding,
        "many_faces_import_bytes": importing,
    }


def refusal(call: Any) -> str | None:
    """The message of the error ``call`` reports (Blender raises it as RuntimeError)."""
    try:
        call()
    except RuntimeError as error:
        return str(error)
    return None


def changing_topology(work: Path) -> str | None:
    """Export a cube whose Decimate ratio jumps from 1 to 0.5 at frame 4: the refusal."""
    bpy.ops.mesh.primitive_uv_sphere_add()
    sphere = bpy.context.active_object
    decimate = sphere.modifiers.new("decimate", "DECIMATE")
    for frame, ratio in ((1, 1.0), (4, 0.5)):
        decimate.ratio = ratio
        decimate.keyframe_insert("ratio", frame=frame)
    for curve in sphere.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            point.interpolation = "CONSTANT"
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 6
    return refusal(lambda: bpy.ops.export_scene.tkc(filepath=str(work / "sphere.tkc")))


#: The scene frames read of WORKDIR/film.tkc, whose time codes skip 1007 (format 1.4).
FILM_FRAMES = (1001, 1006, 1007, 1008, 1013)


def film(work: Path, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """Import WORKDIR/film.tkc (time codes from 1001 with 1007 missing, centimetres, Y up),
    played and baked: the scene range, the object's placement, the vertices at
    :data:`FILM_FRAMES`; then export it back to WORKDIR/film_export.tkc."""
    assert bpy.ops.import_scene.tkc(filepath=str(work / "film.tkc")) == {"FINISHED"}
    obj, scene = bpy.context.active_object, bpy.context.scene
    seen = {
        "film_range": [scene.frame_start, scene.frame_end],
        "film_rotation": list(obj.rotation_euler),
        "film_scale": list(obj.scale),
    }
    for frame in FILM_FRAMES:
        scene.frame_set(frame)
        arrays[f"film_{frame}"] = evaluated_vertices(obj)
    seen["film_export"] = sorted(
        bpy.ops.export_scene.tkc(filepath=str(work / "film_export.tkc"), kg=0.5)
    )
    obj.hide_viewport = True
    assert bpy.ops.import_scene.tkc(filepath=str(work / "film.tkc"), bake=True) == {"FINISHED"}
    baked = bpy.context.active_object
    for frame in FILM_FRAMES:
        scene.frame_set(frame)
        arrays[f"film_baked_{frame}"] = evaluated_vertices(baked)
    return seen


def main(addon: Path, tkc: Path, work: Path) -> None:
    arrays: dict[str, np.ndarray] = {}
    seen = install(addon)
    seen.update(play(tkc, arrays))
    exported = work / "exported.tkc"
    seen["export"] = sorted(bpy.ops.export_scene.tkc(filepath=str(exported), kg=0.5))
    seen["export_again"] = refusal(lambda: bpy.ops.export_scene.tkc(filepath=str(exported)))
    seen["export_modes"] = [  # the other targets, each to a file of its own
        sorted(bpy.ops.export_scene.tkc(filepath=str(work / name), **options))
        for name, options in EXPORT_MODES.items()
    ]
    seen["bake"] = sorted(bpy.ops.import_scene.tkc(filepath=str(tkc), bake=True))
    baked = bpy.context.active_object
    seen["baked_modifiers"] = [modifier.type for modifier in baked.modifiers]
    bpy.context.scene.frame_set(20)
    arrays["baked_20"] = evaluated_vertices(baked)
    baked.hide_render = True  # the render shows the played object alone
    seen["rendered"] = render(bpy.data.objects[seen["object"]], work, arrays)
    seen["topology"] = changing_topology(work)
    (work / "broken.tkc").write_bytes(b"not a tkc file")
    seen["broken"] = refusal(lambda: bpy.ops.import_scene.tkc(filepath=str(work / "broken.tkc")))
    bpy.ops.object.camera_add()
    seen["camera"] = refusal(lambda: bpy.ops.export_scene.tkc(filepath=str(work / "camera.tkc")))
    seen.update(film(work, arrays))
    seen.update(hostile(work))
    seen.update(many_faces(work))
    seen.update(reopened(seen["object"], work, arrays))
    np.savez(work / "session.npz", **arrays)  # type: ignore[arg-type] # (the names are keys)
    (work / "session.json").write_text(json.dumps(seen, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3]))
