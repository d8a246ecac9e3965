#!/usr/bin/env python3
"""Checks a robot's new colliders against its original collision meshes, with MuJoCo itself
reading both files, so that the check shares no code with bvseg's URDF and MJCF readers.

    python check_robot.py ORIGINAL.xml|ORIGINAL.urdf NEW.xml|NEW.urdf [--source visual] [--json]

MuJoCo (`mujoco.MjModel.from_xml_path`) loads ORIGINAL and NEW; a URDF is loaded through a
temporary copy whose mesh file names are made absolute (`package://NAME/rest` read as `rest`
beside the file or above it, as bvseg reads it) and which asks MuJoCo to keep every link as a
body of its own (`fusestatic="false"`) and to drop the visuals (`discardvisual="true"`).

For every body of ORIGINAL with collision mesh geoms (a geom collides when its contype or
conaffinity is not 0; `--source visual` takes every mesh geom), each vertex of those meshes,
in the body's frame (MuJoCo stores mesh vertices in the mesh's own frame, centred and turned
to its principal axes, and the geom's pos and quat place that frame in the body), must lie in
the union of NEW's colliding geoms of the body with the same name: sphere, capsule, cylinder,
ellipsoid, box, and mesh geoms that are convex (each vertex on the hull MuJoCo computed for
it), each in its own frame. MuJoCo keeps mesh vertices in float32, so a vertex may stick out
by its rounding: the test allows 1e-6 of the diagonal of the body's vertices.

Also: each body of NEW sits where the body of ORIGINAL with its name does, both in their
reference pose (qpos0), within 1e-6 (length units and radians); a URDF, which has no place for
its root link's pose in the world, is compared relative to its root. And NEW steps.

When both are MJCF, NEW must keep what ORIGINAL has besides its collision meshes: the names, in
order, of its bodies, joints, actuators, sensors, sites, equality constraints and keyframes; each
body's mass, inertia and inertial frame (relative 1e-9); and each body's visual geoms (those that
do not collide): type, mesh, size, place, group, colour and material. A colliding mesh geom of
ORIGINAL may stay in NEW as a visual geom of the same body and place (bvseg keeps one so when its
body's mass comes from its geoms); any other new visual geom is a failure.

Prints one line per body (vertices, enclosed fraction, geoms by type) and `worst_enclosed`,
`new_mesh_collisions` (NEW's colliding mesh geoms that are not convex); exits 1 when a body
encloses less than 1.0, a collision mesh is left in NEW, a body is misplaced or NEW does not
step, or ORIGINAL has no collision mesh; 2 when a file does not load.
"""
import argparse
import json
import os
import re
import sys
import tempfile

import numpy as np

try:
    import mujoco
except ImportError:  # pragma: no cover - the caller installs it
    sys.exit("check_robot.py: needs MuJoCo's Python package (pip install mujoco)")

REL_SLACK = 1e-6
# Body positions (metres, or the model's unit) and angles (radians) in the reference pose.
PLACE_TOL = 1e-6
TYPES = {
    int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
    int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
    int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
    int(mujoco.mjtGeom.mjGEOM_MESH): "mesh",
}


def resolve(base, given):
    """A URDF mesh file name as bvseg resolves it: file:// and package://NAME/ dropped,
    relative names looked up beside the file, then in its parents (also as NAME/rest)."""
    package = None
    if given.startswith("package://"):
        rest = given[len("package://"):]
        package, _, rest = rest.partition("/") if "/" in rest else (None, "", rest)
    else:
        rest = given[len("file://"):] if given.startswith("file://") else given
    if os.path.isabs(rest):
        return rest
    d = base
    for _ in range(8):
        for c in [os.path.join(d, rest)] + ([os.path.join(d, package, rest)] if package else []):
            if os.path.isfile(c):
                return os.path.abspath(c)
        parent = os.path.dirname(d)
        if parent == d:
            break
        d = parent
    return os.path.join(base, rest)


def load(path):
    """The MjModel of an MJCF or URDF file."""
    if not path.lower().endswith(".urdf"):
        return mujoco.MjModel.from_xml_path(path)
    text = open(path, encoding="utf-8").read()
    base = os.path.dirname(os.path.abspath(path))
    text = re.sub(r'filename="([^"]*)"', lambda m: f'filename="{resolve(base, m.group(1))}"', text)
    ext = '<mujoco><compiler strippath="false" fusestatic="false" discardvisual="true"/></mujoco>'
    text = re.sub(r"(<robot\b[^>]*>)", lambda m: m.group(1) + ext, text, count=1)
    with tempfile.NamedTemporaryFile("w", suffix=".urdf", dir=base if os.access(base, os.W_OK) else None,
                                     delete=False, encoding="utf-8") as f:
        f.write(text)
    try:
        return mujoco.MjModel.from_xml_path(f.name)
    finally:
        os.unlink(f.name)


