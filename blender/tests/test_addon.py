"""Headless test of the Blender add-on in a real Blender (the `bpy` module), run by blender/ci.sh.

    python blender/tests/test_addon.py --bvseg target/release/bvseg --mode legacy
    python blender/tests/test_addon.py --bvseg target/release/bvseg --mode extension --zip ADDON.zip

`legacy` enables blender/bvseg_blender as a legacy add-on (bl_info) from a scripts directory
and runs every check; `extension` installs the built extension zip, as Blender's extension
installer does, and runs one mesh through it.

For each run of `bpy.ops.object.bvseg_colliders()` the checks are: one collider object per
volume of the JSON that bvseg writes for the same input and options (run here again,
independently of the add-on), each named by the preset, parented to its mesh (or to its bone,
at rest where the volume is), wire display, not rendered, Blender's rigid-body shape of its
kind, the exact volume in its properties; and its world-space geometry (evaluated, parenting
applied) encloses every world-space vertex of the mesh (a point-in-convex test against the
convex hull of each collider's vertices). Then: a second run replaces the colliders, errors
come back as Blender reports (a RuntimeError from bpy.ops, not a crash), and colliders shrunk
by 1 % no longer enclose the mesh (so the enclosure test can fail).
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
MESHES = os.path.join(ROOT, "assets", "meshes")
CHARACTERS = os.path.join(ROOT, "assets", "characters")

KIND_WORD = {
    "obb": "box",
    "sphere": "sphere",
    "capsule": "capsule",
    "cylinder": "cylinder",
    "ellipsoid": "ellipsoid",
    "hull": "hull",
}
UNREAL = {"obb": "UBX", "sphere": "USP", "capsule": "UCP"}
RIGID = {
    "obb": "BOX",
    "sphere": "SPHERE",
    "capsule": "CAPSULE",
    "cylinder": "CYLINDER",
    "ellipsoid": "CONVEX_HULL",
    "hull": "CONVEX_HULL",
}

FAILURES = []


def check(cond, what):
    if not cond:
        FAILURES.append(what)
        print(f"  FAIL {what}")
    return cond


def expected_name(preset, source, shape, i):
    if preset == "UNREAL":
        return f"{UNREAL.get(shape, 'UCX')}_{source}_{i:02d}"
    if preset == "GODOT":
        return f"{source}_{i:02d}-convcolonly"
    return f"{source}_{KIND_WORD[shape]}_{i:02d}"


# ---------------------------------------------------------------- geometry of the add-on alone


def unit_fibonacci(n):
    golden = math.pi * (3.0 - math.sqrt(5.0))
    out = []
    for i in range(n):
        z = 1.0 - 2.0 * (i + 0.5) / n
        r = math.sqrt(max(0.0, 1.0 - z * z))
        out.append((r * math.cos(golden * i), r * math.sin(golden * i), z))
    return out


def planes_of(verts, faces):
    """(normal, offset) of every face, from its first three corners."""
    import numpy as np

    v = np.asarray(verts, dtype=np.float64)
    out = []
    for f in faces:
        a, b, c = v[f[0]], v[f[1]], v[f[2]]
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n)
        out.append((n, float(n @ a)))
    return out


def test_geometry(geometry):
    """Every collider mesh encloses the exact surface of its volume, faces outward."""
    print("geometry: collider meshes enclose their exact volumes")
    import numpy as np

    rng = np.random.default_rng(7)
    surf = unit_fibonacci(2000)
    for _ in range(20):
        axes = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        center = rng.normal(size=3)
        radii = rng.uniform(0.05, 3.0, size=3)
        r, h = rng.uniform(0.05, 2.0), rng.uniform(0.0, 3.0)
        axis = axes[0]
        vols = {
            "obb": (
                {"shape": "obb", "center": center.tolist(), "axes": axes.tolist(), "radii": radii.tolist()},
                [
                    center + axes.T @ (radii * np.array(s))
                    for s in [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
                ],
            ),
            "ellipsoid": (
                {
                    "shape": "ellipsoid",
                    "center": center.tolist(),
                    "axes": axes.tolist(),
                    "radii": radii.tolist(),
                },
                [center + axes.T @ (radii * np.array(p)) for p in surf],
            ),
            "sphere": (
                {"shape": "sphere", "center": center.tolist(), "radius": r},
                [center + r * np.array(p) for p in surf],
            ),
            "capsule": (
                {
                    "shape": "capsule",
                    "center": center.tolist(),
                    "axis": axis.tolist(),
                    "half_length": h,
                    "radius": r,
                },
                [center + r * np.array(p) + (h if np.dot(p, axis) >= 0 else -h) * axis for p in surf],
            ),
            "cylinder": (
                {
                    "shape": "cylinder",
                    "center": center.tolist(),
                    "axis": axis.tolist(),
                    "half_length": h + 0.01,
                    "radius": r,
                },
                [
                    center + t * (h + 0.01) * axis + r * (math.cos(a) * axes[1] + math.sin(a) * axes[2])
                    for t in (-1.0, -0.3, 0.5, 1.0)
                    for a in np.linspace(0, 2 * math.pi, 500)
                ],
            ),
        }
        for shape, (vol, points) in vols.items():
            c = geometry.collider(vol)
            world = np.array(c.world_vertices())
            planes = planes_of(world, c.faces)
            scale = float(np.abs(world).max())
            p = np.array(points)
            worst = max(float((p @ n - d).max()) for n, d in planes)
            check(worst <= 1e-12 * scale, f"{shape}: exact surface outside its mesh by {worst:.3g}")
            mid = world.mean(axis=0)
            inward = sum(1 for n, d in planes if n @ mid - d >= 0)
            check(inward == 0, f"{shape}: {inward} faces not facing outward")
            if shape == "ellipsoid":
                check(len(world) <= 64, f"ellipsoid mesh has {len(world)} vertices (at most 64)")
    bad = [
        {"shape": "torus"},
        "not a volume",
        {"shape": "sphere", "center": [0, 0, 0]},
        {"shape": "sphere", "center": [0, 0, 0], "radius": -1},
        {"shape": "sphere", "center": [0, float("nan"), 0], "radius": 1},
        {"shape": "capsule", "center": [0, 0, 0], "axis": [0, 0, 1], "half_length": -1, "radius": 1},
        {"shape": "obb", "center": [0, 0, 0], "axes": [[1, 0, 0], [0, 1, 0]], "radii": [1, 1, 1]},
        {"shape": "hull", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]},
    ]
    for volume in bad:
        try:
            geometry.collider(volume)
            check(False, f"the volume {volume} is not refused")
        except geometry.VolumeError:
            pass


# ---------------------------------------------------------------- Blender scene helpers


def reset(bpy):
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o, do_unlink=True)
    for coll in (
        bpy.data.meshes,
        bpy.data.armatures,
        bpy.data.actions,
        bpy.data.collections,
        bpy.data.materials,
        bpy.data.images,
    ):
        for item in list(coll):
            coll.remove(item)
    scene = bpy.context.scene
    if scene.rigidbody_world is not None:
        with bpy.context.temp_override(scene=scene):
            bpy.ops.rigidbody.world_remove()
    scene.frame_set(1)


def import_obj(bpy, name):
    before = set(bpy.data.objects)
    bpy.ops.wm.obj_import(filepath=os.path.join(MESHES, name))
    (obj,) = set(bpy.data.objects) - before
    return obj


def select(bpy, objects):
    for o in bpy.context.view_layer.objects:
        o.select_set(False)
    for o in objects:
        o.select_set(True)
    bpy.context.view_layer.objects.active = objects[0] if objects else None


def world_vertices(bpy, obj):
    """The evaluated mesh's vertices in world space (float64 from Blender's float32)."""
    import numpy as np

    depsgraph = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(depsgraph)
    me = ev.to_mesh()
    co = np.empty(len(me.vertices) * 3, dtype=np.float32)
    me.vertices.foreach_get("co", co)
    ev.to_mesh_clear()
    m = np.array(ev.matrix_world, dtype=np.float64)
    return co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3]


def collider_halfspaces(bpy, obj, shrink=1.0):
    """The convex hull of a collider's world-space vertices as (normals, offsets): the hull's
    triangles from Blender's own convex hull, their planes from the float64 vertices."""
    import bmesh
    import numpy as np

    world = world_vertices(bpy, obj)
    if shrink != 1.0:
        centre = np.array(obj.matrix_world, dtype=np.float64)[:3, 3]
        world = centre + (world - centre) * shrink
    bm = bmesh.new()
    for p in world:
        bm.verts.new(p)
    bm.verts.index_update()
    bmesh.ops.convex_hull(bm, input=list(bm.verts), use_existing_faces=False)
    tris = [[v.index for v in f.verts] for f in bm.faces]
    bm.free()
    normals, offsets = [], []
    mid = world.mean(axis=0)
    for t in tris:
        a, b, c = world[t[0]], world[t[1]], world[t[2]]
        n = np.cross(b - a, c - a)
        length = np.linalg.norm(n)
        if length == 0.0:
            continue
        n /= length
        d = float(n @ a)
        if n @ mid > d:  # orientation from the hull's interior, not from the face order
            n, d = -n, -d
        normals.append(n)
        offsets.append(d)
    return np.array(normals), np.array(offsets)


