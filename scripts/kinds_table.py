#!/usr/bin/env python3
"""Markdown tables from scripts/bench_kinds.sh's results.jsonl (standard library only).

    python3 scripts/kinds_table.py OUT/results.jsonl
"""
import json
import statistics
import sys
from collections import defaultdict

rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
by = defaultdict(dict)
for r in rows:
    by[(r["mesh"], r["k"])][r["config"]] = r
meshes = sorted({r["mesh"] for r in rows})
configs = ["--bv ellipsoid", "--bv obb", "--bv sphere", "--bv capsule", "--bv cylinder",
           "--target parry", "--target mujoco", "--bv hull"]
med = statistics.median

print("| config | k | median TOV | median protrusion | median floats | median s | all enclosed |")
print("|---|---:|---:|---:|---:|---:|---|")
for c in configs:
    for k in (8, 16, 32):
        rs = [by[(m, k)][c] for m in meshes if c in by[(m, k)]]
        if not rs:
            continue
        print(f"| `{c}` | {k} | {med(r['tov'] for r in rs):.3f} | "
              f"{med(r['protrusion'] for r in rs):.4f} | {med(r['floats'] for r in rs):.0f} | "
              f"{med(r['seconds'] for r in rs):.2f} | "
              f"{'yes' if all(r['coverage'] == 1.0 for r in rs) else 'no'} ({len(rs)} meshes) |")

print()
print("Per mesh at k = 16, TOV relative to ellipsoids only:")
print()
print("| mesh | ellipsoid TOV | parry | mujoco | parry shapes |")
print("|---|---:|---:|---:|---|")
ratios = defaultdict(list)
for m in meshes:
    d = by[(m, 16)]
    if "--bv ellipsoid" not in d:
        continue
    e = d["--bv ellipsoid"]["tov"]
    cells = []
    for c in ("--target parry", "--target mujoco"):
        if c in d:
            ratios[c].append(d[c]["tov"] / e)
            cells.append(f"{d[c]['tov']:.3f} ({d[c]['tov'] / e:.2f}x)")
        else:
            cells.append("")
    shapes = d.get("--target parry", {}).get("shapes", {})
    print(f"| {m} | {e:.3f} | {cells[0]} | {cells[1]} | "
          f"{', '.join(f'{n} {s}' for s, n in sorted(shapes.items()))} |")
for c, rs in ratios.items():
    print(f"\nmedian ratio {c}: {med(rs):.2f}x")

print()
print("Hulls at CoACD's own part count:")
print()
print("| mesh | k | CoACD TOV / protrusion / floats / s / surface covered | V-HACD | bvseg `--bv hull` | bvseg / CoACD TOV | time ratio |")
print("|---|---:|---|---|---|---:|---:|")
hr = []
for m in meshes:
    co = by[(m, 0)].get("coacd")
    if not co:
        continue
    k = co["k_out"]
    vh = by[(m, k)].get("vhacd")
    bv = by[(m, k)].get("--bv hull (coacd k)")
    f = lambda r: (f"{r['tov']:.3f} / {r['protrusion']:.4f} / {r['floats']} / {r['seconds']:.1f} / "
                   f"{r['coverage']:.5f}") if r else ""
    ratio = bv["tov"] / co["tov"] if bv else float("nan")
    hr.append(ratio)
    tr = bv["seconds"] / co["seconds"] if bv else float("nan")
    print(f"| {m} | {k} | {f(co)} | {f(vh)} | {f(bv)} | {ratio:.2f}x | {tr:.2f} |")
if hr:
    print(f"\nmedian bvseg / CoACD TOV: {med(hr):.2f}x")
