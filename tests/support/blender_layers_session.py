"""One headless Blender session (the ``bpy`` module) for the add-on's UV maps, colours,
attributes, normals and materials, run as a script in a process of its own::

    python tests/support/blender_layers_session.py WORKDIR

with the checkout's ``tuckercodec`` importable (the test sets PYTHONPATH). It registers the
add-on from the checkout, then:

* builds a mesh of its own (a subdivided grid of quads and triangles) with two UV maps, a
  float colour per corner, a byte colour per point, a float per face, an integer per point,
  custom normals and two materials, and exports it to WORKDIR/made.tkc; imports that file
  back;
* imports WORKDIR/vellum.tkc (made by the test: the cloth-vellum sequence with a UV map and
  two material sets) and exports it again to WORKDIR/vellum_again.tkc.

It writes what each mesh held, per loop, point and face, to WORKDIR/layers.npz and the names
to WORKDIR/layers.json: the test compares.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import bpy
import numpy as np

from tuckercodec.blender.addon import register, unregister


def made_mesh() -> Any:
    """A grid of quads, a few of them cut into triangles, with every kind of layer."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=6, y_subdivisions=5, size=2.0)
    obj = bpy.context.active_object
    obj.name = "made"
    mesh = obj.data
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="DESELECT")
    bpy.ops.object.mode_set(mode="OBJECT")
    for polygon in mesh.polygons[:6]:
        polygon.select = True
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.quads_convert_to_tris()
    bpy.ops.object.mode_set(mode="OBJECT")
    loops, points, faces = len(mesh.loops), len(mesh.vertices), len(mesh.polygons)
    generator = np.random.default_rng(7)
    second = mesh.uv_layers.new(name="detail")
    second.uv.foreach_set("vector", generator.random(loops * 2, dtype=np.float32))
    colour = mesh.color_attributes.new("tint", "FLOAT_COLOR", "CORNER")
    colour.data.foreach_set("color", generator.random(loops * 4, dtype=np.float32))
    byte = mesh.color_attributes.new("paint", "BYTE_COLOR", "POINT")
    byte.data.foreach_set("color_srgb", generator.integers(0, 256, points * 4) / 255.0)
    weight = mesh.attributes.new("weight", "FLOAT", "FACE")
    weight.data.foreach_set("value", generator.random(faces, dtype=np.float32))
    label = mesh.attributes.new("label", "INT", "POINT")
    label.data.foreach_set("value", generator.integers(-5, 50, points, dtype=np.int32))
    normals = generator.normal(size=(loops, 3)) * 0.2 + (0.0, 0.0, 1.0)
    mesh.normals_split_custom_set(normals / np.linalg.norm(normals, axis=1, keepdims=True))
    for name in ("cloth_red", "cloth_blue"):
        obj.data.materials.append(bpy.data.materials.get(name) or bpy.data.materials.new(name))
    slots = (np.arange(faces) % 3 == 0).astype(np.int32)
    mesh.polygons.foreach_set("material_index", slots)
    mesh.update()
    return obj


def layers_of(obj: Any, prefix: str, arrays: dict[str, np.ndarray]) -> dict[str, Any]:
    """Everything an object's mesh holds, into ``arrays`` under ``prefix``; the names."""
    mesh = obj.data
    loops = len(mesh.loops)
    for layer in mesh.uv_layers:
        values = np.empty(loops * 2, dtype=np.float32)
        layer.uv.foreach_get("vector", values)
        arrays[f"{prefix}uv_{layer.name}"] = values.reshape(-1, 2)
    for layer in mesh.color_attributes:
        values = np.empty(len(layer.data) * 4, dtype=np.float32)
        layer.data.foreach_get("color", values)
        arrays[f"{prefix}colour_{layer.name}"] = values.reshape(-1, 4)
    for name, prop, dtype in (("weight", "value", np.float32), ("label", "value", np.int32)):
        layer = mesh.attributes.get(name)
        if layer is not None:
            values = np.empty(len(layer.data), dtype=dtype)
            layer.data.foreach_get(prop, values)
            arrays[f"{prefix}attribute_{name}"] = values
    normals = np.empty(loops * 3, dtype=np.float32)
    mesh.corner_normals.foreach_get("vector", normals)
    arrays[f"{prefix}normals"] = normals.reshape(-1, 3)
    slots = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("material_index", slots)
    arrays[f"{prefix}material_index"] = slots
    corners = np.empty(loops, dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    arrays[f"{prefix}corners"] = corners
    totals = np.empty(len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    arrays[f"{prefix}loop_totals"] = totals
    # the edges as sorted pairs, in sorted order: Blender numbers them as it finds them
    edges = np.empty(len(mesh.edges) * 2, dtype=np.int32)
    mesh.edges.foreach_get("vertices", edges)
    pairs = np.sort(edges.reshape(-1, 2), axis=1)
    arrays[f"{prefix}edges"] = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    return {
        "uv_maps": [layer.name for layer in mesh.uv_layers],
        "colours": {layer.name: [layer.data_type, layer.domain] for layer in mesh.color_attributes},
        "materials": [m.name if m else None for m in mesh.materials],
        "custom_normals": mesh.has_custom_normals,
    }


def main(work: Path) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    register()
    try:
        session(work)
    finally:
        unregister()  # a process that exits with the add-on registered hangs in Blender's exit


def session(work: Path) -> None:
    """What the module's docstring says, in order."""
    arrays: dict[str, np.ndarray] = {}
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 2
    seen: dict[str, Any] = {"made": layers_of(made_mesh(), "made_", arrays)}
    done = bpy.ops.export_scene.tkc(filepath=str(work / "made.tkc"), kg=0.5)
    seen["made_export"] = sorted(done)
    bpy.ops.import_scene.tkc(filepath=str(work / "made.tkc"), set_scene=False)
    seen["made_again"] = layers_of(bpy.context.active_object, "made_again_", arrays)
    if (work / "vellum.tkc").exists():  # the test made it from ../shared/data
        bpy.ops.import_scene.tkc(filepath=str(work / "vellum.tkc"), set_scene=True)
        vellum = bpy.context.active_object
        seen["vellum"] = layers_of(vellum, "vellum_", arrays)
        done = bpy.ops.export_scene.tkc(filepath=str(work / "vellum_again.tkc"), kg=0.5)
        seen["vellum_export"] = sorted(done)
    np.savez(work / "layers.npz", **arrays)  # type: ignore[arg-type] # (the names are keys)
    (work / "layers.json").write_text(json.dumps(seen, indent=2))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