def outside_count(bpy, points, colliders, shrink=1.0, slack=0.0):
    """How many points lie in no collider (plane offsets allowed `slack`)."""
    import numpy as np

    inside = np.zeros(len(points), dtype=bool)
    for c in colliders:
        n, d = collider_halfspaces(bpy, c, shrink)
        todo = ~inside
        if not todo.any():
            break
        inside[todo] = ((points[todo] @ n.T - d) <= slack).all(axis=1)
    return int((~inside).sum()), inside


def colliders_of(obj):
    cols = [c for c in obj.children if "bvseg_volume" in c]
    return sorted(cols, key=lambda c: c["bvseg_volume"])


def reference_volumes(bpy, bvseg, source, tmp):
    """The volumes bvseg writes for the same input and options as the add-on's last run, with
    an export written here (OBJ: the evaluated mesh in the fitting space; armature: the
    add-on's GLB export, whose node names give the bones)."""
    import numpy as np

    run = json.loads(source["bvseg_run"])
    nodes = None
    if run["input"].endswith(".obj"):
        path = os.path.join(tmp, "ref.obj")
        depsgraph = bpy.context.evaluated_depsgraph_get()
        ev = source.evaluated_get(depsgraph)
        me = ev.to_mesh()
        me.calc_loop_triangles()
        co = np.empty(len(me.vertices) * 3, dtype=np.float32)
        me.vertices.foreach_get("co", co)
        tris = [tuple(t.vertices) for t in me.loop_triangles]
        ev.to_mesh_clear()
        co = co.reshape(-1, 3).astype(np.float64)
        if run["space"] == "WORLD":
            m = np.array(source.matrix_world, dtype=np.float64)
            co = co @ m[:3, :3].T + m[:3, 3]
        with open(path, "w") as f:
            for x, y, z in co.tolist():
                f.write(f"v {x!r} {y!r} {z!r}\n")
            for a, b, c in tris:
                f.write(f"f {a + 1} {b + 1} {c + 1}\n")
    else:
        export = sys.modules[ADDON + ".export"]
        path = os.path.join(tmp, "ref.glb")
        _, nodes = export.write_skinned_glb(source, deformed_meshes(bpy, source), path)
    out = os.path.join(tmp, "ref.json")
    subprocess.run(
        [bvseg, "segment", path, *run["args"], "-o", out, "-q", "--no-hierarchy"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    with open(out) as f:
        return json.load(f)["volumes"], nodes


def check_run(bpy, bvseg, tmp, source, preset, meshes, label, bones=False):
    """The checks of one operator run on `source` (a mesh, or an armature with `meshes`)."""
    print(f"{label}: {source.name}, naming {preset}")
    cols = colliders_of(source)
    volumes, nodes = reference_volumes(bpy, bvseg, source, tmp)
    check(len(cols) == len(volumes), f"{label}: {len(cols)} colliders for {len(volumes)} volumes")
    name = meshes[0].name if len(meshes) == 1 else source.name
    for i, c in enumerate(cols):
        if i >= len(volumes):
            break
        v = volumes[i]
        check(c["bvseg_volume"] == i, f"{label}: collider {c.name} has index {c['bvseg_volume']}, not {i}")
        check(
            c.name == expected_name(preset, name, v["shape"], i),
            f"{label}: collider {i} ({v['shape']}) is named {c.name}",
        )
        params = json.loads(c["bvseg_params"])
        check(
            all(params.get(k) == v[k] for k in v if k not in ("fraction", "protrusion")),
            f"{label}: {c.name} holds another volume than bvseg's {i}",
        )
        check(c.parent is source, f"{label}: {c.name} is not parented to {source.name}")
        if bones:
            bone = nodes[v["bone"]] if isinstance(v.get("bone"), int) else v.get("bone")
            check(
                c.parent_type == "BONE" and c.parent_bone == bone,
                f"{label}: {c.name} hangs on {c.parent_type} {c.parent_bone!r}, not bone {bone!r}",
            )
        else:
            check(c.parent_type == "OBJECT", f"{label}: {c.name} parent type {c.parent_type}")
        check(c.display_type == "WIRE" and c.hide_render, f"{label}: {c.name} is drawn solid or rendered")
        rb = c.rigid_body
        check(
            rb is not None and rb.type == "PASSIVE" and rb.collision_shape == RIGID[v["shape"]],
            f"{label}: {c.name} rigid body {rb and rb.collision_shape}, not {RIGID[v['shape']]}",
        )
    enclosure(bpy, meshes, cols, label)
    return cols


def enclosure(bpy, meshes, cols, label):
    import numpy as np

    points = np.concatenate([world_vertices(bpy, m) for m in meshes])
    out, _ = outside_count(bpy, points, cols)
    check(out == 0, f"{label}: {out} of {len(points)} mesh vertices outside every collider")
    if out == 0:
        print(f"  {len(points)} vertices in {len(cols)} colliders: all enclosed")
    return out


def run_op(bpy, **kw):
    t = time.time()
    result = bpy.ops.object.bvseg_colliders(**kw)
    print(
        f"  bvseg_colliders({', '.join(f'{k}={v!r}' for k, v in kw.items())}) -> {result} "
        f"in {time.time() - t:.1f} s"
    )
    return result


def expect_error(bpy, text, **kw):
    """The operator reports an error containing `text` (bpy.ops raises RuntimeError for an
    error report), and raises nothing else."""
    try:
        result = bpy.ops.object.bvseg_colliders(**kw)
    except RuntimeError as e:
        ok = text in str(e)
        check(ok, f"error report {str(e).strip()!r} does not say {text!r}")
        if ok:
            print(f"  reported: {str(e).strip()}")
        return
    except Exception as e:  # anything but a report is a crash
        check(False, f"expected the report {text!r}, got {type(e).__name__}: {e}")
        return
    check(False, f"expected the report {text!r}, the operator returned {result}")


# ---------------------------------------------------------------- the cases


def test_presets(bpy, bvseg, tmp):
    """One mesh per preset, with a transform, each preset with another target."""
    cases = [
        ("spot.obj", "UNREAL", "physx", "LOCAL"),
        ("bunny.obj", "GODOT", "primitives", "LOCAL"),
        ("fourleg_2.obj", "PLAIN", "physx-hull", "WORLD"),
    ]
    for mesh, preset, target, space in cases:
        reset(bpy)
        obj = import_obj(bpy, mesh)
        obj.location = (0.5, -1.0, 2.0)
        obj.rotation_euler = (0.4, -0.3, 1.2)
        obj.scale = (1.5, 0.8, 1.1)
        select(bpy, [obj])
        run_op(bpy, target=target, naming=preset, space=space)
        check_run(bpy, bvseg, tmp, obj, preset, [obj], f"preset {preset}")
        if preset == "UNREAL":
            # A second run replaces the first one's colliders; nothing piles up.
            first = len(colliders_of(obj))
            run_op(bpy, target="physx", naming=preset, max_k=8)
            cols = colliders_of(obj)
            check(len(cols) <= 8 < first, f"second run: {len(cols)} colliders (max_k 8; first run {first})")
            stale = [o for o in bpy.data.objects if "bvseg_volume" in o and o.parent is obj and o not in cols]
            check(not stale, f"second run left {len(stale)} old colliders")
            check(len(bpy.data.meshes) == 1 + len(cols), f"{len(bpy.data.meshes)} meshes after two runs")
            check_run(bpy, bvseg, tmp, obj, preset, [obj], "rerun")
            # Colliders shrunk by 1 % about their own centres leave vertices out.
            points = world_vertices(bpy, obj)
            out, _ = outside_count(bpy, points, cols, shrink=0.99)
            check(out > 0, "colliders shrunk by 1 % still enclose every vertex: the test cannot fail")
            print(f"  shrunk by 1 %: {out} of {len(points)} vertices outside (as it should)")


def test_multi(bpy, bvseg, tmp):
    """Two meshes in one call, each with its own colliders."""
    reset(bpy)
    a = import_obj(bpy, "spot.obj")
    b = import_obj(bpy, "bunny.obj")
    # Far from the origin: the world coordinates' single-precision rounding is what the
    # colliders' margin must hold there.
    b.location = (30.0, -45.0, 3.0)
    b.rotation_euler = (0.0, 0.0, 0.7)
    b.scale = (2.0, 2.0, 2.0)
    select(bpy, [a, b])
    run_op(bpy, target="parry", naming="UNREAL")
    for o in (a, b):
        check_run(bpy, bvseg, tmp, o, "UNREAL", [o], "multi")


def test_shared(bpy, bvseg, tmp, shared):
    """Held out: meshes of the shared test set that the add-on was not developed on, and CC0
    game assets imported from glTF (several mesh objects in one call; a rigged character)."""
    cases = [
        ("meshes/chair_1.obj", "UNREAL", "physx-hull"),
        ("meshes/octopus_1.obj", "GODOT", "primitives"),
    ]
    for path, preset, target in cases:
        reset(bpy)
        before = set(bpy.data.objects)
        bpy.ops.wm.obj_import(filepath=os.path.join(shared, path))
        (obj,) = set(bpy.data.objects) - before
        obj.location = (-2.0, 5.0, 1.0)
        obj.rotation_euler = (0.1, 0.2, -0.6)
        select(bpy, [obj])
        run_op(bpy, target=target, naming=preset)
        check_run(bpy, bvseg, tmp, obj, preset, [obj], f"held-out {path}")
    for asset in ("building-small-b.glb", "character-male-b.glb"):
        reset(bpy)
        bpy.ops.import_scene.gltf(filepath=os.path.join(shared, "assets", "kenney", asset))
        arms = [o for o in bpy.data.objects if o.type == "ARMATURE"]
        meshes = [o for o in bpy.data.objects if o.type == "MESH"]
        select(bpy, arms or meshes)
        run_op(bpy, target="physx", naming="UNREAL")
        if arms:
            for arm in arms:
                arm.data.pose_position = "REST"
                check_run(bpy, bvseg, tmp, arm, "UNREAL", deformed_meshes(bpy, arm), asset, bones=True)
        else:
            for m in meshes:
                check_run(bpy, bvseg, tmp, m, "UNREAL", [m], asset)


def deformed_meshes(bpy, arm):
    return [
        m
        for m in bpy.context.scene.objects
        if m.type == "MESH" and any(md.type == "ARMATURE" and md.object is arm for md in m.modifiers)
    ]


def test_armature(bpy, bvseg, tmp, character):
    """A skinned glTF character: colliders on bones, enclosing the skin at rest and in poses of
    its animation; and per_bone off: colliders on the mesh as it is posed."""
    reset(bpy)
    bpy.ops.import_scene.gltf(filepath=os.path.join(CHARACTERS, character))
    arm = next(o for o in bpy.data.objects if o.type == "ARMATURE")
    meshes = deformed_meshes(bpy, arm)
    select(bpy, [arm])
    run_op(bpy, naming="PLAIN", per_bone=True)
    arm.data.pose_position = "REST"
    cols = check_run(bpy, bvseg, tmp, arm, "PLAIN", meshes, f"armature {character} at rest", bones=True)
    arm.data.pose_position = "POSE"
    action = arm.animation_data.action if arm.animation_data else None
    if check(action is not None, f"{character}: the import has an action"):
        start, end = (round(x) for x in action.frame_range)
        for frame in sorted({start, (start + end) // 2, end}):
            bpy.context.scene.frame_set(frame)
            print(f"  frame {frame}")
            enclosure(bpy, meshes, cols, f"armature {character} at frame {frame}")
    # per_bone off: the mesh as posed now, colliders on the mesh.
    bpy.context.scene.frame_set(start if action else 1)
    select(bpy, meshes[:1])
    run_op(bpy, naming="GODOT", per_bone=False, max_k=12)
    check_run(bpy, bvseg, tmp, meshes[0], "GODOT", meshes[:1], f"{character} mesh, per_bone off")


def test_errors(bpy, bvseg, tmp, prefs):
    """Errors come back as reports and change nothing."""
    print("errors")
    reset(bpy)
    obj = import_obj(bpy, "bunny.obj")
    select(bpy, [obj])
    run_op(bpy, target="physx", max_k=4)
    before = [c.name for c in colliders_of(obj)]
    # bvseg missing: a preference that names no file, then nothing on PATH.
    prefs.bvseg_path = os.path.join(tmp, "no-such-dir", "bvseg")
    expect_error(bpy, "bvseg not found")
    prefs.bvseg_path = ""
    path = os.environ.get("PATH", "")
    os.environ["PATH"] = os.path.join(tmp, "empty")
    expect_error(bpy, "bvseg not found")
    # Found on PATH.
    bindir = os.path.join(tmp, "bin")
    os.makedirs(bindir, exist_ok=True)
    shutil.copy(bvseg, os.path.join(bindir, "bvseg"))
    os.environ["PATH"] = bindir
    check(run_op(bpy, target="physx", max_k=4) == {"FINISHED"}, "bvseg on PATH is not used")
    os.environ["PATH"] = path
    before = [c.name for c in colliders_of(obj)]
    # A run that fails (exit 2 and bvseg's message), and one that writes no JSON.
    for name, body, text in [
        ("fails", 'echo "bvseg: error: $2: something is wrong" >&2; exit 2', "something is wrong"),
        ("garbage", 'while [ "$1" != "-o" ]; do shift; done; echo "{not json" > "$2"', "not JSON"),
        (
            "noschema",
            'while [ "$1" != "-o" ]; do shift; done; echo "{\\"volumes\\": []}" > "$2"',
            "not a bvseg.volumes document",
        ),
        (
            "badvolume",
            'while [ "$1" != "-o" ]; do shift; done; '
            """echo '{"schema": "bvseg.volumes/2", "volumes": [{"shape": "torus"}]}' > "$2\"""",
            "unknown volume shape",
        ),
    ]:
        fake = os.path.join(tmp, name)
        with open(fake, "w") as f:
            f.write(f"#!/bin/sh\n{body}\n")
        os.chmod(fake, 0o755)
        prefs.bvseg_path = fake
        expect_error(bpy, text)
        check([c.name for c in colliders_of(obj)] == before, f"a failed run ({name}) changed the colliders")
    prefs.bvseg_path = bvseg
    # A run whose message names the temporary file names the object instead.
    # Non-mesh selections, and a mesh that encloses no volume.
    bpy.ops.object.empty_add()
    empty = bpy.context.active_object
    select(bpy, [empty])
    expect_error(bpy, "not a mesh or an armature")
    select(bpy, [])
    expect_error(bpy, "select mesh objects or armatures")
    bpy.ops.mesh.primitive_plane_add()
    plane = bpy.context.active_object
    select(bpy, [plane])
    expect_error(bpy, "bvseg failed")
    expect_error(bpy, "needs a list of kinds", target="custom", kinds="")
    # One good and one bad mesh: colliders for the good one, the bad one reported.
    select(bpy, [obj, plane])
    check(run_op(bpy, target="physx", max_k=4) == {"FINISHED"}, "a good mesh beside a bad one failed")


class Stub:
    """Takes any layout call; records the operator buttons' properties."""

    def __init__(self, log=None):
        self.log = log if log is not None else []

    def __getattr__(self, name):
        def call(*args, **kw):
            if name == "panel":
                return Stub(self.log), Stub(self.log)
            if name == "operator":
                op = type("OpProps", (), {})()
                self.log.append(op)
                return op
            return Stub(self.log)

        return call

    def __setattr__(self, name, value):
        object.__setattr__(self, name, value)


def test_panel(bpy, ui_module):
    """The sidebar panel draws, and its button hands every setting to the operator."""
    print("panel")
    reset(bpy)
    obj = import_obj(bpy, "spot.obj")
    select(bpy, [obj])
    layout = Stub()
    panel = type("PanelSelf", (), {"layout": layout})()
    bpy.context.scene.bvseg.naming = "GODOT"
    ui_module.VIEW3D_PT_bvseg.draw(panel, bpy.context)
    ops = [o for o in layout.log]
    props = sys.modules[ADDON + ".props"].SETTINGS
    check(len(ops) == 1 and all(hasattr(ops[0], p) for p in props), "the panel's button lacks settings")
    check(ops and getattr(ops[0], "naming", None) == "GODOT", "the panel's button ignores the scene's naming")


def test_modal(bpy, bvseg, tmp):
    """The operator as the panel starts it (invoke, then modal on timer events): it ends with
    the colliders, and Esc stops a run without changing the scene."""
    import types

    print("modal")
    operator = sys.modules[ADDON + ".operator"]
    cls = operator.BVSEG_OT_colliders
    reset(bpy)
    obj = import_obj(bpy, "bunny.obj")
    select(bpy, [obj])

    class Timer:
        pass

    status = []
    wm = types.SimpleNamespace(
        progress_begin=lambda a, b: None,
        progress_update=lambda v: None,
        progress_end=lambda: None,
        event_timer_add=lambda step, window=None: Timer(),
        event_timer_remove=lambda t: None,
        modal_handler_add=lambda op: None,
    )
    space = types.SimpleNamespace(status_text_set=lambda text: status.append(text))

    class Context:
        window_manager, workspace, window = wm, space, None

        def __getattr__(self, name):
            return getattr(bpy.context, name)

    reports = []
    settings = {
        name: getattr(bpy.context.scene.bvseg, name) for name in sys.modules[ADDON + ".props"].SETTINGS
    }
    settings.update(target="physx", naming="PLAIN", max_k=12)
    fake = type(
        "ModalOp",
        (),
        {
            "invoke": cls.invoke,
            "modal": cls.modal,
            "_status": cls._status,
            "_end": cls._end,
            "report": lambda self, kind, text: reports.append((set(kind), text)),
            **settings,
        },
    )()
    ctx = Context()
    result = fake.invoke(ctx, None)
    check(result == {"RUNNING_MODAL"}, f"invoke returned {result}")
    started = time.time()
    while result == {"RUNNING_MODAL"} and time.time() - started < 120:
        time.sleep(0.05)
        result = fake.modal(ctx, types.SimpleNamespace(type="TIMER", value="NOTHING", timer=fake._timer))
    check(result == {"FINISHED"}, f"the modal run ended with {result}")
    check(any("bvseg 1/1: bunny" in s for s in status if s), f"no progress in the status bar: {status[:3]}")
    check(status and status[-1] is None, "the status bar text is not cleared")
    check(len(colliders_of(obj)) > 0, "the modal run made no colliders")
    print(f"  modal: {len(colliders_of(obj))} colliders; status bar said {status[-2]!r}")
    # Esc while bvseg runs: the process is killed, the colliders stay as they were.
    before = [c.name for c in colliders_of(obj)]
    settings.update(max_k=96, samples=400000)
    fake = type(
        "ModalOp",
        (),
        {
            "invoke": cls.invoke,
            "modal": cls.modal,
            "_status": cls._status,
            "_end": cls._end,
            "report": lambda self, kind, text: reports.append((set(kind), text)),
            **settings,
        },
    )()
    check(fake.invoke(ctx, None) == {"RUNNING_MODAL"}, "second invoke")
    process = fake._session.job.run.process
    result = fake.modal(ctx, types.SimpleNamespace(type="ESC", value="PRESS", timer=None))
    check(result == {"CANCELLED"}, f"Esc ended with {result}")
    check(process.poll() is not None, "Esc left bvseg running")
    check([c.name for c in colliders_of(obj)] == before, "Esc changed the colliders")
    check(any("stopped" in text for _, text in reports), "Esc was not reported")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bvseg", required=True)
    ap.add_argument("--mode", choices=("legacy", "extension"), default="legacy")
    ap.add_argument("--zip", help="the extension zip (--mode extension)")
    ap.add_argument(
        "--character",
        action="append",
        help="skinned glTF of assets/characters to test (default RiggedSimple.glb, CesiumMan.glb)",
    )
    ap.add_argument(
        "--shared", help="the project's shared test data (meshes/, assets/kenney/): held-out cases"
    )
    ap.add_argument(
        "--only",
        help="comma list of the legacy mode's tests to run: presets, multi, armature, "
        "errors, panel, modal, shared (default all)",
    )
    args = ap.parse_args()
    bvseg = os.path.abspath(args.bvseg)
    if not os.access(bvseg, os.X_OK):
        print(f"{bvseg}: not an executable (build it: cargo build --release -p bvseg-cli)")
        return 2
    tmp = tempfile.mkdtemp(prefix="bvseg-blender-test-")
    # Blender's user directories (preferences, scripts, extensions) in the temporary directory.
    os.environ["BLENDER_USER_RESOURCES"] = os.path.join(tmp, "user")
    os.environ["BLENDER_USER_SCRIPTS"] = os.path.join(tmp, "scripts")
    os.makedirs(os.path.join(tmp, "scripts", "addons"))
    started = time.time()
    import bpy  # isort: skip (first: it puts addon_utils on the path)

    import addon_utils

    print(f"Blender {bpy.app.version_string}, Python {sys.version.split()[0]}")
    global ADDON
    if args.mode == "legacy":
        ADDON = "bvseg_blender"
        shutil.copytree(
            os.path.join(ROOT, "blender", "bvseg_blender"),
            os.path.join(tmp, "scripts", "addons", "bvseg_blender"),
        )
        bpy.utils.refresh_script_paths()
        module = addon_utils.enable(ADDON, default_set=True, handle_error=None)
        check(
            module is not None and module.bl_info["name"] == "bvseg Colliders",
            "the legacy add-on does not enable",
        )
    else:
        ADDON = "bl_ext.user_default.bvseg_blender"
        result = bpy.ops.extensions.package_install_files(
            filepath=os.path.abspath(args.zip), repo="user_default", enable_on_install=True
        )
        check(result == {"FINISHED"}, f"extension install: {result}")
    registered = hasattr(bpy.types, "OBJECT_OT_bvseg_colliders") or "bvseg_colliders" in dir(bpy.ops.object)
    if not check(registered and ADDON in bpy.context.preferences.addons, f"{ADDON} is not enabled"):
        return 1
    prefs = bpy.context.preferences.addons[ADDON].preferences
    prefs.bvseg_path = bvseg
    try:
        test_geometry(sys.modules[ADDON + ".geometry"])
        if args.mode == "legacy":
            tests = {
                "presets": lambda: test_presets(bpy, bvseg, tmp),
                "multi": lambda: test_multi(bpy, bvseg, tmp),
                "armature": lambda: [
                    test_armature(bpy, bvseg, tmp, c)
                    for c in args.character or ["RiggedSimple.glb", "CesiumMan.glb"]
                ],
                "errors": lambda: test_errors(bpy, bvseg, tmp, prefs),
                "panel": lambda: test_panel(bpy, sys.modules[ADDON + ".ui"]),
                "modal": lambda: test_modal(bpy, bvseg, tmp),
            }
            if args.shared:
                tests["shared"] = lambda: test_shared(bpy, bvseg, tmp, os.path.abspath(args.shared))
            for name in args.only.split(",") if args.only else tests:
                tests[name]()
        else:
            reset(bpy)
            obj = import_obj(bpy, "fourleg_2.obj")
            select(bpy, [obj])
            run_op(bpy, target="physx", naming="UNREAL")
            check_run(bpy, bvseg, tmp, obj, "UNREAL", [obj], "extension")
    except Exception:
        traceback.print_exc()
        FAILURES.append("an exception escaped")
    finally:
        # bpy hangs at exit while an add-on's classes are registered.
        addon_utils.disable(ADDON, default_set=True)
        check(not hasattr(bpy.types, "VIEW3D_PT_bvseg"), "the add-on's panel is still registered")
        shutil.rmtree(tmp, ignore_errors=True)
    took = time.time() - started
    if FAILURES:
        print(f"\n{len(FAILURES)} FAILED ({took:.0f} s):")
        for f in FAILURES:
            print(f"  {f}")
        return 1
    print(f"\nblender add-on ({args.mode}): all checks passed ({took:.0f} s)")
    return 0


ADDON = "bvseg_blender"

if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