def quat_matrix(q):
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, dtype=np.float64))
    return m.reshape(3, 3)


def body_name(m, b):
    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body_{b}"


def collides(m, g):
    return m.geom_contype[g] != 0 or m.geom_conaffinity[g] != 0


def mesh_vertices(m, mesh_id):
    a, n = m.mesh_vertadr[mesh_id], m.mesh_vertnum[mesh_id]
    return np.asarray(m.mesh_vert[a:a + n], dtype=np.float64)


def hull_planes(m, mesh_id):
    """Outward unit normals and offsets of the convex hull MuJoCo computed for a mesh (its
    mesh_graph), else of the mesh's own faces; in the mesh's frame."""
    v = mesh_vertices(m, mesh_id)
    adr = m.mesh_graphadr[mesh_id]
    if adr >= 0:
        g = m.mesh_graph
        nv, nf = int(g[adr]), int(g[adr + 1])
        start = adr + 2 + 3 * nv + 3 * nf
        faces = np.asarray(g[start:start + 3 * nf], dtype=np.int64).reshape(nf, 3)
    else:
        a, n = m.mesh_faceadr[mesh_id], m.mesh_facenum[mesh_id]
        faces = np.asarray(m.mesh_face[a:a + n], dtype=np.int64)
    p0, p1, p2 = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    n = np.cross(p1 - p0, p2 - p0)
    length = np.linalg.norm(n, axis=1)
    keep = length > 0
    n, p0 = n[keep] / length[keep, None], p0[keep]
    d = np.einsum("ij,ij->i", n, p0)
    # Turn each plane outward: the vertices' centroid is inside.
    c = v.mean(axis=0)
    flip = n @ c - d > 0
    n[flip], d[flip] = -n[flip], -d[flip]
    return n, d, v


def inside(kind, size, planes, q, slack):
    """Which local points q (n x 3) lie in the geom, within slack."""
    if kind == "sphere":
        return np.linalg.norm(q, axis=1) <= size[0] + slack
    if kind == "capsule":
        z = np.clip(q[:, 2], -size[1], size[1])
        return np.linalg.norm(q - np.c_[np.zeros((len(q), 2)), z], axis=1) <= size[0] + slack
    if kind == "cylinder":
        return (np.hypot(q[:, 0], q[:, 1]) <= size[0] + slack) & (np.abs(q[:, 2]) <= size[1] + slack)
    if kind == "box":
        return np.all(np.abs(q) <= size[:3] + slack, axis=1)
    if kind == "ellipsoid":
        # Grown by the slack along each axis: a conservative-enough allowance for f32 input.
        return np.sum((q / (size[:3] + slack)) ** 2, axis=1) <= 1.0
    if kind == "mesh":
        n, d, _ = planes
        return np.max(q @ n.T - d, axis=1) <= slack
    return np.zeros(len(q), dtype=bool)


def original_vertices(m, source):
    """{body name: vertices in the body's frame} of the bodies with collision (or any) meshes."""
    out = {}
    for g in range(m.ngeom):
        if m.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        if source == "collision" and not collides(m, g):
            continue
        b = m.geom_bodyid[g]
        v = mesh_vertices(m, m.geom_dataid[g])
        p = v @ quat_matrix(m.geom_quat[g]).T + m.geom_pos[g]
        out.setdefault(body_name(m, b), []).append(p)
    return {k: np.concatenate(v) for k, v in out.items()}


def new_geoms(m):
    """{body name: [(kind, size, planes or None, R, t)]} of the colliding geoms, and the
    number of colliding mesh geoms that are not convex."""
    out, nonconvex = {}, 0
    for g in range(m.ngeom):
        if not collides(m, g):
            continue
        kind = TYPES.get(int(m.geom_type[g]), f"type {int(m.geom_type[g])}")
        planes = None
        if kind == "mesh":
            planes = hull_planes(m, m.geom_dataid[g])
            n, d, v = planes
            scale = max(np.ptp(v, axis=0).max(), 1e-12)
            # Convex: every vertex on its hull (no vertex deeper inside than round-off).
            if np.any(np.max(v @ n.T - d, axis=1) < -1e-5 * scale):
                nonconvex += 1
                kind = "mesh (not convex)"
        out.setdefault(body_name(m, m.geom_bodyid[g]), []).append(
            (kind, np.asarray(m.geom_size[g], dtype=np.float64), planes,
             quat_matrix(m.geom_quat[g]), np.asarray(m.geom_pos[g], dtype=np.float64)))
    return out, nonconvex


