"""bvseg.segment: the input forms, byte identity with the command line, the parameters and
their errors, the progress callback, the timeout, threads and the GIL."""

from __future__ import annotations

import json
import threading
import time
import warnings

import numpy as np
import pytest

import bvseg
from conftest import BUNNY, FOURLEG, SPOT

FAST = dict(samples=4000)  # small runs where the figures do not matter


@pytest.fixture(scope="module")
def bunny12() -> bvseg.Segmentation:
    return bvseg.segment(BUNNY, k=12)


# --- byte identity with the command line ------------------------------------------------------


def test_json_is_byte_identical_to_the_cli(tmp_path, run_cli, bunny12):
    cli_out = tmp_path / "cli.json"
    run_cli("segment", str(BUNNY), "--k", "12", "-o", str(cli_out), "-q")
    py_out = tmp_path / "py.json"
    bunny12.save(py_out)
    assert py_out.read_bytes() == cli_out.read_bytes()
    assert bunny12.to_json().encode() == cli_out.read_bytes()


@pytest.mark.parametrize("ext", ["glb", "xml", "obj"])
def test_every_format_is_byte_identical_to_the_cli(tmp_path, run_cli, bunny12, ext):
    cli_out = tmp_path / f"cli.{ext}"
    run_cli("segment", str(BUNNY), "--k", "12", "-o", str(cli_out), "-q")
    # MJCF names its model after the file's stem: same stem on both sides.
    (tmp_path / "py").mkdir()
    py_out = tmp_path / "py" / f"cli.{ext}"
    bunny12.save(py_out)
    assert py_out.read_bytes() == cli_out.read_bytes()


def test_glb_with_mesh_and_labels_are_byte_identical(tmp_path, run_cli, bunny12):
    run_cli("segment", str(BUNNY), "--k", "12", "-o", str(tmp_path / "cli.glb"), "--with-mesh",
            "--labels", str(tmp_path / "cli.txt"), "-q")
    bunny12.save(tmp_path / "py.glb", with_mesh=True)
    bunny12.save_labels(tmp_path / "py.txt")
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()
    assert (tmp_path / "py.txt").read_bytes() == (tmp_path / "cli.txt").read_bytes()
    assert bunny12.labels.tolist() == [int(x) for x in (tmp_path / "cli.txt").read_text().split()]


