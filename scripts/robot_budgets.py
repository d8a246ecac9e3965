#!/usr/bin/env python3
"""Measures `bvseg robot`'s part budgets on a URDF robot: for each budget, the primitives it
gives (in all, and the most on one link), whether they enclose every link's collision mesh
(the shared judge bvrobot.py), and how tight they are (the shared judge bveval.py on each
link's collision mesh, placed in the link's frame, against the link's volumes: the union's
outside volume over the mesh's, TOV, and the largest protrusion over the mesh's diagonal);
prints a Markdown table, one row per budget, with the median and worst link.

    python robot_budgets.py BVSEG ROBOT.urdf [--per-link 3 4 5 6 8] [--total 40 60]
                            [--tools ../shared/tools] [--grid 500000] [--out DIR]

Needs numpy and trimesh (the judges' own needs). docs/robots.md quotes its table.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np


def rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def link_meshes(urdf):
    """{link: trimesh of its collision meshes in the link's frame}."""
    import trimesh
    root = ET.parse(urdf).getroot()
    base = os.path.dirname(os.path.abspath(urdf))
    out = {}
    for link in root.findall("link"):
        parts = []
        for col in link.findall("collision"):
            mesh = col.find("geometry/mesh")
            if mesh is None:
                continue
            o = col.find("origin")
            xyz = np.array([float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()])
            rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
            scale = np.array([float(v) for v in mesh.get("scale", "1 1 1").split()])
            m = trimesh.load(os.path.join(base, mesh.get("filename")), force="mesh", process=False)
            v = (np.asarray(m.vertices) * scale) @ rpy_matrix(*rpy).T + xyz
            parts.append(trimesh.Trimesh(v, np.asarray(m.faces), process=False))
        if parts:
            out[link.get("name")] = trimesh.util.concatenate(parts)
    return out


def measure(args, tag, options, meshes):
    out = os.path.join(args.out, tag)
    subprocess.run([args.bvseg, "robot", args.robot, "-o", out, "-q", *options], check=True)
    manifest = json.load(open(os.path.join(out, "manifest.json")))
    new_urdf = next(os.path.join(out, f) for f in manifest["files"] if f.endswith(".urdf"))
    judge = subprocess.run([sys.executable, os.path.join(args.tools, "bvrobot.py"), args.robot, new_urdf,
                            "--json"], capture_output=True, text=True, check=True)
    enclosed = json.loads(judge.stdout)
    worst = min(l["enclosed"] for l in enclosed["links"].values()) if isinstance(enclosed.get("links"), dict) \
        else enclosed.get("worst_enclosed")
    tov, prot, counts = [], [], []
    for link in manifest["links"]:
        if link["volumes"] is None:
            continue
        counts.append(link["parts"])
        with tempfile.NamedTemporaryFile(suffix=".obj", delete=False) as f:
            meshes[link["name"]].export(f.name)
        try:
            r = subprocess.run([sys.executable, os.path.join(args.tools, "bveval.py"), f.name,
                                os.path.join(out, link["volumes"]), "--json", "--grid", str(args.grid)],
                               capture_output=True, text=True, check=True)
        finally:
            os.unlink(f.name)
        e = json.loads(r.stdout)
        tov.append(e["tov"])
        prot.append(e["protrusion_max_rel"])
    return {"tag": tag, "parts": manifest["parts"], "most": max(counts), "worst_enclosed": worst,
            "tov_median": float(np.median(tov)), "tov_max": max(tov),
            "prot_median": float(np.median(prot)), "prot_max": max(prot)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("bvseg")
    ap.add_argument("robot")
    ap.add_argument("--per-link", type=int, nargs="*", default=[3, 4, 5, 6, 8])
    ap.add_argument("--total", type=int, nargs="*", default=[])
    ap.add_argument("--tools", default=os.path.join(os.path.dirname(__file__), "..", "..", "shared", "tools"))
    ap.add_argument("--grid", type=int, default=500_000)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    a.out = a.out or tempfile.mkdtemp(prefix="robot_budgets_")
    meshes = link_meshes(a.robot)
    rows = [measure(a, f"--max-parts {n}", ["--max-parts", str(n)], meshes) for n in a.per_link]
    rows += [measure(a, f"--total-parts {n}", ["--total-parts", str(n)], meshes) for n in a.total]
    print("| budget | primitives | most on a link | worst link enclosed | TOV median | TOV worst | "
          "protrusion median | protrusion worst |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| `{r['tag']}` | {r['parts']} | {r['most']} | {r['worst_enclosed']:.4f} | {r['tov_median']:.3f} | "
              f"{r['tov_max']:.3f} | {r['prot_median']:.4f} | {r['prot_max']:.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
