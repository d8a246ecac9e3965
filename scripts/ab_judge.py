#!/usr/bin/env python3
"""Judge two or more bvseg binaries on the shared meshes: the shared judge's medians of TOV and
protrusion (max, of the diagonal), and the median wall time, per binary, for one set of
`segment` arguments. For changes that change results (the brief's rule: keep what is not
worse on the median), without the whole of BENCHMARKS.md. Judged figures are cached by the
bytes judged, in the cache benchmarks.py keeps, so an unchanged output costs no judging.

    python3 scripts/ab_judge.py /tmp/base/target/release/bvseg target/release/bvseg
    python3 scripts/ab_judge.py --args "--sampling adaptive" OLD NEW
    python3 scripts/ab_judge.py --meshes human_1,hand_1 OLD NEW

Needs what benchmarks.py needs (../shared or $BVSEG_SHARED, the tools' venv). Standard
library only.
"""
import argparse, shlex, statistics, sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from benchmarks import SHARED, Bench, med  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("bins", nargs="+", help="bvseg binaries; the first is the reference")
    ap.add_argument("--args", default="", help="extra `bvseg segment` arguments")
    ap.add_argument("--meshes", help="comma-separated mesh names (default: every shared mesh)")
    a = ap.parse_args()
    meshes = sorted((SHARED / "meshes").glob("*.obj"))
    if a.meshes:
        meshes = [SHARED / "meshes" / f"{m}.obj" for m in a.meshes.split(",")]
    bench = Bench(argparse.Namespace(quick=False, bvseg=None))
    rows = [[] for _ in a.bins]
    for mesh in meshes:
        line = [f"{mesh.stem:12}"]
        for i, b in enumerate(a.bins):
            bench.bvseg = Path(b)
            r = bench.bvseg_run(mesh, f"ab{i}", shlex.split(a.args))
            rows[i].append(r)
            line.append(f"k {r['k']:3} TOV {r['tov']:.4f} pmax {r['pmax']:.4f} {r['s']:5.2f} s")
        print(" | ".join(line), flush=True)
    print()
    for i, (b, rs) in enumerate(zip(a.bins, rows)):
        print(f"{i} {b}: median TOV {med(rs, 'tov'):.4f}, protrusion max {med(rs, 'pmax'):.4f},"
              f" k {statistics.median(r['k'] for r in rs)}, {statistics.median(r['s'] for r in rs):.2f} s")
    ref = rows[0]
    for i, rs in enumerate(rows[1:], 1):
        better = sum(r["tov"] < q["tov"] for r, q in zip(rs, ref))
        worse = sum(r["tov"] > q["tov"] for r, q in zip(rs, ref))
        print(f"{i} against 0: TOV lower on {better}, higher on {worse} of {len(ref)} meshes")


if __name__ == "__main__":
    main()
