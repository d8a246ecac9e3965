"""python -m bvseg.batch: outputs, names and resumability as `bvseg batch`, the summary, the
local process pool and the Ray Data pipeline."""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import bvseg
import bvseg.batch as batch
from conftest import BUNNY, FOURLEG, MESHES, SPOT

PARAMS = dict(k=6, samples=3000)
ARGS = ["--k", "6", "--samples", "3000"]


@pytest.fixture()
def tree(tmp_path) -> Path:
    """bunny.obj, sub/spot.obj, sub/spot.stl (a bad one: same stem), sub/deeper/dog.obj,
    a hidden file and a text file."""
    d = tmp_path / "in"
    (d / "sub" / "deeper").mkdir(parents=True)
    shutil.copy(BUNNY, d / "bunny.obj")
    shutil.copy(SPOT, d / "sub" / "spot.obj")
    (d / "sub" / "spot.stl").write_bytes(b"solid x\nendsolid x\n")
    shutil.copy(FOURLEG, d / "sub" / "deeper" / "dog.obj")
    (d / ".hidden.obj").write_text("junk")
    (d / "notes.txt").write_text("not a mesh")
    return d


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_listing_and_names(tree):
    rels = batch.list_meshes(str(tree))
    assert rels == ["bunny.obj", "sub/deeper/dog.obj", "sub/spot.obj", "sub/spot.stl"]
    assert batch.output_bases(rels) == ["bunny", "sub/deeper/dog", "sub/spot.obj", "sub/spot.stl"]
    assert batch.list_meshes(str(tree), "**/*.obj") == ["bunny.obj", "sub/deeper/dog.obj", "sub/spot.obj"]
    assert batch.list_meshes(str(tree), "sub/*") == ["sub/spot.obj", "sub/spot.stl"]
    assert batch.list_meshes(str(tree), "*.txt") == ["notes.txt"]
    # A selection keeps the names the whole directory gives.
    assert batch.output_bases(["sub/spot.obj"], rels) == ["sub/spot.obj"]


def test_local_batch_outputs_summary_and_resume(tree, tmp_path):
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "bvseg.batch", str(tree), str(out), "--formats", "json,xml", "--workers", "2", *ARGS]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 2, p.stderr  # the bad STL
    assert "3 done, 0 skipped, 1 failed" in p.stderr
    files = sorted(str(f.relative_to(out)) for f in out.rglob("*") if f.is_file())
    assert files == [
        "bunny.json", "bunny.xml", "sub/deeper/dog.json", "sub/deeper/dog.xml",
        "sub/spot.obj.json", "sub/spot.obj.xml", "summary.csv", "summary.parquet",
    ] or files == [
        "bunny.json", "bunny.xml", "sub/deeper/dog.json", "sub/deeper/dog.xml",
        "sub/spot.obj.json", "sub/spot.obj.xml", "summary.csv",
    ]
    rows = read_csv(out / "summary.csv")
    assert list(rows[0]) == list(batch.COLUMNS)
    assert [(r["file"], r["status"]) for r in rows] == [
        ("bunny.obj", "done"), ("sub/deeper/dog.obj", "done"), ("sub/spot.obj", "done"), ("sub/spot.stl", "error"),
    ]
    assert rows[0]["k"] == "6" and rows[0]["triangles"] == "3674" and float(rows[0]["seconds"]) > 0
    assert float(rows[0]["protrusion_rel"]) > 0 and rows[0]["tolerances_met"] == ""
    assert "spot.stl" in rows[3]["message"]
    # Each output is what segment() writes.
    r = bvseg.segment(tree / "sub" / "spot.obj", **PARAMS)
    assert (out / "sub" / "spot.obj.json").read_text() == r.to_json()

    # Rerun: the three are skipped (with their figures), the bad one is tried again.
    stamp = (out / "bunny.json").stat().st_mtime_ns
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 2 and "0 done, 3 skipped, 1 failed" in p.stderr, p.stderr
    assert (out / "bunny.json").stat().st_mtime_ns == stamp
    rows2 = read_csv(out / "summary.csv")
    assert [r["status"] for r in rows2] == ["skipped", "skipped", "skipped", "error"]
    assert rows2[0]["k"] == "6" and rows2[0]["tov"] == rows[0]["tov"]
    # A missing output is redone; --force redoes all.
    (out / "bunny.xml").unlink()
    p = subprocess.run(cmd + ["--glob", "**/*.obj"], capture_output=True, text=True)
    assert p.returncode == 0 and "1 done, 2 skipped, 0 failed" in p.stderr, p.stderr
    p = subprocess.run(cmd + ["--glob", "*.obj", "--force", "-q"], capture_output=True, text=True)
    assert p.returncode == 0 and p.stderr == ""
    assert (out / "bunny.json").stat().st_mtime_ns != stamp
    assert not [f for f in out.rglob(".*")]  # no temporary files left


