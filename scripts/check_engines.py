"""Checks bvseg's engine outputs against its JSON volumes file: the GLB (the glTF validator's
report, made by scripts/validate_glb.mjs, and the KHR_physics_rigid_bodies colliders with their
KHR_implicit_shapes, parsed from the GLB's JSON and BIN chunks) and the MJCF (loaded and
stepped by MuJoCo's own Python package). Used by scripts/check_engines.sh, which installs
mujoco and numpy in a venv and runs this file with its Python.

    python check_engines.py VALIDATOR_REPORT.json BASE...

BASE is a path without extension: BASE.json, BASE.glb and BASE.xml are checked. Prints one
line per file, `OK` or `FAIL` with the reasons, and exits 1 if any check failed.
"""
import json
import struct
import sys
from collections import Counter

import numpy as np

REL = 1e-6  # f32 rounding, relative (glTF stores f32; sizes are rounded through f32)
HULL_TOL = 1e-5  # hull points: GLB positions + translation, relative to the mesh's diagonal
MESH_TOL = 1e-6  # MuJoCo mesh vertices (stored in f32) in world coordinates, relative to scale
AXIS_TOL = 1e-6  # 1 - |cos| between an axis and its image
STEPS = 10


def close(a, b, rel=REL, scale=None):
    """|a - b| within rel of max(|a|, |b|) (or of scale when given)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ref = scale if scale is not None else np.maximum(np.abs(a), np.abs(b))
    return bool(np.all(np.abs(a - b) <= rel * ref + 1e-300))


def quat_xyzw_matrix(q):
    x, y, z, w = q
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def parallel(u, v):
    u, v = np.asarray(u, float), np.asarray(v, float)
    c = abs(u @ v) / (np.linalg.norm(u) * np.linalg.norm(v))
    return 1 - c <= AXIS_TOL


def same_point_sets(a, b, tol):
    """Worst distance from a point of one set to the nearest of the other (both ways)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if len(a) == 0 or len(b) == 0:
        return np.inf
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    return max(d.min(axis=1).max(), d.min(axis=0).max())


class Report:
    def __init__(self):
        self.reasons = []

    def fail(self, msg):
        self.reasons.append(msg)


def read_glb(path):
    data = open(path, "rb").read()
    magic, version, total = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or total != len(data):
        raise ValueError(f"bad GLB header {magic!r} {version} {total}/{len(data)}")
    off, doc, bin_chunk = 12, None, b""
    while off < len(data):
        length, kind = struct.unpack_from("<I4s", data, off)
        chunk = data[off + 8: off + 8 + length]
        if kind == b"JSON":
            doc = json.loads(chunk)
        elif kind == b"BIN\0":
            bin_chunk = chunk
        off += 8 + length
    return doc, bin_chunk


