#!/usr/bin/env python3
"""eval_quality: measure bvseg's bounding volumes with the independent judge and compare with peers.

Runs `bvseg segment` on the seven meshes of shared/tools/BASELINES.md at fixed k (and in auto
mode), evaluates every output with shared/tools/bveval.py (run by the bvtools venv's python),
parses the peers' figures (gmm, kmeans) from BASELINES.md, and writes a Markdown report plus a
JSONL file of every raw record.

    python3 scripts/eval_quality.py                    # full sweep: 7 meshes x k {8,16,32} + auto
    python3 scripts/eval_quality.py --quick            # smoke run: bunny + horse, k=16, grid 2e5
    python3 scripts/eval_quality.py --bv ellipsoid,obb,mixed --jobs 2
    python3 scripts/eval_quality.py --parse-baselines  # print the parsed peer figures and exit

Outputs are cached in --outdir (default target/eval): a run is skipped when its volumes file,
its run record and its evaluation exist (use --force to redo them; --rerun-stale to redo only
runs made by a different bvseg binary).

Environment: BVTOOLS_VENV (default ../bvtools-venv next to the repository, else
/work/bvtools-venv), BVSEG_SHARED (default ../shared next to the repository).
Only the standard library is used here; bveval runs in the venv.
"""
import argparse
import concurrent.futures
import hashlib
import json
import math
import os
import re
import shlex
import statistics
import subprocess
import sys
import threading
import time
from datetime import datetime, timezone
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_MESHES = ["bunny", "teddy_1", "hand_1", "human_1", "chair_1", "horse", "dinosaur_1"]
DEFAULT_KS = [8, 16, 32]
BV_KINDS = ("ellipsoid", "obb", "mixed")
# bvseg's --bv name -> the `bv` column of BASELINES.md ("mixed" is compared with the better of
# the two per mesh and k, see best_peer()).
BV_PEER = {"ellipsoid": "ell", "obb": "obb"}
PEERS = ("gmm", "kmeans")

_print_lock = threading.Lock()


