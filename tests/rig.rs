//! A skinned mesh: parts bound to bones, and volumes that follow the animation.
// Tests state their expectations by panicking.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use bvseg::shapes::capsule;
use bvseg::{segment, Joint, Mesh, Params, Pose, Rig, Route, Skeleton, SkeletonMode, Skin};
use glam::{DMat4, DVec3};

/// An arm along x from -1 to 1: the upper arm's joint at -1, the elbow at 0, the hand at 1.
fn skeleton() -> Skeleton {
    let joint = |name: &str, parent, x: f64| Joint {
        name: name.into(),
        parent,
        rest: DMat4::from_translation(DVec3::new(x, 0.0, 0.0)),
        node: None,
    };
    Skeleton {
        joints: vec![
            joint("shoulder", None, -1.0),
            joint("elbow", Some(0), 0.0),
            joint("hand", Some(1), 1.0),
        ],
    }
}

/// The elbow's share of a vertex at `x`: blended over [-0.2, 0.2].
fn elbow_weight(x: f64) -> f64 {
    ((x + 0.2) / 0.4).clamp(0.0, 1.0)
}

/// The arm bent by `angle` at the elbow (about z): the joints' world matrices and the
/// vertices of `mesh` posed by linear blend skinning.
fn pose(mesh: &Mesh, angle: f64) -> (Vec<DMat4>, Vec<DVec3>) {
    let bend = DMat4::from_rotation_z(angle);
    let joints = vec![
        DMat4::from_translation(DVec3::new(-1.0, 0.0, 0.0)),
        bend,
        bend * DMat4::from_translation(DVec3::new(1.0, 0.0, 0.0)),
    ];
    let vertices = mesh
        .vertices()
        .iter()
        .map(|&v| {
            let w = elbow_weight(v.x);
            (1.0 - w) * v + w * bend.transform_point3(v)
        })
        .collect();
    (joints, vertices)
}

fn skinned_arm(poses: usize) -> Mesh {
    let mesh = capsule(
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        0.25,
        24,
    );
    let weights = mesh
        .vertices()
        .iter()
        .map(|v| {
            let w = elbow_weight(v.x) as f32;
            [(0, 1.0 - w), (1, w), (0, 0.0), (0, 0.0)]
        })
        .collect();
    let poses = (0..poses)
        .map(|i| {
            let t = i as f64 / (poses - 1) as f64;
            let (joints, vertices) = pose(&mesh, t * std::f64::consts::FRAC_PI_2);
            Pose {
                animation: 0,
                time: t,
                joints,
                vertices,
            }
        })
        .collect();
    let skin = Skin {
        weights,
        corners: mesh.triangles().to_vec(),
        poses,
    };
    mesh.with_rig(Rig {
        skeleton: skeleton(),
        skin: Some(skin),
    })
    .unwrap()
}

#[test]
fn volumes_follow_their_bones_at_and_between_the_sampled_poses() {
    let mesh = skinned_arm(31);
    let params = Params {
        samples: 4000,
        ..Params::default()
    };
    let seg = segment(&mesh, &params).unwrap();
    assert!(seg.parts.iter().all(|p| p.bone.is_some()));
    let bones: std::collections::BTreeSet<usize> =
        seg.parts.iter().filter_map(|p| p.bone).collect();
    assert!(bones.contains(&0) && bones.contains(&1), "{bones:?}");
    assert!(seg.hierarchy.is_empty());
    let sk = skeleton();
    // Sampled poses and the times halfway between them, a quarter turn in all.
    for step in 0..=60 {
        let angle = step as f64 / 60.0 * std::f64::consts::FRAC_PI_2;
        let (joints, vertices) = pose(&mesh, angle);
        for (t, &p) in seg.triangle_parts.iter().enumerate() {
            let part = &seg.parts[p as usize];
            let b = part.bone.unwrap();
            let back = sk.joints[b].rest * joints[b].inverse();
            for &c in &mesh.triangles()[t] {
                let x = back.transform_point3(vertices[c as usize]);
                assert!(
                    part.volume.contains(x),
                    "at {angle}: triangle {t}'s corner escapes part {p} (bone {b})"
                );
            }
        }
    }
}

#[test]
fn the_skeleton_seeds_one_part_per_link_and_none_ignores_it() {
    let mesh = skinned_arm(3);
    let fixed = |skeleton| Params {
        samples: 4000,
        skeleton,
        max_k: 2,
        tov: 10.0,
        max_protrusion: 1.0,
        merge: false,
        // The seeding is the lattice route's (a skinned mesh takes the surface route by
        // default, which starts from one cluster per bone whatever the mode).
        route: Route::Lattice,
        ..Params::default()
    };
    let seg = segment(&mesh, &fixed(SkeletonMode::Rig)).unwrap();
    // Two links: shoulder-elbow and elbow-hand, each a part of its own bone.
    assert_eq!(seg.parts.len(), 2);
    let mut bones: Vec<usize> = seg.parts.iter().map(|p| p.bone.unwrap()).collect();
    bones.sort_unstable();
    assert_eq!(bones, vec![0, 1]);
    let unseeded = segment(&mesh, &fixed(SkeletonMode::None)).unwrap();
    assert_eq!(unseeded.history[0].k, 1);
    // Bones are bound whatever seeded the start.
    assert!(unseeded.parts.iter().all(|p| p.bone.is_some()));
}
