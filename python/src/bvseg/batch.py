"""Segment every mesh and robot of a directory tree, locally in a process pool or as a Ray
Data pipeline.

    python -m bvseg.batch IN_DIR OUT_DIR [--engine local|ray] [--glob PATTERN]
        [--formats json,glb,xml,obj,usda] [--force] [--workers N | --concurrency N]
        [segment options: --k --tov --max-protrusion ... as ``bvseg batch``]
        [robot options: --source --max-parts --total-parts --spheres-per-link --urdf-capsules]

What ``bvseg batch DIR -o OUTDIR`` does, for a tree: every mesh under IN_DIR (recursively; by
default the extensions the loader reads, or the files ``--glob`` matches), one output set per
mesh in the mirror of its subdirectory under OUT_DIR, named as the command line names them
(the file's stem, or its whole name where two meshes of a directory share a stem:
``part.obj.json`` beside ``part.stl.json``). Robots (every ``.urdf``, and each ``.xml`` whose
root is ``<mujoco>`` and that bvseg did not write) run :func:`bvseg.robot` into a directory
of their own under that name, one robot per task. Outputs are written atomically, so an
output that exists is complete, and a mesh whose outputs all exist is skipped (a robot whose
``manifest.json``, written last, exists; ``--force`` redoes it): an interrupted batch resumes
where it stopped. ``OUT_DIR/summary.csv`` (and ``summary.parquet``
when pyarrow is importable) has one row per mesh, sorted by file: file, status (done, skipped,
error), triangles, k, tov, mov, protrusion_rel, tolerances_met, seconds, message (the error,
or the mesh's warnings). Exit status 0, or 2 when some mesh failed (3 with ``--strict`` when
some missed its tolerances), as ``bvseg batch``.

IN_DIR and OUT_DIR may also be URIs pyarrow.fs understands (``s3://bucket/meshes``,
``gs://...``, ``file:///abs/path``): each worker then downloads its mesh to a temporary
directory and uploads its outputs. Robots, whose meshes are other files, are read from a
local IN_DIR only (a ``.urdf`` under a URI is an error row; ``.xml`` files there are not
looked at). See the package's README for running on a Ray cluster.
"""

from __future__ import annotations

import argparse
import csv
import fnmatch
import io
import json
import os
import sys
import time
from collections import Counter
from pathlib import Path, PurePosixPath
from typing import Any, Iterable, Sequence

from . import _worker
from ._worker import COLUMNS

#: The output formats, by extension, as ``bvseg batch --formats``.
FORMATS = ("json", "glb", "xml", "obj", "usda")

#: The keyword arguments of :func:`bvseg.robot` beside :func:`bvseg.segment`'s.
ROBOT_OPTIONS = ("source", "max_parts", "total_parts", "spheres_per_link", "urdf_capsules")


def _is_uri(s: str) -> bool:
    return "://" in s


# --- listing ---------------------------------------------------------------------------------


def _is_robot(base: str, rel: str) -> bool:
    """Whether ``rel`` under ``base`` is a robot: a ``.urdf``, or (in a local directory) an
    MJCF ``.xml`` that bvseg did not write."""
    ext = PurePosixPath(rel).suffix.lower()
    if ext == ".urdf":
        return True
    if ext not in (".xml", ".mjcf") or _is_uri(base):
        return False
    from . import _bvseg

    return _bvseg.robot_format(_join(base, rel)) == "mjcf"


def _matches(rel: str, pattern: str | None, base: str = "") -> bool:
    """Whether the relative path ``rel`` (posix) is selected: by ``pattern`` (a glob where
    ``*`` does not cross ``/`` and ``**/`` is any number of directories), else by extension
    (a mesh) or content (a robot, :func:`_is_robot`)."""
    if pattern is None:
        from . import MESH_EXTENSIONS

        ext = PurePosixPath(rel).suffix.lower().lstrip(".")
        return ext in MESH_EXTENSIONS or _is_robot(base, rel)
    parts, pats = rel.split("/"), pattern.split("/")

    def match(i: int, j: int) -> bool:
        if j == len(pats):
            return i == len(parts)
        if pats[j] == "**":
            return any(match(k, j + 1) for k in range(i, len(parts) + 1))
        return i < len(parts) and fnmatch.fnmatchcase(parts[i], pats[j]) and match(i + 1, j + 1)

    return match(0, 0)