def log(msg):
    with _print_lock:
        print(msg, file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- paths

def default_venv():
    env = os.environ.get("BVTOOLS_VENV")
    if env:
        return Path(env)
    for cand in (ROOT.parent / "bvtools-venv", Path("/work/bvtools-venv")):
        if (cand / "bin" / "python").exists():
            return cand
    return ROOT.parent / "bvtools-venv"


def default_shared():
    env = os.environ.get("BVSEG_SHARED")
    return Path(env) if env else ROOT.parent / "shared"


# --------------------------------------------------------------------------- BASELINES.md

def _cells(line):
    line = line.strip()
    if not (line.startswith("|") and line.endswith("|")):
        return None
    return [c.strip() for c in line[1:-1].split("|")]


def _num(s):
    try:
        return float(s)
    except ValueError:
        return None


def _tables(lines, start, stop):
    """Markdown tables in lines[start:stop]: list of (header cells, rows of cells)."""
    out, i = [], start
    while i < stop:
        head = _cells(lines[i])
        if head is not None and i + 1 < stop and re.fullmatch(r"\|[-:| ]+\|", lines[i + 1].strip()):
            rows, j = [], i + 2
            while j < stop and _cells(lines[j]) is not None:
                rows.append(_cells(lines[j]))
                j += 1
            out.append((head, rows))
            i = j
        else:
            i += 1
    return out


def parse_baselines(path):
    """Parse BASELINES.md.

    Returns {"per_mesh": {mesh: {(method, bv, k): {"k_eff", "tov", "mov", "cov_s", "s"}}},
             "median": {(method, bv, k): {"tov", "mov"}}, "mesh_info": {mesh: header text}}.
    The per-mesh tables have a header `| method | bv | k=8: k' | TOV | MOV | cov_s | s | k=16: k' |
    ...`: a cell `k=K: NAME` starts the columns of k = K. The median table has cells `k=K TOV`.
    """
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    sections = []  # (level-2 title or level-3 mesh, line index)
    for i, ln in enumerate(lines):
        if ln.startswith("## ") or ln.startswith("### "):
            sections.append((ln, i))
    sections.append(("", len(lines)))
    per_mesh, median, info = {}, {}, {}
    colname = {"k'": "k_eff", "TOV": "tov", "MOV": "mov", "cov_s": "cov_s", "s": "s"}
    for (title, a), (_, b) in zip(sections, sections[1:]):
        if title.startswith("## Median"):
            for head, rows in _tables(lines, a + 1, b):
                if head[:2] != ["method", "bv"]:
                    continue
                for r in rows:
                    for h, v in zip(head[2:], r[2:]):
                        m = re.fullmatch(r"k=(\d+)\s+(TOV|MOV)", h)
                        if m:
                            median.setdefault((r[0], r[1], int(m.group(1))), {})[
                                m.group(2).lower()] = _num(v)
        m = re.match(r"###\s+(\S+)\s*(.*)$", title)
        if not m or m.group(1) in ("Best",):
            continue
        mesh = m.group(1)
        tabs = [t for t in _tables(lines, a + 1, b)
                if t[0][:2] == ["method", "bv"] and len(t[0]) > 2 and t[0][2].startswith("k=")]
        if not tabs:
            continue
        info[mesh] = m.group(2).strip("() ")
        head, rows = tabs[0]
        cols, k = [], None  # (k, field) per column after method, bv
        for h in head[2:]:
            mk = re.fullmatch(r"k=(\d+):\s*(.+)", h)
            if mk:
                k, h = int(mk.group(1)), mk.group(2).strip()
            if k is None or h not in colname:
                raise ValueError(f"{path}: unexpected column {h!r} in the table of {mesh}")
            cols.append((k, colname[h]))
        table = per_mesh.setdefault(mesh, {})
        for r in rows:
            if len(r) != len(head):
                raise ValueError(f"{path}: row {r} of {mesh} has {len(r)} cells, not {len(head)}")
            for (kk, field), v in zip(cols, r[2:]):
                table.setdefault((r[0], r[1], kk), {})[field] = _num(v)
    if not per_mesh:
        raise ValueError(f"{path}: no per-mesh tables found")
    return {"per_mesh": per_mesh, "median": median, "mesh_info": info}


def check_baselines(base):
    """Medians of the parsed per-mesh TOV/MOV must equal BASELINES.md's own median table."""
    problems, checked = [], 0
    for (method, bv, k), want in sorted(base["median"].items()):
        for field in ("tov", "mov"):
            vals = [t[(method, bv, k)][field] for t in base["per_mesh"].values()
                    if (method, bv, k) in t and t[(method, bv, k)].get(field) is not None]
            if not vals or want.get(field) is None:
                continue
            got = statistics.median(vals)
            checked += 1
            # The table rounds each median to 3 (TOV) or 2 (MOV) decimals.
            if abs(got - want[field]) > 0.0051:
                problems.append(f"{method}/{bv} k={k} {field}: median of rows {got:.3f}, "
                                f"table {want[field]}")
    return checked, problems


def peer_tov(base, mesh, method, bv, k):
    """The peer's TOV for bvseg's bv kind (mixed: the better of ell/obb), or None."""
    t = base["per_mesh"].get(mesh, {})
    names = [BV_PEER[bv]] if bv in BV_PEER else ["ell", "obb"]
    vals = [t[(method, b, k)]["tov"] for b in names
            if (method, b, k) in t and t[(method, b, k)].get("tov") is not None]
    return min(vals) if vals else None


# --------------------------------------------------------------------------- runs

def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def git_state():
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True,
                                text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--", "crates",
                                "Cargo.toml", "Cargo.lock"], capture_output=True, text=True,
                               check=True).stdout.strip()
        branch = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--abbrev-ref", "HEAD"],
                                capture_output=True, text=True).stdout.strip()
        return {"commit": commit, "branch": branch, "dirty": bool(dirty)}
    except (OSError, subprocess.CalledProcessError):
        return {"commit": None, "branch": None, "dirty": None}


def write_json_atomic(path, obj):
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    tmp.write_text(json.dumps(obj, indent=1) + "\n")
    os.replace(tmp, path)


def read_json(path):
    try:
        return json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None


def parse_summary(text):
    """bvseg's stdout summary (`k  16 (ellipsoid)`, `TOV  0.41`, `time  1.2 s`, ...)."""
    out = {}
    for ln in text.splitlines():
        parts = ln.split()
        if len(parts) < 2:
            continue
        key, val = parts[0], parts[1]
        if key in ("k", "samples", "triangles") and val.isdigit():
            out[key] = int(val)
        elif key in ("TOV", "MOV", "F", "time"):
            v = _num(val)
            if v is not None:
                out[{"time": "seconds"}.get(key, key.lower())] = v
    return out