def test_the_same_files_as_bvseg_batch(tmp_path, run_cli):
    flat = tmp_path / "flat"
    flat.mkdir()
    for m in (BUNNY, SPOT):
        shutil.copy(m, flat / m.name)
    shutil.copy(FOURLEG, flat / "spot.stl.obj")  # an odd name, a stem of its own
    run_cli("batch", str(flat), "-o", str(tmp_path / "cli"), "--formats", "json,glb,xml,obj", *ARGS, "-q")
    rows = batch.run(flat, tmp_path / "py", formats=["json", "glb", "xml", "obj"], params=PARAMS, workers=2)
    assert {r["status"] for r in rows} == {"done"}
    cli_files = sorted(f.name for f in (tmp_path / "cli").iterdir() if f.name != "summary.csv")
    py_files = sorted(f.name for f in (tmp_path / "py").iterdir() if not f.name.startswith("summary."))
    assert cli_files == py_files and len(cli_files) == 12
    for name in cli_files:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    cli_rows = read_csv(tmp_path / "cli" / "summary.csv")
    py_rows = read_csv(tmp_path / "py" / "summary.csv")
    for c, p in zip(cli_rows, py_rows):
        assert (c["file"], c["status"], c["triangles"], c["k"]) == (p["file"], p["status"], p["triangles"], p["k"])
        assert float(c["tov"]) == float(p["tov"]) and float(c["mov"]) == float(p["mov"])


def test_parquet_summary(tree, tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    out = tmp_path / "out"
    batch.run(tree, out, glob="**/*.obj", params=PARAMS, workers=1)
    table = pq.read_table(out / "summary.parquet")
    assert table.column_names == list(batch.COLUMNS)
    assert table.column("k").to_pylist() == [6, 6, 6]
    assert table.column("status").to_pylist() == ["done"] * 3


def test_uris_through_pyarrow_fs(tree, tmp_path):
    pytest.importorskip("pyarrow.fs")
    out = tmp_path / "out"
    rows = batch.run(f"file://{tree}", f"file://{out}", glob="**/*.obj", formats=["json"], params=PARAMS, workers=2)
    assert [r["status"] for r in rows] == ["done"] * 3
    assert (out / "sub" / "deeper" / "dog.json").read_text() == bvseg.segment(tree / "sub" / "deeper" / "dog.obj", **PARAMS).to_json()
    assert (out / "summary.csv").is_file()
    rows = batch.run(f"file://{tree}", f"file://{out}", glob="**/*.obj", params=PARAMS)
    assert [r["status"] for r in rows] == ["skipped"] * 3


def test_bad_arguments(tree, tmp_path):
    with pytest.raises(ValueError, match="k must be at least 1"):
        batch.run(tree, tmp_path / "o", params=dict(k=0))
    with pytest.raises(ValueError, match="formats: 'ply'"):
        batch.run(tree, tmp_path / "o", formats=["ply"])
    with pytest.raises(FileNotFoundError, match="no mesh files"):
        batch.run(tree, tmp_path / "o", glob="*.fbx")
    p = subprocess.run([sys.executable, "-m", "bvseg.batch", str(tree), str(tmp_path / "o"), "--kinds", "torus"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and 'unknown volume kind "torus"' in p.stderr
    assert not (tmp_path / "o").exists()


def test_ray_engine(tree, tmp_path):
    ray = pytest.importorskip("ray")
    pytest.importorskip("ray.data")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        out = tmp_path / "ray"
        rows = batch.run(tree, out, engine="ray", formats=["json", "glb"], concurrency=2, params=PARAMS)
        assert [(r["file"], r["status"]) for r in rows] == [
            ("bunny.obj", "done"), ("sub/deeper/dog.obj", "done"), ("sub/spot.obj", "done"), ("sub/spot.stl", "error"),
        ]
        local = tmp_path / "local"
        batch.run(tree, local, formats=["json", "glb"], params=PARAMS, workers=2)
        for f in ("bunny.json", "bunny.glb", "sub/deeper/dog.json", "sub/spot.obj.glb"):
            assert (out / f).read_bytes() == (local / f).read_bytes(), f
        assert [r["k"] for r in read_csv(out / "summary.csv")][:3] == ["6", "6", "6"]
        rows = batch.run(tree, out, engine="ray", formats=["json", "glb"], params=PARAMS)
        assert [r["status"] for r in rows] == ["skipped", "skipped", "skipped", "error"]
    finally:
        ray.shutdown()