def test_tolerance_mode_defaults_are_the_clis(tmp_path, run_cli):
    run_cli("segment", str(SPOT), "-o", str(tmp_path / "cli.json"), "-q")
    r = bvseg.segment(SPOT)
    r.save(tmp_path / "py.json")
    assert (tmp_path / "py.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    assert r.tolerances_met is True and r.unmet == []
    s = r.summary()
    assert s["tolerances"]["tov"] == bvseg.DEFAULTS["tov"]


@pytest.mark.parametrize(
    "cli_args, kwargs",
    [
        (["--bv", "capsule", "--k", "8"], dict(kinds="capsule", k=8)),
        (["--bv", "obb,capsule,sphere", "--k", "8"], dict(kinds=["obb", "capsule", "sphere"], k=8)),
        (["--target", "mujoco", "--k", "8"], dict(target="mujoco", k=8)),
        (["--target", "parry-hull", "--k", "6", "--max-hull-vertices", "16"],
         dict(target="parry-hull", k=6, max_hull_vertices=16)),
        (["--tov", "0.5", "--max-protrusion", "0.1", "--seed", "3", "--no-merge"],
         dict(tov=0.5, max_protrusion=0.1, seed=3, merge=False)),
        (["--max-protrusion-abs", "1.5", "--mov", "2.0", "--max-k", "10", "--no-tighten", "--margin", "0.01"],
         dict(max_protrusion_abs=1.5, mov=2.0, max_k=10, tighten=False, margin=0.01)),
        (["--sampling", "adaptive", "--skeleton", "auto", "--max-k", "12"],
         dict(sampling="adaptive", skeleton="auto", max_k=12)),
    ],
)
def test_parameters_mirror_the_cli(tmp_path, run_cli, cli_args, kwargs):
    run_cli("segment", str(FOURLEG), "--samples", "6000", *cli_args, "-o", str(tmp_path / "cli.json"), "-q")
    r = bvseg.segment(FOURLEG, samples=6000, **kwargs)
    assert r.to_json() == (tmp_path / "cli.json").read_text()


def test_kinds_and_target_choose_the_shapes():
    caps = bvseg.segment(FOURLEG, kinds="capsule", k=6, **FAST)
    assert caps.schema == "bvseg.volumes/2"
    assert {v["shape"] for v in caps.volumes} == {"capsule"}
    assert all(set(v) >= {"center", "axis", "half_length", "radius", "fraction"} for v in caps.volumes)
    muj = bvseg.segment(FOURLEG, target="mujoco-hull", k=6, **FAST)
    assert {v["shape"] for v in muj.volumes} <= {"ellipsoid", "obb", "sphere", "capsule", "cylinder", "hull"}
    assert muj.document["kinds"] == "ellipsoid,obb,sphere,capsule,cylinder,hull"
    ell = bvseg.segment(FOURLEG, kinds="ellipsoid", k=4, **FAST)
    assert ell.schema == "bvseg.volumes/1" and ell.document["kind"] == "ellipsoid"


# --- input forms ------------------------------------------------------------------------------


def test_every_input_form_gives_the_same_bytes(bunny12):
    expected = bunny12.to_json()
    mesh = bvseg.load_mesh(BUNNY)
    v, f = mesh
    assert v.dtype == np.float64 and v.shape == (1839, 3)
    assert f.dtype == np.int64 and f.shape == (3674, 3)
    assert bvseg.segment(str(BUNNY), k=12).to_json() == expected
    assert bvseg.segment(mesh, k=12).to_json() == expected
    assert bvseg.segment((v, f), k=12).to_json() == expected
    assert bvseg.segment([v.tolist(), f.astype(np.int32)], k=12).to_json() == expected

    class Obj:
        vertices, faces = v, f.astype(np.uint32)

    assert bvseg.segment(Obj(), k=12).to_json() == expected


def test_trimesh_of_the_obj_gives_the_clis_bytes(bunny12):
    trimesh = pytest.importorskip("trimesh")
    tm = trimesh.load(BUNNY, process=False)
    # trimesh keeps the file's vertex order; bvseg renumbers as its OBJ reader does.
    assert not np.array_equal(tm.vertices, bvseg.load_mesh(BUNNY).vertices)
    assert bvseg.segment(tm, k=12).to_json() == bunny12.to_json()


def test_arrays_take_the_loaders_path():
    mesh = bvseg.load_mesh(BUNNY)
    v, f = mesh
    # A repeated vertex, a degenerate triangle, an unused vertex, inward-facing triangles.
    v2 = np.vstack([v, v[:1], [[1e3, 1e3, 1e3]]])
    f2 = f[:, ::-1].copy()
    row, col = np.argwhere(f2 == 0)[0]
    f2[row, col] = len(v)  # the copy of vertex 0
    f2 = np.vstack([f2, [[1, 1, 2]]])
    with pytest.warns(bvseg.BvsegWarning) as rec:
        r = bvseg.segment((v2, f2), k=12)
    assert [str(w.message) for w in rec] == [
        "arrays: welded 1 coincident vertices, dropped 1 degenerate triangles",
        "arrays: the surface faced inward; its orientation was reversed",
    ]
    m = r.mesh
    assert m.report["flipped"] and m.stats["welded"] == 1 and m.dropped.tolist() == [len(f)]
    # The same surface (each triangle turned back, its corners rotated).
    def canon(vertices, faces):
        tris = [[tuple(vertices[i]) for i in t] for t in faces.tolist()]
        return sorted(tuple(t[t.index(min(t)):] + t[: t.index(min(t))]) for t in tris)

    assert m.vertices.shape == v.shape and canon(m.vertices, m.faces) == canon(v, f)
    assert r.k == 12 and r.labels.shape == (len(f2),) and r.labels[-1] == -1
    assert r.triangle_parts.shape == (len(f),)


def test_result_fields(bunny12):
    r = bunny12
    doc = json.loads(r.to_json())
    assert r.volumes == doc["volumes"] and r.metrics == doc["metrics"] and r.history == doc["history"]
    assert r.k == 12 == r.metrics["k"] == len(r.volumes)
    assert r.triangle_parts.dtype == np.uint32 and r.triangle_parts.shape == (3674,)
    assert r.sample_parts.dtype == np.uint32 and len(r.sample_parts) == r.metrics["samples"]
    assert set(np.unique(r.triangle_parts)) <= set(range(12))
    assert r.tolerances_met is None and r.unmet == []
    assert r.params["k"] == 12 and r.params["kinds"] == bvseg.DEFAULTS["kinds"]
    assert r.history[-1]["step"] == "final"
    assert abs(sum(v["fraction"] for v in r.volumes) - 1) < 1e-9
    assert "k=12" in repr(r)


def test_without_the_hierarchy_only_the_hierarchy_is_missing(bunny12):
    with_it = json.loads(bunny12.to_json())
    r = bvseg.segment(BUNNY, k=12, hierarchy=False)
    without = json.loads(r.to_json())
    assert len(with_it["hierarchy"]) == 2 * 12 - 1 and without["hierarchy"] == []
    assert {**without, "hierarchy": with_it["hierarchy"]} == with_it
    assert (r.triangle_parts == bunny12.triangle_parts).all()


def test_defaults_are_the_cores(run_cli):
    d = bvseg.DEFAULTS
    assert (d["tov"], d["max_protrusion"], d["max_k"], d["samples"], d["seed"]) == (0.3, 0.05, 96, 20000, 0)
    assert d["kinds"] == "ellipsoid,obb,sphere,capsule,cylinder" and d["max_hull_vertices"] == 32
    assert d["k"] is None and d["mov"] is None and d["merge"] and d["tighten"] and d["margin"] == 0
    assert d["hierarchy"] is True
    assert d["skeleton"] == "rig" and d["sampling"] == "regular"
    assert d["route"] == "auto" and d["per_bone"] is None
    # The CLI's --help shows the same defaults.
    help_text = run_cli("segment", "--help").stdout
    assert "[default: 0.3]" in help_text and "[default: 20000]" in help_text and "[default: 96]" in help_text
    assert set(bvseg.TARGETS) == {"mujoco", "gltf", "parry", "physx", "usd"}


# --- errors -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(k=0), "k must be at least 1"),
        (dict(k=-2), "k must be a non-negative integer, got -2"),
        (dict(samples=50), r"samples must be between 100 and 50000000, got 50"),
        (dict(k=9999), r"k = 9999 is too large for 20000 samples"),
        (dict(tov=-0.1), r"tolerances must be finite and non-negative \(tov = -0.1\)"),
        (dict(mov=float("inf")), r"\(mov = inf\)"),
        (dict(max_protrusion=0), "max_protrusion must be finite and above 0, got 0"),
        (dict(max_protrusion_abs=-1.0), "max_protrusion_abs must be finite and above 0"),
        (dict(max_k=0), "max_k must be between 1 and 4096, got 0"),
        (dict(max_hull_vertices=300), "max_hull_vertices must be between 4 and 255, got 300"),
        (dict(margin=-1), "margin must be finite and at least 0"),
        (dict(kinds="torus"), 'kinds: unknown volume kind "torus"'),
        (dict(kinds=[]), "kinds: unknown volume kind"),
        (dict(target="unity"), 'target: unknown target "unity": expected one of mujoco'),
        (dict(kinds="obb", target="mujoco"), "kinds and target cannot be combined"),
        (dict(k=4, tov=0.2), "k and tov cannot be combined"),
        (dict(k=4, max_protrusion=0.2), "k and max_protrusion cannot be combined"),
        (dict(max_protrusion=0.1, max_protrusion_abs=1.0), "cannot be combined"),
        (dict(threads=0), "threads must be between 1 and 4096, got 0"),
        (dict(timeout=-1), "timeout must be a number of seconds above 0"),
        (dict(seed=-1), "seed must be a non-negative integer"),
        (dict(sampling="dense"), 'sampling: "dense" is not a sampling: use regular or adaptive'),
        (dict(skeleton="bones"), 'skeleton: "bones" is not a skeleton mode'),
    ],
)
def test_bad_parameters_are_value_errors(kwargs, match):
    with pytest.raises(ValueError, match=match) as e:
        bvseg.segment(BUNNY, **kwargs)
    assert not isinstance(e.value, bvseg.MeshError)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(k="3"), "k must be an integer, got str"),
        (dict(k=2.5), "k must be an integer, got float"),
        (dict(samples=True), "samples must be an integer, got a bool"),
        (dict(tov="low"), "tov must be a number, got str"),
        (dict(kinds=3), "kinds must be a string or a list of strings"),
        (dict(merge="no"), "merge must be True or False"),
        (dict(sampling=2), "sampling must be a string, got int"),
        (dict(no_merge=True), "unexpected keyword argument 'no_merge'"),
        (dict(progress=5), "progress must be callable"),
    ],
)
def test_wrong_types_are_type_errors(kwargs, match):
    with pytest.raises(TypeError, match=match):
        bvseg.segment(BUNNY, **kwargs)


