"""Headless Blender renders a textured mesh before and after a ``.tkc``, for
tests/test_blender_layers.py, in a process of its own::

    python tests/support/blender_render_session.py WORKDIR

WORKDIR/original.npz holds the mesh as it was (``positions`` (K, 3) float32, ``faces``, ``uv``
one float32 UV per corner); WORKDIR/lossless.tkc and WORKDIR/lossy.tkc hold its sequence,
whose frame 0 is that mesh. The session registers the add-on from the checkout (the test sets
PYTHONPATH), gives every object one material (a checker image on its UV map), and renders, one
object at a time at 256 x 256 from one orthographic camera: the original mesh, each file as
the add-on imports it, and the original with its UVs mirrored (what a wrong UV map looks like),
with Workbench (its texture colours, no noise) and Cycles (CPU, 16 samples, a fixed seed). It
writes the images' pixels to WORKDIR/renders.npz (``ENGINE_NAME``: (256, 256, 4) float32) for
the test to compare.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import bpy
import numpy as np

from tuckercodec.blender.addon import register, unregister

SIZE = 256
ENGINES = ("BLENDER_WORKBENCH", "CYCLES")


def checker_material() -> Any:
    """A material whose colour is a checker image (8 x 8 squares) on the mesh's UV map."""
    image = bpy.data.images.new("checker", 512, 512)
    squares = (np.indices((512, 512)) // 64).sum(axis=0) % 2
    pixels = np.ones((512, 512, 4), dtype=np.float32)
    pixels[..., :3] = np.where(squares[..., None] == 1, [0.9, 0.5, 0.1], [0.05, 0.1, 0.6])
    image.pixels.foreach_set(pixels.ravel())
    material = bpy.data.materials.new("checker")
    material.use_nodes = True
    nodes = material.node_tree.nodes
    texture = nodes.new("ShaderNodeTexImage")
    texture.image, texture.interpolation = image, "Closest"
    shader = nodes["Principled BSDF"]
    material.node_tree.links.new(texture.outputs["Color"], shader.inputs["Base Color"])
    nodes.active = texture  # Workbench's texture colour is the active image node's
    return material


def original_object(name: str, data: Any, mirrored: bool) -> Any:
    """The mesh as it was, smooth (as the add-on imports a file without normals)."""
    faces = [row[row >= 0].tolist() for row in data["faces"]]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(data["positions"], [], faces)
    mesh.polygons.foreach_set("use_smooth", np.ones(len(mesh.polygons), dtype=np.bool_))
    uv = data["uv"].copy()
    if mirrored:
        uv[:, 0] = 1.0 - uv[:, 0]
    mesh.uv_layers.new(name="UVMap").uv.foreach_set("vector", uv.ravel())
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.collection.objects.link(obj)
    return obj


def camera_on(obj: Any) -> None:
    """An orthographic camera looking at ``obj`` along its thinnest axis, and a sun."""
    corners = np.array([obj.matrix_world @ v.co for v in obj.data.vertices])
    low, high = corners.min(axis=0), corners.max(axis=0)
    centre, extent = (low + high) / 2, high - low
    thin = int(np.argmin(extent))
    camera_data = bpy.data.cameras.new("camera")
    camera_data.type, camera_data.ortho_scale = "ORTHO", float(extent.max()) * 1.1
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = centre + np.eye(3)[thin] * float(extent.max()) * 2
    target = bpy.data.objects.new("target", None)
    target.location = centre
    bpy.context.collection.objects.link(camera)
    bpy.context.collection.objects.link(target)
    aim = camera.constraints.new("TRACK_TO")
    aim.target, aim.track_axis, aim.up_axis = target, "TRACK_NEGATIVE_Z", "UP_Y"
    bpy.context.scene.camera = camera
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.location = camera.location
    sun.constraints.new("TRACK_TO").target = target
    bpy.context.collection.objects.link(sun)


def render(engine: str, shown: Any, objects: list[Any], work: Path) -> np.ndarray:
    """The image of ``shown`` alone with ``engine``, (SIZE, SIZE, 4) float32."""
    scene = bpy.context.scene
    for obj in objects:
        obj.hide_render = obj is not shown
    scene.render.engine = engine
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.display.shading.color_type = "TEXTURE"
    scene.display.shading.light = "STUDIO"
    scene.cycles.device, scene.cycles.samples, scene.cycles.seed = "CPU", 16, 1
    scene.cycles.use_denoising = False
    path = work / f"render_{engine}_{shown.name}.png"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    pixels = np.empty(SIZE * SIZE * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(SIZE, SIZE, 4)


def session(work: Path) -> None:
    """What the module's docstring says."""
    scene = bpy.context.scene
    scene.frame_start = scene.frame_current = 1
    material = checker_material()
    with np.load(work / "original.npz") as data:
        arrays = dict(data)
    objects = [original_object("original", arrays, False)]
    objects.append(original_object("mirrored", arrays, True))
    for name in ("lossless", "lossy"):
        done = bpy.ops.import_scene.tkc(filepath=str(work / f"{name}.tkc"), set_scene=False)
        assert done == {"FINISHED"}, done
        objects.append(bpy.context.active_object)
    for obj in objects:  # the checker alone: the files' own material slots are left out
        obj.data.materials.clear()
        obj.data.materials.append(material)
    camera_on(objects[0])
    scene.frame_set(1)  # each file's frame 0
    images = {
        f"{engine}_{obj.name}": render(engine, obj, objects, work)
        for engine in ENGINES
        for obj in objects
    }
    np.savez(work / "renders.npz", **images)  # type: ignore[arg-type] # (the names are keys)


def main(work: Path) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    try:
        session(work)
    finally:
        unregister()  # a process that exits with the add-on registered hangs in Blender's exit


if __name__ == "__main__":
    main(Path(sys.argv[1]))
