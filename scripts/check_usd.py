#!/usr/bin/env python3
"""Checks bvseg's USD outputs with Pixar's usd-core (the `pxr` package from PyPI).

    check_usd.py FILE.usda[=VOLUMES.json] ...
    check_usd.py --robot ORIGINAL.xml|.urdf FILE.usda     (needs mujoco and ../shared/tools)

Each file must open with Usd.Stage.Open and have a defaultPrim, an upAxis and a positive
metersPerUnit; every Cube, Sphere, Capsule, Cylinder and Mesh prim under the default prim must
have UsdPhysics.CollisionAPI and purpose "guide"; a Mesh must have MeshCollisionAPI with
physics:approximation "convexHull", at most 64 points and faces of 3 points over them; a
Sphere, Capsule or Cylinder must have no non-uniform scale in its world transform. With
`=VOLUMES.json` (the same run's bvseg.volumes document), the file must have one collider per
volume. Prints one line per file, and exits 1 if any failed.

With --robot, the USD of `bvseg robot` is also placed against the original robot: MuJoCo
loads ORIGINAL at qpos0, and every vertex of its colliding mesh geoms, in world coordinates,
must lie inside the USD colliders (placed by the shared judge bvusd.py's own reader).
"""
import json
import os
import sys

MAX_POINTS = 64
KINDS = ("Cube", "Sphere", "Capsule", "Cylinder", "Mesh")


def check(path, volumes=None):
    from pxr import Usd, UsdGeom, UsdPhysics

    problems = []
    try:
        stage = Usd.Stage.Open(path)
    except Exception as e:  # noqa: BLE001  (pxr raises Tf.ErrorException on a parse error)
        return 0, [f"usd-core could not open {path}: {str(e).strip().splitlines()[-1]}"]
    if stage is None:
        return 0, [f"usd-core could not open {path}"]
    root = stage.GetDefaultPrim()
    if not root:
        return 0, ["no defaultPrim"]
    if UsdGeom.GetStageUpAxis(stage) not in ("Y", "Z"):
        problems.append(f"upAxis {UsdGeom.GetStageUpAxis(stage)!r}")
    if not UsdGeom.GetStageMetersPerUnit(stage) > 0:
        problems.append("metersPerUnit not above 0")
    cache = UsdGeom.XformCache()
    colliders = 0
    for prim in Usd.PrimRange(root):
        kind = prim.GetTypeName()
        if kind not in KINDS:
            continue
        where = f"{prim.GetPath()} ({kind})"
        if not prim.HasAPI(UsdPhysics.CollisionAPI):
            problems.append(f"{where}: no PhysicsCollisionAPI")
            continue
        colliders += 1
        if UsdGeom.Imageable(prim).GetPurposeAttr().Get() != UsdGeom.Tokens.guide:
            problems.append(f"{where}: purpose is not guide")
        m = cache.GetLocalToWorldTransform(prim)
        scales = [m.GetRow3(i).GetLength() for i in range(3)]
        if kind in ("Sphere", "Capsule", "Cylinder") and max(scales) - min(scales) > 1e-6 * max(scales):
            problems.append(f"{where}: non-uniform scale {scales}")
        if kind == "Mesh":
            if not prim.HasAPI(UsdPhysics.MeshCollisionAPI):
                problems.append(f"{where}: no PhysicsMeshCollisionAPI")
            elif UsdPhysics.MeshCollisionAPI(prim).GetApproximationAttr().Get() != "convexHull":
                problems.append(f"{where}: approximation is not convexHull")
            mesh = UsdGeom.Mesh(prim)
            points = mesh.GetPointsAttr().Get() or []
            counts = mesh.GetFaceVertexCountsAttr().Get() or []
            indices = mesh.GetFaceVertexIndicesAttr().Get() or []
            if not 4 <= len(points) <= MAX_POINTS:
                problems.append(f"{where}: {len(points)} points (4 to {MAX_POINTS} allowed)")
            if set(counts) != {3} or len(indices) != 3 * len(counts) or any(
                not 0 <= i < len(points) for i in indices
            ):
                problems.append(f"{where}: faces are not triangles over its points")
    if volumes is not None:
        with open(volumes) as f:
            n = len(json.load(f)["volumes"])
        if n != colliders:
            problems.append(f"{colliders} colliders for {n} volumes")
    if colliders == 0:
        problems.append("no collider")
    return colliders, problems


def robot(original, path):
    """Vertices of ORIGINAL's colliding mesh geoms at qpos0 that the USD colliders miss."""
    import mujoco
    import numpy as np

    here = os.path.dirname(os.path.abspath(__file__))
    shared = os.environ.get("BVSEG_SHARED", os.path.join(here, "..", "..", "shared"))
    sys.path.insert(0, os.path.join(shared, "tools"))
    import bvusd  # the shared judge's reader: every collider with its full transform

    model = mujoco.MjModel.from_xml_path(original)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    points = []
    for g in range(model.ngeom):
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            continue
        mesh = model.geom_dataid[g]
        a, n = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        rotation = data.geom_xmat[g].reshape(3, 3)
        points.append(model.mesh_vert[a : a + n] @ rotation.T + data.geom_xpos[g])
    if not points:
        return 0, 0, ["the original has no colliding mesh"]
    points = np.concatenate(points)
    colliders, bad, _, _ = bvusd.colliders(path)
    tol = bvusd.EPS * max(float(np.linalg.norm(np.ptp(points, axis=0))), 1.0)
    inside = np.zeros(len(points), dtype=bool)
    for c in colliders:
        inside |= bvusd.inside(c, points, tol)
    missed = int((~inside).sum())
    return len(points), missed, bad


def main():
    args = sys.argv[1:]
    if not args:
        print(__doc__, file=sys.stderr)
        return 2
    if args[0] == "--robot":
        if len(args) != 3:
            print("usage: check_usd.py --robot ORIGINAL FILE.usda", file=sys.stderr)
            return 2
        n, missed, bad = robot(args[1], args[2])
        ok = n > 0 and missed == 0 and not bad
        print(f"{'OK' if ok else 'FAIL'} {args[2]} against {args[1]} at qpos0: "
              f"{n - missed} of {n} mesh vertices inside{'; ' + '; '.join(bad) if bad else ''}")
        return 0 if ok else 1
    failed = False
    for arg in args:
        path, _, volumes = arg.partition("=")
        colliders, problems = check(path, volumes or None)
        if problems:
            failed = True
            print(f"FAIL {path}: {colliders} colliders; " + "; ".join(problems[:10]))
        else:
            print(f"OK {path}: {colliders} colliders, usd-core opens it, CollisionAPI on each")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
