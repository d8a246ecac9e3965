"""bvseg.robot: the same files as `bvseg robot`, what it returns, its errors, the progress
callback and the timeout; robots in bvseg.batch."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import bvseg
import bvseg.batch as batch
from conftest import BUNNY, ROOT

ARM = ROOT / "assets" / "robots" / "arm" / "arm.xml"
FAST = dict(max_parts=3, samples=2000)
FAST_ARGS = ["--max-parts", "3", "--samples", "2000"]


@pytest.fixture(scope="module")
def arm(tmp_path_factory) -> bvseg.Robot:
    return bvseg.robot(ARM, tmp_path_factory.mktemp("arm") / "out", **FAST)


def test_the_same_files_as_the_cli(tmp_path, run_cli, arm):
    run_cli("robot", str(ARM), "-o", str(tmp_path / "cli"), *FAST_ARGS, "-q")
    out = Path(arm.out_dir)
    cli = sorted(str(p.relative_to(tmp_path / "cli")) for p in (tmp_path / "cli").rglob("*") if p.is_file())
    py = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert cli == py == [
        "arm_bodies.xml", "bvseg_arm.urdf", "bvseg_arm.usda", "bvseg_arm.xml", "curobo.yml",
        "links/base.json", "links/finger.json", "links/lower.json", "links/upper.json",
        "manifest.json",
    ]
    for rel in py:
        assert (out / rel).read_bytes() == (tmp_path / "cli" / rel).read_bytes(), rel


def test_what_it_returns(arm):
    assert arm.name == "bvseg_arm" and arm.robot == "bvseg_arm" and arm.format == "mjcf"
    assert Path(arm.files[-1]).name == "manifest.json" == Path(arm.manifest).name
    assert Path(arm.urdf).is_file() and Path(arm.mjcf).is_file() and Path(arm.curobo).is_file()
    assert arm.warnings == []
    # The MJCF's world body is a link, without meshes here.
    assert [link["name"] for link in arm.links] == ["world", "base", "upper", "lower", "finger"]
    assert arm.link("world")["volumes"] is None and arm.link("world")["parts"] == 0
    for link in arm.links[1:]:
        assert 1 <= link["parts"] <= 3 and link["parts"] == len(link["shapes"])
        assert link["meshes"] == 1 and link["triangles"] > 0 and link["spheres"] >= 1
        # The URDF's kinds only.
        assert set(link["shapes"]) <= {"obb", "sphere", "cylinder"}
        vols = arm.volumes(link["name"])
        assert [v["shape"] for v in vols] == link["shapes"]
        assert json.loads(Path(link["volumes"]).read_text())["volumes"] == vols
    # The arm's own capsule and box pad are kept.
    assert arm.link("upper")["kept"] == 1 and arm.link("finger")["kept"] == 1
    assert arm.parts == sum(link["parts"] for link in arm.links)
    # The MJCF as written, its body tree in the included file with new geoms in place of the
    # collision meshes, the capsule as it was.
    assert '<include file="arm_bodies.xml"/>' in Path(arm.mjcf).read_text()
    bodies = (Path(arm.out_dir) / "arm_bodies.xml").read_text()
    assert '<geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/>' in bodies
    assert all(f'name="{link}_bvseg_0"' in bodies for link in ("base", "upper", "lower", "finger"))
    manifest = json.loads(Path(arm.manifest).read_text())
    assert manifest["files"][-1] == "curobo.yml" and manifest["parts"] == arm.parts
    with pytest.raises(KeyError):
        arm.link("nope")
    assert "4 links segmented" in repr(arm)


def test_budgets(tmp_path):
    r = bvseg.robot(ARM, tmp_path / "o", total_parts=5, spheres_per_link=2, samples=2000, urdf_capsules=True)
    assert 4 <= r.parts <= 5  # 5 shared by volume, each link at least one
    assert all(1 <= link["spheres"] <= 2 for link in r.links if link["name"] != "world")
    # MJCF's visual source: every mesh geom, the visual twins of base and upper too.
    r = bvseg.robot(ARM, tmp_path / "v", source="visual", k=1, samples=2000)
    assert [link["meshes"] for link in r.links] == [0, 2, 2, 1, 1]
    assert [link["parts"] for link in r.links] == [0, 1, 1, 1, 1]


TWO = """<?xml version="1.0"?>
<robot name="two">
  <link name="base"><collision><geometry><mesh filename="{mesh}"/></geometry></collision></link>
  <link name="{second}"/>
  <joint name="j" type="fixed"><parent link="base"/><child link="{child}"/></joint>
