//! `bvseg robot` on a two-link robot written by the test: every link's collision vertices lie
//! in its new volumes, the URDF keeps no mesh collision, and bad robots are one-line errors
//! with nothing written; meshes it cannot replace are kept with a warning; MJCF robots given
//! back as written but for their colliding mesh geoms (the bundled arms, and one written
//! here); robots in `bvseg batch`. That the new MJCF geoms sit where MuJoCo places the meshes
//! is checked with MuJoCo by scripts/check_robot.py (CI's engine check).
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
    // USD: one Xform per link at its world pose with the joint at zero, the link's colliders
    // under it in its frame.
    let usd = fs::read_to_string(dir.join("out/two.usda")).unwrap();
    assert!(usd.contains("defaultPrim = \"two\"") && usd.contains("upAxis = \"Z\""));
    let arm = &usd[usd.find("def Xform \"arm\"").unwrap()..];
    assert!(
        arm.contains("double3 xformOp:translate = (0, 0, 1)"),
        "{arm}"
    );
    let colliders = usd.matches("PhysicsCollisionAPI").count();
    let parts: usize = ["base", "arm"]
        .iter()
        .map(|l| {
            bvseg_io::read_volumes(dir.join(format!("out/links/{l}.json")))
                .unwrap()
                .volumes
                .len()
        })
        .sum();
    assert_eq!(colliders, parts);
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
            "mesh that does not parse",
            "two.urdf",
            urdf("meshes/broken.obj", "arm", "arm"),
            vec!["\"base\"", "broken.obj"],
        ),
        (
            "missing MJCF mesh",
            "one.xml",
            mjcf("meshes/nothere.stl", ""),
            vec!["one.xml", "\"b\"", "meshes/nothere.stl", "not found"],
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
    assert_eq!(
        files(&dir.join("out")),
        [
            "arm_bodies.xml",
            "bvseg_arm.urdf",
            "bvseg_arm.usda",
            "bvseg_arm.xml",
            "curobo.yml",
            "links",
            "manifest.json"
        ]
    );
    // The body tree is in the included file: its collision meshes are replaced there, and its
    // visual meshes, capsule and pad are as they were.
    let bodies = fs::read_to_string(dir.join("out/arm_bodies.xml")).unwrap();
    let original = fs::read_to_string(arm.parent().unwrap().join("arm_bodies.xml")).unwrap();
    for line in original
        .lines()
        .filter(|l| !l.contains("class=\"collision\""))
    {
        assert!(bodies.contains(line), "{line:?} is not kept");
    }
    for body in ["base", "upper", "lower", "finger"] {
        assert!(
            bodies.contains(&format!("name=\"{body}_bvseg_0\"")),
            "{body}"
        );
    }
    let xml = fs::read_to_string(dir.join("out/bvseg_arm.xml")).unwrap();
    assert!(xml.contains("<include file=\"arm_bodies.xml\"/>"));
    assert!(xml.contains("<!-- bvseg "), "marked as bvseg's");
    // --max-parts 3 bounds every link.
    for link in ["base", "upper", "lower", "finger"] {
        let doc = bvseg_io::read_volumes(dir.join(format!("out/links/{link}.json"))).unwrap();
        assert!((1..=3).contains(&doc.volumes.len()), "{link}");
    }
    let urdf = fs::read_to_string(dir.join("out/bvseg_arm.urdf")).unwrap();
    assert!(!urdf.contains("<mesh"));
    assert_eq!(urdf.matches("upper_kept_").count(), 1, "the capsule");
    assert_eq!(urdf.matches("finger_kept_").count(), 1, "the pad");
    // The world and four bodies: the base's joint to the world, and the three joints.
    assert_eq!(urdf.matches("<joint ").count(), 4);
    assert!(urdf.contains("<joint name=\"shoulder\" type=\"revolute\">"));
    assert!(urdf.contains("<joint name=\"slide\" type=\"prismatic\">"));
}