class Run:
    """One bvseg run and its evaluation."""

    def __init__(self, mesh, bv, k, cfg):
        self.mesh, self.bv, self.k, self.cfg = mesh, bv, k, cfg
        ktag = f"k{k}" if k is not None else f"auto_t{cfg.tov:g}_m{cfg.mov:g}"
        self.name = f"{mesh}_{bv}_{ktag}_n{cfg.samples}_s{cfg.seed}"
        self.mesh_path = cfg.meshdir / f"{mesh}.obj"
        self.vol_path = cfg.outdir / f"{self.name}.json"
        self.run_path = cfg.outdir / f"{self.name}.run.json"
        self.eval_path = cfg.outdir / f"{self.name}.eval_g{cfg.grid}_sp{cfg.surface_points}.json"

    def bvseg_cmd(self):
        c = self.cfg
        cmd = [str(c.bvseg), "segment", str(self.mesh_path)]
        if self.k is not None:
            cmd += ["--k", str(self.k)]
        else:
            cmd += ["--tov", f"{c.tov:g}", "--mov", f"{c.mov:g}"]
        cmd += ["--bv", self.bv, "--samples", str(c.samples), "--seed", str(c.seed)]
        if c.threads:
            cmd += ["--threads", str(c.threads)]
        return cmd + ["-o", str(self.vol_path), "--quiet"]

    def eval_cmd(self):
        c = self.cfg
        return [str(c.python), str(c.bveval), str(self.mesh_path), str(self.vol_path),
                "--grid", str(c.grid), "--surface-points", str(c.surface_points),
                "--seed", str(c.eval_seed), "--json"]

    def execute(self):
        c = self.cfg
        rec = {"mesh": self.mesh, "bv": self.bv, "k_requested": self.k,
               "mode": "fixed" if self.k is not None else "auto", "name": self.name,
               "volumes_file": str(self.vol_path), "status": "ok"}
        if self.k is None:
            rec["tol_tov"], rec["tol_mov"] = c.tov, c.mov
        meta = read_json(self.run_path)
        fresh = (not c.force and meta is not None and meta.get("returncode") == 0
                 and self.vol_path.exists())
        if fresh and c.rerun_stale and meta.get("bvseg_sha256") != c.bvseg_sha:
            fresh = False
        if fresh:
            rec["cached"] = True
        else:
            rec["cached"] = False
            cmd = self.bvseg_cmd()
            t0 = time.perf_counter()
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=c.timeout)
                rc, out, err = p.returncode, p.stdout, p.stderr
            except subprocess.TimeoutExpired as e:
                rc, out, err = None, e.stdout or "", f"timeout after {c.timeout} s"
                out = out.decode() if isinstance(out, bytes) else out
            wall = time.perf_counter() - t0
            meta = {"command": cmd, "returncode": rc, "wall_seconds": round(wall, 3),
                    "stdout": out[-4000:], "stderr": err[-4000:], "summary": parse_summary(out),
                    "bvseg_sha256": c.bvseg_sha, "git": c.git,
                    "threads": c.threads, "jobs": c.jobs,
                    "finished": datetime.now(timezone.utc).isoformat(timespec="seconds")}
            if rc == 0 and not self.vol_path.exists():
                meta["returncode"] = rc = -1000
                meta["stderr"] += "\n(no volumes file written)"
            write_json_atomic(self.run_path, meta)
            if self.eval_path.exists():
                self.eval_path.unlink()
        rec["bvseg_command"] = meta["command"]
        rec["bvseg_returncode"] = meta["returncode"]
        rec["wall_seconds"] = meta["wall_seconds"]
        rec["bvseg_summary"] = meta.get("summary", {})
        rec["bvseg_sha256"] = meta.get("bvseg_sha256")
        rec["bvseg_git"] = meta.get("git")
        rec["stale"] = meta.get("bvseg_sha256") != c.bvseg_sha
        if meta["returncode"] != 0:
            rec["status"] = "bvseg_failed"
            rec["error"] = (meta.get("stderr") or "").strip().splitlines()[-1:] or ["?"]
            rec["error"] = rec["error"][0]
            return rec
        vol = read_json(self.vol_path) or {}
        met = vol.get("metrics") if isinstance(vol.get("metrics"), dict) else {}
        rec["reported"] = {key: met.get(key) for key in ("k", "tov", "mov", "samples", "f")}
        rec["reported"]["generator"] = vol.get("generator")
        ev = read_json(self.eval_path)
        if ev is None or c.force_eval:
            cmd = self.eval_cmd()
            env = dict(os.environ)
            for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
                env[var] = str(c.threads or 1)
            t0 = time.perf_counter()
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, env=env,
                                   timeout=c.timeout)
                rc, out, err = p.returncode, p.stdout, p.stderr
            except subprocess.TimeoutExpired:
                rc, out, err = None, "", f"timeout after {c.timeout} s"
            ewall = time.perf_counter() - t0
            if rc != 0:
                rec["status"] = "eval_failed"
                rec["error"] = (err.strip().splitlines() or ["?"])[-1]
                rec["eval_command"] = cmd
                return rec
            try:
                ev = json.loads(out)
            except ValueError:
                rec["status"], rec["error"] = "eval_failed", "bveval printed no JSON"
                return rec
            ev["eval_command"] = cmd
            ev["eval_wall_seconds"] = round(ewall, 3)
            ev["eval_stderr"] = err[-2000:]
            write_json_atomic(self.eval_path, ev)
        rec["eval"] = ev
        if self.k is None:
            rec["tolerances_met"] = ev["tov"] <= c.tov and ev["mov"] <= c.mov
        return rec