def poses(m, relative):
    """{body name: (position, quaternion)} in the reference pose (qpos0): in the world, or
    with `relative` in the frame of the body's root body."""
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    out = {}
    for b in range(1, m.nbody):
        pos, quat = np.array(d.xpos[b]), np.array(d.xquat[b])
        if relative:
            r = m.body_rootid[b]
            inv = np.zeros(4)
            mujoco.mju_negQuat(inv, d.xquat[r])
            p, q = np.zeros(3), np.zeros(4)
            mujoco.mju_rotVecQuat(p, pos - d.xpos[r], inv)
            mujoco.mju_mulQuat(q, inv, quat)
            pos, quat = p, q
        out[body_name(m, b)] = (pos, quat)
    return out


NAMED = {
    "bodies": ("nbody", mujoco.mjtObj.mjOBJ_BODY),
    "joints": ("njnt", mujoco.mjtObj.mjOBJ_JOINT),
    "actuators": ("nu", mujoco.mjtObj.mjOBJ_ACTUATOR),
    "sensors": ("nsensor", mujoco.mjtObj.mjOBJ_SENSOR),
    "sites": ("nsite", mujoco.mjtObj.mjOBJ_SITE),
    "equalities": ("neq", mujoco.mjtObj.mjOBJ_EQUALITY),
    "keyframes": ("nkey", mujoco.mjtObj.mjOBJ_KEY),
}


def names(m, what):
    count, obj = NAMED[what]
    return [mujoco.mj_id2name(m, obj, i) for i in range(getattr(m, count))]


def visual_geoms(m):
    """The geoms that do not collide, each as a comparable tuple (body, type, mesh, size,
    pos, quat, group, rgba, material), rounded to 1e-9."""
    out = []
    for g in range(m.ngeom):
        if collides(m, g):
            continue
        mesh = (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_MESH, m.geom_dataid[g])
                if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH else None)
        out.append((body_name(m, m.geom_bodyid[g]), int(m.geom_type[g]), mesh,
                    *[tuple(np.round(np.asarray(a, dtype=np.float64), 9)) for a in
                      (m.geom_size[g], m.geom_pos[g], m.geom_quat[g], m.geom_rgba[g])],
                    int(m.geom_group[g]), int(m.geom_matid[g])))
    return out


def collision_meshes(m):
    """The colliding mesh geoms, as visual_geoms writes them (what may stay as a visual)."""
    out = []
    for g in range(m.ngeom):
        if collides(m, g) and m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            mesh = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_MESH, m.geom_dataid[g])
            out.append((body_name(m, m.geom_bodyid[g]), mesh,
                        tuple(np.round(np.asarray(m.geom_pos[g], dtype=np.float64), 9)),
                        tuple(np.round(np.asarray(m.geom_quat[g], dtype=np.float64), 9))))
    return out


def kept(mo, mn):
    """What NEW (an MJCF) must keep of ORIGINAL (an MJCF): a list of failures, and counts."""
    fails, counts = [], {}
    for what in NAMED:
        a, b = names(mo, what), names(mn, what)
        counts[what] = len(a)
        if a != b:
            fails.append(f"{what} differ: {a} != {b}")
    if mo.nbody == mn.nbody:
        for field in ("body_mass", "body_inertia", "body_ipos", "body_iquat"):
            a, b = getattr(mo, field), getattr(mn, field)
            scale = max(float(np.abs(a).max()), 1e-300)
            if not np.allclose(a, b, rtol=1e-9, atol=1e-9 * scale):
                worst = int(np.argmax(np.abs(np.asarray(a) - np.asarray(b)).reshape(mo.nbody, -1).max(axis=1)))
                fails.append(f"{field} differs (body {body_name(mo, worst)}: {a[worst]} != {b[worst]})")
    vo, vn = visual_geoms(mo), visual_geoms(mn)
    missing = [g for g in vo if g not in vn]
    extra = list(vn)
    for g in vo:
        if g in extra:
            extra.remove(g)
    allowed = collision_meshes(mo)
    carriers = [g for g in extra if (g[0], g[2], g[4], g[5]) in allowed]
    others = [g for g in extra if g not in carriers]
    if missing:
        fails.append(f"{len(missing)} visual geoms missing, e.g. body {missing[0][0]} mesh {missing[0][2]}")
    if others:
        fails.append(f"{len(others)} new visual geoms, e.g. body {others[0][0]} mesh {others[0][2]}")
    counts["visual_geoms"] = len(vo)
    counts["collision_meshes_kept_for_mass"] = len(carriers)
    return fails, counts


