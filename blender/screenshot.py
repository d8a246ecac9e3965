"""Renders the add-on's screenshot headless (Workbench): spot with Unreal-named engine
primitives and CesiumMan with per-bone colliders, in their object colours.

    target/blender-venv/bin/python blender/screenshot.py \
        target/release/bvseg docs/images/blender-colliders.png

(target/blender-venv: made by blender/ci.sh.) The colliders are drawn as thin wire tubes (a
Wireframe modifier), since a render does not draw Blender's wire display.
"""

import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "blender"))

import bpy  # noqa: E402  isort: skip (first: it puts mathutils on the path)
import bvseg_blender  # noqa: E402
from mathutils import Vector  # noqa: E402


def main(bvseg, out):
    os.environ["PATH"] = os.path.dirname(os.path.abspath(bvseg)) + os.pathsep + os.environ.get("PATH", "")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bvseg_blender.register()
    try:
        scene = bpy.context.scene
        bpy.ops.wm.obj_import(filepath=os.path.join(ROOT, "assets", "meshes", "spot.obj"))
        spot = bpy.context.selected_objects[0]
        spot.rotation_euler = (math.radians(90), 0.0, math.radians(-60))
        spot.location = (-0.85, 0.0, 0.72)
        bpy.ops.object.bvseg_colliders(target="physx", naming="UNREAL")
        bpy.ops.import_scene.gltf(filepath=os.path.join(ROOT, "assets", "characters", "CesiumMan.glb"))
        arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
        root = arm.parent or arm
        root.location = (0.75, 0.0, 0.0)
        root.scale = (1.1, 1.1, 1.1)
        for o in bpy.context.view_layer.objects:
            o.select_set(o is arm)
        bpy.context.view_layer.objects.active = arm
        bpy.ops.object.bvseg_colliders(naming="PLAIN", per_bone=True)
        for o in bpy.data.objects:
            if "bvseg_volume" in o:
                o.hide_render = False
                o.display_type = "SOLID"
                w = o.modifiers.new("wire", "WIREFRAME")
                w.thickness = 0.006
                w.use_even_offset = True
            elif o.type == "MESH":
                o.color = (0.8, 0.8, 0.8, 1.0)
        for o in bpy.data.objects:
            if o.type == "MESH" and "bvseg_volume" not in o and o.name.startswith("Icosphere"):
                o.hide_render = True
        cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
        scene.collection.objects.link(cam)
        cam.rotation_euler = (math.radians(80), 0.0, 0.0)
        cam.data.lens = 50
        scene.camera = cam
        scene.render.resolution_x, scene.render.resolution_y = 800, 450
        # Frame every collider's corners, then step back a little.
        depsgraph = bpy.context.evaluated_depsgraph_get()
        coords = []
        for o in bpy.data.objects:
            if "bvseg_volume" in o:
                for c in o.bound_box:
                    coords.extend(o.matrix_world @ Vector(c))
        location, _ = cam.camera_fit_coords(depsgraph, coords)
        forward = cam.rotation_euler.to_matrix() @ Vector((0.0, 0.0, -1.0))
        cam.location = Vector(location) - forward * 0.6
        scene.render.engine = "BLENDER_WORKBENCH"
        shading = scene.display.shading
        shading.light = "STUDIO"
        shading.color_type = "OBJECT"
        shading.show_shadows = False
        shading.show_cavity = True
        scene.render.film_transparent = False
        scene.world = bpy.data.worlds.new("world")
        scene.render.image_settings.color_mode = "RGB"
        scene.render.image_settings.compression = 100
        scene.render.filepath = os.path.abspath(out)
        bpy.ops.render.render(write_still=True)
    finally:
        bvseg_blender.unregister()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
    sys.stdout.flush()
    os._exit(0)
