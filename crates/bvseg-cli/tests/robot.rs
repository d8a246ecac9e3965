//! `bvseg robot` on a two-link robot written by the test: every link's collision vertices lie
//! in its new volumes, the URDF keeps no mesh collision, and bad robots are one-line errors
//! with nothing written.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use std::fs;
use std::path::Path;

use bvseg_testkit::{run, scratch};
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

#[test]
fn bad_robots_are_one_line_errors_and_write_nothing() {
    for (case, file) in [
        ("missing mesh", urdf("meshes/nothere.obj", "arm", "arm")),
        ("link named twice", urdf("meshes/base.obj", "base", "base")),
        ("joint to no link", urdf("meshes/base.obj", "arm", "hand")),
    ] {
        let dir = scratch(&format!("robot_bad_{}", case.replace(' ', "_")));
        setup(&dir);
        fs::write(dir.join("two.urdf"), file).unwrap();
        let out = run(
            BIN,
            &dir,
            &["robot", "two.urdf", "-o", "out", "--samples", "3000"],
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{case}: {err}");
        let line = err
            .lines()
            .find(|l| l.starts_with("bvseg: error:"))
            .unwrap_or_default();
        assert!(!line.is_empty(), "{case}: {err}");
        assert!(
            !dir.join("out").join("two.urdf").exists(),
            "{case}: wrote output"
        );
    }
}
