#!/usr/bin/env python3
"""Regenerates BENCHMARKS.md: bvseg against CoACD and V-HACD, judged by the shared tools.

    python3 scripts/benchmarks.py            # every shared mesh; writes BENCHMARKS.md
    python3 scripts/benchmarks.py --quick    # three bundled meshes, small grids (CI)
    python3 scripts/benchmarks.py --page     # also the browser page against the native CLI

Needs the shared tools next to the repository (../shared, or $BVSEG_SHARED) and their venv
(`bash ../shared/tools/setup.sh`; $BVTOOLS_VENV, default ../shared/tools/.venv, then
/work/bvtools-venv). Every output is judged by ../shared/tools/bveval.py. The peers' outputs
are cached in target/benchmarks/cache (they do not change with bvseg); bvseg runs are not.
Standard library only.
"""
import argparse, hashlib, json, math, os, platform, re, statistics, subprocess, sys, time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("BVSEG_SHARED", ROOT.parent / "shared"))
TARGETS = ["gltf", "parry", "physx", "mujoco", "usd"]
KINDS = ["ellipsoid", "obb", "sphere", "capsule", "cylinder", "hull", "default"]
KS = [4, 8, 16, 32, 64]
SAMPLES = [10_000, 100_000, 1_000_000, 5_000_000]
QUICK_MESHES = ["bunny", "spot", "fourleg_2"]
# The paper's section 6 (skeleton-seeded start, adaptive sampling) against the plain start on a
# regular lattice: what each start costs and gives, on a human, a hand and a four-legged animal.
STARTS = {"default": [], "--skeleton none --sampling regular": ["--skeleton", "none", "--sampling", "regular"],
          "--sampling adaptive": ["--sampling", "adaptive"], "--skeleton auto": ["--skeleton", "auto"],
          "--skeleton auto --sampling adaptive": ["--skeleton", "auto", "--sampling", "adaptive"]}
SECTION6_MESHES = ["human_1", "hand_1", "fourleg_1"]


def venv_python():
    for v in [os.environ.get("BVTOOLS_VENV"), SHARED / "tools/.venv", "/work/bvtools-venv"]:
        if v and (Path(v) / "bin/python").exists():
            return str(Path(v) / "bin/python")
    sys.exit("benchmarks.py: no venv for the shared tools: run `bash ../shared/tools/setup.sh`")


def run(cmd, timeout=3600, env=None):
    """Runs `cmd` (with `env` added to the environment); returns (wall seconds, stdout). Fails
    loudly."""
    t0 = time.perf_counter()
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True, timeout=timeout,
                       env={**os.environ, **(env or {})})
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} exited {p.returncode}: {p.stderr.strip()[-400:]}")
    return wall, p.stdout


