//! `segment` with several outputs, `--json`, `--plot`, `--strict`, limits; `info`; `batch`.
// Tests and benchmarks state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;
use std::process::Output;

use bvseg_testkit::{scratch, stderr, BUNNY};

const BIN: &str = env!("CARGO_BIN_EXE_bvseg");

fn bvseg(dir: &Path, args: &[&str]) -> Output {
    bvseg_testkit::run(BIN, dir, args)
}

#[test]
fn every_output_format_in_one_run() {
    let dir = scratch("every_output_format_in_one_run");
    let o = bvseg(
        &dir,
        &[
            "segment",
            BUNNY,
            "--samples",
            "2000",
            "--k",
            "3",
            "--bv",
            "mixed",
            "-o",
            "v.json",
            "-o",
            "v.glb",
            "-o",
            "v.xml",
            "-o",
            "v.obj",
            "--with-mesh",
            "--labels",
            "l.txt",
            "--plot",
            "p.svg",
            "--json",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(o.stderr.is_empty(), "{}", stderr(&o));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["k"], 3);
    assert_eq!(summary["triangles"], 3674);
    assert!(
        summary["tolerances_met"].is_null(),
        "fixed k has no tolerances"
    );
    assert_eq!(summary["outputs"].as_array().unwrap().len(), 4);

    let doc: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("v.json")).unwrap()).unwrap();
    let vols = doc["volumes"].as_array().unwrap();
    assert_eq!(vols.len(), 3);
    // Three leaves and two inner nodes.
    assert_eq!(doc["hierarchy"].as_array().unwrap().len(), 5);
    // MJCF: one geom per volume, sizes equal to the JSON radii.
    let xml = fs::read_to_string(dir.join("v.xml")).unwrap();
    let x = roxmltree::Document::parse(&xml).unwrap();
    let geoms: Vec<_> = x.descendants().filter(|n| n.has_tag_name("geom")).collect();
    assert_eq!(geoms.len(), 3);
    for (g, v) in geoms.iter().zip(vols) {
        let size: Vec<f64> = g
            .attribute("size")
            .unwrap()
            .split(' ')
            .map(|s| s.parse().unwrap())
            .collect();
        let radii: Vec<f64> = v["radii"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_f64().unwrap())
            .collect();
        assert_eq!(size, radii);
        let ty = if v["shape"] == "obb" {
            "box"
        } else {
            "ellipsoid"
        };
        assert_eq!(g.attribute("type"), Some(ty));
    }
    // GLB: starts as one, has the three parts and the input mesh.
    let glb = fs::read(dir.join("v.glb")).unwrap();
    assert!(glb.starts_with(b"glTF"));
    let text = String::from_utf8_lossy(&glb);
    for i in 0..3 {
        assert!(text.contains(&format!("\"part_{i}\"")));
    }
    assert!(text.contains("\"input_mesh\""));
    // OBJ: one object per part.
    let obj = fs::read_to_string(dir.join("v.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("o part_")).count(), 3);
    // Labels: one per triangle, each a part.
    let labels = fs::read_to_string(dir.join("l.txt")).unwrap();
    assert_eq!(labels.lines().count(), 3674);
    assert!(labels.lines().all(|l| l.parse::<usize>().unwrap() < 3));
    let svg = fs::read_to_string(dir.join("p.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("<polyline") && svg.trim_end().ends_with("</svg>")
    );
    roxmltree::Document::parse(&svg).unwrap();
}

/// `--no-hierarchy` leaves the JSON's hierarchy empty and every other field as it was.
#[test]
fn no_hierarchy_empties_only_the_hierarchy() {
    let dir = scratch("no_hierarchy_empties_only_the_hierarchy");
    let run = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "segment",
            BUNNY,
            "--samples",
            "2000",
            "--k",
            "4",
            "-q",
            "-o",
            out,
        ];
        args.extend_from_slice(extra);
        let o = bvseg(&dir, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = fs::read_to_string(dir.join(out)).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let mut with = run("with.json", &[]);
    let without = run("without.json", &["--no-hierarchy"]);
    assert_eq!(with["hierarchy"].as_array().unwrap().len(), 7);
    assert_eq!(without["hierarchy"], serde_json::json!([]));
    with["hierarchy"] = serde_json::json!([]);
    assert_eq!(with, without);
}

#[test]
fn strict_exits_3_when_tolerances_are_not_met() {
    let dir = scratch("strict_exits_3_when_tolerances_are_not_met");
    let args = [
        "segment",
        BUNNY,
        "--samples",
        "2000",
        "--max-k",
        "2",
        "--tov",
        "0.01",
        "--mov",
        "0.01",
        "--plot",
        "p.svg",
    ];
    let o = bvseg(&dir, &args);
    assert!(
        o.status.success(),
        "without --strict only a warning: {}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("warning: tolerances not met"));
    let svg = fs::read_to_string(dir.join("p.svg")).unwrap();
    assert!(svg.contains("TOV tolerance 0.01"), "tolerance lines drawn");
    let mut strict = args.to_vec();
    strict.extend(["--strict", "-q", "--json"]);
    let o = bvseg(&dir, &strict);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["tolerances_met"], false);
}

#[test]
fn limits_and_output_checks_come_first() {
    let dir = scratch("limits_and_output_checks_come_first");
    let o = bvseg(
        &dir,
        &["segment", BUNNY, "--max-triangles", "1000", "-o", "a.json"],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("3674 triangles is above --max-triangles 1000"),
        "{}",
        stderr(&o)
    );
    let o = bvseg(
        &dir,
        &[
            "segment",
            BUNNY,
            "--samples",
            "200000",
            "--max-samples",
            "100000",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("above --max-samples"), "{}", stderr(&o));
    let o = bvseg(&dir, &["segment", BUNNY, "-o", "a.json", "--with-mesh"]);
    assert!(
        stderr(&o).contains("--with-mesh applies to a .glb output"),
        "{}",
        stderr(&o)
    );
    let o = bvseg(&dir, &["segment", BUNNY, "--plot", "p.png"]);
    assert!(stderr(&o).contains("name the file .svg"), "{}", stderr(&o));
    let o = bvseg(&dir, &["segment", BUNNY, "-o", "a.json", "-o", "a.json"]);
    assert!(stderr(&o).contains("named twice"), "{}", stderr(&o));
    assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
}

#[test]
fn info_reports_the_mesh() {
    let dir = scratch("info_reports_the_mesh");
    let o = bvseg(&dir, &["info", BUNNY, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["triangles"], 3674);
    assert_eq!(r["components"], 1);
    assert_eq!(r["open_edges"], 0);
    assert!(r["volume"].as_f64().unwrap() > 0.0);
    let o = bvseg(&dir, &["info", BUNNY]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("orientation   outward"), "{text}");
}

#[test]
fn batch_is_parallel_resumable_and_summarised() {
    let dir = scratch("batch_is_parallel_resumable_and_summarised");
    let input = dir.join("in");
    fs::create_dir_all(&input).unwrap();
    fs::copy(BUNNY, input.join("bunny.obj")).unwrap();
    // The same solid as ASCII STL, and a broken file.
    let m = bvseg_io::load(BUNNY, &Default::default()).unwrap().mesh;
    let mut stl = String::from("solid b\n");
    for t in m.triangles() {
        stl += "facet normal 0 0 0\nouter loop\n";
        for &i in t {
            let p = m.vertices()[i as usize];
            stl += &format!("vertex {} {} {}\n", p.x, p.y, p.z);
        }
        stl += "endloop\nendfacet\n";
    }
    stl += "endsolid b\n";
    fs::write(input.join("bunny.stl"), stl).unwrap();
    fs::write(input.join("broken.obj"), "v 0 0 0\n").unwrap();
    fs::write(input.join("notes.txt"), "not a mesh").unwrap();
    let args = [
        "batch",
        "in",
        "-o",
        "out",
        "--samples",
        "2000",
        "--k",
        "2",
        "--formats",
        "json,xml",
    ];
    let o = bvseg(&dir, &args);
    assert_eq!(o.status.code(), Some(2), "one file failed: {}", stderr(&o));
    let mut outs: Vec<String> = fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    outs.sort();
    assert_eq!(
        outs,
        [
            "bunny.obj.json",
            "bunny.obj.xml",
            "bunny.stl.json",
            "bunny.stl.xml",
            "summary.csv"
        ]
    );
    let csv = fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(
        rows[0],
        "file,status,triangles,k,tov,mov,tolerances_met,message"
    );
    assert!(rows[1].starts_with("broken.obj,error,"), "{csv}");
    assert!(rows[2].starts_with("bunny.obj,done,3674,2,"), "{csv}");
    assert!(rows[3].starts_with("bunny.stl,done,3674,2,"), "{csv}");
    // Same solid, same volumes.
    assert_eq!(
        fs::read(dir.join("out/bunny.obj.json")).unwrap(),
        fs::read(dir.join("out/bunny.stl.json")).unwrap()
    );
    // Resumed: finished files are skipped, keeping their figures.
    let o = bvseg(&dir, &args);
    let csv2 = fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    assert!(csv2.contains("bunny.obj,skipped,,2,"), "{csv2}");
    assert!(
        stderr(&o).contains("0 done, 2 skipped, 1 failed"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn labels_follow_the_file_triangles() {
    let dir = scratch("labels_follow_the_file_triangles");
    // The bunny with a degenerate triangle (a repeated corner) in second place.
    let text = fs::read_to_string(BUNNY).unwrap();
    let mut out = String::new();
    let mut faces = 0;
    for line in text.lines() {
        out += line;
        out += "\n";
        if line.starts_with("f ") {
            faces += 1;
            if faces == 1 {
                out += "f 1 1 2\n";
            }
        }
    }
    fs::write(dir.join("b.obj"), out).unwrap();
    let o = bvseg(
        &dir,
        &[
            "segment",
            "b.obj",
            "--samples",
            "2000",
            "--k",
            "2",
            "--labels",
            "l.txt",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let labels: Vec<i64> = fs::read_to_string(dir.join("l.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(labels.len(), 3675);
    assert_eq!(labels[1], -1);
    assert_eq!(labels.iter().filter(|&&l| l == -1).count(), 1);
    assert!(labels.iter().all(|&l| (-1..2).contains(&l)));
}

/// A skinned character through the command line: the GLB carries the file's skin and walk
/// (with `--with-mesh`, the mesh skinned), and the MJCF is a ragdoll with a free root.
#[test]
fn a_character_gets_a_skinned_glb_and_a_ragdoll() {
    let dir = scratch("a_character_gets_a_skinned_glb_and_a_ragdoll");
    let man = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/characters/CesiumMan.glb"
    );
    let o = bvseg(
        &dir,
        &[
            "segment",
            man,
            "--samples",
            "3000",
            "-o",
            "m.glb",
            "-o",
            "m.xml",
            "--with-mesh",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let glb = fs::read(dir.join("m.glb")).unwrap();
    let len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    assert_eq!(doc["skins"][0]["joints"].as_array().unwrap().len(), 19);
    assert_eq!(doc["animations"].as_array().unwrap().len(), 1);
    let skinned = doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == "input_mesh")
        .unwrap();
    assert_eq!(skinned["skin"], 0);
    let xml = fs::read_to_string(dir.join("m.xml")).unwrap();
    assert_eq!(xml.matches("<freejoint").count(), 1);
    assert!(xml.contains("type=\"ball\""));
}

#[test]
fn usd_output_takes_its_options_in_segment_and_batch() {
    let dir = scratch("usd_output_takes_its_options");
    let o = bvseg(
        &dir,
        &[
            "segment",
            BUNNY,
            "--samples",
            "2000",
            "--k",
            "5",
            "-o",
            "c.json",
            "-o",
            "c.usda",
            "--up-axis",
            "Z",
            "--meters-per-unit",
            "0.01",
            "--usd-rigid-body",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let text = fs::read_to_string(dir.join("c.usda")).unwrap();
    assert!(text.starts_with("#usda 1.0\n"));
    for needle in [
        "defaultPrim = \"c\"",
        "upAxis = \"Z\"",
        "metersPerUnit = 0.01",
        "def Xform \"c\" (\n    prepend apiSchemas = [\"PhysicsRigidBodyAPI\"]",
    ] {
        assert!(text.contains(needle), "{needle} not in\n{text}");
    }
    let doc: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("c.json")).unwrap()).unwrap();
    let volumes = doc["volumes"].as_array().unwrap().len();
    assert_eq!(text.matches("\"PhysicsCollisionAPI\"").count(), volumes);

    // Bad values are usage errors, before any run.
    for (flag, value) in [
        ("--up-axis", "X"),
        ("--meters-per-unit", "0"),
        ("--meters-per-unit", "-1"),
    ] {
        let o = bvseg(&dir, &["segment", BUNNY, flag, value, "-o", "d.usda"]);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        assert!(!dir.join("d.usda").exists());
    }

    // batch writes it through the same writer, with the same options.
    fs::create_dir_all(dir.join("in")).unwrap();
    fs::copy(BUNNY, dir.join("in/bunny.obj")).unwrap();
    let o = bvseg(
        &dir,
        &[
            "batch",
            "in",
            "-o",
            "out",
            "--formats",
            "json,usda",
            "--k",
            "4",
            "--samples",
            "2000",
            "--up-axis",
            "Z",
            "-q",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let batch = fs::read_to_string(dir.join("out/bunny.usda")).unwrap();
    assert!(batch.contains("defaultPrim = \"bunny\"") && batch.contains("upAxis = \"Z\""));
    assert_eq!(batch.matches("\"PhysicsCollisionAPI\"").count(), 4);
}
