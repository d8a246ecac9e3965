"""bvseg.verify: the independent check, against the command line's `bvseg verify --json`."""

from __future__ import annotations

import json

import pytest

import bvseg
from conftest import BUNNY, FOURLEG

POINTS = 100_000


@pytest.fixture(scope="module")
def result() -> bvseg.Segmentation:
    return bvseg.segment(FOURLEG, k=10, samples=6000)


def test_segmentations_enclose_the_mesh(result):
    report = bvseg.verify(FOURLEG, result, points=POINTS)
    assert report["enclosed"] is True
    assert report["triangles_unenclosed"] == 0 and report["max_escape_rel"] == 0
    assert report["triangles"] == 2956 and report["closed"]
    assert report["k"] == 10 and report["reported_tov"] == result.metrics["tov"]
    # The verifier's own estimate agrees with the run's, within its grid's error.
    assert abs(report["tov"] - result.metrics["tov"]) < 0.05 + 5 * report["tov_se"]


@pytest.mark.parametrize("kinds", ["capsule", "hull", "ellipsoid", "sphere,cylinder"])
def test_every_kind_encloses(kinds):
    r = bvseg.segment(BUNNY, k=8, samples=5000, kinds=kinds)
    assert bvseg.verify(BUNNY, r, points=POINTS)["enclosed"]


def test_every_volumes_form_gives_the_same_report(tmp_path, result):
    path = tmp_path / "v.json"
    result.save(path)
    forms = [result, result.volumes, result.document, result.to_json(), path, str(path)]
    reports = [bvseg.verify(FOURLEG, v, points=POINTS) for v in forms]
    strip = lambda r: {k: v for k, v in r.items() if k not in ("volumes_file", "kind", "reported_tov", "reported_mov", "reported_protrusion_rel")}  # noqa: E731
    for r in reports[1:]:
        assert strip(r) == strip(reports[0])
    assert reports[4]["volumes_file"] == str(path)
    mesh = bvseg.load_mesh(FOURLEG)
    assert bvseg.verify(mesh, result, points=POINTS) == reports[0]
    assert bvseg.verify(tuple(mesh), result, points=POINTS)["enclosed"]


def test_the_report_is_the_clis(tmp_path, run_cli, result):
    path = tmp_path / "v.json"
    result.save(path)
    cli = json.loads(run_cli("verify", str(FOURLEG), str(path), "--json", "--points", str(POINTS)).stdout)
    py = bvseg.verify(FOURLEG, path, points=POINTS)
    py["mesh"] = str(FOURLEG)
    assert py == cli
    assert bvseg.verify(FOURLEG, path, points=POINTS, threads=1) == bvseg.verify(FOURLEG, path, points=POINTS, threads=2)


def test_a_shrunk_volume_escapes(result):
    vols = [dict(v) for v in result.volumes]
    for v in vols:
        v["radii"] = [0.5 * x for x in v.get("radii", [])] or v.get("radii")
        if "radius" in v:
            v["radius"] *= 0.5
    report = bvseg.verify(FOURLEG, vols, points=POINTS)
    assert report["enclosed"] is False
    assert report["triangles_unenclosed"] > 0 and report["max_escape_rel"] > 0.01
    assert report["worst_triangle"] is not None


def test_bad_documents_and_options(tmp_path, result):
    with pytest.raises(ValueError, match="schema must be"):
        bvseg.verify(FOURLEG, {"volumes": result.volumes})
    with pytest.raises(ValueError, match="volumes must be a non-empty list"):
        bvseg.verify(FOURLEG, [])
    bad = [dict(v) for v in result.volumes]
    bad[2]["fraction"] = -1
    with pytest.raises(ValueError, match="volume 2"):
        bvseg.verify(FOURLEG, bad)
    with pytest.raises(ValueError, match="not valid JSON"):
        bvseg.verify(FOURLEG, "{not json")
    with pytest.raises(ValueError, match="points"):
        bvseg.verify(FOURLEG, result, points=10)
    with pytest.raises(FileNotFoundError):
        bvseg.verify(FOURLEG, tmp_path / "missing.json")
    with pytest.raises(bvseg.MeshError):
        bvseg.verify((result.mesh.vertices, [[0, 1, 10**9]]), result)
    with pytest.raises(TypeError, match="volumes must be"):
        bvseg.verify(FOURLEG, 3.5)
