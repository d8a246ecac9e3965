"""One mesh of a batch (:mod:`bvseg.batch`): segment it, write its outputs, return its summary
row. A module of its own so that process pools and Ray workers import it by name."""

from __future__ import annotations

import json
import os
import tempfile
import time
import warnings
from typing import Any

#: The columns of summary.csv, in order: the command line's ``bvseg batch`` columns, with the
#: protrusion (over the diagonal) and the wall time added.
COLUMNS = (
    "file",
    "status",
    "triangles",
    "k",
    "tov",
    "mov",
    "protrusion_rel",
    "tolerances_met",
    "seconds",
    "message",
)


def empty_row(file: str, status: str, message: str = "") -> dict[str, Any]:
    row: dict[str, Any] = {c: None for c in COLUMNS}
    row.update(file=file, status=status, message=message)
    return row


def _one_line(e: BaseException) -> str:
    text = str(e) or type(e).__name__
    if not isinstance(e, (ValueError, OSError, TimeoutError)):
        text = f"{type(e).__name__}: {text}"
    return text.replace("\r", " ").replace("\n", " ")


def _segment_local(path: str, outputs: list[str], params: dict[str, Any]) -> dict[str, Any]:
    import bvseg

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bvseg.BvsegWarning)
        result = bvseg.segment(path, **params)
    for out in outputs:
        result.save(out)  # atomic: bvseg_io::write_atomic (temporary file, then rename)
    s = result.summary()
    return {
        "triangles": s["triangles"],
        "k": s["k"],
        "tov": s["tov"],
        "mov": s["mov"],
        "protrusion_rel": s["protrusion_rel"],
        "tolerances_met": s["tolerances_met"],
        "message": "; ".join(result.warnings),
    }


def _robot_local(task: dict[str, Any]) -> dict[str, Any]:
    """One robot (``task["robot"]``: its output directory, parameters and options)."""
    import bvseg

    spec = task["robot"]
    r = bvseg.robot(task["source"], spec["out_dir"], **spec["options"], **spec["params"])
    met = [link["tolerances_met"] for link in r.links if link["tolerances_met"] is not None]
    segmented = sum(1 for link in r.links if link["volumes"] is not None)
    return {
        "triangles": sum(link["triangles"] for link in r.links),
        "k": r.parts,
        "tolerances_met": all(met) if met else None,
        "message": f"robot: {segmented} links segmented, {r.spheres} spheres, outputs in {spec['base']}/",
    }


def _segment_remote(task: dict[str, Any], params: dict[str, Any]) -> dict[str, Any]:
    """A mesh and outputs named by URIs (pyarrow.fs): download, segment, upload."""
    from pyarrow import fs as pafs

    source: str = task["source"]
    src_fs, src_path = pafs.FileSystem.from_uri(source)
    with tempfile.TemporaryDirectory(prefix="bvseg-batch-") as tmp:
        local = os.path.join(tmp, os.path.basename(src_path))
        with src_fs.open_input_stream(src_path) as f, open(local, "wb") as g:
            while chunk := f.read(1 << 20):
                g.write(chunk)
        outs = [os.path.join(tmp, "out", os.path.basename(o)) for o in task["outputs"]]
        os.makedirs(os.path.join(tmp, "out"))
        row = _segment_local(local, outs, params)
        for local_out, uri in zip(outs, task["outputs"]):
            upload(local_out, uri)
    return row


def upload(local: str, uri: str) -> None:
    """Copies the file ``local`` to ``uri`` so that a reader never sees part of it: to a
    temporary name beside it, then moved over it (object stores write whole objects)."""
    from pyarrow import fs as pafs

    dest_fs, dest = pafs.FileSystem.from_uri(uri)
    parent = dest.rsplit("/", 1)[0] if "/" in dest else ""
    if parent:
        dest_fs.create_dir(parent, recursive=True)
    tmp = f"{parent}/.{dest.rsplit('/', 1)[-1]}.tmp-{os.getpid()}" if parent else f".{dest}.tmp-{os.getpid()}"
    with open(local, "rb") as f, dest_fs.open_output_stream(tmp) as g:
        while chunk := f.read(1 << 20):
            g.write(chunk)
    dest_fs.move(tmp, dest)


def process(task: dict[str, Any], params: dict[str, Any]) -> dict[str, Any]:
    """Segments the mesh ``task["source"]`` with ``params`` (the keyword arguments of
    :func:`bvseg.segment`) and writes ``task["outputs"]``, or runs the robot of a task with
    ``task["robot"]``; returns its summary row. Never raises: a failure is a row with status
    ``error`` and the message."""
    start = time.perf_counter()
    try:
        if task.get("robot") and task.get("remote"):
            raise ValueError(
                f"{task['file']}: robots are read from and written to local directories (their meshes are files beside them)"
            )
        if task.get("robot"):
            row = _robot_local(task)
        elif task.get("remote"):
            row = _segment_remote(task, params)
        else:
            for out in task["outputs"]:
                os.makedirs(os.path.dirname(out) or ".", exist_ok=True)
            row = _segment_local(task["source"], task["outputs"], params)
        out = empty_row(task["file"], "done")
        out.update(row)
    except Exception as e:  # noqa: BLE001 - one mesh's failure is its row, not the batch's
        out = empty_row(task["file"], "error", _one_line(e))
    out["seconds"] = round(time.perf_counter() - start, 3)
    return out


def process_batch(batch: dict[str, Any], params: dict[str, Any]) -> dict[str, list[str]]:
    """:func:`process` over a Ray Data batch: column ``task`` holds each task as JSON, and
    the rows come back as JSON in column ``row`` (one string column each way, so that Arrow
    never has to guess a type)."""
    return {"row": [json.dumps(process(json.loads(str(t)), params)) for t in batch["task"]]}
