"""The Blender add-on ``tuckercodec_blender``: open a ``.tkc`` in Blender and export one.

* :mod:`.addon` is the add-on itself (operators, menus, playback); it imports ``bpy`` and runs
  only inside Blender.
* :mod:`.meshes` is what the add-on does to arrays, without ``bpy``: faces as Blender's polygons
  and back, the frame a scene frame shows, the topology check of an export.
* :mod:`.layers` is the translation, as arrays, between a sequence's attributes, face sets and
  fields and Blender's UV maps, colours, attributes and material slots; :mod:`.mesh_layers`
  puts them into a Blender mesh and reads them back (``bpy``).
* :mod:`.package` writes the installable zip (``tuckercodec blender-addon OUT.zip``): a Blender
  4.2+ extension whose ``tuckercodec_blender/__init__.py`` loads :mod:`.addon` from the
  tuckercodec wheel it bundles, beside the wheels of scipy, msgpack and zstandard.
"""
