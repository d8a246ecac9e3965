"""bvseg colliders for Blender: wraps the selected meshes (or a rigged character's skin, per
bone) in tight enclosing colliders with the bvseg command line, named for Unreal, Godot or
plainly, parented to the mesh or its bones.

Scripting interface (stable): `register()` / `unregister()`, and the operator
`bpy.ops.object.bvseg_colliders(target=..., naming='UNREAL'|'GODOT'|'PLAIN', max_k=...,
per_bone=..., tov=..., max_protrusion=..., ...)` acting on the selected objects.
"""

# Read by Blender when the folder is installed as a legacy add-on; an extension is described by
# blender_manifest.toml instead.
bl_info = {
    "name": "bvseg Colliders",
    "author": "bvseg contributors",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "View3D > Sidebar > bvseg; Object > Colliders (bvseg)",
    "description": "Tight enclosing colliders (boxes, spheres, capsules, cylinders, convex) from bvseg, "
    "named for Unreal or Godot",
    "category": "Physics",
}

import bpy  # noqa: E402 (after bl_info, which Blender reads first)

from . import operator, ui  # noqa: E402


def register():
    for cls in ui.CLASSES:
        bpy.utils.register_class(cls)
    ui.register_settings()
    bpy.types.VIEW3D_MT_object.append(operator.menu_entry)


def unregister():
    bpy.types.VIEW3D_MT_object.remove(operator.menu_entry)
    ui.unregister_settings()
    for cls in reversed(ui.CLASSES):
        bpy.utils.unregister_class(cls)