def peak_mb(cmd):
    """Wall seconds and peak resident MB of `cmd`, by GNU time when installed."""
    if Path("/usr/bin/time").exists():
        t0 = time.perf_counter()
        p = subprocess.run(["/usr/bin/time", "-f", "%M"] + [str(c) for c in cmd],
                           capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if p.returncode != 0:
            raise RuntimeError(p.stderr.strip()[-400:])
        return wall, int(p.stderr.strip().splitlines()[-1]) / 1024
    return run(cmd)[0], float("nan")


class Bench:
    def __init__(self, a):
        self.a, self.py = a, venv_python()
        self.out = ROOT / "target/benchmarks"
        self.cache = self.out / "cache"
        self.cache.mkdir(parents=True, exist_ok=True)
        self.bvseg = Path(a.bvseg) if a.bvseg else ROOT / "target/release/bvseg"
        self.grid = ["--grid", "200000", "--surface-points", "20000", "--boundary-points", "20000"] \
            if a.quick else ["--grid", "1000000", "--surface-points", "100000"]

    def judge(self, mesh, vol):
        """The judge's figures, cached by the bytes judged (bvseg's outputs are deterministic);
        `None` when the judge fails (it runs out of memory on hulls of thousands of faces)."""
        key = hashlib.sha256(Path(mesh).read_bytes() + Path(vol).read_bytes()
                             + " ".join(self.grid).encode()).hexdigest()[:24]
        hit = self.cache / f"judge.{key}.json"
        if not hit.exists():
            try:
                _, out = run([self.py, SHARED / "tools/bveval.py", mesh, vol, "--json", "--seed", "0"] + self.grid)
                hit.write_text(out)
            except RuntimeError as e:
                print(f"judge failed on {vol}: {str(e)[-200:]}", file=sys.stderr)
                hit.write_text("null")
        return json.loads(hit.read_text())

    def bvseg_run(self, mesh, name, args):
        vol = self.out / f"{Path(mesh).stem}.{name}.json"
        wall, _ = run([self.bvseg, "segment", mesh, "-q", "-o", vol] + args)
        return self.record(mesh, name, vol, wall)

    def peer(self, mesh, method, k):
        digest = hashlib.sha256(Path(mesh).read_bytes()).hexdigest()[:16]
        vol = self.cache / f"{Path(mesh).stem}.{digest}.{method}.{k}.json"
        meta = vol.with_suffix(".time")
        if not vol.exists():
            wall, _ = run([self.py, SHARED / "tools/peers.py", mesh, "--method", method, "--bv", "hull",
                           "--k", k, "--out", vol])
            meta.write_text(f"{wall}")
        return self.record(mesh, method, vol, float(meta.read_text()))

    def record(self, mesh, name, vol, wall):
        j = self.judge(mesh, vol)
        if j is None:
            n = len(json.loads(Path(vol).read_text())["volumes"])
            return {"mesh": Path(mesh).stem, "run": name, "k": n, "tov": NAN, "pmax": NAN, "pmean": NAN,
                    "surface": NAN, "escape": NAN, "floats": NAN, "s": wall}
        return {"mesh": Path(mesh).stem, "run": name, "k": j["k"], "tov": j["tov"],
                "pmax": j["protrusion_max_rel"], "pmean": j["protrusion_mean_rel"],
                "surface": j["coverage_surface"], "escape": j["max_escape_rel"], "floats": j["floats"], "s": wall}

    def quality(self, meshes):
        rows = []
        for m in meshes:
            print(f"quality: {Path(m).stem}", file=sys.stderr)
            rows.append(self.bvseg_run(m, "bvseg", []))
            for name in ("--sampling adaptive", "--skeleton auto"):
                rows.append(self.bvseg_run(m, name, STARTS[name]))
            for t in TARGETS:
                rows.append(self.bvseg_run(m, f"--target {t}", ["--target", t]))
            co = self.peer(m, "coacd", 1)
            rows.append(co)
            k = co["k"]
            rows.append(self.bvseg_run(m, "--bv hull", ["--bv", "hull", "--max-hull-vertices", "255",
                                                       "--k", str(k)]))
            rows.append(self.peer(m, "vhacd", k))
        return rows

    def kinds(self, meshes):
        """Judged TOV against k for each kind, median over `meshes`."""
        by = {}
        for kind in KINDS:
            for k in KS:
                tovs = []
                for m in meshes:
                    args = ["--k", str(k)] + ([] if kind == "default" else ["--bv", kind])
                    tovs.append(self.bvseg_run(m, f"{kind}-{k}", args)["tov"])
                by[(kind, k)] = med([{"tov": t} for t in tovs], "tov")
                print(f"kinds: {kind} k={k} TOV {by[(kind, k)]:.3f}", file=sys.stderr)
        return by

    def starts(self, meshes, rounds):
        """Each start of STARTS on each mesh, `rounds` times alternating; median times."""
        rows = []
        for m in meshes:
            walls = {n: [] for n in STARTS}
            for _ in range(rounds):
                for n, args in STARTS.items():
                    walls[n].append(run([self.bvseg, "segment", m, "-q", "-o", self.out / "start.json"] + args)[0])
            for n, args in STARTS.items():
                r = self.bvseg_run(m, n, args)
                r["s"] = statistics.median(walls[n])
                rows.append(r)
                print(f"starts: {Path(m).stem} {n}: {r['s']:.2f} s, TOV {r['tov']:.3f}", file=sys.stderr)
        return rows

    def speed(self, mesh, samples):
        rows = []
        for n in samples:
            vol = self.out / f"speed.{n}.json"
            wall, mb = peak_mb([self.bvseg, "segment", mesh, "-q", "--samples", n, "--max-samples",
                                max(n, 5_000_000), "--k", "64", "-o", vol])
            rows.append({"n": n, "s": wall, "mb": mb})
            print(f"speed: {n} samples {wall:.2f} s {mb:.0f} MB", file=sys.stderr)
        return rows

    def page(self):
        """The page's run of spot (web/tests/pagebench.mjs) and the native CLI's best of 3."""
        if not (ROOT / "web/dist/index.html").exists():
            subprocess.run(["bash", ROOT / "web/build.sh"], check=True)
        # The page's job: the volumes, without the hierarchy (which only the JSON document
        # carries: the page builds it when the user exports one). So no output file here.
        native = min(run([self.bvseg, "segment", ROOT / "assets/meshes/spot.obj", "-q"])[0]
                     for _ in range(3))
        pages = {}
        # Each pagebench run's median lines, as `LABEL: isolated X s, plain Y s`; a user's first
        # run is Run clicked 3 s after the page shows it, once the threaded page has warmed the
        # core up (which it does only without autorun).
        # `shown`: from the click to the result on the screen, what the user waits.
        for env, lines in (({"AGAIN": "1"}, (("median run:", "first run"), ("median later run:", "later run"),
                                             ("median click to result shown:", "later run, shown"))),
                           ({"CLICK": "3", "PAGES": "isolated"},
                            (("median run:", "first run clicked after 3 s"),
                             ("median click to result shown:", "first run clicked after 3 s, shown")))):
            _, out = run(["node", ROOT / "web/tests/pagebench.mjs", "3", "spot"], env=env)
            for label, name in lines:
                line = next(l for l in out.splitlines() if l.startswith(label))
                for k, v in re.findall(r"(\w+) ([\d.]+) s", line):
                    pages[f"{k}, {name}"] = float(v)
        return native, pages


NAN = float("nan")


def med(rows, key):
    """The median of `key` over the rows the judge measured (NaN: it failed)."""
    xs = [r[key] for r in rows if not math.isnan(r[key])]
    return statistics.median(xs) if xs else NAN


def svg_plot(path, title, xlabel, ylabel, series, logx=False, logy=False):
    """A line chart of `series` ({name: [(x, y)]}) as a small standalone SVG."""
    W, H, L, B = 560, 340, 60, 44
    f = (lambda v: math.log10(v)) if logx else (lambda v: v)
    g = (lambda v: math.log10(max(v, 1e-9))) if logy else (lambda v: v)
    xs = [f(x) for s in series.values() for x, _ in s]
    ys = [g(y) for s in series.values() for _, y in s]
    x0, x1, y0 = min(xs), max(xs), min(ys) if logy else min(min(ys), 0)
    y1 = max(ys) + 0.05 * (max(ys) - y0)
    px = lambda x: L + (f(x) - x0) / ((x1 - x0) or 1) * (W - L - 130)
    py = lambda y: H - B - (g(y) - y0) / ((y1 - y0) or 1) * (H - B - 30)
    colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2"]
    s = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="11">',
         f'<rect width="{W}" height="{H}" fill="white"/><text x="{W / 2 - 60}" y="18" font-size="13">{title}</text>',
         f'<line x1="{L}" y1="{H - B}" x2="{W - 130}" y2="{H - B}" stroke="black"/>',
         f'<line x1="{L}" y1="{H - B}" x2="{L}" y2="26" stroke="black"/>',
         f'<text x="{(W - 130 + L) / 2 - 30}" y="{H - 8}">{xlabel}</text>',
         f'<text x="14" y="{H / 2}" transform="rotate(-90 14 {H / 2})">{ylabel}</text>']
    for x in sorted({x for sr in series.values() for x, _ in sr}):
        s.append(f'<text x="{px(x) - 10}" y="{H - B + 16}">{x:g}</text>')
    for i in range(5):
        yv = y0 + (y1 - y0) * i / 4
        v = 10 ** yv if logy else yv
        s.append(f'<text x="{L - 44}" y="{py(v) + 4}">{v:.3g}</text>'
                 f'<line x1="{L}" y1="{py(v)}" x2="{W - 130}" y2="{py(v)}" stroke="#ddd"/>')
    for i, (name, pts) in enumerate(series.items()):
        c = colours[i % len(colours)]
        s.append(f'<polyline fill="none" stroke="{c}" stroke-width="2" points="'
                 + " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in pts) + '"/>')
        s.append(f'<text x="{W - 120}" y="{40 + 16 * i}" fill="{c}">{name}</text>')
    path.write_text("\n".join(s + ["</svg>"]) + "\n")


def machine():
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?") \
        if Path("/proc/cpuinfo").exists() else platform.processor()
    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def commit():
    """The checkout measured, read before the run writes its report and plots into it."""
    git = lambda *c: subprocess.run(["git", *c], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return f"`{git('rev-parse', '--short=12', 'HEAD')}`" + (" (with uncommitted changes)" if git("status", "--porcelain", "-uno") else "")


def report(a, rows, kinds, starts, speed, page, plots):
    cmd = "python3 scripts/benchmarks.py" + (" --quick" if a.quick else "") + (" --page" if a.page else "")
    L = ["# bvseg benchmarks", "",
         f"Written by `scripts/benchmarks.py` on {time.strftime('%Y-%m-%d')}; regenerate with `{cmd}`.",
         f"Commit {a.commit};"
         f" machine: {machine()}. Every figure is the shared judge's (`../shared/tools/bveval.py`"
         f" {' '.join(Bench(a).grid)}), on the meshes of `../shared/meshes` (their sources and licences"
         " are in its README). Times are wall-clock seconds of one process (bvseg with every core;"
         " the peers as `../shared/tools/peers.py` runs them), on a shared machine: compare them as ratios.", "",
         "**Runs.** `bvseg`: the defaults (every primitive kind, tolerance mode). `--target T`: the kinds"
         " an engine takes natively. `coacd`: CoACD 1.0.14 at its default threshold, its own hulls;"
         " `--bv hull`: bvseg's hulls (at most 255 vertices) at CoACD's count; `vhacd`: V-HACD 4 at"
         " CoACD's count. TOV: volume of the union outside the mesh over the mesh's volume."
         " Protrusion: the one-way Hausdorff distance from the union's boundary to the surface (max) and"
         " its mean, over the box diagonal. Surface: the share of surface points inside the union;"
         " escape: the farthest a vertex or surface point lies outside it, over the diagonal."
         " Floats: storage as the primitive-decomposition literature counts it.", "",
         "## Medians over the meshes", "",
         "| run | k | TOV | protrusion max | protrusion mean | surface enclosed | max escape | floats | s |",
         "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    names = list(dict.fromkeys(r["run"] for r in rows))
    for n in names:
        rs = [r for r in rows if r["run"] == n]
        L.append(f"| {n} | {med(rs, 'k'):g} | {med(rs, 'tov'):.3f} | {med(rs, 'pmax'):.4f} | "
                 f"{med(rs, 'pmean'):.4f} | {med(rs, 'surface'):.5f} | {med(rs, 'escape'):.1e} | {med(rs, 'floats'):g} | {med(rs, 's'):.2f} |")
    failed = [f"{r['mesh']} ({r['run']})" for r in rows if math.isnan(r["tov"])]
    if failed:
        L += ["", f"The judge failed (out of memory on hulls of thousands of faces) on: {', '.join(failed)};"
              " the medians leave those runs out."]
    L += ["", "## Per mesh", "", "| mesh | run | k | TOV | protr. max | protr. mean | surface | escape | floats | s |",
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if r["run"] in ("bvseg", "coacd", "--bv hull", "vhacd"):
            L.append(f"| {r['mesh']} | {r['run']} | {r['k']} | {r['tov']:.3f} | {r['pmax']:.4f} | "
                     f"{r['pmean']:.4f} | {r['surface']:.5f} | {r['escape']:.1e} | {r['floats']} | {r['s']:.2f} |")
    L += ["", "The `--target` runs per mesh are in `target/benchmarks/rows.json` after a run.", "",
          "## TOV against k for each kind", "",
          f"Fixed k, judged TOV, median over {', '.join(a.kind_meshes)}:", "",
          f"![TOV against k]({plots[0]})", "", "| kind | " + " | ".join(f"k = {k}" for k in KS) + " |",
          "|---|" + "---:|" * len(KS)]
    for kind in KINDS:
        L.append(f"| {kind} | " + " | ".join(f"{kinds[(kind, k)]:.3f}" for k in KS) + " |")
    L += ["", "## Skeleton-seeded start and adaptive sampling (the paper's section 6)", "",
          f"Each start on {', '.join(Path(m).stem for m in a.start_meshes)}: whole CLI process, median of"
          f" {a.rounds} runs alternating between the starts; TOV and protrusion (max, over the diagonal) by the"
          " judge. `ratio`: time over `--skeleton none --sampling regular`'s on the same mesh.", "",
          "| mesh | start | k | TOV | protr. max | s | ratio |", "|---|---|---:|---:|---:|---:|---:|"]
    base = {r["mesh"]: r["s"] for r in starts if r["run"] == "--skeleton none --sampling regular"}
    L += [f"| {r['mesh']} | {r['run']} | {r['k']} | {r['tov']:.3f} | {r['pmax']:.4f} | {r['s']:.2f} | "
          f"{r['s'] / base[r['mesh']]:.2f} |" for r in starts]
    L += ["", "## Speed against the number of samples", "",
          f"`bvseg segment {a.speed_mesh} --samples N --k 64`, one process each (peak resident memory by"
          " GNU time):", "", f"![time against samples]({plots[1]})", "", "| samples | s | peak MB |",
          "|---:|---:|---:|"]
    L += [f"| {r['n']:,} | {r['s']:.2f} | {r['mb']:.0f} |" for r in speed]
    L += ["", "## The page against the native CLI", ""]
    if page:
        native, pages = page
        L += ["`AGAIN=1 node web/tests/pagebench.mjs 3 spot` (median of 3 runs in headless Chromium, served"
              " as docs/viewer.md says, each on a fresh page; `later run`: the median of a second run on each"
              " page, once the browser has compiled the module; `clicked after 3 s`: `CLICK=3`, Run clicked 3 s"
              " after the page shows it, without autorun, so after the page's warm-up; `shown`: from the click"
              " to the result on the screen, what the user waits, where the other rows give the core's run time)"
              " against the CLI's best of"
              " 3 on bundled spot"
              " (the same job: no output file, so no hierarchy, as in the page), same machine, same run:", "",
              "| | s | ratio to native |", "|---|---:|---:|", f"| native CLI | {native:.2f} | 1.00 |"]
        L += [f"| page, {k} | {v:.2f} | {v / native:.2f} |" for k, v in pages.items()]
    else:
        L.append(f"Not measured in this run (`{cmd} --page` measures it).")
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="three bundled meshes, small judge grids")
    ap.add_argument("--page", action="store_true", help="also time the browser page (needs web/ built)")
    ap.add_argument("--out", default=None, help="report path (default BENCHMARKS.md; --quick: target/benchmarks/QUICK.md)")
    ap.add_argument("--bvseg", help="the bvseg binary (default: target/release/bvseg, built first)")
    ap.add_argument("--no-build", action="store_true")
    a = ap.parse_args()
    a.commit = commit()
    if not (SHARED / "tools/bveval.py").exists():
        sys.exit(f"benchmarks.py: no shared tools at {SHARED} (set BVSEG_SHARED)")
    if not a.bvseg and not a.no_build:
        subprocess.run(["cargo", "build", "--release", "-q", "-p", "bvseg-cli", "--bin", "bvseg"],
                       cwd=ROOT, check=True)
    if a.quick:
        meshes = [ROOT / f"assets/meshes/{m}.obj" for m in QUICK_MESHES]
        a.kind_meshes, samples = ["bunny"], SAMPLES[:2]
        a.start_meshes, a.rounds = [ROOT / "assets/meshes/spot.obj"], 1
    else:
        meshes = sorted((SHARED / "meshes").glob("*.obj"))
        a.kind_meshes, samples = ["bunny", "human_1", "chair_1"], SAMPLES
        a.start_meshes, a.rounds = [SHARED / f"meshes/{m}.obj" for m in SECTION6_MESHES], 3
    a.speed_mesh = "assets/meshes/bunny.obj"
    b = Bench(a)
    rows = b.quality(meshes)
    (b.out / "rows.json").write_text(json.dumps(rows, indent=1))
    kind_paths = [m if m.exists() else SHARED / f"meshes/{m.name}"
                  for m in (ROOT / f"assets/meshes/{n}.obj" for n in a.kind_meshes)]
    kinds = b.kinds(kind_paths)
    starts = b.starts(a.start_meshes, a.rounds)
    speed = b.speed(ROOT / a.speed_mesh, samples)
    page = b.page() if a.page else None
    out = Path(a.out) if a.out else (b.out / "QUICK.md" if a.quick else ROOT / "BENCHMARKS.md")
    img = (ROOT / "docs/images") if not a.quick else b.out
    plots = [img / "bench-tov-k.svg", img / "bench-time-samples.svg"]
    svg_plot(plots[0], "Judged TOV against k (median)", "k (fixed)", "TOV",
             {kind: [(k, kinds[(kind, k)]) for k in KS] for kind in KINDS}, logx=True, logy=True)
    svg_plot(plots[1], "Time against samples (k = 64)", "samples", "seconds",
             {"bvseg": [(r["n"], r["s"]) for r in speed]}, logx=True, logy=True)
    rel = [os.path.relpath(p, out.parent) for p in plots]
    out.write_text(report(a, rows, kinds, starts, speed, page, rel))
    print(f"benchmarks.py: wrote {out} ({len(out.read_text().splitlines())} lines)", file=sys.stderr)
    bad = [r for r in rows if r["run"].startswith(("bvseg", "--")) and r["surface"] < 1.0]
    if bad:
        sys.exit(f"benchmarks.py: bvseg left surface uncovered: {bad}")


if __name__ == "__main__":
    main()
