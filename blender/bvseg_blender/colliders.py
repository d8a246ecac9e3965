"""Collider objects in the scene: one per volume, named by the engine preset, parented to the
mesh (or to the bone its volume moves with), wire display, not rendered, tagged so that the
next run replaces them."""

import json

import bmesh
import bpy
from mathutils import Matrix

from . import geometry, naming

# Custom property on every collider: the index of its volume. A run removes the tagged
# children of the object it runs on before it adds the new ones.
TAG = "bvseg_volume"
COLLECTION = "bvseg colliders"

# Wire colours by kind (Object colour: the viewport shows them with Wireframe colour = Object).
COLORS = {
    "obb": (0.95, 0.55, 0.10, 1.0),
    "sphere": (0.20, 0.70, 1.00, 1.0),
    "capsule": (0.30, 0.90, 0.30, 1.0),
    "cylinder": (0.90, 0.30, 0.80, 1.0),
    "ellipsoid": (1.00, 0.85, 0.20, 1.0),
    "hull": (0.95, 0.25, 0.25, 1.0),
}


def previous(parent):
    """The colliders an earlier run hung under `parent`."""
    return [o for o in parent.children if TAG in o]


def remove_previous(parent):
    """Deletes the colliders of an earlier run on `parent` (and their meshes); returns how
    many."""
    old = previous(parent)
    for o in old:
        data = o.data
        bpy.data.objects.remove(o, do_unlink=True)
        if data is not None and data.users == 0:
            bpy.data.meshes.remove(data)
    return len(old)


def _collection(scene):
    coll = bpy.data.collections.get(COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(COLLECTION)
    if coll.name not in scene.collection.children:
        scene.collection.children.link(coll)
    return coll


def _mesh(name, c):
    me = bpy.data.meshes.new(name)
    if c.faces is not None:
        me.from_pydata(c.vertices, [], c.faces)
        me.update()
        return me
    # A hull: its points' convex hull; points inside it (none from bvseg) are dropped.
    bm = bmesh.new()
    try:
        for v in c.vertices:
            bm.verts.new(v)
        bmesh.ops.convex_hull(bm, input=list(bm.verts), use_existing_faces=False)
        loose = [v for v in bm.verts if not v.link_faces]
        if loose:
            bmesh.ops.delete(bm, geom=loose, context="VERTS")
        bm.to_mesh(me)
    finally:
        bm.free()
    me.update()
    return me


class Placement:
    """Where colliders hang and how their frames (in the space the volumes were fitted in)
    map to their parent: `parent`, and per volume a bone name or None."""

    def __init__(self, parent, fit_to_world=None, bones=None):
        self.parent = parent
        # The fitting space to world at the time of the export; None: the parent's own space.
        self.fit_to_world = None if fit_to_world is None else Matrix(fit_to_world)
        self.bones = bones or {}

    def attach(self, obj, bone_name):
        parent = self.parent
        obj.parent = parent
        bone = parent.data.bones.get(bone_name) if bone_name and parent.type == "ARMATURE" else None
        if self.fit_to_world is None:
            obj.parent_type = "OBJECT"
            obj.matrix_parent_inverse = Matrix.Identity(4)
        elif bone is not None:
            obj.parent_type = "BONE"
            obj.parent_bone = bone.name
            # Blender places a bone's child from the bone's tail in the pose: A P T, with A the
            # armature's world matrix, P the pose matrix and T the bone's length along its Y.
            # With the inverse of its rest value A B T (B the rest matrix) as parent inverse,
            # world = A P T (A B T)^-1 F: the volume's frame F at rest, moved with the bone.
            rest = parent.matrix_world @ bone.matrix_local @ Matrix.Translation((0.0, bone.length, 0.0))
            obj.matrix_parent_inverse = rest.inverted() @ self.fit_to_world
        else:
            obj.parent_type = "OBJECT"
            obj.matrix_parent_inverse = parent.matrix_world.inverted() @ self.fit_to_world


def build(context, name, placement, volumes, settings):
    """Creates one collider object per volume (dicts of a bvseg.volumes file), after removing
    the previous ones under placement.parent. Returns (objects, warnings). Raises
    geometry.VolumeError before touching the scene if a volume is not one bvseg writes."""
    shapes = []
    for i, v in enumerate(volumes):
        try:
            shapes.append(geometry.collider(v))
        except geometry.VolumeError as e:
            raise geometry.VolumeError(f"volume {i}: {e}") from e
    remove_previous(placement.parent)
    coll = _collection(context.scene)
    warnings = []
    objects = []
    for i, (v, c) in enumerate(zip(volumes, shapes, strict=True)):
        wanted = naming.collider_name(settings.naming, name, c.shape, i)
        obj = bpy.data.objects.new(wanted, _mesh(wanted, c))
        if obj.name != wanted:
            warnings.append(f"Blender named collider {wanted} {obj.name} (the name is taken or too long)")
        coll.objects.link(obj)
        bone = v.get("bone")
        bone_name = placement.bones.get(bone) if bone is not None else None
        if bone is not None and bone_name is None:
            warnings.append(f"{obj.name}: bone {bone!r} of the volume is not in {placement.parent.name}")
        placement.attach(obj, bone_name)
        obj.matrix_basis = Matrix(c.matrix())
        obj[TAG] = i
        obj["bvseg_shape"] = c.shape
        if bone_name:
            obj["bvseg_bone"] = bone_name
        # The exact volume in the fitting space (the mesh only encloses it), for exporters.
        obj["bvseg_params"] = json.dumps({k: v[k] for k in v if k not in ("fraction", "protrusion")})
        obj.display_type = "WIRE"
        obj.hide_render = True
        obj.color = COLORS.get(c.shape, (1.0, 1.0, 1.0, 1.0))
        objects.append((obj, c))
    if settings.rigid_body and objects:
        warnings += _rigid_bodies(context, objects)
    return [o for o, _ in objects], warnings


def _rigid_bodies(context, objects):
    """Passive, animated (they follow their parent) rigid bodies with Blender's own collision
    shape where one matches the kind, and no collision margin, so the shape is the collider's."""
    scene = context.scene
    objs = [o for o, _ in objects]
    try:
        with context.temp_override(
            scene=scene,
            object=objs[0],
            active_object=objs[0],
            selected_objects=objs,
            selected_editable_objects=objs,
        ):
            if scene.rigidbody_world is None:
                bpy.ops.rigidbody.world_add()
            bpy.ops.rigidbody.objects_add(type="PASSIVE")
    except RuntimeError as e:
        return [f"no rigid bodies were added: {str(e).strip()}"]
    for o, c in objects:
        rb = o.rigid_body
        if rb is None:
            continue
        rb.collision_shape = c.rigid_body_shape
        rb.kinematic = True
        rb.use_margin = True
        rb.collision_margin = 0.0
    return []