def test_bad_meshes_are_mesh_errors(tmp_path):
    assert issubclass(bvseg.MeshError, ValueError)
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    cases = [
        ((tri, [[0, 1, 7]]), "triangle 0 refers to vertex 7, but the mesh has only 4 vertices"),
        ((tri, [[0, -1, 2]]), "triangle 0 refers to vertex -1"),
        ((np.where(tri == 1, np.nan, tri), tet), "non-finite coordinate"),
        ((np.where(tri == 1, np.inf, tri), tet), "non-finite coordinate"),
        ((tri, np.zeros((0, 3), int)), "no triangles"),
        ((tri[:, :2], tet), r"vertices must have shape \(n, 3\)"),
        ((tri, tet[:, :2]), r"faces must have shape \(n, 3\)"),
        ((tri, tet + 0.5), "must be integer vertex indices"),
        ((tri, [[0, 0, 1]]), "no triangles \\(1 degenerate dropped\\)"),
        ((tri, [[0, 1, 2]]), "encloses no volume"),  # one triangle: open and flat
        ((tri * 1e300, tet), "out-of-range coordinate"),
    ]
    for mesh, match in cases:
        with pytest.raises(bvseg.MeshError, match=match):
            bvseg.segment(mesh, **FAST)
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nf 1 2 9\n")
    with pytest.raises(bvseg.MeshError, match="bad.obj: a face refers to a vertex that does not exist"):
        bvseg.segment(bad)
    txt = tmp_path / "mesh.ply"
    txt.write_text("ply\n")
    with pytest.raises(bvseg.MeshError, match=r"unsupported mesh format '.ply'"):
        bvseg.load_mesh(txt)
    with pytest.raises(FileNotFoundError, match="cannot open"):
        bvseg.segment(tmp_path / "missing.obj")
    with pytest.raises(TypeError, match="mesh must be a path"):
        bvseg.segment(42)