/// An MJCF written as MuJoCo saves robots: the base's collision mesh in the world body, a
/// `<frame>` around a body's mesh, visual twins, an actuator; with an include and a relative
/// mesh directory.
const SAVED: &str = r#"<mujoco model="saved">
  <compiler angle="radian" meshdir="meshes"/>
  <!-- kept -->
  <asset>
    <mesh name="base" file="base.obj"/>
    <mesh name="arm" file="arm.obj" scale="1 1 2"/>
  </asset>
  <worldbody>
    <geom type="mesh" contype="0" conaffinity="0" group="1" density="0" mesh="base"/>
    <geom type="mesh" rgba="1 1 1 1" mesh="base"/>
    <body name="link1" pos="0 0 1">
      <inertial pos="0 0 0.5" mass="1" diaginertia="0.1 0.1 0.1"/>
      <joint name="joint1" range="-1 1"/>
      <frame pos="0 0 0.5" quat="0.7071067811865476 0 0 0.7071067811865476">
        <geom type="mesh" contype="0" conaffinity="0" group="1" density="0" mesh="arm"/>
        <geom name="arm_collision" type="mesh" friction="0.5" mesh="arm"/>
      </frame>
      <include file="hand.xml"/>
    </body>
  </worldbody>
  <actuator>
    <position name="act1" joint="joint1" kp="10"/>
  </actuator>
</mujoco>
"#;

const HAND: &str = r#"<mujoco>
  <body name="hand" pos="0 0 1">
    <joint name="joint2" type="slide" axis="1 0 0" range="0 0.1"/>
    <geom type="mesh" mesh="arm" pos="0.5 0 0"/>
  </body>
</mujoco>
"#;

#[test]
fn an_mjcf_robot_comes_back_as_written_with_primitive_colliders() {
    let dir = scratch("robot_mjcf_kept");
    let (base, arm) = setup(&dir);
    fs::write(dir.join("saved.xml"), SAVED).unwrap();
    fs::write(dir.join("hand.xml"), HAND).unwrap();
    let out = run(
        BIN,
        &dir,
        &["robot", "saved.xml", "-o", "out/robot", "--samples", "3000"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("warning"), "{err}");
    assert_eq!(
        files(&dir.join("out/robot")),
        [
            "curobo.yml",
            "hand.xml",
            "links",
            "manifest.json",
            "saved.urdf",
            "saved.usda",
            "saved.xml"
        ]
    );
    // The world's and each body's collision meshes are segmented in its frame: the world's
    // base as it is, the arm scaled by 2 in z and placed by its frame (a quarter turn about
    // z, 0.5 up), the hand's arm moved by 0.5 in x.
    // setup() gives the arm as the URDF places it (z scaled by 2, then 0.5 up): undo it.
    let arm: Vec<DVec3> = arm
        .iter()
        .map(|p| DVec3::new(p.x, p.y, (p.z - 0.5) / 2.0))
        .collect();
    let quarter = |p: DVec3| DVec3::new(-p.y, p.x, 2.0 * p.z + 0.5);
    for (link, vertices) in [
        ("world", base.clone()),
        ("link1", arm.iter().map(|&p| quarter(p)).collect()),
        (
            "hand",
            arm.iter()
                .map(|&p| DVec3::new(p.x + 0.5, p.y, 2.0 * p.z))
                .collect(),
        ),
    ] {
        let doc = bvseg_io::read_volumes(dir.join(format!("out/robot/links/{link}.json"))).unwrap();
        for p in vertices {
            assert!(
                doc.volumes.iter().any(|v| v.contains(p)),
                "{link}: {p} is outside its volumes"
            );
        }
    }
    let xml = fs::read_to_string(dir.join("out/robot/saved.xml")).unwrap();
    // Every line but the colliding mesh geoms' is kept, in order; the mesh directory leads
    // back to the input's.
    let kept: Vec<String> = SAVED
        .lines()
        .filter(|l| !l.contains("type=\"mesh\"") || l.contains("contype=\"0\""))
        .map(|l| l.replace("meshdir=\"meshes\"", "meshdir=\"../../meshes\""))
        .collect();
    let mut at = 0;
    for line in &kept {
        let found = xml[at..]
            .find(line)
            .unwrap_or_else(|| panic!("{line:?} not kept in order:\n{xml}"));
        at += found + line.len();
    }
    // The new geoms: where the meshes were, in the frame the mesh was written in, with its
    // other attributes; no colliding mesh geom left.
    assert!(xml.contains("<geom name=\"world_bvseg_0\" type="), "{xml}");
    assert!(
        xml.contains("<geom name=\"arm_collision_bvseg_0\" type="),
        "{xml}"
    );
    assert!(xml.contains("friction=\"0.5\"/>"), "{xml}");
    let frame = &xml[xml.find("<frame").unwrap()..xml.find("</frame>").unwrap()];
    assert!(frame.contains("arm_collision_bvseg_0"), "{frame}");
    let hand = fs::read_to_string(dir.join("out/robot/hand.xml")).unwrap();
    assert!(hand.contains("<geom name=\"hand_bvseg_0\" type="), "{hand}");
    assert!(hand.contains("<joint name=\"joint2\" type=\"slide\" axis=\"1 0 0\" range=\"0 0.1\"/>"));
    for text in [&xml, &hand] {
        assert!(!text
            .lines()
            .any(|l| l.contains("type=\"mesh\"") && !l.contains("contype=\"0\"")));
    }
    // The hand has no <inertial>: MuJoCo weighs it by its geoms, so its mesh stays for its
    // mass, no longer colliding, and the new geoms weigh nothing.
    assert!(
        hand.contains("contype=\"0\" conaffinity=\"0\" type=\"mesh\" mesh=\"arm\""),
        "{hand}"
    );
    assert!(hand.contains("mass=\"0\""), "{hand}");
    let manifest: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("out/robot/manifest.json")).unwrap())
            .unwrap();
    assert_eq!(
        manifest["files"].as_array().unwrap().last().unwrap(),
        "curobo.yml"
    );
    assert_eq!(manifest["links"][0]["name"], "world");
    // The URDF has the world as a link, and the first body's joint.
    let urdf = fs::read_to_string(dir.join("out/robot/saved.urdf")).unwrap();
    assert!(
        urdf.contains("<joint name=\"joint1\" type=\"revolute\">"),
        "{urdf}"
    );
    assert!(urdf.contains("<parent link=\"world\"/>"), "{urdf}");
}