def body_offsets(mo, mn, relative):
    """The largest distance and angle between a body of ORIGINAL and the body of NEW with its
    name, both models in their reference pose (qpos0)."""
    po, pn = poses(mo, relative), poses(mn, relative)
    dist, angle = 0.0, 0.0
    for name, (p, q) in po.items():
        if name not in pn:
            continue
        p2, q2 = pn[name]
        dist = max(dist, float(np.linalg.norm(p - p2)))
        # The angle of q^-1 q2, from its vector part (acos near 1 would lose half the digits).
        inv, rel = np.zeros(4), np.zeros(4)
        mujoco.mju_negQuat(inv, q)
        mujoco.mju_mulQuat(rel, inv, q2)
        angle = max(angle, 2 * float(np.arctan2(np.linalg.norm(rel[1:]), abs(rel[0]))))
    return dist, angle


def check(original, new, source):
    mo, mn = load(original), load(new)
    # A URDF has no place for its root link's pose in the world: compare within each tree.
    offset, turn = body_offsets(mo, mn, new.lower().endswith(".urdf"))
    data = mujoco.MjData(mn)
    for _ in range(10):
        mujoco.mj_step(mn, data)
    steps_ok = bool(np.all(np.isfinite(data.qpos)))
    verts = original_vertices(mo, source)
    geoms, nonconvex = new_geoms(mn)
    links, worst = {}, 1.0
    for name, p in sorted(verts.items()):
        slack = REL_SLACK * max(float(np.linalg.norm(np.ptp(p, axis=0))), 1e-9)
        ok = np.zeros(len(p), dtype=bool)
        counts = {}
        for kind, size, planes, R, t in geoms.get(name, []):
            counts[kind] = counts.get(kind, 0) + 1
            if kind not in ("sphere", "capsule", "cylinder", "box", "ellipsoid", "mesh"):
                continue
            q = (p - t) @ R  # into the geom's frame
            ok |= inside(kind, size, planes, q, slack)
        frac = float(ok.mean()) if len(p) else 1.0
        worst = min(worst, frac)
        links[name] = {"vertices": int(len(p)), "enclosed": frac, "geoms": counts}
    both_mjcf = not original.lower().endswith(".urdf") and not new.lower().endswith(".urdf")
    kept_fails, kept_counts = kept(mo, mn) if both_mjcf else ([], {})
    return {
        "original": original,
        "new": new,
        "kept_failures": kept_fails,
        "kept": kept_counts,
        "source": source,
        "links": links,
        "worst_enclosed": worst,
        "new_mesh_collisions": nonconvex,
        "new_geoms": int(mn.ngeom),
        "steps": steps_ok,
        "body_offset": offset,
        "body_angle": turn,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("original")
    ap.add_argument("new")
    ap.add_argument("--source", choices=("collision", "visual"), default="collision")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    a = ap.parse_args()
    try:
        r = check(a.original, a.new, a.source)
    except (ValueError, OSError) as e:
        print(f"check_robot.py: {e}".replace("\n", " "), file=sys.stderr)
        sys.exit(2)
    if a.json:
        print(json.dumps(r, indent=1))
    else:
        for name, link in r["links"].items():
            kinds = ", ".join(f"{n} {k}" for k, n in sorted(link["geoms"].items()))
            print(f"{name}: {link['vertices']} vertices, enclosed {link['enclosed']:.6f} ({kinds or 'no geoms'})")
        print(f"worst_enclosed {r['worst_enclosed']}, new_mesh_collisions {r['new_mesh_collisions']}, "
              f"new geoms {r['new_geoms']}, steps {'ok' if r['steps'] else 'NOT finite'}, "
              f"bodies placed within {r['body_offset']:.2g} and {r['body_angle']:.2g} rad")
        if r["kept"]:
            k = r["kept"]
            print("kept: " + ", ".join(f"{n} {w}" for w, n in k.items())
                  + ("" if not r["kept_failures"] else "; FAILED: " + "; ".join(r["kept_failures"])))
    placed = r["body_offset"] <= PLACE_TOL and r["body_angle"] <= PLACE_TOL
    ok = (r["links"] and r["worst_enclosed"] >= 1.0 and r["new_mesh_collisions"] == 0 and r["steps"]
          and placed and not r["kept_failures"])
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
