//! `bvseg robot` on a two-link robot written by the test: every link's collision vertices lie
//! in its new volumes, the URDF keeps no mesh collision, and bad robots are one-line errors
//! with nothing written; the bundled MJCF arm; robots in `bvseg batch`.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;

use bvseg_testkit::{files, run, scratch};
use glam::DVec3;

const BIN: &str = env!("CARGO_BIN_EXE_bvseg");

/// An OBJ box from `lo` to `hi`.
fn write_box(path: &Path, lo: DVec3, hi: DVec3) -> Vec<DVec3> {
    let v: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let faces = [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    let mut s = String::new();
    for p in &v {
        s += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for f in faces {
        s += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    fs::write(path, s).unwrap();
    v
}

fn urdf(base_mesh: &str, second_link: &str, child: &str) -> String {
    format!(
        r#"<?xml version="1.0"?>
<robot name="two">
  <!-- kept as it is -->
  <link name="base">
    <visual><geometry><mesh filename="meshes/base.obj"/></geometry></visual>
    <collision><geometry><mesh filename="{base_mesh}"/></geometry></collision>
  </link>
  <link name="{second_link}">
    <collision>
      <origin xyz="0 0 0.5" rpy="0 0 0"/>
      <geometry><mesh filename="package://two/meshes/arm.obj" scale="1 1 2"/></geometry>
    </collision>
  </link>
  <joint name="j" type="revolute">
    <parent link="base"/><child link="{child}"/>
    <origin xyz="0 0 1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>
"#
    )
}

fn setup(dir: &Path) -> (Vec<DVec3>, Vec<DVec3>) {
    fs::create_dir_all(dir.join("meshes")).unwrap();
    let base = write_box(
        &dir.join("meshes/base.obj"),
        DVec3::ZERO,
        DVec3::new(1.0, 0.6, 1.0),
    );
    let arm = write_box(
        &dir.join("meshes/arm.obj"),
        DVec3::new(0.4, 0.2, 0.0),
        DVec3::new(0.6, 0.4, 0.5),
    );
    // The arm's collision is scaled by 2 in z and moved up by 0.5 in its link's frame.
    let arm = arm
        .into_iter()
        .map(|p| DVec3::new(p.x, p.y, 2.0 * p.z + 0.5))
        .collect();
    (base, arm)
}

#[test]
fn a_robot_gets_primitive_colliders_per_link() {
    let dir = scratch("robot_ok");
    let (base, arm) = setup(&dir);
    fs::write(dir.join("two.urdf"), urdf("meshes/base.obj", "arm", "arm")).unwrap();
    let out = run(
        BIN,
        &dir,
        &["robot", "two.urdf", "-o", "out", "--samples", "3000", "-q"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (link, vertices) in [("base", &base), ("arm", &arm)] {
        let doc = bvseg_io::read_volumes(dir.join(format!("out/links/{link}.json"))).unwrap();
        for p in vertices {
            assert!(
                doc.volumes.iter().any(|v| v.contains(*p)),
                "{link}: {p} is outside its volumes"
            );
        }
    }
    let text = fs::read_to_string(dir.join("out/two.urdf")).unwrap();
    assert!(text.contains("<!-- kept as it is -->"));
    let collisions: Vec<&str> = text.split("<collision").skip(1).collect();
    assert!(!collisions.is_empty());
    assert!(collisions
        .iter()
        .all(|c| !c[..c.find("</collision>").unwrap()].contains("<mesh")));
    assert!(
        text.contains(r#"<mesh filename="meshes/base.obj"/>"#),
        "the visual is kept"
    );
    let curobo = fs::read_to_string(dir.join("out/curobo.yml")).unwrap();
    assert!(curobo.contains("collision_spheres") && curobo.contains("self_collision_ignore"));
    assert!(dir.join("out/two.xml").is_file());
}

/// An MJCF robot of one body whose collision mesh is `mesh`, including `include` (a file
/// name, or nothing).
fn mjcf(mesh: &str, include: &str) -> String {
    let include = if include.is_empty() {
        String::new()
    } else {
        format!("<include file=\"{include}\"/>")
    };
    format!(
        r#"<mujoco model="one">
  {include}
  <asset><mesh name="m" file="{mesh}"/></asset>
  <worldbody><body name="b"><geom type="mesh" mesh="m"/></body></worldbody>
</mujoco>
"#
    )
}

#[test]
fn bad_robots_are_one_line_errors_and_write_nothing() {
    // (case, file name, its text, what the one line must name)
    let cases: Vec<(&str, &str, String, Vec<&str>)> = vec![
        (
            "missing mesh",
            "two.urdf",
            urdf("meshes/nothere.obj", "arm", "arm"),
            vec!["two.urdf", "\"base\"", "meshes/nothere.obj", "not found"],
        ),
        (
            "link named twice",
            "two.urdf",
            urdf("meshes/base.obj", "base", "base"),
            vec!["two.urdf", "\"base\"", "used twice"],
        ),
        (
            "joint to no link",
            "two.urdf",
            urdf("meshes/base.obj", "arm", "hand"),
            vec!["two.urdf", "\"j\"", "\"hand\"", "not a link"],
        ),
        (
            "unreadable mesh format",
            "two.urdf",
            urdf("meshes/base.dae", "arm", "arm"),
            vec!["\"base\"", "base.dae", "unsupported mesh format '.dae'"],
        ),
        (
            "mesh that does not parse",
            "two.urdf",
            urdf("meshes/broken.obj", "arm", "arm"),
            vec!["\"base\"", "broken.obj"],
        ),
        (
            "mesh without volume",
            "two.urdf",
            urdf("meshes/flat.obj", "arm", "arm"),
            vec!["two.urdf", "link \"base\"", "enclose no volume"],
        ),
        (
            "include cycle",
            "one.xml",
            mjcf("meshes/base.obj", "inc.xml"),
            vec!["include cycle", "one.xml", "inc.xml"],
        ),
        (
            "unknown class",
            "one.xml",
            mjcf("meshes/base.obj", "").replace(r#"type="mesh""#, r#"class="nope""#),
            vec!["one.xml", "unknown default class \"nope\""],
        ),
    ];
    for (case, name, text, needles) in cases {
        let dir = scratch(&format!("robot_bad_{}", case.replace(' ', "_")));
        setup(&dir);
        fs::write(dir.join("meshes/base.dae"), "<COLLADA/>").unwrap();
        fs::write(dir.join("meshes/broken.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
        fs::write(
            dir.join("meshes/flat.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
        )
        .unwrap();
        // inc.xml includes one.xml, which includes inc.xml.
        fs::write(
            dir.join("inc.xml"),
            r#"<mujoco><include file="one.xml"/></mujoco>"#,
        )
        .unwrap();
        fs::write(dir.join(name), text).unwrap();
        let out = run(
            BIN,
            &dir,
            &["robot", name, "-o", "out", "--samples", "3000"],
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{case}: {err}");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{case}: not one line: {err}");
        assert!(lines[0].starts_with("bvseg: error: "), "{case}: {err}");
        for n in needles {
            assert!(lines[0].contains(n), "{case}: {n:?} not in {err}");
        }
        assert!(!dir.join("out").exists(), "{case}: wrote output");
    }
}

/// The bundled MJCF arm (assets/robots/arm): four bodies, their collision meshes (visual ones
/// skipped), the capsule kept, and no mesh left in the outputs. That the meshes are placed
/// where MuJoCo places them is checked with MuJoCo by scripts/check_robot.py (CI's engine
/// check).
#[test]
fn the_bundled_mjcf_arm() {
    let dir = scratch("robot_arm");
    let arm = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/robots/arm/arm.xml");
    let out = run(
        BIN,
        &dir,
        &[
            "robot",
            arm.to_str().unwrap(),
            "-o",
            "out",
            "--max-parts",
            "3",
            "--samples",
            "2000",
            "-q",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        files(&dir.join("out/links")),
        ["base.json", "finger.json", "lower.json", "upper.json"]
    );
    let xml = fs::read_to_string(dir.join("out/bvseg_arm.xml")).unwrap();
    assert!(!xml.contains("type=\"mesh\""), "a mesh geom is left");
    assert_eq!(xml.matches("upper_kept_").count(), 1, "the capsule");
    assert_eq!(xml.matches("finger_kept_").count(), 1, "the pad");
    assert!(xml.contains("type=\"capsule\""));
    // --max-parts 3 bounds every link.
    for link in ["base", "upper", "lower", "finger"] {
        let doc = bvseg_io::read_volumes(dir.join(format!("out/links/{link}.json"))).unwrap();
        assert!((1..=3).contains(&doc.volumes.len()), "{link}");
    }
    let urdf = fs::read_to_string(dir.join("out/bvseg_arm.urdf")).unwrap();
    assert!(!urdf.contains("<mesh"));
    assert_eq!(urdf.matches("<joint ").count(), 3);
}

#[test]
fn batch_runs_robots_one_directory_each() {
    let dir = scratch("robot_batch");
    setup(&dir);
    fs::write(dir.join("two.urdf"), urdf("meshes/base.obj", "arm", "arm")).unwrap();
    fs::write(
        dir.join("bad.urdf"),
        urdf("meshes/nothere.obj", "arm", "arm"),
    )
    .unwrap();
    // one.xml's mesh sits beside it: part of the robot, not an input of its own.
    fs::copy(dir.join("meshes/arm.obj"), dir.join("part.obj")).unwrap();
    fs::write(dir.join("one.xml"), mjcf("part.obj", "")).unwrap();
    // Not robots: an XML of something else, and an MJCF bvseg wrote.
    fs::write(dir.join("notes.xml"), "<notes/>").unwrap();
    fs::write(
        dir.join("proxies.xml"),
        "<mujoco model=\"x\">\n  <!-- bvseg 0.0.1 -->\n</mujoco>\n",
    )
    .unwrap();
    fs::copy(bvseg_testkit::BUNNY, dir.join("bunny.obj")).unwrap();
    let args = [
        "batch",
        ".",
        "-o",
        "out",
        "--samples",
        "2000",
        "--k",
        "2",
        "--max-parts",
        "2",
    ];
    let out = run(BIN, &dir, &args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "the bad robot: {err}");
    let csv = fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let status: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        status,
        [
            ("bad.urdf", "error"),
            ("bunny.obj", "done"),
            ("one.xml", "done"),
            ("two.urdf", "done")
        ],
        "{csv}"
    );
    assert!(csv.contains("nothere.obj"), "{csv}");
    // two.urdf: two links of 2 parts each, and their triangles.
    assert_eq!(rows[3][2], "24");
    assert_eq!(rows[3][3], "4");
    assert_eq!(
        files(&dir.join("out/two")),
        ["curobo.yml", "links", "two.urdf", "two.xml"]
    );
    assert_eq!(
        files(&dir.join("out/one")),
        ["curobo.yml", "links", "one.urdf", "one.xml"]
    );
    assert!(!dir.join("out/bad").join("curobo.yml").exists());
    // Rerun: the robots are done, the bad one is tried again.
    let stamp = fs::metadata(dir.join("out/two/two.urdf"))
        .unwrap()
        .modified()
        .unwrap();
    let out = run(BIN, &dir, &args);
    assert_eq!(out.status.code(), Some(2));
    let csv = fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    assert!(
        csv.contains("two.urdf,skipped") && csv.contains("one.xml,skipped"),
        "{csv}"
    );
    assert!(csv.contains("bad.urdf,error"), "{csv}");
    let again = fs::metadata(dir.join("out/two/two.urdf"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(stamp, again);
}