</robot>
"""


def write_two(d: Path, mesh="bunny.obj", second="arm", child="arm") -> Path:
    d.mkdir(parents=True, exist_ok=True)
    shutil.copy(BUNNY, d / "bunny.obj")
    (d / "bad.dae").write_text("<COLLADA/>")
    p = d / "two.urdf"
    p.write_text(TWO.format(mesh=mesh, second=second, child=child))
    return p


@pytest.mark.parametrize(
    "case, kind, needles",
    [
        (dict(mesh="nothere.obj"), FileNotFoundError, ["two.urdf", '"base"', "nothere.obj"]),
        (dict(second="base", child="base"), bvseg.RobotError, ['"base" is used twice']),
        (dict(child="hand"), bvseg.RobotError, ['joint "j"', '"hand" is not a link']),
    ],
)
def test_bad_robots(tmp_path, case, kind, needles):
    p = write_two(tmp_path / "in", **case)
    with pytest.raises(kind) as e:
        bvseg.robot(p, tmp_path / "out", samples=2000)
    for n in needles:
        assert n in str(e.value)
    assert "\n" not in str(e.value)
    assert not (tmp_path / "out").exists()


def test_meshes_it_cannot_read_stay_with_a_warning(tmp_path):
    p = write_two(tmp_path / "in", mesh="bad.dae")
    with pytest.warns(bvseg.BvsegWarning, match=r'link "base": mesh "bad.dae": unsupported mesh format'):
        r = bvseg.robot(p, tmp_path / "out", samples=2000)
    assert len(r.warnings) == 1 and r.link("base")["parts"] == 0
    assert '<mesh filename="bad.dae"/>' in Path(r.urdf).read_text()


def test_bad_mjcf(tmp_path):
    (tmp_path / "a.xml").write_text('<mujoco><include file="b.xml"/></mujoco>')
    (tmp_path / "b.xml").write_text('<mujoco><include file="a.xml"/></mujoco>')
    with pytest.raises(bvseg.RobotError, match="include cycle"):
        bvseg.robot(tmp_path / "a.xml", tmp_path / "out")
    (tmp_path / "c.xml").write_text("<mujoco><worldbody>")
    with pytest.raises(bvseg.RobotError, match="c.xml"):
        bvseg.robot(tmp_path / "c.xml", tmp_path / "out")
    (tmp_path / "d.txt").write_text("")
    with pytest.raises(bvseg.RobotError, match=r"unsupported robot format '\.txt'"):
        bvseg.robot(tmp_path / "d.txt", tmp_path / "out")
    with pytest.raises(FileNotFoundError):
        bvseg.robot(tmp_path / "nothere.urdf", tmp_path / "out")


def test_bad_arguments(tmp_path):
    for kwargs, kind, text in [
        (dict(max_parts=0), ValueError, "at least 1"),
        (dict(max_parts=2, total_parts=4), ValueError, "cannot be combined"),
        (dict(spheres_per_link=0), ValueError, "spheres per link"),
        (dict(source="both"), ValueError, "source must be"),
        (dict(samples=5), ValueError, "samples must be between"),
        (dict(max_parts="3"), TypeError, "max_parts must be an integer"),
        (dict(nope=1), TypeError, "spheres_per_link"),
    ]:
        with pytest.raises(kind, match=text):
            bvseg.robot(ARM, tmp_path / "out", **kwargs)
    assert not (tmp_path / "out").exists()


def test_progress_and_its_exceptions(tmp_path):
    seen = []
    bvseg.robot(ARM, tmp_path / "a", progress=seen.append, **FAST)
    assert {s["link"] for s in seen} == {"base", "upper", "lower", "finger"}
    assert {s["spheres"] for s in seen} == {True, False}
    assert {"step", "k", "tov"} <= set(seen[0])

    def stop(step):
        raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        bvseg.robot(ARM, tmp_path / "b", progress=stop, **FAST)
    assert not (tmp_path / "b").exists()


def test_timeout(tmp_path):
    with pytest.raises(TimeoutError, match=r"gave up after 0.05 s \(timeout\)"):
        bvseg.robot(ARM, tmp_path / "out", tov=0.001, max_k=1000, max_parts=1000, timeout=0.05)
    assert not (tmp_path / "out").exists()


def test_robots_in_a_batch(tmp_path, run_cli):
    d = tmp_path / "in"
    shutil.copytree(ARM.parent, d / "arm")
    write_two(d / "two")
    write_two(d / "bad", mesh="nothere.obj")
    shutil.copy(BUNNY, d / "bunny.obj")
    (d / "notes.xml").write_text("<notes/>")
    rels = batch.list_meshes(str(d))
    # A robot's meshes and included files are its own; a robot that cannot be read (bad) keeps
    # none, so the mesh beside it is an input.
    assert rels == ["arm/arm.xml", "bad/bunny.obj", "bad/two.urdf", "bunny.obj", "two/two.urdf"]
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "bvseg.batch", str(d), str(out), "--workers", "2", "--k", "2",
           "--samples", "2000", "--max-parts", "2"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    with open(out / "summary.csv", newline="") as f:
        rows = {r["file"]: r for r in csv.DictReader(f)}
    assert {k: r["status"] for k, r in rows.items()} == {
        "arm/arm.xml": "done", "bad/bunny.obj": "done", "bad/two.urdf": "error",
        "bunny.obj": "done", "two/two.urdf": "done",
    }
    assert "nothere.obj" in rows["bad/two.urdf"]["message"]
    assert rows["arm/arm.xml"]["k"] == "8" and "outputs in arm/arm/" in rows["arm/arm.xml"]["message"]
    # The robot's files are bvseg.robot's, which are the CLI's (but for the main MJCF's
    # meshdir, which leads back from where it is written to the robot's folder).
    run_cli("robot", str(ARM), "-o", str(tmp_path / "cli"), "--k", "2", "--samples", "2000", "--max-parts", "2", "-q")
    for f in ("arm_bodies.xml", "bvseg_arm.urdf", "curobo.yml", "links/upper.json"):
        assert (out / "arm" / "arm" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert (out / "two" / "two" / "two.urdf").is_file() and (out / "bunny.json").is_file()
    # Rerun: robots done are skipped, the bad one is tried again.
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 2 and "0 done, 4 skipped, 1 failed" in p.stderr, p.stderr


def test_robots_need_local_directories(tmp_path):
    pytest.importorskip("pyarrow.fs")
    d = tmp_path / "in"
    write_two(d)
    rows = batch.run(f"file://{d}", f"file://{tmp_path / 'out'}", params=dict(samples=2000), workers=1)
    row = next(r for r in rows if r["file"] == "two.urdf")
    assert row["status"] == "error" and "local directories" in row["message"]