#[test]
fn meshes_that_cannot_be_replaced_stay_with_a_warning() {
    // (file name, text, what the warning names, what the output keeps)
    let cases: Vec<(&str, String, Vec<&str>, &str)> = vec![
        (
            "two.urdf",
            urdf("meshes/base.dae", "arm", "arm"),
            vec!["\"base\"", "base.dae", "unsupported mesh format '.dae'"],
            r#"<collision><geometry><mesh filename="meshes/base.dae"/></geometry></collision>"#,
        ),
        (
            "two.urdf",
            urdf("meshes/flat.obj", "arm", "arm"),
            vec!["two.urdf", "link \"base\"", "enclose no volume"],
            r#"<collision><geometry><mesh filename="meshes/flat.obj"/></geometry></collision>"#,
        ),
        (
            "one.xml",
            mjcf("meshes/base.obj", "").replace(
                r#"<mesh name="m" file="meshes/base.obj"/>"#,
                r#"<mesh name="m" vertex="0 0 0 1 0 0 0 1 0 0 0 1"/>"#,
            ),
            vec!["one.xml", "\"b\"", "given by vertices"],
            r#"<geom type="mesh" mesh="m"/>"#,
        ),
    ];
    for (name, text, needles, kept) in cases {
        let dir = scratch("robot_kept_with_warning");
        setup(&dir);
        fs::write(dir.join("meshes/base.dae"), "<COLLADA/>").unwrap();
        fs::write(
            dir.join("meshes/flat.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
        )
        .unwrap();
        fs::write(dir.join(name), text).unwrap();
        let out = run(
            BIN,
            &dir,
            &["robot", name, "-o", "out", "--samples", "3000"],
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{name}: {err}");
        let warning = err
            .lines()
            .find(|l| l.starts_with("bvseg: warning: "))
            .unwrap_or_else(|| panic!("{name}: no warning: {err}"));
        for n in needles {
            assert!(warning.contains(n), "{n:?} not in {warning}");
        }
        let written = fs::read_dir(dir.join("out"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                p.extension().is_some_and(|e| e == "urdf" || e == "xml")
                    && p.extension() == Path::new(name).extension()
            })
            .unwrap();
        let written = fs::read_to_string(written).unwrap();
        assert!(
            written.contains(kept),
            "{name}: {kept} not kept:\n{written}"
        );
        let manifest: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(dir.join("out/manifest.json")).unwrap())
                .unwrap();
        assert_eq!(manifest["warnings"][0], warning["bvseg: warning: ".len()..]);
    }
}

#[test]
fn outputs_never_replace_the_robots_own_files() {
    let dir = scratch("robot_overwrite");
    setup(&dir);
    fs::write(dir.join("one.xml"), mjcf("meshes/base.obj", "")).unwrap();
    let out = run(
        BIN,
        &dir,
        &["robot", "one.xml", "-o", ".", "--samples", "2000"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("one of the robot's own files"), "{err}");
    assert_eq!(
        fs::read_to_string(dir.join("one.xml")).unwrap(),
        mjcf("meshes/base.obj", "")
    );
    assert!(!dir.join("manifest.json").exists());
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
        [
            "curobo.yml",
            "links",
            "manifest.json",
            "two.urdf",
            "two.usda",
            "two.xml"
        ]
    );
    assert_eq!(
        files(&dir.join("out/one")),
        [
            "curobo.yml",
            "links",
            "manifest.json",
            "one.urdf",
            "one.usda",
            "one.xml"
        ]
    );
    assert!(!dir.join("out/bad").join("manifest.json").exists());
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

/// With the visual meshes as the source, a body whose colliding geoms are all primitives gets
/// its new geoms before its end tag, colliding whatever its class says; a primitive sized
/// from a mesh stays MuJoCo's own.
#[test]
fn visual_meshes_give_a_body_new_colliders() {
    let dir = scratch("robot_mjcf_visual");
    setup(&dir);
    fs::write(
        dir.join("v.xml"),
        r#"<mujoco model="v">
  <default><default class="visual"><geom type="mesh" contype="0" conaffinity="0"/></default></default>
  <asset><mesh name="base" file="meshes/base.obj"/></asset>
  <worldbody>
    <body name="b" childclass="visual">
      <geom mesh="base"/>
      <geom class="main" type="box" size="0.1 0.1 0.1"/>
      <geom class="main" type="box" mesh="base"/>
    </body>
  </worldbody>
</mujoco>
"#,
    )
    .unwrap();
    let out = run(
        BIN,
        &dir,
        &[
            "robot",
            "v.xml",
            "-o",
            "out",
            "--source",
            "visual",
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
    let xml = fs::read_to_string(dir.join("out/v.xml")).unwrap();
    let b = &xml[xml.find("<body").unwrap()..xml.find("</body>").unwrap()];
    assert!(b.contains("<geom mesh=\"base\"/>"), "{b}");
    assert!(
        b.contains("<geom class=\"main\" type=\"box\" mesh=\"base\"/>"),
        "{b}"
    );
    let new: Vec<&str> = b.lines().filter(|l| l.contains("b_bvseg_")).collect();
    assert!(!new.is_empty(), "{b}");
    assert!(new
        .iter()
        .all(|l| l.contains("contype=\"1\" conaffinity=\"1\"")));
    // Without --source visual the body has no colliding mesh geom: the file comes back as it
    // was, but for bvseg's comment.
    let out = run(
        BIN,
        &dir,
        &["robot", "v.xml", "-o", "out2", "--samples", "2000", "-q"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let xml = fs::read_to_string(dir.join("out2/v.xml")).unwrap();
    assert!(!xml.contains("_bvseg_"), "{xml}");
}
