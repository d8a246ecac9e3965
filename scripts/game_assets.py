#!/usr/bin/env python3
"""The game-asset table: bvseg's default run on low-poly GLB assets, judged by the shared tools.

    python3 scripts/game_assets.py [DIR ...] [--bvseg BIN] [--baseline BIN] [--coacd] [--md OUT.md]

DIR defaults to ../shared/assets/kenney (or $BVSEG_SHARED/assets/kenney). For each GLB: the
volume count, the judged protrusion (bveval.py, fraction of the diagonal), the share of vertices
and surface points enclosed, the wall time, and for skinned files the worst pose's enclosure
(bvpose.py). `--baseline BIN` adds another bvseg binary's figures on the same files (an A/B
run); `--coacd` adds CoACD's (peers.py, default threshold). Medians at the end. Needs the shared
tools' venv ($BVTOOLS_VENV, ../shared/tools/.venv or /work/bvtools-venv). Standard library only.
"""
import argparse, json, os, statistics, subprocess, sys, tempfile, time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("BVSEG_SHARED", ROOT.parent / "shared"))


def venv_python():
    for v in [os.environ.get("BVTOOLS_VENV"), SHARED / "tools/.venv", "/work/bvtools-venv"]:
        if v and (Path(v) / "bin/python").exists():
            return str(Path(v) / "bin/python")
    sys.exit("game_assets.py: no venv for the shared tools: run `bash ../shared/tools/setup.sh`")


def judge(py, mesh, volumes):
    out = subprocess.run([py, str(SHARED / "tools/bveval.py"), str(mesh), str(volumes), "--json",
                          "--boundary-points", "30000", "--surface-points", "30000"],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def pose(py, mesh, volumes):
    out = subprocess.run([py, str(SHARED / "tools/bvpose.py"), str(mesh), str(volumes), "--json",
                          "--poses", "8"], capture_output=True, text=True)
    if out.returncode != 0:
        return None
    d = json.loads(out.stdout)
    return min(d["worst_vertices"], d["worst_surface"])


def run_bvseg(binary, mesh, out):
    start = time.perf_counter()
    subprocess.run([binary, "segment", str(mesh), "-o", str(out), "-q"], check=True,
                   capture_output=True)
    return time.perf_counter() - start


def row(py, name, mesh, volumes, seconds):
    d = judge(py, mesh, volumes)
    posed = pose(py, mesh, volumes) if any(
        "bone" in v for v in json.load(open(volumes))["volumes"]) else None
    return {"asset": name, "volumes": d["k"], "protrusion": d["protrusion_max_rel"],
            "vertices": d["coverage_vertices"], "surface": d["coverage_surface"],
            "seconds": seconds, "posed": posed}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="*", type=Path)
    ap.add_argument("--bvseg", default=str(ROOT / "target/release/bvseg"))
    ap.add_argument("--baseline")
    ap.add_argument("--coacd", action="store_true")
    ap.add_argument("--md", type=Path)
    a = ap.parse_args()
    py = venv_python()
    dirs = a.dirs or [SHARED / "assets/kenney"]
    meshes = sorted(m for d in dirs for m in d.glob("*.glb"))
    if not meshes:
        sys.exit("game_assets.py: no .glb files found")
    tools = [("bvseg", a.bvseg)] + ([("baseline", a.baseline)] if a.baseline else [])
    rows = {t: [] for t, _ in tools}
    if a.coacd:
        rows["coacd"] = []
    tmp = Path(tempfile.mkdtemp(prefix="bvseg-assets-"))
    for m in meshes:
        for t, binary in tools:
            out = tmp / f"{t}-{m.stem}.json"
            rows[t].append(row(py, m.stem, m, out, run_bvseg(binary, m, out)))
        if a.coacd:
            out = tmp / f"coacd-{m.stem}.json"
            start = time.perf_counter()
            subprocess.run([py, str(SHARED / "tools/peers.py"), str(m), "--k", "8", "--method",
                            "coacd", "--bv", "hull", "--out", str(out)], check=True,
                           capture_output=True)
            rows["coacd"].append(row(py, m.stem, m, out, time.perf_counter() - start))
        r = rows["bvseg"][-1]
        print(f"{m.stem}: {r['volumes']} volumes, protrusion {r['protrusion']:.4f}, "
              f"{r['seconds']:.2f} s", file=sys.stderr)
    lines = []
    for t, rs in rows.items():
        lines += [f"### {t}", "",
                  "| asset | volumes | protrusion | vertices | surface | posed | seconds |",
                  "|---|---:|---:|---:|---:|---:|---:|"]
        for r in rs:
            posed = "" if r["posed"] is None else f"{r['posed']:.4f}"
            lines.append(f"| {r['asset']} | {r['volumes']} | {r['protrusion']:.4f} | "
                         f"{r['vertices']:.4f} | {r['surface']:.4f} | {posed} | {r['seconds']:.2f} |")
        med = lambda k: statistics.median(r[k] for r in rs)
        within = sum(r["protrusion"] <= 0.05 for r in rs)
        lines += ["", f"{t}: median {med('volumes'):g} volumes, median protrusion "
                  f"{med('protrusion'):.4f}, protrusion <= 0.05 on {within} of {len(rs)}, "
                  f"every vertex enclosed on {sum(r['vertices'] == 1.0 for r in rs)}, "
                  f"median {med('seconds'):.2f} s", ""]
    text = "\n".join(lines)
    print(text)
    if a.md:
        a.md.write_text(text + "\n")


if __name__ == "__main__":
    main()