def list_meshes(in_dir: str, pattern: str | None = None) -> list[str]:
    """The relative paths (posix, sorted) of the meshes and robots under ``in_dir`` (a
    directory or a pyarrow.fs URI), recursively: those whose extension the loader reads and
    the robots (:func:`_is_robot`), or those ``pattern`` matches (``"**/*.obj"``,
    ``"chairs/*.glb"``, ``"**/*.urdf"``), less the files a robot among them uses (its meshes,
    the MJCF files it includes). Hidden files and directories (a leading ``.``) are left out,
    as are the temporary files of interrupted writes."""
    rels: list[str] = []
    if _is_uri(in_dir):
        from pyarrow import fs as pafs

        fs, base = pafs.FileSystem.from_uri(in_dir)
        base = base.rstrip("/")
        for info in fs.get_file_info(pafs.FileSelector(base, recursive=True)):
            if info.type == pafs.FileType.File:
                rels.append(info.path[len(base) + 1 :])
    else:
        root = Path(in_dir)
        if not root.is_dir():
            raise NotADirectoryError(f"{in_dir}: not a directory")
        for dirpath, dirnames, filenames in os.walk(root):
            dirnames[:] = sorted(d for d in dirnames if not d.startswith("."))
            for name in filenames:
                rels.append((Path(dirpath) / name).relative_to(root).as_posix())
    def hidden(r: str) -> bool:
        return any(p.startswith(".") for p in r.split("/"))

    picked = [r for r in rels if not hidden(r) and _matches(r, pattern, in_dir)]
    # A robot's own meshes and included files are part of it, not inputs of their own.
    used: set[str] = set()
    if not _is_uri(in_dir):
        from . import _bvseg

        for r in picked:
            if _is_robot(in_dir, r):
                used.update(_bvseg.robot_uses(_join(in_dir, r)))
    return sorted(r for r in picked if os.path.realpath(_join(in_dir, r)) not in used)


def output_bases(rels: Sequence[str], others: Iterable[str] = ()) -> list[str]:
    """The output name (without extension) of each mesh, as a relative posix path: its
    directory and stem, or its whole file name where two meshes of one directory share a stem
    (the command line's rule, per directory). The stems of ``others`` (the directory's other
    meshes, which ``--glob`` left out) count too, so that a mesh's names do not depend on the
    selection."""
    def key(r: str) -> tuple[str, str]:
        p = PurePosixPath(r)
        return (str(p.parent), p.stem)

    count = Counter(key(r) for r in set(rels) | set(others))
    out = []
    for r in rels:
        p = PurePosixPath(r)
        name = p.name if count[key(r)] > 1 else p.stem
        out.append(str(p.parent / name) if str(p.parent) != "." else name)
    return out


def _join(base: str, rel: str) -> str:
    if _is_uri(base):
        return base.rstrip("/") + "/" + rel
    return os.path.join(base, *rel.split("/"))


def _exists(path: str) -> bool:
    if _is_uri(path):
        from pyarrow import fs as pafs

        fs, p = pafs.FileSystem.from_uri(path)
        return bool(fs.get_file_info(p).type == pafs.FileType.File)
    return os.path.isfile(path)


def _read_text(path: str) -> str | None:
    try:
        if _is_uri(path):
            from pyarrow import fs as pafs

            fs, p = pafs.FileSystem.from_uri(path)
            with fs.open_input_stream(p) as f:
                return bytes(f.read()).decode("utf-8")
        with open(path, encoding="utf-8") as f:
            return f.read()
    except (OSError, UnicodeDecodeError):
        return None