def accessor(doc, binary, index):
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    width = {"SCALAR": 1, "VEC3": 3}[acc["type"]]
    dtype = {5126: "<f4", 5125: "<u4"}[acc["componentType"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    arr = np.frombuffer(binary, dtype=dtype, count=acc["count"] * width, offset=start)
    return arr.reshape(-1, width) if width > 1 else arr


def mesh_geometry(doc, binary, node_index):
    """Positions and triangles of a node's mesh (its primitives together)."""
    node = doc["nodes"][node_index]
    pts, tris = [], []
    for prim in doc["meshes"][node["mesh"]]["primitives"]:
        p = accessor(doc, binary, prim["attributes"]["POSITION"]).astype(float)
        i = accessor(doc, binary, prim["indices"]).reshape(-1, 3) if "indices" in prim else \
            np.arange(len(p)).reshape(-1, 3)
        tris.append(i + sum(len(q) for q in pts))
        pts.append(p)
    return np.concatenate(pts), np.concatenate(tris)


def reachable(doc):
    seen, stack = set(), list(doc["scenes"][doc.get("scene", 0)]["nodes"])
    while stack:
        n = stack.pop()
        if n not in seen:
            seen.add(n)
            stack.extend(doc["nodes"][n].get("children", []))
    return seen


def node_worlds(nodes):
    """Each node's world matrix (4x4) from the TRS or matrix of it and its parents."""
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    local = []
    for n in nodes:
        if "matrix" in n:
            local.append(np.array(n["matrix"], float).reshape(4, 4).T)
        else:
            m = np.eye(4)
            m[:3, :3] = quat_xyzw_matrix(n.get("rotation", [0, 0, 0, 1])) * np.array(
                n.get("scale", [1, 1, 1]), float)
            m[:3, 3] = n.get("translation", [0, 0, 0])
            local.append(m)
    out = {}

    def world(i):
        if i not in out:
            out[i] = local[i] if i not in parent else world(parent[i]) @ local[i]
        return out[i]
    return [world(i) for i in range(len(nodes))]


def check_glb(path, volumes, diag, validation, rep):
    if validation is None:
        rep.fail("no validator report")
    else:
        if validation["errors"]:
            errs = [m for m in validation["messages"] if m.startswith("ERROR")]
            rep.fail(f"validator: {validation['errors']} errors: " + "; ".join(errs[:3]))
    doc, binary = read_glb(path)
    nodes = doc["nodes"]
    shapes = doc.get("extensions", {}).get("KHR_implicit_shapes", {}).get("shapes", [])
    colliders = {n["name"]: i for i, n in enumerate(nodes)
                 if "KHR_physics_rigid_bodies" in n.get("extensions", {})}
    in_scene = reachable(doc)
    worlds = node_worlds(nodes)
    parent = {c: i for i, n in enumerate(nodes) for c in n.get("children", [])}
    joints = {j for skin in doc.get("skins", []) for j in skin["joints"]}
    if len(colliders) != len(volumes):
        rep.fail(f"{len(colliders)} collider nodes for {len(volumes)} volumes")
    for name, i in colliders.items():
        if "scale" in nodes[i]:
            rep.fail(f"{name} has a scale")
        if i not in in_scene:
            rep.fail(f"{name} not in the scene")
    for k, v in enumerate(volumes):
        name = f"part_{k}_collider"
        if name not in colliders:
            rep.fail(f"no {name}")
            continue
        node = nodes[colliders[name]]
        # World placement: a character's colliders hang under its joints.
        t, rot = worlds[colliders[name]][:3, 3], worlds[colliders[name]][:3, :3]
        geom = node["extensions"]["KHR_physics_rigid_bodies"]["collider"]["geometry"]
        shape = v["shape"]
        where = f"part {k} ({shape})"
        if "bone" in v and joints and parent.get(colliders[name]) not in joints:
            rep.fail(f"{where}: the collider of a volume with a bone is not under a joint")
        if shape in ("sphere", "obb", "capsule", "cylinder"):
            if not close(t, v["center"], scale=diag):
                rep.fail(f"{where}: translation {t.tolist()} != centre {v['center']}")
            if "shape" not in geom or geom.get("convexHull"):
                rep.fail(f"{where}: collider is not an implicit shape: {geom}")
                continue
            s = shapes[geom["shape"]]
            want = {"sphere": "sphere", "obb": "box", "capsule": "capsule",
                    "cylinder": "cylinder"}[shape]
            if s.get("type") != want:
                rep.fail(f"{where}: implicit shape type {s.get('type')}, want {want}")
                continue
            p = s[want]
            if shape == "sphere":
                if not close(p["radius"], v["radius"]):
                    rep.fail(f"{where}: radius {p['radius']} != {v['radius']}")
            elif shape == "obb":
                size = np.array(p["size"], float)
                if not close(size, 2 * np.array(v["radii"])):
                    rep.fail(f"{where}: size {size.tolist()} != 2*radii "
                             f"{(2 * np.array(v['radii'])).tolist()}")
                for j in range(3):
                    if not parallel(rot[:, j], v["axes"][j]):
                        rep.fail(f"{where}: local axis {j} not along axes[{j}]")
            else:
                r, h = v["radius"], v["half_length"]
                if not (close(p["radiusTop"], r) and close(p["radiusBottom"], r)):
                    rep.fail(f"{where}: radii {p['radiusTop']}/{p['radiusBottom']} != {r}")
                if shape == "capsule" and h == 0:
                    if not 0 < p["height"] <= 1e-6 * r:
                        rep.fail(f"{where}: half_length 0 but height {p['height']}")
                elif not close(p["height"], 2 * h):
                    rep.fail(f"{where}: height {p['height']} != 2*half_length {2 * h}")
                if not parallel(rot[:, 1], v["axis"]):
                    rep.fail(f"{where}: rotation does not map +Y onto axis "
                             f"({(rot[:, 1]).tolist()} vs {v['axis']})")
        elif shape in ("hull", "ellipsoid"):
            if not geom.get("convexHull") or "node" not in geom:
                rep.fail(f"{where}: not a convexHull node collider: {geom}")
                continue
            pts, tris = mesh_geometry(doc, binary, geom["node"])
            world = t + pts @ rot.T
            if shape == "hull":
                want = np.array(v["points"], float)
                d = same_point_sets(world, want, HULL_TOL * diag)
                if len(pts) != len(want) or d > HULL_TOL * diag:
                    rep.fail(f"{where}: {len(pts)} hull points vs {len(want)} in the JSON, "
                             f"worst distance {d:.3g}")
            else:
                if not close(t, v["center"], scale=diag):
                    rep.fail(f"{where}: translation {t.tolist()} != centre {v['center']}")
                # The hull must enclose the ellipsoid: per face, the ellipsoid's support in
                # the outward normal is at most the face's offset.
                c, axes, radii = np.array(v["center"]), np.array(v["axes"]), np.array(v["radii"])
                a, b, cc = world[tris[:, 0]], world[tris[:, 1]], world[tris[:, 2]]
                n = np.cross(b - a, cc - a)
                n /= np.linalg.norm(n, axis=1, keepdims=True)
                inward = np.einsum("ij,ij->i", n, c - a) > 0
                n[inward] *= -1
                support = c @ n.T + np.sqrt(((n @ axes.T) * radii) ** 2 @ np.ones(3))
                gap = np.einsum("ij,ij->i", n, a) - support
                if gap.min() < -REL * diag:
                    rep.fail(f"{where}: convex hull does not enclose the ellipsoid "
                             f"(by {-gap.min():.3g})")
        else:
            rep.fail(f"{where}: unknown shape")


def check_mjcf(path, volumes, diag, rep, mujoco):
    model = mujoco.MjModel.from_xml_path(path)
    data = mujoco.MjData(model)
    # Geom frames in the world at qpos0: a character's ragdoll has its geoms in its bones'
    # bodies, and must put them where the volumes are in the rest pose.
    mujoco.mj_forward(model, data)
    gpos, gmat = data.geom_xpos.copy(), data.geom_xmat.copy()
    for _ in range(STEPS):
        mujoco.mj_step(model, data)
    if not np.all(np.isfinite(data.qacc)) or not np.all(np.isfinite(data.geom_xpos)):
        rep.fail("non-finite state after stepping")
    warnings = [(mujoco.mjtWarning(i).name, w.number) for i, w in enumerate(data.warning)
                if w.number]
    if warnings:
        rep.fail(f"MuJoCo warnings {warnings}")
    G = mujoco.mjtGeom
    if model.ngeom != len(volumes):
        rep.fail(f"{model.ngeom} geoms for {len(volumes)} volumes")
    want_type = {"sphere": G.mjGEOM_SPHERE, "capsule": G.mjGEOM_CAPSULE,
                 "cylinder": G.mjGEOM_CYLINDER, "ellipsoid": G.mjGEOM_ELLIPSOID,
                 "obb": G.mjGEOM_BOX, "hull": G.mjGEOM_MESH}
    for k, v in enumerate(volumes):
        shape, where = v["shape"], f"part {k} ({v['shape']})"
        g = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"part_{k}")
        if g < 0:
            rep.fail(f"{where}: no geom part_{k}")
            continue
        gtype, size = model.geom_type[g], model.geom_size[g]
        pos, xmat = gpos[g], gmat[g].reshape(3, 3)
        # Without joints the body is welded to the world: after stepping, the geoms stay
        # where the model puts them.
        if model.njnt == 0 and not (close(data.geom_xpos[g], pos, scale=diag)
                                    and close(data.geom_xmat[g].reshape(3, 3), xmat, scale=1.0)):
            rep.fail(f"{where}: moved while stepping")
        want = want_type.get(shape)
        zero_capsule = shape == "capsule" and v["half_length"] == 0
        if zero_capsule and gtype == G.mjGEOM_SPHERE:
            want = G.mjGEOM_SPHERE
        if gtype != want:
            rep.fail(f"{where}: geom type {G(gtype).name}, want {G(want).name}")
            continue
        if shape != "hull" and not close(pos, v["center"], scale=diag):
            rep.fail(f"{where}: pos {pos.tolist()} != centre {v['center']}")
        if shape == "sphere" or zero_capsule and gtype == G.mjGEOM_SPHERE:
            if not close(size[0], v["radius"]):
                rep.fail(f"{where}: size {size[0]} != radius {v['radius']}")
        elif shape in ("capsule", "cylinder"):
            if not close(size[:2], [v["radius"], v["half_length"]]):
                rep.fail(f"{where}: size {size[:2].tolist()} != radius, half_length "
                         f"{[v['radius'], v['half_length']]}")
            if not parallel(xmat[:, 2], v["axis"]):
                rep.fail(f"{where}: geom Z not along axis")
        elif shape in ("ellipsoid", "obb"):
            if not close(size, v["radii"]):
                rep.fail(f"{where}: size {size.tolist()} != radii {v['radii']}")
            for j in range(3):
                if not parallel(xmat[:, j], v["axes"][j]):
                    rep.fail(f"{where}: geom axis {j} not along axes[{j}]")
        elif shape == "hull":
            m = model.geom_dataid[g]
            start, count = model.mesh_vertadr[m], model.mesh_vertnum[m]
            local = model.mesh_vert[start: start + count].astype(float)
            world = pos + local @ xmat.T
            want_pts = np.array(v["points"], float)
            d = same_point_sets(world, want_pts, MESH_TOL * diag)
            if count != len(want_pts) or d > MESH_TOL * diag:
                rep.fail(f"{where}: {count} mesh vertices vs {len(want_pts)} points, "
                         f"worst distance {d:.3g} (tolerance {MESH_TOL * diag:.3g})")


def summary(validation):
    """The validator's counts, its warnings in full (the first 3) and its infos and hints by
    code; every message is in the report file."""
    if not validation:
        return ""
    rest = Counter(m.split()[1] for m in validation["messages"]
                   if m.split()[0] in ("INFO", "HINT"))
    warnings = [m for m in validation["messages"] if m.startswith("WARNING")]
    text = (f" [validator: {validation['errors']} errors, {validation['warnings']} warnings, "
            f"{validation['infos']} infos" + (f", {validation['hints']} hints"
                                               if validation["hints"] else ""))
    if warnings:
        text += ": " + "; ".join(warnings[:3]) + (" ..." if len(warnings) > 3 else "")
    if rest:
        text += ": " + ", ".join(f"{c} x{n}" for c, n in sorted(rest.items()))
    return text + "]"


def main():
    if len(sys.argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    import mujoco

    validations = json.load(open(sys.argv[1]))
    failed = 0
    for base in sys.argv[2:]:
        doc = json.load(open(base + ".json"))
        volumes = doc["volumes"]
        diag = float(doc["metrics"]["diagonal"])
        kinds = Counter(v["shape"] for v in volumes)
        what = ", ".join(f"{n} {s}" for s, n in sorted(kinds.items()))
        for ext in ("glb", "xml"):
            path = f"{base}.{ext}"
            rep = Report()
            try:
                if ext == "glb":
                    validation = validations.get(path)
                    check_glb(path, volumes, diag, validation, rep)
                    extra = summary(validation)
                else:
                    check_mjcf(path, volumes, diag, rep, mujoco)
                    extra = ""
            except Exception as e:  # a file the client cannot load is a failure, not a crash
                rep.fail(f"{type(e).__name__}: {str(e).strip()[:300]}")
                extra = ""
            name = path.rsplit("/", 1)[-1]
            if rep.reasons:
                failed += 1
                shown = rep.reasons[:4] + ([f"... {len(rep.reasons) - 4} more"]
                                           if len(rep.reasons) > 4 else [])
                print(f"FAIL {name} ({what}): " + "; ".join(shown) + extra)
            else:
                print(f"OK   {name} ({what}){extra}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