def test_an_open_mesh_that_encloses_nothing_is_the_clis_error(tmp_path, run_cli):
    sheet = tmp_path / "sheet.obj"
    sheet.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
    p = run_cli("segment", str(sheet), check=False)
    assert p.returncode == 2
    with pytest.raises(bvseg.MeshError) as e:
        bvseg.segment(sheet)
    assert p.stderr.strip() == f"bvseg: error: {e.value}"


def test_output_errors(tmp_path, bunny12):
    with pytest.raises(ValueError, match="unsupported output format '.ply'"):
        bunny12.save(tmp_path / "out.ply")
    with pytest.raises(FileNotFoundError):
        bunny12.save(tmp_path / "no" / "such" / "out.json")
    with pytest.raises(ValueError, match="with_mesh applies to a .glb output"):
        bunny12.save(tmp_path / "out.json", with_mesh=True)
    assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_mesh_warnings_are_issued(tmp_path):
    # A tetrahedron with a repeated vertex, used by a repeated face: welded, and reported.
    obj = tmp_path / "two.obj"
    obj.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\nf 5 3 2\n"
    )
    m = bvseg.load_mesh(obj)
    assert m.warnings and m.stats["welded"] == 1
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        r = bvseg.segment(obj, k=1, **FAST)
    assert [str(x.message) for x in w if x.category is bvseg.BvsegWarning] == [f"{obj}: {t}" for t in m.warnings]
    assert r.warnings == m.warnings