def _skipped(rel: str, json_out: str | None) -> dict[str, Any]:
    """A skipped mesh's row, with the figures of its existing JSON output when there is one."""
    row = _worker.empty_row(rel, "skipped", "outputs exist")
    text = _read_text(json_out) if json_out else None
    try:
        m = json.loads(text)["metrics"] if text else None
    except (ValueError, KeyError, TypeError):
        m = None
    if isinstance(m, dict):
        for c in ("k", "tov", "mov", "protrusion_rel"):
            row[c] = m.get(c)
    return row


# --- summary ---------------------------------------------------------------------------------


def _csv_value(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def summary_csv(rows: Iterable[dict[str, Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([_csv_value(r.get(c)) for c in COLUMNS])
    return buf.getvalue()


def _write_bytes(path: str, data: bytes) -> None:
    """Writes ``data`` to ``path`` atomically: a temporary file beside it, then a rename."""
    if _is_uri(path):
        import tempfile

        with tempfile.NamedTemporaryFile(delete=False) as t:
            t.write(data)
        try:
            _worker.upload(t.name, path)
        finally:
            os.unlink(t.name)
        return
    d = os.path.dirname(path) or "."
    tmp = os.path.join(d, f".{os.path.basename(path)}.tmp-{os.getpid()}")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def write_summary(out_dir: str, rows: list[dict[str, Any]]) -> list[str]:
    """Writes summary.csv, and summary.parquet when pyarrow is importable; returns the paths."""
    written = [_join(out_dir, "summary.csv")]
    _write_bytes(written[0], summary_csv(rows).encode("utf-8"))
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    schema = pa.schema(
        [
            ("file", pa.string()),
            ("status", pa.string()),
            ("triangles", pa.int64()),
            ("k", pa.int64()),
            ("tov", pa.float64()),
            ("mov", pa.float64()),
            ("protrusion_rel", pa.float64()),
            ("tolerances_met", pa.bool_()),
            ("seconds", pa.float64()),
            ("message", pa.string()),
        ]
    )
    table = pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in rows], schema=schema)
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    written.append(_join(out_dir, "summary.parquet"))
    _write_bytes(written[1], sink.getvalue().to_pybytes())
    return written


# --- engines ---------------------------------------------------------------------------------


def _say(quiet: bool, text: str) -> None:
    if not quiet:
        print(text, file=sys.stderr, flush=True)


def _progress_line(n: int, total: int, row: dict[str, Any]) -> str:
    msg = f": {row['message']}" if row.get("message") else ""
    return f"[{n}/{total}] {row['status']} {row['file']}{msg}"


def _run_local(tasks: list[dict[str, Any]], params: dict[str, Any], workers: int, quiet: bool, done0: int, total: int) -> list[dict[str, Any]]:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    rows: list[dict[str, Any]] = []
    if not tasks:
        return rows
    # spawn: a fresh interpreter per worker, never a fork of a process with threads running.
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {pool.submit(_worker.process, t, params): t for t in tasks}
        for fut in as_completed(futures):
            try:
                row = fut.result()
            except BrokenProcessPool as e:
                row = _worker.empty_row(futures[fut]["file"], "error", f"the worker process died: {e}")
            rows.append(row)
            _say(quiet, _progress_line(done0 + len(rows), total, row))
    return rows


def _run_ray(tasks: list[dict[str, Any]], params: dict[str, Any], concurrency: int | None, cpus_per_task: float, quiet: bool, done0: int, total: int) -> list[dict[str, Any]]:
    try:
        import ray
        import ray.data
    except ImportError as e:
        raise SystemExit(f"bvseg.batch: --engine ray needs Ray Data: pip install 'bvseg[ray]' ({e})") from None
    if not tasks:
        return []
    if not ray.is_initialized():
        # RAY_ADDRESS (or a running local cluster) is joined as it is; else a local one starts.
        if os.environ.get("RAY_ADDRESS"):
            ray.init()
        else:
            ray.init(include_dashboard=False)
    ds: Any = ray.data.from_items([{"task": json.dumps(t)} for t in tasks], override_num_blocks=len(tasks))
    kwargs: dict[str, Any] = {"batch_size": 1, "num_cpus": cpus_per_task, "fn_kwargs": {"params": params}}
    if concurrency is not None:
        strategy = getattr(ray.data, "TaskPoolStrategy", None)
        if strategy is not None:
            kwargs["compute"] = strategy(size=concurrency)
        else:  # older Ray Data
            kwargs["concurrency"] = concurrency
    ds = ds.map_batches(_worker.process_batch, **kwargs)
    rows: list[dict[str, Any]] = []
    for r in ds.iter_rows():
        row = json.loads(r["row"])
        rows.append(row)
        _say(quiet, _progress_line(done0 + len(rows), total, row))
    return rows


def run(
    in_dir: str | os.PathLike[str],
    out_dir: str | os.PathLike[str],
    *,
    engine: str = "local",
    glob: str | None = None,
    formats: Sequence[str] = ("json",),
    force: bool = False,
    workers: int | None = None,
    concurrency: int | None = None,
    params: dict[str, Any] | None = None,
    robot_options: dict[str, Any] | None = None,
    quiet: bool = True,
) -> list[dict[str, Any]]:
    """The batch as a function: segments every mesh and robot under ``in_dir`` into
    ``out_dir`` and writes the summary; returns the rows (sorted by file). ``robot_options``
    are :func:`bvseg.robot`'s own keyword arguments (``source``, ``max_parts``,
    ``total_parts``, ``spheres_per_link``, ``urdf_capsules``), for the robots. ``engine`` is ``"local"`` (a
    process pool of ``workers``, default one per core) or ``"ray"`` (Ray Data, at most
    ``concurrency`` tasks at once; joins ``RAY_ADDRESS`` or the Ray already initialised, else
    starts a local one). ``params`` are :func:`bvseg.segment`'s keyword arguments; ``threads``
    among them is per mesh (default: the cores divided among the workers; one per task on
    Ray, which then reserves that many CPUs per task)."""
    import bvseg

    in_dir, out_dir = os.fspath(in_dir), os.fspath(out_dir)
    if engine not in ("local", "ray"):
        raise ValueError(f"engine must be 'local' or 'ray', got {engine!r}")
    exts: list[str] = []
    for f in formats:
        ext = f.strip().lstrip(".").lower()
        if ext not in FORMATS:
            raise ValueError(f"formats: '{f}': unsupported output format (supported: {', '.join(FORMATS)})")
        if ext not in exts:
            exts.append(ext)
    params = {k: v for k, v in (params or {}).items() if v is not None}
    robot_options = {k: v for k, v in (robot_options or {}).items() if v is not None}
    for k in robot_options:
        if k not in ROBOT_OPTIONS:
            raise TypeError(f"robot_options: unknown option {k!r} (it takes {', '.join(ROBOT_OPTIONS)})")
    # A robot's links always get a JSON document, which carries the hierarchy.
    robot_params = dict(params)
    # Only the JSON document carries the hierarchy: without it, the runs skip building it.
    params.setdefault("hierarchy", "json" in exts)
    cores = os.cpu_count() or 1
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if concurrency is not None and concurrency < 1:
        raise ValueError(f"concurrency must be at least 1, got {concurrency}")
    if not _is_uri(in_dir):
        in_dir = os.path.abspath(in_dir)
    if not _is_uri(out_dir):
        out_dir = os.path.abspath(out_dir)
    rels = list_meshes(in_dir, glob)
    bases = output_bases(rels, list_meshes(in_dir) if glob is not None else ())
    if not rels:
        raise FileNotFoundError(
            f"{in_dir}: no mesh files ({glob or ', '.join(bvseg.MESH_EXTENSIONS)}) nor robots under the directory"
        )
    if engine == "local":
        workers = min(workers or cores, len(rels))
        params.setdefault("threads", max(1, cores // workers))
    else:
        params.setdefault("threads", 1)
    bvseg._bvseg.check_params(**params)  # the errors segment() would raise, before any work
    robot_params.setdefault("threads", params["threads"])
    if not _is_uri(out_dir):
        os.makedirs(out_dir, exist_ok=True)

    rows: list[dict[str, Any]] = []
    tasks: list[dict[str, Any]] = []
    remote = _is_uri(in_dir) or _is_uri(out_dir)
    for rel, base in zip(rels, bases):
        if _is_robot(in_dir, rel):
            robot_dir = _join(out_dir, base)
            if not force and _exists(_join(robot_dir, bvseg._bvseg.ROBOT_DONE_FILE)):
                rows.append(_worker.empty_row(rel, "skipped", "outputs exist"))
                _say(quiet, _progress_line(len(rows), len(rels), rows[-1]))
                continue
            tasks.append({
                "file": rel, "source": _join(in_dir, rel), "outputs": [], "remote": remote,
                "robot": {"out_dir": robot_dir, "base": base, "params": robot_params, "options": robot_options},
            })
            continue
        outs = [_join(out_dir, f"{base}.{e}") for e in exts]
        if not force and all(_exists(o) for o in outs):
            rows.append(_skipped(rel, _join(out_dir, f"{base}.json") if "json" in exts else None))
            _say(quiet, _progress_line(len(rows), len(rels), rows[-1]))
            continue
        tasks.append({"file": rel, "source": _join(in_dir, rel), "outputs": outs, "remote": remote})
    start = time.perf_counter()
    if engine == "local":
        rows += _run_local(tasks, params, workers or 1, quiet, len(rows), len(rels))
    else:
        rows += _run_ray(tasks, params, concurrency, float(params["threads"]), quiet, len(rows), len(rels))
    rows.sort(key=lambda r: r["file"])
    written = write_summary(out_dir, rows)
    n = Counter(r["status"] for r in rows)
    unmet = sum(1 for r in rows if r.get("tolerances_met") is False)
    _say(
        quiet,
        f"bvseg.batch: {n['done']} done, {n['skipped']} skipped, {n['error']} failed, {unmet} short "
        f"of the tolerances in {time.perf_counter() - start:.1f} s; summary in {', '.join(written)}",
    )
    return rows


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m bvseg.batch",
        description="Segment every mesh under IN_DIR into OUT_DIR (resumable), locally or on Ray.",
    )
    p.add_argument("in_dir", metavar="IN_DIR", help="directory (or pyarrow.fs URI) of meshes, searched recursively")
    p.add_argument("out_dir", metavar="OUT_DIR", help="directory (or URI) for the outputs and summary.csv")
    p.add_argument("--engine", choices=("local", "ray"), default="local", help="a local process pool (default) or a Ray Data pipeline")
    p.add_argument("--glob", metavar="PATTERN", help="select the files this matches (e.g. '**/*.obj'); default: every .obj, .gltf, .glb, .stl")
    p.add_argument("--formats", default="json", metavar="EXT,...", help="output formats: json, glb, xml (MJCF), obj, usda (default: json)")
    p.add_argument("--force", action="store_true", help="redo meshes whose outputs already exist")
    p.add_argument("--workers", type=int, metavar="N", help="local engine: processes (default: one per core)")
    p.add_argument("--concurrency", type=int, metavar="N", help="ray engine: most tasks at once (default: as the cluster's CPUs allow)")
    p.add_argument("--strict", action="store_true", help="exit 3 when some mesh missed its tolerances")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing on stderr but errors")
    from . import DEFAULTS, _bvseg

    s = p.add_argument_group("segment options (as bvseg segment; the defaults are the core's)")
    def d(name: str) -> str:
        return f"(default: {DEFAULTS[name]})"

    s.add_argument("--k", type=int, help="exactly this many parts, instead of the tolerances")
    s.add_argument("--tov", type=float, help=f"tolerance on the total outside volume {d('tov')}")
    s.add_argument("--max-protrusion", type=float, help=f"tolerance on the protrusion, of the diagonal {d('max_protrusion')}")
    s.add_argument("--max-protrusion-abs", type=float, help="the same in mesh units")
    s.add_argument("--mov", type=float, help="tolerance on the largest per-part outside volume (default: unchecked)")
    s.add_argument("--max-k", type=int, help=f"most parts in tolerance mode {d('max_k')}")
    s.add_argument("--bv", "--kinds", dest="kinds", metavar="KINDS", help=f"kinds of volume, e.g. obb,capsule {d('kinds')}")
    s.add_argument("--target", metavar="NAME", help="an engine's native kinds: mujoco, gltf, parry, physx, usd (NAME-hull too)")
    s.add_argument("--max-hull-vertices", type=int, help=f"most vertices of a hull {d('max_hull_vertices')}")
    s.add_argument("--samples", type=int, help=f"target number of interior samples {d('samples')}")
    s.add_argument("--seed", type=int, help=f"seed of the initialisation {d('seed')}")
    s.add_argument("--threads", type=int, help="threads per mesh (default: cores / workers locally, 1 on Ray)")
    s.add_argument("--no-merge", action="store_true", help="do not merge parts at the end")
    s.add_argument("--no-tighten", action="store_true",
                   help="do not tighten: no boundary-layer moves that lower the outside volume, no reshaping of the volumes")
    # Its former name, still read.
    s.add_argument("--no-polish", dest="no_tighten", action="store_true", help=argparse.SUPPRESS)
    s.add_argument("--margin", type=float, help=f"grow every volume by this, in mesh units {d('margin')}")
    s.add_argument("--timeout", type=float, metavar="SECONDS", help="give up on a mesh (a whole robot) after this long")
    r = p.add_argument_group("robot options (as bvseg robot)")
    r.add_argument("--source", choices=("collision", "visual"), help="which meshes of each link to segment (default: collision)")
    r.add_argument("--max-parts", type=int, metavar="N", help=f"most parts per link (default: {_bvseg.DEFAULT_PARTS_PER_LINK})")
    r.add_argument("--total-parts", type=int, metavar="N", help="most parts per robot, shared among its links by volume")
    r.add_argument("--spheres-per-link", type=int, metavar="N", help="most spheres per link in curobo.yml (default: 16)")
    r.add_argument("--urdf-capsules", action="store_true", help="write capsules as URDF 1.1 <capsule>")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    params: dict[str, Any] = {
        name: getattr(args, name)
        for name in (
            "k", "tov", "max_protrusion", "max_protrusion_abs", "mov", "max_k", "kinds", "target",
            "max_hull_vertices", "samples", "seed", "threads", "margin", "timeout",
        )
    }
    if args.no_merge:
        params["merge"] = False
    if args.no_tighten:
        params["tighten"] = False
    robot_options = {name: getattr(args, name) for name in ROBOT_OPTIONS}
    try:
        rows = run(
            args.in_dir,
            args.out_dir,
            engine=args.engine,
            glob=args.glob,
            formats=args.formats.split(","),
            force=args.force,
            workers=args.workers,
            concurrency=args.concurrency,
            params=params,
            robot_options=robot_options,
            quiet=args.quiet,
        )
    except (ValueError, TypeError, OSError) as e:
        print(f"bvseg.batch: error: {e}", file=sys.stderr)
        return 2
    if any(r["status"] == "error" for r in rows):
        return 2
    if args.strict and any(r.get("tolerances_met") is False for r in rows):
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
