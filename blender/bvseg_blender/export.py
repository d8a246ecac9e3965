"""What bvseg reads: a mesh object's evaluated triangles as OBJ, or an armature with its skinned
meshes as glTF binary (so bvseg sees the skin and binds each volume to a bone)."""

import json
import struct

import bpy
import numpy as np


class ExportError(Exception):
    """An object that cannot be handed to bvseg: one line for the user."""


def write_obj(obj, depsgraph, path, matrix=None):
    """Writes the evaluated (modifiers applied) mesh of `obj` as triangles to `path`, its
    vertices mapped by `matrix` (4x4, None: the object's own local coordinates). Returns the
    vertices written (n x 3, float64). Coordinates are printed with 17 significant digits, so
    bvseg reads exactly the values written."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        n, t = len(mesh.vertices), len(mesh.loop_triangles)
        if n == 0 or t == 0:
            raise ExportError(f"{obj.name}: the mesh has no faces")
        co = np.empty(n * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        tris = np.empty(t * 3, dtype=np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
    finally:
        evaluated.to_mesh_clear()
    co = co.reshape(n, 3).astype(np.float64)
    if matrix is not None:
        m = np.array(matrix, dtype=np.float64)
        co = co @ m[:3, :3].T + m[:3, 3]
    if not np.isfinite(co).all():
        raise ExportError(f"{obj.name}: the mesh has non-finite coordinates")
    with open(path, "w", encoding="ascii") as f:
        f.write(f"# {n} vertices, {t} triangles of Blender object {obj.name!r}\n")
        f.write("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in co.tolist()))
        f.write("".join(f"f {a} {b} {c}\n" for a, b, c in (tris.reshape(t, 3) + 1).tolist()))
    return co


def write_skinned_glb(armature, meshes, path):
    """Exports `armature` and its skinned `meshes` (at rest, with their modifiers but the
    armature's, and the armature's actions) to a GLB in Blender's own axes (Z up), so the
    file's model space is Blender's world space. Returns the meshes' vertices placed by their
    objects (n x 3, world space at rest when the meshes hang under the armature unposed) and
    the glTF node names by index."""
    view_layer = bpy.context.view_layer
    selected = [o for o in view_layer.objects if o.select_get()]
    active = view_layer.objects.active
    # An armature shown at rest would export its actions as the rest pose over and over.
    pose_position = armature.data.pose_position
    try:
        armature.data.pose_position = "POSE"
        for o in selected:
            o.select_set(False)
        for o in [armature, *meshes]:
            o.select_set(True)
        view_layer.objects.active = armature
        result = bpy.ops.export_scene.gltf(
            filepath=path,
            export_format="GLB",
            use_selection=True,
            export_yup=False,
            export_apply=True,
            export_skins=True,
            export_animations=True,
            export_morph=False,
            export_materials="NONE",
            export_texcoords=False,
            export_normals=False,
            export_cameras=False,
            export_lights=False,
            export_extras=False,
        )
    except RuntimeError as e:
        raise ExportError(f"{armature.name}: glTF export failed: {str(e).strip()}") from e
    finally:
        armature.data.pose_position = pose_position
        for o in view_layer.objects:
            o.select_set(o in selected)
        view_layer.objects.active = active
    if "FINISHED" not in result:
        raise ExportError(f"{armature.name}: glTF export failed")
    nodes = glb_node_names(path)
    placed = [np.zeros((0, 3))]
    for m in meshes:
        co = np.empty(len(m.data.vertices) * 3, dtype=np.float32)
        m.data.vertices.foreach_get("co", co)
        w = np.array(m.matrix_world, dtype=np.float64)
        placed.append(co.reshape(-1, 3).astype(np.float64) @ w[:3, :3].T + w[:3, 3])
    return np.concatenate(placed), nodes


def glb_node_names(path):
    """The names of a GLB file's nodes, by index (None for an unnamed node)."""
    try:
        with open(path, "rb") as f:
            header = f.read(20)
            magic, _, _, length, kind = struct.unpack("<4sIIII", header)
            if magic != b"glTF" or kind != 0x4E4F534A:
                raise ExportError("the exported glTF has no JSON chunk")
            doc = json.loads(f.read(length))
    except (OSError, struct.error, json.JSONDecodeError) as e:
        raise ExportError(f"cannot read the exported glTF: {e}") from e
    return [n.get("name") for n in doc.get("nodes", [])]
