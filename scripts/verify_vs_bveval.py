#!/usr/bin/env python3
"""verify_vs_bveval: compare `bvseg verify` with the independent judge bveval.py.

For every mesh of shared/meshes: `bvseg segment MESH -o OUT.json` (defaults), then
`bvseg verify MESH OUT.json --json` and `bveval.py MESH OUT.json --json` (both at their
default 2e6-point grids, seed 0), and prints a Markdown table of TOV and MOV from both with
their standard errors, the difference in units of the combined standard error, and the
enclosure verdicts.

    python3 scripts/verify_vs_bveval.py [--outdir target/verify-cmp] [--meshes bunny,horse]

Environment: BVTOOLS_VENV (default $BVSEG_SHARED/tools/.venv), BVSEG_SHARED (default ../shared).
Run `cargo build --release --bin bvseg` first.
"""
import argparse
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--outdir", default=os.path.join(ROOT, "target", "verify-cmp"))
    ap.add_argument("--meshes", default="")
    a = ap.parse_args()
    shared = os.environ.get("BVSEG_SHARED", os.path.join(ROOT, "..", "shared"))
    venv = os.environ.get("BVTOOLS_VENV", os.path.join(shared, "tools", ".venv"))
    py = os.path.join(venv, "bin", "python")
    bveval = os.path.join(shared, "tools", "bveval.py")
    bvseg = os.path.join(ROOT, "target", "release", "bvseg")
    mdir = os.path.join(shared, "meshes")
    names = sorted(f[:-4] for f in os.listdir(mdir) if f.endswith(".obj"))
    if a.meshes:
        names = [n for n in names if n in a.meshes.split(",")]
    os.makedirs(a.outdir, exist_ok=True)
    print("| mesh | k | verify TOV ± SE | bveval TOV ± SE | z | verify MOV ± SE (#) | bveval MOV ± SE (#) | z | verify enclosed | bveval cover v/s, escape |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|---|")
    zs = []
    for n in names:
        mesh = os.path.join(mdir, n + ".obj")
        out = os.path.join(a.outdir, n + ".json")
        subprocess.run([bvseg, "segment", "-q", mesh, "-o", out], check=True, stdout=subprocess.DEVNULL)
        p = subprocess.run([bvseg, "verify", mesh, out, "--json"], capture_output=True, text=True)
        if p.returncode not in (0, 1):
            print(f"| {n} | verify failed: {p.stderr.strip()} |")
            continue
        v = json.loads(p.stdout)
        q = subprocess.run([py, bveval, mesh, out, "--json"], capture_output=True, text=True, check=True)
        b = json.loads(q.stdout)

        def z(x, sx, y, sy):
            s = math.hypot(sx, sy)
            return (x - y) / s if s > 0 else (0.0 if x == y else math.inf)
        zt = z(v["tov"], v["tov_se"], b["tov"], b["tov_se"])
        zm = z(v["mov"], v["mov_se"], b["mov"], b["mov_se"])
        zs += [zt, zm]
        print(f"| {n} | {v['k']} | {v['tov']:.4f} ± {v['tov_se']:.4f} | {b['tov']:.4f} ± {b['tov_se']:.4f} | "
              f"{zt:+.2f} | {v['mov']:.4f} ± {v['mov_se']:.4f} ({v['mov_index']}) | "
              f"{b['mov']:.4f} ± {b['mov_se']:.4f} ({b['mov_index']}) | {zm:+.2f} | "
              f"{'yes' if v['enclosed'] else 'NO'} ({v['triangles_unenclosed']} escape) | "
              f"{100 * b['coverage_vertices']:.2f} % / {100 * b['coverage_surface']:.2f} %, {b['max_escape_rel']:.2g} |")
        sys.stdout.flush()
    if zs:
        within = sum(abs(x) <= 2 for x in zs)
        print(f"\n{within} of {len(zs)} differences within 2 combined SE; max |z| = {max(abs(x) for x in zs):.2f}")


if __name__ == "__main__":
    main()