# --- progress, cancellation, threads, the GIL -------------------------------------------------


def test_progress_is_called_per_step(bunny12):
    steps: list[dict] = []
    r = bvseg.segment(SPOT, progress=steps.append)
    # Each step the run makes, in order, with the keys of the file's history (which also
    # records what a step undid, such as a backtracked split).
    assert len(steps) > 3 and all(set(s) == set(r.history[0]) for s in steps)
    it = iter(r.history)
    assert all(any(s == h for h in it) for s in steps)
    assert steps[-1] == r.history[-1] and steps[-1]["step"] == "final" and steps[-1]["k"] == r.k


def test_a_raising_callback_cancels_and_propagates():
    seen = []

    class Stop(Exception):
        pass

    def cb(step):
        seen.append(step["k"])
        if len(seen) == 3:
            raise Stop("enough")

    t = time.perf_counter()
    with pytest.raises(Stop, match="enough"):
        bvseg.segment(SPOT, tov=0.01, max_k=200, progress=cb)
    assert len(seen) == 3
    assert time.perf_counter() - t < 30


def test_timeout():
    with pytest.raises(TimeoutError, match=r"gave up after 0.2 s \(timeout\)"):
        bvseg.segment(SPOT, tov=0.001, max_k=1000, timeout=0.2)
    # A generous one changes nothing.
    assert bvseg.segment(BUNNY, k=12, timeout=600).to_json() == bvseg.segment(BUNNY, k=12).to_json()


def test_results_do_not_depend_on_threads():
    one = bvseg.segment(FOURLEG, k=10, threads=1, **FAST).to_json()
    two = bvseg.segment(FOURLEG, k=10, threads=2, **FAST).to_json()
    assert one == two


def test_the_gil_is_released_during_a_run():
    done = threading.Event()
    result = {}

    def work():
        result["r"] = bvseg.segment(SPOT, samples=10000)  # a second or two
        done.set()

    t = threading.Thread(target=work)
    stamps = []
    t.start()
    while not done.is_set():
        stamps.append(time.perf_counter())
        sum(range(200))  # pure-Python work, which needs the GIL
    t.join()
    assert result["r"].k > 1
    run_time = stamps[-1] - stamps[0]
    gaps = np.diff(stamps)
    # Were the GIL held during the run, this thread would have stopped for all of it.
    assert run_time > 0.5, run_time
    assert gaps.max() < 0.25 * run_time, (gaps.max(), run_time)
    assert len(stamps) > 1000


@pytest.mark.parametrize("threads", [None, 2])
def test_ctrl_c_stops_a_run(threads):
    import _thread
    import signal

    # Python's own Ctrl-C handler, which a process started in the background (nohup, `&` in a
    # script) does not get: there SIGINT is ignored, and so is interrupt_main.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, _thread.interrupt_main)
    t = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            bvseg.segment(SPOT, tov=0.001, max_k=1000, threads=threads)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert time.perf_counter() - t < 20


def test_a_skinned_character_returns_its_bones():
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "assets" / "characters" / "CesiumMan.glb"
    result = bvseg.segment(str(path), samples=6000)
    bones = result.bones
    assert len(bones) == result.k
    assert all(b is not None for b in bones)
    assert len({b["joint"] for b in bones}) >= 8
    assert [v["bone"] for v in result.volumes] == [b["node"] for b in bones]