# --------------------------------------------------------------------------- report

def fmt(x, nd=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.{nd}f}"


def pct(x, nd=3):
    return "–" if x is None else f"{100 * x:.{nd}f} %"


def ratio(a, b):
    return a / b if a is not None and b not in (None, 0) else None


def med(vals):
    vals = [v for v in vals if v is not None]
    return (statistics.median(vals), len(vals)) if vals else (None, 0)


def median_table(w, fixed, base, cfg):
    w("\n## Medians over the meshes\n")
    w("Median per k of each column over the meshes that have a bvseg run (n); "
      "the ratio column is the median of the per-mesh ratios.\n")
    w("| bv | k | n | bvseg TOV | GMM TOV | k-means TOV | median bvseg/GMM | "
      "median bvseg/k-means | bvseg MOV | bvseg s |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for bv in cfg.bvs:
        for k in cfg.ks:
            rows = [r for r in fixed if r["bv"] == bv and r["k_requested"] == k]
            if not rows:
                continue
            tv = [r["eval"]["tov"] for r in rows]
            gm = [peer_tov(base, r["mesh"], "gmm", bv, k) for r in rows]
            km = [peer_tov(base, r["mesh"], "kmeans", bv, k) for r in rows]
            w(f"| {bv} | {k} | {len(rows)} | {fmt(med(tv)[0])} | {fmt(med(gm)[0])} | "
              f"{fmt(med(km)[0])} | {fmt(med([ratio(a, b) for a, b in zip(tv, gm)])[0], 2)} | "
              f"{fmt(med([ratio(a, b) for a, b in zip(tv, km)])[0], 2)} | "
              f"{fmt(med([r['eval']['mov'] for r in rows])[0])} | "
              f"{fmt(med([r['wall_seconds'] for r in rows])[0], 1)} |")


def build_report(records, base, cfg, argv, started, finished):
    ok = [r for r in records if r["status"] == "ok"]
    L = []
    w = L.append
    g = cfg.git
    w("# bvseg quality vs. peer baselines\n")
    w(f"Generated {finished} by `scripts/eval_quality.py` (wall time "
      f"{(datetime.fromisoformat(finished) - datetime.fromisoformat(started)).total_seconds():.0f} s).")
    w(f"bvseg binary `{cfg.bvseg}` (sha256 {cfg.bvseg_sha[:12]}); repository at "
      f"{g.get('branch')} {str(g.get('commit'))[:12]}"
      + (" **with uncommitted changes in crates/**" if g.get("dirty") else "")
      + (" (the binary was given with --bvseg: it need not be built from this checkout)"
         if cfg.bvseg_given else "") + ".")
    gens = sorted({str((r.get("reported") or {}).get("generator")) for r in ok
                   if (r.get("reported") or {}).get("generator")})
    if gens:
        w(f"Generator field of the volumes files: {', '.join(gens)}.")
    nfail = len(records) - len(ok)
    w(f"Runs: {len(records)}, evaluated {len(ok)}, failed {nfail}"
      f"{' (see Failed runs)' if nfail else ''}; "
      f"{sum(bool(r.get('cached')) for r in records)} taken from the cache in {cfg.outdir}.")
    w(f"Judge: `{cfg.bveval}` with --grid {cfg.grid} --surface-points {cfg.surface_points} "
      f"--seed {cfg.eval_seed}; bvseg --samples {cfg.samples} --seed {cfg.seed}"
      f"{f' --threads {cfg.threads}' if cfg.threads else ''}, {cfg.jobs} run(s) at a time.")
    w(f"Peers: `{cfg.baselines}` (gmm and kmeans rows; evaluated there with --grid 1000000 "
      "--surface-points 100000).")
    stale = [r for r in records if r.get("stale")]
    if stale:
        w(f"\n**Warning: {len(stale)} cached run(s) were made by a different bvseg binary** "
          "(rerun with --rerun-stale or --force): "
          + ", ".join(r["name"] for r in stale[:10]) + (" …" if len(stale) > 10 else ""))
    if cfg.grid != 1000000:
        w(f"\nNote: grid {cfg.grid} differs from the peers' 1e6; TOV is unbiased either way but "
          "its SE is larger.")
    w("\nTOV = vol(∪V_i \\ S)/vol(S), MOV = max_i vol(V_i \\ S)/vol(S_i), as measured by bveval "
      "(± is bveval's standard error). Ratios < 1 mean bvseg is tighter than the peer. "
      "`k'` = volumes bvseg produced. `s` = bvseg wall time (measured around the process).")

    fixed = [r for r in ok if r["mode"] == "fixed"]
    for bv in cfg.bvs:
        rows = sorted([r for r in fixed if r["bv"] == bv],
                      key=lambda r: (cfg.meshes.index(r["mesh"]), r["k_requested"]))
        if not rows:
            continue
        peer_note = ("" if bv in BV_PEER else
                     " (peers: the better of their ellipsoid and OBB rows)")
        w(f"\n## Fixed k, --bv {bv}{peer_note}\n")
        w("| mesh | k | k' | bvseg TOV ± SE | MOV | cov interior | GMM TOV | k-means TOV | "
          "bvseg/GMM | bvseg/k-means | s |")
        w("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for r in rows:
            e, k = r["eval"], r["k_requested"]
            gm = peer_tov(base, r["mesh"], "gmm", bv, k)
            km = peer_tov(base, r["mesh"], "kmeans", bv, k)
            kflag = "" if e["k"] == k else " ⚠"
            w(f"| {r['mesh']} | {k} | {e['k']}{kflag} | {fmt(e['tov'])} ± {fmt(e['tov_se'])} | "
              f"{fmt(e['mov'])} | {pct(e['coverage_interior'], 2)} | {fmt(gm)} | {fmt(km)} | "
              f"{fmt(ratio(e['tov'], gm), 2)} | {fmt(ratio(e['tov'], km), 2)} | "
              f"{fmt(r['wall_seconds'], 1)} |")

    if fixed:
        median_table(w, fixed, base, cfg)

    auto = sorted([r for r in ok if r["mode"] == "auto"],
                  key=lambda r: (cfg.bvs.index(r["bv"]), cfg.meshes.index(r["mesh"])))
    if auto:
        w(f"\n## Auto mode (--tov {cfg.tov:g} --mov {cfg.mov:g})\n")
        w("`met` = both TOV ≤ tov and MOV ≤ mov as measured by bveval (`~` when the failing "
          "margin is within 2 SE); `bvseg says` = the values bvseg reports for itself.\n")
        w("| mesh | bv | k | TOV ± SE | MOV ± SE | met | bvseg says TOV / MOV | "
          "cov vertices | cov surface | cov interior | max escape | s |")
        w("|---|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|")
        for r in auto:
            e, rep = r["eval"], r.get("reported", {})
            met = r["tolerances_met"]
            near = (e["tov"] - 2 * e["tov_se"] <= cfg.tov and e["mov"] - 2 * e["mov_se"] <= cfg.mov)
            w(f"| {r['mesh']} | {r['bv']} | {e['k']} | {fmt(e['tov'])} ± {fmt(e['tov_se'])} | "
              f"{fmt(e['mov'])} ± {fmt(e['mov_se'])} | {'yes' if met else ('~' if near else 'no')} | "
              f"{fmt(rep.get('tov'))} / {fmt(rep.get('mov'))} | {pct(e['coverage_vertices'])} | "
              f"{pct(e['coverage_surface'])} | {pct(e['coverage_interior'])} | "
              f"{e['max_escape_rel']:.3g} | {fmt(r['wall_seconds'], 1)} |")
        w(f"\nTolerances met on {sum(r['tolerances_met'] for r in auto)} of {len(auto)} meshes.")

    if ok:
        w("\n## Coverage over all runs\n")
        w("| quantity | worst | run |")
        w("|---|---:|---|")
        for key, label in (("coverage_vertices", "vertex coverage (min)"),
                           ("coverage_surface", "surface coverage (min)"),
                           ("coverage_interior", "interior coverage (min)")):
            rs = [r for r in ok if r["eval"].get(key) is not None]
            if rs:
                r = min(rs, key=lambda r: r["eval"][key])
                w(f"| {label} | {pct(r['eval'][key])} | {r['name']} |")
        r = max(ok, key=lambda r: r["eval"]["max_escape_rel"])
        w(f"| max escape / box diagonal (max) | {r['eval']['max_escape_rel']:.3g} | {r['name']} |")
        warn = sorted({f"{r['mesh']}: {x}" for r in ok for x in r["eval"].get("warnings", [])})
        if warn:
            w("\nbveval warnings: " + "; ".join(warn))

    bad = [r for r in records if r["status"] != "ok"]
    if bad:
        w("\n## Failed runs\n")
        w("| run | status | error |")
        w("|---|---|---|")
        for r in bad:
            w(f"| {r['name']} | {r['status']} | {str(r.get('error', '')).replace('|', '/')} |")

    w("\n## Reproduce\n")
    w("```")
    w("cargo build --release -p bvseg-cli --bin bvseg")
    w(f"BVTOOLS_VENV={cfg.venv} BVSEG_SHARED={cfg.shared} python3 scripts/eval_quality.py "
      + " ".join(shlex.quote(a) for a in argv))
    w("# each run is")
    ex = next((r for r in ok if r["mode"] == "fixed"), None) or (ok[0] if ok else None)
    if ex:
        w(" ".join(shlex.quote(a) for a in ex["bvseg_command"]))
        w(" ".join(shlex.quote(a) for a in ex["eval"].get("eval_command", [])))
    exa = next((r for r in ok if r["mode"] == "auto"), None)
    if exa:
        w("# auto mode")
        w(" ".join(shlex.quote(a) for a in exa["bvseg_command"]))
    w("```")
    w(f"\nRaw records (bveval output, bvseg command, wall time, ...): `{cfg.jsonl}`.")
    return "\n".join(L) + "\n"


# --------------------------------------------------------------------------- main

def parse_list(s, conv=str):
    return [conv(x) for x in re.split(r"[,\s]+", s.strip()) if x]


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--meshes", default=",".join(DEFAULT_MESHES),
                    help="comma-separated mesh names in $BVSEG_SHARED/meshes (default: the 7 of "
                         "BASELINES.md)")
    ap.add_argument("--ks", default="8,16,32", help="fixed k values (default 8,16,32)")
    ap.add_argument("--bv", default="ellipsoid", help="comma list of ellipsoid,obb,mixed")
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=0, help="bvseg seed")
    ap.add_argument("--tov", type=float, default=0.3, help="auto-mode TOV tolerance (0.3)")
    ap.add_argument("--mov", type=float, default=0.5, help="auto-mode MOV tolerance (0.5)")
    ap.add_argument("--no-auto", action="store_true", help="skip the auto-mode runs")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2)")
    ap.add_argument("--threads", type=int, default=None,
                    help="bvseg --threads (default: cores // jobs, at least 1)")
    ap.add_argument("--grid", type=int, default=1_000_000, help="bveval --grid (default 1e6)")
    ap.add_argument("--surface-points", type=int, default=100_000)
    ap.add_argument("--eval-seed", type=int, default=0, help="bveval --seed")
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: bunny+horse, k=16, grid 2e5 (explicit --meshes/--ks/--grid win)")
    ap.add_argument("--outdir", default=None, help="cache and outputs (default target/eval)")
    ap.add_argument("--md", default=None, help="report (default OUTDIR/QUALITY.md)")
    ap.add_argument("--jsonl", default=None, help="raw records (default OUTDIR/records.jsonl)")
    ap.add_argument("--force", action="store_true", help="redo every run and evaluation")
    ap.add_argument("--force-eval", action="store_true", help="redo every evaluation only")
    ap.add_argument("--rerun-stale", action="store_true",
                    help="redo cached runs made by a different bvseg binary")
    ap.add_argument("--bvseg", default=None,
                    help="bvseg binary (default target/release/bvseg, built first)")
    ap.add_argument("--no-build", action="store_true", help="do not run cargo build first")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per process")
    ap.add_argument("--baselines", default=None,
                    help="peers' table (default $BVSEG_SHARED/tools/BASELINES.md)")
    ap.add_argument("--parse-baselines", action="store_true",
                    help="print the parsed gmm/kmeans figures, check them, and exit")
    ap.add_argument("--dry-run", action="store_true", help="print the commands and exit")
    a = ap.parse_args(argv)

    given = {x.split("=")[0] for x in argv if x.startswith("--")}
    if a.quick:
        if "--meshes" not in given:
            a.meshes = "bunny,horse"
        if "--ks" not in given:
            a.ks = "16"
        if "--grid" not in given:
            a.grid = 200_000

    cfg = a
    cfg.shared = default_shared().resolve()
    cfg.venv = default_venv()
    cfg.python = cfg.venv / "bin" / "python"
    cfg.bveval = cfg.shared / "tools" / "bveval.py"
    cfg.meshdir = cfg.shared / "meshes"
    cfg.baselines = Path(a.baselines) if a.baselines else cfg.shared / "tools" / "BASELINES.md"
    cfg.meshes = parse_list(a.meshes)
    cfg.ks = parse_list(a.ks, int)
    cfg.bvs = parse_list(a.bv)
    for bv in cfg.bvs:
        if bv not in BV_KINDS:
            ap.error(f"--bv: unknown kind {bv!r} (choose from {', '.join(BV_KINDS)})")
    if a.jobs < 1:
        ap.error("--jobs must be >= 1")
    if any(k < 1 for k in cfg.ks):
        ap.error("--ks must be positive")

    try:
        base = parse_baselines(cfg.baselines)
    except (OSError, ValueError) as e:
        print(f"eval_quality: error: cannot parse the baselines: {e}", file=sys.stderr)
        return 2
    checked, problems = check_baselines(base)
    if a.parse_baselines:
        for mesh, t in base["per_mesh"].items():
            for (method, bv, k), v in sorted(t.items()):
                if method in PEERS:
                    print(f"{mesh:11s} {method:7s} {bv:4s} k={k:<3d} k'={v['k_eff']:g} "
                          f"TOV={v['tov']:.3f} MOV={v['mov']:.3f} cov_s={v['cov_s']:g} s={v['s']:g}")
        print(f"{len(base['per_mesh'])} meshes, "
              f"{sum(len(t) for t in base['per_mesh'].values())} (method, bv, k) rows; "
              f"{checked} medians re-derived, {len(problems)} mismatches", file=sys.stderr)
        for p in problems:
            print(f"  mismatch: {p}", file=sys.stderr)
        return 1 if problems else 0
    if problems:
        for p in problems:
            log(f"eval_quality: warning: BASELINES.md medians disagree with its rows: {p}")
    missing = [m for m in cfg.meshes if m not in base["per_mesh"]]
    if missing:
        log(f"eval_quality: note: no peer figures for {', '.join(missing)}")

    for path, what in ((cfg.python, "the bvtools venv's python (set BVTOOLS_VENV or run "
                        "`BVTOOLS_VENV=... bash $BVSEG_SHARED/tools/setup.sh`)"),
                       (cfg.bveval, "bveval.py (set BVSEG_SHARED)")):
        if not path.exists():
            print(f"eval_quality: error: {path} not found: {what}", file=sys.stderr)
            return 2
    for m in cfg.meshes:
        if not (cfg.meshdir / f"{m}.obj").exists():
            print(f"eval_quality: error: mesh {cfg.meshdir / (m + '.obj')} not found",
                  file=sys.stderr)
            return 2

    cfg.outdir = Path(a.outdir) if a.outdir else ROOT / "target" / "eval"
    cfg.outdir = cfg.outdir.resolve()
    cfg.md = Path(a.md) if a.md else cfg.outdir / "QUALITY.md"
    cfg.jsonl = Path(a.jsonl) if a.jsonl else cfg.outdir / "records.jsonl"
    if a.threads is None:
        cfg.threads = max(1, (os.cpu_count() or 1) // a.jobs)
    cfg.bvseg_given = bool(a.bvseg)
    cfg.bvseg = Path(a.bvseg).resolve() if a.bvseg else ROOT / "target" / "release" / "bvseg"
    if not a.bvseg and not a.no_build and not a.dry_run:
        log("eval_quality: cargo build --release -p bvseg-cli --bin bvseg")
        p = subprocess.run(["cargo", "build", "--release", "-p", "bvseg-cli", "--bin", "bvseg"],
                           cwd=ROOT)
        if p.returncode != 0:
            print("eval_quality: error: cargo build failed", file=sys.stderr)
            return 2
    if not cfg.bvseg.exists() and not a.dry_run:
        print(f"eval_quality: error: {cfg.bvseg} not found", file=sys.stderr)
        return 2
    cfg.bvseg_sha = sha256(cfg.bvseg) if cfg.bvseg.exists() else None
    cfg.git = git_state()

    runs = []
    for bv in cfg.bvs:
        for m in cfg.meshes:
            if not a.no_auto:
                runs.append(Run(m, bv, None, cfg))
            for k in cfg.ks:
                runs.append(Run(m, bv, k, cfg))
    # Longest first (auto, then large k, then large meshes) keeps both workers busy to the end.
    order = sorted(runs, key=lambda r: (r.k is not None, -(r.k or 0)))
    if a.dry_run:
        for r in order:
            print(" ".join(shlex.quote(x) for x in r.bvseg_cmd()))
            print(" ".join(shlex.quote(x) for x in r.eval_cmd()))
        return 0

    cfg.outdir.mkdir(parents=True, exist_ok=True)
    started = datetime.now(timezone.utc).isoformat(timespec="seconds")
    log(f"eval_quality: {len(runs)} runs, {a.jobs} at a time, bvseg --threads {cfg.threads}, "
        f"outputs in {cfg.outdir}")
    results, done = {}, 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futs = {pool.submit(r.execute): r for r in order}
        for fut in concurrent.futures.as_completed(futs):
            r = futs[fut]
            try:
                rec = fut.result()
            except Exception as e:  # noqa: BLE001 - keep the sweep going, report the run
                rec = {"mesh": r.mesh, "bv": r.bv, "k_requested": r.k, "name": r.name,
                       "mode": "fixed" if r.k is not None else "auto",
                       "status": "harness_error", "error": repr(e)}
            results[r.name] = rec
            done += 1
            if rec["status"] == "ok":
                e = rec["eval"]
                log(f"[{done}/{len(runs)}] {r.name}: k={e['k']} TOV={e['tov']:.4f}±"
                    f"{e['tov_se']:.4f} MOV={e['mov']:.3f} cov_i={e['coverage_interior']:.5f} "
                    f"bvseg {rec['wall_seconds']:.1f} s{' (cached)' if rec['cached'] else ''}")
            else:
                log(f"[{done}/{len(runs)}] {r.name}: {rec['status']}: {rec.get('error')}")
    records = [results[r.name] for r in runs]
    finished = datetime.now(timezone.utc).isoformat(timespec="seconds")

    report = build_report(records, base, cfg, argv, started, finished)
    cfg.md.parent.mkdir(parents=True, exist_ok=True)
    cfg.md.write_text(report)
    cfg.jsonl.parent.mkdir(parents=True, exist_ok=True)
    with open(cfg.jsonl, "w") as fh:
        for rec in records:
            rec = dict(rec)
            for peer in PEERS:
                if rec.get("k_requested") is not None:
                    rec[f"{peer}_tov"] = peer_tov(base, rec["mesh"], peer, rec["bv"],
                                                  rec["k_requested"])
            fh.write(json.dumps(rec) + "\n")
    nstale = sum(bool(r.get("stale")) for r in records)
    if nstale:
        log(f"eval_quality: warning: {nstale} cached run(s) were made by a different bvseg binary "
            "(--rerun-stale or --force to redo them)")
    nbad = sum(r["status"] != "ok" for r in records)
    log(f"eval_quality: wrote {cfg.md} and {cfg.jsonl}"
        + (f"; {nbad} run(s) failed" if nbad else ""))
    return 1 if nbad else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except BrokenPipeError:  # e.g. `--dry-run | head`
        sys.exit(1)
